"""``servotune verify RESULT.json``: nonlinear checks of a tuned design against linear predictions.

RESULT.json holds at least ``{"axis": "path/to/axis", "design": {"c": ..., "kv": ..., "kp": ...,
"ti": ...}}`` (SI; a relative axis path is taken from the file's folder, then from the current
folder). The design is simulated with LuGre friction at the pads (sigma2 = C) under sine sweeps
standing still, and each sweep's resonance and peak are compared with the closed loop with
locked pads, with viscous pads C and with the LuGre describing function at the simulated pad
amplitude.
"""

from __future__ import annotations

import json
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from ..simulate.verify import DEFAULT_FORCES, design_setup, verify_design
from ._common import add_output_options, print_json
from .table3 import load_setup

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


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "verify", help="nonlinear (LuGre) checks of a tuned design vs the linear predictions",
        description="Simulate a tuned design (RESULT.json with 'axis' and 'design' {c, kv, kp, "
                    "ti}) with LuGre guide-way friction (sigma2 = C) under sine sweeps standing "
                    "still, and compare resonance and peak oscillation per force with the "
                    "closed loop with locked pads, viscous pads C, and the describing function "
                    "at the simulated pad amplitude.")
    p.add_argument("result", help="tuning results file (JSON)")
    p.add_argument("--force-pp", type=float, action="append", default=None, metavar="N",
                   help=f"sweep force peak to peak [N], repeatable (default {DEFAULT_FORCES})")
    p.add_argument("--duration", type=float, default=20.0, help="sweep time [s] (default 20)")
    p.add_argument("--f-start-hz", type=float, default=10.0)
    p.add_argument("--f-end-hz", type=float, default=100.0)
    p.add_argument("--workers", type=int, default=1, help="parallel processes (default 1)")
    add_output_options(p, default_out=None)
    p.set_defaults(func=run)


def run(args) -> int:
    axis, design = read_result(args.result)
    forces = tuple(args.force_pp) if args.force_pp else DEFAULT_FORCES
    if any(not (f > 0 and math.isfinite(f)) for f in forces):
        raise ValueError("--force-pp must be positive forces [N]")
    if args.workers < 1:
        raise ValueError("--workers must be >= 1")
    setup = design_setup(load_setup(axis), **design)
    kwargs = dict(forces=forces, f_start_hz=args.f_start_hz, f_end_hz=args.f_end_hz,
                  duration=args.duration)
    if args.workers > 1:
        with ProcessPoolExecutor(max_workers=args.workers) as pool:
            result = verify_design(setup, executor=pool, **kwargs)
    else:
        result = verify_design(setup, **kwargs)
    result["axis"] = str(axis)
    if args.json:
        print_json(result)
        return 0
    d = result["design"]
    print(f"design on {axis}: C = {d['c']:.4g} N s/m, Kv = {d['kv']:.4g} 1/s, "
          f"Kp = {d['kp']:.4g} N m s/rad, Ti = {d['ti']:.4g} s")
    for name, pred in result["linear"].items():
        print(f"  linear, pads {name:8}: resonance {pred['resonance_hz']:6.1f} Hz, peak "
              f"{pred['peak_m_per_n']:.3g} m/N")
    for row in result["sweeps"]:
        dfp = row["describing"]
        print(f"  LuGre sweep {row['force_pp_n']:g} N p-p: resonance {row['resonance_hz']:.1f} Hz"
              f", peak {row['peak_m_per_n']:.3g} m/N, pad amplitude {row['pad_amplitude_m']:.3g} m"
              f"; describing function there: {dfp['resonance_hz']:.1f} Hz, "
              f"{dfp['peak_m_per_n']:.3g} m/N")
        verdict = ", ".join(f"{n} {'agrees' if row[f'agrees_{n}'] else 'differs'}"
                            for n in ("locked", "presliding", "viscous", "describing"))
        print(f"    {verdict} (within {result['freq_tol']:.0%} in frequency and "
              f"{result['peak_tol']:.0%} in peak)")
    sys.stdout.flush()
    return 0
