"""The main job, phase by phase: ``servotune tune models/paper_x_axis`` timed from the inside.

The job is run as ``servotune tune`` runs it (:func:`servotune.cli.tune.run`): the library
functions are called in the same sequence, in a fresh process per variant, and the phases inside
:func:`servotune.design.tune_axis` are timed by wrapping, for the duration of the run, the
module-level functions it calls (the library itself is not changed; a phase whose function the
library no longer calls is an error, not a silent zero):

=======================  ==========================================================================
phase                    what is timed
=======================  ==========================================================================
``imports``              importing servotune and what the job needs (numpy, scipy, casadi, ...)
``load_axis``            :func:`servotune.axis.load_axis` (axis.toml, structure, defaults)
``regime_models``        :func:`servotune.design.axis_regimes` (standing: the process amplitude and
                         the describing function; feeding: LuGre linearised at each feed speed)
``problem_setup``        the rest of :func:`servotune.design.tuning_problem` (bounds, thrust budget,
                         chatter target)
``optimisation``         :func:`servotune.tuning.tune` without its linear checks: stable starts,
                         the casadi kernels (compiled to C when a compiler is found), the IPOPT
                         solves and the grid exchange (sub-phases reported apart)
``linear_verification``  the linear checks inside ``tune``: :func:`~servotune.tuning.verify` of the
                         initial and the tuned design in every regime model on dense grids (the
                         exact sampled-data loop of a digital drive, the python-control state
                         space of a continuous one), and
                         :func:`~servotune.tuning.requirement_checks`
``analyses``             the rest of ``tune_axis``: process amplitude, realisation of C, loop
                         reports, compliance curves per regime, lobes, mode peaks against C
``verdict``              :func:`servotune.verdict.nonlinear_verdict` (LuGre time simulations, run by
                         a process pool of ``--workers`` processes as the command does, the pool's
                         start and shut-down included); skipped with ``--no-simulation``
``results``              ``AxisTuning.to_dict`` (the results object)
``figures``              :func:`servotune.report.tuning_figures` and saving them (matplotlib import
                         included, as in the command)
``report``               ``report.html`` and ``results.json`` written into a run folder (a
                         temporary ``--out``) and swapped into place
=======================  ==========================================================================

``total`` is the wall time from loading the axis to the written report (imports apart).

Baselines (``speedup`` = baseline total / job total, both measured in this run, each variant
in a fresh process):

* ``workers1`` (the default with simulation): the same job with ``--workers 1``, i.e. the
  verdict's simulations run serially in the calling process, against the default of the command
  (one process per CPU this process may use). ``speedup_verdict`` is the ratio of the verdict
  phases alone.
* ``nojit`` (the default with ``--no-simulation``): the same job with ``SERVOTUNE_JIT=0`` (casadi's
  kernels interpreted by its virtual machine instead of compiled to C). ``speedup_optimisation``
  is the ratio of the optimisation phases alone.
* ``none``: no baseline (``speedup`` is null).

BLAS and OpenMP are held to one thread (before numpy is imported), as in the other scripts (the
verdict's worker processes are forked from the job and inherit it); ``--blas-threads default``
runs the job with the thread variables as given in the environment instead, as the
``servotune`` command runs (OpenBLAS then starts one thread per core).

Usage: ``python benchmarks/main_job.py [--json] [--no-simulation] [--baseline workers1|nojit|none]
[--workers N] [--starts N] [--no-plots] [--blas-threads 1|default] [--axis PATH]``
"""

from __future__ import annotations

import time

_T_START = time.perf_counter()

import os  # noqa: E402

_THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
_ENV_GIVEN = {_var: os.environ.get(_var) for _var in _THREAD_VARS}
# a child run with --blas-threads default keeps the environment as given
_BLAS_MARK = "SERVOTUNE_BENCHMARK_BLAS_THREADS"
if os.environ.get(_BLAS_MARK) != "default":
    for _var in _THREAD_VARS:
        os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
AXIS = ROOT / "models" / "paper_x_axis"

PHASES = ("load_axis", "regime_models", "problem_setup", "optimisation", "linear_verification",
          "analyses", "verdict", "results", "figures", "report")
BASELINES = {
    "workers1": "the same job with --workers 1: the verdict's simulations serially in the "
                "calling process (the default runs them in a pool of one process per CPU)",
    "nojit": "the same job with SERVOTUNE_JIT=0: casadi's per-frequency kernels interpreted "
             "instead of compiled to C",
}


class _Clock:
    """Wall time spent inside wrapped functions, by name (inclusive), and call counts."""

    def __init__(self):
        self.spent, self.calls, self._undo = {}, {}, []

    def wrap(self, module, attribute: str, name: str) -> None:
        original = getattr(module, attribute)

        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                self.spent[name] = self.spent.get(name, 0.0) + time.perf_counter() - t0
                self.calls[name] = self.calls.get(name, 0) + 1

        setattr(module, attribute, timed)
        self._undo.append((module, attribute, original))

    def restore(self) -> None:
        for module, attribute, original in reversed(self._undo):
            setattr(module, attribute, original)
        self._undo.clear()

    def get(self, name: str) -> float:
        return self.spent.get(name, 0.0)


def run_job(axis_path, workers: int, simulate: bool, starts: int, plots: bool) -> dict:
    """The job of ``servotune tune AXIS --workers W --starts S [--no-simulation] [--no-plots]``
    in this process, phase by phase (see the module docstring)."""
    t_imports = time.perf_counter()
    import casadi
    import numpy as np
    import scipy

    import servotune
    from servotune import design, interrupt, report, verdict
    from servotune.axis import load_axis
    from servotune.cli import _common
    from servotune.tuning import solve as tuning_solve

    imports = time.perf_counter() - t_imports + (t_imports - _T_START)

    clock = _Clock()
    clock.wrap(design, "axis_regimes", "regime_models")
    clock.wrap(design, "tuning_problem", "tuning_problem")
    clock.wrap(design, "tune", "tune")
    clock.wrap(tuning_solve, "verify", "verify")
    clock.wrap(tuning_solve, "requirement_checks", "requirement_checks")
    clock.wrap(tuning_solve, "stable_starts", "stable_starts")
    clock.wrap(tuning_solve, "Kernels", "kernels")
    clock.wrap(verdict, "nonlinear_verdict", "verdict")
    phases, sub = {}, {}
    load_start = os.getloadavg()[0]
    tmp = tempfile.TemporaryDirectory(prefix="servotune-main-job-")
    try:
        t_job = time.perf_counter()
        axis = load_axis(axis_path)
        phases["load_axis"] = time.perf_counter() - t_job
        files = ["report.html", "results.json"] + ([] if not plots else
                                                   ["compliance.png", "nonlinear.png",
                                                    "bode.png",
                                                    "lobes.png", "modes.png", "two_mass.png"])
        out = _common.RunOutput(tmp.name, "tune", axis.name, files)
        simulate = simulate and axis.drive is not None and axis.friction is not None
        t0 = time.perf_counter()
        pool_cm = (interrupt.process_pool(workers) if simulate and workers > 1
                   else _NoPool())
        with pool_cm as pool:
            job = design.tune_axis(axis, starts=starts, simulate=simulate, executor=pool)
            t_pool_end = time.perf_counter()
        pool_shutdown = time.perf_counter() - t_pool_end
        t_tune_axis = t_pool_end - t0
        t0 = time.perf_counter()
        results = job.to_dict()
        phases["results"] = time.perf_counter() - t0
        with out.writing() as folder:
            t0 = time.perf_counter()
            paths = []
            if plots:  # as the command: rendered by as many processes as it has workers
                figures = report.tuning_figures(job)
                rendered = report.render_figures([f for _, _, f in figures], workers=workers)
                for (file, title, _), data in zip(figures, rendered, strict=True):
                    (folder / file).write_bytes(data)
                    paths.append((folder / file, title))
            phases["figures"] = time.perf_counter() - t0
            t0 = time.perf_counter()
            report.write_html_report(job, folder, force=True, figures=paths)
            results["files"] = [str(out.file(p.name)) for p, _ in paths]
            _common.write_results(folder, _common.to_jsonable(results))
        phases["report"] = time.perf_counter() - t0
        total = time.perf_counter() - t_job
        written = sorted(p.name for p in out.path.iterdir())
    finally:
        clock.restore()
        tmp.cleanup()

    needed = ["regime_models", "tuning_problem", "tune", "verify", "stable_starts", "kernels"]
    if simulate:
        needed.append("verdict")
    missing = [n for n in needed if not clock.calls.get(n)]
    if missing:
        raise RuntimeError(f"the library no longer calls {missing} during tune_axis: the phases "
                           "of this benchmark need updating")
    verification = clock.get("verify") + clock.get("requirement_checks")
    phases["regime_models"] = clock.get("regime_models")
    phases["problem_setup"] = clock.get("tuning_problem") - clock.get("regime_models")
    phases["optimisation"] = clock.get("tune") - verification
    phases["linear_verification"] = verification
    phases["verdict"] = clock.get("verdict") + (pool_shutdown if simulate else 0.0)
    phases["analyses"] = (t_tune_axis - clock.get("tuning_problem") - clock.get("tune")
                          - clock.get("verdict"))
    sub = {"optimisation_stable_starts_s": clock.get("stable_starts"),
           "optimisation_kernels_s": clock.get("kernels"),
           "optimisation_ipopt_and_exchange_s": (phases["optimisation"]
                                                 - clock.get("stable_starts")
                                                 - clock.get("kernels")),
           "verdict_pool_shutdown_s": pool_shutdown if simulate else None,
           "linear_verification_calls": clock.calls.get("verify", 0)}
    r = job.result
    sims = [s for v in (job.verdict.regimes if job.verdict is not None else ())
            for s in v.simulations]
    out = {
        "imports_s": imports,
        **{f"{p}_s": phases.get(p, 0.0) for p in PHASES},
        "total_s": total,
        "unaccounted_s": total - sum(phases.get(p, 0.0) for p in PHASES),
        **sub,
        "workers": workers if simulate else None,
        "simulate": simulate,
        "jit": os.environ.get("SERVOTUNE_JIT", "1") != "0",
        "thread_environment": {var: os.environ.get(var) for var in _THREAD_VARS},
        "status": job.status,
        "design": job.design.to_dict(),
        "regime_models": [m.name for m in r.problem.regimes],
        "excluded_models": [m.name for m, _ in r.excluded],
        "starts": r.stats.starts,
        "ipopt_iterations": r.stats.iterations,
        "exchange_rounds": r.stats.exchange_rounds,
        "simulations": len(sims),
        "simulated_s": float(sum(s.duration or 0.0 for s in sims)),
        "simulation_wall_sum_s": float(sum(s.wall_time or 0.0 for s in sims)),
        "simulation_wall_max_s": float(max((s.wall_time or 0.0 for s in sims), default=0.0)),
        "files_written": written,
        "load_average_1min": [load_start, os.getloadavg()[0]],
        "versions": {"servotune": getattr(servotune, "__version__", None),
                     "python": sys.version.split()[0], "numpy": np.__version__,
                     "scipy": scipy.__version__, "casadi": casadi.__version__},
    }
    return out


class _NoPool:
    def __enter__(self):
        return None

    def __exit__(self, *exc):
        return False


def _child(args, workers: int, jit: bool) -> dict:
    """One variant of the job in a fresh process; its JSON plus the process' wall time."""
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", "--workers", str(workers),
           "--starts", str(args.starts), "--axis", str(args.axis)]
    if args.no_simulation:
        cmd.append("--no-simulation")
    if args.no_plots:
        cmd.append("--no-plots")
    env = dict(os.environ)
    if args.blas_threads == "default":  # as the command runs: the environment as given
        env[_BLAS_MARK] = "default"
        for var, value in _ENV_GIVEN.items():
            if value is None:
                env.pop(var, None)
            else:
                env[var] = value
    if not jit:
        env["SERVOTUNE_JIT"] = "0"
    t0 = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    if out.returncode != 0:
        raise RuntimeError(f"the job ({' '.join(cmd[2:])}) failed:\n{out.stderr.strip()[-2000:]}")
    result = json.loads(out.stdout)
    result["process_wall_s"] = wall
    return result


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--axis", default=str(AXIS))
    parser.add_argument("--no-simulation", action="store_true",
                        help="skip the nonlinear verdict (as servotune tune --no-simulation)")
    parser.add_argument("--workers", type=int, default=None,
                        help="processes of the verdict (default: the CPUs this process may "
                             "use, as the command)")
    parser.add_argument("--starts", type=int, default=4, help="starting points (default 4)")
    parser.add_argument("--no-plots", action="store_true", help="no figures (as the command)")
    parser.add_argument("--baseline", choices=("workers1", "nojit", "none"), default=None,
                        help="default: workers1, or nojit with --no-simulation")
    parser.add_argument("--blas-threads", choices=("1", "default"), default="1",
                        help="1 (default): BLAS and OpenMP on one thread, as the other "
                             "benchmarks; default: the thread variables as given in the "
                             "environment, as the servotune command runs")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.workers is None:
        from servotune.cli._common import default_workers

        args.workers = default_workers()
    if not 1 <= args.workers <= 256:
        parser.error("--workers must lie in 1..256")
    if args.child:
        result = run_job(args.axis, args.workers, not args.no_simulation, args.starts,
                         not args.no_plots)
        print(json.dumps(result))
        return result
    baseline = args.baseline or ("nojit" if args.no_simulation else "workers1")
    if baseline == "workers1" and args.no_simulation:
        parser.error("--baseline workers1 compares the verdict's workers; it needs the "
                     "simulation (drop --no-simulation or choose --baseline nojit)")
    if baseline == "workers1" and args.workers == 1:
        parser.error("--baseline workers1 needs --workers above 1 for the job itself")

    load_start = os.getloadavg()[0]
    job = _child(args, args.workers, jit=True)
    base = None
    if baseline == "workers1":
        base = _child(args, 1, jit=True)
    elif baseline == "nojit":
        base = _child(args, args.workers, jit=False)
    result = {
        "axis": str(args.axis),
        "command": f"servotune tune {args.axis} --starts {args.starts}"
                   + (" --no-simulation" if args.no_simulation else
                      f" --workers {args.workers}") + (" --no-plots" if args.no_plots else ""),
        "blas_threads": args.blas_threads,
        "baseline": "none" if base is None else f"{baseline}: {BASELINES[baseline]}",
        "speedup": None if base is None else base["total_s"] / job["total_s"],
    }
    if base is not None and baseline == "workers1":
        result["speedup_verdict"] = base["verdict_s"] / job["verdict_s"]
    if base is not None and baseline == "nojit":
        result["speedup_optimisation"] = base["optimisation_s"] / job["optimisation_s"]
    result.update({"job": job, "baseline_job": base,
                   "load_average_1min": [load_start, os.getloadavg()[0]]})
    if args.json:
        print(json.dumps(result, indent=2))
        return result
    print(f"{result['command']}  (status: {job['status']}; {len(job['regime_models'])} regime "
          f"models; {job['ipopt_iterations']} IPOPT iterations; {job['simulations']} "
          f"simulations)")
    cols = [("job", job)] + ([] if base is None else [(baseline, base)])
    print(f"  {'phase':24}" + "".join(f"{name:>12}" for name, _ in cols))
    for p in ("imports", *PHASES, "total"):
        print(f"  {p:24}" + "".join(f"{r[p + '_s']:11.2f}s" for _, r in cols))
    sub = ("optimisation_stable_starts", "optimisation_kernels", "optimisation_ipopt_and_exchange")
    for p in sub:
        print(f"    {p:22}" + "".join(f"{r[p + '_s']:11.2f}s" for _, r in cols))
    if base is not None:
        extra = {k: v for k, v in result.items() if k.startswith("speedup_")}
        print(f"  speedup {result['speedup']:.2f} against {result['baseline']}"
              + "".join(f"; {k} {v:.2f}" for k, v in extra.items()))
    print(f"  load average {result['load_average_1min'][0]:.2f} -> "
          f"{result['load_average_1min'][1]:.2f}")
    return result


if __name__ == "__main__":
    main()
