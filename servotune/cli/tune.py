"""``servotune tune``: tune guide-way damping and servo gains of an axis, verify, report.

Exit status: 0 when the design is verified (the linear checks hold in every regime model and
the nonlinear axis holds the claim in every regime), 1 when it is not, 3 when the linear checks
hold but the nonlinear verification was skipped (``--no-simulation``), 2 for bad input.
"""

from __future__ import annotations

from .. import report, summary
from ..axis import load_axis
from ..design import tune_axis
from ._common import add_output_options, print_json, to_jsonable

__all__ = ["add_parser", "run", "EXIT_VERIFIED", "EXIT_NOT_VERIFIED", "EXIT_LINEAR_ONLY"]

VARIABLES = ("c", "kv", "kp", "ti")
EXIT_VERIFIED, EXIT_NOT_VERIFIED, EXIT_LINEAR_ONLY = 0, 1, 3


def _free(text: str) -> tuple[str, ...]:
    names = tuple(v.strip().lower() for v in text.split(",") if v.strip())
    unknown = [v for v in names if v not in VARIABLES]
    if unknown or not names:
        raise ValueError(f"--free takes a comma-separated subset of {','.join(VARIABLES)}, "
                         f"got {text!r}")
    return names


def _starts(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise ValueError(f"--starts takes a whole number from 1 to 50, got {text!r}") from None
    if not 1 <= value <= 50:
        raise ValueError(f"--starts takes a whole number from 1 to 50, got {value}")
    return value


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "tune", help="tune guide-way damping C, Kv and the velocity PI (casadi), verify",
        description="Tune the guide-way damping C and the position/velocity loop gains of an "
                    "axis for every regime it works in (standing, feeding at each feed speed) "
                    "against its worst work-piece compliance peak (and, with "
                    "--chatter-weight, its chatter limit), under the Ms, loop-hierarchy, "
                    "integral-time and thrust requirements, with the digital drive's delays; "
                    "verify the design with python-control on grids the optimiser never saw "
                    "and on the nonlinear axis (LuGre friction, time simulation); print the "
                    "result and write results.json, figures and report.html. Exit status: 0 "
                    "verified, 1 not verified, 3 linear check only (--no-simulation), 2 bad "
                    "input.")
    p.add_argument("axis", help="axis folder with axis.toml (e.g. models/paper_x_axis)")
    p.add_argument("--free", type=_free, default=None,
                   help="design variables the optimiser may change (default: [tuning] free "
                        "of the axis, else c,kv,kp,ti)")
    p.add_argument("--chatter-weight", type=float, default=None,
                   help="weight in [0, 1] of the chatter limit against the compliance peak "
                        "(default: [tuning] chatter_weight of the axis, else 0)")
    p.add_argument("--starts", type=_starts, default=4,
                   help="starting points, 1 to 50 (default 4)")
    p.add_argument("--no-simulation", action="store_true",
                   help="skip the nonlinear verification (the design is then not called "
                        "verified; exit status 3 when the linear checks hold)")
    p.add_argument("--workers", type=int, default=None,
                   help="processes for the nonlinear simulations (default: as many as CPUs, "
                        "1 = serial)")
    add_output_options(p, default_out="out/tune_AXISNAME")
    p.set_defaults(func=run)


def exit_status(job) -> int:
    """The documented exit status of a tuning job."""
    if job.verified:
        return EXIT_VERIFIED
    if job.status == "linear only":
        return EXIT_LINEAR_ONLY
    return EXIT_NOT_VERIFIED


def run(args) -> int:
    if args.workers is not None and args.workers < 1:
        raise ValueError("--workers must be a whole number >= 1")
    axis = load_axis(args.axis)
    out = (report.default_folder(f"tune_{axis.name}") if str(args.out) == "out/tune_AXISNAME"
           else args.out)
    names = ["report.html", "results.json", "compliance.png", "nonlinear.png",
             "bode_before.png", "bode_after.png", "lobes.png", "modes.png", "two_mass.png"]
    report.check_writable([out / n for n in names], args.force)
    simulate = (not args.no_simulation and axis.drive is not None
                and axis.friction is not None)
    executor = None
    if simulate and args.workers != 1:
        from concurrent.futures import ProcessPoolExecutor

        executor = ProcessPoolExecutor(max_workers=args.workers)
    try:
        job = tune_axis(axis, free=args.free, chatter_weight=args.chatter_weight,
                        starts=args.starts, simulate=simulate, executor=executor)
    finally:
        if executor is not None:
            executor.shutdown()
    results = job.to_dict()
    figures = report.tuning_figures(job)
    files = [report.save_figure(fig, out / file, args.force) for file, _, fig in figures]
    html_path = report.write_html_report(
        job, out, args.force, figures=[(out / file, title) for file, title, _ in figures])
    results["files"] = [str(f) for f in files]
    results["report"] = str(html_path)
    report.write_json(out / "results.json", to_jsonable(results), force=args.force)
    status = exit_status(job)
    results["exit_status"] = status
    if args.json:
        print_json(results)
        return status
    r = job.result
    print(f"{axis.name}: tuned {', '.join(r.problem.free)} over {r.stats['models']} regime "
          f"models ({r.stats['starts']} starts, {r.stats['iterations']} IPOPT iterations, "
          f"{r.stats['time_s']:.1f} s)")
    for table in (summary.inputs_table(job), summary.design_table(job),
                  summary.regimes_table(job), summary.thrust_table(job),
                  summary.realisation_table(job), summary.loops_table(job)):
        if table is not None:
            print(summary.text(table))
    if job.two_mass is not None:
        t = job.two_mass
        print(f"  two-mass check (sec 4.1): Copt closed form {t.c_opt_analytic:.6e} N s/m, "
              f"tuned {t.c_opt_tuned:.6e} N s/m (relative difference "
              f"{t.c_relative_difference:+.1e}); peak g(alpha)/K {t.peak_analytic:.6e} m/N, "
              f"tuned {t.peak_tuned:.6e} m/N ({t.peak_relative_difference:+.1e})")
    head, lines = summary.verdict_lines(job)
    print("  " + head)
    for line in lines:
        print("    " + line)
    print(f"  wrote {out / 'results.json'} and {len(files)} figures")
    print(f"  report: {html_path}")
    return status
