"""From an axis description to the models the simulation needs (glue over ``[drive]`` and
``[friction]`` of ``axis.toml``).

:func:`axis_setup` takes an :class:`servotune.axis.Axis` (or any object with a ``structure``
ModalModel and ``friction`` and ``drive`` mappings as read from ``axis.toml``) and returns the
structure, the :class:`~servotune.drive.Drive`, the pad DOFs, the axis-total LuGre parameters
and the viscous-only damping of the "vd" model. The table format is the lead's draft
(``notes/axis_format.md``); every error names the key and how to fix it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from ..drive import Drive, Motor, PIController, kv_from_m_per_min_per_mm
from ..friction.lugre import LuGreParameters
from ..structure.model import ModalModel

__all__ = ["AxisSetup", "axis_setup", "drive_from_table", "lugre_from_table"]


@dataclass(frozen=True, eq=False)
class AxisSetup:
    """What a simulation of an axis description needs (SI)."""

    name: str
    structure: ModalModel
    drive: Drive
    pads: tuple[str, ...]
    lugre: LuGreParameters
    viscous: float


def _need(table: Mapping, key: str, where: str):
    if key not in table:
        raise ValueError(f"axis description: {where} {key} is missing; add it (SI units)")
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"axis description: {where} {key} must be a number, got {value!r}")
    return float(value)


def drive_from_table(table: Mapping) -> Drive:
    """The :class:`Drive` of a ``[drive]`` table (``[drive.motor]``, ``[drive.transmission]``,
    ``[drive.current_loop]``, ``[drive.velocity_loop]``, ``[drive.position_loop]``).

    Examples
    --------
    >>> d = drive_from_table({
    ...     "encoder": "linear",
    ...     "motor": {"rotor": "motor.rotor", "stator": "motor.stator", "torque_constant": 1.5,
    ...               "back_emf_constant": 1.5, "resistance": 0.25, "inductance": 4e-3},
    ...     "transmission": {"ratio": 1.591549e-3},
    ...     "current_loop": {"kp": 20.0, "ti": 16e-3},
    ...     "velocity_loop": {"kp": 5.7, "ti": 25e-3},
    ...     "position_loop": {"kv_m_per_min_per_mm": 1.0}})
    >>> round(d.kv, 4), d.feedback
    (16.6667, 'linear')
    """
    if not table:
        raise ValueError("axis description: the [drive] table is missing; the simulation needs "
                         "the motor, transmission and the three loops")
    motor = table.get("motor", {})
    m = Motor(torque_constant=_need(motor, "torque_constant", "[drive.motor]"),
              back_emf_constant=_need(motor, "back_emf_constant", "[drive.motor]"),
              resistance=_need(motor, "resistance", "[drive.motor]"),
              inductance=_need(motor, "inductance", "[drive.motor]"),
              rotor=str(motor.get("rotor", "motor.rotor")),
              stator=motor.get("stator", "motor.stator"))
    ratio = _need(table.get("transmission", {}), "ratio", "[drive.transmission]")
    cur = table.get("current_loop", {})
    vel = table.get("velocity_loop", {})
    pos = table.get("position_loop", {})
    if "kv" in pos:
        kv = _need(pos, "kv", "[drive.position_loop]")
    else:
        kv = kv_from_m_per_min_per_mm(_need(pos, "kv_m_per_min_per_mm", "[drive.position_loop]"))
    encoder = table.get("encoder", "linear")
    if encoder not in ("linear", "motor"):
        raise ValueError(f"axis description: [drive] encoder must be 'linear' or 'motor', got "
                         f"{encoder!r}")
    return Drive(motor=m, ratio=ratio,
                 current_loop=PIController(_need(cur, "kp", "[drive.current_loop]"),
                                           float(cur.get("ti", math.inf))),
                 velocity_loop=PIController(_need(vel, "kp", "[drive.velocity_loop]"),
                                            float(vel.get("ti", math.inf))),
                 kv=kv, feedback=encoder, encoder=str(table.get("encoder_dof", "encoder.x")),
                 velocity_feedforward=float(table.get("velocity_feedforward", 1.0)))


def lugre_from_table(table: Mapping) -> LuGreParameters:
    """The axis-total LuGre parameters of ``[friction] lugre`` (a name or an inline table)."""
    spec = table.get("lugre")
    if spec is None:
        raise ValueError("axis description: [friction] lugre is missing; give a named set "
                         f"({', '.join(LuGreParameters.names())}) or a table "
                         "{fc=, fs=, vs=, delta=, sigma0=, sigma1=, sigma2=}")
    if isinstance(spec, str):
        return LuGreParameters.named(spec)
    if isinstance(spec, Mapping):
        names = ("fc", "fs", "vs", "delta", "sigma0", "sigma1", "sigma2")
        unknown = sorted(set(spec) - set(names))
        if unknown:
            raise ValueError(f"axis description: [friction] lugre has unknown keys {unknown}; "
                             f"use {list(names)}")
        return LuGreParameters(**{k: _need(spec, k, "[friction] lugre") for k in names})
    raise ValueError(f"axis description: [friction] lugre must be a name or a table, got {spec!r}")


def axis_setup(axis) -> AxisSetup:
    """Structure, drive, pads, LuGre parameters and viscous-only damping of an axis.

    The "vd" damping is ``[friction] viscous`` [N s/m] when given, else the LuGre sigma2 (the
    paper's viscous-only model keeps the viscous part of the identified friction).
    The drive gets full velocity feed-forward unless ``[drive] velocity_feedforward`` says
    otherwise (the moving trials impose the speed through the reference).
    """
    structure = getattr(axis, "structure", None)
    if not isinstance(structure, ModalModel):
        raise ValueError("axis_setup() needs an axis with a ModalModel structure "
                         "(servotune.axis.load_axis)")
    friction = getattr(axis, "friction", {}) or {}
    pads = tuple(friction.get("pads", ()))
    if not pads:
        raise ValueError("axis description: [friction] pads is missing; list the pad DOFs, e.g. "
                         'pads = ["pad1.x", "pad2.x"]')
    structure.index(list(pads))
    lugre = lugre_from_table(friction)
    viscous = float(friction.get("viscous", lugre.sigma2))
    if not (math.isfinite(viscous) and viscous >= 0):
        raise ValueError(f"axis description: [friction] viscous must be >= 0 N s/m, got {viscous}")
    drive = drive_from_table(getattr(axis, "drive", {}) or {})
    return AxisSetup(name=str(getattr(axis, "name", "axis")), structure=structure, drive=drive,
                     pads=pads, lugre=lugre, viscous=viscous)
