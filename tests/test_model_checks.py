"""Model checks of an axis: the structure's rotor-to-encoder motion against the drive's
transmission ratio (sign included), and the band coverage of the kept fixed-interface modes."""

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from axis_fixtures import RATIO, small_axis, small_drive

import servotune as st
from servotune.model_checks import band_coverage, transmission_check
from servotune.plant import Contact, build_plant
from servotune.requirements import Requirements
from servotune.structure import ModalModel

ROOT = Path(__file__).resolve().parents[1]
PADS = ["pad1.x", "pad2.x"]


def flipped(structure, dof):
    """The structure with one DOF's direction reversed, as a sign error in an export does."""
    t = np.ones(structure.n)
    t[structure.dofs.index(dof)] = -1.0
    return ModalModel(t[:, None] * structure.mass * t, t[:, None] * structure.stiffness * t,
                      structure.dofs)


def closed_loop_unstable(structure, drive):
    plant = build_plant(structure, drive, Contact.viscous(1e4), PADS)
    return bool(np.max(plant.poles().real) > 0)


def test_structure_ratio_is_the_screw_of_the_model():
    # the fixture's screw couples r * rotor to the slide: r = 10 mm / 2 pi
    check = transmission_check(small_axis(), small_drive())
    assert check.status == "ok" and check.passed
    assert check.structure_ratio == pytest.approx(RATIO, rel=1e-9)
    assert dict(check.slide_ratios)["wp.x"] == pytest.approx(RATIO, rel=1e-9)
    assert not closed_loop_unstable(small_axis(), small_drive())


def test_bundled_axis_matches_its_belt_and_screw():
    axis = st.load_axis(ROOT / "models" / "paper_x_axis")
    check = transmission_check(axis.structure, axis.drive)
    # models/paper_x_axis/build.py: 20 mm lead, belt 80/40 mm: r = 0.020 / (2 pi) / 2
    assert check.structure_ratio == pytest.approx(0.020 / (2 * math.pi) / 2.0, rel=1e-9)
    assert check.status == "ok"


@pytest.mark.parametrize("dof", ["encoder.x", "motor.rotor"])
def test_a_flipped_direction_is_named_and_makes_the_loop_unstable(dof):
    structure = flipped(small_axis(), dof)
    check = transmission_check(structure, small_drive())
    assert check.status == "flipped" and not check.passed
    assert check.flipped == dof
    assert check.structure_ratio == pytest.approx(-RATIO, rel=1e-9)
    assert "positive feedback" in check.message and f"reverse {dof}" in check.message
    # it states how the slide really moves: +r with the encoder flipped, -r with the rotor
    sign = 1.0 if dof == "encoder.x" else -1.0
    assert f"wp.x {sign * RATIO:+.4g}" in check.message
    assert "DOF map" not in check.message or "no sign" in check.message
    # what the message claims: with linear feedback the closed loop has a pole on the right
    assert closed_loop_unstable(structure, small_drive())


def test_a_wrong_ratio_is_a_mismatch_and_motor_feedback_has_no_sign_to_check():
    drive = small_drive()
    off = replace(drive, ratio=2 * math.pi * RATIO)  # a lead given instead of lead / 2 pi
    check = transmission_check(small_axis(), off)
    assert check.status == "mismatch" and not check.passed
    assert "[drive.transmission] ratio" in check.message
    motor = transmission_check(flipped(small_axis(), "encoder.x"),
                               replace(drive, feedback="motor"))
    assert motor.status == "not applicable" and motor.passed


def test_an_encoder_the_motor_does_not_move_is_undetermined():
    s = small_axis()
    # cut the screw: the slide (and the encoder on it) is then free of the motor
    k = s.stiffness.copy()
    r, p = s.dofs.index("motor.rotor"), s.dofs.index("pad1.x")
    kk = 3.0e8 * np.outer(np.eye(s.n)[r] * RATIO - np.eye(s.n)[p],
                          np.eye(s.n)[r] * RATIO - np.eye(s.n)[p])
    cut = ModalModel(s.mass, k - kk, s.dofs)
    check = transmission_check(cut, small_drive())
    assert check.status == "undetermined" and not check.passed
    assert "not determined" in check.message


def test_unknown_dofs_are_clear_errors():
    with pytest.raises(KeyError, match=r"encoder\.y"):
        transmission_check(small_axis(), replace(small_drive(), encoder="encoder.y"))


def test_band_coverage_from_requirements_both_ways():
    w2 = (2 * math.pi * np.array([120.0, 480.0])) ** 2
    model = ModalModel(np.eye(3), np.diag(np.r_[1e6, w2]), ["wp.x", "mode.1", "mode.2"])
    assert band_coverage(model).covered  # default 5-300 Hz: 450 Hz needed, 480 Hz kept
    narrow = Requirements(band=(2 * math.pi * 5.0, 2 * math.pi * 400.0))
    result = band_coverage(model, narrow)
    assert not result.covered and result.required_hz == pytest.approx(600.0)
    assert "5-400 Hz" in result.message and "480 Hz" in result.message
    assert "f_max_hz = 600" in result.message
    assert band_coverage(model, (2 * math.pi * 5.0, 2 * math.pi * 400.0), margin=1.15).covered
