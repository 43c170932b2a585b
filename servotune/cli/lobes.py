"""``servotune lobes``: regenerative-chatter stability lobes of a milling set-up (paper, sec 2)."""

from __future__ import annotations

import argparse
import math
import warnings
from pathlib import Path

from ..units import HZ_PER_RAD_S
from ._common import (
    COUNT,
    CliError,
    RunOutput,
    UsageError,
    add_common_options,
    add_contact_options,
    axis_from_args,
    contact_from_args,
    default_notes,
    friction_law_of,
    number,
    print_json,
    require_section,
    save_figure,
    write_results,
)

__all__ = ["add_parser", "run", "BENCHMARK"]

BENCHMARK = {"teeth": 2, "kt": 6e8, "kn": 2e8, "immersion": 1.0, "milling": "down"}
SETUP_FLAGS = {"teeth": "--teeth", "kt": "--kt", "kn": "--kn", "immersion": "--immersion",
               "milling": "--milling"}
DEFAULT_INTERVALS = None  # servotune.chatter.sdm.DEFAULT_INTERVALS (tests check they agree)

MM = 1e-3

_TEETH = number(1, 100, integer=True, example=4)
# the plausible ranges of [cutting] kt and kn in an axis file (a unit slip: N/mm^2)
_COEFFICIENT = number(1e5, 1e11, example="6e8", unit="N/m^2")
_NORMAL = number(0.0, 1e11, example="2e8", unit="N/m^2")
_IMMERSION = number(0.0, 1.0, low_open=True, example=0.5)
_RPM = number(0.0, 1e6, low_open=True, example=12000, unit="rpm")
_SPEEDS = number(2, 100_000, integer=True, example=2000)
_INTERVALS = number(4, 4096, integer=True, example=40)
_DEPTH_MM = number(0.0, 1e4, low_open=True, example=2, unit="mm")
_MODE_PARTS = (("FN_HZ", number(0.0, 1e6, low_open=True, example=900, unit="Hz")),
               ("ZETA", number(0.0, 1.0, low_open=True, high_open=True, example=0.02)),
               ("K_N_PER_M", number(0.0, 1e15, low_open=True, example="1e7", unit="N/m")))


class _ModeAction(argparse.Action):
    """``--mode FN_HZ ZETA K_N_PER_M``, each part checked against its own range."""

    def __call__(self, parser, namespace, values, option_string=None):
        parsed = []
        for text, (name, parse) in zip(values, _MODE_PARTS, strict=True):
            try:
                parsed.append(parse(text))
            except argparse.ArgumentTypeError as exc:
                raise argparse.ArgumentError(self, f"{name}: {exc}") from None
        items = list(getattr(namespace, self.dest, None) or [])
        items.append(tuple(parsed))
        setattr(namespace, self.dest, items)


def add_parser(subparsers) -> None:
    """Add the ``servotune lobes`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "lobes", help="chatter stability lobes, b_crit and the chatter margin (sec 2)",
        description="Stability lobes of milling from the tool/work-piece compliance: the "
                    "zero-order approximation (Altintas and Budak 1995) or the "
                    "semi-discretisation (Insperger and Stepan 2004). Give the compliance as an "
                    "axis (its closed-loop work-piece compliance with --contact and its "
                    "[cutting] set-up), as modes (--mode, --mode-y) or as a measured FRF "
                    "(--frf). Without an axis the default cutting set-up is the "
                    "Insperger-Stepan benchmark: 2 teeth, Kt = 6e8, Kn = 2e8 N/m^2, full slot, "
                    "down-milling; options given override the axis' [cutting].")
    p.add_argument("axis", nargs="?", metavar="AXIS",
                   help="an axis folder (e.g. models/paper_x_axis)")
    add_contact_options(p, default="viscous")
    p.add_argument("--mode", nargs=3, action=_ModeAction, default=[],
                   metavar=("FN_HZ", "ZETA", "K_N_PER_M"),
                   help="a mode of the compliance in --direction: natural frequency [Hz], "
                        "damping ratio [-], modal stiffness [N/m] (repeatable)")
    p.add_argument("--mode-y", nargs=3, action=_ModeAction, default=[],
                   metavar=("FN_HZ", "ZETA", "K_N_PER_M"),
                   help="a mode in y, normal to the feed (repeatable), for 2-D compliance")
    p.add_argument("--direction", choices=("x", "y"), default="x",
                   help="direction of the --mode modes and of a SISO compliance "
                        "(x = feed, default)")
    p.add_argument("--frf", metavar="FILE.csv",
                   help="measured compliance: columns f_hz and re_ij_m_per_n, im_ij_m_per_n for "
                        "ij in xx, xy, yx, yy (at least xx or yy)")
    p.add_argument("--teeth", type=_TEETH, default=None, help="number of teeth (2)")
    p.add_argument("--kt", type=_COEFFICIENT, default=None,
                   help="tangential cutting coefficient Kt [N/m^2] (6e8)")
    p.add_argument("--kn", type=_NORMAL, default=None,
                   help="normal (radial) cutting coefficient Kn [N/m^2] (2e8); "
                        "Altintas' ratio Kr = Kn/Kt")
    p.add_argument("--immersion", type=_IMMERSION, default=None,
                   help="radial immersion a/D in (0, 1] (1 = full slot)")
    p.add_argument("--milling", choices=("down", "up"), default=None,
                   help="down (climb) or up (conventional) milling (down)")
    p.add_argument("--speed-rpm", nargs=2, type=_RPM, metavar=("MIN", "MAX"),
                   help="spindle-speed range [rpm] (default: the first ten lobes)")
    p.add_argument("--speed-count", type=_SPEEDS, dest="speeds", metavar="N",
                   help="number of spindle speeds (default 2000 for zoa, 200 for sdm)")
    # older spelling, kept: --speeds (a count, easily read as speeds in m/s or rpm)
    p.add_argument("--speeds", type=_SPEEDS, dest="speeds", help=argparse.SUPPRESS)
    p.add_argument("--method", choices=("zoa", "sdm"), default="zoa",
                   help="zoa: zero-order approximation; sdm: semi-discretisation (slower; "
                        "finds the flip lobes of low immersion; needs --mode)")
    p.add_argument("--lobes", type=COUNT, help="zoa: number of lobes (default: enough for MIN)")
    p.add_argument("--intervals", type=_INTERVALS, default=DEFAULT_INTERVALS,
                   help="sdm: intervals per tooth period (default: chosen per speed from the tooth "
                        "period and the highest mode, refined until b_lim is within 1 %%)")
    p.add_argument("--depth-max-mm", type=_DEPTH_MM,
                   help="sdm: deepest cut examined [mm] (default 5 x the zero-order b_crit)")
    p.add_argument("--required-depth-mm", type=_DEPTH_MM,
                   help="required axial depth [mm]: report the chatter margin")
    add_common_options(p, plots=True)
    p.set_defaults(func=run)


def _compliance(args):
    from .. import chatter

    modes = ([chatter.Mode.from_hz(*m, direction=args.direction) for m in args.mode]
             + [chatter.Mode.from_hz(*m, direction="y") for m in args.mode_y])
    given = [name for name, ok in (("AXIS", args.axis is not None), ("--mode", bool(modes)),
                                   ("--frf", bool(args.frf))) if ok]
    if len(given) > 1:
        raise UsageError(f"give one source of the compliance, not {' and '.join(given)}")
    if args.axis is not None:
        from ..analysis import feed_compliance
        from ..axis import load_axis

        axis = axis_from_args(load_axis(args.axis), args)
        contact = contact_from_args(axis, args)
        # the compliance the design job's lobes use, on the same frequency grid
        frd = feed_compliance(axis, contact)
        d = axis.cutting.direction if axis.cutting is not None else "x"
        args.direction = d
        return frd, f"{axis.name}: closed-loop wp.{d} compliance with {contact.note}", axis
    if args.frf:
        return _read_frf(args.frf), f"measured FRF {args.frf}", None
    if not modes:
        raise UsageError("give the compliance: AXIS, --mode FN_HZ ZETA K_N_PER_M (repeatable) "
                         "or --frf FILE.csv")
    return chatter.modal_compliance(modes), f"{len(modes)} mode(s)", None


def _read_frf(path):
    """The measured FRF of ``--frf``; frequencies out of order or not > 0 said in the file's
    terms (column f_hz, its data row, Hz)."""
    import re

    from .. import chatter

    try:
        return chatter.read_frf_csv(path)
    except ValueError as exc:
        text = str(exc)
        found = re.findall(r"got (\S+?)(?: then (\S+))? \(at index", text)
        if not text.startswith("omega must") or not found:
            raise
        values = [float(v) / (2.0 * math.pi) for v in found[0] if v]
        row = int(re.search(r"at index (\d+)", text).group(1)) + 1
        where = (f"data row {row} has {values[1]:.6g} Hz after {values[0]:.6g} Hz"
                 if len(values) == 2 else f"data row {row} has {values[0]:.6g} Hz")
        raise ValueError(f"{path}: column f_hz: {where}; the frequencies must be > 0 Hz and "
                         "increase from row to row: sort the rows by f_hz and drop repeated "
                         "frequencies") from None


def _setup(args, axis):
    """The milling set-up and, when the benchmark fills in values, a note saying which."""
    from .. import chatter

    base = dict(BENCHMARK)
    missing = [flag for key, flag in SETUP_FLAGS.items() if getattr(args, key) is None]
    if axis is not None and axis.cutting is None and missing:
        require_section(axis, "cutting", "[cutting]",
                        "servotune lobes AXIS (the milling set-up of the chatter limit)",
                        f", or give the whole set-up on the command line (missing: "
                        f"{', '.join(missing)})")
    note = None
    if axis is None and missing:
        note = ("cutting set-up not given in full: " + ", ".join(
            f"{flag} {BENCHMARK[key]:g}" if not isinstance(BENCHMARK[key], str) else
            f"{flag} {BENCHMARK[key]}" for key, flag in SETUP_FLAGS.items()
            if getattr(args, key) is None) + " from the Insperger-Stepan benchmark")
    if axis is not None and axis.cutting is not None:
        c = axis.cutting
        base = {"teeth": c.setup.teeth, "kt": c.setup.kt, "kn": c.setup.kn,
                "immersion": c.setup.radial_immersion, "milling": c.setup.milling}
        if args.speed_rpm is None:
            args.speed_rpm = list(c.speed_rpm)
        if args.required_depth_mm is None and axis.requirements.depth_required:
            args.required_depth_mm = axis.requirements.depth_required / MM
    values = {k: (getattr(args, k) if getattr(args, k) is not None else v)
              for k, v in base.items()}
    return chatter.MillingSetup(teeth=values["teeth"], kt=values["kt"], kn=values["kn"],
                                radial_immersion=values["immersion"],
                                milling=values["milling"]), note


def _subject(args, axis) -> str:
    if axis is not None:
        return axis.name
    if args.frf:
        return Path(args.frf).stem
    return "modes"


def run(args) -> int:
    """Run ``servotune lobes``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        The exit status: 0. Errors are raised, and reported by
        :func:`servotune.cli.main` with status 1.
    """
    from .. import progress

    if args.method == "zoa":  # flags of the semi-discretisation only
        unused = [flag for flag, value in (("--intervals", args.intervals),
                                           ("--depth-max-mm", args.depth_max_mm))
                  if value is not None]
        if unused:
            raise UsageError(f"{' and '.join(unused)} {'set' if len(unused) > 1 else 'sets'} "
                             "the semi-discretisation: add --method sdm, or drop "
                             f"{'them' if len(unused) > 1 else 'it'}")
    with progress.task("loading the compliance"):
        from .. import chatter

        system, source, axis = _compliance(args)
    setup, note = _setup(args, axis)
    if args.speed_rpm is not None and not args.speed_rpm[0] < args.speed_rpm[1]:
        raise CliError(f"--speed-rpm {args.speed_rpm[0]:g} {args.speed_rpm[1]:g}: the speed "
                       "range needs MIN < MAX")
    required = None if args.required_depth_mm is None else args.required_depth_mm * MM
    names = [] if args.no_plots else [f"lobes_{args.method}.png"]
    run_out = RunOutput.for_args(args, "lobes", _subject(args, axis), ["results.json", *names])
    count = args.speeds if args.speeds is not None else (2000 if args.method == "zoa" else 200)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with progress.task("stability lobes, zero-order approximation"):
            speeds = chatter.spindle_speeds(system, setup, args.speed_rpm, count,
                                            direction=args.direction)
            zoa = chatter.stability_lobes(system, setup, speeds, direction=args.direction,
                                          lobes=args.lobes)
        if args.method == "sdm":
            depth_max = None if args.depth_max_mm is None else args.depth_max_mm * MM
            with progress.task(f"stability lobes, semi-discretisation ({len(speeds)} speeds)"):
                result = chatter.sdm_lobes(system, setup, speeds, depth_max,
                                           intervals=args.intervals, direction=args.direction)
            shown = [result, zoa]
        else:
            result, shown = zoa, [zoa]
    from ..analysis import chatter_minimum_edge

    edge = chatter_minimum_edge(system, setup, args.direction)
    out = result.to_dict()
    out["compliance"] = source
    out["min_re_g_at_band_edge"] = edge
    if edge is not None:
        out["critical_frequency_hz"] = None     # the grid's edge, not a chatter resonance
    if args.method == "sdm":
        out["zoa_b_crit_m"] = zoa.b_crit
        out["zoa_critical_speed_rpm"] = zoa.critical_speed_rpm
    if required is not None:
        out["required_depth_m"] = required
        out["margin"] = result.margin(required)
    out["warnings"] = [str(w.message) for w in caught]
    out["notes"] = ([note] if note else []) + (default_notes(axis) if axis is not None else [])
    out["folder"] = str(run_out.path)
    out["figures"] = [str(run_out.file(n)) for n in names]
    with progress.task(f"writing {run_out.path}"), run_out.writing() as folder:
        if names:
            from .. import plots

            save_figure(plots.plot_stability_lobes(shown, required_depth=required),
                        folder / names[0])
        out["friction_law"] = friction_law_of(axis)
        write_results(folder, out)
    if args.json:
        print_json(out)
        return 0
    name = {"zoa": "zero-order approximation",
            "sdm": f"semi-discretisation ({result.intervals} intervals)"}[args.method]
    print(f"stability lobes, {name}: {source}; {setup.teeth} teeth, a/D = "
          f"{setup.radial_immersion:g}, {setup.milling}-milling, Kt = {setup.kt:g}, "
          f"Kn = {setup.kn:g} N/m^2")
    print(f"  speeds              : {result.speed_rpm[0]:.0f} .. {result.speed_rpm[-1]:.0f} rpm "
          f"({result.speed_rpm.size})")
    print(f"  b_crit              : {result.b_crit / MM:.4f} mm")
    if edge is not None:
        side = "lower" if edge == "low" else "upper"
        print(f"  WARNING: the most negative Re G is at the {side} edge of the compliance's "
              f"frequency grid ({zoa.critical_frequency * HZ_PER_RAD_S:.4g} Hz): no chatter "
              "resonance found inside it; Re G still falls beyond, so b_crit is not a limit; "
              "give the compliance over a wider band")
    print(f"  critical speed      : {result.critical_speed_rpm:.1f} rpm")
    if args.method == "zoa":
        print("  chatter frequency   : " + (
            f"{result.critical_frequency * HZ_PER_RAD_S:.1f} Hz" if edge is None
            else "none found inside the grid"))
    else:
        print(f"  zero-order b_crit   : {zoa.b_crit / MM:.4f} mm "
              f"at {zoa.critical_speed_rpm:.1f} rpm")
    print(f"  lowest limit shown  : {result.min_depth_limit / MM:.4f} mm")
    if out["speeds_without_limit"]:
        print(f"  note: {out['speeds_without_limit']} speeds have no limit below the depths "
              "examined")
    if required is not None:
        print(f"  margin at {required / MM:g} mm : {out['margin']:.3f} "
              f"({'stable' if out['margin'] > 1 else 'chatter'} at the worst speed)")
    for message in out["notes"]:  # each stands in for what was not given
        print(f"  default taken: {message}")
    for message in out["warnings"]:
        print(f"  warning: {message}")
    print(f"  wrote {run_out.path}")
    return 0
