"""``servotune identify``: natural frequencies, damping ratios and residues from measured FRFs.

Reads impact-hammer FRFs (CSV or UFF dataset 58, :mod:`servotune.measured.frf`), estimates the
poles by LSCF at every model order, chooses the physical ones by the stabilisation rule (or the
poles nearest to ``--modes-hz``), fits the residues by LSFD and reports how well the modes
reproduce the measurement (:mod:`servotune.measured.ema`). Figures: the measured against the
synthesised FRFs, and the stabilisation diagram.

With ``--axis`` the measurement is joined with the axis model (:mod:`servotune.measured.update`):
the first FRF is the receptance at ``--dof`` with the drive switched off and the guide-way pads
stuck (the axis' ``stiction`` contact); the natural frequencies and damping ratios of the stored
modes that move the identified poles most are fitted to it within bounds, and a copy of the
axis folder with the updated model is written (``updated_axis/``), the user's axis untouched.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ._common import (
    RunOutput,
    UsageError,
    add_common_options,
    number,
    print_json,
    save_figure,
    write_results,
)

__all__ = ["add_parser", "run"]

FIGURES = ("frf_fit.png", "stabilisation.png")
UPDATE_FIGURE = "model_update.png"
UPDATED_AXIS = "updated_axis"
NOT_DONE = "the drive's measured speed plant (--kind) is not in this version"
_FREQUENCY = number(0.0, 1e6, low_open=True, example=120, unit="Hz")
_ORDER = number(5, 200, integer=True, example=40)
QUANTITIES = ("receptance", "mobility", "accelerance")


def add_parser(subparsers) -> None:
    """Add the ``servotune identify`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "identify",
        help="modes from measured FRFs (LSCF/LSFD); with --axis, the axis model updated to "
             "them",
        description="Modal identification of measured FRFs (impact-hammer receptances at the "
                    "work piece): poles by LSCF at model orders 2..2N, residues by LSFD with "
                    "lower and upper residual terms (sdypy-EMA). A pole is physical when it "
                    "stands over at least 5 consecutive model orders within 1 % in frequency "
                    "and 5 % in damping of the order below, with a damping ratio in (0, 0.3), "
                    "outside the band's outer 3 %; such poles within 1 % are one mode. "
                    "--modes-hz picks the poles nearest to given frequencies instead. Writes "
                    "results.json, frf_fit.png (measured against synthesised) and "
                    "stabilisation.png. With --axis, the axis' reduced model is updated to the "
                    "measurement: the first FRF is the receptance at --dof with the drive off "
                    "and the pads stuck (the stiction contact); the natural frequency (stiffness "
                    "in the modal basis, shapes kept) and the damping ratio of the stored mode "
                    "that moves each identified pole most are fitted by least squares on the "
                    "log-magnitude and phase over the band (frequencies within +-20 %, damping "
                    "ratios in [0.001, 0.2]); writes model_update.png and updated_axis/, a copy "
                    "of the axis folder with the updated structure.npz and modal_damping. Not "
                    "yet: the drive's measured speed plant (--kind).")
    p.add_argument("files", nargs="+", metavar="FRF_FILE",
                   help="CSV (f_hz with re,im or mag,phase_deg; '# quantity:' and '# units:' "
                        "comment lines) or UFF dataset 58 (.uff, .unv); several FRFs of one "
                        "excitation on the same frequency lines; the first is the one whose "
                        "residues are 'residue' (give the driving point first)")
    p.add_argument("--kind", choices=("structure",), default="structure",
                   help="what was measured: 'structure' (FRFs of the machine structure, e.g. "
                        "hammer tests at the work piece, drive off, pads stuck; the only kind "
                        "so far)")
    p.add_argument("--axis", default=None, metavar="AXIS",
                   help="axis folder to update to the measurement (the folder itself is never "
                        "changed: the updated copy goes to "
                        "DIR/identify_<first file's name>/updated_axis)")
    p.add_argument("--dof", default=None, metavar="DOF",
                   help="the DOF of the measurement, force and response (default wp.x; only "
                        "with --axis)")
    p.add_argument("--quantity", choices=QUANTITIES, default=None,
                   help="the quantity of files that do not state it (default receptance)")
    p.add_argument("--units", default=None, metavar="UNIT",
                   help="units of CSV files that do not state them: m/N, mm/N, um/N, nm/N; "
                        "m/s/N, mm/s/N; m/s^2/N, g/N (default the SI unit)")
    p.add_argument("--band-hz", type=_FREQUENCY, nargs=2, metavar=("LO", "HI"), default=None,
                   help="the band to fit [Hz] (default the whole measurement above 0 Hz)")
    p.add_argument("--max-order", type=_ORDER, default=40, metavar="N",
                   help=f"number of LSCF model orders (denominator degrees 2..2N), "
                        f"{_ORDER.accepted} (default 40)")
    p.add_argument("--modes-hz", type=_FREQUENCY, nargs="+", metavar="F", default=None,
                   help="take the poles nearest to these natural frequencies [Hz] instead of "
                        "the automatic rule")
    add_common_options(p, plots=True)
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``servotune identify``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        The exit status: 0. Errors are raised, and reported by :func:`servotune.cli.main`
        with status 1 (2 for arguments in conflict).
    """
    from .. import progress
    from ..units import HZ_PER_RAD_S, RAD_S_PER_HZ

    if args.band_hz is not None and args.band_hz[0] >= args.band_hz[1]:
        raise UsageError(f"--band-hz {args.band_hz[0]:g} {args.band_hz[1]:g}: the low "
                         "frequency must be below the high one")
    if args.dof is not None and args.axis is None:
        raise UsageError(f"--dof {args.dof}: the DOF of the measurement serves the updating of "
                         "an axis; give --axis AXIS too, or drop --dof")
    files = [Path(f) for f in args.files]
    names = [] if args.no_plots else list(FIGURES)
    if args.axis is not None and not args.no_plots:
        names.append(UPDATE_FIGURE)
    written = [*names, UPDATED_AXIS] if args.axis is not None else names
    subject = files[0].stem + (f"+{len(files) - 1}" if len(files) > 1 else "")
    axis = None
    if args.axis is not None:
        with progress.task(f"loading {args.axis}"):
            axis, contact, dof = _axis_and_contact(args)
    out = RunOutput.for_args(args, "identify", subject, ["results.json", *written])
    with progress.task(f"reading {len(files)} file(s)"):
        from ..measured.ema import identify_modes
        from ..measured.frf import read_frfs

        frfs = read_frfs(files, quantity=args.quantity, units=args.units)
    band = None if args.band_hz is None else tuple(f * RAD_S_PER_HZ for f in args.band_hz)
    wanted = None if args.modes_hz is None else [f * RAD_S_PER_HZ for f in args.modes_hz]
    with progress.task(f"identifying modes of {len(frfs)} FRF(s)"):
        fit = identify_modes(frfs, band=band, max_order=args.max_order, frequencies=wanted)
    update = None
    if axis is not None:
        from ..measured.update import update_model

        with progress.task(f"updating {axis.name} to the measurement at {dof}"):
            update = update_model(axis.structure, fit, contact, axis.pads, dof)
    result = {"command": "identify", "kind": args.kind, "files": [str(f) for f in files],
              **fit.to_dict(), "folder": str(out.path),
              "figures": [str(out.file(n)) for n in names], "not_done": NOT_DONE}
    if update is not None:
        extra = update.to_dict()
        notes, warnings = extra.pop("notes"), extra.pop("warnings")
        result.update({"axis": str(args.axis), "updated_axis": str(out.file(UPDATED_AXIS)),
                       **extra})
        result["warnings"] = [*result["warnings"], *warnings]
        result["notes"] = [*result["notes"], *notes]
    with progress.task(f"writing {out.path}"), out.writing() as folder:
        if update is not None:
            from ..measured.update import write_updated_axis

            write_updated_axis(axis, update, folder / UPDATED_AXIS,
                               source=", ".join(f.name for f in files))
        if names:
            save_figure(fit.plot_fit(), folder / FIGURES[0])
            save_figure(fit.plot_stabilisation(), folder / FIGURES[1])
            if update is not None:
                save_figure(update.plot(), folder / UPDATE_FIGURE)
        write_results(folder, result)
    for text in (*fit.warnings, *(update.warnings if update is not None else ())):
        print(f"WARNING: {text}", file=sys.stderr)
    if args.json:
        print_json(result)
        return 0
    lo, hi = fit.band
    how = "chosen by the rule" if fit.chosen_by == "rule" else "nearest to --modes-hz"
    print(f"{len(fit.modes)} mode(s) from {len(frfs)} {fit.frfs[0].quantity} FRF(s), "
          f"{lo * HZ_PER_RAD_S:g}-{hi * HZ_PER_RAD_S:g} Hz, model orders up to "
          f"{2 * fit.max_order} ({how}):")
    print("  mode    f [Hz]   zeta [%]   residue (first FRF) [m/(N s)]   stable orders")
    for k, m in enumerate(fit.modes, start=1):
        r = m.residues[0]
        print(f"  {k:4d} {m.frequency * HZ_PER_RAD_S:9.3f}  {100 * m.damping_ratio:8.3f}   "
              f"{r.real:+.4e} {r.imag:+.4e}j   {m.stable_orders:5d}")
    print(f"  FRF error (relative RMS over the band): {100 * fit.frf_error:.2f} %")
    for note in fit.defaults:
        print(f"  default taken: {note}")
    for note in fit.notes:
        print(f"  note: {note}")
    if update is not None:
        _print_update(update, axis, out.file(UPDATED_AXIS))
    print(f"  not done: {NOT_DONE}")
    print(f"  wrote {out.path}")
    return 0


def _axis_and_contact(args):
    """The axis, its stiction contact (the pads stuck) and the measured DOF; clear errors."""
    from ..analysis import axis_contact
    from ..axis import load_axis
    from ..structure.model import UnknownDofError
    from ._common import CliError, require_section

    axis = load_axis(args.axis)
    require_section(axis, "friction", "[friction]", "servotune identify --axis",
                    ": the pads, stuck during the test, sit on its stiction contact")
    dof = args.dof or "wp.x"
    try:
        axis.structure.index(dof)
    except UnknownDofError as exc:
        raise CliError(f"--dof {dof}: {exc}") from None
    return axis, axis_contact(axis, "stiction"), dof


def _print_update(update, axis, folder) -> None:
    """The updating's lines of the text output."""
    from ..units import HZ_PER_RAD_S

    print(f"  updating {axis.name} to the {update.quantity} at {update.dof} (drive off, pads: "
          f"{update.contact.note}):")
    print("    identified          model before        model after     | stored mode  "
          "f [Hz] before -> after   zeta [%] before -> after   share")
    for p in update.parameters:
        d = p.to_dict()
        i, b, a = d["identified"], d["model_before"], d["model_after"]
        print(f"    {i['frequency_hz']:8.3f} Hz {100 * i['damping_ratio']:5.2f} %  "
              f"{b['frequency_hz']:8.3f} Hz {100 * b['damping_ratio']:5.2f} %  "
              f"{a['frequency_hz']:8.3f} Hz {100 * a['damping_ratio']:5.2f} % | {p.mode + 1:5d}  "
              f"{p.frequency_before * HZ_PER_RAD_S:9.3f} -> {p.frequency_after * HZ_PER_RAD_S:9.3f}"
              f"   {100 * p.damping_before:7.3f} -> {100 * p.damping_after:7.3f}    "
              f"{p.match.share:5.2f}")
    print(f"  FRF error (relative RMS over the band): before {100 * update.frf_error_before:.2f} "
          f"%, after {100 * update.frf_error_after:.2f} %")
    for note in update.notes:
        print(f"  note: {note}")
    print(f"  updated axis: {folder} (every command takes it; {axis.path} is unchanged)")
