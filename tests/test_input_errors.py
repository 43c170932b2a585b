"""Errors in physical terms: implausible friction named as such, an infeasible thrust in kN
with the fields that fix it, and the error as one JSON object under ``--json``.

References: hand calculations from the axis file's own values (the LuGre bristle time
constant sigma1/sigma0 of Bianchi et al. 2014; the usable continuous thrust torque / ratio x
(1 - reserve); the friction at rapid speed Fc + sigma2 v).
"""

import json
import math
from pathlib import Path

import pytest

from servotune.axis import AxisFormatError, load_axis
from servotune.cli import main
from servotune.template import write_template


def _starter(tmp_path, *replacements):
    write_template(tmp_path / "ax")
    toml = tmp_path / "ax" / "axis.toml"
    text = toml.read_text()
    for old, new in replacements:
        assert old in text
        text = text.replace(old, new, 1)
    toml.write_text(text)
    return tmp_path / "ax"


def test_a_bristle_damping_no_contact_has_is_refused(tmp_path):
    """sigma1 = 1e12 N s/m over sigma0 = 5.9e9 N/m is a 169 s bristle time constant (a unit or
    exponent slip: identified contacts give milliseconds, Bianchi 2014: 1.6e7 / 5.9e9 = 2.7
    ms, which loads)."""
    folder = _starter(tmp_path, ("sigma1 = 1.6e7 ", "sigma1 = 1.0e12 "))
    with pytest.raises(AxisFormatError) as err:
        load_axis(folder)
    text = str(err.value)
    assert "[friction.lugre] sigma1" in text and "implausible" in text
    assert f"{1.0e12 / 5.9e9:.3g} s" in text
    axis = load_axis(_starter(tmp_path / "ok"))
    p = axis.friction.lugre
    assert p.sigma1 / p.sigma0 == pytest.approx(1.6e7 / 5.9e9)


def test_an_infeasible_thrust_is_said_in_kn_with_the_fields_that_fix_it(tmp_path, capsys):
    """A motor of 2 N m continuous cannot carry the guide ways' own friction at rapid speed:
    the error gives the thrust needed and usable in kN (hand calculation below), names the
    fields that fix it, speaks of no scaled units, exits 1 and prints one JSON object."""
    folder = _starter(tmp_path, ("torque_continuous = 12.0", "torque_continuous = 2.0"))
    axis = load_axis(folder)
    usable = 2.0 / axis.drive.ratio * (1.0 - axis.requirements.thrust_margin)
    lugre = axis.friction.lugre
    needed = lugre.fc + lugre.sigma2 * axis.operation.rapid_speed
    code = main(["tune", str(folder), "--no-simulation", "--json", "--out",
                 str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert code == 1
    out = json.loads(captured.out)
    assert out["status"] == "error" and out["exit_status"] == 1
    text = out["error"]
    assert text in captured.err
    assert f"needs {needed / 1e3:.3g} kN of {usable / 1e3:.3g} kN usable" in text
    assert "[drive.motor] torque_continuous" in text and "[operation] rapid_speed" in text
    assert "scaled units" not in text


def test_an_input_error_is_one_json_object_under_json(tmp_path, capsys):
    """A missing axis folder: exit 1, the message on standard error and, with --json, the same
    message as the one JSON object on standard output."""
    code = main(["tune", str(tmp_path / "nowhere"), "--json"])
    captured = capsys.readouterr()
    assert code == 1
    out = json.loads(captured.out)
    assert out["status"] == "error" and out["error_kind"] in ("input", "file")
    assert out["error"] in captured.err and "nowhere" in out["error"]


def test_structure_files_and_settings_are_named_in_their_errors(tmp_path):
    """The starter axis' structure.npz broken three ways, and a damping list of the wrong
    length: each error names the file or field and what is wrong, in the project's words
    (not numpy's)."""
    import numpy as np

    folder = _starter(tmp_path)
    npz = folder / "structure.npz"
    data = dict(np.load(npz))
    n = data["mass"].shape[0]
    cases = [
        (lambda: npz.write_text("garbage"), "not an .npz archive"),
        (lambda: np.savez(npz, **{**data, "mass": data["mass"].astype(str)}),
         "mass is not a real 2-D matrix"),
        (lambda: np.savez(npz, **{k: v for k, v in data.items() if k != "stiffness"}),
         "no matrix 'stiffness'"),
    ]
    for write, words in cases:
        write()
        with pytest.raises(AxisFormatError) as err:
            load_axis(folder)
        assert "structure.npz" in str(err.value) and words in str(err.value)
    np.savez(npz, **data)
    toml = folder / "axis.toml"
    toml.write_text(toml.read_text().replace("modal_damping = 0.03 ",
                                             "modal_damping = [0.03, 0.02] ", 1))
    with pytest.raises(AxisFormatError) as err:
        load_axis(folder)
    text = str(err.value)
    assert "[structure] modal_damping" in text and f"2 values for {n} modes" in text
    assert "broadcast" not in text


def test_a_dof_map_direction_that_is_none_is_refused(tmp_path):
    from servotune.structure.io import MatrixFileError, read_dof_map

    good = tmp_path / "good.csv"
    good.write_text("node,dof\n12,UX\n12,ROTZ\n13,3\n")
    assert read_dof_map(good) == ("12.ux", "12.rotz", "13.3")
    bad = tmp_path / "bad.csv"
    bad.write_text("node,dof\n12,UX\n12,UQ\n")
    with pytest.raises(MatrixFileError, match=r"row 2 .*'UQ'"):
        read_dof_map(bad)


def test_rigid_body_mass_needs_every_node(tmp_path):
    """Coordinates of one node of two: the rigid-body 'mass' would count only that node's
    (half of the true total here); refused, naming the missing node. With both, the
    rigid-body mass in X is the total mass (hand sum)."""
    import numpy as np

    from servotune.structure import ModalModel
    from servotune.structure.cbcheck import cb_check

    m = np.diag([2.0, 2.0, 2.0, 3.0, 3.0, 3.0])
    k = np.zeros((6, 6))
    k[np.ix_([0, 3], [0, 3])] = [[1e6, -1e6], [-1e6, 1e6]]
    for a in (1, 2):
        k[np.ix_([a, a + 3], [a, a + 3])] = [[1e6, -1e6], [-1e6, 1e6]]
    dofs = ["1.x", "1.y", "1.z", "2.x", "2.y", "2.z"]
    model = ModalModel(m, k, dofs)
    with pytest.raises(ValueError, match=r"cover 1 of the 2 nodes .*'2'"):
        cb_check(model, coordinates={"1": (0.0, 0.0, 0.0)})
    check = cb_check(model, coordinates={"1": (0.0, 0.0, 0.0), "2": (1.0, 0.0, 0.0)})
    assert check.rigid_body_mass[0, 0] == pytest.approx(5.0)


@pytest.mark.parametrize("command", [["tune", "--no-simulation"],
                                     ["nlcompliance", "--force-pp", "600", "--harmonics", "3",
                                      "--f-start-hz", "40", "--f-end-hz", "70", "--continuous",
                                      "--no-plots"]])
def test_a_law_without_lugre_data_is_taken_by_the_jobs_that_used_to_need_lugre(tmp_path, capsys,
                                                                             command):
    """The bundled axis with the GMS law: the design job and harmonic balance take the axis'
    own law (no internal error, no LuGre stand-in) and name it in their JSON."""
    import re
    import shutil

    from test_friction_gms import P

    folder = tmp_path / "axis"
    shutil.copytree(Path(__file__).resolve().parents[1] / "models" / "paper_x_axis", folder)
    text = re.sub(r"variation = \{[^}]*\}[^\n]*\n(\s+#[^\n]*\n)*", "",
                  (folder / "axis.toml").read_text())
    start, end = text.index("[friction.lugre]"), text.index("[drive]")
    table = "\n".join(f"{k} = {v!r}" for k, v in (
        ("stiffness", list(P.stiffness)), ("fractions", list(P.fractions)),
        ("damping", list(P.damping)), ("fc", P.fc), ("fs", P.fs), ("vs", P.vs),
        ("delta", P.delta), ("sigma2", P.sigma2), ("attraction", P.attraction)))
    (folder / "axis.toml").write_text(text[:start] + "[friction.gms]\n" + table + "\n\n"
                                      + text[end:])
    name, *flags = command
    code = main([name, str(folder), *flags, "--json", "--out", str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert code in (0, 1, 3), captured.err      # 3: tune's linear check only (documented)
    out = json.loads(captured.out)
    assert out["friction_law"] == "gms"
    assert "internal error" not in captured.err
    if name == "tune":
        assert {m["friction_law"] for m in out["regime_models"]} == {"gms"}
        # the feeding regimes' friction level is GMS' own Stribeck curve at their speed
        feeding = [m for m in out["regime_models"] if m["model"] == "sliding"]
        for m in feeding:
            v = m["speed_m_per_s"]
            level = P.fc + (P.fs - P.fc) * math.exp(-((v / P.vs) ** P.delta))
            assert m["friction_level_n"] == pytest.approx(level, rel=1e-9)


def test_without_a_drive_any_law_tunes_the_viscous_pads(tmp_path, capsys):
    """The two-mass axis of Fig 5 (no drive) with its damper given as the viscous law: tune
    needs no LuGre data there and reaches the closed-form Copt (4.912e5 N s/m, the paper's)."""
    import shutil

    folder = tmp_path / "tm"
    shutil.copytree(Path(__file__).resolve().parents[1] / "models" / "two_mass_fig5", folder)
    toml = folder / "axis.toml"
    text = toml.read_text()
    line = next(x for x in text.splitlines() if x.startswith("viscous = "))
    toml.write_text(text.replace(line, "", 1).replace(
        'pads = ["pad1.x"]', 'pads = ["pad1.x"]\n[friction.viscous]\nc = 4.912e5', 1))
    code = main(["tune", str(folder), "--json", "--out", str(tmp_path / "out")])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["friction_law"] == "viscous"
    assert out["design"]["c"] == pytest.approx(4.912e5, rel=1e-3)


def _every_sample_fails(settings, sample):
    """A study task whose every sample fails (as an unstable loop or a refused axis would)."""
    return {"sample_id": int(sample["sample_id"]), "key": sample["key"], "axis": "ax",
            "status": "failed", "error": "RuntimeError: the closed loop is unstable",
            "time_s": 0.0, "worker": "here"}


def test_a_study_whose_every_sample_failed_exits_1_and_says_so(tmp_path, capsys, monkeypatch):
    """Two samples, both failed: exit status 1 (not 0), the counts say 0 done and 2 failed,
    one error line names the count, the first reason and where the rows are, and the one
    JSON object says status "failed" with exit_status 1; the rows stay for a look."""
    import functools
    import sys

    import cloudpickle

    import servotune.study
    from servotune.study import runner

    write_template(tmp_path / "ax")
    study = tmp_path / "s.toml"
    study.write_text('[study]\nname = "s"\naxes = ["ax"]\ncompute = ["compliance"]\n'
                     'samples = 2\nseed = 0\n[vary."friction.lugre.fc"]\n'
                     'distribution = "uniform"\nlow = 0.9\nhigh = 1.1\nrelative = true\n')
    monkeypatch.setattr(servotune.study, "run_study",
                        functools.partial(runner.run_study, task=_every_sample_fails))
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    try:
        args = ["study", str(study), "--workers", "1", "--out", str(tmp_path / "out"),
                "--no-plots"]
        assert main(args) == 1
        captured = capsys.readouterr()
        assert captured.out.startswith("study s: 2 of 2 samples run: 0 done, 2 failed\n")
        assert ("servotune study: error: all 2 samples failed, so the study has no result "
                "(sample 0: RuntimeError: the closed loop is unstable); the reasons are in "
                ) in captured.err
        assert "study_s/results.parquet" in captured.err
        assert main([*args, "--json"]) == 1  # all done before: still no result
        out = json.loads(capsys.readouterr().out)
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
    assert out["status"] == "failed" and out["exit_status"] == 1
    assert (out["summary"]["done"], out["summary"]["failed"]) == (0, 2)


def test_study_counts_name_the_samples_whose_design_fails_its_checks():
    """Rows done but with a design that fails its linear checks (an unstable loop: no peak)
    are counted apart, not passed off as plain "done"."""
    from servotune.study import summarise

    rows = [{"sample_id": 0, "status": "done", "linear_ok": False},
            {"sample_id": 1, "status": "done", "linear_ok": True},
            {"sample_id": 2, "status": "failed", "error": "ValueError: x"}]
    s = summarise(rows, 3)
    assert s.counts() == ("3 of 3 samples run: 2 done (1 with a design that fails its linear "
                          "checks), 1 failed")
    assert s.to_dict()["linear_checks_failed"] == 1
    assert summarise(rows[1:], 2).counts() == "2 of 2 samples run: 1 done, 1 failed"


@pytest.mark.parametrize("argv, words", [
    (["lobes", "--mode", "922", "0.011", "1.34e6", "--teeth", "0"],
     "argument --teeth: '0' is not accepted: give a whole number from 1 to 100"),
    (["nlcompliance", "AXIS"], "the following arguments are required: --force-pp"),
    (["modes", "AXIS", "--no-plots"], "--no-plots: servotune modes writes no figures"),
    (["twomass", "--m1", "nan"], "argument --m1"),
])
def test_a_usage_error_is_one_json_object_under_json(tmp_path, capsys, argv, words):
    """A flag argparse refuses: exit 2, its usage message on standard error and, with --json,
    the same message as the one JSON object on standard output (error_kind "usage")."""
    axis = str(Path(__file__).resolve().parents[1] / "models" / "paper_x_axis")
    argv = [axis if a == "AXIS" else a for a in argv]
    code = main([*argv, "--json"])
    captured = capsys.readouterr()
    assert code == 2
    out = json.loads(captured.out)
    assert out == {"command": f"servotune {argv[0]}", "status": "error", "error_kind": "usage",
                   "error": out["error"], "exit_status": 2}
    assert words in out["error"] and out["error"] in captured.err
    assert main(argv) == 2 and capsys.readouterr().out == ""  # without --json: no JSON


def test_an_axis_named_by_its_axis_toml_is_the_same_axis_as_its_folder(tmp_path, capsys):
    """modes on the folder, then on its axis.toml, then on the folder: one axis, so each run
    replaces its own results (it used to be refused as 'another axis of the same name')."""
    folder = _starter(tmp_path)
    out = ["--out", str(tmp_path / "out")]
    for target in (folder, folder / "axis.toml", folder):
        assert main(["modes", str(target), *out]) == 0, capsys.readouterr().err
    assert "another axis" not in capsys.readouterr().err
    other = tmp_path / "other" / "ax"
    other.parent.mkdir()
    write_template(other)  # the same [axis] name as the first
    assert main(["modes", str(other / "axis.toml"), *out]) == 1  # a different axis: refused
    assert "another axis of the same name" in capsys.readouterr().err


def test_ctrl_c_under_json_is_one_json_object(tmp_path, capsys, monkeypatch):
    """Interrupted under --json (a command, and a study before its first sample): exit 130,
    the one line on standard error and the same line as the one JSON object on standard
    output (error_kind "interrupted"), as for every other end of a command."""
    import servotune.cli.twomass
    import servotune.study

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(servotune.cli.twomass, "run", interrupted)
    monkeypatch.setattr(servotune.study, "run_study", interrupted)
    write_template(tmp_path / "ax")
    study = tmp_path / "s.toml"
    study.write_text('[study]\nname = "s"\naxes = ["ax"]\ncompute = ["compliance"]\n')
    for argv in (["twomass"], ["study", str(study), "--out", str(tmp_path / "out")]):
        assert main([*argv, "--json"]) == 130
        captured = capsys.readouterr()
        out = json.loads(captured.out)
        assert out["error_kind"] == "interrupted" and out["exit_status"] == 130
        assert out["error"] == captured.err.strip()
        assert out["error"].startswith(f"servotune {argv[0]}: interrupted")
        assert "nothing was written" in out["error"]


def test_an_empty_list_of_feed_speeds_is_said_to_mean_standing_only(tmp_path, capsys):
    """feed_speeds = [] leaves out every feeding regime: loaded (a standing-only axis is
    legitimate) but said among the defaults taken, not silently."""
    folder = _starter(tmp_path, ("# feed_speeds = [0.01, 0.05]", "feed_speeds = []"))
    axis = load_axis(folder)
    assert axis.operation.feed_speeds == ()
    assert any("feed_speeds = []: no feeding regime, the axis is judged standing only" in d
               for d in axis.defaults)
    assert main(["modes", str(folder), "--out", str(tmp_path / "out")]) == 0
    assert "default taken: [operation] feed_speeds = []: no feeding regime" in \
        capsys.readouterr().out


def test_lobes_says_default_taken_for_what_stands_in(tmp_path, capsys):
    """One vocabulary in every command: the benchmark's cutting values that stand in for the
    flags not given, and the axis' own defaults, are each 'default taken:' in lobes as in
    modes and bode."""
    code = main(["lobes", "--mode", "922", "0.011", "1.34e6", "--speed-count", "50",
                 "--out", str(tmp_path / "out")])
    text = capsys.readouterr().out
    assert code == 0
    assert "  default taken: cutting set-up not given in full: --teeth 2" in text
    assert "  note: cutting set-up" not in text
