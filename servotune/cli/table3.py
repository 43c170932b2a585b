"""``servotune table3 [AXIS]``: the paper's Table 3, simulated, beside the published one.

Runs the 15 sine-sweep trials of Bianchi et al. (2014), sec 5.3 (LuGre standing still and at
30 mm/s, viscous-only standing still; 50 ... 2000 N peak to peak; 10 -> 100 Hz in 20 s; energies
over t = 2 .. 20 s) on an axis description, in parallel over ``--workers`` processes, prints the
simulated table beside the paper's and checks the remarks A-C.
"""

from __future__ import annotations

from pathlib import Path

from ._common import (
    CliError,
    RunOutput,
    add_common_options,
    add_duration_option,
    add_workers_option,
    default_workers,
    number,
    print_json,
    write_results,
)

__all__ = ["add_parser", "run", "default_axis", "load_setup"]

_FREQUENCY = number(0.0, 1e4, low_open=True, example=10, unit="Hz")


def default_axis() -> Path:
    """Return the bundled paper axis, ``models/paper_x_axis`` of the source tree.

    Returns
    -------
    pathlib.Path
        Its folder.
    """
    return Path(__file__).resolve().parents[2] / "models" / "paper_x_axis"


def load_setup(path, continuous: bool = True):
    """Load an axis description and turn it into the set-up of the simulation.

    Parameters
    ----------
    path : str or os.PathLike
        The axis folder (with ``axis.toml``), read by :func:`servotune.axis.load_axis`.
    continuous : bool, optional
        Take the drive in continuous time, as the paper models it (sec 3), instead of the
        digital drive of ``[drive.sampling]`` (default True).

    Returns
    -------
    servotune.simulate.setup.AxisSetup
        The set-up of the nonlinear simulation.

    Raises
    ------
    FileNotFoundError
        When the folder has no ``axis.toml``.
    AxisFormatError
        When the description is not valid (:func:`servotune.axis.load_axis`).
    """
    from ..axis import load_axis
    from ..simulate.setup import axis_setup

    path = Path(path)
    if path.is_file() and path.name == "axis.toml":
        path = path.parent          # the axis named by its description, as load_axis takes it
    if not (path / "axis.toml").is_file():
        raise FileNotFoundError(f"{path} has no axis.toml; give an axis folder such as "
                                f"{default_axis()}")
    axis = load_axis(path)
    return axis_setup(axis.with_continuous_drive() if continuous else axis)


def add_parser(subparsers) -> None:
    """Add the ``servotune table3`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "table3", help="simulate the paper's Table 3 (sine sweeps with LuGre friction)",
        description="The 15 trials of Table 3 (Bianchi et al. 2014, sec 5.3): a force at the "
                    "work piece swept 10 -> 100 Hz in 20 s at 50-2000 N peak to peak, LuGre "
                    "friction standing still and at 30 mm/s, viscous-only pads standing still; "
                    "energies over t = 2..20 s. Prints the result beside the paper's table and "
                    "checks its remarks A-C.")
    p.add_argument("axis", nargs="?", default=None,
                   help="axis folder with axis.toml (default: the bundled models/paper_x_axis)")
    add_workers_option(p)
    add_duration_option(p)
    p.add_argument("--f-start-hz", type=_FREQUENCY, default=10.0,
                   help="sweep start (default 10 Hz)")
    p.add_argument("--f-end-hz", type=_FREQUENCY, default=100.0,
                   help="sweep end (default 100 Hz)")
    add_common_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``servotune table3``.

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
    from .. import interrupt, progress

    if not args.f_start_hz < args.f_end_hz:
        raise CliError(f"--f-start-hz {args.f_start_hz:g} and --f-end-hz {args.f_end_hz:g}: the "
                       "sweep needs start < end")
    with progress.task("loading the axis"):
        from ..simulate import table3 as t3

        setup = load_setup(args.axis if args.axis is not None else default_axis())
    out = RunOutput.for_args(args, "table3", setup.name, ["results.json"])
    settings = t3.SweepSettings(f_start_hz=args.f_start_hz, f_end_hz=args.f_end_hz,
                                duration=args.duration,
                                window=(0.1 * args.duration, args.duration))
    workers = args.workers or default_workers()
    with progress.task(f"Table 3 sine sweeps on {setup.name}", total=len(t3.TRIALS),
                       unit="trials") as task:
        if workers == 1:
            table = t3.table3(setup, None, settings=settings, progress=task.report)
        else:
            with interrupt.process_pool(workers) as pool:
                table = t3.table3(setup, pool, settings=settings, progress=task.report)
    result = table.to_dict()
    result["folder"] = str(out.path)
    with out.writing() as folder:
        result["friction_law"] = "lugre"  # table3 refuses another law
        write_results(folder, result)
    if args.json:
        print_json(result)
        return 0
    paper = {(m, float(f), float(v)): r for m, f, v, *r in t3.PAPER_TABLE3}
    s = settings
    print(f"Table 3 on {table.axis}: force at wp.x swept {s.f_start_hz:g} -> {s.f_end_hz:g} Hz in "
          f"{s.duration:g} s; energies over {s.window[0]:g}..{s.window[1]:g} s "
          "(simulated | paper)")
    print(f"{'#':>2} {'model':>5} {'F pp':>6} {'v':>6} | {'E fric [J]':>21} | {'E motor [J]':>21} |"
          f" {'res [Hz]':>14} | {'osc/F [m/N]':>19}")
    for i, r in enumerate(table.rows, 1):
        ref = paper.get((r["model"], r["force_pp_n"], r["speed_m_per_s"]))
        pe = (f"{ref[0]:>9.4g}", f"{ref[1]:>9.4g}", f"{ref[2]:>6}", f"{ref[3]:>8.3g}") if ref \
            else ("", "", "", "")
        print(f"{i:>2} {r['model']:>5} {r['force_pp_n']:>6g} {r['speed_m_per_s'] * 1e3:>4g}mm"
              f" | {r['energy_friction_j']:>10.4g} {pe[0]:>10} | {r['energy_motor_j']:>10.4g} "
              f"{pe[1]:>10} | {r['resonance_hz']:>6.1f} {pe[2]:>7} | "
              f"{r['wp_oscillation_per_force_m_per_n']:>9.3g} {pe[3]:>9}")
    refs = table.references
    print("linear references in the band: "
          + ", ".join(f"{k} {v['resonance_hz']:.1f} Hz ({v['compliance_m_per_n']:.3g} m/N)"
                      for k, v in refs.items()))
    for key, remark in table.remarks.items():
        print(f"remark {key}: {'holds' if remark['holds'] else 'does NOT hold'} - "
              f"{remark['detail']}")
    print(f"wrote {out.path}")
    return 0
