"""The structure a simulation needs: a Craig-Bampton model without its highest fixed-interface
modes (servotune.simulate.truncation).

References: the static flexibility of the full FE matrices (K^-1 at the boundary, a direct
solve of the unreduced model); the receptance by direct solution of (K - w^2 M + j w D) (the
n^3 method, not the modal sum the truncation checks with); the Ritz property (a model on fewer
coordinates has frequencies no lower than the model it comes from); a time simulation of the
full model (the same sweep, the peak within the integrator's accuracy).
"""

import math

import numpy as np
import pytest
import scipy.linalg

from servotune.friction import LuGreParameters
from servotune.simulate import LuGreFriction, NonlinearAxis, simulate, sine_sweep
from servotune.simulate.truncation import TRUNCATION_TOLERANCE, simulation_structure
from servotune.structure import ModalModel, craig_bampton

PORTS = ["pad1.x", "pad2.x", "wp.x"]


def chain(n=60, mass=20.0, k=5e8, seed=3):
    """A free-free chain of n masses with a few grounded springs (the FE model); the pads are
    its first and last mass, the work piece its middle."""
    rng = np.random.default_rng(seed)
    m = np.diag(mass * (0.5 + rng.random(n)))
    kk = np.zeros((n, n))
    for i in range(n - 1):
        ki = k * (0.5 + rng.random())
        kk[i:i + 2, i:i + 2] += ki * np.array([[1.0, -1.0], [-1.0, 1.0]])
    kk[n // 3, n // 3] += 1e7
    return m, kk, [0, n - 1, n // 2]


@pytest.fixture(scope="module")
def reduced():
    m, k, boundary = chain()
    model = craig_bampton(m, k, boundary, n_modes=len(m) - len(boundary), damping_ratio=0.03,
                          boundary_names=PORTS)
    return m, k, boundary, model


def test_modes_far_above_the_band_are_dropped_and_the_statics_kept(reduced):
    m, k, boundary, model = reduced
    t = simulation_structure(model, PORTS, f_top_hz=100.0)
    f = sorted(t.structure.reduction.fixed_interface_hz)
    assert t.truncated and 0 < t.kept < t.total == len(m) - len(boundary)
    assert max(f) <= t.cutoff_hz == 1000.0   # 10 x the band's top
    # static flexibility at the boundary: exact (the full, unreduced FE matrices)
    flex_full = scipy.linalg.solve(k, np.eye(len(m))[:, boundary])[boundary]
    sub = t.structure
    idx = sub.index(PORTS)
    flex_sub = scipy.linalg.solve(sub.stiffness, np.eye(sub.n)[:, idx])[idx]
    np.testing.assert_allclose(flex_sub, flex_full, rtol=1e-9)
    # Ritz: no frequency of the truncated model below the full model's same-numbered one
    full_f = model.natural_frequencies()
    sub_f = sub.natural_frequencies()
    assert np.all(sub_f >= full_f[:sub_f.size] * (1 - 1e-9))
    # and those in the band within the check's tolerance
    low = full_f < 2 * math.pi * 100.0
    np.testing.assert_allclose(sub_f[:low.sum()], full_f[low], rtol=TRUNCATION_TOLERANCE)


def test_reported_deviation_is_the_direct_solutions(reduced):
    _, _, _, model = reduced
    t = simulation_structure(model, PORTS, f_top_hz=100.0)
    lo, hi = t.checked_hz
    omega = 2 * math.pi * np.geomspace(lo, hi, 400)
    h_full = model.receptance(omega, PORTS, PORTS)
    h_sub = t.structure.receptance(omega, PORTS, PORTS)
    drive = np.abs(np.diagonal(h_full, axis1=1, axis2=2)).max(axis=0)
    dev = (np.abs(h_sub - h_full).max(axis=0) / np.sqrt(np.outer(drive, drive))).max()
    assert dev <= TRUNCATION_TOLERANCE
    assert t.deviation == pytest.approx(dev, rel=1e-3, abs=1e-9)


def test_a_tolerance_that_the_cut_breaks_raises_the_cutoff(reduced, monkeypatch):
    from servotune.simulate import truncation

    _, _, _, model = reduced
    loose = simulation_structure(model, PORTS, f_top_hz=100.0)
    monkeypatch.setattr(truncation, "TRUNCATION_TOLERANCE", loose.deviation / 10)
    monkeypatch.setattr(truncation, "_CACHE", {})
    tight = truncation.simulation_structure(model, PORTS, f_top_hz=100.0)
    assert tight.kept > loose.kept
    assert tight.deviation <= loose.deviation / 10 or not tight.truncated


def test_models_without_fixed_interface_modes_are_simulated_whole():
    m, k, _ = chain(8)
    model = ModalModel(m, k, [f"n{i}.x" for i in range(8)])
    t = simulation_structure(model, ["n0.x"], f_top_hz=10.0)
    assert t.structure is model and not t.truncated


def test_a_sweep_on_the_truncated_model_peaks_as_on_the_full_one(reduced):
    _, _, _, model = reduced
    t = simulation_structure(model, PORTS, f_top_hz=100.0)
    law = LuGreFriction(LuGreParameters.named("bianchi2014"))
    scenario = sine_sweep(200.0, 30.0, 90.0, 1.0)
    peaks = []
    for structure in (model, t.structure):
        result = simulate(NonlinearAxis(structure, None, ("pad1.x", "pad2.x"), law), scenario,
                          record=["wp_x"])
        peaks.append(result.sweep_envelope().peak)
    assert t.kept < t.total
    assert peaks[1] == pytest.approx(peaks[0], rel=2e-3)


def test_tune_on_the_truncated_structure_is_checked_on_the_whole_model(tmp_path):
    """The table axis' export with 100 fixed-interface modes (up to about 30 kHz): tuned on the
    modes below the cut-off, its design checked on all 100 (the note), and that check equals
    the design checked on the whole axis by check_design (the user's own route)."""
    import json
    import re
    import shutil
    from pathlib import Path

    import servotune as st
    from servotune.cli import main
    from servotune.design import check_design
    from servotune.tuning.problem import Design

    src = Path(__file__).resolve().parents[1] / "examples" / "data" / "table_axis"
    ax = tmp_path / "ax"
    shutil.copytree(src, ax)
    toml = ax / "axis.toml"
    toml.write_text(re.sub(r"^f_max_hz = .*$", "n_modes = 100", toml.read_text(),
                           flags=re.MULTILINE))
    assert main(["tune", str(ax), "--json", "--no-simulation", "--no-plots", "--starts", "1",
                 "--workers", "1", "--out", str(tmp_path / "out")]) in (0, 3)
    out = json.loads((tmp_path / "out" / "tune_table_axis" / "results.json").read_text())
    note = next(n for n in out["notes"] if n.startswith("the structure: "))
    kept = int(re.search(r"(\d+) of 100 fixed-interface modes", note).group(1))
    assert 0 < kept < 100
    whole_peak = float(re.search(r"worst compliance peak ([0-9.e+-]+) m/N", note).group(1))
    axis = st.load_axis(ax)
    assert len([d for d in axis.structure.dofs if d.startswith("mode.")]) == 100
    design = Design(**{k: v for k, v in out["design"].items()})
    checked = check_design(axis, design)
    assert whole_peak == pytest.approx(checked.after.peak_compliance, rel=1e-3)
    assert out["peak_compliance_after"] == pytest.approx(whole_peak, rel=TRUNCATION_TOLERANCE)
