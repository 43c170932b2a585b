"""``servotune compliance``: work-piece compliance of an axis with a guide-way contact model."""

from __future__ import annotations

from .. import analysis, report
from ..axis import load_axis
from ..plant import Contact
from ._common import (
    add_contact_options,
    add_output_options,
    axis_from_args,
    contact_from_args,
    print_json,
)

__all__ = ["add_parser", "run"]

FIG9_C = (5e3, 5e4, 5e5, 5e6, 5e7)  # the paper's Fig 9 [N s/m]


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "compliance", help="work-piece X compliance with a guide-way contact model (Fig 9)",
        description="Closed-loop work-piece X compliance x/F with the chosen guide-way model, "
                    "beside locked and free pads; and the paper's Fig 9: the compliance with "
                    "viscous guide-way damping C = 5e3 ... 5e7 N s/m and no motion control. "
                    "The peak is taken over [requirements] band_hz.")
    p.add_argument("axis", help="axis folder with axis.toml (e.g. models/paper_x_axis)")
    add_contact_options(p, default="viscous")
    add_output_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    axis = axis_from_args(load_axis(args.axis), args)
    contact = contact_from_args(axis, args)
    figures = [args.out / f"compliance_{axis.name}.png"]
    fig9 = axis.friction is not None
    if fig9:
        figures.append(args.out / f"compliance_fig9_{axis.name}.png")
    report.check_writable(figures, args.force)
    controlled = axis.drive is not None
    curves = []
    for c in [contact] + [x for x in (Contact.locked(), Contact.free())
                          if x.kind != contact.kind and axis.friction is not None]:
        if controlled or c.kind != "free":  # uncontrolled free pads: no static stiffness
            curves.append(analysis.compliance_curve(axis, c))
    from ..plots import plot_compliance

    main = curves[0]
    fig = plot_compliance([(c.label, c.omega, c.values) for c in curves],
                          title=f"{axis.name}: work-piece X compliance"
                                + (" (closed loop)" if controlled else " (no control)"),
                          marks=[(f"{main.peak_compliance:.3g} m/N at "
                                  f"{main.peak_frequency * analysis.HZ:.1f} Hz",
                                  main.peak_frequency, main.peak_compliance)])
    report.save_figure(fig, figures[0], args.force)
    fig9_curves = []
    if fig9:
        fig9_curves = analysis.uncontrolled_compliance(axis, FIG9_C)
        report.save_figure(plot_compliance(
            [(c.label, c.omega, c.values) for c in fig9_curves],
            title=f"{axis.name}: compliance with viscous guide-way damping, no motion control "
                  "(Fig 9)"), figures[1], args.force)
    out = {"axis": axis.name, "contact": contact.kind, "contact_note": contact.note,
           "controlled": controlled,
           "peak_compliance": main.peak_compliance,
           "peak_frequency_hz": main.peak_frequency * analysis.HZ,
           "curves": [c.to_dict() for c in curves],
           "fig9": [dict(c.to_dict(), c=cv) for c, cv in zip(fig9_curves, FIG9_C, strict=False)],
           "figures": [str(f) for f in figures]}
    if args.json:
        print_json(out)
        return 0
    print(f"{axis.name}: work-piece X compliance" + (" (closed loop)" if controlled else ""))
    for c in curves:
        print(f"  {c.label:55} peak {c.peak_compliance:.4g} m/N at "
              f"{c.peak_frequency * analysis.HZ:.2f} Hz")
    for c in fig9_curves:
        print(f"  no control, {c.label:43} peak {c.peak_compliance:.4g} m/N at "
              f"{c.peak_frequency * analysis.HZ:.2f} Hz")
    for f in figures:
        print(f"  wrote {f}")
    return 0
