"""``servotune bode``: the velocity and position loops of an axis with their margins.

The axis' model checks run first (:func:`servotune.model_checks.axis_model_checks`): a
structure whose rotor-to-encoder motion contradicts the drive's transmission (a flipped DOF
direction, a ratio off by more than 2 %) is refused with an error naming the DOF and the fix
(its margins would be those of a positive-feedback loop); kept modes that do not cover the
requirements' band give a warning (standard error, the text output, ``warnings`` in the JSON).
"""

from __future__ import annotations

import sys

from ._common import (
    RunOutput,
    add_common_options,
    add_contact_options,
    axis_from_args,
    contact_from_args,
    default_notes,
    friction_law_of,
    print_json,
    require_section,
    save_figure,
    write_results,
)

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> None:
    """Add the ``servotune bode`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "bode", help="loop transfer functions of the velocity and position loops, with margins",
        description="Bode diagram of the velocity loop (opened at the motor-speed feedback, "
                    "position loop open) and of the position loop (opened at the position "
                    "feedback, velocity loop closed); gain and phase margins, sensitivity peak "
                    "Ms and closed-loop bandwidth of each. An Ms at the first or last "
                    "frequency of the grid is flagged (ms_at_band_edge): the largest value "
                    "there is no peak, the sensitivity still rises beyond.")
    p.add_argument("axis", help="axis folder with axis.toml (e.g. models/paper_x_axis)")
    add_contact_options(p, default="viscous")
    add_common_options(p, plots=True)
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``servotune bode``.

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

    with progress.task(f"loading {args.axis}"):
        from .. import analysis
        from ..axis import load_axis
        from ..model_checks import axis_model_checks

        axis = axis_from_args(load_axis(args.axis), args)
    require_section(axis, "drive", "[drive]", "servotune bode (it analyses the servo loops)")
    with progress.task(f"{axis.name}: model checks"):
        checks = axis_model_checks(axis).require()
    for text in checks.warnings:
        print(f"WARNING: {text}", file=sys.stderr)
    contact = contact_from_args(axis, args)
    names = [] if args.no_plots else ["bode.png"]
    run = RunOutput.for_args(args, "bode", axis.name, ["results.json", *names])
    with progress.task(f"{axis.name}: loop analysis"):
        result = analysis.loop_report(axis, contact)
    out = {"axis": axis.name, "kv": axis.drive.kv,
           "kv_m_per_min_per_mm": axis.drive.kv_m_per_min_per_mm, **result.to_dict(),
           "folder": str(run.path), "figures": [str(run.file(n)) for n in names],
           "warnings": list(checks.warnings), "model_checks": checks.to_dict(),
           "notes": default_notes(axis)}
    with progress.task(f"writing {run.path}"), run.writing() as folder:
        if names:
            save_figure(result.plot(f"{axis.name}: loops with {contact.note}"), folder / names[0])
        out["friction_law"] = friction_law_of(axis)
        write_results(folder, out)
    if args.json:
        print_json(out)
        return 0
    print(f"{axis.name}: loops with {contact.note}; Kv = {axis.drive.kv:.3g} 1/s "
          f"({axis.drive.kv_m_per_min_per_mm:.3g} (m/min)/mm)")
    for note in out["notes"]:
        print(f"  default taken: {note}")
    print(f"  {'loop':10} {'PM [deg]':>9} {'GM [dB]':>8} {'lower GM [dB]':>14} {'Ms':>6} "
          f"{'crossover [Hz]':>15} {'bandwidth [Hz]':>15}")
    for name in ("velocity", "position"):
        a = out[f"{name}_loop"]
        gm = "inf" if a["gain_margin_db"] is None else f"{a['gain_margin_db']:.1f}"
        low = "-" if a["gain_margin_lower_db"] is None else f"{a['gain_margin_lower_db']:.1f}"
        print(f"  {name:10} {a['phase_margin_deg']:9.1f} {gm:>8} {low:>14} {a['ms']:6.2f} "
              f"{a['crossover_hz']:15.2f} {a['bandwidth_hz']:15.2f}")
    for name in ("velocity", "position"):
        a = out[f"{name}_loop"]
        if a["ms_at_band_edge"] is not None:
            side = "lower" if a["ms_at_band_edge"] == "low" else "upper"
            lo, hi = a["band_hz"]
            print(f"  {name} loop: Ms {a['ms']:.2f} is the largest sensitivity at the grid's "
                  f"{side} edge {a['ms_frequency_hz']:.4g} Hz, not a peak found inside "
                  f"{lo:.4g}-{hi:.4g} Hz: the sensitivity still rises there")
    for name in ("velocity", "position"):
        a = out[f"{name}_loop"]
        if a.get("inert"):
            print(f"  WARNING: {name} loop: {a['note']}")
    for line in checks.warnings:
        print(f"  WARNING: {line}")
    print(f"  wrote {run.path}")
    return 0
