"""The command line, called in-process through ``main([...])``: results, the output policy,
interruption, start-up and the listed small fixes."""

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import two_mass_reference as ref

from servotune.cli import COMMANDS, SUMMARIES, _common, build_parser, main
from servotune.cli._common import RunOutput, print_json, to_jsonable

MODELS = Path(__file__).resolve().parents[1] / "models"


def test_twomass_json_matches_the_closed_forms_of_layout_b(tmp_path, capsys):
    # ground --C-- M1 --K-- M2 (paper sec 4.1, written out in two_mass_reference): the fixed
    # points, Copt, the peak g(a)/K at the second fixed point; the resonance is the free pair
    # for C = 0, M2 on K for C -> inf
    assert main(["twomass", "--m1", "5000", "--k", "16e6", "--alpha", "0.3",
                 "--out", str(tmp_path), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    hz = 1.0 / (2 * math.pi)
    fixed = np.array(ref.fixed_points())
    np.testing.assert_allclose(result["fixed_points_hz"], fixed * hz, rtol=1e-12)
    np.testing.assert_allclose(result["c_opt"], ref.c_opt(), rtol=1e-10)
    np.testing.assert_allclose(result["c_opt"], ref.COPT_PAPER, rtol=1e-4)
    np.testing.assert_allclose(result["peak_compliance"], ref.g() / ref.K, rtol=1e-10)
    np.testing.assert_allclose(result["peak_frequency_hz"], fixed[1] * hz, rtol=1e-10)
    np.testing.assert_allclose(result["resonance_c0_hz"], hz * math.sqrt(
        ref.K * (ref.M1 + ref.M2) / (ref.M1 * ref.M2)), rtol=1e-12)
    np.testing.assert_allclose(result["resonance_cinf_hz"], math.sqrt(ref.K / ref.M2) * hz,
                               rtol=1e-12)
    folder = tmp_path / "twomass_layout_B"
    assert result["folder"] == str(folder)
    assert [Path(f).name for f in result["figures"]] == ["fig5_compliance.png",
                                                         "fig4_g_alpha.png"]
    for f in result["figures"]:
        assert Path(f).parent == folder and Path(f).stat().st_size > 10_000
    assert json.loads((folder / "results.json").read_text()) == result


def test_twomass_layout_a_matches_its_closed_forms_without_plots(tmp_path, capsys):
    # ground --K-- M2 --C-- M1 (a Lanchester damper, the reading of the paper's unreadable
    # layout A figure that servotune.twomass documents): one fixed point
    # w^2 = 2 K / (M1 + 2 M2), Copt = sqrt(K M2) sqrt(2 / ((1 + a)(1 + 2 a))); |H| there is the
    # same for every C, so the C -> inf value 1 / |K - (M1 + M2) w^2|; the resonance is M2 on K
    # for C = 0 and M1 + M2 on K for C -> inf
    assert main(["twomass", "--layout", "A", "--no-plots", "--out", str(tmp_path),
                 "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    a, hz = ref.ALPHA, 1.0 / (2 * math.pi)
    m1, m2, k = ref.M1, ref.M2, ref.K
    wf = math.sqrt(2 * k / (m1 + 2 * m2))
    np.testing.assert_allclose(result["fixed_points_hz"], [wf * hz], rtol=1e-12)
    np.testing.assert_allclose(result["c_opt"], math.sqrt(k * m2) * math.sqrt(
        2 / ((1 + a) * (1 + 2 * a))), rtol=1e-10)
    np.testing.assert_allclose(result["peak_compliance"], 1 / abs(k - (m1 + m2) * wf**2),
                               rtol=1e-10)
    np.testing.assert_allclose(result["resonance_c0_hz"], math.sqrt(k / m2) * hz, rtol=1e-12)
    np.testing.assert_allclose(result["resonance_cinf_hz"], math.sqrt(k / (m1 + m2)) * hz,
                               rtol=1e-12)
    assert sorted(p.name for p in (tmp_path / "twomass_layout_A").iterdir()) == [
        ".servotune-run.json", "results.json"]
    assert main(["twomass", "--layout", "A", "--no-plots", "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "layout A" in text
    printed = re.search(r"Copt\s*:\s*(\S+) N s/m", text)
    assert printed and float(printed.group(1)) == pytest.approx(result["c_opt"], rel=1e-4)


# --------------------------------------------------------------------------- output policy

def test_a_run_replaces_its_own_results_and_keeps_what_it_did_not_write(tmp_path, capsys):
    folder = tmp_path / "twomass_layout_B"
    assert main(["twomass", "--out", str(tmp_path), "--alpha", "0.3", "--json"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert main(["twomass", "--out", str(tmp_path), "--alpha", "0.5", "--json"]) == 0
    second = json.loads(capsys.readouterr().out)
    assert second["c_opt"] != first["c_opt"]
    assert json.loads((folder / "results.json").read_text())["c_opt"] == second["c_opt"]
    # a file the user put there: refused before any work, in CLI words, nothing changed
    (folder / "notes.txt").write_text("mine")
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    assert main(["twomass", "--out", str(tmp_path), "--alpha", "0.7"]) == 1
    err = capsys.readouterr().err
    assert "notes.txt" in err and "another --out" in err and "force=" not in err
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["twomass_layout_B"]  # no leftovers


def test_the_old_force_flag_is_accepted_but_hidden(tmp_path, capsys):
    assert main(["twomass", "--no-plots", "--out", str(tmp_path), "--force"]) == 0
    assert "--force" not in build_parser("twomass").format_help()


@pytest.mark.parametrize("name", ["../../x", "/etc/x", "a/b", "..", ".hidden", "x y\tz"])
def test_a_subject_name_never_leads_outside_out(tmp_path, name):
    out = tmp_path / "out"
    run = RunOutput(out, "bode", name, ["bode.png"])
    assert run.path.parent == out and not run.path.name.startswith(".")
    with run.writing() as folder:
        (folder / "bode.png").write_bytes(b"x")
    assert sorted(p for p in tmp_path.rglob("*") if p.is_file()) == sorted(
        [run.path / "bode.png", run.path / RunOutput.MANIFEST])


def test_an_axis_named_to_escape_writes_inside_out(tmp_path, capsys):
    import shutil

    axis = tmp_path / "axis"
    shutil.copytree(MODELS / "two_mass_fig5", axis)
    toml = axis / "axis.toml"
    text = toml.read_text()
    start = text.index("name = ")
    end = text.index("\n", start)
    toml.write_text(text[:start] + 'name = "../../escaped"' + text[end:])
    out = tmp_path / "deep" / "out"
    assert main(["modes", str(axis), "--out", str(out)]) == 0
    written = [p for p in tmp_path.rglob("*") if p.is_file() and axis not in p.parents]
    assert written and all(out in p.parents for p in written)


@pytest.mark.parametrize("layout", ["file", "under_file"])
def test_out_that_cannot_be_a_folder_is_a_clear_error(tmp_path, capsys, layout):
    blocker = tmp_path / "results.txt"
    blocker.write_text("a file")
    out = blocker if layout == "file" else blocker / "sub"
    assert main(["twomass", "--no-plots", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "results.txt is a file" in err and "Traceback" not in err
    assert blocker.read_text() == "a file" and sorted(tmp_path.iterdir()) == [blocker]


def test_out_without_permission_is_a_clear_error(tmp_path, capsys, monkeypatch):
    # (as root, permissions do not stop writing: the refusal is simulated where it happens)
    import servotune.cli._common as common

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(common.tempfile, "mkdtemp", refuse)
    out = tmp_path / "new" / "out"
    assert main(["twomass", "--no-plots", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "permission denied" in err.lower() and "--out" in err
    assert not (tmp_path / "new").exists()  # the folders made for it are gone again


def test_out_in_a_read_only_folder_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    import os

    import servotune.cli._common as common

    real = os.access
    monkeypatch.setattr(common.os, "access", lambda p, mode: False if Path(p) == tmp_path
                        else real(p, mode))
    assert main(["twomass", "--no-plots", "--out", str(tmp_path / "out")]) == 1
    assert "no permission to write into" in capsys.readouterr().err


def test_ctrl_c_exits_130_with_one_line_and_keeps_the_earlier_results(tmp_path, capsys,
                                                                      monkeypatch):
    assert main(["twomass", "--no-plots", "--out", str(tmp_path)]) == 0
    folder = tmp_path / "twomass_layout_B"
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    capsys.readouterr()
    import servotune.cli._common as common

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(common, "write_results", interrupted)
    monkeypatch.setattr("servotune.cli.twomass.write_results", interrupted)
    assert main(["twomass", "--no-plots", "--out", str(tmp_path), "--alpha", "0.5"]) == 130
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "interrupted" in err and "nothing was written" in err
    assert "Traceback" not in err
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["twomass_layout_B"]


def test_ctrl_c_names_the_task_it_interrupted(tmp_path, capsys, monkeypatch):
    from servotune import progress

    def slow(*args, **kwargs):
        with progress.task("fixed points", total=4) as t:
            t.update(1)
            raise KeyboardInterrupt

    monkeypatch.setattr("servotune.twomass.analyse_two_mass", slow)
    assert main(["twomass", "--no-plots", "--out", str(tmp_path)]) == 130
    assert "interrupted during fixed points (1/4)" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_an_unexpected_error_is_one_line_not_a_traceback(tmp_path, capsys, monkeypatch):
    def broken(*args, **kwargs):
        raise AttributeError("'NoneType' object has no attribute 'x'")

    monkeypatch.setattr("servotune.twomass.analyse_two_mass", broken)
    assert main(["twomass", "--no-plots", "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "internal error" in err and err.count("\n") == 1 and not any(tmp_path.iterdir())


# --------------------------------------------------------------------------- JSON

def test_non_finite_values_become_null_with_a_reason(capsys):
    loop = {"phase_margin_deg": math.inf, "crossover_hz": math.nan, "ms": 1.2,
            "gains": np.array([1.0, np.nan]), "n": np.int64(3)}
    print_json({"velocity_loop": loop})
    out = json.loads(capsys.readouterr().out)["velocity_loop"]
    assert out["phase_margin_deg"] is None and out["crossover_hz"] is None
    assert "no gain crossover" in out["phase_margin_deg_reason"]
    assert out["phase_margin_deg_reason"].startswith("+infinity")
    assert out["crossover_hz_reason"].startswith("not a number")
    assert out["gains"] == [1.0, None] and "null entries" in out["gains_reason"]
    assert out["ms"] == 1.2 and out["n"] == 3 and "ms_reason" not in out
    assert to_jsonable(math.inf) is None


# --------------------------------------------------------------------------- the listed fixes

def test_modes_band_is_printed_in_hz(tmp_path, capsys):
    assert main(["modes", str(MODELS / "two_mass_fig5"), "--pads", "locked", "--out",
                 str(tmp_path)]) == 0
    text = capsys.readouterr().out
    result = json.loads((tmp_path / "modes_two_mass_fig5" / "results.json").read_text())
    low, high = result["band_hz"]
    assert f"({low:g}-{high:g} Hz)" in text
    from servotune.axis import load_axis

    band = load_axis(MODELS / "two_mass_fig5").requirements.band
    np.testing.assert_allclose([low, high], np.array(band) / (2 * math.pi))
    # with the pad (M1) locked, M2 rings on K alone: one mode at sqrt(K / M2)
    np.testing.assert_allclose(result["frequencies_hz"],
                               [math.sqrt(ref.K / ref.M2) / (2 * math.pi)], rtol=1e-12)


def test_init_names_the_axis_after_its_folder(tmp_path, capsys):
    from servotune.axis import load_axis

    folder = tmp_path / "x axis of mill 3"
    assert main(["init", str(folder), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["axis"] == "x_axis_of_mill_3"
    assert load_axis(folder).name == "x_axis_of_mill_3"
    assert main(["init", str(folder)]) == 1
    err = capsys.readouterr().err
    assert "--force" in err and "force=True" not in err
    assert main(["init", str(folder), "--force"]) == 0


def test_the_template_lists_only_structure_formats_that_load():
    import re

    from servotune.structure import io
    from servotune.template import TEMPLATE_TOML

    listed = set(re.findall(r"(\.[a-z]{2,5})\b", TEMPLATE_TOML.split("[friction]")[0]))
    listed -= {".x", ".y", ".z", ".rotor", ".stator", ".csv"}  # DOF names, the DOF map
    known = set(io._MTX) | set(io._HB) | {".mat", ".npz"}
    assert listed and listed <= known, listed - known


def test_friction_json_before_fit_prints_json(tmp_path, capsys):
    from servotune.friction import lugre
    from servotune.friction.lugre import BIANCHI2014

    v = np.concatenate([-np.geomspace(2e-4, 0.5, 20), np.geomspace(2e-4, 0.5, 20)])
    data = tmp_path / "curve.csv"
    rows = "\n".join(f"{a:.17g},{b:.17g}" for a, b in
                     zip(v, lugre.steady_state_friction(BIANCHI2014, v), strict=True))
    data.write_text("v_m_per_s,f_n\n" + rows + "\n")
    assert main(["friction", "--json", "fit", str(data), "--no-plots", "--out",
                 str(tmp_path)]) == 0
    assert json.loads(capsys.readouterr().out)["estimates"]["fc"] == pytest.approx(
        BIANCHI2014.fc, rel=1e-3)


# --------------------------------------------------------------------------- parser

def test_the_summaries_agree_with_the_commands():
    parser = build_parser()
    actions = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    helps = {c.dest: c.help for c in actions._choices_actions}
    assert set(helps) == set(COMMANDS)
    for name, text in SUMMARIES.items():
        assert helps[name] == text, name


def test_parameter_set_and_interval_constants_agree_with_the_library():
    from servotune import chatter
    from servotune.cli import friction, lobes
    from servotune.friction.lugre import LuGreParameters

    assert friction.PARAMETER_SETS == LuGreParameters.names()
    assert lobes.DEFAULT_INTERVALS == chatter.DEFAULT_INTERVALS


def test_help_and_argument_errors_load_no_numerics():
    # what keeps `servotune --help` fast: none of the heavy libraries is imported
    code = ("import sys\nfrom servotune.cli import main\n"
            "codes = [main(['--help']), main(['modes', 'x', '--count', '-3']),"
            " main(['lobes', '--speeds', '0'])]\n"
            "heavy = sorted(m for m in ('numpy', 'scipy', 'control', 'casadi', 'numba',"
            " 'matplotlib') if m in sys.modules)\n"
            "print(codes, heavy, file=sys.stderr)\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert run.stderr.strip().splitlines()[-1] == "[0, 2, 2] []"


@pytest.mark.parametrize("given", [None, "2"])
def test_the_command_runs_blas_on_one_thread_unless_told_otherwise(given, tmp_path):
    # numpy reads the thread count when it is loaded: the command sets it before, and keeps
    # the user's own setting
    import os

    from servotune.cli import THREAD_VARIABLES

    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    if given is not None:
        env["OPENBLAS_NUM_THREADS"] = given
    code = ("import os, sys\nfrom servotune.cli import main\n"
            f"code = main(['twomass', '--no-plots', '--out', {str(tmp_path)!r}])\n"
            "print(code, 'numpy' in sys.modules, os.environ['OPENBLAS_NUM_THREADS'],"
            " os.environ['OMP_NUM_THREADS'], file=sys.stderr)\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=env)
    assert run.stderr.strip().splitlines()[-1] == f"0 True {given or '1'} 1"


def test_import_servotune_is_lazy_but_complete():
    code = ("import sys, servotune as st\n"
            "assert 'control' not in sys.modules and 'numpy' not in sys.modules\n"
            "missing = [n for n in st.__all__ if getattr(st, n, None) is None]\n"
            "print(missing, st.load_axis.__module__, st.analysis.__name__)\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert run.stdout.split() == ["[]", "servotune.axis", "servotune.analysis"]


def _subparser(command):
    parser = build_parser(command)
    actions = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    return actions.choices[command]


def _option(parser, flag):
    return next((a for a in parser._actions if flag in a.option_strings), None)


def _flag_table():
    text = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    section = text.split("## Command-line flags", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0].startswith("`--"):
            flag = cells[0].strip("`").split()[0]
            rows[flag] = [c.strip() for c in cells[3].split(",")]
    return rows


def test_the_readme_flag_table_matches_the_commands():
    rows = _flag_table()
    assert set(rows) == {"--json", "--quiet", "--out", "--no-plots", "--workers", "--duration",
                         "--force", "--continuous", "--speed", "--speed-rpm", "--speed-count",
                         "--force-pp"}
    for flag, commands in rows.items():
        if commands == ["all"]:
            commands = list(COMMANDS)
        for command in commands:
            words = command.split()
            parser = _subparser(words[0])
            if len(words) == 2:
                actions = next(a for a in parser._actions
                               if a.__class__.__name__ == "_SubParsersAction")
                parser = actions.choices[words[1]]
            assert _option(parser, flag) is not None, (flag, command)
            assert "==SUPPRESS==" not in str(_option(parser, flag).help), (flag, command)


@pytest.mark.parametrize("command", COMMANDS)
def test_one_default_per_notion(command):
    parser = _subparser(command)
    defaults = {"--out": Path(_common.DEFAULT_OUT), "--workers": None, "--duration": 20.0,
                "--json": False, "--quiet": False, "--no-plots": False}
    for flag in ("--json", "--quiet"):
        assert _option(parser, flag).default is False, flag
    if command != "init":
        assert _option(parser, "--out") is not None, "--out"
    for flag, default in defaults.items():
        action = _option(parser, flag)
        if action is not None:
            assert action.default == default, (flag, action.default)
    for old in ("--sweep-duration",):
        action = _option(parser, old)
        assert action is None or action.help == "==SUPPRESS==", old


def test_helpers_for_the_tune_and_verify_rework():
    import argparse

    from servotune.cli._common import (
        STARTS,
        add_common_options,
        add_duration_option,
        add_workers_option,
        default_workers,
    )

    parser = argparse.ArgumentParser(prog="servotune tune")
    parser.add_argument("--starts", type=STARTS, default=4)
    add_duration_option(parser, aliases=("--sweep-duration",))
    add_workers_option(parser)
    add_common_options(parser, plots=True)
    args = parser.parse_args(["--sweep-duration", "4", "--starts", "2"])
    assert args.duration == 4.0 and args.starts == 2 and args.workers is None
    assert args.out == Path(_common.DEFAULT_OUT) and not args.no_plots
    assert "--sweep-duration" not in parser.format_help()
    for bad in (["--starts", "0"], ["--starts", "-5"], ["--starts", "1000000"],
                ["--sweep-duration", "0"], ["--workers", "0"]):
        with pytest.raises(SystemExit):
            parser.parse_args(bad)
    assert default_workers() >= 1


@pytest.mark.parametrize("quiet, as_json, tty, shown", [
    (False, False, True, True), (True, False, True, False), (False, True, True, False),
    (False, False, False, False)])
def test_progress_only_on_a_terminal_without_quiet_or_json(quiet, as_json, tty, shown,
                                                           monkeypatch):
    import argparse

    from servotune.cli._common import show_progress

    monkeypatch.setattr(sys.stderr, "isatty", lambda: tty, raising=False)
    assert show_progress(argparse.Namespace(quiet=quiet, json=as_json)) is shown


# --- verify reads the design as tune writes it; contact flags; sampling; [drive.motor] -------

def test_verify_reads_the_results_file_tune_writes(tmp_path):
    # tune writes the design through to_jsonable: a Ti without integral action (inf) becomes
    # null with 'ti_reason' beside it; read_result takes it back as inf
    from servotune.cli._common import write_results
    from servotune.cli.verify import read_result
    from servotune.tuning import Design

    design = Design(c=5578.0, kv=25.5, kp=5.85, ti=math.inf)
    write_results(tmp_path, {"axis": "axis", "design": design.to_dict()})
    (tmp_path / "axis").mkdir()
    axis, values, fixed = read_result(tmp_path / "results.json")
    assert axis == tmp_path / "axis" and fixed is None
    assert values == {"c": 5578.0, "kv": 25.5, "kp": 5.85, "ti": math.inf}
    assert Design(**values) == design


@pytest.mark.parametrize("flag, accepted", [
    ("--force-pp", "(0, 1e+06] N"), ("--speed", "(0, 10] m/s"),
    ("--f-start-hz", "(0, 100000] Hz"), ("--f-end-hz", "(0, 100000] Hz")])
def test_verify_flags_state_their_range_in_the_help(flag, accepted):
    parser = build_parser("verify")
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    action = next(a for a in sub.choices["verify"]._actions if flag in a.option_strings)
    assert accepted in " ".join(action.help.split())


@pytest.mark.parametrize("flags, kind, parameters", [
    (["--contact", "sliding", "--speed", "0.03"], "sliding", {"speed": 0.03}),
    (["--contact", "equivalent", "--amplitude", "2e-6", "--frequency-hz", "50"], "equivalent",
     {"amplitude": 2e-6, "frequency_hz": 50.0})])
def test_compliance_flags_that_fit_the_contact_still_work(tmp_path, capsys, flags, kind,
                                                          parameters):
    # the peak the command reports for the contact its flags describe, against a second
    # evaluation: python-control's own frequency response of that closed-loop plant, on a
    # fine grid around the peak
    import control

    from servotune.analysis import axis_contact, axis_plant
    from servotune.axis import load_axis

    assert main(["compliance", str(MODELS / "paper_x_axis"), "--continuous", *flags,
                 "--no-plots", "--json", "--out", str(tmp_path)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["contact"] == kind
    axis = load_axis(MODELS / "paper_x_axis").with_continuous_drive()
    plant = axis_plant(axis, axis_contact(axis, kind, **parameters))
    sub = plant[plant.output_labels.index("wp_x"), plant.input_labels.index("f_wp_x")]
    f_peak = out["peak_frequency_hz"]
    omega = 2 * math.pi * np.linspace(0.97 * f_peak, 1.03 * f_peak, 2001)
    response = np.abs(control.frequency_response(sub, omega).complex.ravel())
    assert out["peak_compliance"] == pytest.approx(response.max(), rel=1e-4)
    assert f_peak == pytest.approx(omega[np.argmax(response)] / (2 * math.pi), rel=1e-4)


def test_axis_contact_names_its_own_parameters():
    from servotune.analysis import axis_contact
    from servotune.axis import load_axis

    axis = load_axis(MODELS / "paper_x_axis")
    with pytest.raises(ValueError, match=r"amplitude .* and frequency_hz"):
        axis_contact(axis, "equivalent", amplitude=2e-6)
    with pytest.raises(ValueError, match="non-zero speed"):
        axis_contact(axis, "sliding", speed=0.0)
    with pytest.raises(ValueError, match="speed is a parameter of the 'sliding' contact"):
        axis_contact(axis, "locked", speed=0.03)


def _starter(tmp_path, old, new):
    """The starter axis of servotune init with ``old`` replaced by ``new`` in axis.toml."""
    from servotune.template import template_toml, write_template

    write_template(tmp_path / "ax", name="ax")
    text = template_toml("ax")
    assert text.count(old) == 1, old
    (tmp_path / "ax" / "axis.toml").write_text(text.replace(old, new))
    return tmp_path / "ax"


@pytest.mark.parametrize("key", ["current_period", "velocity_period", "position_period"])
def test_a_zero_sample_period_is_refused_and_points_to_continuous(tmp_path, key):
    from servotune.axis import AxisFormatError, load_axis

    old = {"current_period": "current_period = 125.0e-6",
           "velocity_period": "velocity_period = 125.0e-6",
           "position_period": "position_period = 1.0e-3"}[key]
    axis = _starter(tmp_path, old, f"{key} = 0.0")
    with pytest.raises(AxisFormatError) as info:
        load_axis(axis)
    text = str(info.value)
    assert f"[drive.sampling] {key}" in text and "must be > 0" in text
    assert "continuous = true" in text


def test_drive_motor_keys_name_the_section_and_offer_no_alias(tmp_path):
    from servotune.axis import AxisFormatError, load_axis

    axis = _starter(tmp_path, "torque_constant = 1.2", "torque_konstant = 1.2")
    with pytest.raises(AxisFormatError) as info:
        load_axis(axis)
    text = str(info.value)
    assert "[drive.motor]: unknown key 'torque_konstant'" in text and "[motor]" not in text
    assert "'torque_peak'" in text and "torque_max" not in text


def test_torque_max_stays_accepted_as_the_older_name_of_torque_peak(tmp_path):
    from servotune.axis import load_axis

    # with torque_continuous it is the peak torque of the thrust budget
    axis = load_axis(_starter(tmp_path, "torque_peak = 36.0", "torque_max = 36.0"))
    assert axis.drive.limits.torque_peak == 36.0


@pytest.mark.parametrize("command", ["bode", "modes", "compliance"])
def test_an_omitted_section_is_stated_in_one_line_of_the_output(command, tmp_path, capsys):
    # the starter axis without [requirements] and [tuning]: the defaults that stand in are
    # said, once each, in the text output and in the JSON notes
    from servotune.template import write_template

    write_template(tmp_path / "ax")
    lines, keep = [], True
    for line in (tmp_path / "ax" / "axis.toml").read_text().splitlines():
        if line.startswith("["):
            keep = not line.startswith(("[requirements]", "[tuning]"))
        if keep:
            lines.append(line)
    (tmp_path / "ax" / "axis.toml").write_text("\n".join(lines) + "\n")
    argv = [command, str(tmp_path / "ax"), "--out", str(tmp_path / "o")]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert text.count("[requirements] absent: the defaults, band 5-300 Hz") == 1
    assert text.count("[tuning] absent") == 1
    assert main([*argv, "--json"]) == 0
    notes = json.loads(capsys.readouterr().out)["notes"]
    assert sum("[requirements] absent" in n for n in notes) == 1


def test_the_results_of_another_axis_of_the_same_name_are_not_replaced(tmp_path, capsys):
    # two copies of the starter axis share [axis] name: the second bode run into the same
    # --out would replace the first one's results; it refuses, naming the other axis, and
    # leaves them as they were; the first axis itself may run again
    from servotune.template import write_template

    for name in ("a", "b"):
        write_template(tmp_path / name, name="same")
    out = tmp_path / "out"
    assert main(["bode", str(tmp_path / "a"), "--no-plots", "--out", str(out)]) == 0
    before = (out / "bode_same" / "results.json").read_bytes()
    capsys.readouterr()
    assert main(["bode", str(tmp_path / "b"), "--no-plots", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "another axis of the same name" in err and str((tmp_path / "a").resolve()) in err
    assert (out / "bode_same" / "results.json").read_bytes() == before
    assert main(["bode", str(tmp_path / "a"), "--no-plots", "--out", str(out)]) == 0
