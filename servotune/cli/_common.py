"""Helpers shared by the subcommands: output options and printing."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

__all__ = ["add_output_options", "print_json", "to_jsonable"]


def add_output_options(parser, default_out: str | None = "out") -> None:
    """``--json``, ``--out DIR`` and ``--force`` as every subcommand spells them."""
    parser.add_argument("--json", action="store_true",
                        help="print one JSON object of the results (SI values)")
    if default_out is not None:
        parser.add_argument("--out", type=Path, default=Path(default_out),
                            help=f"folder for figures and results (default: {default_out})")
        parser.add_argument("--force", action="store_true",
                            help="overwrite existing output files")


def to_jsonable(obj):
    """Numpy scalars and arrays to plain Python; non-finite floats as None (null)."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None  # JSON has no inf/nan: null (e.g. no gain crossover, an unstable loop)
    if isinstance(obj, Path):
        return str(obj)
    return obj


def print_json(obj) -> None:
    """Print one JSON object on standard output."""
    json.dump(to_jsonable(obj), sys.stdout, indent=2)
    sys.stdout.write("\n")


CONTACT_KINDS = ("locked", "stiction", "viscous", "equivalent", "sliding", "free")


def add_contact_options(parser, default: str = "viscous") -> None:
    """``--contact`` and its parameters, as the analysis subcommands spell them."""
    parser.add_argument("--contact", choices=CONTACT_KINDS, default=default,
                        help="guide-way model: locked pads, stiction (LuGre presliding spring "
                             "and damper), viscous (the axis' viscous-only damping, or --c), "
                             "equivalent (LuGre describing function at --amplitude and "
                             "--frequency-hz), sliding (LuGre linearised at --speed), free "
                             f"(default {default})")
    parser.add_argument("--c", type=float, default=None,
                        help="viscous guide-way damping C [N s/m] (axis total) for --contact "
                             "viscous")
    parser.add_argument("--amplitude", type=float, default=None,
                        help="vibration amplitude [m] for --contact equivalent")
    parser.add_argument("--frequency-hz", type=float, default=None,
                        help="vibration frequency [Hz] for --contact equivalent (default: the "
                             "locked-pad work-piece resonance is not guessed; give it)")
    parser.add_argument("--speed", type=float, default=None,
                        help="sliding speed [m/s] for --contact sliding")
    parser.add_argument("--continuous", action="store_true",
                        help="the drive in continuous time, as the paper models it (no "
                             "sampling, no delays) instead of the digital drive of "
                             "[drive.sampling]")


def axis_from_args(axis, args):
    """The axis with the drive the options ask for (``--continuous``: the paper's model)."""
    return axis.with_continuous_drive() if getattr(args, "continuous", False) else axis


def contact_from_args(axis, args):
    """The contact model the options ask for."""
    from ..analysis import axis_contact

    return axis_contact(axis, args.contact, amplitude=args.amplitude,
                        frequency_hz=args.frequency_hz, speed=args.speed, c=args.c)
