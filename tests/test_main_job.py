"""The main job end to end on a small axis, and a catalogue of bad axis descriptions."""

import json
import re
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
    # init -> tune (with the nonlinear verdict) -> results.json + report.html. Tuned on the
    # sampled-data model of its digital drive, the starter's design holds its linear checks,
    # every simulated sweep and the harmonic-balance scan: feeding at 20 mm/s with 3 x the
    # process force the pads still reverse and slip each cycle near 147 Hz (the resonance
    # tests/test_verdict_harmonic.py confirms by a stepped sine), but its periodic response
    # now stays within the 30 % tolerance of the claim; the command exits 0.
    out = tmp_path / "report"
    assert main(["tune", str(starter), "--out", str(out), "--starts", "2", "--workers", "1",
                 "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["verified"] is True and result["status"] == "verified"
    folder = out / f"tune_{result['axis_name']}"
    saved = json.loads((folder / "results.json").read_text())
    assert saved["design"] == result["design"]
    # the claim of every regime is the worst of its models in the dense check; every sweep
    # holds it within the tolerance, decays and sees its peak inside the band
    models = result["performance_after"]["models"]
    for regime in result["regimes"]:
        mine = [m["peak_compliance"] for m in models if m["regime"] == regime["name"]]
        assert regime["claimed_peak_m_per_n"] == max(mine)
        assert regime["nonlinear_peak_after_m_per_n"] <= 1.3 * regime["claimed_peak_m_per_n"]
        sweeps = [s for s in regime["simulations"] if s["kind"] == "sweep"]
        assert sweeps and all(not s["at_edge"] and s["decays"] for s in sweeps)
        assert regime["holds"], regime["reason"]
        for h in regime["harmonic_balance"]:
            assert h["peak_m_per_n"] <= 1.3 * regime["claimed_peak_m_per_n"]
    feeding = next(r for r in result["regimes"] if r["name"] == "feeding 20 mm/s")
    worst = max(feeding["harmonic_balance"], key=lambda h: h["peak_m_per_n"])
    assert 120.0 < worst["resonance_hz"] < 170.0   # the slipping pads' resonance
    assert worst["peak_m_per_n"] > feeding["claimed_peak_m_per_n"]
    assert result["peak_compliance_after"] == max(r["claimed_peak_m_per_n"]
                                                  for r in result["regimes"])
    # the linear checks hold: the thrust budget and the hierarchy of the loops
    assert all(case["fits"] for case in result["thrust"]["cases"])
    assert all(c["holds"] for c in result["checks"])
    page = (folder / "report.html").read_text()
    assert page.count("data:image/png;base64,") >= 5  # self-contained
    assert "Regimes" in page and "Thrust" in page and "Nonlinear verification" in page


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
    (lambda t: re.sub(r"\[friction\.lugre\].*?(?=\[drive\])", "", t, flags=re.S).replace(
        'pads = ["pad1.x", "pad2.x"]', 'pads = ["pad1.x", "pad2.x"]\nlugre = "teflon"'),
     r"\[friction\] lugre"),
    (lambda t: t.replace("torque_constant = 1.2", "torque_constant = -1.2"),
     r"\[drive.motor\] torque_constant"),
    (lambda t: t.replace("resistance = 0.4", 'resistance = "0.4 ohm"'),
     r"\[drive.motor\] resistance.*number in ohm"),
    (lambda t: t.replace("kp = 3.7 ", "kp_nm = 3.7 "),
     r"\[drive\.velocity_loop\]: unknown keys \['kp_nm'\]"),
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
    (lambda t: t.replace("fc = 2198.0 ", "fc = 7000.0 "), r"\[friction\] lugre.*fc"),
    (lambda t: t.replace("sigma1 = 1.6e7 ", "sigma1 = -1.6e7 "), "generate energy"),
    (lambda t: t.replace("torque_continuous = 12.0", "torque_continuous = 50.0"),
     r"\[drive.motor\] torque_continuous.*exceeds"),
    (lambda t: t.replace("torque_continuous = 12.0", "# torque_continuous = 12.0"),
     r"\[drive.motor\] torque_continuous: missing"),
    (lambda t: t.replace("current_period = 125.0e-6", "current_period = 125.0"),
     r"\[drive.sampling\] current_period.*plausible"),
    (lambda t: t.replace("acceleration = 2.0 ", "acceleration = -2.0 "),
     r"\[operation\] acceleration"),
    (lambda t: t.replace("# feed_speeds = [0.01, 0.05]", "feed_speeds = [0.01, 50.0]"),
     r"\[operation\] feed_speeds.*m/s"),
    (lambda t: t.replace("# rapid_speed = 0.5 ", "rapid_speed = 5.0 "),
     r"\[operation\] rapid_speed.*speed_max_rpm"),
    (lambda t: t.replace("# friction_spread = {", "friction_spread = { mu = 0.2 }\n# x = {"),
     r"\[tuning\] friction_spread"),
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
    text = text.replace('free = ["c", "kv", "kp", "ti", "notch"]',
                        'free = ["c", "kp"]\nc = [6.0e3, 8.0e3]')
    (folder / "axis.toml").write_text(text)
    axis = load_axis(folder)
    assert axis.tuning.free == ("c", "kp") and axis.tuning.bounds["c"] == (6e3, 8e3)
    from servotune.design import tune_axis

    job = tune_axis(axis, starts=1)
    assert job.result.problem.free == ("c", "kp")
    assert 6e3 <= job.design.c <= 8e3
    assert job.design.kv == axis.drive.kv  # not free: unchanged
    (folder / "axis.toml").write_text(text.replace("c = [6.0e3, 8.0e3]", "c = [8.0e3, 6.0e3]"))
    with pytest.raises(AxisFormatError, match=r"\[tuning\] c"):
        load_axis(folder)


def test_a_damping_range_the_motor_cannot_push_is_refused_by_name(starter, tmp_path):
    # the starter's 36 N m motor leaves 80 % of 36 / r = 18.1 kN of usable peak thrust; friction
    # 2.2 kN and the moving mass (the rotor's 0.012 kg m^2 over r^2 plus 1102 kg of slide,
    # encoder head and work piece) at 2 m/s^2 take most of it, so at 0.5 m/s rapid a total
    # viscous C above about 8.4 kN s/m does not fit: asking for 20-50 kN s/m fails on the
    # thrust, by name
    from servotune.design import tune_axis
    from servotune.tuning import RequirementsNotMetError

    folder = tmp_path / "axis"
    shutil.copytree(starter, folder)
    text = (folder / "axis.toml").read_text()
    (folder / "axis.toml").write_text(text.replace('free = ["c", "kv", "kp", "ti", "notch"]',
                                                   'free = ["c"]\nc = [2.0e4, 5.0e4]'))
    axis = load_axis(folder)
    mass = 0.012 / axis.drive.ratio**2 + 400.0 + 400.0 + 2.0 + 300.0
    budget = (0.8 * 36.0 / axis.drive.ratio - 2198.0 - mass * 2.0) / 0.5
    from servotune.thrust import moving_mass

    assert moving_mass(axis.structure, axis.pads) == pytest.approx(mass, rel=1e-9)
    with pytest.raises(RequirementsNotMetError, match="thrust: rapid traverse"):
        tune_axis(axis, starts=1)
    assert 8.0e3 < budget < 9.0e3
