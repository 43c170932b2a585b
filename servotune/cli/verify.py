"""``servotune verify RESULT.json``: does the nonlinear axis do what the design claims?

RESULT.json is the ``results.json`` that ``servotune tune`` writes (``out/tune_<axis>/``); it
must hold ``{"axis": "path/to/axis", "design": {"c": ..., "kv": ..., "kp": ..., "ti": ...}}``
(SI: C [N s/m], Kv [1/s], Kp [N m s/rad], Ti [s]; a relative axis path is taken from the
file's folder, then from the current folder). The design is checked on the axis' linear regime
models (dense grids, python-control) and simulated with LuGre friction at the pads (sigma2 =
C): sine sweeps standing still and while feeding, at the process force and a smaller and a
larger one unless ``--force-pp`` says otherwise, over the band of the axis unless
``--f-start-hz``/``--f-end-hz`` say otherwise, at the axis' feed speeds unless ``--speed`` says
otherwise (see :mod:`servotune.verdict`). Exit status 0 when verified, 1 when not.
"""

from __future__ import annotations

import difflib
import json
import math
from pathlib import Path

from ._common import (
    CliError,
    RunOutput,
    UsageError,
    add_common_options,
    add_workers_option,
    default_workers,
    friction_law_of,
    number,
    print_json,
    save_figure,
    write_results,
)

__all__ = ["add_parser", "run", "read_result", "DESIGN_KEYS"]

#: The design keys of a results file: unit and the largest plausible value (SI), the upper
#: limits of the bounds of axis.toml's [tuning] (a unit slip beyond them is refused).
DESIGN_KEYS = {"c": ("N s/m", 1e12), "kv": ("1/s", 1e4), "kp": ("N m s/rad", 1e7),
               "ti": ("s", 1e3)}
#: The tuned current set-point notch's keys (optional; all three or none).
NOTCH_KEYS = {"notch_frequency": ("rad/s", 1e7), "notch_width": ("-", 10.0),
              "notch_depth": ("-", 1.0)}
#: The tuned current set-point low-pass' key (optional).
LOWPASS_KEYS = {"lowpass_frequency": ("rad/s", 1e7)}
_WANTED = ("the design must hold c [N s/m], kv [1/s], kp [N m s/rad] and ti [s] as numbers, "
           "as servotune tune writes them")
_WHERE = "e.g. out/tune_<axis>/results.json"

# flag ranges: a sweep force up to 1 MN, a feed speed up to 10 m/s (beyond any rapid traverse
# of a machine tool), sweep frequencies up to 100 kHz
FORCE_PP = number(0.0, 1e6, low_open=True, example=300, unit="N")
SPEED = number(0.0, 10.0, low_open=True, example=0.05, unit="m/s")
FREQUENCY = number(0.0, 1e5, low_open=True, example=50, unit="Hz")


def read_result(path) -> tuple[Path, dict, dict | None]:
    """Return the axis folder, the design and the drive parts the tuning kept, of a tuning
    results file.

    Parameters
    ----------
    path : str or os.PathLike
        A ``results.json`` that ``servotune tune`` wrote.

    Returns
    -------
    axis : pathlib.Path
        The axis folder.
    design : dict
        The design: ``c``, ``kv``, ``kp``, ``ti`` [SI] (and the tuned notch's
        ``notch_frequency``, ``notch_width``, ``notch_depth`` when it has one, the tuned
        low-pass' ``lowpass_frequency`` [rad/s] when it has one).
    fixed : dict or None
        ``drive_fixed``: the current loop and set-point filters the design was tuned with
        (:func:`servotune.design.with_drive_fixed`); None when the file has none (the axis'
        own then).

    Raises
    ------
    FileNotFoundError, ValueError
        A missing file, a folder, a file that is not JSON, or one without the axis and the
        whole design (c, kv, kp, ti) as positive numbers; the message names what is wrong.
    """
    path = Path(path)
    if path.is_dir():
        inside = path / "results.json"
        hint = (f": give {inside}" if inside.is_file() else
                f" (an axis folder: run servotune tune {path} first)"
                if (path / "axis.toml").is_file() else f" ({_WHERE})")
        raise CliError(f"{path} is a folder; verify wants the results.json that servotune tune "
                       f"writes{hint}")
    if not path.is_file():
        raise FileNotFoundError(f"{path} does not exist; give the results.json that servotune "
                                f"tune writes ({_WHERE})")
    try:
        data = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path} is not valid JSON: {exc}; give the results.json that "
                         f"servotune tune writes") from None
    if not isinstance(data, dict) or "axis" not in data or "design" not in data:
        raise ValueError(f"{path} needs the keys 'axis' (axis folder) and 'design' "
                         "({'c', 'kv', 'kp', 'ti'}), as servotune tune writes them "
                         f"({_WHERE})")
    design = data["design"]
    if not isinstance(design, dict):
        raise ValueError(f"{path}: 'design' must be an object {{'c', 'kv', 'kp', 'ti'}}, got "
                         f"{design!r}; {_WANTED}")
    values = _design_values(path, design)
    fixed = data.get("drive_fixed")
    if fixed is not None and not isinstance(fixed, dict):
        raise ValueError(f"{path}: 'drive_fixed' must be an object (current_kp, current_ti, "
                         f"lowpass, notches), got {fixed!r}")
    return _axis_folder(path, data["axis"]), values, fixed


def _design_values(path: Path, design: dict) -> dict:
    """The four design values, each checked, with a message naming the key."""
    # tune writes a value that is not finite as null with '<key>_reason' beside it
    keys = {**DESIGN_KEYS, **NOTCH_KEYS, **LOWPASS_KEYS}
    reasons = {f"{k}_reason" for k in keys}
    unknown = [k for k in design if k not in keys and k not in reasons]
    if unknown:
        key = unknown[0]
        close = difflib.get_close_matches(str(key), list(keys), n=1)
        guess = f" (did you mean {close[0]!r}?)" if close else ""
        raise ValueError(f"{path}: design has an unknown key {key!r}{guess}; {_WANTED}")
    missing = [k for k in DESIGN_KEYS if k not in design]
    if missing:
        raise ValueError(f"{path}: design has no {', '.join(repr(k) for k in missing)}; "
                         f"{_WANTED}")
    notch = [k for k in NOTCH_KEYS if design.get(k) is not None]
    if notch and len(notch) != len(NOTCH_KEYS):
        raise ValueError(f"{path}: design has {', '.join(notch)} but not all of "
                         f"{', '.join(NOTCH_KEYS)}: the tuned notch needs its frequency, width "
                         "and depth")
    values = {}
    for key, (unit, high) in keys.items():
        if (key in NOTCH_KEYS and not notch) or (key in LOWPASS_KEYS
                                                 and design.get(key) is None):
            continue
        value = design[key]
        where = f"{path}: design.{key}"
        if (key == "ti" and value is None
                and str(design.get("ti_reason", "")).startswith("+infinity")):
            value = math.inf  # no integral action, as tune writes it
        if value is None or isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{where} is {json.dumps(value)}; give a number in {unit} "
                             f"({_WANTED})")
        if key == "ti" and value == math.inf:
            values[key] = value
            continue
        if not math.isfinite(value) or value <= 0:
            raise ValueError(f"{where} is {value!r}; give a finite number > 0 in {unit}")
        if value > high:
            raise ValueError(f"{where} is {value!r}, above the plausible {high:g} {unit}; "
                             "check the value and its unit (SI)")
        values[key] = float(value)
    return values


def _axis_folder(path: Path, axis) -> Path:
    """The axis folder a results file names: relative to the file's folder, else to the
    current folder."""
    if not isinstance(axis, str) or not axis.strip():
        raise ValueError(f"{path}: 'axis' must be the path of the axis folder (a string), got "
                         f"{json.dumps(axis)}")
    axis = Path(axis)
    if axis.is_absolute():
        candidates = [axis]
    else:
        candidates = [path.parent / axis, axis]
    for candidate in candidates:
        if candidate.exists():
            return candidate
    looked = " or ".join(str(c) for c in dict.fromkeys(candidates))
    raise FileNotFoundError(f"{path}: the axis folder {str(axis)!r} does not exist (looked for "
                            f"{looked}); give the axis folder servotune tune was run on")


def add_parser(subparsers) -> None:
    """Add the ``servotune verify`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "verify", help="does the nonlinear axis (LuGre) do what a tuned design claims?",
        description="Check a tuned design (the results.json of servotune tune, e.g. "
                    "out/tune_<axis>/results.json: 'axis' and 'design' {c, kv, kp, ti}) on the "
                    "axis' linear regime models and simulate it with LuGre friction at the pads "
                    "(sigma2 = C): sine sweeps standing still and while feeding, at the process "
                    "force and a smaller and a larger one, over the band of the axis; the "
                    "verdict per regime. Exit status 0 verified, 1 not verified.")
    p.add_argument("result", help="the results.json of servotune tune "
                                  "(e.g. out/tune_<axis>/results.json)")
    p.add_argument("--force-pp", type=FORCE_PP, action="append", default=None,
                   metavar="N", help=f"sweep force peak to peak [N], {FORCE_PP.accepted}, "
                                     "repeatable (default: the process force and a smaller "
                                     "and a larger one)")
    p.add_argument("--speed", type=SPEED, action="append", default=None,
                   metavar="V", help=f"feed speed [m/s] of a feeding regime, "
                                     f"{SPEED.accepted}, repeatable (default: the axis' feed "
                                     "speeds)")
    p.add_argument("--f-start-hz", type=FREQUENCY, default=None, metavar="F",
                   help=f"sweep start [Hz], {FREQUENCY.accepted}, below --f-end-hz (default: "
                        "from the axis' band and modes)")
    p.add_argument("--f-end-hz", type=FREQUENCY, default=None, metavar="F",
                   help=f"sweep end [Hz], {FREQUENCY.accepted} (default: from the axis' band "
                        "and modes)")
    add_workers_option(p)
    add_common_options(p, plots=True)
    p.set_defaults(func=run)


def _band(args):
    """The sweep band of the flags (None: the axis'), checked before any work."""
    if (args.f_start_hz is None) != (args.f_end_hz is None):
        raise UsageError("give both --f-start-hz and --f-end-hz, or neither (then the band "
                       "comes from the axis)")
    if args.f_start_hz is None:
        return None
    if not args.f_start_hz < args.f_end_hz:
        raise CliError(f"--f-start-hz {args.f_start_hz:g} must be below --f-end-hz "
                       f"{args.f_end_hz:g}")
    return (args.f_start_hz, args.f_end_hz)


def run(args) -> int:
    """Run ``servotune verify``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        The exit status: 0 when the design is verified, 1 when it is not. Errors are raised,
        and reported by :func:`servotune.cli.main` with status 1.
    """
    from .. import interrupt, progress

    band = _band(args)
    axis_path, values, fixed = read_result(args.result)
    with progress.task(f"loading {args.result}"):
        from .. import plots
        from ..axis import load_axis
        from ..design import check_design, with_drive_fixed
        from ..tuning import Design
        from ..verdict import nonlinear_verdict

        axis = with_drive_fixed(load_axis(axis_path), fixed, args.result)
    if axis.drive is None or axis.friction is None:
        raise ValueError(f"{axis.file}: the nonlinear verification needs [drive] and [friction]")
    design = Design(**values)
    names = ["results.json"] + ([] if args.no_plots else ["nonlinear.png"])
    output = RunOutput.for_args(args, "verify", axis.name, names)
    with progress.task(f"{axis.name}: linear check"):
        result = check_design(axis, design, feed_speeds=args.speed)
    workers = args.workers or default_workers()
    with progress.task(f"{axis.name}: nonlinear simulations", unit="run") as task, \
            (interrupt.process_pool(workers) if workers > 1 else _NoPool()) as pool:
        verdict = nonlinear_verdict(axis, result, executor=pool, forces=args.force_pp,
                                    band_hz=band, speeds=args.speed, simulate_before=False,
                                    progress=task.report)
    rows = [s.to_dict() for r in verdict.regimes for s in r.simulations]
    out = {"axis": str(axis.path), "axis_name": axis.name, "friction_law": friction_law_of(axis),
           "design": design.to_dict(),
           "verified": verdict.verified, "reasons": list(verdict.reasons),
           "headline": verdict.headline, "coverage": verdict.coverage,
           "coverage_text": verdict.coverage_text,
           "regimes": [r.to_dict() for r in verdict.regimes], "rows": rows,
           "checks": [c.to_dict() for c in result.checks], "folder": str(output.path)}
    with output.writing() as folder:
        if not args.no_plots:
            save_figure(plots.plot_regime_verification(
                verdict.regimes, tolerance=verdict.tolerance,
                title=f"{axis.name}: LuGre time simulation of the design"),
                folder / "nonlinear.png")
        write_results(folder, out)
    status = 0 if verdict.verified else 1
    if args.json:
        print_json(out)
        return status
    d = design
    print(f"design on {axis.name}: C = {d.c:.4g} N s/m"
          + ("" if d.kv is None else f", Kv = {d.kv:.4g} 1/s, Kp = {d.kp:.4g} N m s/rad, "
                                     f"Ti = {d.ti:.4g} s"))
    for r in verdict.regimes:
        print(f"  {r.name}: claim {r.claimed_peak if r.claimed_peak is None else f'{r.claimed_peak:.3g}'} "  # noqa: E501
              f"m/N; {'holds' if r.holds else 'does NOT hold: ' + r.reason}")
        for s in r.simulations:
            if s.kind == "sweep":
                peak = "failed" if s.peak is None else (f"peak {s.peak:.3g} m/N at "
                                                        f"{s.resonance_hz:.1f} Hz")
                print(f"    sweep {s.band_hz[0]:.3g}-{s.band_hz[1]:.3g} Hz at "
                      f"{s.force_pp:.4g} N p-p, {s.speed * 1e3:.3g} mm/s: {peak}")
            else:
                print(f"    fed at {s.speed * 1e3:.3g} mm/s without force: "
                      + ("stick-slip" if s.stick_slip else "slides steadily"))
    print(verdict.headline)
    print(f"  wrote {output.path} ({', '.join(names)})")
    return status


class _NoPool:
    def __enter__(self):
        return None

    def __exit__(self, *exc):
        return False
