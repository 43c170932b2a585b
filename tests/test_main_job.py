"""The main job end to end on a small axis, and a catalogue of bad axis descriptions."""

import json
import shutil

import pytest

from servotune.axis import AxisFormatError, load_axis
from servotune.cli import main
from servotune.design import nonlinear_check
from servotune.template import write_template
from servotune.tuning import Design


@pytest.fixture(scope="module")
def starter(tmp_path_factory):
    folder = tmp_path_factory.mktemp("starter")
    write_template(folder)
    return folder


def test_init_writes_a_loadable_axis_and_refuses_to_overwrite(tmp_path, capsys):
    assert main(["init", str(tmp_path)]) == 0
    axis = load_axis(tmp_path)
    assert axis.drive is not None and axis.cutting is not None and axis.friction is not None
    before = (tmp_path / "axis.toml").read_text()
    assert main(["init", str(tmp_path)]) == 1
    assert "--force" in capsys.readouterr().err
    assert (tmp_path / "axis.toml").read_text() == before


def test_whole_path_on_a_small_axis(starter, tmp_path, capsys):
    # init -> tune (with the nonlinear check) -> results.json + report.html
    out = tmp_path / "report"
    assert main(["tune", str(starter), "--out", str(out), "--starts", "2", "--workers", "1",
                 "--sweep-duration", "4", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["verified"] is True
    assert result["peak_compliance_after"] < result["peak_compliance_before"]
    saved = json.loads((out / "results.json").read_text())
    assert saved["design"] == result["design"]
    page = (out / "report.html").read_text()
    assert page.count("data:image/png;base64,") >= 5  # self-contained
    assert "Nonlinear verification" in page and "fixed-point theory" in page
    # the nonlinear sweeps at standstill agree with the presliding (stiction) linear model
    rows = saved["nonlinear_verification"]["sweeps"]
    assert rows and all(r["agrees_presliding"] or r["agrees_describing"] for r in rows)


def test_nonlinear_check_runs_the_same_through_an_executor(starter):
    from concurrent.futures import ThreadPoolExecutor

    axis = load_axis(starter)
    design = Design(c=axis.friction.viscous, kv=axis.drive.kv, kp=axis.drive.velocity_loop.kp,
                    ti=axis.drive.velocity_loop.ti)
    a = nonlinear_check(axis, design, forces=(100.0, 400.0), duration=2.0)
    with ThreadPoolExecutor(2) as pool:
        b = nonlinear_check(axis, design, forces=(100.0, 400.0), duration=2.0, executor=pool)
    assert [r["peak_m_per_n"] for r in a["sweeps"]] == [r["peak_m_per_n"] for r in b["sweeps"]]


BAD = [
    # (what is changed in axis.toml, the message that must appear)
    (lambda t: t.replace('[axis]\nname = "my_axis"', '[axis]\nnom = "x"'), r"\[axis\] name"),
    (lambda t: t.replace('file = "structure.npz"', 'file = "missing.npz"'),
     "missing.npz does not exist"),
    (lambda t: t.replace('pads = ["pad1.x", "pad2.x"]', 'pads = ["pad1.x", "pad7.x"]'),
     r"\[friction\] pads: unknown DOF 'pad7.x'"),
    (lambda t: t.replace('rotor = "motor.rotor"', 'rotor = "spindle"'),
     r"\[drive.motor\] rotor: unknown DOF 'spindle'"),
    (lambda t: t.replace('lugre = "bianchi2014"', 'lugre = "teflon"'), r"\[friction\] lugre"),
    (lambda t: t.replace("torque_constant = 1.2", "torque_constant = -1.2"),
     r"\[drive.motor\] torque_constant"),
    (lambda t: t.replace("resistance = 0.4", 'resistance = "0.4 ohm"'),
     r"\[drive.motor\] resistance.*number in SI"),
    (lambda t: t.replace("kp = 3.7 ", "kp_nm = 3.7 "),
     r"\[velocity_loop\]: unknown keys \['kp_nm'\]"),
    (lambda t: t.replace("kv_m_per_min_per_mm = 1.0           # the",
                         "kv_m_per_min_per_mm = 1.0\nkv = 16.7 # the"), "exactly one of kv"),
    (lambda t: t.replace("radial_immersion = 0.5", "radial_immersion = 50.0"),
     r"\[cutting\].*radial"),
    (lambda t: t.replace("ms_position_max = 1.5", "ms_position_max = 0.9"),
     r"\[requirements\].*ms_position_max"),
    (lambda t: t.replace("band_hz = [5.0, 300.0]", "band_hz = [300.0, 5.0]"),
     r"\[requirements\].*band"),
    (lambda t: t.replace('[axis]', '[axes]'), r"sections: unknown \['axes'\]"),
    (lambda t: t + "\n[friction.extra]\nx = 1\n", r"\[friction\]: unknown keys \['extra'\]"),
    (lambda t: t.replace("lugre = \"bianchi2014\"",
                         "lugre = { fc = 7000.0, fs = 6013.0, vs = 0.01, delta = 1.0, "
                         "sigma0 = 5.9e9, sigma1 = 1.6e7, sigma2 = 5578.0 }"),
     r"\[friction\] lugre.*fc"),
    (lambda t: t.replace("lugre = \"bianchi2014\"",
                         "lugre = { fc = 2198.0, fs = 6013.0, vs = 0.01, delta = 1.0, "
                         "sigma0 = 5.9e9, sigma1 = -1.6e7, sigma2 = 5578.0 }"),
     "generate energy"),
]


@pytest.mark.parametrize("change, message", BAD)
def test_bad_axis_files_name_file_field_and_fix_and_write_nothing(starter, tmp_path, change,
                                                                  message, capsys):
    folder = tmp_path / "axis"
    shutil.copytree(starter, folder)
    (folder / "axis.toml").write_text(change((folder / "axis.toml").read_text()))
    with pytest.raises(AxisFormatError, match=message) as info:
        load_axis(folder)
    assert "axis.toml" in str(info.value)
    out = tmp_path / "out"
    assert main(["tune", str(folder), "--out", str(out)]) == 1
    assert "axis.toml" in capsys.readouterr().err
    assert not out.exists()


def test_unreachable_requirement_is_named_and_nothing_written(starter, tmp_path, capsys):
    folder = tmp_path / "axis"
    shutil.copytree(starter, folder)
    text = (folder / "axis.toml").read_text()
    text = text.replace("ms_velocity_max = 2.0", "ms_velocity_max = 1.001")
    (folder / "axis.toml").write_text(text)
    out = tmp_path / "out"
    assert main(["tune", str(folder), "--out", str(out), "--free", "kp", "--starts", "1",
                 "--no-simulation"]) == 1
    assert "Ms velocity loop" in capsys.readouterr().err
    assert not out.exists() or not any(out.iterdir())


def test_tuning_section_sets_free_variables_and_bounds(starter, tmp_path):
    folder = tmp_path / "axis"
    shutil.copytree(starter, folder)
    text = (folder / "axis.toml").read_text()
    text = text.replace('free = ["c", "kv", "kp", "ti"]', 'free = ["c", "kp"]')
    text = text.replace("c = [1.0e3, 1.0e8]", "c = [2.0e4, 5.0e4]")
    (folder / "axis.toml").write_text(text)
    axis = load_axis(folder)
    assert axis.tuning.free == ("c", "kp") and axis.tuning.bounds["c"] == (2e4, 5e4)
    from servotune.design import tune_axis

    job = tune_axis(axis, starts=1)
    assert job.result.problem.free == ("c", "kp")
    assert 2e4 <= job.design.c <= 5e4
    assert job.design.kv == axis.drive.kv  # not free: unchanged
    (folder / "axis.toml").write_text(text.replace("c = [2.0e4, 5.0e4]", "c = [5.0e4, 2.0e4]"))
    with pytest.raises(AxisFormatError, match=r"\[tuning\] c"):
        load_axis(folder)
