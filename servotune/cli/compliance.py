"""``servotune compliance``: work-piece compliance of an axis with a guide-way contact model."""

from __future__ import annotations

from ..units import HZ_PER_RAD_S
from ._common import (
    RunOutput,
    add_common_options,
    add_contact_options,
    axis_from_args,
    check_contact_args,
    contact_from_args,
    default_notes,
    print_json,
    save_figure,
    write_results,
)

__all__ = ["add_parser", "run"]

FIG9_C = (5e3, 5e4, 5e5, 5e6, 5e7)  # the paper's Fig 9 [N s/m]


def add_parser(subparsers) -> None:
    """Add the ``servotune compliance`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "compliance", help="work-piece X compliance with a guide-way contact model (Fig 9)",
        description="Closed-loop work-piece X compliance x/F with the chosen guide-way model, "
                    "beside locked and free pads; and the paper's Fig 9: the compliance with "
                    "viscous guide-way damping C = 5e3 ... 5e7 N s/m and no motion control. "
                    "The peak is taken over [requirements] band_hz. Without [drive] the "
                    "compliance is that of the structure without motion control; without "
                    "[friction] there is no Fig 9.")
    p.add_argument("axis", help="axis folder with axis.toml (e.g. models/paper_x_axis)")
    add_contact_options(p, default="viscous")
    add_common_options(p, plots=True)
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``servotune compliance``.

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

    check_contact_args(args)  # flags that do not fit --contact: refused before any work
    with progress.task(f"loading {args.axis}"):
        from .. import analysis
        from ..axis import load_axis
        from ..plant import Contact

        axis = axis_from_args(load_axis(args.axis), args)
    contact = contact_from_args(axis, args)
    controlled = axis.drive is not None
    fig9 = axis.friction is not None
    notes = default_notes(axis)
    if not controlled:
        notes.append("no [drive] section: the compliance of the structure without motion "
                     "control")
    if not fig9:
        notes.append("no [friction] section: no Fig 9 (it varies the guide-way damping)")
    names = [] if args.no_plots else ["compliance.png"] + (["compliance_fig9.png"] if fig9
                                                           else [])
    run = RunOutput.for_args(args, "compliance", axis.name, ["results.json", *names])
    curves, fig9_curves = [], []
    with progress.task(f"{axis.name}: compliance curves"):
        for c in [contact] + [x for x in (Contact.locked(), Contact.free())
                              if x.kind != contact.kind and axis.friction is not None]:
            if controlled or c.pads != "free":  # uncontrolled free pads: no static stiffness
                curves.append(analysis.compliance_curve(axis, c))
        if fig9:
            fig9_curves = analysis.uncontrolled_compliance(axis, FIG9_C)
    main = curves[0]
    out = {"axis": axis.name, "contact": contact.kind, "contact_note": contact.note,
           "controlled": controlled, "notes": notes,
           "peak_compliance": main.peak_compliance,
           "peak_frequency_hz": main.peak_frequency * HZ_PER_RAD_S,
           "peak_at_edge": main.at_edge,
           "curves": [c.to_dict() for c in curves],
           "fig9": [dict(c.to_dict(), c=cv) for c, cv in zip(fig9_curves, FIG9_C, strict=False)],
           "folder": str(run.path), "figures": [str(run.file(n)) for n in names]}
    with progress.task(f"writing {run.path}"), run.writing() as folder:
        if names:
            from ..plots import plot_compliance

            save_figure(plot_compliance(
                [(c.label, c.omega, c.values) for c in curves],
                title=f"{axis.name}: work-piece X compliance"
                      + (" (closed loop)" if controlled else " (no control)"),
                marks=[(f"{main.peak_compliance:.3g} m/N at "
                        f"{main.peak_frequency * HZ_PER_RAD_S:.1f} Hz",
                        main.peak_frequency, main.peak_compliance)]), folder / names[0])
        if names and fig9:
            save_figure(plot_compliance(
                [(c.label, c.omega, c.values) for c in fig9_curves],
                title=f"{axis.name}: compliance with viscous guide-way damping, no motion "
                      "control (Fig 9)"), folder / names[1])
        write_results(folder, out)
    if args.json:
        print_json(out)
        return 0
    print(f"{axis.name}: work-piece X compliance" + (" (closed loop)" if controlled else ""))
    for note in notes:
        print(f"  note: {note}")
    for c in curves:
        print(f"  {c.label:55} peak {c.peak_compliance:.4g} m/N at "
              f"{c.peak_frequency * HZ_PER_RAD_S:.2f} Hz"
              + (f"  AT THE BAND EDGE ({c.band[0] * HZ_PER_RAD_S:g}-"
                 f"{c.band[1] * HZ_PER_RAD_S:g} Hz): the largest "
                 "value there, not a resonance; widen [requirements] band_hz to find the peak"
                 if c.at_edge else ""))
    for c in fig9_curves:
        print(f"  no control, {c.label:43} peak {c.peak_compliance:.4g} m/N at "
              f"{c.peak_frequency * HZ_PER_RAD_S:.2f} Hz")
    print(f"  wrote {run.path}")
    return 0
