"""``servotune modes``: natural frequencies of an axis and each mode's share of work-piece X.

The share (``wp_x_participation``) of mode j is its part of the static compliance at the
work-piece X DOF: phi_j(wp.x)^2 / omega_j^2 over the sum of the same for every flexible mode
(phi mass-normalised). The shares add up to 1; rigid-body modes get 0. The mode with the
largest share is the one that moves the work piece in X.

The peak work-piece X compliance is sought over the axis' requirement band widened to hold the
modes that move the work piece (:func:`servotune.analysis.default_band`); a largest value at the
band's first or last frequency is no resonance and is reported as such (:mod:`servotune.peaks`).
A rigid-body mode that moves the work piece has no peak in any band: the output says so.

When the structure is a reduced model whose kept fixed-interface modes do not cover the
requirements' band with the margin (``servotune.model_checks.band_coverage``), a warning that
names the band, the frequency reached and the fix goes to standard error (and into the JSON
under ``warnings``): the modes and the compliance near the top of the band are then not
reliable.
"""

from __future__ import annotations

import math
import sys

from ..units import HZ_PER_RAD_S
from ._common import (
    COUNT,
    RunOutput,
    add_common_options,
    default_notes,
    friction_law_of,
    print_json,
    write_results,
)

__all__ = ["add_parser", "run"]

WP_X = "wp.x"


def add_parser(subparsers) -> None:
    """Add the ``servotune modes`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "modes", help="natural frequencies and each mode's share of work-piece X motion",
        description="Natural frequencies of the axis structure and, per mode, its share of "
                    "work-piece X motion: phi_j(wp.x)^2/omega_j^2 over the sum over all "
                    "flexible modes (phi mass-normalised), i.e. the mode's part of the static "
                    "compliance at wp.x; shares add up to 1, rigid-body modes get 0. Also the "
                    "peak work-piece X compliance over [requirements] band_hz (default "
                    "5-300 Hz) widened to hold the work-piece modes (x1.3 margin), when no "
                    "rigid-body mode moves the work piece; a largest value at the band's edge "
                    "is flagged, not reported as a resonance.")
    p.add_argument("axis", help="axis folder with axis.toml (e.g. models/paper_x_axis)")
    p.add_argument("--pads", choices=("locked", "free"), default="free",
                   help="guide-way pads held (stiction at standstill) or free (default free)")
    p.add_argument("--motor", choices=("locked", "free"), default="free",
                   help="motor rotor held (a stiff servo) or free (default free)")
    p.add_argument("--count", type=COUNT, default=None,
                   help="show only the lowest COUNT modes in the text output")
    add_common_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``servotune modes``.

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
        from ..analysis import default_band
        from ..axis import load_axis
        from ..model_checks import band_coverage
        from ..peaks import rigid_body_moves, structure_peak

        axis = load_axis(args.axis)
    out = RunOutput.for_args(args, "modes", axis.name, ["results.json"])
    coverage = band_coverage(axis.structure, axis.requirements)
    warnings = [] if coverage.covered else [f"band coverage: {coverage.message}"]
    for text in warnings:
        print(f"WARNING: {text}", file=sys.stderr)
    model = axis.configuration(pads=args.pads, motor=args.motor)
    with progress.task(f"{axis.name}: modes of {model.n} DOFs"):
        omega = model.natural_frequencies()
        zeta = model.modal_damping_ratios()
        share = model.participation(WP_X)
    j = int(share.argmax())
    rigid = int((omega == 0).sum())
    default = default_band(axis)
    band = default.band
    rigid_wp = rigid_body_moves(model, WP_X)
    peak = None if rigid_wp else structure_peak(model, WP_X, band)
    result = {
        "axis": axis.name, "pads": args.pads, "motor": args.motor, "n_dofs": model.n,
        "frequencies_hz": (omega * HZ_PER_RAD_S).tolist(),
        "damping_ratios": [None if math.isnan(z) else float(z) for z in zeta],
        "wp_x_participation": share.tolist(),
        "wp_x_mode": j + 1, "wp_x_mode_hz": float(omega[j] * HZ_PER_RAD_S),
        "rigid_body_modes": rigid,
        "wp_x_peak_compliance": None if peak is None else peak.peak,
        "wp_x_peak_hz": (None if peak is None or peak.resonance is None
                         else peak.resonance * HZ_PER_RAD_S),
        "wp_x_peak_at_band_edge": None if peak is None else peak.edge,
        "wp_x_largest_compliance": None if peak is None else peak.largest,
        "wp_x_largest_at_hz": (None if peak is None
                               else peak.largest_frequency * HZ_PER_RAD_S),
        "wp_x_rigid_body_mode": rigid_wp,
        "band_hz": [band[0] * HZ_PER_RAD_S, band[1] * HZ_PER_RAD_S],
        "default_band": default.to_dict(),
        "notes": [*default_notes(axis), default.note()],
        "folder": str(out.path),
        "band_coverage": coverage.to_dict(),
        "warnings": warnings,
    }
    with out.writing() as folder:
        result["friction_law"] = friction_law_of(axis)
        write_results(folder, result)
    if args.json:
        print_json(result)
        return 0
    print(f"{axis.name}: pads {args.pads}, motor {args.motor}, {model.n} DOFs, "
          f"{rigid} rigid-body mode(s)")
    print("  mode    f [Hz]   zeta [%]   wp.x share [%]")
    count = len(omega) if args.count is None else args.count
    for i in range(min(count, len(omega))):
        z = "      -" if math.isnan(zeta[i]) else f"{100 * zeta[i]:7.2f}"
        mark = "  <- work piece X" if i == j else ""
        print(f"  {i + 1:4d} {omega[i] * HZ_PER_RAD_S:9.2f}  {z}   {100 * share[i]:10.2f}{mark}")
    print(f"  work-piece X mode: {omega[j] * HZ_PER_RAD_S:.2f} Hz "
          f"({100 * share[j]:.1f} % of the static "
          "compliance at wp.x)")
    lo, hi = band[0] * HZ_PER_RAD_S, band[1] * HZ_PER_RAD_S
    if peak is not None and peak.edge is None:
        print(f"  peak wp.x compliance: {peak.peak:.3e} m/N at "
              f"{peak.resonance * HZ_PER_RAD_S:.2f} Hz ({lo:g}-{hi:g} Hz)")
    elif peak is not None:
        print("  wp.x compliance: " + peak.describe(
            widen_low="widen [requirements] band_hz below",
            widen_high="widen [requirements] band_hz above"))
    else:
        print("  no peak wp.x compliance: a rigid-body mode (0 Hz) moves the work piece "
              f"(pads {args.pads}, motor {args.motor}); its compliance grows without bound "
              "towards 0 Hz and no band can hold it")
    for note in default_notes(axis):
        print(f"  default taken: {note}")
    print(f"  default taken: {default.note()}")
    if coverage.reduced:
        print(f"  {'WARNING: ' if not coverage.covered else ''}{coverage.message}")
    print(f"  wrote {out.path}")
    return 0
