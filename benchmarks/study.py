"""Throughput of a study on a LocalCluster of 1 and of 2 worker processes.

The same study (the starter axis of ``servotune init``, its Coulomb friction drawn over +-30 %,
each sample tuned with two starts: a few seconds of work per sample) runs on one worker (the
baseline) and then on two, each into a fresh folder, cluster start and shut-down included.
``speedup`` = wall time on 1 worker / wall time on 2; ``parallel_efficiency`` = speedup / 2;
``task_s_median`` the median time of one sample inside a worker, and ``overhead_s`` the wall
time that the samples do not explain (cluster start, scheduling, writing rows) on 1 worker.
A sample whose tuning raises (e.g. no stable start with the digital drive at a high friction
draw) is a row with status ``failed``; it counts in the times as it ran, and ``failed`` gives
their number in each run (the same draws in both).

    .venv/bin/python benchmarks/study.py --json [--samples 12]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

STUDY = """
[study]
name = "bench"
axes = ["ax"]
compute = ["tune"]
samples = {samples}
seed = 0
starts = 2

[vary."friction.lugre.fc"]
distribution = "uniform"
low = 0.7
high = 1.3
relative = true
"""


def run(samples: int, workers: int, top: Path) -> dict:
    from servotune.study import load_study, read_rows, run_study

    study = load_study(top / "study.toml")
    out = top / f"out_{workers}"
    t0 = time.perf_counter()
    result = run_study(study, out, workers=workers)
    wall = time.perf_counter() - t0
    rows = read_rows(result.folder)
    task = [r["time_s"] for r in rows]
    return {"workers": workers, "samples": samples, "wall_s": wall,
            "samples_per_s": samples / wall, "task_s_median": statistics.median(task),
            "task_s_sum": sum(task), "overhead_s": wall - sum(task) / workers,
            "failed": result.failed}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--samples", type=int, default=12)
    p.add_argument("--json", action="store_true")
    args = p.parse_args(argv)
    from servotune.template import write_template

    with tempfile.TemporaryDirectory() as tmp:
        top = Path(tmp)
        write_template(top / "ax")
        (top / "study.toml").write_text(STUDY.format(samples=args.samples))
        one = run(args.samples, 1, top)
        two = run(args.samples, 2, top)
    speedup = one["wall_s"] / two["wall_s"]
    out = {"benchmark": "study", "baseline": "the same study on a LocalCluster of 1 worker",
           "speedup": speedup, "parallel_efficiency": speedup / 2.0,
           "load_average": os.getloadavg(), "one_worker": one, "two_workers": two}
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        for r in (one, two):
            print(f"{r['workers']} worker(s): {r['samples']} samples in {r['wall_s']:.1f} s "
                  f"({r['samples_per_s']:.3f}/s; a sample {r['task_s_median']:.2f} s; "
                  f"{r['failed']} failed)")
        print(f"speedup {speedup:.2f}x, parallel efficiency {speedup / 2:.0%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
