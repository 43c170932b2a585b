"""Axis descriptions: a folder with ``axis.toml`` and the matrix files it names.

:func:`load_axis` reads the description into an :class:`Axis`: the structure as a
:class:`~servotune.structure.ModalModel` (built from the ``[structure]`` table) and the other
tables (``[friction]``, ``[drive]``, ``[cutting]``, ``[requirements]``) kept as read-only
mappings for the modules that interpret them. Values are SI unless the key says otherwise
(``_hz``, ``_deg``, ``_db``, ``_rpm``, ``kv_m_per_min_per_mm``).

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

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from .structure.io import MatrixFileError, read_structure
from .structure.model import ModalModel, UnknownDofError
from .structure.reduction import craig_bampton

__all__ = ["Axis", "AxisFormatError", "load_axis"]

SECTIONS = ("axis", "structure", "friction", "drive", "cutting", "requirements")
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
    friction, drive, cutting, requirements : Mapping
        The tables of the same name, read-only (empty when absent).
    """

    name: str
    description: str
    path: Path
    structure: ModalModel
    friction: Mapping = field(default_factory=lambda: MappingProxyType({}))
    drive: Mapping = field(default_factory=lambda: MappingProxyType({}))
    cutting: Mapping = field(default_factory=lambda: MappingProxyType({}))
    requirements: Mapping = field(default_factory=lambda: MappingProxyType({}))

    @property
    def pads(self) -> tuple[str, ...]:
        """The guide-way pad DOFs of ``[friction]``.

        Raises
        ------
        AxisFormatError
            If the description has no ``[friction]`` ``pads``.
        """
        pads = self.friction.get("pads")
        if not pads:
            raise AxisFormatError(f"{self.path / 'axis.toml'}: [friction] pads is missing; add "
                                  'pads = ["pad1.x", ...] (the relative-X DOFs of the guide-way '
                                  "pads)")
        return tuple(pads)

    @property
    def motor_rotor(self) -> str:
        """The motor rotor DOF of ``[drive.motor]``."""
        rotor = self.drive.get("motor", {}).get("rotor")
        if not rotor:
            raise AxisFormatError(f"{self.path / 'axis.toml'}: [drive.motor] rotor is missing; "
                                  'add rotor = "motor.rotor" (the rotor rotation DOF)')
        return rotor


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
    friction = data.get("friction", {})
    if "pads" in friction:
        if not isinstance(friction["pads"], list) or not friction["pads"]:
            raise _err(file, "[friction] pads", f"got {friction['pads']!r}",
                       'give a list of pad DOF names, e.g. ["pad1.x", "pad2.x"]')
        _check_dofs(structure, friction["pads"], file, "[friction] pads")
    motor = data.get("drive", {}).get("motor", {})
    for key in ("rotor", "stator"):
        if key in motor:
            _check_dofs(structure, [motor[key]], file, f"[drive.motor] {key}")
    if data.get("drive", {}).get("encoder") == "linear":
        _check_dofs(structure, ["encoder.x"], file, "[drive] encoder = 'linear'")
    return Axis(name=name, description=str(data["axis"].get("description", "")),
                path=folder.resolve(), structure=structure,
                friction=_frozen(friction), drive=_frozen(data.get("drive", {})),
                cutting=_frozen(data.get("cutting", {})),
                requirements=_frozen(data.get("requirements", {})))
