"""A long simulation holds a window of its inputs and only the histories it is asked for.

References: the same run with the inputs held whole (a window longer than the run) gives the
identical histories, bit for bit (the window changes where the samples are kept, not what
they are); a run that records a few signals gives exactly those columns of the full
recording; the memory numpy allocates for a long run (tracemalloc, which numpy reports its
arrays to) grows with its recorded histories, not with its input samples.
"""

import tracemalloc

import numpy as np
import pytest
from axis_fixtures import PADS, small_axis, small_drive

from servotune.friction import LuGreParameters
from servotune.simulate import (
    LuGreFriction,
    NonlinearAxis,
    point_to_point,
    simulate,
    simulator,
    sine_sweep,
)

P = LuGreParameters.named("bianchi2014")


def lugre_axis(**drive):
    return NonlinearAxis(small_axis(), small_drive(velocity_feedforward=1.0, **drive), PADS,
                         LuGreFriction(P))


@pytest.mark.parametrize("scenario", [
    sine_sweep(200.0, 20.0, 120.0, 0.4),
    point_to_point([0.0, 2e-3, 0.0], speed=0.02, acceleration=1.0, dwell=0.05),
], ids=["sweep", "move"])
def test_windowed_inputs_give_the_identical_run(monkeypatch, scenario):
    axis = lugre_axis()
    whole = simulate(axis, scenario, record_step=2.5e-4)
    # windows of 7 steps: many window edges inside the run, none on a checkpoint
    monkeypatch.setattr(simulator, "INPUT_WINDOW", 7)
    windowed = simulate(axis, scenario, record_step=2.5e-4)
    assert set(whole.signals) == set(windowed.signals)
    for name, s in whole.signals.items():
        np.testing.assert_array_equal(windowed.signals[name], s, err_msg=name)
    np.testing.assert_array_equal(windowed.work, whole.work)
    assert windowed.stats["steps"] == whole.stats["steps"]


def test_recorded_subset_is_the_full_recordings_columns():
    axis = lugre_axis()
    scenario = sine_sweep(200.0, 20.0, 120.0, 0.3)
    full = simulate(axis, scenario)
    few = simulate(axis, scenario, record=("wp_x", "torque", "f_wp_x"))
    assert set(few.signals) == {"wp_x", "torque", "f_wp_x"}
    for name in few.signals:
        np.testing.assert_array_equal(few.signals[name], full.signals[name], err_msg=name)
    np.testing.assert_array_equal(few.t, full.t)


def test_unknown_recorded_signal_is_named():
    with pytest.raises(ValueError, match=r"record: \['wp_q'\] are not signals of this run.*"
                                         r"wp_x"):
        simulate(lugre_axis(), sine_sweep(100.0, 20.0, 50.0, 0.05), record=["wp_x", "wp_q"])


def test_long_run_memory_is_its_histories_not_its_inputs(monkeypatch):
    monkeypatch.setattr(simulator, "INPUT_WINDOW", 1000)   # a run 16 windows long
    axis = lugre_axis()
    step, duration = 2.5e-4, 4.0
    n = round(duration / step)
    simulate(axis, sine_sweep(100.0, 20.0, 60.0, 0.01), record=["wp_x"])  # compiled, warm
    tracemalloc.start()
    try:
        result = simulate(axis, sine_sweep(100.0, 20.0, 60.0, duration), step=step,
                          record_step=step, record=["wp_x"])
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert result.t.size == n + 1
    # held whole, the inputs (3 samples a step of at least x_ref, v_ref, a_ref, f_wp_x, one)
    # would take 1.9 MB; the histories (t, wp_x and the works of 4 channels) take 0.8 MB
    inputs_whole = 3 * n * 5 * 8
    histories = 6 * result.t.size * 8
    assert histories <= peak < histories + 0.4 * inputs_whole


def test_a_move_of_an_axis_without_drive_is_refused():
    axis = NonlinearAxis(small_axis(), None, PADS, LuGreFriction(P))
    with pytest.raises(ValueError, match="moves the axis but the axis has no drive"):
        simulate(axis, point_to_point([0.0, 1e-3], speed=0.01, acceleration=1.0))
