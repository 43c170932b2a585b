"""A study that fails loudly and tells the truth: a bad study ends before any sample runs
(exit status 1, the file, the field and the fix), the counts are over the samples run, Ctrl-C
says what the folder keeps and reaches no worker, and an interrupted study's rows feed
``tune --spread-from``."""

import functools
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import servotune.study
from servotune.cli import main
from servotune.study import StudyFormatError, load_study, read_rows, summarise
from servotune.study.spread import spread_from_study
from servotune.template import write_template

ROOT = Path(__file__).resolve().parents[1]

# the starter axis (servotune.template): Coulomb 2198 N, static 6013 N, velocity kp 4.0
HEAD = '[study]\nname = "s"\naxes = ["ax"]\ncompute = ["compliance"]\nsamples = 2\nseed = 0\n'
SPREAD = ('[vary."friction.lugre.fc"]\ndistribution = "uniform"\nlow = {low}\nhigh = {high}\n'
          'relative = true\n')


@pytest.fixture
def folder(tmp_path):
    write_template(tmp_path / "ax")
    return tmp_path


def _write(folder: Path, body: str) -> Path:
    path = folder / "s.toml"
    path.write_text(body)
    return path


def _refused(folder, body, capsys) -> str:
    """Run the command on a study that must be refused; returns its message."""
    path = _write(folder, body)
    out = folder / "out"
    assert main(["study", str(path), "--workers", "1", "--out", str(out), "--no-plots"]) == 1
    captured = capsys.readouterr()
    assert captured.out == "" and not out.exists()  # refused before anything was written
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("servotune study: error: ")
    assert "KeyError" not in lines[0] and "Traceback" not in lines[0]
    return lines[0]


# ------------------------------------------------------------------ refused before any work
@pytest.mark.parametrize("vary, words", [
    # a mistyped relative field: no such number to multiply
    (SPREAD.replace("fc", "fcc").format(low=0.7, high=1.3),
     ['[vary."friction.lugre.fcc"]', "no field 'fcc' in [friction.lugre]",
      'did you mean "friction.lugre.fc"']),
    # a mistyped absolute field: the loader refuses it, and the close match is named
    ('[vary."friction.lugre.fcc"]\nvalues = [1000.0, 2000.0]\n',
     ["no field 'fcc'", "axis loader refuses it", 'did you mean "friction.lugre.fc"']),
    # a mistyped section
    ('[vary."drvie.velocity_loop.kp"]\nvalues = [3.0]\n',
     ["no field 'drvie'", 'did you mean "drive.velocity_loop.kp"']),
    ('[vary."drive.velocity_loop.kpp"]\nvalues = [3.0]\n',
     ["no field 'kpp' in [drive.velocity_loop]", 'did you mean "drive.velocity_loop.kp"']),
])
def test_a_mistyped_path_ends_the_study_before_any_sample_with_the_close_match(
        folder, capsys, vary, words):
    message = _refused(folder, HEAD + vary, capsys)
    assert str(folder / "s.toml") in message
    for w in words:
        assert w in message, message


@pytest.mark.parametrize("vary, words", [
    ('[vary."friction.lugre.fc"]\nvalues = ["high"]\n',
     ["'high' is a text", "friction.lugre.fc is a number", "without quotes"]),
    ('[vary."friction.lugre.fc"]\nvalues = ["high", 2000.0]\n', ["mixes numbers and texts"]),
    ('[vary."friction.pads"]\nvalues = [2.0]\n', ["2.0 is a number", "is a list"]),
    ('[vary."axis.name"]\ndistribution = "uniform"\nlow = 1\nhigh = 2\n',
     ["draws numbers, but axis.name is a text", "values = [...]"]),
    # a value the loader refuses in every sample: named with the loader's reason
    ('[vary."drive.velocity_loop.kp"]\nvalues = [3.0, -1.0]\n',
     ["value -1.0", "refuses every sample with it", "[drive.velocity_loop] kp"]),
    ('[vary."friction.lugre.fc"]\nvalues = [1.0, 3.0]\nrelative = true\n',
     ["factor 3.0", "fs (static friction"]),
    # every random draw refused
    (SPREAD.format(low=3.0, high=4.0), ["refuses every sample", "fs (static friction"]),
])
def test_a_value_of_the_wrong_type_or_range_ends_the_study_before_any_sample(
        folder, capsys, vary, words):
    message = _refused(folder, HEAD + vary, capsys)
    for w in words:
        assert w in message, message


def test_a_syntax_error_in_an_axis_names_the_file_and_the_line(folder, capsys):
    axis_file = folder / "ax" / "axis.toml"
    lines = axis_file.read_text().splitlines()
    broken = next(i for i, line in enumerate(lines) if line.startswith("fc = "))
    lines[broken] = "fc = [2198.0,"  # an unclosed array
    axis_file.write_text("\n".join(lines) + "\n")
    message = _refused(folder, HEAD, capsys)
    assert str(axis_file) in message and "not valid TOML" in message
    # tomllib reports where it noticed: the line after the unclosed array
    assert f"line {broken + 2}" in message, message
    assert str(folder / "s.toml") in message  # and which study names the axis


def test_a_good_study_costs_a_few_axis_builds_to_check(folder, monkeypatch):
    # the loader judges each listed value once and a random study by its first good draw
    from servotune.study import validate

    calls = []
    real = validate._build
    monkeypatch.setattr(validate, "_build", lambda *a: calls.append(a) or real(*a))
    body = (HEAD.replace("samples = 2", "samples = 50") + SPREAD.format(low=0.7, high=1.3)
            + '[vary."drive.velocity_loop.kp"]\nvalues = [3.0, 4.0, 5.0]\n')
    study = load_study(_write(folder, body))
    assert len(study.sample_list()) == 150 and len(calls) == 3
    # without the check (check_axes=False) a bad study still loads, as the library allows
    typo = _write(folder, HEAD + SPREAD.replace("fc", "fcc").format(low=0.7, high=1.3))
    with pytest.raises(StudyFormatError, match="fcc"):
        load_study(typo)
    assert load_study(typo, check_axes=False).variations[0].path == "friction.lugre.fcc"


# ------------------------------------------------------------------------------- the counts
def test_the_counts_are_over_the_samples_run_with_the_failures_beside():
    rows = [{"sample_id": 0, "status": "done", "verified": True},
            {"sample_id": 1, "status": "failed", "error": "ValueError: x"}]
    s = summarise(rows, 2)
    assert s.counts() == "2 of 2 samples run: 1 of 2 verified (50 %), 1 failed"
    assert s.verified_share == 0.5 and s.to_dict()["finished"] == 2
    rows.append({"sample_id": 2, "status": "done", "verified": False})
    s = summarise(rows, 5)
    assert s.counts() == ("3 of 5 samples run (2 not run): 1 of 3 verified (33 %), "
                          "1 not verified, 1 failed")
    assert s.verified_share == pytest.approx(1 / 3)
    assert summarise([], 4).counts() == "0 of 4 samples run (4 not run): 0 done, 0 failed"


def test_a_study_with_a_failing_sample_counts_it_apart(folder, capsys):
    # Coulomb friction drawn up to 3 times its own: seed 0 draws 2.27 and 2.78, and above
    # 6013 / 2198 = 2.74 static friction is below Coulomb, which the loader refuses for that
    # sample alone: a failed row, not a refused study
    path = _write(folder, HEAD + SPREAD.format(low=1.0, high=3.0))
    out = folder / "out"
    assert main(["study", str(path), "--workers", "2", "--out", str(out), "--no-plots",
                 "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)["summary"]
    assert (summary["finished"], summary["done"], summary["failed"]) == (2, 1, 1)
    # the sample done (Coulomb x 2.27) needs more thrust than the motor has: counted apart
    assert summary["counts"] == ("2 of 2 samples run: 1 done (1 with a design that fails its "
                                 "linear checks), 1 failed")
    assert summary["linear_checks_failed"] == 1
    assert main(["study", str(path), "--out", str(out), "--no-plots"]) == 0  # all done: no work
    text = capsys.readouterr().out
    assert text.startswith("study s: 2 of 2 samples run: 1 done (1 with a design that fails "
                           "its linear checks), 1 failed\n"), text
    assert "failed: sample 1: AxisFormatError" in text and "fs (static friction" in text


# ----------------------------------------------------------------------------- interruption
def _interrupting_run_study(after_rows, *args, **kwargs):
    """run_study, interrupted (as by Ctrl-C) once ``after_rows`` rows are written."""
    written = []

    def on_row(row):
        written.append(row)
        if len(written) >= after_rows:
            raise KeyboardInterrupt

    if after_rows == 0:
        def progress(done, total):
            raise KeyboardInterrupt
        kwargs["progress"] = progress
    return servotune.study.runner.run_study(*args, on_row=on_row, **kwargs)


def test_ctrl_c_says_what_the_folder_keeps_and_spread_from_reads_it(folder, capsys,
                                                                     monkeypatch):
    # (Coulomb friction at most the starter's own: its design is stable there, so that every
    # row has a compliance peak)
    path = _write(folder, HEAD + SPREAD.format(low=0.7, high=1.0))
    out = folder / "out"
    study_dir = out / "study_s"
    # before any sample finished: study.json and an empty rows/ are there, and said
    monkeypatch.setattr(servotune.study, "run_study",
                        functools.partial(_interrupting_run_study, 0))
    assert main(["study", str(path), "--workers", "2", "--out", str(out)]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("servotune study: interrupted")
    assert f"{study_dir} holds study.json and an empty rows/" in err[0]
    assert (study_dir / "study.json").is_file() and not read_rows(study_dir)
    with pytest.raises(ValueError, match="none of 2 of the study's samples has finished"):
        spread_from_study(study_dir)
    # after one row: the line says so, and where
    monkeypatch.setattr(servotune.study, "run_study",
                        functools.partial(_interrupting_run_study, 1))
    assert main(["study", str(path), "--workers", "2", "--out", str(out)]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert f"{study_dir} keeps study.json and the rows of 1 of 2 samples" in err[0]
    assert "1 finished in this run" in err[0] and "nothing was written" not in err[0]
    rows = read_rows(study_dir)
    assert len(rows) == 1 and not (study_dir / "results.parquet").exists()
    # the interrupted study's kept row is a friction sample for tune --spread-from
    samples = spread_from_study(study_dir, count=4)
    assert samples == ((f"study sample {rows[0]['sample_id']}",
                        {"fc": rows[0]["in.friction.lugre.fc"]}),)
    assert "1 of 2 samples run (the study was interrupted" in samples.note
    assert samples.rows == 1 and samples.samples == 2


def test_ctrl_c_at_the_terminal_prints_one_line_and_no_worker_traceback(folder):
    # a terminal's Ctrl-C goes to every process of its group (the workers too): sent so here,
    # while the two local workers are tuning
    path = _write(folder, HEAD.replace('"compliance"', '"tune"').replace("samples = 2",
                                                                          "samples = 4")
                  + SPREAD.format(low=0.7, high=1.3))
    out = folder / "out"
    command = [sys.executable, "-c", "import sys; from servotune.cli import main; "
               "sys.exit(main(sys.argv[1:]))", "study", str(path), "--workers", "2",
               "--out", str(out), "--no-plots"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, cwd=folder, start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        while not (out / "study_s" / "study.json").exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        time.sleep(6.0)  # the cluster started and the workers in their first samples
        assert process.poll() is None
        os.killpg(process.pid, signal.SIGINT)
        stdout, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == 130, stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("servotune study: interrupted"), stderr
    assert "Traceback" not in stderr and stdout == ""
    assert str(out / "study_s") in lines[0]
