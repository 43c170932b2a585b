"""Axis descriptions: a folder with ``axis.toml`` and the matrix files it names.

:func:`load_axis` reads the description into an :class:`Axis` of validated objects: the
structure as a :class:`~servotune.structure.ModalModel` (``[structure]``), the guide-way friction
as a :class:`~servotune.friction.guideway.GuideWayFriction` (``[friction]``), the cascade as a
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

An FE export names its rows by node and direction (a DOF map with ``node`` and ``dof``
columns); ``ports`` gives the few DOFs the analyses need their names (``pad1.x``, ``wp.x``,
``motor.rotor``, ``encoder.x``) by node number or by position, as
:mod:`servotune.structure.ports` does for ``servotune check --ports``::

    coordinates = "nodes.csv"     # node,x,y,z [m]; needed for ports given by position
    port_tolerance = 1e-3         # [m], largest distance of a port's position to its node
    [structure.ports]
    "pad1.x" = { node = 101, direction = "x" }        # x/y/z/rx/ry/rz, or UX, ROTX, 1-6
    "wp.x" = { position = [0.0, 0.0, 0.8], direction = "UX" }
    "encoder.x" = { node = 120, direction = "-UX" }   # minus: the port is -UX of the export

(or ``ports = "ports.csv"``, a file ``port,node,direction`` or ``port,x,y,z,direction``). A
direction with a minus sign is for a DOF of the export that points against the axis: its row
and column of M and K are multiplied by -1 on loading.

Every error names the file, the field and what to do about it.
"""

from __future__ import annotations

import copyreg
import dataclasses
import itertools
import math
import re
import tomllib
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from .chatter.setup import MillingSetup
from .drive import (
    Drive,
    DriveLimits,
    LowPassFilter,
    Motor,
    NotchFilter,
    PIController,
    Sampling,
    TorqueSpeedCurve,
    kv_from_m_per_min_per_mm,
)
from .friction.guideway import GuideWayFriction
from .friction.identify import fit_steady_state, read_friction_csv
from .friction.law import friction_law, friction_law_names
from .regimes import SPREAD_PARAMETERS, FrictionSpread, Operation, friction_spread
from .requirements import Requirements
from .structure.io import MatrixFileError, read_coordinates, read_structure
from .structure.model import ModalModel, UnknownDofError
from .structure.ports import Port, PortError, apply_signs, name_ports, port_signs, read_ports
from .structure.reduction import craig_bampton
from .validation import finite, fraction, positive

__all__ = ["Axis", "AxisFormatError", "Cutting", "TuningSettings", "load_axis",
           "axis_from_tables", "structure_matrices"]

SECTIONS = ("axis", "structure", "friction", "drive", "cutting", "operation", "requirements",
            "tuning")
_STRUCTURE_KEYS = {"file", "mass", "stiffness", "dof_map", "modal_damping", "reduce",
                   "coordinates", "ports", "port_tolerance", "mass_name", "stiffness_name",
                   "guideway_springs"}
_REDUCE_KEYS = {"boundary", "n_modes", "f_max_hz"}
_PORT_KEYS = {"node", "position", "direction"}
_PORT_FIX = ('name each port by node and direction, "pad1.x" = { node = 101, direction = "x" }, '
             'or by position [m], { position = [x, y, z], direction = "x" } with coordinates = '
             '"nodes.csv" (directions x, y, z, rx, ry, rz, or UX ... ROTZ, or 1-6; a leading - '
             'where the port points against the export\'s direction, direction = "-UX")')


class AxisFormatError(ValueError):
    """An axis description that cannot be used; the message names file, field and fix."""


def read_only(mapping) -> MappingProxyType:
    """Return a read-only view of a copy of ``mapping`` (the axis' settings tables).

    Parameters
    ----------
    mapping : Mapping
        The table.

    Returns
    -------
    types.MappingProxyType
    """
    return MappingProxyType(dict(mapping))


# read-only tables pickle as their contents (an axis goes to the workers of a process pool)
copyreg.pickle(MappingProxyType, lambda m: (read_only, (dict(m),)))


def _frozen(value):
    """Nested TOML data as read-only mappings and tuples."""
    if isinstance(value, dict):
        return MappingProxyType({k: _frozen(v) for k, v in value.items()})
    if isinstance(value, list):
        return tuple(_frozen(v) for v in value)
    return value


@dataclass(frozen=True)
class Cutting:
    """The milling set-up of an axis, the spindle-speed range of interest [rpm] and the feed
    per tooth [m].

    Raises
    ------
    ValueError
        A setup that is not a MillingSetup, speeds that are not 0 < low < high, a direction
        other than "x" or "y", a feed per tooth that is not finite and > 0.
    """

    setup: MillingSetup
    speed_rpm: tuple[float, float] = (1000.0, 12000.0)
    direction: str = "x"
    feed_per_tooth: float = 1e-4

    def __post_init__(self) -> None:
        if not isinstance(self.setup, MillingSetup):
            raise ValueError("Cutting.setup must be a servotune.chatter.MillingSetup, got "
                             f"{type(self.setup).__name__}")
        speeds = tuple(self.speed_rpm) if isinstance(self.speed_rpm, (tuple, list)) else ()
        speeds = tuple(positive("Cutting", "speed_rpm", v, "rpm") for v in speeds)
        if len(speeds) != 2 or not speeds[0] < speeds[1]:
            raise ValueError(f"Cutting.speed_rpm must be (low, high) spindle speeds in rpm with "
                             f"0 < low < high, got {self.speed_rpm!r}")
        object.__setattr__(self, "speed_rpm", speeds)
        if self.direction not in ("x", "y"):
            raise ValueError(f"Cutting.direction must be 'x' (feed) or 'y', got "
                             f"{self.direction!r}")
        object.__setattr__(self, "feed_per_tooth",
                           positive("Cutting", "feed_per_tooth", self.feed_per_tooth, "m"))

    def feed_speeds(self) -> tuple[float, float]:
        """Return the slide speeds [m/s] at the two ends of the spindle-speed range.

        The feed speed is ``f_z N n / 60`` with f_z the feed per tooth [m], N the number of
        teeth of the cutter and n the spindle speed [rpm].

        Returns
        -------
        tuple of float
            ``(v_low, v_high)`` [m/s] at ``speed_rpm[0]`` and ``speed_rpm[1]``.
        """
        return tuple(self.feed_per_tooth * self.setup.teeth * n / 60.0 for n in self.speed_rpm)


#: Free names beside the bounded variables: the tuned current set-point notch and low-pass.
FREE_EXTRA = ("notch", "lowpass")


@dataclass(frozen=True)
class TuningSettings:
    """``[tuning]``: which design variables are free, their bounds (SI) and the chatter weight.

    ``bounds`` maps ``c`` [N s/m], ``kv`` [1/s], ``kp`` [N m s/rad], ``ti`` [s] and
    ``lowpass_frequency`` [rad/s] (the tuned low-pass' corner) to (low, high); absent ones take
    :data:`servotune.design.DEFAULT_BOUNDS` (the low-pass those of
    :class:`servotune.tuning.TuningProblem`).
    ``friction_spread`` maps fc, fs, sigma1 (fractions) and sigma0 (a factor) to the spread of
    the friction the tuning must cover (see :func:`servotune.regimes.friction_samples`);
    ``friction_samples`` are further samples ``(label, {parameter: value})``, e.g. a study's
    worst (:func:`servotune.study.spread.spread_from_study`, ``servotune tune --spread-from``).
    ``friction_variation`` maps fc, fs, sigma0, sigma1 to the identified friction's own
    variation, +- values in SI units (``[friction] variation``, or a named set's measured one):
    the nonlinear verdict checks the corners of ``friction_spread`` when given, else of it
    (:func:`servotune.regimes.friction_spread`).

    Raises
    ------
    ValueError
        Free names that are not distinct names among c, kv, kp, ti, notch, lowpass; bounds
        that are not 0 < low < high; a chatter weight outside [0, 1]; a spread or samples that
        :func:`servotune.regimes.friction_samples` refuses; a variation of another parameter
        or not finite and > 0.
    """

    free: tuple[str, ...] = ("c", "kv", "kp", "ti", "notch")
    bounds: Mapping = field(default_factory=lambda: MappingProxyType({}))
    chatter_weight: float = 0.0
    friction_spread: Mapping = field(default_factory=lambda: MappingProxyType({}))
    friction_samples: tuple = ()
    friction_variation: Mapping = field(default_factory=lambda: MappingProxyType({}))

    def __post_init__(self) -> None:
        names = ("c", "kv", "kp", "ti")
        free = (self.free,) if isinstance(self.free, str) else tuple(self.free)
        if (not free or len(set(free)) != len(free)
                or not set(free) <= {*names, *FREE_EXTRA}):
            raise ValueError("TuningSettings.free must be distinct names among "
                             f"{(*names, *FREE_EXTRA)}, got {self.free!r}")
        object.__setattr__(self, "free", free)
        bounds = {}
        bounded = (*names, "lowpass_frequency")
        for key, pair in dict(self.bounds).items():
            if key not in bounded:
                raise ValueError(f"TuningSettings.bounds has {key!r}; give bounds of {bounded}")
            low, high = (positive("TuningSettings", f"bounds[{key!r}]", v) for v in pair)
            if len(tuple(pair)) != 2 or not low < high:
                raise ValueError(f"TuningSettings.bounds[{key!r}] must be (low, high) with "
                                 f"0 < low < high (SI), got {pair!r}")
            bounds[key] = (low, high)
        object.__setattr__(self, "bounds", MappingProxyType(bounds))
        object.__setattr__(self, "chatter_weight", fraction(
            "TuningSettings", "chatter_weight", self.chatter_weight, closed=True))
        spread = {k: finite("TuningSettings", f"friction_spread[{k!r}]", v)
                  for k, v in dict(self.friction_spread).items()}
        samples = tuple((str(label), MappingProxyType(dict(values)))
                        for label, values in self.friction_samples)
        try:
            from .friction.lugre import BIANCHI2014
            from .regimes import friction_samples

            friction_samples(BIANCHI2014, spread, samples)  # names and ranges
        except (TypeError, ValueError) as exc:
            raise ValueError(f"TuningSettings.friction_spread or friction_samples: {exc}; give "
                             "fractions in (0, 1) for fc, fs, sigma1 and a factor > 1 for "
                             "sigma0") from None
        object.__setattr__(self, "friction_spread", MappingProxyType(spread))
        object.__setattr__(self, "friction_samples", samples)
        variation = {}
        for key, value in dict(self.friction_variation).items():
            if key not in SPREAD_PARAMETERS:
                raise ValueError(f"TuningSettings.friction_variation has {key!r}; give "
                                 f"{', '.join(SPREAD_PARAMETERS)}")
            variation[key] = positive("TuningSettings", f"friction_variation[{key!r}]", value,
                                      SPREAD_PARAMETERS[key])
        object.__setattr__(self, "friction_variation", MappingProxyType(variation))


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
    operation : Operation or None
        ``[operation]``: feed speeds, rapid speed, acceleration, process force (None without a
        drive and friction, where there is nothing to operate).
    requirements : Requirements
        Defaults when the table is absent.
    tuning : TuningSettings
        ``[tuning]``; defaults when absent.
    tables : Mapping
        The raw TOML tables, read-only.
    defaults : tuple of str
        One line for each value that was not given and took a default (shown with results).

    Raises
    ------
    ValueError
        A part of the wrong type.
    AxisFormatError
        A pad, motor or encoder DOF that the structure does not have.
    """

    name: str
    description: str
    path: Path
    structure: ModalModel
    friction: GuideWayFriction | None = None
    drive: Drive | None = None
    cutting: Cutting | None = None
    operation: Operation | None = None
    requirements: Requirements = field(default_factory=Requirements)
    tuning: TuningSettings = field(default_factory=TuningSettings)
    tables: Mapping = field(default_factory=lambda: MappingProxyType({}))
    defaults: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"Axis.name must be a non-empty str, got {self.name!r}")
        if not isinstance(self.description, str):
            raise ValueError(f"Axis.description must be a str, got {self.description!r}")
        object.__setattr__(self, "path", Path(self.path))
        for name, kind, optional in (
                ("structure", ModalModel, False), ("friction", GuideWayFriction, True),
                ("drive", Drive, True), ("cutting", Cutting, True),
                ("operation", Operation, True), ("requirements", Requirements, False),
                ("tuning", TuningSettings, False)):
            value = getattr(self, name)
            if not (isinstance(value, kind) or (optional and value is None)):
                raise ValueError(f"Axis.{name} must be a {kind.__name__}"
                                 + (" or None" if optional else "")
                                 + f", got {type(value).__name__}")
        dofs = set(self.structure.dofs)
        named = [("friction.pads", pad) for pad in (self.friction.pads if self.friction else ())]
        if self.drive is not None:
            named += [("drive.motor.rotor", self.drive.motor.rotor)]
            if self.drive.motor.stator is not None:
                named += [("drive.motor.stator", self.drive.motor.stator)]
            if self.drive.feedback == "linear":
                named += [("drive.encoder", self.drive.encoder)]
        for where, dof in named:
            if dof not in dofs:  # an AxisFormatError: e.g. a default stator DOF not in the file
                raise AxisFormatError(
                    f"{self.file}: Axis.{where} names DOF {dof!r}, which the structure does not "
                    "have; name a DOF of the structure "
                    f"({sorted(d for d in dofs if not d.startswith('mode.'))}) in axis.toml "
                    "([friction] pads, [drive.motor] rotor and stator, the linear encoder's "
                    "encoder.x)")
        if not isinstance(self.tables, Mapping):
            raise ValueError(f"Axis.tables must be a mapping, got {type(self.tables).__name__}")
        object.__setattr__(self, "defaults", tuple(str(d) for d in self.defaults))

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
        """Return the drive, or raise a clear error naming the missing table.

        Returns
        -------
        Drive
            The drive of ``[drive]``.

        Raises
        ------
        AxisFormatError
            If the description has no ``[drive]``.
        """
        if self.drive is None:
            raise AxisFormatError(f"{self.file}: [drive] is missing; add [drive.motor], "
                                  "[drive.transmission], [drive.current_loop], "
                                  "[drive.velocity_loop] and [drive.position_loop] (see "
                                  "`servotune init`)")
        return self.drive

    def require_cutting(self) -> Cutting:
        """Return the milling set-up, or raise a clear error naming the missing table.

        Returns
        -------
        Cutting
            The milling set-up of ``[cutting]``.

        Raises
        ------
        AxisFormatError
            If the description has no ``[cutting]``.
        """
        if self.cutting is None:
            raise AxisFormatError(f"{self.file}: [cutting] is missing; add teeth, kt, kn, "
                                  "radial_immersion, milling and speed_rpm (see `servotune init`)")
        return self.cutting

    def with_continuous_drive(self) -> Axis:
        """Return the axis with its drive in continuous time (no sampling, no delays).

        The paper's model (sec 3: "continuous time elements"), for reproducing its results.

        Returns
        -------
        Axis
            A copy whose drive has continuous sampling; the axis itself when it has no drive.
        """
        import dataclasses

        if self.drive is None:
            return self
        return dataclasses.replace(
            self, drive=dataclasses.replace(self.drive, sampling=Sampling.continuous()))

    def configuration(self, pads: str = "free", motor: str = "free") -> ModalModel:
        """Return the structure with the guide-way pads and/or the motor rotor held or free.

        Pads locked is stiction at standstill; the rotor held stands for a stiff servo.

        Parameters
        ----------
        pads : {"free", "locked"}
            Whether the pad DOFs of ``[friction]`` are held.
        motor : {"free", "locked"}
            Whether the motor rotor DOF is held.

        Returns
        -------
        ModalModel
            The structure with the held DOFs removed (``ModalModel.locked``); the structure
            itself when nothing is held.

        Raises
        ------
        ValueError
            If ``pads`` or ``motor`` is neither ``"locked"`` nor ``"free"``.
        AxisFormatError
            If pads are locked without ``[friction]``, or the motor without ``[drive]``.
        """
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
    values = zeta if isinstance(zeta, list) else [zeta]
    if (not isinstance(zeta, (int, float, list)) or isinstance(zeta, bool) or not values
            or not all(isinstance(z, (int, float)) and not isinstance(z, bool)
                       and math.isfinite(z) and 0 <= z < 1 for z in values)):
        raise _err(file, "[structure] modal_damping", f"got {zeta!r}",
                   "give a damping ratio in [0, 1) such as 0.03, or a list with one per mode")
    matrices = _read_matrices(table, folder, file)
    try:
        if "reduce" in table:
            spec = table["reduce"]
            if not isinstance(spec, dict) or set(spec) - _REDUCE_KEYS or "boundary" not in spec:
                raise _err(file, "[structure] reduce", f"got {spec!r}",
                           "give reduce = { boundary = [DOF names], n_modes = N } "
                           "(or f_max_hz = F instead of n_modes)")
            boundary = spec["boundary"]
            if (not isinstance(boundary, list) or not boundary
                    or not all(isinstance(b, str) for b in boundary)):
                raise _err(file, "[structure] reduce.boundary", f"got {boundary!r}",
                           'give a list of DOF names, e.g. boundary = ["pad1.x", "wp.x"]')
            if "n_modes" in spec and "f_max_hz" in spec:
                raise _err(file, "[structure] reduce", "both n_modes and f_max_hz are given",
                           "give one of them")
            n_modes = spec.get("n_modes")
            if n_modes is not None and (isinstance(n_modes, bool) or not isinstance(
                    n_modes, int) or n_modes < 0):
                raise _err(file, "[structure] reduce.n_modes", f"got {n_modes!r}",
                           "give a whole number >= 0 of fixed-interface modes (0: static)")
            f_max = spec.get("f_max_hz")
            if f_max is not None and (isinstance(f_max, bool) or not isinstance(
                    f_max, (int, float)) or not math.isfinite(f_max) or f_max <= 0):
                raise _err(file, "[structure] reduce.f_max_hz", f"got {f_max!r}",
                           "give the highest fixed-interface mode to keep, in Hz (a number "
                           "> 0, e.g. 500.0)")
            index = matrices.index(boundary)
            interior = matrices.mass.shape[0] - len(set(index))
            n_modes = spec.get("n_modes")
            if n_modes is not None and n_modes > interior:
                raise _err(file, "[structure] reduce.n_modes",
                           f"{n_modes} fixed-interface modes asked, but the structure has "
                           f"{interior} interior DOF(s) ({matrices.mass.shape[0]} DOFs, "
                           f"{len(set(index))} at the boundary)",
                           f"give at most {interior} (all of them: no reduction error), or "
                           "f_max_hz instead")
            return craig_bampton(matrices.mass, matrices.stiffness, index,
                                 n_modes=spec.get("n_modes"), f_max_hz=spec.get("f_max_hz"),
                                 damping_ratio=zeta, boundary_names=boundary)
        return matrices.to_modal_model(damping_ratio=zeta)
    except UnknownDofError as exc:
        raise _err(file, "[structure] reduce.boundary", str(exc),
                   "use names of the DOF map or of [structure] ports") from None
    except AxisFormatError:
        raise
    except ValueError as exc:
        if "damping_ratio has" in str(exc):
            raise _err(file, "[structure] modal_damping", str(exc).replace(
                "ModalModel.damping_ratio", "modal_damping"),
                "give one ratio (e.g. 0.03) or a list with one per mode of the model") from None
        raise _err(file, "[structure]", str(exc), "fix the matrices or the settings") from None


def structure_matrices(axis: Axis):
    """Return the matrices of an axis' ``[structure]`` as read, with its ports named.

    The matrices before any reduction: what a reduction on loading is checked against. The
    data files are read again, relative to the axis' folder.

    Parameters
    ----------
    axis : Axis
        A loaded axis description.

    Returns
    -------
    servotune.structure.StructureMatrices
        Mass and stiffness matrices [kg, N/m] (sparse) with their DOF names.

    Raises
    ------
    AxisFormatError
        As :func:`load_axis` for ``[structure]``.
    """
    return _read_matrices(axis.tables["structure"], axis.path, axis.file)


def _read_matrices(table, folder: Path, file: Path):
    """The checked matrices of ``[structure]`` with their DOF names (ports named)."""
    for name in ("file", "mass", "stiffness", "dof_map"):
        if name in table and (not isinstance(table[name], str) or not table[name].strip()):
            raise _err(file, f"[structure] {name}", f"got {table[name]!r}",
                       'give a file name in quotes, relative to the axis folder, e.g. '
                       '"structure.npz"')
    if "file" in table:
        if "mass" in table or "stiffness" in table:
            raise _err(file, "[structure]", "both file and mass/stiffness are given",
                       "give either file or mass and stiffness")
        paths = {"mass": folder / table["file"]}
        key = "[structure] file"
    elif "mass" in table and "stiffness" in table:
        paths = {"mass": folder / table["mass"], "stiffness": folder / table["stiffness"]}
        key = "[structure] mass/stiffness"
    else:
        raise _err(file, "[structure]", "no matrices are named",
                   'add file = "structure.npz" or mass = "M.mtx" and stiffness = "K.mtx"')
    dof_map = folder / table["dof_map"] if "dof_map" in table else None
    for label, p in ((key, paths["mass"]), (key, paths.get("stiffness")),
                     ("[structure] dof_map", dof_map)):
        if p is not None and not p.is_file():
            raise _err(file, label, f"{p} is a folder, not a file" if p.is_dir() else
                       f"{p} does not exist",
                       "check the name (paths are relative to the axis folder)")
    ports = _ports(table, folder, file)
    names = {}
    for name in ("mass_name", "stiffness_name"):
        if name in table:
            if not isinstance(table[name], str) or not table[name].strip():
                raise _err(file, f"[structure] {name}", f"got {table[name]!r}",
                           "give the matrix' name inside the file, e.g. \"MHH\"")
            names[name] = table[name].strip()
    try:
        matrices = read_structure(paths["mass"], paths.get("stiffness"), dof_map, **names)
    except MatrixFileError as exc:
        raise _err(file, key, str(exc), "fix or re-export the matrix files") from None
    except (OSError, EOFError, zipfile.BadZipFile) as exc:  # a file cut short or not an archive
        raise _err(file, key, f"cannot read {' + '.join(str(p) for p in paths.values())} "
                   f"({type(exc).__name__}: {exc})",
                   "fix or re-export the matrix files") from None
    if ports is not None:
        matrices = _name_ports(matrices, ports, dof_map or paths["mass"], file)
    if "guideway_springs" in table:
        matrices = _without_guideway_springs(matrices, table["guideway_springs"], file)
    for label, matrix, limit, unit in (("mass", matrices.mass, 1e9, "kg (or kg m^2)"),
                                       ("stiffness", matrices.stiffness, 1e16,
                                        "N/m (or N m/rad)")):
        top = _largest(matrix)
        if not top <= limit:
            raise _err(file, key, f"the {label} matrix holds {top:.3g} {unit}, beyond the "
                       f"plausible {limit:g}", "check the units of the export (SI: kg, N/m)")
    return matrices


def _without_guideway_springs(matrices, spec, file: Path):
    """The matrices with the FE model's guide-way springs taken out (the friction model at the
    pads takes their place): ``[structure] guideway_springs = {"<DOF>" = k}`` for a spring
    [N/m] from a DOF to the ground, ``{"<DOF>" = {to = "<DOF>", stiffness = k}}`` for one
    between two DOFs."""
    import numpy as np
    import scipy.sparse

    key = "[structure] guideway_springs"
    fix = ('give {"<DOF>" = <N/m>} for each FE spring that holds the slide on its guide ways '
           '(to the ground), or {"<DOF>" = {to = "<DOF>", stiffness = <N/m>}} between two DOFs')
    if not isinstance(spec, dict) or not spec:
        raise _err(file, key, f"got {spec!r}", fix)
    n = matrices.n
    change = scipy.sparse.lil_array((n, n))
    for dof, value in spec.items():
        other, k = None, value
        if isinstance(value, dict):
            if set(value) != {"to", "stiffness"} or not isinstance(value["to"], str):
                raise _err(file, f"{key}.{dof}", f"got {value!r}", fix)
            other, k = value["to"], value["stiffness"]
        if isinstance(k, bool) or not isinstance(k, (int, float)) or not (
                math.isfinite(k) and 0 < k <= 1e16):
            raise _err(file, f"{key}.{dof}", f"got {k!r}", "give the spring's stiffness in N/m "
                       "(a number > 0)")
        try:
            rows = matrices.index([dof] if other is None else [dof, other])
        except UnknownDofError as exc:
            raise _err(file, f"{key}.{dof}", str(exc), "use names of the DOF map or of "
                       "[structure] ports") from None
        vec = np.zeros(n)
        vec[rows[0]] = 1.0
        if other is not None:
            vec[rows[1]] -= 1.0
        nz = np.flatnonzero(vec)
        for i in nz:
            for j in nz:
                change[i, j] += k * vec[i] * vec[j]
    stiffness = (matrices.stiffness - change.tocsr()).tocsr()
    for dof in spec:
        i = int(matrices.index([dof])[0])
        if stiffness[i, i] < -1e-9 * abs(matrices.stiffness[i, i]):
            raise _err(file, f"{key}.{dof}", f"{spec[dof]!r} is more than the stiffness the "
                       f"model has at {dof} ({matrices.stiffness[i, i]:.4g} N/m on its "
                       "diagonal)", "give the FE spring's own stiffness (check the units: N/m)")
    return dataclasses.replace(matrices, stiffness=stiffness,
                               source=f"{matrices.source} without its guide-way springs")


def _ports(table, folder: Path, file: Path):
    """``[structure] ports``, ``coordinates`` and ``port_tolerance``: the ports (a table or a
    ports CSV, see :mod:`servotune.structure.ports`), the node coordinates [m] (None when not
    given) and the tolerance [m]; None without ports."""
    for key in ("coordinates", "port_tolerance"):
        if key in table and "ports" not in table:
            raise _err(file, f"[structure] {key}", "given without ports (it serves only to find "
                       "ports given by position)", f"add [structure.ports] or remove {key}")
    if "ports" not in table:
        return None
    if "file" not in table and "dof_map" not in table:
        raise _err(file, "[structure] ports", "the matrices have no DOF map to name ports in",
                   'add dof_map = "dofs.csv" (columns node, dof: the rows of the export by node '
                   "number and direction)")
    spec = table["ports"]
    if isinstance(spec, str):
        path = folder / spec
        if not path.is_file():
            raise _err(file, "[structure] ports", f"{path} does not exist",
                       "check the name (paths are relative to the axis folder)")
        try:
            ports = read_ports(path)
        except PortError as exc:
            raise _err(file, "[structure] ports", str(exc),
                       "give a CSV port,node,direction (or port,x,y,z,direction [m])") from None
    elif isinstance(spec, Mapping) and spec:
        ports = tuple(_port(name, value, file) for name, value in spec.items())
    else:
        raise _err(file, "[structure] ports", f"got {spec!r}", f"give a table of ports: {_PORT_FIX}"
                   ', or the name of a ports CSV (ports = "ports.csv")')
    coordinates = None
    if "coordinates" in table:
        value = table["coordinates"]
        path = folder / value if isinstance(value, str) else None
        if path is None or not path.is_file():
            raise _err(file, "[structure] coordinates",
                       f"{path} does not exist" if path is not None else f"got {value!r}",
                       'give the node coordinates file, coordinates = "nodes.csv" (columns node, '
                       "x, y, z [m]; relative to the axis folder)")
        try:
            coordinates = read_coordinates(path)
        except MatrixFileError as exc:
            raise _err(file, "[structure] coordinates", str(exc),
                       "give a CSV with a header node,x,y,z and one row per node [m]") from None
    else:
        by_position = [p.name for p in ports if p.position is not None]
        if by_position:
            raise _err(file, "[structure] coordinates", f"missing: ports {by_position} are "
                       "given by position", 'add coordinates = "nodes.csv" (columns node, x, y, '
                       "z [m]) or give those ports by node number")
    tolerance = _number(table, "port_tolerance", file, "structure", 1e-3, low=1e-9, high=10.0,
                        unit="m")
    return ports, coordinates, tolerance


def _port(name, spec, file: Path) -> Port:
    """One port of ``[structure.ports]``: ``{ node = N, direction = D }`` or
    ``{ position = [x, y, z], direction = D }``."""
    field = f'[structure.ports] "{name}"'
    if not isinstance(spec, Mapping):
        raise _err(file, field, f"got {spec!r}", _PORT_FIX)
    unknown = set(spec) - _PORT_KEYS
    if unknown or "direction" not in spec:
        problem = (f"unknown keys {sorted(unknown)}" if unknown else "no direction")
        raise _err(file, field, problem, _PORT_FIX)
    node, position = spec.get("node"), spec.get("position")
    if node is not None and (isinstance(node, bool) or not isinstance(node, (int, str))
                             or not str(node).strip()):
        raise _err(file, f"{field} node", f"got {node!r}",
                   "give the node number of the export (e.g. node = 101)")
    if position is not None and (
            not isinstance(position, (list, tuple)) or len(position) != 3
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                       and math.isfinite(v) for v in position)):
        raise _err(file, f"{field} position", f"got {position!r}",
                   "give three coordinates [m], position = [x, y, z]")
    if not isinstance(spec["direction"], (str, int)) or isinstance(spec["direction"], bool):
        raise _err(file, f"{field} direction", f"got {spec['direction']!r}", _PORT_FIX)
    try:
        return Port(name, spec["direction"], node, position)
    except PortError as exc:
        raise _err(file, field, str(exc), _PORT_FIX) from None


def _name_ports(matrices, ports, source: Path, file: Path):
    """The matrices with the ports' rows renamed (:func:`~servotune.structure.name_ports`) and
    the rows and columns of ports with a minus sign (``direction = "-UX"``) multiplied by -1
    (:func:`~servotune.structure.port_signs`, :func:`~servotune.structure.apply_signs`)."""
    ports, coordinates, tolerance = ports
    try:
        signs = port_signs(matrices.dofs, ports, coordinates, tolerance)
        dofs = name_ports(matrices.dofs, ports, coordinates, tolerance)
    except PortError as exc:
        raise _err(file, "[structure] ports", str(exc),
                   f"ports name rows of the DOF map {source} (<node>.<direction>) by node "
                   "number or position and direction") from None
    return dataclasses.replace(matrices, mass=apply_signs(matrices.mass, signs),
                               stiffness=apply_signs(matrices.stiffness, signs), dofs=dofs)


def _largest(matrix) -> float:
    """Largest magnitude of a dense or sparse matrix (inf when not finite)."""
    import numpy as np

    data = matrix.data if hasattr(matrix, "tocsr") else np.asarray(matrix)
    if data.size == 0:
        return 0.0
    if not np.all(np.isfinite(data)):
        return math.inf
    return float(np.abs(data).max())


def _check_dofs(model: ModalModel, names, file, field):
    if not all(isinstance(n, str) for n in names):
        raise _err(file, field, f"got {list(names)!r}", "give DOF names as strings")
    try:
        model.index(list(names))
    except UnknownDofError as exc:
        raise _err(file, field, str(exc), "name DOFs of the structure") from None


def _table(data, name, file, required=(), optional=(), parent=""):
    """A sub-table with only known keys, the required ones present (``parent``: the section
    that holds it, as the file names it, e.g. "drive")."""
    table = data.get(name)
    if table is None:
        return None
    label = f"[{parent}.{name}]" if parent else f"[{name}]"
    if not isinstance(table, dict):
        raise _err(file, label, f"got {table!r}", f"make {label} a table")
    unknown = set(table) - set(required) - set(optional)
    if unknown:
        raise _err(file, label, f"unknown keys {sorted(unknown)}",
                   f"use {sorted(set(required) | set(optional))} (check the spelling)")
    missing = [k for k in required if k not in table]
    if missing:
        raise _err(file, label, f"missing {missing}", "add them (see `servotune init`)")
    return table


def _number(table, key, file, section, default=None, positive=True, low=None, high=None,
            unit="SI units"):
    """A number of a table: the default when absent; positive unless told otherwise; within
    [low, high] when given (a plausibility range that catches unit slips)."""
    value = table.get(key, default)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _err(file, f"[{section}] {key}", f"got {value!r}", f"give a number in {unit}")
    if not math.isfinite(value):
        raise _err(file, f"[{section}] {key}", f"got {value!r}", "give a finite number")
    if positive and not value > 0:
        raise _err(file, f"[{section}] {key}", f"got {value!r}", "give a positive value")
    if (low is not None and value < low) or (high is not None and value > high):
        raise _err(file, f"[{section}] {key}", f"{value!r} is outside the plausible range "
                   f"[{low:g}, {high:g}] {unit}", "check the value and its unit")
    return float(value)


def _bool(table, key, file, section, default):
    value = table.get(key, default)
    if not isinstance(value, bool):
        raise _err(file, f"[{section}] {key}", f"got {value!r}", "give true or false")
    return value


def _friction(data, structure, folder, file) -> GuideWayFriction | None:
    laws = friction_law_names()
    table = _table(data, "friction", file, ("pads",), ("viscous", "measurements", "variation",
                                                       *laws))
    if table is None:
        return None
    pads = table["pads"]
    if not isinstance(pads, list) or not pads or not all(isinstance(p, str) for p in pads):
        raise _err(file, "[friction] pads", f"got {pads!r}",
                   'give a list of pad DOF names, e.g. ["pad1.x", "pad2.x"]')
    _check_dofs(structure, pads, file, "[friction] pads")
    # the law: the one key named after a registered law ([friction.<name>]); a number
    # "viscous" is the viscous-only damping, not the viscous law
    named = [k for k in table if k in laws and not (k == "viscous"
                                                     and not isinstance(table[k], dict))]
    if len(named) > 1:
        raise _err(file, "[friction]", f"two friction laws {named}", "keep one of them")
    name = named[0] if named else "lugre"
    cls = friction_law(name)
    try:
        law = cls.from_table(table.get(name, "bianchi2014"))
    except (TypeError, ValueError, KeyError) as exc:
        text = str(exc)
        key = re.search(r"unexpected keyword argument '(\w+)'", text)
        if key:  # a mistyped key: say so in the file's words, not the constructor's
            raise _err(file, f"[friction.{name}]", f"unknown key {key.group(1)!r}",
                       f"check the spelling; {cls.table_hint}") from None
        raise _err(file, f"[friction] {name}", text, cls.table_hint) from None
    measurements = table.get("measurements")
    if measurements is not None:
        if not isinstance(measurements, dict) or set(measurements) - {"stribeck"}:
            raise _err(file, "[friction] measurements", f"got {measurements!r}",
                       'give measurements = { stribeck = "stribeck.csv" } (columns v_m_per_s, '
                       "f_n)")
        params = getattr(law, "lugre_parameters", None)
        if params is None:
            raise _err(file, "[friction] measurements", f"given with the {name} law",
                       "the Stribeck fit identifies LuGre parameters: use [friction.lugre] or "
                       "remove measurements")
        csv = folder / str(measurements["stribeck"])
        try:
            measured = read_friction_csv(csv)
            if measured.kind != "steady_state":
                raise ValueError("the file holds no velocity column (v_m_per_s)")
            law = cls(fit_steady_state(measured.velocity, measured.force,
                                       base=params).parameters)
        except (OSError, ValueError) as exc:
            raise _err(file, "[friction] measurements.stribeck", str(exc),
                       "give a CSV of sliding friction over both velocity signs") from None
    _check_bristles(getattr(law, "lugre_parameters", None), file, name)
    _check_lugre_ranges(getattr(law, "lugre_parameters", None), file, name)
    viscous = table.get("viscous") if not isinstance(table.get("viscous"), dict) else None
    viscous = _number({"viscous": viscous}, "viscous", file, "friction", positive=False,
                      low=0.0, high=1e10, unit="N s/m")
    if len(set(pads)) != len(pads):
        raise _err(file, "[friction] pads", f"{pads!r} names a DOF twice",
                   "list each pad's relative-X DOF once")
    try:
        return GuideWayFriction(tuple(pads), viscous=viscous, law=law)
    except ValueError as exc:
        raise _err(file, "[friction]", str(exc), "fix the values") from None


#: Largest plausible bristle time constant sigma1 / sigma0 [s]: identified guide ways and
#: contacts give 1e-4 to 1e-2 s (Canudas de Wit et al. 1995: 3.2 ms; Bianchi et al. 2014:
#: 2.7 ms); a hundred times the upper end is a unit or exponent slip, not a contact.
BRISTLE_TIME_MAX = 1.0


def _check_bristles(params, file, name) -> None:
    """Refuse LuGre bristles whose damping time constant sigma1 / sigma0 no contact has."""
    if params is None or not params.sigma0 > 0:
        return
    tau = params.sigma1 / params.sigma0
    if tau > BRISTLE_TIME_MAX:
        raise _err(file, f"[friction.{name}] sigma1",
                   f"sigma1 / sigma0 = {params.sigma1:.3g} N s/m / {params.sigma0:.3g} N/m = "
                   f"{tau:.3g} s: a bristle damping time constant above "
                   f"{BRISTLE_TIME_MAX:g} s is physically implausible (identified guide "
                   "ways give 1e-4 to 1e-2 s: Canudas de Wit et al. 1995, Bianchi et al. 2014 "
                   "2.7 ms)",
                   "check the unit (N s/m) and the exponent of sigma1, e.g. sigma1 = "
                   f"{2.7e-3 * params.sigma0:.2g} for 2.7 ms")


#: Plausible ranges of the LuGre parameters of an axis' guide ways (totals, SI): far wider
#: than identified guide ways (Bianchi et al. 2014: Fc 2.2 kN, vs 0.01 m/s, sigma2 5.6 kN s/m;
#: Canudas de Wit et al. 1995: vs 1e-3 m/s), to catch unit and exponent slips only.
LUGRE_RANGES = {"fc": (0.0, 1e7, "N"), "fs": (0.0, 1e7, "N"), "vs": (1e-7, 1.0, "m/s"),
                "delta": (0.0, 10.0, "(an exponent)"), "sigma0": (0.0, 1e14, "N/m"),
                "sigma2": (0.0, 1e10, "N s/m")}


def _check_lugre_ranges(params, file, name) -> None:
    """Refuse LuGre parameters outside what any guide way has (a unit or exponent slip)."""
    if params is None:
        return
    for key, (low, high, unit) in LUGRE_RANGES.items():
        value = getattr(params, key)
        if not low <= value <= high:
            shown = "" if unit.startswith("(") else f" {unit}"
            raise _err(file, f"[friction.{name}] {key}", f"{value:g}{shown} is outside the "
                       f"plausible range [{low:g}, {high:g}] {unit} of guide-way friction",
                       (f"check the value and its unit ({unit}, axis totals)" if shown else
                        "check the value (identified guide ways give 0.5 to 2)")
                       + (", e.g. 0.01 m/s, not mm/s" if key == "vs" else ""))


_MOTOR_KEYS = ("torque_constant", "back_emf_constant", "resistance", "inductance")
#: Plausible ranges (SI) that catch unit slips; far wider than any servo motor.
_MOTOR_RANGES = {"torque_constant": (1e-5, 1e3, "N m/A"),
                 "back_emf_constant": (1e-5, 1e3, "V s/rad"),
                 "resistance": (1e-6, 1e4, "ohm"), "inductance": (1e-9, 100.0, "H")}


def _drive(data, structure, file, defaults) -> Drive | None:
    table = _table(data, "drive", file, ("motor", "transmission", "current_loop",
                                         "velocity_loop", "position_loop"),
                   ("encoder", "feedforward", "filters", "sampling"))
    if table is None:
        return None
    # [drive.motor] checked here so that its messages name the section as the file does;
    # torque_max, the older name of torque_peak, is accepted but not offered
    motor_optional = ("rotor", "stator", "rotor_inertia", "torque_peak", "torque_continuous",
                      "speed_max_rpm", "rated_speed_rpm", "torque_speed")
    if not isinstance(table["motor"], dict):
        raise _err(file, "[drive.motor]", f"got {table['motor']!r}", "make [drive.motor] a table")
    motor_unknown = sorted(set(table["motor"]) - set(_MOTOR_KEYS) - set(motor_optional)
                           - {"torque_max"})
    if motor_unknown:
        import difflib

        valid = sorted(set(_MOTOR_KEYS) | set(motor_optional))
        guesses = [f"{m[0]!r}" + (f" for {k!r}" if len(motor_unknown) > 1 else "")
                   for k in motor_unknown if (m := difflib.get_close_matches(k, valid, n=1))]
        raise _err(file, "[drive.motor]", (f"unknown key {motor_unknown[0]!r}"
                                           if len(motor_unknown) == 1 else
                                           f"unknown keys {motor_unknown}")
                   + (f" (did you mean {', '.join(guesses)}?)" if guesses else ""),
                   f"use {valid} (check the spelling)")
    motor_missing = [k for k in _MOTOR_KEYS if k not in table["motor"]]
    if motor_missing:
        raise _err(file, "[drive.motor]", f"missing {motor_missing}",
                   "add them from the motor data sheet (see `servotune init`)")
    motor = _table(table, "motor", file, _MOTOR_KEYS, (*motor_optional, "torque_max"),
                   parent="drive")
    trans = _table(table, "transmission", file, ("ratio",), ("lead", "belt_ratio"),
                   parent="drive")
    current = _table(table, "current_loop", file, ("kp", "ti"), parent="drive")
    velocity = _table(table, "velocity_loop", file, ("kp", "ti"), parent="drive")
    position = _table(table, "position_loop", file, (), ("kv", "kv_m_per_min_per_mm"),
                      parent="drive")
    feedforward = _table(table, "feedforward", file, (), ("velocity", "torque_inertia"),
                         parent="drive") or {}
    filters = _table(table, "filters", file, (), ("lowpass_hz", "notch_hz", "notch_width",
                                                   "notch_depth"), parent="drive") or {}
    encoder = table.get("encoder", "linear")
    if encoder not in ("linear", "motor"):
        raise _err(file, "[drive] encoder", f"got {encoder!r}", 'give "linear" or "motor"')
    if ("kv" in position) == ("kv_m_per_min_per_mm" in position):
        raise _err(file, "[drive.position_loop]", "give exactly one of kv [1/s] and "
                   "kv_m_per_min_per_mm", "e.g. kv_m_per_min_per_mm = 1.0 (the paper's Kv)")
    kv = (_number(position, "kv", file, "drive.position_loop", low=1e-3, high=1e4, unit="1/s")
          if "kv" in position else
          kv_from_m_per_min_per_mm(_number(position, "kv_m_per_min_per_mm", file,
                                            "drive.position_loop", low=1e-4, high=600.0,
                                            unit="(m/min)/mm")))
    for name in ("rotor", "stator"):
        if name in motor:
            if not isinstance(motor[name], str):
                raise _err(file, f"[drive.motor] {name}", f"got {motor[name]!r}",
                           'give one DOF name, e.g. "motor.rotor"')
            _check_dofs(structure, [motor[name]], file, f"[drive.motor] {name}")
    if motor.get("rotor", "motor.rotor") == motor.get("stator", "motor.stator"):
        raise _err(file, "[drive.motor] stator", f"the same DOF as rotor "
                   f"({motor.get('rotor', 'motor.rotor')!r}): the torque acts between the two, "
                   "so it would cancel", 'give the stator\'s own rotation DOF (e.g. '
                   '"motor.stator"), or leave stator out for a grounded stator')
    if encoder == "linear":
        _check_dofs(structure, ["encoder.x"], file, "[drive] encoder = 'linear'")
    try:
        sampling = _sampling(table, file, defaults)
        lowpass = _number(filters, "lowpass_hz", file, "drive.filters", unit="Hz")
        _below_nyquist(lowpass, "lowpass_hz", sampling, file)
        lowpass = None if lowpass is None else LowPassFilter(lowpass)
        notches = _notches(filters, file)
        for i, notch in enumerate(notches):
            _below_nyquist(notch.f_hz, "notch_hz" + (f" (notch {i + 1})" if len(notches) > 1
                                                     else ""), sampling, file)
        limits = _limits(motor, file, defaults)
        motor_values = [_number(motor, k, file, "drive.motor", low=_MOTOR_RANGES[k][0],
                                high=_MOTOR_RANGES[k][1], unit=_MOTOR_RANGES[k][2])
                        for k in _MOTOR_KEYS]
        _check_winding(*motor_values[2:], file)
        return Drive(
            motor=Motor(*motor_values,
                        rotor=motor.get("rotor", "motor.rotor"),
                        stator=motor.get("stator", "motor.stator")),
            ratio=_number(trans, "ratio", file, "drive.transmission", low=1e-7, high=10.0,
                          unit="m/rad"),
            current_loop=PIController(
                _number(current, "kp", file, "drive.current_loop", low=1e-6, high=1e6,
                        unit="V/A"),
                _number(current, "ti", file, "drive.current_loop", low=1e-7, high=1.0,
                        unit="s")),
            velocity_loop=PIController(
                _number(velocity, "kp", file, "drive.velocity_loop", low=1e-9, high=1e7,
                        unit="N m s/rad"),
                _number(velocity, "ti", file, "drive.velocity_loop", low=1e-7, high=10.0,
                        unit="s")),
            kv=kv, feedback=encoder,
            velocity_feedforward=_number(feedforward, "velocity", file, "drive.feedforward", 0.0,
                                         positive=False, low=0.0, high=2.0,
                                         unit="(a gain: 1 feeds the whole commanded speed)"),
            torque_feedforward_inertia=_number(feedforward, "torque_inertia", file,
                                               "drive.feedforward", 0.0, positive=False,
                                               low=0.0, high=1e3, unit="kg m^2"),
            lowpass=lowpass, notches=notches, sampling=sampling, limits=limits)
    except AxisFormatError:
        raise
    except ValueError as exc:
        raise _err(file, "[drive]", str(exc), "fix the value") from None


def _below_nyquist(f_hz, key, sampling, file) -> None:
    """Refuse a set-point filter at or above half the current controller's sample rate (the
    drive computes the filter at that rate)."""
    if f_hz is None or sampling.is_continuous:
        return
    nyquist = 0.5 / sampling.current_period
    if f_hz >= nyquist:
        raise _err(file, f"[drive.filters] {key}", f"{f_hz:g} Hz is at or above half the "
                   f"current controller's sample rate ({nyquist:g} Hz, [drive.sampling] "
                   f"current_period = {sampling.current_period:g} s): the drive cannot "
                   "compute the filter", f"give a frequency below {nyquist:g} Hz in Hz (not "
                   "rad/s), or a shorter current_period")


#: Largest plausible electrical time constant L / R of a servo motor's winding [s]: data
#: sheets give 1 to 50 ms; seconds are a unit slip (mH given as H).
WINDING_TIME_MAX = 1.0


def _check_winding(resistance, inductance, file) -> None:
    tau = inductance / resistance
    if tau > WINDING_TIME_MAX:
        raise _err(file, "[drive.motor] inductance",
                   f"L / R = {inductance:g} H / {resistance:g} ohm = {tau:.3g} s: an electrical "
                   f"time constant above {WINDING_TIME_MAX:g} s no servo motor has (data sheets "
                   "give 1 to 50 ms)", "check the units: inductance in H (3 mH = 3.0e-3), "
                   "resistance in ohm")


def _notches(filters: dict, file) -> tuple:
    """The current set-point notches of ``[drive.filters]``: ``notch_hz``, ``notch_width`` and
    ``notch_depth`` each a number (one notch) or a list (one entry per notch, the same
    length); width 0.5 and depth 0.1 when absent."""
    if "notch_hz" not in filters:
        extra = [k for k in ("notch_width", "notch_depth") if k in filters]
        if extra:
            raise _err(file, "[drive.filters]", f"{extra} without notch_hz",
                       "give the notch frequency notch_hz [Hz] (or remove them)")
        return ()
    values = {}
    for key, default in (("notch_hz", None), ("notch_width", 0.5), ("notch_depth", 0.1)):
        value = filters.get(key, default)
        values[key] = value if isinstance(value, list) else [value]
    n = len(values["notch_hz"])
    for key in ("notch_width", "notch_depth"):
        if key not in filters:
            values[key] = values[key] * n
        elif len(values[key]) != n:
            raise _err(file, f"[drive.filters] {key}", f"has {len(values[key])} entries for "
                       f"{n} notch frequencies", "give one value per notch_hz entry")
    out = []
    for i in range(n):
        row = {k: v[i] for k, v in values.items()}
        where = "drive.filters" + (f" (notch {i + 1})" if n > 1 else "")
        out.append(NotchFilter(_number(row, "notch_hz", file, where, unit="Hz"),
                               _number(row, "notch_width", file, where, unit="-"),
                               _number(row, "notch_depth", file, where, positive=False,
                                       low=0.0, high=1.0, unit="-")))
    return tuple(out)


_TORQUE_SPEED_KEYS = ("speed_rpm", "peak", "continuous")
_TORQUE_SPEED_EXAMPLE = ("torque_speed = {speed_rpm = [0, 3000, 4500], peak = [90, 90, 60], "
                         "continuous = [27, 27, 18]}")


def _limits(motor, file, defaults) -> DriveLimits | None:
    """Torque and speed limits of ``[drive.motor]`` (None when no torque limit is given).

    The torques over speed: ``torque_speed`` (a table), else the rated torques constant up to
    ``rated_speed_rpm`` and falling at constant power above it, else constant up to
    ``speed_max_rpm`` (the default, stated in ``defaults``).
    """
    if "torque_max" in motor and "torque_peak" in motor:
        raise _err(file, "[drive.motor]", "both torque_max and torque_peak are given",
                   "give torque_peak (torque_max is its older name)")
    key = "torque_peak" if "torque_peak" in motor else "torque_max"
    peak = _number(motor, key, file, "drive.motor", low=1e-3, high=1e6, unit="N m")
    continuous = _number(motor, "torque_continuous", file, "drive.motor", low=1e-3, high=1e6,
                         unit="N m")
    speed = _number(motor, "speed_max_rpm", file, "drive.motor", low=1.0, high=1e6, unit="rpm")
    rated = _number(motor, "rated_speed_rpm", file, "drive.motor", low=1.0, high=1e6,
                    unit="rpm")
    rad = 2 * math.pi / 60
    curve = _torque_speed(motor, file, speed)
    if curve is not None:
        if rated is not None:
            raise _err(file, "[drive.motor] rated_speed_rpm", "given with torque_speed, which "
                       "already says how the torque falls with speed",
                       "remove rated_speed_rpm (or torque_speed)")
        for name, kind, given, values in (
                (key, "peak", peak, curve.torque_peak),
                ("torque_continuous", "continuous", continuous, curve.torque_continuous)):
            if given is not None and not math.isclose(given, max(values), rel_tol=1e-9):
                raise _err(file, f"[drive.motor] {name}", f"{given:g} N m is not the largest "
                           f"{kind} torque of torque_speed ({max(values):g} N m)",
                           f"remove {name} (the table gives it) or make the two agree")
        if speed is None:
            defaults.append(f"[drive.motor] speed_max_rpm from torque_speed: its last speed, "
                            f"{curve.speed_max / rad:.6g} rpm")
        return DriveLimits.from_curve(curve, None if speed is None else speed * rad)
    if continuous is None and (peak is None or key == "torque_max"):
        if rated is not None:
            raise _err(file, "[drive.motor] rated_speed_rpm", "given without torque_peak and "
                       "torque_continuous", "add the torques [N m] it applies to, or remove it")
        return None  # torque_max alone is the informative field of older files
    if peak is None or continuous is None:
        missing = "torque_continuous" if peak is not None else "torque_peak"
        raise _err(file, f"[drive.motor] {missing}", "missing (the thrust budget needs both the "
                   "peak and the continuous torque)",
                   f"add {missing} [N m] from the motor and converter data")
    if continuous > peak:
        raise _err(file, "[drive.motor] torque_continuous", f"{continuous:g} N m exceeds "
                   f"{key} = {peak:g} N m", "give the rated (thermally continuous) torque")
    if rated is not None and speed is not None and rated > speed:
        raise _err(file, "[drive.motor] rated_speed_rpm", f"{rated:g} rpm exceeds speed_max_rpm "
                   f"= {speed:g} rpm", "give the speed above which the torque falls, at most "
                   "the top speed")
    torques = f"{peak:g} N m peak, {continuous:g} N m continuous"
    top = (f"up to speed_max_rpm = {speed:g}" if speed is not None else
           "(no speed_max_rpm: at any speed)")
    if rated is None:
        defaults.append(f"[drive.motor] torque_speed absent: {torques} at every speed {top} "
                        "(add torque_speed, or rated_speed_rpm, if the torque falls before)")
    else:
        defaults.append(f"[drive.motor] torque_speed absent: {torques} up to rated_speed_rpm = "
                        f"{rated:g}, then falling at constant power (T x speed constant) {top}")
    return DriveLimits(peak, continuous, None if speed is None else speed * rad,
                       rated_speed=None if rated is None else rated * rad)


def _torque_speed(motor, file, speed_max_rpm) -> TorqueSpeedCurve | None:
    """``[drive.motor] torque_speed``: motor speed [rpm] and peak and continuous torque [N m]
    at each; increasing speeds from 0 to at least ``speed_max_rpm``."""
    table = motor.get("torque_speed")
    if table is None:
        return None
    field = "[drive.motor] torque_speed"
    if not isinstance(table, dict):
        raise _err(file, field, f"got {table!r}", "give a table of motor speeds [rpm] and the "
                   f"peak and continuous torques [N m] at each, e.g. {_TORQUE_SPEED_EXAMPLE}")
    unknown = sorted(set(table) - set(_TORQUE_SPEED_KEYS))
    missing = [k for k in _TORQUE_SPEED_KEYS if k not in table]
    if unknown or missing:
        raise _err(file, field, (f"unknown keys {unknown}" if unknown else "")
                   + ("; " if unknown and missing else "")
                   + (f"missing {missing}" if missing else ""),
                   f"give exactly speed_rpm, peak and continuous, e.g. {_TORQUE_SPEED_EXAMPLE}")
    columns = {}
    for k, unit in (("speed_rpm", "rpm"), ("peak", "N m"), ("continuous", "N m")):
        values = table[k]
        if (not isinstance(values, list) or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                for v in values)):
            raise _err(file, f"{field}.{k}", f"got {values!r}",
                       f"give a list of finite numbers in {unit}")
        columns[k] = [float(v) for v in values]
    speeds, peaks, conts = columns["speed_rpm"], columns["peak"], columns["continuous"]
    if not len(speeds) == len(peaks) == len(conts):
        raise _err(file, field, f"speed_rpm has {len(speeds)} values, peak {len(peaks)} and "
                   f"continuous {len(conts)}", "give one peak and one continuous torque per "
                   "speed")
    if len(speeds) < 2:
        raise _err(file, f"{field}.speed_rpm", f"{len(speeds)} point(s) make no curve",
                   "give at least two speeds, from 0 rpm to the motor's top speed")
    if speeds[0] != 0.0:
        raise _err(file, f"{field}.speed_rpm", f"the first speed is {speeds[0]:g} rpm",
                   "start the table at 0 rpm (standstill)")
    for a, b in itertools.pairwise(speeds):
        if not b > a:
            raise _err(file, f"{field}.speed_rpm", f"{a:g} rpm is followed by {b:g} rpm",
                       "list the speeds in increasing order, each once")
    if speeds[-1] > 1e6:
        raise _err(file, f"{field}.speed_rpm", f"{speeds[-1]:g} rpm is outside the plausible "
                   "range [0, 1e+06] rpm", "check the value and its unit (rpm)")
    for k, values in (("peak", peaks), ("continuous", conts)):
        for s, t in zip(speeds, values, strict=True):
            if not 1e-3 <= t <= 1e6:
                raise _err(file, f"{field}.{k}", f"{t:g} N m at {s:g} rpm is outside "
                           "[0.001, 1e+06] N m", "give torques > 0 in N m (where the motor gives "
                           "no torque it cannot run: end the table before that speed)")
    for s, p, c in zip(speeds, peaks, conts, strict=True):
        if c > p:
            raise _err(file, f"{field}.continuous", f"{c:g} N m at {s:g} rpm exceeds the peak "
                       f"torque there ({p:g} N m)", "give the thermally continuous torque, at "
                       "most the peak torque at each speed")
    if speed_max_rpm is not None and speeds[-1] < speed_max_rpm * (1 - 1e-9):
        raise _err(file, f"{field}.speed_rpm", f"the table ends at {speeds[-1]:g} rpm, below "
                   f"speed_max_rpm = {speed_max_rpm:g} rpm", "extend the table to the motor's "
                   "top speed, or lower speed_max_rpm to where the table ends")
    try:
        return TorqueSpeedCurve.from_rpm(speeds, peaks, conts)
    except ValueError as exc:
        raise _err(file, field, str(exc), "fix the table") from None


_SAMPLING_KEYS = ("current_period", "velocity_period", "position_period", "computation_delay",
                  "speed_filter", "integral_rule", "continuous")


def _sampling(table, file, defaults) -> Sampling:
    """``[drive.sampling]``: the digital drive (defaults of current industrial drives).

    Sample periods must be > 0 (a continuous drive is ``continuous = true``, not a zero
    period): current and velocity periods in [1e-6, 0.01] s, the position period in
    [1e-6, 0.1] s, each a whole multiple of the next faster one (velocity of current, position
    of velocity); ``computation_delay`` a whole number of sample periods in [0, 10];
    ``speed_filter`` in [0, 0.05] s (0: none; drives smooth the measured speed over at most
    tens of ms); ``integral_rule`` ``"forward_euler"`` or ``"tustin"``.
    """
    section = "drive.sampling"
    sampling = table.get("sampling")
    if sampling is None:
        defaults.append("[drive.sampling] absent: a digital drive with current and velocity "
                        "loops at 125 us, the position loop at 1 ms and one period of "
                        "computation delay (set continuous = true for the paper's continuous "
                        "drive)")
        return Sampling()
    if not isinstance(sampling, dict):
        raise _err(file, f"[{section}]", f"got {sampling!r}", f"make [{section}] a table")
    unknown = sorted(set(sampling) - set(_SAMPLING_KEYS))
    if unknown:
        raise _err(file, f"[{section}]", f"unknown keys {unknown}",
                   f"use {sorted(_SAMPLING_KEYS)} (check the spelling)")
    if _bool(sampling, "continuous", file, section, False):
        if set(sampling) - {"continuous"}:
            raise _err(file, f"[{section}]", "continuous = true with sample periods",
                       "give either continuous = true or the periods")
        return Sampling.continuous()
    kwargs = {}
    for key, high in (("current_period", 0.01), ("velocity_period", 0.01),
                      ("position_period", 0.1)):
        if key in sampling:
            value = sampling[key]
            if (isinstance(value, (int, float)) and not isinstance(value, bool)
                    and math.isfinite(value) and value <= 0):
                raise _err(file, f"[{section}] {key}", f"got {value!r}, but a sample period "
                           "must be > 0", "give the period in seconds (e.g. 125e-6), or "
                           "continuous = true (and no periods) for a continuous drive")
            kwargs[key] = _number(sampling, key, file, section, low=1e-6, high=high, unit="s")
    if "computation_delay" in sampling:
        delay = _number(sampling, "computation_delay", file, section, positive=False,
                        low=0.0, high=10.0, unit="sample periods")
        if delay != round(delay):
            raise _err(file, f"[{section}] computation_delay", f"got {delay!r}; it counts "
                       "sample periods, not seconds",
                       "give the whole number of periods from sampling to applying the output "
                       "(the output is applied at a sample instant): 0, 1 (the usual) or 2")
        kwargs["computation_delay"] = round(delay)
    if "speed_filter" in sampling:
        kwargs["speed_filter"] = _number(sampling, "speed_filter", file, section,
                                         positive=False, low=0.0, high=0.05, unit="s")
    if "integral_rule" in sampling:
        rule = sampling["integral_rule"]
        if rule not in ("forward_euler", "tustin"):
            raise _err(file, f"[{section}] integral_rule", f"got {rule!r}",
                       'give "forward_euler" (the default) or "tustin"')
        kwargs["integral_rule"] = rule
    try:
        return Sampling(**kwargs)
    except ValueError as exc:
        raise _err(file, f"[{section}]", str(exc).removeprefix("Sampling."),
                   "fix the periods in [drive.sampling]") from None


def _cutting(data, file) -> Cutting | None:
    table = _table(data, "cutting", file, ("teeth", "kt", "kn"),
                   ("radial_immersion", "milling", "speed_rpm", "direction", "helix_angle",
                    "feed_per_tooth"))
    if table is None:
        return None
    speeds = table.get("speed_rpm", [1000.0, 12000.0])
    if (not isinstance(speeds, list) or len(speeds) != 2 or
            not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in speeds)
            or not 0 < speeds[0] < speeds[1] <= 2e5):
        raise _err(file, "[cutting] speed_rpm", f"got {speeds!r}",
                   "give [low, high] spindle speeds in rpm with 0 < low < high <= 200000")
    teeth = table["teeth"]
    if isinstance(teeth, bool) or not isinstance(teeth, int) or not 1 <= teeth <= 200:
        raise _err(file, "[cutting] teeth", f"got {teeth!r}", "give a whole number from 1 to 200")
    for key, low, high in (("kt", 1e5, 1e11), ("kn", 0.0, 1e11)):
        _number(table, key, file, "cutting", positive=(key == "kt"), low=low, high=high,
                unit="N/m^2")
    direction = table.get("direction", "x")
    if direction not in ("x", "y"):
        raise _err(file, "[cutting] direction", f"got {direction!r}", 'give "x" or "y"')
    if "radial_immersion" in table:  # a/D: a slip such as 1e-9 would make the forces vanish
        _number(table, "radial_immersion", file, "cutting", low=1e-3, high=1.0, unit="a/D")
    try:
        setup = MillingSetup(teeth=table["teeth"], kt=table["kt"], kn=table["kn"],
                             radial_immersion=table.get("radial_immersion", 1.0),
                             milling=table.get("milling", "down"),
                             helix_angle=table.get("helix_angle", 0.0))
    except (TypeError, ValueError) as exc:
        raise _err(file, "[cutting]", str(exc), "fix the value (kt, kn in N/m^2)") from None
    feed = _number(table, "feed_per_tooth", file, "cutting", 1e-4, low=1e-7, high=0.01,
                   unit="m")
    return Cutting(setup, (float(speeds[0]), float(speeds[1])), direction, feed)


def _operation(data, drive, friction, cutting, requirements, file, defaults
               ) -> Operation | None:
    """``[operation]``: feed speeds, rapid speed, acceleration, process force (defaults from
    ``[cutting]`` and the drive's limits, each default stated in ``defaults``)."""
    keys = ("feed_speeds", "rapid_speed", "acceleration", "process_force_pp", "feed_force",
            "standing")
    table = _table(data, "operation", file, (), keys)
    if drive is None or friction is None:
        if table is not None:
            raise _err(file, "[operation]", "given for an axis without [drive] or [friction]",
                       "add the drive and the friction, or remove [operation]")
        return None
    table = table or {}
    kwargs = {"standing": _bool(table, "standing", file, "operation", True)}
    if "feed_speeds" in table:
        speeds = table["feed_speeds"]
        if (not isinstance(speeds, list) or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) for v in speeds)):
            raise _err(file, "[operation] feed_speeds", f"got {speeds!r}",
                       "give a list of slide speeds while cutting [m/s], e.g. [0.02, 0.04]")
        for v in speeds:
            if not (math.isfinite(v) and 1e-6 <= v <= 10.0):
                raise _err(file, "[operation] feed_speeds", f"{v!r} is outside the plausible "
                           "range [1e-06, 10] m/s", "give speeds in m/s (1 m/min = 0.01667 m/s)")
        kwargs["feed_speeds"] = tuple(float(v) for v in speeds)
        if not speeds:
            defaults.append("[operation] feed_speeds = []: no feeding regime, the axis is "
                            "judged standing only (leave feed_speeds out to take them from "
                            "[cutting])")
    elif cutting is not None and cutting.direction == "x":
        kwargs["feed_speeds"] = cutting.feed_speeds()
        lo, hi = kwargs["feed_speeds"]
        defaults.append(f"[operation] feed_speeds from [cutting]: feed_per_tooth x teeth x "
                        f"speed_rpm = {lo * 1e3:.3g} and {hi * 1e3:.3g} mm/s")
    elif cutting is not None:
        kwargs["feed_speeds"] = ()
        defaults.append("[operation] feed_speeds: none (the axis is the cross axis of the cut, "
                        "[cutting] direction = 'y': it holds position while the cutter feeds)")
    else:
        kwargs["feed_speeds"] = ()
        defaults.append("[operation] feed_speeds: none ([cutting] is absent): the axis is judged "
                        "standing only; add feed_speeds to judge it while feeding")
    rapid = _number(table, "rapid_speed", file, "operation", low=1e-4, high=20.0, unit="m/s")
    if rapid is None and drive.speed_max is not None:
        rapid = drive.speed_max
        if rapid > 20.0:
            raise _err(file, "[drive.transmission] ratio", f"speed_max_rpm x ratio = "
                       f"{rapid:.3g} m/s at the slide, past any machine tool (20 m/s)",
                       "give the ratio in m/rad: lead / (2 pi) / belt ratio, e.g. 1.59e-3 "
                       "for a 10 mm lead (or give [operation] rapid_speed)")
        defaults.append(f"[operation] rapid_speed from [drive.motor] speed_max_rpm and the "
                        f"transmission: {rapid:.3g} m/s ({rapid * 60:.3g} m/min)")
    elif rapid is not None and drive.speed_max is not None and rapid > drive.speed_max * 1.000001:
        raise _err(file, "[operation] rapid_speed", f"{rapid:g} m/s needs more than the motor's "
                   f"speed_max_rpm ({drive.speed_max:.4g} m/s at the slide)",
                   "lower it or raise speed_max_rpm")
    kwargs["rapid_speed"] = rapid
    feeds = kwargs.get("feed_speeds", ())
    if rapid is not None and feeds and max(feeds) > rapid:
        # name both sources: the rapid speed's and the feed speeds' (given, or derived from
        # [cutting])
        rapid_from = ("[operation] rapid_speed" if "rapid_speed" in table
                      else "[drive.motor] speed_max_rpm x [drive.transmission] ratio")
        feeds_from = ("[operation] feed_speeds" if "feed_speeds" in table
                      else "[cutting] feed_per_tooth x teeth x speed_rpm")
        raise _err(file, rapid_from, f"the rapid speed {rapid:.4g} m/s is below the feed speed "
                   f"{max(feeds):.4g} m/s of {feeds_from}",
                   "check the motor's top speed and the feed speeds (m/s)")
    if "acceleration" in table:
        kwargs["acceleration"] = _number(table, "acceleration", file, "operation", low=1e-3,
                                         high=200.0, unit="m/s^2")
    elif drive.limits is not None:
        defaults.append("[operation] acceleration: 1 m/s^2 (add acceleration [m/s^2] for the "
                        "axis' rapid moves)")
    force = _number(table, "process_force_pp", file, "operation", low=1e-3, high=1e7, unit="N")
    feed_force = _number(table, "feed_force", file, "operation", positive=False, low=0.0,
                         high=1e7, unit="N")
    if (force is None or feed_force is None) and cutting is not None \
            and requirements.depth_required is not None:
        from .chatter.forces import cutting_force

        cut = cutting_force(cutting.setup, requirements.depth_required, cutting.feed_per_tooth,
                            cutting.direction)
        if force is None:
            force = cut.peak_to_peak
            if not (math.isfinite(force) and force > 0.0):  # e.g. an immersion that cuts nothing
                raise _err(file, "[cutting]", f"the cutting force at the required depth "
                           f"{requirements.depth_required:g} m is {force!r} N peak to peak (no "
                           "tooth engages)", "check radial_immersion, milling and the depth, or "
                           "give [operation] process_force_pp")
            defaults.append(f"[operation] process_force_pp from [cutting] at the required depth "
                            f"{requirements.depth_required * 1e3:g} mm and "
                            f"{cutting.feed_per_tooth * 1e3:g} mm per tooth: {force:.4g} N")
        if feed_force is None:
            feed_force = abs(cut.mean) if cutting.direction == "x" else 0.0
    if force is None:
        defaults.append("[operation] process_force_pp: none (no [cutting] or no "
                        "[requirements] depth_required); the standing regime is judged at "
                        "600 N peak to peak")
    kwargs.update(process_force_pp=force, feed_force=feed_force or 0.0)
    try:
        return Operation(**kwargs, defaults=())
    except ValueError as exc:
        raise _err(file, "[operation]", str(exc), "fix the values") from None


#: Largest upper bound of each design variable (SI), past any machine tool.
_BOUND_MAX = {"c": 1e12, "kv": 1e4, "kp": 1e7, "ti": 1e3}


def _tuning(data, file) -> TuningSettings:
    names = ("c", "kv", "kp", "ti")
    table = _table(data, "tuning", file, (), ("free", "chatter_weight", "friction_spread",
                                              "lowpass_hz", *names))
    if table is None:
        return TuningSettings()
    free = table.get("free", list(TuningSettings.free))
    if (not isinstance(free, list) or not free
            or not all(v in (*names, *FREE_EXTRA) for v in free)
            or len(set(free)) != len(free)):
        raise _err(file, "[tuning] free", f"got {free!r}",
                   f"give a list of distinct names among {[*names, *FREE_EXTRA]} (notch: the "
                   "current set-point notch's frequency, width and depth; lowpass: the corner "
                   "of [drive.filters] lowpass_hz)")
    bounds = {}
    for key in names:
        if key in table:
            b = table[key]
            if (not isinstance(b, list) or len(b) != 2
                    or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                               for v in b) or not 0 < b[0] < b[1] < math.inf):
                raise _err(file, f"[tuning] {key}", f"got {b!r}",
                           "give the bounds [low, high] in SI units with 0 < low < high <= "
                           f"{_BOUND_MAX[key]:g}")
            bounds[key] = (float(b[0]), float(b[1]))
    if "lowpass_hz" in table:
        b = table["lowpass_hz"]
        if (not isinstance(b, list) or len(b) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in b)
                or not 0 < b[0] < b[1] < math.inf):
            raise _err(file, "[tuning] lowpass_hz", f"got {b!r}",
                       "give the bounds [low, high] of the tuned low-pass' corner in Hz with "
                       "0 < low < high")
        bounds["lowpass_frequency"] = (2.0 * math.pi * b[0], 2.0 * math.pi * b[1])
    weight = table.get("chatter_weight", 0.0)
    if isinstance(weight, bool) or not isinstance(weight, (int, float)) or not 0 <= weight <= 1:
        raise _err(file, "[tuning] chatter_weight", f"got {weight!r}", "give a number in [0, 1]")
    spread = table.get("friction_spread", {})
    if not isinstance(spread, dict):
        raise _err(file, "[tuning] friction_spread", f"got {spread!r}",
                   "give a table such as { fc = 0.3, sigma0 = 3.0 } (fractions for fc, fs, "
                   "sigma1; a factor for sigma0)")
    try:
        from .friction.lugre import BIANCHI2014
        from .regimes import friction_samples

        friction_samples(BIANCHI2014, spread)  # validates names and values
    except (TypeError, ValueError) as exc:
        raise _err(file, "[tuning] friction_spread", str(exc), "fix the spread") from None
    return TuningSettings(tuple(free), MappingProxyType(bounds), float(weight),
                          MappingProxyType({k: float(v) for k, v in spread.items()}))


def _friction_variation(data, friction, tuning, file, defaults) -> dict:
    """``[friction] variation``: the identified friction's own variation, +- values in SI units
    (default: a named set's measured one); states in ``defaults`` which spread the nonlinear
    verdict checks when ``[tuning] friction_spread`` does not say."""
    table = data.get("friction") or {}
    given = table.get("variation")
    lugre = None if friction is None else friction.lugre
    if given is not None:
        if not isinstance(given, dict) or not given:
            raise _err(file, "[friction] variation", f"got {given!r}",
                       "give a table of +- values in SI units, e.g. { fs = 258.0, sigma0 = "
                       "1.17e9, sigma1 = 1.3e6 }")
        if lugre is None:
            raise _err(file, "[friction] variation", "given without LuGre friction",
                       "the variation is of LuGre parameters: use [friction.lugre] or remove it")
        for key, value in given.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise _err(file, f"[friction] variation.{key}", f"got {value!r}",
                           "give a number in SI units")
        variation = {k: float(v) for k, v in given.items()}
        source = "[tuning] friction_spread absent: the identified variation of [friction]"
    elif lugre is not None and _named_set(table) == "bianchi2014":
        from .friction.lugre import BIANCHI2014_SPREAD

        variation = dict(BIANCHI2014_SPREAD)
        source = ("[tuning] friction_spread and [friction] variation absent: the variation "
                  "measured over the paper's six tests of the named set bianchi2014")
    else:
        variation, source = {}, ""
    try:
        if lugre is not None and variation:
            FrictionSpread.absolute(lugre, variation)   # names, and the low corner > 0
        box = friction_spread(lugre, dict(tuning.friction_spread), variation)
    except ValueError as exc:
        raise _err(file, "[friction] variation", str(exc), "fix the variation") from None
    if lugre is None:
        return variation
    if tuning.friction_spread:
        pass  # the spread is given: nothing defaulted
    elif box is not None:
        defaults.append(f"{source}, {box.describe()}: the nonlinear verdict checks its "
                        f"{len(box.corners())} corners")
    else:
        defaults.append("[friction] variation and [tuning] friction_spread absent: the nonlinear "
                        "verdict checks the nominal friction only (state the identified set's "
                        "variation as [friction] variation = { fs = ..., sigma0 = ..., sigma1 = "
                        "... }, +- values in SI units)")
    return variation


def _named_set(table) -> str | None:
    """The name of the named LuGre set of a LuGre ``[friction]`` (``lugre = "bianchi2014"``,
    the default), if any; None when the parameters are given or fitted to measurements."""
    if "measurements" in table:
        return None
    value = table.get("lugre", "bianchi2014")
    return value.lower() if isinstance(value, str) else None


_REQUIREMENT_RANGES = {"ms_velocity_max": (1.0, 100.0, ""), "ms_position_max": (1.0, 100.0, ""),
                       "phase_margin_min_deg": (0.0, 90.0, "deg"),
                       "gain_margin_min_db": (0.0, 60.0, "dB"), "kv_min": (0.0, 1e4, "1/s"),
                       "depth_required": (1e-7, 1.0, "m")}


def _declared_settings(file) -> dict:
    """The settings the installed requirements declare (loads the requirement plug-ins)."""
    from .plugins import PluginError
    from .tuning.constraint import declared_settings

    try:
        return declared_settings()
    except PluginError as exc:
        raise _err(file, "[requirements]", f"a requirement plug-in is broken: {exc}",
                   "fix or uninstall the plug-in it names") from None


def _requirements(data, file) -> Requirements:
    ratios = ("bandwidth_ratio_min", "current_bandwidth_ratio_min", "ti_bandwidth_min",
              "ti_bandwidth_max")
    keys = ("ms_velocity_max", "ms_position_max", "phase_margin_min_deg", "gain_margin_min_db",
            "kv_min", "kv_min_m_per_min_per_mm", "band_hz", "loop_band_hz", "depth_required",
            "thrust_margin", "nonlinear_tolerance", *ratios)
    given = data.get("requirements")
    declared = {}
    if isinstance(given, dict) and set(given) - set(keys):
        # keys servotune does not know may be settings of installed requirement plug-ins
        declared = _declared_settings(file)
    table = _table(data, "requirements", file, (), (*keys, *declared))
    if table is None:
        return Requirements()
    kwargs = {}
    settings = {}
    for key, (setting, owner) in declared.items():
        if key in table:
            try:
                settings[key] = setting.parse(table[key])
            except ValueError as exc:
                raise _err(file, f"[requirements] {key}", str(exc),
                           f"give a number in [{setting.low:g}, {setting.high:g}] "
                           f"{setting.unit} (a setting of the requirement {owner!r})") from None
    if settings:
        kwargs["settings"] = settings
    for key in ("ms_velocity_max", "ms_position_max", "phase_margin_min_deg",
                "gain_margin_min_db", "kv_min", "depth_required"):
        if key in table:
            low, high, unit = _REQUIREMENT_RANGES[key]
            kwargs[key] = _number(table, key, file, "requirements", positive=False, low=low,
                                  high=high, unit=unit)
    pm = kwargs.get("phase_margin_min_deg")
    if pm is not None and 0.0 < pm <= 0.5 * math.pi:  # no design asks for 1 deg: radians
        raise _err(file, "[requirements] phase_margin_min_deg", f"{pm:g} deg is no phase "
                   f"margin a design asks for, but {pm:g} rad = {math.degrees(pm):.3g} deg is",
                   f"give degrees, e.g. {math.degrees(pm):.0f} (or 0 for no phase-margin "
                   "requirement)")
    for key in ratios:
        if key in table:
            kwargs[key] = _number(table, key, file, "requirements", low=0.0, high=1e3,
                                  unit="(a ratio)")
    for key in ("thrust_margin", "nonlinear_tolerance"):
        if key in table:
            kwargs[key] = _number(table, key, file, "requirements", positive=False, low=0.0,
                                  high=0.99 if key == "thrust_margin" else 10.0,
                                  unit="(a fraction)")
    if "kv_min_m_per_min_per_mm" in table:
        kwargs["kv_min"] = kv_from_m_per_min_per_mm(
            _number(table, "kv_min_m_per_min_per_mm", file, "requirements", positive=False,
                    low=0.0, high=600.0, unit="(m/min)/mm"))
    for key, name in (("band_hz", "band"), ("loop_band_hz", "loop_band")):
        if key in table:
            band = table[key]
            if (not isinstance(band, list) or len(band) != 2
                    or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                               and math.isfinite(v) for v in band)
                    or not 0 < band[0] < band[1] <= 1e5):
                raise _err(file, f"[requirements] {key}", f"got {band!r}",
                           "give [low, high] in Hz with 0 < low < high <= 100000")
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
        The checked description (see :func:`axis_from_tables`).

    Raises
    ------
    AxisFormatError
        A missing file, invalid TOML, an unknown section, a missing or wrong field, DOF names
        that the structure does not have.

    See Also
    --------
    servotune.design.tune_axis : the design job on the loaded axis.
    servotune.analysis.loop_report : the loops of the axis.
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
        hint = ("give the axis folder (the one holding axis.toml)" if file.name != "axis.toml"
                else "fix the syntax")
        raise AxisFormatError(f"{file}: not valid TOML ({exc}); {hint}") from None
    except UnicodeDecodeError:  # a binary file, e.g. the structure.npz beside axis.toml
        raise AxisFormatError(f"{file}: not an axis description (not a text file); give the "
                              "axis folder (the one holding axis.toml)") from None
    return axis_from_tables(data, file)


def axis_from_tables(data: dict, file) -> Axis:
    """Return an axis from the tables of an ``axis.toml`` already read.

    A study varies the tables and builds each sample's axis this way. Values left out take
    their defaults, each noted in ``Axis.defaults``.

    Parameters
    ----------
    data : dict
        The tables as :mod:`tomllib` gives them.
    file : path-like
        The ``axis.toml`` the tables stand for: data files are relative to its folder and
        errors name it.

    Returns
    -------
    Axis
        The checked description; its ``path`` is the resolved folder of ``file``.

    Raises
    ------
    AxisFormatError
        As :func:`load_axis`.
    """
    file = Path(file)
    if not isinstance(data, dict):
        raise AxisFormatError(f"{file}: the description must be a table of sections")
    unknown = set(data) - set(SECTIONS)
    if unknown:
        raise _err(file, "sections", f"unknown {sorted(unknown)}", f"use only {list(SECTIONS)}")
    for section in ("axis", "structure"):
        if not isinstance(data.get(section), dict):
            raise _err(file, f"[{section}]", "missing", f"add the [{section}] table")
    name = data["axis"].get("name")
    if not isinstance(name, str) or not name:
        raise _err(file, "[axis] name", "missing", 'add name = "my_axis"')
    unknown = set(data["axis"]) - {"name", "description"}
    if unknown:
        raise _err(file, "[axis]", f"unknown keys {sorted(unknown)}",
                   "use name and description (check the spelling)")
    folder = file.parent
    structure = _structure(data["structure"], folder, file)
    defaults: list[str] = []
    friction = _friction(data, structure, folder, file)
    drive = _drive(data, structure, file, defaults)
    cutting = _cutting(data, file)
    requirements = _requirements(data, file)
    if "requirements" not in data:
        r = requirements
        lo, hi = (w / (2.0 * math.pi) for w in r.band)
        defaults.append(f"[requirements] absent: the defaults, band {lo:g}-{hi:g} Hz of the "
                        f"compliance peak, Ms velocity <= {r.ms_velocity_max:g}, position <= "
                        f"{r.ms_position_max:g}, no required depth")
    if "tuning" not in data and drive is not None:
        defaults.append("[tuning] absent: C, Kv, Kp, Ti all free within the default bounds "
                        "(servotune.design.DEFAULT_BOUNDS)")
    if drive is not None and drive.limits is None:
        defaults.append("[drive.motor] has no torque_peak and torque_continuous: the thrust "
                        "budget is not checked")
    operation = _operation(data, drive, friction, cutting, requirements, file, defaults)
    tuning = _tuning(data, file)
    kv_high = dict(tuning.bounds).get("kv", (None, None))[1]
    if kv_high is not None and requirements.kv_min > kv_high:
        raise _err(file, "[requirements] kv_min", f"the least Kv {requirements.kv_min:.4g} 1/s "
                   f"({requirements.kv_min * 60e-3:.4g} (m/min)/mm) is above the largest Kv "
                   f"the tuning may choose, [tuning] kv = {kv_high:.4g} 1/s", "lower kv_min "
                   "(kv_min_m_per_min_per_mm is in (m/min)/mm: 1.0 is 16.67 1/s) or raise the "
                   "upper bound of [tuning] kv")
    c_low = dict(tuning.bounds).get("c", (None, None))[0]
    lugre = getattr(getattr(friction, "law", None), "lugre_parameters", None)
    if drive is not None and c_low is not None and lugre is not None and c_low < lugre.sigma2:
        raise _err(file, "[tuning] c", f"the lower bound {c_low:g} N s/m is below the guide "
                   f"ways' own viscous friction sigma2 = {lugre.sigma2:g} N s/m ([friction."
                   "lugre]): C is the total guide-way damping, so damping can be added to "
                   "sigma2 but not taken from it", f"give a lower bound >= {lugre.sigma2:g} "
                   "N s/m, or leave c out (then it starts at sigma2)")
    variation = _friction_variation(data, friction, tuning, file,
                                    defaults if drive is not None else [])
    if variation:
        tuning = dataclasses.replace(tuning, friction_variation=MappingProxyType(variation))
    return Axis(name=name, description=str(data["axis"].get("description", "")),
                path=folder.resolve(), structure=structure, friction=friction, drive=drive,
                cutting=cutting, operation=operation, requirements=requirements,
                tuning=tuning, tables=_frozen(data), defaults=tuple(defaults))
