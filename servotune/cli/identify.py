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

``--kind speed-plant`` reads the drive's measuring function instead, motor speed over motor
torque [rad/(s N m)] (:mod:`servotune.measured.speed_plant`): with ``--axis`` it is compared
with the axis' speed plant (guide ways in presliding, the ``stiction`` contact) and the
velocity loop is closed on the measurement by the axis' own drive (its PI, current loop,
sampling, delays and speed measurement), non-parametrically, as auto-tuners do: the margins,
Ms and bandwidth of that loop beside the model's.

``--kind closed-loop`` reads the work-piece compliance at ``--dof`` measured with the axis
under position control by its own drive and the guide ways standing (the pads on the
``stiction`` contact), the quantity ``servotune compliance AXIS --contact stiction`` computes
(:mod:`servotune.measured.closed_loop`): its modes are identified as for ``structure`` (they
are the closed loop's poles, not the structure's modes), and with ``--axis`` the same stored
modes' frequencies and damping ratios are fitted so that the model's closed-loop compliance
(sampled-data for a digital drive, or the drive in continuous time with ``--continuous``)
matches it.
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
SPEED_PLANT_FIGURE = "speed_plant.png"
UPDATED_AXIS = "updated_axis"
KINDS = ("structure", "speed-plant", "closed-loop")
NOT_DONE = ("physical updating parameters (port stiffnesses, masses, the pads' presliding "
            "stiffness: --kind structure and closed-loop correct the stored modes' frequencies "
            "and damping ratios only) and FRFs from time data (H1/H2) are not in this version")
_FREQUENCY = number(0.0, 1e6, low_open=True, example=120, unit="Hz")
_ORDER = number(5, 200, integer=True, example=40)
QUANTITIES = ("receptance", "mobility", "accelerance", "speed_per_torque")


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
                    "of the axis folder with the updated structure.npz and modal_damping. "
                    "--kind speed-plant reads the drive's measured speed plant (motor speed "
                    "over motor torque, rad/s/N m), compares it with the speed plant of the "
                    "--axis (needed; guide ways in presliding) and closes the velocity loop on "
                    "it with the axis' drive (PI, current loop, sampling, delays, speed by "
                    "backward difference): margins, Ms and bandwidth, measured and model; writes "
                    "speed_plant.png. --kind closed-loop reads the work-piece compliance at "
                    "--dof measured under position control by the axis' drive, guide ways "
                    "standing (what servotune compliance --contact stiction computes): its "
                    "modes as for structure and, with --axis, the same stored modes fitted so "
                    "that the model's closed-loop compliance (sampled-data for a digital "
                    "drive; --continuous for the drive in continuous time) matches it.")
    p.add_argument("files", nargs="+", metavar="FRF_FILE",
                   help="CSV (f_hz with re,im or mag,phase_deg; '# quantity:' and '# units:' "
                        "comment lines) or UFF dataset 58 (.uff, .unv); several FRFs of one "
                        "excitation on the same frequency lines; the first is the one whose "
                        "residues are 'residue' (give the driving point first)")
    p.add_argument("--kind", choices=KINDS, default="structure",
                   help="what was measured: 'structure' (FRFs of the machine structure, e.g. "
                        "hammer tests at the work piece, drive off, pads stuck); 'speed-plant' "
                        "(the drive's measuring function: motor speed over motor torque, "
                        "rad/s/N m; needs --axis); 'closed-loop' (the work-piece compliance "
                        "under position control by the axis' drive, guide ways standing)")
    p.add_argument("--axis", default=None, metavar="AXIS",
                   help="axis folder to update to the measurement (the folder itself is never "
                        "changed: the updated copy goes to "
                        "DIR/identify_<first file's name>/updated_axis)")
    p.add_argument("--dof", default=None, metavar="DOF",
                   help="the DOF of the measurement, force and response (default wp.x; only "
                        "with --axis)")
    p.add_argument("--quantity", choices=QUANTITIES, default=None,
                   help="the quantity of files that do not state it (default receptance; "
                        "speed_per_torque with --kind speed-plant)")
    p.add_argument("--units", default=None, metavar="UNIT",
                   help="units of CSV files that do not state them: m/N, mm/N, um/N, nm/N; "
                        "m/s/N, mm/s/N; m/s^2/N, g/N; rad/s/N m, rpm/N m (default the SI "
                        "unit)")
    p.add_argument("--band-hz", type=_FREQUENCY, nargs=2, metavar=("LO", "HI"), default=None,
                   help="the band to fit [Hz] (default the whole measurement above 0 Hz)")
    p.add_argument("--max-order", type=_ORDER, default=40, metavar="N",
                   help=f"number of LSCF model orders (denominator degrees 2..2N), "
                        f"{_ORDER.accepted} (default 40)")
    p.add_argument("--modes-hz", type=_FREQUENCY, nargs="+", metavar="F", default=None,
                   help="take the poles nearest to these natural frequencies [Hz] instead of "
                        "the automatic rule")
    p.add_argument("--continuous", action="store_true",
                   help="with --kind speed-plant or closed-loop: the axis' drive in "
                        "continuous time, as the paper models it (no sampling, no delays), "
                        "instead of the digital drive of [drive.sampling]")
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
    if args.kind == "speed-plant":
        return _run_speed_plant(args)
    if args.continuous and args.kind == "structure":
        raise UsageError("--continuous: the drive's model serves --kind speed-plant and "
                         "closed-loop; a structure measurement has the drive switched off")
    if args.continuous and args.axis is None:
        raise UsageError("--continuous: the drive's model serves the updating of an axis; "
                         "give --axis AXIS too, or drop --continuous")
    if args.quantity == "speed_per_torque":
        raise UsageError("--quantity speed_per_torque is the drive's speed plant: give --kind "
                         "speed-plant")
    if args.dof is not None and args.axis is None:
        raise UsageError(f"--dof {args.dof}: the DOF of the measurement serves the updating of "
                         "an axis; give --axis AXIS too, or drop --dof")
    files = [Path(f) for f in args.files]
    names = [] if args.no_plots else list(FIGURES)
    if args.axis is not None and not args.no_plots:
        names.append(UPDATE_FIGURE)
    written = [*names, UPDATED_AXIS] if args.axis is not None else names
    subject = files[0].stem + (f"+{len(files) - 1}" if len(files) > 1 else "")
    axis = test = None
    if args.axis is not None:
        with progress.task(f"loading {args.axis}"):
            axis, contact, dof = _axis_and_contact(args)
            test = _test_of(args, axis, contact)
    out = RunOutput.for_args(args, "identify", subject, ["results.json", *written])
    with progress.task(f"reading {len(files)} file(s)"):
        from ..measured.ema import identify_modes
        from ..measured.frf import read_frfs

        frfs = read_frfs(files, quantity=args.quantity, units=args.units)
    speed = [f.name for f in frfs if f.quantity == "speed_per_torque"]
    if speed:
        raise UsageError(f"{speed[0]} is a speed per torque, the drive's speed plant: give "
                         "--kind speed-plant")
    band = None if args.band_hz is None else tuple(f * RAD_S_PER_HZ for f in args.band_hz)
    wanted = None if args.modes_hz is None else [f * RAD_S_PER_HZ for f in args.modes_hz]
    with progress.task(f"identifying modes of {len(frfs)} FRF(s)"):
        fit = identify_modes(frfs, band=band, max_order=args.max_order, frequencies=wanted)
    update = None
    if axis is not None:
        from ..measured.update import update_model

        if test is not None:
            import dataclasses

            test = dataclasses.replace(test, quantity=fit.frfs[0].quantity)
        with progress.task(f"updating {axis.name} to the measurement at {dof}"):
            update = update_model(axis.structure, fit, contact, axis.pads, dof, test=test)
    result = {"command": "identify", "kind": args.kind, "files": [str(f) for f in files],
              **fit.to_dict(), "folder": str(out.path),
              "figures": [str(out.file(n)) for n in names], "not_done": NOT_DONE}
    if update is not None:
        extra = update.to_dict()
        notes, warnings = extra.pop("notes"), extra.pop("warnings")
        result.update({"axis": str(args.axis), "updated_axis": str(out.file(UPDATED_AXIS)),
                       **extra})
        if test is not None:
            result["drive"] = test.drive_name
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
    """The axis (its drive as ``--continuous`` asks), its stiction contact (the pads stuck, or
    standing under position control) and the measured DOF; clear errors."""
    from ..analysis import axis_contact
    from ..axis import load_axis
    from ..structure.model import UnknownDofError
    from ._common import CliError, axis_from_args, require_section

    axis = axis_from_args(load_axis(args.axis), args)
    if args.kind == "closed-loop":
        require_section(axis, "drive", "[drive]", "servotune identify --kind closed-loop",
                        ": its drive held the axis under position control during the "
                        "measurement")
    require_section(axis, "friction", "[friction]", "servotune identify --axis",
                    ": the pads, stuck during the test, sit on its stiction contact")
    dof = args.dof or "wp.x"
    try:
        axis.structure.index(dof)
    except UnknownDofError as exc:
        raise CliError(f"--dof {dof}: {exc}") from None
    return axis, axis_contact(axis, "stiction"), dof


def _test_of(args, axis, contact):
    """The closed-loop test configuration of ``--kind closed-loop``, its model loop stable
    (None for structure); clear errors."""
    if args.kind != "closed-loop":
        return None
    from ..measured.closed_loop import ClosedLoopTest
    from ._common import CliError

    test = ClosedLoopTest(axis.drive, contact, axis.pads)
    try:
        test.check(axis.structure)
    except ValueError as exc:
        hint = ("; the drive in continuous time (--continuous) may be stable, or tune the "
                "drive first" if test.sampled else "; tune the drive first")
        raise CliError(f"--kind closed-loop --axis {args.axis}: {exc}{hint}") from None
    return test


def _print_update(update, axis, folder) -> None:
    """The updating's lines of the text output."""
    from ..units import HZ_PER_RAD_S

    print(f"  updating {axis.name} to the {update.quantity} at {update.dof} "
          f"({update.configuration}):")
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


def _run_speed_plant(args) -> int:
    """``servotune identify --kind speed-plant``: the measured speed plant against the axis',
    the velocity loop closed on each."""
    from .. import progress
    from ..units import HZ_PER_RAD_S, RAD_S_PER_HZ
    from ._common import axis_from_args

    flag = "--kind speed-plant"
    if args.axis is None:
        raise UsageError(f"{flag}: the velocity loop is closed on the measurement by an axis' "
                         "drive, and the measurement compared with its model: give --axis AXIS")
    for given, name in ((args.dof, "--dof"), (args.modes_hz, "--modes-hz")):
        if given is not None:
            raise UsageError(f"{name}: not with {flag} (the speed plant's ports are the "
                             "motor's: torque in, speed out; no modes are identified)")
    if args.quantity not in (None, "speed_per_torque"):
        raise UsageError(f"--quantity {args.quantity}: {flag} reads motor speed over motor "
                         "torque (speed_per_torque)")
    files = [Path(f) for f in args.files]
    if len(files) > 1:
        raise UsageError(f"{flag}: give one file, the measured speed plant (got {len(files)})")
    names = [] if args.no_plots else [SPEED_PLANT_FIGURE]
    with progress.task(f"loading {args.axis}"):
        from ..analysis import axis_contact
        from ..axis import load_axis
        from ..measured.speed_plant import SPEED_PLANT_CONTACT
        from ._common import require_section

        axis = axis_from_args(load_axis(args.axis), args)
        require_section(axis, "drive", "[drive]", f"servotune identify {flag}",
                        ": its controllers close the velocity loop on the measurement")
        require_section(axis, "friction", "[friction]", f"servotune identify {flag}",
                        ": the pads, in presliding during the measurement, sit on its "
                        "stiction contact")
        contact = axis_contact(axis, SPEED_PLANT_CONTACT)
    out = RunOutput.for_args(args, "identify", files[0].stem, ["results.json", *names])
    with progress.task(f"reading {files[0]}"):
        from ..measured.frf import read_frfs

        frfs = read_frfs(files, quantity="speed_per_torque", units=args.units)
    if len(frfs) > 1:
        raise UsageError(f"{files[0]}: holds {len(frfs)} FRFs; {flag} takes one, the measured "
                         "speed plant")
    frf = frfs[0]
    band = None if args.band_hz is None else tuple(f * RAD_S_PER_HZ for f in args.band_hz)
    with progress.task(f"{axis.name}: velocity loop on the measured speed plant"):
        from ..measured.speed_plant import compare_speed_plant

        try:
            comparison = compare_speed_plant(frf, axis.structure, axis.drive, contact,
                                             axis.pads, band)
        except ValueError as exc:
            from ._common import CliError

            raise CliError(f"{files[0]}: {exc}") from None
    result = {"command": "identify", "kind": args.kind, "files": [str(f) for f in files],
              "frfs": [frf.to_dict()], "axis": str(args.axis), **comparison.to_dict(),
              "folder": str(out.path), "figures": [str(out.file(n)) for n in names],
              "not_done": NOT_DONE}
    result["notes"] = [*frf.defaults, *frf.notes, *result["notes"]]
    with progress.task(f"writing {out.path}"), out.writing() as folder:
        if names:
            from ..measured.figures import plot_speed_plant

            save_figure(plot_speed_plant(comparison, f"{axis.name}: measured speed plant "
                                                     f"{files[0].name}"), folder / names[0])
        write_results(folder, result)
    for text in comparison.warnings:
        print(f"WARNING: {text}", file=sys.stderr)
    if args.json:
        print_json(result)
        return 0
    lo, hi = comparison.band
    print(f"{frf.name}: speed plant (motor speed / motor torque), {frf.omega.size} lines "
          f"{frf.omega[0] * HZ_PER_RAD_S:g}-{frf.omega[-1] * HZ_PER_RAD_S:g} Hz, against "
          f"{axis.name} ({contact.note}):")
    print(f"  FRF error (relative RMS over {lo * HZ_PER_RAD_S:g}-{hi * HZ_PER_RAD_S:g} Hz): "
          f"{100 * comparison.frf_error:.2f} %")
    v = result["velocity_loop"]
    print(f"  velocity loop ({v['drive']} drive, position loop open), closed on:")
    print(f"    {'':15} {'GM [dB]':>8} {'PM [deg]':>9} {'Ms':>6} {'crossover [Hz]':>15} "
          f"{'phase cross. [Hz]':>18} {'bandwidth [Hz]':>15}")
    rows = [("the measurement", v["measured"])]
    if v["model"] is not None:
        rows.append(("the model", v["model"]))
    for label, a in rows:
        gm = "inf" if a["gain_margin_db"] is None else f"{a['gain_margin_db']:.2f}"
        pc = "-" if a["phase_crossover_hz"] is None else f"{a['phase_crossover_hz']:.1f}"
        print(f"    {label:15} {gm:>8} {a['phase_margin_deg']:9.2f} {a['ms']:6.3f} "
              f"{a['crossover_hz']:15.2f} {pc:>18} {a['bandwidth_hz']:15.2f}")
    if v["model"] is None:
        print(f"    the model: {v['model_unstable']}")
    verdict = {None: "not judged (the measurement ends before |L| has fallen)", True:
               "stable (Nyquist criterion: -1 not encircled)", False:
               f"UNSTABLE ({v['unstable_poles']} unstable closed-loop poles, Nyquist criterion)"}
    print(f"  the loop on the measurement: {verdict[v['stable']]}")
    for note in result["notes"]:
        print(f"  note: {note}")
    for line in comparison.warnings:
        print(f"  WARNING: {line}")
    print(f"  not done: {NOT_DONE}")
    print(f"  wrote {out.path}")
    return 0
