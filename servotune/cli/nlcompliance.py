"""``servotune nlcompliance AXIS --force-pp F [F ...]``: amplitude-dependent compliance.

Multi-harmonic balance of the closed-loop axis with LuGre friction at the guide-way pads
(:func:`servotune.harmonic.nonlinear_compliance`): per work-piece force level the compliance
curve over the band, its peak and resonance and the pad amplitude at the peak, at rest or
feeding at ``--speed``; a figure of the curves over the linear presliding, viscous-only and
(when feeding) sliding models and the describing-function prediction (the paper's remarks A-C
in one plot).

The default band is the axis' requirement band widened to hold the structure's work-piece
modes (:func:`servotune.analysis.default_band`). A largest value at the band's first or last
frequency is no resonance (:mod:`servotune.peaks`): the output says which edge and which flag
widens the band, and the JSON's ``resonance_hz`` is null.
"""

from __future__ import annotations

from ._common import (
    CliError,
    RunOutput,
    add_common_options,
    default_notes,
    friction_law_of,
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
                    "models and the describing-function prediction. The band defaults to "
                    "[requirements] band_hz widened to hold the modes that move the work piece "
                    "(x1.3 margin); a largest value at the band's edge is flagged, not "
                    "reported as a resonance.")
    p.add_argument("axis", help="axis folder with axis.toml (e.g. models/paper_x_axis)")
    p.add_argument("--force-pp", type=FORCE_PP, nargs="+", action="extend", required=True,
                   metavar="N", help=f"work-piece force peak to peak [N], {FORCE_PP.accepted}; "
                                     "one curve per value")
    p.add_argument("--speed", type=SPEED, default=0.0,
                   help=f"feed speed [m/s], {SPEED.accepted} (default 0: at rest)")
    p.add_argument("--harmonics", type=HARMONICS, default=9,
                   help=f"harmonics kept, {HARMONICS.accepted} (default 9)")
    p.add_argument("--f-start-hz", type=FREQUENCY, default=None,
                   help="band start [Hz] (default: [requirements] band_hz, widened to hold the "
                        "work-piece modes with x1.3 margin; the paper's sweep is 10-100 Hz)")
    p.add_argument("--f-end-hz", type=FREQUENCY, default=None,
                   help="band end [Hz] (default: as --f-start-hz)")
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
        If the band is not ``--f-start-hz < --f-end-hz`` (either taken from the default band
        when not given), or the closed loop linearised in the regime is unstable
        (:func:`servotune.harmonic.compliance.require_stable_regime`).

    Notes
    -----
    Writes ``results.json``
    (:meth:`servotune.harmonic.compliance.NonlinearCompliance.to_dict` with the axis' notes and
    the band's note, ``default_band`` (:meth:`servotune.peaks.ModeBand.to_dict`),
    ``continuous_drive``, ``folder`` and ``figures``) and, unless ``--no-plots``,
    ``nlcompliance.png``; prints the JSON with ``--json``, else a table of the peaks per force
    level.
    """
    from .. import progress

    if (args.f_start_hz is not None and args.f_end_hz is not None
            and not args.f_start_hz < args.f_end_hz):
        raise CliError(f"--f-start-hz {args.f_start_hz:g} and --f-end-hz {args.f_end_hz:g}: the "
                       "band needs start < end")
    with progress.task(f"loading {args.axis}"):
        from ..analysis import default_band
        from ..axis import load_axis
        from ..harmonic import HarmonicSettings, nonlinear_compliance
        from ..harmonic.compliance import require_stable_regime
        from ..peaks import chosen_band
        from ..simulate.setup import axis_setup

        axis = load_axis(args.axis)
        if args.continuous:
            axis = axis.with_continuous_drive()
        setup = axis_setup(axis)
    default = default_band(axis)
    try:
        band, band_note = chosen_band(default, args.f_start_hz, args.f_end_hz)
    except ValueError as exc:
        raise CliError(f"{exc} (--f-start-hz, --f-end-hz; an end not given is the default "
                       f"band's, {default.band_hz[0]:.4g}-{default.band_hz[1]:.4g} Hz)") from None
    try:
        require_stable_regime(setup, args.speed)
    except ValueError as exc:
        hint = "" if args.continuous else (" (the paper models the drive in continuous time: "
                                            "try --continuous)")
        raise CliError(f"{args.axis}: {exc}{hint}") from None
    names = [] if args.no_plots else ["nlcompliance.png"]
    out = RunOutput.for_args(args, "nlcompliance", axis.name, ["results.json", *names])
    forces = list(dict.fromkeys(args.force_pp))
    with progress.task(f"{axis.name}: harmonic balance", total=len(forces),
                       unit="force levels") as task:
        result = nonlinear_compliance(setup, forces, speed=args.speed, band=band,
                                      settings=HarmonicSettings(args.harmonics),
                                      progress=task.report)
    data = result.to_dict()
    data["continuous_drive"] = bool(args.continuous)
    data["default_band"] = default.to_dict()
    data["notes"] = default_notes(axis) + [band_note] + data["notes"]
    data["folder"] = str(out.path)
    data["figures"] = [str(out.file(n)) for n in names]
    with out.writing() as folder:
        data["friction_law"] = friction_law_of(axis)
        write_results(folder, data)
        if names:
            save_figure(result.plot(), folder / names[0])
    if args.json:
        print_json(data)
        return 0
    where = "at rest" if not args.speed else f"feeding at {args.speed * 1e3:g} mm/s"
    print(f"{axis.name}: work-piece X compliance with LuGre pads {where}, harmonic balance with "
          f"{result.settings.harmonics} harmonics ({result.settings.samples} AFT samples)")
    given = args.f_start_hz is not None or args.f_end_hz is not None
    print(f"  {'note' if given else 'default taken'}: {band_note}")
    widen = {"widen_low": "widen the band (--f-start-hz)",
             "widen_high": "widen the band (--f-end-hz)"}
    print(f"{'F pp [N]':>9} | {'resonance [Hz]':>14} | {'peak [m/N]':>10} | "
          f"{'pad ampl. [m]':>13} | {'H=1 [Hz]':>8} {'H=1 [m/N]':>10} | points")
    edges = []
    for c, d in zip(result.curves, result.describing, strict=True):
        cp, dp = c.band_peak, d.band_peak
        res, peak = _cells(cp, 14, 10)
        d_res, d_peak = _cells(dp, 8, 10)
        print(f"{c.force_pp:>9g} | {res} | {peak} | {c.pad_amplitude_at_peak:>13.3g} | "
              f"{d_res} {d_peak} | {c.omega.size}")
        edges += [f"{c.force_pp:g} N: {cp.describe(**widen)}"] if cp.edge else []
        edges += [f"{c.force_pp:g} N, H=1: {dp.describe(**widen)}"] if dp.edge else []
    refs = result.reference_band_peaks()
    print("linear models: " + ", ".join(
        f"{k} {_short(p)}" for k, p in refs.items()))
    for line in edges:
        print(f"  {line}")
    print(f"wrote {out.path}")
    return 0


def _cells(found, width_hz: int, width_peak: int) -> tuple[str, str]:
    """The resonance and peak cells of a table row: "at edge" instead of a resonance (the lines
    under the table say which edge)."""
    from ..units import HZ_PER_RAD_S

    if found.edge is None:
        return (f"{found.resonance * HZ_PER_RAD_S:>{width_hz}.2f}",
                f"{found.peak:>{width_peak}.4g}")
    return f"{'at edge':>{width_hz}}", f"{'-':>{width_peak}}"


def _short(found) -> str:
    """A linear model's peak in a few words: the resonance, or the edge its largest value is at."""
    from ..units import HZ_PER_RAD_S

    if found.edge is None:
        return f"{found.resonance * HZ_PER_RAD_S:.1f} Hz ({found.peak:.3g} m/N)"
    side = "lower" if found.edge == "low" else "upper"
    return (f"no resonance in the band (the largest value, {found.largest:.3g} m/N, is at its "
            f"{side} edge {found.largest_frequency * HZ_PER_RAD_S:.4g} Hz)")
