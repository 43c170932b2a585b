"""``servotune modes``: natural frequencies of an axis and each mode's share of work-piece X.

The share (``wp_x_participation``) of mode j is its part of the static compliance at the
work-piece X DOF: phi_j(wp.x)^2 / omega_j^2 over the sum of the same for every flexible mode
(phi mass-normalised). The shares add up to 1; rigid-body modes get 0. The mode with the
largest share is the one that moves the work piece in X.

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
                    "5-300 Hz) when the configuration has no rigid-body mode.")
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
        from ..axis import load_axis
        from ..model_checks import band_coverage

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
    band = axis.requirements.band
    peak = None
    if rigid == 0:
        w_peak, value = model.compliance_peak(WP_X, band[0], band[1])
        peak = {"wp_x_peak_compliance": value, "wp_x_peak_hz": w_peak * HZ_PER_RAD_S}
    result = {
        "axis": axis.name, "pads": args.pads, "motor": args.motor, "n_dofs": model.n,
        "frequencies_hz": (omega * HZ_PER_RAD_S).tolist(),
        "damping_ratios": [None if math.isnan(z) else float(z) for z in zeta],
        "wp_x_participation": share.tolist(),
        "wp_x_mode": j + 1, "wp_x_mode_hz": float(omega[j] * HZ_PER_RAD_S),
        "rigid_body_modes": rigid,
        "wp_x_peak_compliance": None if peak is None else peak["wp_x_peak_compliance"],
        "wp_x_peak_hz": None if peak is None else peak["wp_x_peak_hz"],
        "band_hz": [band[0] * HZ_PER_RAD_S, band[1] * HZ_PER_RAD_S],
        "notes": default_notes(axis),
        "folder": str(out.path),
        "band_coverage": coverage.to_dict(),
        "warnings": warnings,
    }
    with out.writing() as folder:
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
    if peak is not None:
        lo, hi = band[0] * HZ_PER_RAD_S, band[1] * HZ_PER_RAD_S
        print(f"  peak wp.x compliance: {peak['wp_x_peak_compliance']:.3e} m/N at "
              f"{peak['wp_x_peak_hz']:.2f} Hz ({lo:g}-{hi:g} Hz)")
    for note in result["notes"]:
        print(f"  default taken: {note}")
    if coverage.reduced:
        print(f"  {'WARNING: ' if not coverage.covered else ''}{coverage.message}")
    print(f"  wrote {out.path}")
    return 0
