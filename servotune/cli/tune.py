"""``servotune tune``: tune guide-way damping and servo gains of an axis, verify, report.

Exit status: 0 when the design is verified (the linear checks hold in every regime model and
the nonlinear axis holds the claim in every regime), 1 when it is not (or the input is bad), 3
when the linear checks hold but the nonlinear verification was skipped (``--no-simulation``),
2 for a bad flag, 130 when interrupted.

Before any tuning the axis' model checks run (:func:`servotune.model_checks.axis_model_checks`):
a structure whose rotor-to-encoder motion contradicts the drive's transmission (a flipped DOF
direction, a ratio off by more than 2 %) is refused with an error that names the DOF and the
fix (tuning it would give wrong advice); kept modes that do not cover the requirements' band
give a warning (standard error, the text output and ``warnings`` in the JSON).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ._common import (
    FRACTION,
    STARTS,
    RunOutput,
    UsageError,
    add_common_options,
    add_workers_option,
    default_workers,
    friction_law_of,
    number,
    print_json,
    require_section,
    to_jsonable,
    write_results,
)

__all__ = ["add_parser", "run", "exit_status", "EXIT_VERIFIED", "EXIT_NOT_VERIFIED",
           "EXIT_LINEAR_ONLY"]

VARIABLES = ("c", "kv", "kp", "ti", "notch", "lowpass")
SPREAD_SAMPLES = number(1, 20, integer=True, example=4)
EXIT_VERIFIED, EXIT_NOT_VERIFIED, EXIT_LINEAR_ONLY = 0, 1, 3
FIGURES = ("compliance.png", "nonlinear.png", "bode.png", "lobes.png",
           "modes.png", "two_mass.png")


def _free(text: str) -> tuple[str, ...]:
    names = tuple(v.strip().lower() for v in text.split(",") if v.strip())
    unknown = [v for v in names if v not in VARIABLES]
    if unknown or not names or len(set(names)) != len(names):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not accepted: give a comma-separated subset of "
            f"{','.join(VARIABLES)} (e.g. c,kv)")
    return names


def add_parser(subparsers) -> None:
    """Add the ``servotune tune`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "tune", help="tune guide-way damping C, Kv and the velocity PI (casadi), verify",
        description="Tune the guide-way damping C and the position/velocity loop gains of an "
                    "axis for every regime it works in (standing, feeding at each feed speed) "
                    "against its worst work-piece compliance peak (and, with "
                    "--chatter-weight, its chatter limit), under the Ms, loop-hierarchy, "
                    "integral-time and thrust requirements, with the drive modelled as the "
                    "sampled-data system it is; "
                    "verify the design with python-control on grids the optimiser never saw "
                    "and on the nonlinear axis (LuGre friction, time simulation); print the "
                    "result and write results.json, figures and report.html. Exit status: 0 "
                    "verified, 1 not verified, 3 linear check only (--no-simulation), 2 bad "
                    "flag, 130 interrupted.")
    p.add_argument("axis", help="axis folder with axis.toml (e.g. models/paper_x_axis)")
    p.add_argument("--free", type=_free, default=None,
                   help="design variables the optimiser may change, among "
                        "c,kv,kp,ti,notch,lowpass (notch: the current set-point notch's "
                        "frequency, width and depth, started on the resonance that lifts the "
                        "velocity loop; lowpass: the corner of the drive's own set-point "
                        "low-pass, [drive.filters] lowpass_hz; default: [tuning] free of the "
                        "axis, else c,kv,kp,ti,notch)")
    p.add_argument("--chatter-weight", type=FRACTION, default=None,
                   help="weight in [0, 1] of the chatter limit against the compliance peak "
                        "(default: [tuning] chatter_weight of the axis, else 0)")
    p.add_argument("--starts", type=STARTS, default=4,
                   help="starting points, 1 to 100 (default 4)")
    p.add_argument("--no-simulation", action="store_true",
                   help="skip the nonlinear verification (the design is then not called "
                        "verified; exit status 3 when the linear checks hold)")
    p.add_argument("--no-commission", action="store_true",
                   help="start from the axis' own drive (its current loop, filters and gains) "
                        "instead of the commissioning design (servotune.baseline: current "
                        "loop by the technical optimum, velocity PI by the symmetric optimum "
                        "reduced to the Ms limit, a notch, Kv from the hierarchy)")
    p.add_argument("--spread-from", type=Path, default=None, metavar="STUDY",
                   help="a friction-spread study's folder (an interrupted one gives the samples "
                        "it finished) or its results.parquet (servotune study): its worst "
                        "samples become further friction models of every regime, so the design "
                        "is tuned for them too")
    p.add_argument("--spread-samples", type=SPREAD_SAMPLES, default=None, metavar="N",
                   help="how many of the study's worst samples (1 to 20, default 4)")
    add_workers_option(p)
    add_common_options(p, plots=True)
    p.set_defaults(func=run)


def exit_status(job) -> int:
    """Return the documented exit status of a tuning job.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job.

    Returns
    -------
    int
        0 verified, 3 when only the linear checks were made and hold, else 1.
    """
    if job.verified:
        return EXIT_VERIFIED
    if job.status == "linear only":
        return EXIT_LINEAR_ONLY
    return EXIT_NOT_VERIFIED


def run(args) -> int:
    """Run ``servotune tune``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        The exit status: 0 when the design is verified, 1 when it is not, 3 when the
        nonlinear verification was skipped. Errors are raised, and reported by
        :func:`servotune.cli.main` with status 1.
    """
    from .. import interrupt, progress

    if args.spread_samples is not None and args.spread_from is None:
        raise UsageError("--spread-samples counts the worst samples of --spread-from STUDY; "
                         "give --spread-from too, or drop --spread-samples")
    with progress.task(f"loading {args.axis}"):
        from .. import report, summary
        from ..axis import load_axis
        from ..design import tune_axis
        from ..model_checks import axis_model_checks

        axis = load_axis(args.axis)
    require_section(axis, "friction", "[friction]",
                    "servotune tune (the guide-way pads are where C acts)")
    if args.spread_from is not None:
        import dataclasses

        from ..study.spread import spread_from_study

        samples = spread_from_study(args.spread_from, args.spread_samples or 4)
        spread_note = getattr(samples, "note", None)
        axis = dataclasses.replace(axis, tuning=dataclasses.replace(
            axis.tuning, friction_samples=samples))
    with progress.task(f"{axis.name}: model checks"):
        checks = axis_model_checks(axis).require()
    for text in checks.warnings:
        print(f"WARNING: {text}", file=sys.stderr)
    notes = []
    if args.spread_from is not None and spread_note:
        notes.append(spread_note)
    if axis.drive is None:
        notes.append("no [drive]: the structure with viscous guide-way pads alone is tuned "
                     "(C only, the paper's sec 4.1 analysis without control)")
    files = ["report.html", "results.json"] + ([] if args.no_plots else list(FIGURES))
    out = RunOutput.for_args(args, "tune", axis.name, files)
    simulate = (not args.no_simulation and axis.drive is not None
                and axis.friction is not None)
    workers = args.workers or default_workers()
    # the stages (commissioning, tuning rounds, the spread's screen, the analyses, the
    # verdict's simulations with their count) name themselves inside this task
    with progress.task(f"{axis.name}: the design job"):
        pool_cm = (interrupt.process_pool(workers) if simulate and workers > 1
                   else _no_pool())
        with pool_cm as pool:
            job = tune_axis(axis, free=args.free, chatter_weight=args.chatter_weight,
                            starts=args.starts, simulate=simulate, executor=pool,
                            commission=not args.no_commission)
    interrupt.check("the tuning")
    results = job.to_dict()
    results["friction_law"] = friction_law_of(axis)
    notes += list(job.result.notes)
    results["notes"] = notes + results["notes"]
    results["warnings"] = list(checks.warnings)
    results["model_checks"] = checks.to_dict()
    status = exit_status(job)
    results["exit_status"] = status
    results["folder"] = str(out.path)
    with progress.task(f"writing {out.path}"), out.writing() as folder:
        figures = [] if args.no_plots else report.tuning_figures(job)
        paths = []
        # rendered in as many processes as the simulations had (each figure takes a few
        # tenths of a second)
        rendered = report.render_figures([fig for _, _, fig in figures], workers=workers)
        for (file, title, _), data in zip(figures, rendered, strict=True):
            (folder / file).write_bytes(data)
            paths.append((folder / file, title))
        report.write_html_report(job, folder, force=True, figures=paths)
        results["files"] = [str(out.file(p.name)) for p, _ in paths]
        results["report"] = str(out.file("report.html"))
        write_results(folder, to_jsonable(results))
    if args.json:
        print_json(results)
        return status
    r = job.result
    # the verdict first, then what it rests on
    head, lines = summary.verdict_lines(job)
    print(f"{axis.name}: {head}")
    for line in lines:
        print("    " + line)
    print(f"  design: {summary.design_line(r.design)}")
    print(f"  report: {out.file('report.html')}")
    print("Details")
    print(f"  tuned {', '.join(r.problem.free)} over {r.stats.models} regime "
          f"models ({r.stats.starts} starts, {r.stats.iterations} IPOPT iterations, "
          f"{r.stats.time_s:.1f} s)")
    for line in notes:
        print(f"  note: {line}")
    for line in checks.warnings:
        print(f"  WARNING: {line}")
    for table in (summary.inputs_table(job), summary.rounds_table(job), summary.design_table(job),
                  summary.baseline_table(job),
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
    label = ("VERIFIED" if job.verified else "NOT VERIFIED (linear check only)"
             if job.status == "linear only" else "NOT VERIFIED")
    print(f"{axis.name}: {label} (the verdict above)")
    print(f"  wrote {out.path} (results.json, {len(results['files'])} figures, report.html)")
    print(f"  report: {out.file('report.html')}")
    return status


class _no_pool:
    def __enter__(self):
        return None

    def __exit__(self, *exc):
        return False
