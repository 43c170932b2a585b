"""``servotune bode``: the velocity and position loops of an axis with their margins."""

from __future__ import annotations

from .. import analysis, report
from ..axis import load_axis
from ._common import (
    add_contact_options,
    add_output_options,
    axis_from_args,
    contact_from_args,
    print_json,
)

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "bode", help="loop transfer functions of the velocity and position loops, with margins",
        description="Bode diagram of the velocity loop (opened at the motor-speed feedback, "
                    "position loop open) and of the position loop (opened at the position "
                    "feedback, velocity loop closed); gain and phase margins, sensitivity peak "
                    "Ms and closed-loop bandwidth of each.")
    p.add_argument("axis", help="axis folder with axis.toml (e.g. models/paper_x_axis)")
    add_contact_options(p, default="viscous")
    add_output_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    axis = axis_from_args(load_axis(args.axis), args)
    contact = contact_from_args(axis, args)
    figure = args.out / f"bode_{axis.name}.png"
    report.check_writable([figure], args.force)
    result = analysis.loop_report(axis, contact)
    report.save_figure(result.plot(f"{axis.name}: loops with {contact.note}"), figure, args.force)
    out = {"axis": axis.name, "kv": axis.drive.kv,
           "kv_m_per_min_per_mm": axis.drive.kv_m_per_min_per_mm, **result.to_dict(),
           "figures": [str(figure)]}
    if args.json:
        print_json(out)
        return 0
    print(f"{axis.name}: loops with {contact.note}; Kv = {axis.drive.kv:.3g} 1/s "
          f"({axis.drive.kv_m_per_min_per_mm:.3g} (m/min)/mm)")
    print(f"  {'loop':10} {'PM [deg]':>9} {'GM [dB]':>8} {'Ms':>6} {'crossover [Hz]':>15} "
          f"{'bandwidth [Hz]':>15}")
    for name in ("velocity", "position"):
        a = out[f"{name}_loop"]
        gm = "inf" if a["gain_margin_db"] is None else f"{a['gain_margin_db']:.1f}"
        print(f"  {name:10} {a['phase_margin_deg']:9.1f} {gm:>8} {a['ms']:6.2f} "
              f"{a['crossover_hz']:15.2f} {a['bandwidth_hz']:15.2f}")
    print(f"  wrote {figure}")
    return 0
