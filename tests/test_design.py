"""The design job: servotune tune on the bundled models against closed forms and the
independent verification."""

import json
from pathlib import Path

import numpy as np
import pytest

from servotune import twomass
from servotune.axis import load_axis
from servotune.cli import main
from servotune.design import mode_peaks_vs_damping

MODELS = Path(__file__).resolve().parents[1] / "models"


def test_tune_two_mass_reproduces_copt_and_g_alpha(tmp_path, capsys):
    # paper sec 4.1, Fig 5: Copt = 4.912e5 N s/m, peak g(alpha)/K, with alpha = 0.3
    assert main(["tune", str(MODELS / "two_mass_fig5"), "--out", str(tmp_path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    system = twomass.TwoMassSystem(m1=5000.0, k=16e6, alpha=0.3)
    assert out["verified"] is True
    assert out["design"]["c"] == pytest.approx(twomass.optimal_damping(system), rel=1e-4)
    assert out["c_opt_analytic"] == pytest.approx(4.912e5, rel=1e-4)
    assert out["peak_compliance_after"] == pytest.approx(twomass.g_alpha(0.3) / 16e6, rel=1e-6)
    assert abs(out["two_mass_check"]["c_relative_difference"]) < 1e-4
    assert (tmp_path / "results.json").is_file()


def test_tune_refuses_to_overwrite(tmp_path, capsys):
    (tmp_path / "results.json").write_text("{}")
    assert main(["tune", str(MODELS / "two_mass_fig5"), "--out", str(tmp_path)]) == 1
    assert "--force" in capsys.readouterr().err
    assert (tmp_path / "results.json").read_text() == "{}"


def test_tune_bundled_axis_improves_and_verifies(tmp_path, capsys):
    assert main(["tune", str(MODELS / "paper_x_axis"), "--out", str(tmp_path), "--json",
                 "--starts", "2", "--no-simulation"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["verified"] is True
    for key in ("c", "kv", "kp", "ti"):
        assert out["design"][key] > 0
    assert out["peak_compliance_after"] < 0.5 * out["peak_compliance_before"]
    assert out["b_crit_after_m"] > out["b_crit_before_m"]
    req = load_axis(MODELS / "paper_x_axis").requirements
    assert out["ms_velocity"] <= req.ms_limit("velocity") * 1.005
    assert out["ms_position"] <= req.ms_limit("position") * 1.005
    saved = json.loads((tmp_path / "results.json").read_text())
    assert saved["design"] == out["design"]
    assert all(Path(f).stat().st_size > 10_000 for f in out["files"])


def test_several_modes_ask_for_different_damping():
    # paper sec 5.2: with the servo closed, the modes that move the work piece have their
    # smallest peaks at different C
    axis = load_axis(MODELS / "paper_x_axis")
    peaks = mode_peaks_vs_damping(axis, np.geomspace(1e3, 1e8, 21), c_chosen=1e6)
    assert peaks.peaks.shape[0] >= 2
    best = sorted(peaks.c_best)
    assert best[-1] / best[0] > 1.5
