"""The speed PI set on a measured speed plant without a model (servotune.measured.speed_tuning),
checked on the model the measurement was computed from: the state-space (sampled-data) loop of
servotune.closed_loop with the tuned PI holds the Ms limit, a gain 3 % higher breaks it, and the
Ti rule holds. weak_motor_axis: its digital drive as given; paper_x_axis with the continuous
drive (as given, its digital velocity loop is unstable)."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from servotune.analysis import axis_contact
from servotune.axis import load_axis
from servotune.closed_loop import closed_loop
from servotune.drive import PIController
from servotune.measured.speed_plant import model_speed_plant
from servotune.measured.speed_tuning import tune_velocity_loop

MODELS = Path(__file__).resolve().parents[1] / "models"


def _axis(name):
    axis = load_axis(MODELS / name)
    return axis.with_continuous_drive() if name == "paper_x_axis" else axis


@pytest.mark.parametrize("name", ["weak_motor_axis", "paper_x_axis"])
def test_the_pi_set_on_the_measured_plant_holds_ms_on_the_model(name):
    axis = _axis(name)
    drive, contact = axis.require_drive(), axis_contact(axis, "stiction")
    omega = 2 * np.pi * np.geomspace(1.0, 3000.0, 1500)
    measured = model_speed_plant(axis.structure, drive, omega, contact, axis.pads)
    req = axis.requirements
    limit = req.ms_limit("velocity")
    tuned = tune_velocity_loop(omega, measured, drive, limit,
                               (req.ti_bandwidth_min, req.ti_bandwidth_max), n_ti=12)
    assert tuned.analysis.ms <= limit * (1 + 1e-9)
    rule = tuned.ti * tuned.analysis.bandwidth
    assert req.ti_bandwidth_min <= rule <= req.ti_bandwidth_max

    def model_ms(kp):
        d = dataclasses.replace(drive, velocity_loop=PIController(kp, tuned.ti))
        loop = closed_loop(axis.structure, d, contact, axis.pads)
        return loop.analyse_loop("velocity", 2 * np.pi * np.geomspace(0.1, 3000.0, 6000)).ms

    # the second method: servotune's own loop of the model with the tuned PI
    assert model_ms(tuned.kp) <= limit * (1 + 5e-3)
    assert model_ms(1.03 * tuned.kp) > limit          # the largest gain within the limit
    # and the bandwidth the measurement promises is the model's
    d = dataclasses.replace(drive, velocity_loop=PIController(tuned.kp, tuned.ti))
    model = closed_loop(axis.structure, d, contact, axis.pads).analyse_loop(
        "velocity", 2 * np.pi * np.geomspace(0.1, 3000.0, 6000))
    assert tuned.analysis.bandwidth == pytest.approx(model.bandwidth, rel=0.03)


def test_an_impossible_ti_rule_is_refused_naming_what_to_relax():
    axis = _axis("weak_motor_axis")
    drive, contact = axis.require_drive(), axis_contact(axis, "stiction")
    omega = 2 * np.pi * np.geomspace(1.0, 3000.0, 600)
    measured = model_speed_plant(axis.structure, drive, omega, contact, axis.pads)
    # Ti x bandwidth of 500 with Ti of a millisecond: a loop of 80 kHz, which no drive has
    with pytest.raises(ValueError, match=r"Ti x bandwidth in \[500, 600\].*relax"):
        tune_velocity_loop(omega, measured, drive, 1.5, ti_bandwidth=(500.0, 600.0),
                           ti_range=(1e-3, 2e-3), n_ti=3)
