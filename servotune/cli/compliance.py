"""``servotune compliance``: work-piece compliance of an axis with a guide-way contact model.

The peak is sought over the axis' requirement band widened to hold the structure's work-piece
modes (:func:`servotune.analysis.default_band`); a largest value at the band's first or last
frequency is no resonance (:mod:`servotune.peaks`), and the output says so.
"""

from __future__ import annotations

from ..units import HZ_PER_RAD_S
from ._common import (
    CliError,
    RunOutput,
    add_common_options,
    add_contact_options,
    axis_from_args,
    check_contact_args,
    contact_from_args,
    default_notes,
    friction_law_of,
    number,
    print_json,
    save_figure,
    write_results,
)

__all__ = ["add_parser", "run"]

FIG9_C = (5e3, 5e4, 5e5, 5e6, 5e7)  # the paper's Fig 9 [N s/m]
FREQUENCY = number(0.0, 1e4, low_open=True, example=10, unit="Hz")


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
                    "The peak is taken over [requirements] band_hz, widened to hold the "
                    "modes that move the work piece (x1.3 margin), or over --f-start-hz to "
                    "--f-end-hz; a largest value at the band's edge is flagged, not reported "
                    "as a resonance. Without [drive] the "
                    "compliance is that of the structure without motion control; without "
                    "[friction] there is no Fig 9.")
    p.add_argument("axis", help="axis folder with axis.toml (e.g. models/paper_x_axis)")
    p.add_argument("--f-start-hz", type=FREQUENCY, default=None,
                   help="start of the band of the peak [Hz] (default: [requirements] band_hz, "
                        "widened to hold the work-piece modes with x1.3 margin)")
    p.add_argument("--f-end-hz", type=FREQUENCY, default=None,
                   help="end of the band of the peak [Hz] (default: as --f-start-hz)")
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
        from ..peaks import chosen_band
        from ..plant import Contact

        axis = axis_from_args(load_axis(args.axis), args)
    contact = contact_from_args(axis, args)
    controlled = axis.drive is not None
    fig9 = axis.friction is not None
    default = analysis.default_band(axis)
    try:
        band, band_note = chosen_band(default, args.f_start_hz, args.f_end_hz)
    except ValueError as exc:
        raise CliError(f"{exc} (--f-start-hz, --f-end-hz; an end not given is the default "
                       f"band's, {default.band_hz[0]:.4g}-{default.band_hz[1]:.4g} Hz)") from None
    omega = analysis.band_omega(band)
    notes = [*default_notes(axis), band_note]
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
                curves.append(analysis.compliance_curve(axis, c, omega=omega, band=band))
        if fig9:
            fig9_curves = analysis.uncontrolled_compliance(axis, FIG9_C, omega=omega, band=band)
    main = curves[0]
    first = main.to_dict()
    del first["label"]
    out = {"axis": axis.name, "contact": contact.kind, "contact_note": contact.note,
           "controlled": controlled, "notes": notes, **first,
           "default_band": default.to_dict(),
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
                        f"{main.peak_frequency * HZ_PER_RAD_S:.1f} Hz"
                        + ("" if main.edge is None else
                           f" (the band's {main.edge} edge: no resonance)"),
                        main.peak_frequency, main.peak_compliance)]), folder / names[0])
        if names and fig9:
            save_figure(plot_compliance(
                [(c.label, c.omega, c.values) for c in fig9_curves],
                title=f"{axis.name}: compliance with viscous guide-way damping, no motion "
                      "control (Fig 9)"), folder / names[1])
        out["friction_law"] = friction_law_of(axis)
        write_results(folder, out)
    if args.json:
        print_json(out)
        return 0
    print(f"{axis.name}: work-piece X compliance" + (" (closed loop)" if controlled else ""))
    # one vocabulary: what the command assumed is a default taken, anything else a note
    taken = set(default_notes(axis))
    if args.f_start_hz is None and args.f_end_hz is None:
        taken.add(band_note)
    for note in notes:
        print(f"  {'default taken' if note in taken else 'note'}: {note}")
    widen = {"widen_low": "widen the band (--f-start-hz)",
             "widen_high": "widen the band (--f-end-hz)"}
    for c in curves:
        print(f"  {c.label:55} {c.band_peak.describe(**widen)}")
    for c in fig9_curves:
        print(f"  no control, {c.label:43} {c.band_peak.describe(**widen)}")
    print(f"  wrote {run.path}")
    return 0
