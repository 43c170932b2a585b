"""``servotune verify RESULT.json``: does the nonlinear axis do what the design claims?

RESULT.json holds at least ``{"axis": "path/to/axis", "design": {"c": ..., "kv": ..., "kp": ...,
"ti": ...}}`` (SI; the file ``servotune tune`` writes; a relative axis path is taken from the
file's folder, then from the current folder). The design is checked on the axis' linear regime
models (dense grids, python-control) and simulated with LuGre friction at the pads (sigma2 =
C): sine sweeps standing still and while feeding, at the process force and a smaller and a
larger one unless ``--force-pp`` says otherwise, over the band of the axis unless
``--f-start-hz``/``--f-end-hz`` say otherwise, at the axis' feed speeds unless ``--speed`` says
otherwise (see :mod:`servotune.verdict`). Exit status 0 when verified, 1 when not.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from ._common import (
    RunOutput,
    add_common_options,
    add_workers_option,
    default_workers,
    print_json,
    save_figure,
    write_results,
)

__all__ = ["add_parser", "run", "read_result"]


def read_result(path) -> tuple[Path, dict]:
    """The axis folder and the design of a tuning results file."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path} does not exist; give the JSON written by the tuning")
    try:
        data = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path} is not valid JSON: {exc}") from None
    if not isinstance(data, dict) or "axis" not in data or "design" not in data:
        raise ValueError(f"{path} needs the keys 'axis' (axis folder) and 'design' "
                         "({'c', 'kv', 'kp', 'ti'})")
    design = data["design"]
    if not isinstance(design, dict) or "c" not in design:
        raise ValueError(f"{path}: 'design' must be an object with at least 'c' [N s/m]")
    values = {}
    for key in ("c", "kv", "kp", "ti"):
        value = design.get(key)
        if value is not None:
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not (
                    value > 0 and (math.isfinite(value) or key == "ti")):
                raise ValueError(f"{path}: design.{key} must be a positive number, got {value!r}")
            value = float(value)
        values[key] = value
    axis = Path(data["axis"])
    if not axis.is_absolute() and (path.parent / axis).exists():
        axis = path.parent / axis
    return axis, values


def _positive(name):
    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"{name} takes a positive number, got {text!r}") from None
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} takes a positive number, got {text!r}")
        return value
    return parse


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "verify", help="does the nonlinear axis (LuGre) do what a tuned design claims?",
        description="Check a tuned design (RESULT.json of servotune tune: 'axis' and 'design' "
                    "{c, kv, kp, ti}) on the axis' linear regime models and simulate it with "
                    "LuGre friction at the pads (sigma2 = C): sine sweeps standing still and "
                    "while feeding, at the process force and a smaller and a larger one, over "
                    "the band of the axis; the verdict per regime. Exit status 0 verified, "
                    "1 not verified.")
    p.add_argument("result", help="tuning results file (JSON)")
    p.add_argument("--force-pp", type=_positive("--force-pp"), action="append", default=None,
                   metavar="N", help="sweep force peak to peak [N], repeatable (default: the "
                                     "process force and a smaller and a larger one)")
    p.add_argument("--speed", type=_positive("--speed"), action="append", default=None,
                   metavar="V", help="feed speed [m/s] of a feeding regime, repeatable "
                                     "(default: the axis' feed speeds)")
    p.add_argument("--f-start-hz", type=_positive("--f-start-hz"), default=None,
                   help="sweep start [Hz] (default: from the axis' band and modes)")
    p.add_argument("--f-end-hz", type=_positive("--f-end-hz"), default=None,
                   help="sweep end [Hz] (default: from the axis' band and modes)")
    add_workers_option(p)
    add_common_options(p, plots=True)
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import interrupt, progress

    with progress.task(f"loading {args.result}"):
        from .. import plots
        from ..axis import load_axis
        from ..design import check_design
        from ..tuning import Design
        from ..verdict import nonlinear_verdict

    axis_path, values = read_result(args.result)
    band = None
    if (args.f_start_hz is None) != (args.f_end_hz is None):
        raise ValueError("give both --f-start-hz and --f-end-hz, or neither")
    if args.f_start_hz is not None:
        if not args.f_start_hz < args.f_end_hz:
            raise ValueError("--f-start-hz must be below --f-end-hz")
        band = (args.f_start_hz, args.f_end_hz)
    axis = load_axis(axis_path)
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
    out = {"axis": str(axis.path), "axis_name": axis.name, "design": design.to_dict(),
           "verified": verdict.verified, "reasons": list(verdict.reasons),
           "regimes": [r.to_dict() for r in verdict.regimes], "rows": rows,
           "checks": [c.to_dict() for c in result.checks], "folder": str(output.path)}
    with output.writing() as folder:
        if not args.no_plots:
            save_figure(plots.plot_regime_verification(
                verdict.regimes, title=f"{axis.name}: LuGre time simulation of the design"),
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
    print(("VERIFIED" if verdict.verified else "NOT VERIFIED") + (
        "" if verdict.verified else ": " + "; ".join(verdict.reasons)))
    return status


class _NoPool:
    def __enter__(self):
        return None

    def __exit__(self, *exc):
        return False
