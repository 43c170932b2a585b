"""``servotune check`` and ``servotune modes`` on reduced models: the verdict and the warning
about fixed-interface modes that do not cover the band, each both ways."""

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp
from structure_star import star

from servotune.cli import main

ROOT = Path(__file__).resolve().parents[1]
TABLE_AXIS = ROOT / "examples" / "data" / "table_axis"


@pytest.fixture(scope="module")
def star_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("star")
    mass, stiffness, dofs = star(n_arms=6, n_per_arm=60)
    scipy.io.mmwrite(folder / "M.mtx", sp.coo_array(mass), symmetry="symmetric")
    scipy.io.mmwrite(folder / "K.mtx", sp.coo_array(stiffness), symmetry="symmetric")
    (folder / "dofs.csv").write_text("name\n" + "\n".join(dofs) + "\n")
    return folder


def run_json(capsys, argv):
    code = main([*argv, "--json"])
    captured = capsys.readouterr()
    return code, json.loads(captured.out), captured.err


def test_check_fails_when_the_kept_modes_do_not_cover_the_band(star_files, capsys):
    f = star_files
    base = ["check", str(f / "M.mtx"), str(f / "K.mtx"), "--dof-map", str(f / "dofs.csv"),
            "--boundary", "hub.x", "--band-hz", "5", "150"]
    code, out, _ = run_json(capsys, [*base, "--n-modes", "6"])
    assert code == 1 and out["passed"] is False
    coverage = out["band_coverage"]
    assert coverage["covered"] is False and coverage["required_hz"] == pytest.approx(225.0)
    assert "5-150 Hz" in coverage["message"] and "f_max_hz = 225" in coverage["message"]
    # the model check of the reduced matrices alone still passes: the reduction is what fails
    assert out["model_check_passed"] is True
    assert "mass_eigenvalue_ratio" in out and "mass_min_eigenvalue" not in out
    # the default keeps every mode up to margin x band top: the band is covered
    code, out, _ = run_json(capsys, base)
    assert out["band_coverage"]["covered"] is True
    assert out["band_coverage"]["complete_below_hz"] >= 225.0
    # with modes to 4 x the band's top every part of the check passes
    code, out, _ = run_json(capsys, [*base, "--f-max-hz", "600"])
    assert code == 0 and out["passed"] is True, out["reduction_check"]["failures"]
    assert out["reduction_check"]["max_frequency_error"] < 0.01
    assert out["reduction_check"]["max_compliance_error"] < 0.05


def test_check_text_report_names_the_failure(star_files, capsys):
    f = star_files
    code = main(["check", str(f / "M.mtx"), str(f / "K.mtx"), "--dof-map",
                 str(f / "dofs.csv"), "--boundary", "hub.x", "--n-modes", "6",
                 "--band-hz", "5", "150"])
    text = capsys.readouterr().out
    assert code == 1
    assert "FAILED: the 6 fixed-interface modes kept reach" in text
    assert "overall: FAILED" in text


@pytest.fixture
def table_axis(tmp_path, monkeypatch):
    folder = tmp_path / "table_axis"
    shutil.copytree(TABLE_AXIS, folder)
    monkeypatch.chdir(tmp_path)   # the commands' default out/ folders go there
    # the example keeps every fixed-interface mode to 600 Hz; these tests start from 8 (to
    # 422 Hz, too few for its 5-400 Hz band)
    toml = folder / "axis.toml"
    text = toml.read_text()
    assert "f_max_hz = 600.0" in text
    toml.write_text(text.replace("f_max_hz = 600.0", "n_modes = 8", 1))
    return folder


def set_reduction(folder, line):
    toml = folder / "axis.toml"
    text = toml.read_text()
    assert "n_modes = 8" in text
    toml.write_text(text.replace("n_modes = 8", line, 1))


def test_modes_warns_when_the_band_is_not_covered_and_not_when_it_is(table_axis, capsys):
    # 8 fixed-interface modes reach 422 Hz; the axis' band is 5-400 Hz: 600 Hz are needed
    code, out, err = run_json(capsys, ["modes", str(table_axis)])
    assert code == 0
    assert "WARNING" in err and "5-400 Hz" in err and "422.1 Hz" in err
    assert "f_max_hz = 600" in err
    assert out["band_coverage"]["covered"] is False and len(out["warnings"]) == 1
    set_reduction(table_axis, "f_max_hz = 600.0")
    code, out, err = run_json(capsys, ["modes", str(table_axis)])
    assert code == 0 and "WARNING" not in err
    assert out["band_coverage"]["covered"] is True and out["warnings"] == []


def test_check_of_an_axis_checks_reduction_and_transmission(table_axis, capsys):
    code, out, _ = run_json(capsys, ["check", str(table_axis)])
    assert code == 1 and out["passed"] is False
    assert out["transmission"]["status"] == "ok"
    assert out["reduction_check"]["band_coverage"]["covered"] is False
    # modes to 1500 Hz: the check against the full matrices passes
    set_reduction(table_axis, "f_max_hz = 1500.0")
    code, out, _ = run_json(capsys, ["check", str(table_axis)])
    assert code == 0, out["reduction_check"]["failures"]
    assert out["reduction_check"]["max_compliance_error"] < 0.05


def test_modes_compliance_peak_uses_the_port_receptance(capsys):
    # the peak of the bundled axis with the pads locked, against the direct solution
    import servotune as st

    axis = st.load_axis(ROOT / "models" / "paper_x_axis")
    model = axis.configuration(pads="locked")
    w, peak = model.compliance_peak("wp.x", *axis.requirements.band)
    direct = abs(model.receptance([w], ["wp.x"], ["wp.x"])[0, 0, 0])
    assert peak == pytest.approx(direct, rel=1e-10)
    grid = np.geomspace(*axis.requirements.band, 400)
    dense = np.abs(model.receptance(grid, ["wp.x"], ["wp.x"])[:, 0, 0]).max()
    assert peak >= dense * (1 - 1e-12) and peak == pytest.approx(dense, rel=0.05)
    code, out, _ = run_json(capsys, ["modes", str(ROOT / "models" / "paper_x_axis"),
                                     "--pads", "locked"])
    assert code == 0 and out["wp_x_peak_compliance"] == pytest.approx(peak, rel=1e-9)
    assert math.isclose(out["band_coverage"]["required_hz"], 450.0)
