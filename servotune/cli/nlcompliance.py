"""``servotune nlcompliance AXIS --force-pp F [F ...]``: amplitude-dependent compliance.

Multi-harmonic balance of the closed-loop axis with LuGre friction at the guide-way pads
(:func:`servotune.harmonic.nonlinear_compliance`): per work-piece force level the compliance
curve over the band, its peak and resonance and the pad amplitude at the peak, at rest or
feeding at ``--speed``; a figure of the curves over the linear presliding, viscous-only and
(when feeding) sliding models and the describing-function prediction (the paper's remarks A-C
in one plot).
"""

from __future__ import annotations

from ._common import (
    CliError,
    RunOutput,
    add_common_options,
    default_notes,
    number,
    print_json,
    save_figure,
    write_results,
)

__all__ = ["add_parser", "run"]

HELP = "amplitude-dependent compliance with LuGre pads by harmonic balance (Table 3, A-C)"
FORCE_PP = number(0.0, 1e6, low_open=True, example=600, unit="N")
SPEED = number(0.0, 10.0, example=0.03, unit="m/s")
HARMONICS = number(1, 50, integer=True, example=9)
FREQUENCY = number(0.0, 1e4, low_open=True, example=10, unit="Hz")


def add_parser(subparsers) -> None:
    """Add the ``servotune nlcompliance`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "nlcompliance", help=HELP,
        description="Work-piece X compliance of the closed-loop axis with LuGre friction at "
                    "the guide-way pads, per force level, by multi-harmonic balance with "
                    "continuation in frequency: the curve, its peak and resonance and the pad "
                    "amplitude at the peak, at rest or feeding at --speed. The figure shows the "
                    "curves over the linear presliding (pads locked), viscous-only and sliding "
                    "models and the describing-function prediction.")
    p.add_argument("axis", help="axis folder with axis.toml (e.g. models/paper_x_axis)")
    p.add_argument("--force-pp", type=FORCE_PP, nargs="+", action="extend", required=True,
                   metavar="N", help=f"work-piece force peak to peak [N], {FORCE_PP.accepted}; "
                                     "one curve per value")
    p.add_argument("--speed", type=SPEED, default=0.0,
                   help=f"feed speed [m/s], {SPEED.accepted} (default 0: at rest)")
    p.add_argument("--harmonics", type=HARMONICS, default=9,
                   help=f"harmonics kept, {HARMONICS.accepted} (default 9)")
    p.add_argument("--f-start-hz", type=FREQUENCY, default=10.0,
                   help="band start (default 10 Hz, the paper's sweep)")
    p.add_argument("--f-end-hz", type=FREQUENCY, default=100.0,
                   help="band end (default 100 Hz)")
    p.add_argument("--continuous", action="store_true",
                   help="the drive in continuous time, as the paper models it (no sampling, "
                        "no delays) instead of the digital drive of [drive.sampling]")
    add_common_options(p, plots=True)
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``servotune nlcompliance``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        The exit status: 0. Errors are raised, and reported by
        :func:`servotune.cli.main` with status 1.

    Raises
    ------
    CliError
        If the band is not ``--f-start-hz < --f-end-hz``, or the closed loop linearised in the
        regime is unstable (:func:`servotune.harmonic.compliance.require_stable_regime`).

    Notes
    -----
    Writes ``results.json``
    (:meth:`servotune.harmonic.compliance.NonlinearCompliance.to_dict` with the axis' notes,
    ``continuous_drive``, ``folder`` and ``figures``) and, unless ``--no-plots``,
    ``nlcompliance.png``; prints the JSON with ``--json``, else a table of the peaks per force
    level.
    """
    from .. import progress
    from ..units import HZ_PER_RAD_S, RAD_S_PER_HZ

    if not args.f_start_hz < args.f_end_hz:
        raise CliError(f"--f-start-hz {args.f_start_hz:g} and --f-end-hz {args.f_end_hz:g}: the "
                       "band needs start < end")
    with progress.task(f"loading {args.axis}"):
        from ..axis import load_axis
        from ..harmonic import HarmonicSettings, nonlinear_compliance
        from ..harmonic.compliance import require_stable_regime
        from ..simulate.setup import axis_setup

        axis = load_axis(args.axis)
        if args.continuous:
            axis = axis.with_continuous_drive()
        setup = axis_setup(axis)
    try:
        require_stable_regime(setup, args.speed)
    except ValueError as exc:
        hint = "" if args.continuous else (" (the paper models the drive in continuous time: "
                                            "try --continuous)")
        raise CliError(f"{args.axis}: {exc}{hint}") from None
    names = [] if args.no_plots else ["nlcompliance.png"]
    out = RunOutput.for_args(args, "nlcompliance", axis.name, ["results.json", *names])
    forces = list(dict.fromkeys(args.force_pp))
    band = (args.f_start_hz * RAD_S_PER_HZ, args.f_end_hz * RAD_S_PER_HZ)
    with progress.task(f"{axis.name}: harmonic balance", total=len(forces),
                       unit="force levels") as task:
        result = nonlinear_compliance(setup, forces, speed=args.speed, band=band,
                                      settings=HarmonicSettings(args.harmonics),
                                      progress=task.report)
    data = result.to_dict()
    data["continuous_drive"] = bool(args.continuous)
    data["notes"] = default_notes(axis) + data["notes"]
    data["folder"] = str(out.path)
    data["figures"] = [str(out.file(n)) for n in names]
    with out.writing() as folder:
        write_results(folder, data)
        if names:
            save_figure(result.plot(), folder / names[0])
    if args.json:
        print_json(data)
        return 0
    where = "at rest" if not args.speed else f"feeding at {args.speed * 1e3:g} mm/s"
    print(f"{axis.name}: work-piece X compliance with LuGre pads {where}, harmonic balance with "
          f"{result.settings.harmonics} harmonics ({result.settings.samples} AFT samples)")
    print(f"{'F pp [N]':>9} | {'resonance [Hz]':>14} | {'peak [m/N]':>10} | "
          f"{'pad ampl. [m]':>13} | {'H=1 [Hz]':>8} {'H=1 [m/N]':>10} | points")
    for c, d in zip(result.curves, result.describing, strict=True):
        print(f"{c.force_pp:>9g} | {c.resonance * HZ_PER_RAD_S:>14.2f} | {c.peak:>10.4g} | "
              f"{c.pad_amplitude_at_peak:>13.3g} | {d.resonance * HZ_PER_RAD_S:>8.2f} "
              f"{d.peak:>10.4g} | {c.omega.size}")
    print("linear models: " + ", ".join(
        f"{k} {w * HZ_PER_RAD_S:.1f} Hz ({p:.3g} m/N)"
        for k, (w, p) in result.reference_peaks().items()))
    print(f"wrote {out.path}")
    return 0
