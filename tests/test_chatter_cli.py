"""``servotune lobes`` in-process through ``main([...])``: both compliance forms and errors."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from servotune import chatter
from servotune.cli import main

ROOT = Path(__file__).resolve().parent.parent
MODE = ["--mode", "922", "0.011", str(0.03993 * (2 * math.pi * 922.0) ** 2)]


def run_json(argv, capsys):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_mode_form_zero_order(tmp_path, capsys):
    out = run_json(["lobes", *MODE, "--speed-rpm", "5000", "25000", "--speeds", "500",
                    "--required-depth-mm", "0.2", "--out", str(tmp_path), "--json"], capsys)
    for key in ("b_crit_m", "critical_speed_rpm", "lobes", "margin", "critical_frequency_hz"):
        assert key in out
    assert set(out["lobes"]) == {"speed_rpm", "b_lim_m"}
    assert len(out["lobes"]["speed_rpm"]) == len(out["lobes"]["b_lim_m"]) == 500
    # Tlusty: b_crit Kt mu = 2 k zeta (1 + zeta), mu = N Kr / 4 in a full slot
    k = 0.03993 * (2 * math.pi * 922.0) ** 2
    mu = 2 * (2e8 / 6e8) / 4
    assert out["b_crit_m"] * 6e8 * mu == pytest.approx(2 * k * 0.011 * 1.011, rel=1e-9)
    assert out["margin"] == pytest.approx(out["min_depth_limit_m"] / 0.2e-3)
    assert 5000 <= out["critical_speed_rpm"] <= 25000
    assert (tmp_path / "lobes_modes" / "lobes_zoa.png").stat().st_size > 10_000


def test_frf_form_matches_the_mode_form(tmp_path, capsys):
    system = chatter.modal_compliance([chatter.Mode.from_hz(922, 0.011, 1.34e6, "y")])
    w, g = chatter.compliance_matrix(system, np.linspace(5000, 7000, 4001))
    path = tmp_path / "frf.csv"
    np.savetxt(path, np.column_stack([w / (2 * math.pi), g[:, 1, 1].real, g[:, 1, 1].imag]),
               delimiter=",", header="f_hz,re_yy_m_per_n,im_yy_m_per_n", comments="")
    args = ["--speed-rpm", "12000", "20000", "--no-plots", "--json"]
    from_frf = run_json(["lobes", "--frf", str(path), *args], capsys)
    from_mode = run_json(["lobes", "--mode", "922", "0.011", "1.34e6", "--direction", "y",
                          *args], capsys)
    assert from_frf["b_crit_m"] == pytest.approx(from_mode["b_crit_m"], rel=1e-5)
    assert from_frf["critical_speed_rpm"] == pytest.approx(from_mode["critical_speed_rpm"],
                                                           rel=1e-3)


def test_semi_discretisation_form(tmp_path, capsys):
    out = run_json(["lobes", *MODE, "--method", "sdm", "--immersion", "0.05",
                    "--speed-rpm", "17500", "19000", "--speeds", "7", "--intervals", "30",
                    "--depth-max-mm", "3", "--out", str(tmp_path), "--json"], capsys)
    assert out["method"] == "sdm" and out["intervals"] == 30
    # flip lobe below the zero-order limit
    assert out["b_crit_m"] < 0.7 * out["zoa_b_crit_m"]
    assert (tmp_path / "lobes_modes" / "lobes_sdm.png").stat().st_size > 10_000


def test_text_output_with_two_directions(capsys):
    assert main(["lobes", *MODE, "--mode-y", "1100", "0.02", "2e6", "--teeth", "4",
                 "--immersion", "0.3", "--milling", "up", "--no-plots"]) == 0
    text = capsys.readouterr().out
    assert "b_crit" in text and "critical speed" in text and "2 mode(s)" in text


@pytest.mark.parametrize("argv, words", [
    (["lobes", "axis_x"], "no axis description here"),
    (["lobes", *MODE, "--speed-rpm", "9000", "5000"], "speed range"),
    (["lobes", "--frf", "missing.csv"], "missing.csv"),
])
def test_bad_input_is_a_clear_error(argv, words, capsys, tmp_path):
    assert main([*argv, "--no-plots", "--out", str(tmp_path)]) == 1
    assert words in capsys.readouterr().err


@pytest.mark.parametrize("argv, words", [
    (["lobes", "models/paper_x_axis", *MODE], "one source of the compliance"),
    (["lobes"], "give the compliance"),
    (["lobes", *MODE, "--immersion", "1.5"], "--immersion"),
    (["lobes", *MODE, "--kt=-6e8"], "--kt"),
    (["lobes", "--mode", "922", "1.5", "1e6"], "ZETA"),
    (["lobes", *MODE, "--speeds", "0"], "--speeds"),
])
def test_out_of_range_flags_are_usage_errors(argv, words, capsys, tmp_path):
    assert main([*argv, "--no-plots", "--out", str(tmp_path)]) == 2
    assert words in capsys.readouterr().err


def test_measured_frf_with_semi_discretisation_is_refused(tmp_path, capsys):
    path = tmp_path / "frf.csv"
    f = np.linspace(800, 1000, 50)
    h = 1 / (1.34e6 * (1 - (f / 922) ** 2 + 2j * 0.011 * f / 922))
    np.savetxt(path, np.column_stack([f, h.real, h.imag]), delimiter=",",
               header="f_hz,re_xx_m_per_n,im_xx_m_per_n", comments="")
    assert main(["lobes", "--frf", str(path), "--method", "sdm", "--no-plots"]) == 1
    assert "state-space" in capsys.readouterr().err


def test_a_file_of_the_user_in_the_results_folder_is_not_lost(tmp_path, capsys):
    folder = tmp_path / "lobes_modes"
    folder.mkdir()
    target = folder / "notes.txt"
    target.write_bytes(b"keep me")
    assert main(["lobes", *MODE, "--out", str(tmp_path)]) == 1
    assert "notes.txt" in capsys.readouterr().err and target.read_bytes() == b"keep me"
    target.unlink()
    assert main(["lobes", *MODE, "--out", str(tmp_path)]) == 0
    assert (folder / "lobes_zoa.png").stat().st_size > 10_000


def test_axis_lobes_agree_with_the_closed_loop_compliance(tmp_path, capsys):
    # the AXIS form: lobes of the closed-loop work-piece compliance; b_crit is Tlusty's
    # -1/(2 Kt mu min Re G) of that compliance (computed here directly from the plant)
    import numpy as np

    from servotune import analysis
    from servotune.axis import load_axis

    models = __import__("pathlib").Path(__file__).resolve().parents[1] / "models"
    assert main(["lobes", str(models / "paper_x_axis"), "--continuous", "--out", str(tmp_path),
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    axis = load_axis(models / "paper_x_axis").with_continuous_drive()
    curve = analysis.compliance_curve(axis, analysis.axis_contact(axis, "viscous"),
                                      omega=2 * np.pi * np.geomspace(1.0, 2000.0, 20000))
    mu = chatter.directional_factor(axis.cutting.setup, "x")
    expected = -1.0 / (2 * axis.cutting.setup.kt * (mu * curve.values.real).min())
    assert out["b_crit_m"] == pytest.approx(expected, rel=2e-3)


def test_lobes_of_an_axis_use_the_design_jobs_compliance(capsys, tmp_path, monkeypatch):
    # `servotune lobes AXIS` and the design job's lobes take the compliance from one function
    # on one grid; the reference here is python-control's own frequency response of the
    # closed-loop plant on that grid, turned into lobes by the same zero-order method
    import control

    from servotune import analysis
    from servotune.axis import load_axis

    monkeypatch.chdir(tmp_path)
    axis_dir = ROOT / "models" / "paper_x_axis"
    # the axis' own gains are stable only without the digital drive's delays (--continuous)
    out = run_json(["lobes", str(axis_dir), "--continuous", "--no-plots", "--json"], capsys)
    axis = load_axis(axis_dir).with_continuous_drive()
    contact = analysis.axis_contact(axis, "viscous")     # the command's default
    plant = analysis.axis_plant(axis, contact)
    d = axis.cutting.direction
    sub = plant[plant.output_labels.index(f"wp_{d}"), plant.input_labels.index(f"f_wp_{d}")]
    omega = np.geomspace(2 * np.pi * 1.0, 2 * np.pi * 2000.0, 6000)
    frd = control.frequency_response(sub, omega)
    speeds = np.linspace(*axis.cutting.speed_rpm, len(out["lobes"]["speed_rpm"]))
    reference = chatter.stability_lobes(frd, axis.cutting.setup, speeds, direction=d)
    # python-control's dense response of this 100-state plant is itself accurate to ~2e-5
    # (benchmarks/README.md, frequency_response.py), hence the tolerance
    assert out["b_crit_m"] == pytest.approx(reference.b_crit, rel=1e-4)
    assert out["critical_speed_rpm"] == pytest.approx(reference.critical_speed_rpm, rel=1e-4)
    design_job = analysis.axis_lobes(axis, contact, n_speeds=len(speeds))
    assert out["b_crit_m"] == pytest.approx(design_job.b_crit, rel=1e-12)
