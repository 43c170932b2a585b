"""Studies on dask.distributed: the study file, the samples, and runs on a LocalCluster of two
worker processes (end to end, resume after an interruption, a failing sample, a killed
worker)."""

import json
import math
import os
from pathlib import Path

import cloudpickle
import numpy as np
import pyarrow.parquet as pq
import pytest

from servotune.axis import load_axis
from servotune.cli import main
from servotune.friction import LuGreParameters
from servotune.study import (
    StudyFormatError,
    apply_values,
    load_study,
    read_rows,
    run_sample,
    run_study,
)
from servotune.template import write_template


def _study(tmp_path, body: str, name="s.toml") -> Path:
    if not (tmp_path / "ax").exists():
        write_template(tmp_path / "ax")
    path = tmp_path / name
    path.write_text(body)
    return path


SMALL = """
[study]
name = "small"
axes = ["ax"]
compute = ["compliance", "lobes"]
samples = 3
seed = 4

[vary."friction.lugre.fc"]
distribution = "uniform"
low = 0.7
high = 1.3
relative = true

[vary."drive.velocity_loop.kp"]
values = [3.0, 4.0]
"""


# --------------------------------------------------------------------------- the study file
@pytest.mark.parametrize("body, words", [
    ('[study]\nname = "x"\naxes = ["nowhere"]\n', ["axes", "no axis.toml"]),
    ('[study]\naxes = ["ax"]\ncompute = ["tune", "dance"]\n', ["compute", "choose among"]),
    ('[study]\naxes = ["ax"]\nsampels = 3\n', ["unknown keys", "sampels"]),
    ('[study]\naxes = ["ax"]\n[vary."friction.lugre.fc"]\ndistribution = "gauss"\n',
     ["distribution", "'gauss'", "uniform"]),
    ('[study]\naxes = ["ax"]\n[vary."friction.lugre.fc"]\ndistribution = "uniform"\n'
     'low = 2\nhigh = 1\n', ["low 2 is not below high 1"]),
    ('[study]\naxes = ["ax"]\n[vary."friction.lugre.fc"]\nvalues = [1]\ngrid = {low = 1, '
     'high = 2, count = 3}\n', ["exactly one"]),
    ('[study]\naxes = ["ax"]\n[vary.fc]\nvalues = [1]\n', ["dotted path"]),
    ('[study]\naxes = ["ax"]\ncompute = ["verify"]\n', ["verify needs a design"]),
    ('[study]\naxes = ["ax"]\nsamples = 0\n', ["samples", "1..1000000"]),
    ('[study\n', ["not valid TOML"]),
])
def test_a_bad_study_file_is_refused_naming_the_field_and_the_fix(tmp_path, body, words):
    path = _study(tmp_path, body)
    with pytest.raises(StudyFormatError) as exc:
        load_study(path)
    assert str(path) in str(exc.value)
    for w in words:
        assert w in str(exc.value)


def test_samples_are_the_product_of_the_lists_and_the_draws_and_stay_put(tmp_path):
    study = load_study(_study(tmp_path, SMALL))
    samples = study.sample_list()
    assert len(samples) == 2 * 3
    assert len({s.key for s in samples}) == 6 and [s.sample_id for s in samples] == list(range(6))
    # draw d of every grid point comes from default_rng([seed, d]): the same factor for kp 3
    # and kp 4, within [0.7, 1.3], and the first draws unchanged when more are asked for
    fc = [dict(s.values)["friction.lugre.fc"] for s in samples]
    expected = [float(np.random.default_rng([4, d]).uniform(0.7, 1.3)) for d in range(3)]
    assert fc == expected * 2
    more = load_study(_study(tmp_path, SMALL.replace("samples = 3", "samples = 5"), "m.toml"))
    first = [s.key for s in more.sample_list() if s.sample_id in (0, 1, 2)]
    assert first == [s.key for s in samples[:3]]


def test_a_varied_field_below_a_named_lugre_set_expands_the_set():
    # an axis that names its friction ("bianchi2014"): varying fc must keep every other
    # parameter of that set, and a relative value multiplies the set's own
    tables = {"axis": {"name": "a"}, "friction": {"pads": ["pad1.x"], "lugre": "bianchi2014"}}
    named = LuGreParameters.named("bianchi2014")
    applied = {}
    out = apply_values(tables, [("friction.lugre.fc", 1.3), ("friction.lugre.sigma0", 2e9)],
                       relative=lambda p: p.endswith(".fc"), applied=applied)
    lugre = out["friction"]["lugre"]
    assert lugre["fc"] == pytest.approx(1.3 * named.fc)
    assert lugre["sigma0"] == 2e9 and lugre["fs"] == named.fs and lugre["vs"] == named.vs
    assert applied == {"friction.lugre.fc": lugre["fc"], "friction.lugre.sigma0": 2e9}
    assert tables["friction"]["lugre"] == "bianchi2014"  # the input is not changed


# ------------------------------------------------------------------- runs on a LocalCluster
def test_a_small_study_runs_end_to_end_and_each_row_is_its_own_sample(tmp_path):
    # the rows computed by two worker processes equal the same samples computed here, one by
    # one (the sample each row names is the sample it was computed for), and the varied
    # values reached the axis: kp of the row is the listed one, fc the factor times the
    # starter's own 2198 N
    study = load_study(_study(tmp_path, SMALL))
    run = run_study(study, tmp_path / "out", workers=2)
    assert (run.samples, run.computed, run.skipped, run.failed) == (6, 6, 0, 0)
    table = pq.read_table(run.folder / "results.parquet").to_pylist()
    assert [r["sample_id"] for r in table] == list(range(6))
    settings = {"compute": ["compliance", "lobes"], "relative": ["friction.lugre.fc"]}
    for sample in study.sample_list()[::5]:
        here = run_sample(settings, sample.to_dict())
        row = table[sample.sample_id]
        assert row["peak_compliance_m_per_n"] == pytest.approx(here["peak_compliance_m_per_n"],
                                                               rel=1e-12)
        assert row["b_crit_m"] == pytest.approx(here["b_crit_m"], rel=1e-12)
        values = dict(sample.values)
        assert row["kp"] == values["drive.velocity_loop.kp"]
        assert row["in.friction.lugre.fc"] == pytest.approx(
            2198.0 * values["friction.lugre.fc"], rel=1e-12)
    assert (run.folder / "summary.html").exists() is False  # written by the command only


def test_an_interrupted_study_resumes_without_recomputing_finished_samples(tmp_path):
    study = load_study(_study(tmp_path, SMALL))
    seen = []

    def stop_after_two(row):
        seen.append(row["key"])
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_study(study, tmp_path / "out", workers=2, on_row=stop_after_two)
    folder = tmp_path / "out" / "study_small"
    assert {p.stem for p in (folder / "rows").glob("*.parquet")} == set(seen)
    again = []
    run = run_study(study, tmp_path / "out", workers=2, on_row=lambda r: again.append(r["key"]))
    assert run.skipped == 2 and run.computed == 4 and not set(again) & set(seen)
    assert len(read_rows(folder)) == 6


def test_a_failing_sample_is_a_row_with_its_reason_and_the_study_goes_on(tmp_path):
    # Coulomb friction drawn up to 3 times the starter's 2198 N: the draws of seed 0 are
    # 2.27 and 2.78, and above 6013 / 2198 = 2.74 the static friction is below it, which the
    # axis loader refuses for that sample alone (the study itself is good)
    body = SMALL.replace("low = 0.7\nhigh = 1.3", "low = 1.0\nhigh = 3.0").replace(
        "values = [3.0, 4.0]", "values = [3.0]").replace("samples = 3", "samples = 2").replace(
        "seed = 4", "seed = 0")
    study = load_study(_study(tmp_path, body))
    run = run_study(study, tmp_path / "out", workers=2)
    rows = read_rows(run.folder)
    assert run.failed == 1 and len(rows) == 2
    bad = next(r for r in rows if r["status"] == "failed")
    assert "fs" in bad["error"] and bad["factor.friction.lugre.fc"] > 6013 / 2198
    assert next(r for r in rows if r["status"] == "done")["peak_compliance_m_per_n"] > 0


def _dies_once(marker_dir, settings, sample):
    """The study's task, except that the first attempt at sample 0 kills its worker process."""
    marker = Path(marker_dir) / "died"
    if sample["sample_id"] == 0 and not marker.exists():
        marker.write_text(str(os.getpid()))
        os._exit(1)
    return run_sample(settings, sample)


def test_a_worker_killed_mid_study_loses_nothing_and_its_task_is_run_again(tmp_path):
    import functools
    import sys

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    try:
        study = load_study(_study(tmp_path, SMALL.replace("samples = 3", "samples = 2")))
        task = functools.partial(_dies_once, str(tmp_path))
        run = run_study(study, tmp_path / "out", workers=2, task=task)
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
    assert (tmp_path / "died").exists()  # a worker did die
    rows = read_rows(run.folder)
    assert [r["sample_id"] for r in rows] == [0, 1, 2, 3]
    assert all(r["status"] == "done" for r in rows)
    assert rows[0]["worker"].split(":")[1] != (tmp_path / "died").read_text()


def test_the_study_command_writes_the_table_and_the_summary(tmp_path, capsys):
    path = _study(tmp_path, SMALL.replace("samples = 3", "samples = 1"))
    out = tmp_path / "out"
    assert main(["study", str(path), "--workers", "2", "--out", str(out), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["summary"]["done"] == 2 and result["summary"]["failed"] == 0
    folder = out / "study_small"
    page = (folder / "summary.html").read_text()
    assert "Study: small" in page and "data:image/png;base64," in page
    assert (folder / "results.parquet").exists() and (folder / "study_results.png").exists()
    # a second run skips both samples
    assert main(["study", str(path), "--workers", "2", "--out", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["run"]["skipped"] == 2


def test_the_study_command_refuses_a_folder_it_would_mix_into(tmp_path, capsys):
    path = _study(tmp_path, SMALL)
    folder = tmp_path / "out" / "study_small"
    folder.mkdir(parents=True)
    (folder / "notes.txt").write_text("mine")
    assert main(["study", str(path), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert "not a study's" in err and not (folder / "rows").exists()
    assert main(["study", str(path), "--scheduler", "localhost:8786"]) == 2
    assert "tcp://" in capsys.readouterr().err


def test_a_design_is_judged_on_every_sample_of_a_spread_it_was_not_tuned_for(tmp_path):
    # compute = verify with a fixed design: each sample's row carries that design unchanged
    # and the verdict of the nonlinear axis (here standing only, one force, to stay short)
    write_template(tmp_path / "ax")
    text = (tmp_path / "ax" / "axis.toml").read_text()
    assert "# feed_speeds" in text
    (tmp_path / "ax" / "axis.toml").write_text(text.replace(
        "# feed_speeds = [0.01, 0.05]", "feed_speeds = [0.05]"))
    design = {"c": 5578.0, "kv": 45.3, "kp": 3.03, "ti": 0.0105}
    (tmp_path / "tuned.json").write_text(json.dumps({"axis": "ax", "design": design}))
    body = ('[study]\nname = "judge"\naxes = ["ax"]\ncompute = ["verify"]\n'
            'design = "tuned.json"\nsamples = 2\n'
            '[vary."friction.lugre.sigma0"]\ndistribution = "loguniform"\n'
            'low = 0.5\nhigh = 2.0\nrelative = true\n')
    study = load_study(_study(tmp_path, body))
    axis = load_axis(tmp_path / "ax")
    run = run_study(study, tmp_path / "out", workers=2)
    rows = read_rows(run.folder)
    assert len(rows) == 2 and all(r["status"] == "done" for r in rows)
    for r in rows:
        assert (r["c"], r["kv"], r["kp"], r["ti"]) == tuple(design.values())
        assert isinstance(r["verified"], bool)
        assert r["nonlinear_peak_m_per_n"] > 0 and math.isfinite(r["nonlinear_peak_m_per_n"])
        assert r["in.friction.lugre.sigma0"] == pytest.approx(
            axis.friction.lugre.sigma0 * r["factor.friction.lugre.sigma0"], rel=1e-12)


# ------------------------------------------------------ a study's samples as a friction spread
def _table(path, rows):
    import pyarrow as pa

    names = list(dict.fromkeys(k for r in rows for k in r))
    pq.write_table(pa.table({k: [r.get(k) for r in rows] for k in names}), path)


def test_the_worst_samples_of_a_study_become_friction_samples_of_every_regime(tmp_path):
    from servotune.regimes import Operation, regime_models
    from servotune.study.spread import spread_from_study

    rows = [{"sample_id": i, "status": "done", "in.friction.lugre.fc": 2000.0 + i,
             "factor.friction.lugre.fc": 1.0, "in.drive.velocity_loop.kp": 3.0,
             "peak_compliance_m_per_n": 1e-8 * (1 + i % 3),
             "nonlinear_peak_m_per_n": [2e-8, 5e-8, 1e-8, 4e-8][i]} for i in range(4)]
    rows.append({"sample_id": 4, "status": "failed", "in.friction.lugre.fc": 9999.0,
                 "error": "RequirementsNotMetError"})
    _table(tmp_path / "results.parquet", rows)
    samples = spread_from_study(tmp_path, count=2)
    # the realised (nonlinear) peak ranks them: samples 1 and 3; only LuGre columns are taken
    assert samples == (("study sample 1", {"fc": 2001.0}), ("study sample 3", {"fc": 2003.0}))
    nominal = LuGreParameters.named("bianchi2014")
    models = regime_models(nominal, Operation(feed_speeds=(0.02,), standing=True), None, None,
                           None, extra_samples=samples)
    by_sample = {}
    for m in models:
        by_sample.setdefault(m.sample, []).append(m)
    assert set(by_sample) == {"nominal", "study sample 1", "study sample 3"}
    assert all(len(v) == 2 for v in by_sample.values())  # standing + feeding each
    assert by_sample["study sample 3"][0].friction.params.fc == 2003.0
    assert by_sample["study sample 3"][0].friction.params.fs == nominal.fs
    with pytest.raises(ValueError, match="varied no LuGre parameter"):
        _table(tmp_path / "other.parquet", [{"sample_id": 0, "status": "done",
                                             "in.drive.velocity_loop.kp": 3.0,
                                             "peak_compliance_m_per_n": 1e-8}])
        spread_from_study(tmp_path / "other.parquet")
    with pytest.raises(ValueError, match="not a Parquet table"):
        (tmp_path / "bad.parquet").write_text("no")
        spread_from_study(tmp_path / "bad.parquet")


def test_tune_takes_a_studys_worst_samples_as_further_friction_models(tmp_path, capsys):
    # the worst sample of a (here written) study table joins every regime: the tuning
    # reports its models by name, the sliding one at the sample's friction level
    # g(v) = Fc + (Fs - Fc) exp(-(v/vs)^delta) with the study's Fc and Fs
    write_template(tmp_path / "ax")
    axis = load_axis(tmp_path / "ax")
    lugre = axis.friction.lugre
    fc, fs = 1.25 * lugre.fc, 0.8 * lugre.fs
    _table(tmp_path / "results.parquet", [
        {"sample_id": 7, "status": "done", "in.friction.lugre.fc": fc,
         "in.friction.lugre.fs": fs, "peak_compliance_m_per_n": 2e-7},
        {"sample_id": 8, "status": "done", "in.friction.lugre.fc": lugre.fc,
         "in.friction.lugre.fs": lugre.fs, "peak_compliance_m_per_n": 1e-7}])
    code = main(["tune", str(tmp_path / "ax"), "--spread-from", str(tmp_path / "results.parquet"),
                 "--spread-samples", "1", "--no-simulation", "--starts", "1", "--json",
                 "--no-plots", "--out", str(tmp_path / "out")])
    out = json.loads(capsys.readouterr().out)
    assert code in (1, 3)
    mine = [m for m in out["regime_models"] if m["sample"] == "study sample 7"]
    assert {m["regime"] for m in mine} == {m["regime"] for m in out["regime_models"]
                                          if m["sample"] == "nominal"}
    assert not any(m["sample"] == "study sample 8" for m in out["regime_models"])
    for m in mine:
        if m["model"] == "sliding":
            v = m["speed_m_per_s"]
            level = fc + (fs - fc) * math.exp(-((v / lugre.vs) ** lugre.delta))
            assert m["friction_level_n"] == pytest.approx(level, rel=1e-9)
