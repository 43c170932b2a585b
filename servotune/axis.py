"""Axis descriptions: a folder with ``axis.toml`` and the matrix files it names.

:func:`load_axis` reads the description into an :class:`Axis` of validated objects: the
structure as a :class:`~servotune.structure.ModalModel` (``[structure]``), the guide-way friction
as a :class:`~servotune.plant.GuideWayFriction` (``[friction]``), the cascade as a
:class:`~servotune.drive.Drive` (``[drive]``), the milling set-up as :class:`Cutting`
(``[cutting]``) and the :class:`~servotune.requirements.Requirements` (``[requirements]``).
Values are SI unless the key says otherwise (``_hz``, ``_deg``, ``_db``, ``_rpm``,
``kv_m_per_min_per_mm``). The raw tables stay available as read-only mappings under
``Axis.tables``.

``[structure]`` takes either a reduced model in one ``.npz`` file::

    [structure]
    file = "structure.npz"        # arrays mass, stiffness (n x n) and dofs (n names)
    modal_damping = 0.03          # one zeta, or a list with one per mode

or FE matrices in any format of :mod:`servotune.structure.io`, optionally reduced on loading::

    [structure]
    mass = "M.mtx"
    stiffness = "K.mtx"
    dof_map = "dofs.csv"
    reduce = { boundary = ["pad1.x", "wp.x"], n_modes = 30 }   # or f_max_hz = 500.0

Every error names the file, the field and what to do about it.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from .chatter.setup import MillingSetup
from .drive import (
    Drive,
    LowPassFilter,
    Motor,
    NotchFilter,
    PIController,
    kv_from_m_per_min_per_mm,
)
from .friction.identify import fit_steady_state, read_friction_csv
from .friction.lugre import LuGreParameters
from .plant import GuideWayFriction
from .requirements import Requirements
from .structure.io import MatrixFileError, read_structure
from .structure.model import ModalModel, UnknownDofError
from .structure.reduction import craig_bampton

__all__ = ["Axis", "AxisFormatError", "Cutting", "TuningSettings", "load_axis"]

SECTIONS = ("axis", "structure", "friction", "drive", "cutting", "requirements", "tuning")
_STRUCTURE_KEYS = {"file", "mass", "stiffness", "dof_map", "modal_damping", "reduce"}
_REDUCE_KEYS = {"boundary", "n_modes", "f_max_hz"}


class AxisFormatError(ValueError):
    """An axis description that cannot be used; the message names file, field and fix."""


def _frozen(value):
    """Nested TOML data as read-only mappings and tuples."""
    if isinstance(value, dict):
        return MappingProxyType({k: _frozen(v) for k, v in value.items()})
    if isinstance(value, list):
        return tuple(_frozen(v) for v in value)
    return value


@dataclass(frozen=True)
class Cutting:
    """The milling set-up of an axis and the spindle-speed range of interest [rpm]."""

    setup: MillingSetup
    speed_rpm: tuple[float, float] = (1000.0, 12000.0)
    direction: str = "x"


@dataclass(frozen=True)
class TuningSettings:
    """``[tuning]``: which design variables are free, their bounds (SI) and the chatter weight.

    ``bounds`` maps ``c`` [N s/m], ``kv`` [1/s], ``kp`` [N m s/rad] and ``ti`` [s] to
    (low, high); absent ones take :data:`servotune.design.DEFAULT_BOUNDS`.
    """

    free: tuple[str, ...] = ("c", "kv", "kp", "ti")
    bounds: Mapping = field(default_factory=lambda: MappingProxyType({}))
    chatter_weight: float = 0.0


@dataclass(frozen=True, eq=False)
class Axis:
    """A feed axis as described in ``axis.toml``.

    Attributes
    ----------
    name, description : str
    path : Path
        The folder of the description (data files are relative to it).
    structure : ModalModel
        The structural model with named DOFs and its distributed damping.
    friction : GuideWayFriction or None
    drive : Drive or None
    cutting : Cutting or None
    requirements : Requirements
        Defaults when the table is absent.
    tuning : TuningSettings
        ``[tuning]``; defaults when absent.
    tables : Mapping
        The raw TOML tables, read-only.
    """

    name: str
    description: str
    path: Path
    structure: ModalModel
    friction: GuideWayFriction | None = None
    drive: Drive | None = None
    cutting: Cutting | None = None
    requirements: Requirements = field(default_factory=Requirements)
    tuning: TuningSettings = field(default_factory=TuningSettings)
    tables: Mapping = field(default_factory=lambda: MappingProxyType({}))

    @property
    def file(self) -> Path:
        return self.path / "axis.toml"

    @property
    def pads(self) -> tuple[str, ...]:
        """The guide-way pad DOFs of ``[friction]``.

        Raises
        ------
        AxisFormatError
            If the description has no ``[friction]``.
        """
        if self.friction is None:
            raise AxisFormatError(f"{self.file}: [friction] is missing; add it with "
                                  'pads = ["pad1.x", ...] (the relative-X DOFs of the guide-way '
                                  'pads) and lugre = "bianchi2014" or a parameter table')
        return self.friction.pads

    @property
    def motor_rotor(self) -> str:
        """The motor rotor DOF of ``[drive.motor]``."""
        return self.require_drive().motor.rotor

    def require_drive(self) -> Drive:
        """The drive, or a clear error naming the missing table."""
        if self.drive is None:
            raise AxisFormatError(f"{self.file}: [drive] is missing; add [drive.motor], "
                                  "[drive.transmission], [drive.current_loop], "
                                  "[drive.velocity_loop] and [drive.position_loop] (see "
                                  "`servotune init`)")
        return self.drive

    def require_cutting(self) -> Cutting:
        """The milling set-up, or a clear error naming the missing table."""
        if self.cutting is None:
            raise AxisFormatError(f"{self.file}: [cutting] is missing; add teeth, kt, kn, "
                                  "radial_immersion, milling and speed_rpm (see `servotune init`)")
        return self.cutting

    def configuration(self, pads: str = "free", motor: str = "free") -> ModalModel:
        """The structure with the guide-way pads and/or the motor rotor held (``"locked"``)
        or free (``"free"``): pads locked is stiction at standstill, the rotor held stands for
        a stiff servo."""
        for label, value in (("pads", pads), ("motor", motor)):
            if value not in ("locked", "free"):
                raise ValueError(f"{label} must be 'locked' or 'free', got {value!r}")
        held = (list(self.pads) if pads == "locked" else []) + (
            [self.motor_rotor] if motor == "locked" else [])
        return self.structure.locked(held) if held else self.structure


def _err(file, field, problem, fix):
    return AxisFormatError(f"{file}: {field}: {problem}; {fix}")


def _structure(table, folder: Path, file: Path) -> ModalModel:
    unknown = set(table) - _STRUCTURE_KEYS
    if unknown:
        raise _err(file, "[structure]", f"unknown keys {sorted(unknown)}",
                   f"use only {sorted(_STRUCTURE_KEYS)}")
    zeta = table.get("modal_damping", 0.03)
    if not isinstance(zeta, (int, float, list)) or isinstance(zeta, bool):
        raise _err(file, "[structure] modal_damping", f"got {zeta!r}",
                   "give a damping ratio such as 0.03 or a list with one per mode")
    if "file" in table:
        if "mass" in table or "stiffness" in table:
            raise _err(file, "[structure]", "both file and mass/stiffness are given",
                       "give either file or mass and stiffness")
        paths = {"mass": folder / str(table["file"])}
        key = "[structure] file"
    elif "mass" in table and "stiffness" in table:
        paths = {"mass": folder / str(table["mass"]), "stiffness": folder / str(table["stiffness"])}
        key = "[structure] mass/stiffness"
    else:
        raise _err(file, "[structure]", "no matrices are named",
                   'add file = "structure.npz" or mass = "M.mtx" and stiffness = "K.mtx"')
    for p in paths.values():
        if not p.is_file():
            raise _err(file, key, f"{p} does not exist",
                       "check the name (paths are relative to the axis folder)")
    dof_map = folder / str(table["dof_map"]) if "dof_map" in table else None
    try:
        matrices = read_structure(paths["mass"], paths.get("stiffness"), dof_map)
    except MatrixFileError as exc:
        raise _err(file, key, str(exc), "fix or re-export the matrix files") from None
    try:
        if "reduce" in table:
            spec = table["reduce"]
            if not isinstance(spec, dict) or set(spec) - _REDUCE_KEYS or "boundary" not in spec:
                raise _err(file, "[structure] reduce", f"got {spec!r}",
                           "give reduce = { boundary = [DOF names], n_modes = N } "
                           "(or f_max_hz = F instead of n_modes)")
            boundary = list(spec["boundary"])
            index = matrices.index(boundary)
            return craig_bampton(matrices.mass, matrices.stiffness, index,
                                 n_modes=spec.get("n_modes"), f_max_hz=spec.get("f_max_hz"),
                                 damping_ratio=zeta, boundary_names=boundary)
        return matrices.to_modal_model(damping_ratio=zeta)
    except UnknownDofError as exc:
        raise _err(file, "[structure] reduce.boundary", str(exc),
                   "use names of the DOF map") from None
    except AxisFormatError:
        raise
    except ValueError as exc:
        raise _err(file, "[structure]", str(exc), "fix the matrices or the settings") from None


def _check_dofs(model: ModalModel, names, file, field):
    try:
        model.index(list(names))
    except UnknownDofError as exc:
        raise _err(file, field, str(exc), "name DOFs of the structure") from None


def _table(data, name, file, required=(), optional=()):
    """A sub-table with only known keys, the required ones present."""
    table = data.get(name)
    if table is None:
        return None
    if not isinstance(table, dict):
        raise _err(file, f"[{name}]", f"got {table!r}", f"make [{name}] a table")
    unknown = set(table) - set(required) - set(optional)
    if unknown:
        raise _err(file, f"[{name}]", f"unknown keys {sorted(unknown)}",
                   f"use {sorted(set(required) | set(optional))} (check the spelling)")
    missing = [k for k in required if k not in table]
    if missing:
        raise _err(file, f"[{name}]", f"missing {missing}", "add them (see `servotune init`)")
    return table


def _number(table, key, file, section, default=None, positive=True):
    value = table.get(key, default)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _err(file, f"[{section}] {key}", f"got {value!r}", "give a number in SI units")
    if positive and not value > 0:
        raise _err(file, f"[{section}] {key}", f"got {value!r}", "give a positive value")
    return float(value)


def _friction(data, structure, folder, file) -> GuideWayFriction | None:
    table = _table(data, "friction", file, ("pads",), ("lugre", "viscous", "measurements"))
    if table is None:
        return None
    pads = table["pads"]
    if not isinstance(pads, list) or not pads or not all(isinstance(p, str) for p in pads):
        raise _err(file, "[friction] pads", f"got {pads!r}",
                   'give a list of pad DOF names, e.g. ["pad1.x", "pad2.x"]')
    _check_dofs(structure, pads, file, "[friction] pads")
    lugre = table.get("lugre", "bianchi2014")
    try:
        if isinstance(lugre, str):
            params = LuGreParameters.named(lugre)
        elif isinstance(lugre, dict):
            params = LuGreParameters(**lugre)
        else:
            raise ValueError(f"got {lugre!r}")
    except (TypeError, ValueError, KeyError) as exc:
        raise _err(file, "[friction] lugre", str(exc),
                   f"give a named set {LuGreParameters.names()} or a table "
                   "{fc, fs, vs, delta, sigma0, sigma1, sigma2} in SI units") from None
    measurements = table.get("measurements")
    if measurements is not None:
        if not isinstance(measurements, dict) or set(measurements) - {"stribeck"}:
            raise _err(file, "[friction] measurements", f"got {measurements!r}",
                       'give measurements = { stribeck = "stribeck.csv" } (columns v_m_per_s, '
                       "f_n)")
        csv = folder / str(measurements["stribeck"])
        try:
            measured = read_friction_csv(csv)
            if measured.kind != "steady_state":
                raise ValueError("the file holds no velocity column (v_m_per_s)")
            params = fit_steady_state(measured.velocity, measured.force, base=params).parameters
        except (OSError, ValueError) as exc:
            raise _err(file, "[friction] measurements.stribeck", str(exc),
                       "give a CSV of sliding friction over both velocity signs") from None
    try:
        return GuideWayFriction(tuple(pads), params,
                                _number(table, "viscous", file, "friction", positive=False))
    except ValueError as exc:
        raise _err(file, "[friction]", str(exc), "fix the values") from None


_MOTOR_KEYS = ("torque_constant", "back_emf_constant", "resistance", "inductance")


def _drive(data, structure, file) -> Drive | None:
    table = _table(data, "drive", file, ("motor", "transmission", "current_loop",
                                         "velocity_loop", "position_loop"),
                   ("encoder", "feedforward", "filters"))
    if table is None:
        return None
    motor = _table(table, "motor", file, _MOTOR_KEYS,
                   ("rotor", "stator", "rotor_inertia", "torque_max", "speed_max_rpm"))
    trans = _table(table, "transmission", file, ("ratio",), ("lead", "belt_ratio"))
    current = _table(table, "current_loop", file, ("kp", "ti"))
    velocity = _table(table, "velocity_loop", file, ("kp", "ti"))
    position = _table(table, "position_loop", file, (), ("kv", "kv_m_per_min_per_mm"))
    feedforward = _table(table, "feedforward", file, (), ("velocity", "torque_inertia")) or {}
    filters = _table(table, "filters", file, (), ("lowpass_hz", "notch_hz", "notch_width",
                                                   "notch_depth")) or {}
    encoder = table.get("encoder", "linear")
    if encoder not in ("linear", "motor"):
        raise _err(file, "[drive] encoder", f"got {encoder!r}", 'give "linear" or "motor"')
    if ("kv" in position) == ("kv_m_per_min_per_mm" in position):
        raise _err(file, "[drive.position_loop]", "give exactly one of kv [1/s] and "
                   "kv_m_per_min_per_mm", "e.g. kv_m_per_min_per_mm = 1.0 (the paper's Kv)")
    kv = (_number(position, "kv", file, "drive.position_loop") if "kv" in position else
          kv_from_m_per_min_per_mm(_number(position, "kv_m_per_min_per_mm", file,
                                            "drive.position_loop")))
    for name in ("rotor", "stator"):
        if name in motor:
            _check_dofs(structure, [motor[name]], file, f"[drive.motor] {name}")
    if encoder == "linear":
        _check_dofs(structure, ["encoder.x"], file, "[drive] encoder = 'linear'")
    try:
        lowpass = (LowPassFilter(filters["lowpass_hz"]) if "lowpass_hz" in filters else None)
        notch = (NotchFilter(filters["notch_hz"], filters.get("notch_width", 0.5),
                             filters.get("notch_depth", 0.1)) if "notch_hz" in filters else None)
        return Drive(
            motor=Motor(*(_number(motor, k, file, "drive.motor") for k in _MOTOR_KEYS),
                        rotor=motor.get("rotor", "motor.rotor"),
                        stator=motor.get("stator", "motor.stator")),
            ratio=_number(trans, "ratio", file, "drive.transmission"),
            current_loop=PIController(_number(current, "kp", file, "drive.current_loop"),
                                      _number(current, "ti", file, "drive.current_loop")),
            velocity_loop=PIController(_number(velocity, "kp", file, "drive.velocity_loop"),
                                       _number(velocity, "ti", file, "drive.velocity_loop")),
            kv=kv, feedback=encoder,
            velocity_feedforward=_number(feedforward, "velocity", file, "drive.feedforward", 0.0,
                                         positive=False),
            torque_feedforward_inertia=_number(feedforward, "torque_inertia", file,
                                               "drive.feedforward", 0.0, positive=False),
            lowpass=lowpass, notch=notch)
    except ValueError as exc:
        raise _err(file, "[drive]", str(exc), "fix the value") from None


def _cutting(data, file) -> Cutting | None:
    table = _table(data, "cutting", file, ("teeth", "kt", "kn"),
                   ("radial_immersion", "milling", "speed_rpm", "direction", "helix_angle"))
    if table is None:
        return None
    speeds = table.get("speed_rpm", [1000.0, 12000.0])
    if (not isinstance(speeds, list) or len(speeds) != 2 or
            not all(isinstance(v, (int, float)) for v in speeds) or not 0 < speeds[0] < speeds[1]):
        raise _err(file, "[cutting] speed_rpm", f"got {speeds!r}",
                   "give [low, high] spindle speeds in rpm with 0 < low < high")
    direction = table.get("direction", "x")
    if direction not in ("x", "y"):
        raise _err(file, "[cutting] direction", f"got {direction!r}", 'give "x" or "y"')
    try:
        setup = MillingSetup(teeth=table["teeth"], kt=table["kt"], kn=table["kn"],
                             radial_immersion=table.get("radial_immersion", 1.0),
                             milling=table.get("milling", "down"),
                             helix_angle=table.get("helix_angle", 0.0))
    except (TypeError, ValueError) as exc:
        raise _err(file, "[cutting]", str(exc), "fix the value (kt, kn in N/m^2)") from None
    return Cutting(setup, (float(speeds[0]), float(speeds[1])), direction)


def _tuning(data, file) -> TuningSettings:
    names = ("c", "kv", "kp", "ti")
    table = _table(data, "tuning", file, (), ("free", "chatter_weight", *names))
    if table is None:
        return TuningSettings()
    free = table.get("free", list(names))
    if (not isinstance(free, list) or not free or not all(v in names for v in free)
            or len(set(free)) != len(free)):
        raise _err(file, "[tuning] free", f"got {free!r}",
                   f"give a list of distinct names among {list(names)}")
    bounds = {}
    for key in names:
        if key in table:
            b = table[key]
            if (not isinstance(b, list) or len(b) != 2
                    or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                               for v in b) or not 0 < b[0] < b[1] < math.inf):
                raise _err(file, f"[tuning] {key}", f"got {b!r}",
                           "give the bounds [low, high] in SI units with 0 < low < high")
            bounds[key] = (float(b[0]), float(b[1]))
    weight = table.get("chatter_weight", 0.0)
    if isinstance(weight, bool) or not isinstance(weight, (int, float)) or not 0 <= weight <= 1:
        raise _err(file, "[tuning] chatter_weight", f"got {weight!r}", "give a number in [0, 1]")
    return TuningSettings(tuple(free), MappingProxyType(bounds), float(weight))


def _requirements(data, file) -> Requirements:
    keys = ("ms_velocity_max", "ms_position_max", "phase_margin_min_deg", "gain_margin_min_db",
            "kv_min", "kv_min_m_per_min_per_mm", "band_hz", "loop_band_hz", "depth_required")
    table = _table(data, "requirements", file, (), keys)
    if table is None:
        return Requirements()
    kwargs = {}
    for key in ("ms_velocity_max", "ms_position_max", "phase_margin_min_deg",
                "gain_margin_min_db", "kv_min", "depth_required"):
        if key in table:
            kwargs[key] = _number(table, key, file, "requirements", positive=False)
    if "kv_min_m_per_min_per_mm" in table:
        kwargs["kv_min"] = kv_from_m_per_min_per_mm(
            _number(table, "kv_min_m_per_min_per_mm", file, "requirements", positive=False))
    for key, name in (("band_hz", "band"), ("loop_band_hz", "loop_band")):
        if key in table:
            band = table[key]
            if (not isinstance(band, list) or len(band) != 2
                    or not all(isinstance(v, (int, float)) for v in band)):
                raise _err(file, f"[requirements] {key}", f"got {band!r}",
                           "give [low, high] in Hz")
            kwargs[name] = (2 * math.pi * band[0], 2 * math.pi * band[1])
    try:
        return Requirements(**kwargs)
    except ValueError as exc:
        raise _err(file, "[requirements]", str(exc), "fix the value") from None


def load_axis(path) -> Axis:
    """Load an axis description.

    Parameters
    ----------
    path : path-like
        The axis folder (holding ``axis.toml``) or the TOML file itself.

    Returns
    -------
    Axis

    Raises
    ------
    AxisFormatError
        A missing file, invalid TOML, an unknown section, a missing or wrong field, DOF names
        that the structure does not have.
    """
    path = Path(path)
    file = path / "axis.toml" if path.is_dir() else path
    if not file.is_file():
        raise AxisFormatError(f"{file}: no axis description here; give an axis folder with an "
                              "axis.toml (e.g. models/paper_x_axis)")
    try:
        with open(file, "rb") as handle:
            data = tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        raise AxisFormatError(f"{file}: not valid TOML ({exc}); fix the syntax") from None
    unknown = set(data) - set(SECTIONS)
    if unknown:
        raise _err(file, "sections", f"unknown {sorted(unknown)}", f"use only {list(SECTIONS)}")
    for section in ("axis", "structure"):
        if not isinstance(data.get(section), dict):
            raise _err(file, f"[{section}]", "missing", f"add the [{section}] table")
    name = data["axis"].get("name")
    if not isinstance(name, str) or not name:
        raise _err(file, "[axis] name", "missing", 'add name = "my_axis"')
    folder = file.parent
    structure = _structure(data["structure"], folder, file)
    return Axis(name=name, description=str(data["axis"].get("description", "")),
                path=folder.resolve(), structure=structure,
                friction=_friction(data, structure, folder, file),
                drive=_drive(data, structure, file), cutting=_cutting(data, file),
                requirements=_requirements(data, file), tuning=_tuning(data, file),
                tables=_frozen(data))
