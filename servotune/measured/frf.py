"""Measured frequency response functions: reading CSV and Universal File Format dataset 58.

An impact-hammer test at the work piece gives receptances (displacement over force, m/N), or
mobilities (m/s per N) or accelerances (m/s^2 per N) when the sensor is a velocity or an
acceleration pick-up. The drive's own measuring function of the speed loop gives the speed
plant, motor speed over motor torque (``speed_per_torque``, rad/(s N m)). Every file comes in
as :class:`MeasuredFrf`: the angular frequencies [rad/s], the complex values in SI units and
the quantity they are, so that what follows never sees Hz, mm, g or rpm.

Files
-----
CSV (read through :func:`servotune.tablefile.read_table`): a header row with ``f_hz`` and either
``re, im`` or ``mag, phase_deg``. The quantity and its unit are stated in comment lines before
the data, ``# quantity: receptance`` and ``# units: um/N`` (``=`` works as well as ``:``), or
given by the caller; without either the values are receptances in m/N.

UFF dataset 58 ("function at nodal DOF"), read by pyuff: every record of function type 4
(frequency response function) is one FRF; its ordinate type says the quantity (8 displacement,
11 velocity, 12 acceleration, over 13 force), a dataset 164 in the file its units. A velocity
over a force whose response and reference directions are both rotations (+-RX, RY, RZ, codes
4-6) is an angular speed over a torque: the speed plant.

Examples
--------
>>> import tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "hammer.csv"
>>> _ = path.write_text("# units: um/N\\nf_hz,re,im\\n10,0.5,-0.1\\n20,0.4,-0.3\\n")
>>> frf = read_frf_csv(path)
>>> frf.quantity, frf.values[0]
('receptance', np.complex128(5e-07-1e-07j))
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..tablefile import TableFileError, read_table

__all__ = [
    "FrfFileError",
    "MeasuredFrf",
    "QUANTITIES",
    "UFF_SUFFIXES",
    "read_frf_csv",
    "read_frf_uff",
    "read_frfs",
]


class FrfFileError(TableFileError):
    """A measured-FRF file that cannot be used; the message names the file, the line or record
    and the fix."""


#: quantity -> (its SI unit, the units accepted with their factor to SI)
QUANTITIES: dict[str, tuple[str, dict[str, float]]] = {
    "receptance": ("m/N", {"m/N": 1.0, "mm/N": 1e-3, "um/N": 1e-6, "nm/N": 1e-9}),
    "mobility": ("m/s/N", {"m/s/N": 1.0, "(m/s)/N": 1.0, "mm/s/N": 1e-3, "(mm/s)/N": 1e-3}),
    "accelerance": ("m/s^2/N", {"m/s^2/N": 1.0, "(m/s^2)/N": 1.0, "g/N": 9.80665}),
    "speed_per_torque": ("rad/s/N m", {
        "rad/s/N m": 1.0, "rad/(s N m)": 1.0, "(rad/s)/(N m)": 1.0, "(rad/s)/N m": 1.0,
        "1/(s N m)": 1.0, "rpm/N m": 2 * math.pi / 60, "(1/min)/(N m)": 2 * math.pi / 60,
        "1/min/N m": 2 * math.pi / 60}),
}

#: what each quantity is, for messages
_QUANTITY_WORDS = {"receptance": "receptance (m/N)", "mobility": "mobility (m/s/N)",
                   "accelerance": "accelerance (m/s^2/N)",
                   "speed_per_torque": "speed_per_torque (rad/s/N m: the drive's speed plant)"}

#: file-name endings read as Universal File Format (anything else is read as CSV)
UFF_SUFFIXES = (".uff", ".unv", ".uf", ".58")

#: UFF dataset 58 ordinate types -> quantity (the denominator being a force, type 13)
_UFF_ORDINATES = {8: "receptance", 11: "mobility", 12: "accelerance"}

#: names of the UFF datasets a file may hold instead, for messages
_UFF_NAMES = {15: "nodes", 18: "coordinate systems", 55: "data at nodes (mode shapes)",
              58: "function at nodal DOF", 82: "trace lines", 151: "header", 164: "units",
              2400: "model header", 2411: "nodes", 2412: "elements",
              2414: "analysis data at nodes", 2420: "coordinate systems"}

#: UFF 58 function types, for messages
_UFF_FUNCTIONS = {0: "general", 1: "time response", 2: "auto spectrum", 3: "cross spectrum",
                  4: "frequency response function", 5: "transmissibility", 6: "coherence",
                  9: "power spectral density"}


@dataclass(frozen=True)
class MeasuredFrf:
    """One measured frequency response function, SI inside.

    Attributes
    ----------
    omega : numpy.ndarray
        Angular frequencies [rad/s], increasing, >= 0 (read-only).
    values : numpy.ndarray
        The complex FRF at ``omega`` in SI units of ``quantity`` (read-only).
    quantity : str
        ``"receptance"`` [m/N], ``"mobility"`` [m/(s N)], ``"accelerance"`` [m/(s^2 N)] or
        ``"speed_per_torque"`` [rad/(s N m)] (motor speed over motor torque).
    name : str
        What the FRF is, for tables and figures (the file, and the record and DOFs of a UFF).
    source : pathlib.Path
        The file it was read from.
    defaults : tuple of str
        What was assumed in reading it (the quantity or the units taken by default).
    notes : tuple of str
        Other remarks (units converted, records left out).
    """

    omega: np.ndarray
    values: np.ndarray
    quantity: str
    name: str
    source: Path
    defaults: tuple[str, ...] = field(default=())
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self):
        omega = np.array(self.omega, dtype=float)
        values = np.array(self.values, dtype=complex)
        if omega.ndim != 1 or values.shape != omega.shape:
            raise ValueError(f"MeasuredFrf {self.name}: omega and values must be 1-D arrays of "
                             f"one length, got {omega.shape} and {values.shape}")
        if omega.size < 2 or not np.all(np.isfinite(omega)) or omega[0] < 0 or np.any(
                np.diff(omega) <= 0):
            raise ValueError(f"MeasuredFrf {self.name}: omega must hold at least two finite, "
                             "increasing frequencies >= 0 rad/s")
        if not np.all(np.isfinite(values)):
            raise ValueError(f"MeasuredFrf {self.name}: the values must be finite")
        if self.quantity not in QUANTITIES:
            raise ValueError(f"MeasuredFrf {self.name}: quantity {self.quantity!r} is not one "
                             f"of {', '.join(QUANTITIES)}")
        omega.flags.writeable = False
        values.flags.writeable = False
        object.__setattr__(self, "omega", omega)
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "source", Path(self.source))
        object.__setattr__(self, "defaults", tuple(self.defaults))
        object.__setattr__(self, "notes", tuple(self.notes))

    @property
    def unit(self) -> str:
        """The SI unit of the values (``"m/N"`` for a receptance)."""
        return QUANTITIES[self.quantity][0]

    def to_dict(self) -> dict:
        """Return what the FRF is, for results files (not its values).

        Returns
        -------
        dict
            ``name``, ``file``, ``quantity``, ``unit``, ``points``, ``f_min_hz``,
            ``f_max_hz``.
        """
        return {"name": self.name, "file": str(self.source), "quantity": self.quantity,
                "unit": self.unit, "points": int(self.omega.size),
                "f_min_hz": float(self.omega[0] / (2 * math.pi)),
                "f_max_hz": float(self.omega[-1] / (2 * math.pi))}


def _unit_key(text: str) -> str:
    key = text.strip().lower().replace(" ", "").replace("µ", "u").replace("μ", "u")
    return key.replace("**", "^").replace("²", "^2").replace("s2", "s^2")


def _unit_factor(quantity: str, units: str, where: str) -> float:
    """The factor from ``units`` to SI for ``quantity``; FrfFileError naming ``where``."""
    si, table = QUANTITIES[quantity]
    factor = {_unit_key(k): v for k, v in table.items()}.get(_unit_key(units))
    if factor is None:
        known = ", ".join(table)
        raise FrfFileError(f"{where}: units {units!r} are not known for a {quantity}; give one "
                           f"of {known} (SI: {si})")
    return factor


def _check_quantity(quantity: str, where: str) -> str:
    key = re.sub(r"[\s-]+", "_", quantity.strip().lower())
    if key not in QUANTITIES:
        raise FrfFileError(f"{where}: quantity {quantity!r} is not known; give "
                           f"{', '.join(_QUANTITY_WORDS.values())}")
    return key


_STATEMENT = re.compile(r"#\s*(quantity|units?)\s*[:=]\s*(.+?)\s*$", re.IGNORECASE)


def _statements(path: Path) -> dict[str, tuple[str, int]]:
    """The ``# quantity: ...`` and ``# units: ...`` comment lines of a CSV: key -> (value,
    line)."""
    found: dict[str, tuple[str, int]] = {}
    try:
        with open(path, newline="") as handle:
            for number, line in enumerate(handle, start=1):
                stripped = line.strip()
                if not stripped:
                    continue
                if not stripped.startswith("#"):
                    break
                match = _STATEMENT.match(stripped)
                if match:
                    key = "units" if match.group(1).lower().startswith("unit") else "quantity"
                    found[key] = (match.group(2).strip().strip(",").strip(), number)
    except (OSError, UnicodeDecodeError):
        pass  # read_table reports it
    return found


CSV_HINT = ("a header row f_hz,re,im or f_hz,mag,phase_deg; the quantity and its unit in "
            "comment lines before it, e.g. '# quantity: receptance' and '# units: m/N'")


def read_frf_csv(path, quantity: str | None = None, units: str | None = None) -> MeasuredFrf:
    """Read one measured FRF from a CSV file.

    Parameters
    ----------
    path : str or os.PathLike
        The file: a header row with ``f_hz`` [Hz] and ``re, im`` or ``mag, phase_deg``
        (magnitude, phase in degrees); ``#`` lines are comments, and the comment lines before
        the header may state ``# quantity: receptance|mobility|accelerance|speed_per_torque``
        and ``# units: m/N`` (also ``mm/N``, ``um/N``, ``nm/N``; ``m/s/N``, ``mm/s/N``;
        ``m/s^2/N``, ``g/N``; ``rad/s/N m``, ``rpm/N m``).
    quantity : str, optional
        The quantity when the file does not state it (default receptance). A file that states
        another is refused.
    units : str, optional
        The units when the file does not state them (default: the SI unit of the quantity).

    Returns
    -------
    MeasuredFrf
        The FRF in SI units, frequencies in rad/s.

    Raises
    ------
    FrfFileError
        Naming the file, the line and the fix: no such file, a missing column, a value that
        is not a number, frequencies that do not increase, an unknown quantity or unit.
    """
    path = Path(path)
    table = read_table(path, "measured FRF", min_rows=2, hint=CSV_HINT, error=FrfFileError)
    stated = _statements(path)
    defaults = []
    if "quantity" in stated:
        text, line = stated["quantity"]
        q = _check_quantity(text, f"{path}, line {line}")
        if quantity is not None and _check_quantity(quantity, "--quantity") != q:
            raise FrfFileError(f"{path}, line {line}: the file states a {q}, but a {quantity} "
                               "was asked for (--quantity, or --kind speed-plant); correct the "
                               "file or the option")
    elif quantity is not None:
        q = _check_quantity(quantity, "--quantity")
    else:
        q = "receptance"
        defaults.append(f"{path.name}: a receptance (no '# quantity:' line, no --quantity)")
    if "units" in stated:
        text, line = stated["units"]
        factor = _unit_factor(q, text, f"{path}, line {line}")
    elif units is not None:
        factor = _unit_factor(q, units, "--units")
    else:
        factor = 1.0
        if "quantity" in stated or quantity is not None:
            defaults.append(f"{path.name}: units {QUANTITIES[q][0]} (no '# units:' line)")
        else:
            defaults[-1] = (f"{path.name}: a receptance in m/N (no '# quantity:' or "
                            "'# units:' line, no --quantity)")
    cartesian, polar = table.has("re", "im"), table.has("mag", "phase_deg")
    table.require("f_hz", hint=CSV_HINT)
    if cartesian and polar:
        raise table.error("give either the columns re,im or mag,phase_deg, not both")
    if not (cartesian or polar):
        raise table.error(f"the measured FRF needs the columns re,im or mag,phase_deg; found "
                          f"{', '.join(table.header)} ({CSV_HINT})")
    f_hz = table.numbers("f_hz")
    for i in range(f_hz.size):
        if f_hz[i] < 0:
            raise table.error(f"f_hz is {f_hz[i]:g}: frequencies must be >= 0 Hz", i)
        if i and f_hz[i] <= f_hz[i - 1]:
            raise table.error(f"f_hz {f_hz[i]:g} does not increase (the line before has "
                              f"{f_hz[i - 1]:g}); sort the rows by frequency, one per line", i)
    if cartesian:
        values = table.numbers("re") + 1j * table.numbers("im")
    else:
        mag = table.numbers("mag")
        bad = np.flatnonzero(mag < 0)
        if bad.size:
            raise table.error(f"mag is {mag[bad[0]]:g}: a magnitude must be >= 0", int(bad[0]))
        values = mag * np.exp(1j * np.deg2rad(table.numbers("phase_deg")))
    return MeasuredFrf(2 * math.pi * f_hz, values * factor, q, path.name, path, tuple(defaults))


def _uff_error(path: Path, message: str, record: int | None = None) -> FrfFileError:
    where = f"{path}" if record is None else f"{path}, record {record}"
    return FrfFileError(f"{where}: {message}")


def _uff_unit_factor(uff, types, path: Path) -> tuple[float, float]:
    """The length and force factors of the file's units (dataset 164; 1, 1 without one): SI
    is the file's value divided by them."""
    where = np.flatnonzero(np.asarray(types) == 164)
    if not where.size:
        return 1.0, 1.0
    try:
        units = uff.read_sets(int(where[0]))
        length, force = float(units["length"]), float(units["force"])
    except Exception as exc:  # pyuff raises bare Exceptions
        raise _uff_error(path, f"the units dataset 164 cannot be read ({exc}); correct it or "
                               "remove it (SI is then taken)", int(where[0]) + 1) from None
    if not (length > 0 and force > 0 and math.isfinite(length) and math.isfinite(force)):
        raise _uff_error(path, f"the units dataset 164 has length factor {length:g} and force "
                               f"factor {force:g}; both must be positive", int(where[0]) + 1)
    return length, force


def _uff_scale(path: Path, quantity: str, length: float, force: float) -> tuple[float, tuple]:
    """The factor to SI of a record's values and the note to report: to SI divide by the
    factors (dataset 164), so a response over a force is multiplied by force / length, an angular
    speed over a torque (force times length; the radian has no unit factor) by
    force * length."""
    factor = force * length if quantity == "speed_per_torque" else force / length
    notes = () if math.isclose(factor, 1.0) else (
        f"{path.name}: values scaled by {factor:g} to SI (dataset 164: length factor "
        f"{length:g}, force factor {force:g})",)
    return factor, notes


def read_frf_uff(path, quantity: str | None = None) -> list[MeasuredFrf]:
    """Read the FRFs of a Universal File Format file (dataset 58, function type 4).

    Parameters
    ----------
    path : str or os.PathLike
        The file (ASCII or binary dataset 58, as pyuff reads them).
    quantity : str, optional
        The quantity of records whose ordinate type does not say it (default receptance). A
        record that states another is refused.

    Returns
    -------
    list of MeasuredFrf
        One per FRF record, in the file's order, SI units (a dataset 164 is applied).

    Raises
    ------
    FrfFileError
        Naming the file, the record and the fix: not a universal file, no dataset 58, no
        frequency response function among them, a record pyuff cannot read, real values.
    """
    import pyuff

    path = Path(path)
    if not path.is_file():
        raise FrfFileError(f"{path}: no such file" if not path.exists()
                           else f"{path}: is a folder, not a universal file")
    try:
        uff = pyuff.UFF(str(path))
        types = [int(t) for t in uff.get_set_types()]
    except Exception as exc:  # pyuff raises bare Exceptions
        raise _uff_error(path, f"cannot be read as a universal file ({exc}); export the FRFs "
                               "as UFF dataset 58") from None
    if not types:
        raise _uff_error(path, "holds no universal-file dataset (blocks between lines "
                               "'    -1'); export the FRFs as UFF dataset 58")
    records = [i for i, t in enumerate(types) if t == 58]
    if not records:
        found = ", ".join(f"{t} ({_UFF_NAMES.get(t, 'other')})" for t in dict.fromkeys(types))
        raise _uff_error(path, f"holds dataset(s) {found}, no dataset 58 (function at nodal "
                               "DOF); export the FRFs as dataset 58 with function type 4 "
                               "(frequency response function)")
    units = _uff_unit_factor(uff, types, path)
    asked = None if quantity is None else _check_quantity(quantity, "--quantity")
    frfs, skipped = [], []
    for i in records:
        record = i + 1
        try:
            data = uff.read_sets(i)
        except Exception as exc:  # pyuff raises bare Exceptions
            raise _uff_error(path, f"dataset 58 cannot be read ({exc}); re-export it",
                             record) from None
        kind = int(data.get("func_type", -1))
        if kind != 4:
            skipped.append(f"{record} ({_UFF_FUNCTIONS.get(kind, f'type {kind}')})")
            continue
        frfs.append(_uff_record(path, record, data, units, asked))
    if not frfs:
        raise _uff_error(path, "no dataset 58 holds a frequency response function (function "
                               f"type 4); records: {', '.join(skipped)}; export the FRFs")
    if skipped:
        note = (f"{path.name}: records {', '.join(skipped)} are not FRFs (function type 4) and "
                "were left out")
        frfs[0] = replace(frfs[0], notes=(*frfs[0].notes, note))
    return frfs


def _rotational(code) -> bool:
    """Whether a UFF direction code is a rotation (+-4, 5, 6)."""
    try:
        return abs(int(code)) in (4, 5, 6)
    except (TypeError, ValueError):
        return False


def _uff_record(path: Path, record: int, data: dict, units: tuple[float, float],
                asked: str | None) -> MeasuredFrf:
    """One FRF of a dataset-58 record."""
    abscissa = int(data.get("abscissa_spec_data_type", 18) or 18)
    if abscissa not in (0, 18):
        raise _uff_error(path, f"the abscissa is of type {abscissa}, not frequency (18); "
                               "export the FRF over frequency", record)
    values = np.asarray(data.get("data", []))
    x = np.asarray(data.get("x", []), dtype=float)
    if not np.iscomplexobj(values):
        raise _uff_error(path, "holds real values; an FRF is complex (ordinate data type 5 or "
                               "6): export real and imaginary parts", record)
    if values.size < 2 or x.shape != values.shape:
        raise _uff_error(path, f"holds {values.size} values over {x.size} frequencies; an FRF "
                               "needs at least two", record)
    ordinate = int(data.get("ordinate_spec_data_type", 0) or 0)
    denominator = int(data.get("orddenom_spec_data_type", 13) or 13)
    defaults = []
    stated = _UFF_ORDINATES.get(ordinate)
    if stated == "mobility" and _rotational(data.get("rsp_dir")) and _rotational(
            data.get("ref_dir")):
        stated = "speed_per_torque"  # an angular velocity over a moment
    if denominator != 13:
        raise _uff_error(path, f"the ordinate denominator is of type {denominator}, not force "
                               "(13): an FRF over the hammer force is expected", record)
    if stated is None:
        q = asked or "receptance"
        defaults.append(f"{path.name} record {record}: ordinate type {ordinate} does not say the "
                     f"quantity; a {q}" + ("" if asked else " (no --quantity)"))
    elif asked == "speed_per_torque" and stated == "mobility":
        q = asked  # a drive's export need not mark the motor's rotation in the directions
        defaults.append(f"{path.name} record {record}: a velocity over a force (ordinate type "
                        f"{ordinate}, translational directions) taken as speed per torque")
    else:
        if asked is not None and asked != stated:
            raise _uff_error(path, f"holds a {stated} (ordinate type {ordinate}), but a "
                                   f"{asked} was asked for (--quantity, or --kind speed-plant); "
                                   "correct the file or the option", record)
        q = stated
    if x[0] < 0 or np.any(np.diff(x) <= 0) or not np.all(np.isfinite(x)):
        raise _uff_error(path, "the frequencies do not increase from >= 0 Hz", record)
    if not np.all(np.isfinite(values)):
        raise _uff_error(path, "holds values that are not finite", record)
    rsp = f"{data.get('rsp_node', '?')}:{_direction(data.get('rsp_dir'))}"
    ref = f"{data.get('ref_node', '?')}:{_direction(data.get('ref_dir'))}"
    name = f"{path.name} #{record} ({rsp}/{ref})"
    factor, unit_notes = _uff_scale(path, q, *units)
    return MeasuredFrf(2 * math.pi * x, values * factor, q, name, path, tuple(defaults),
                       unit_notes)


def _direction(code) -> str:
    try:
        code = int(code)
    except (TypeError, ValueError):
        return "?"
    names = {1: "+X", 2: "+Y", 3: "+Z", 4: "+RX", 5: "+RY", 6: "+RZ"}
    name = names.get(abs(code), str(code))
    return name if code >= 0 else "-" + name[1:]


def read_frfs(paths, quantity: str | None = None, units: str | None = None
              ) -> list[MeasuredFrf]:
    """Read measured FRFs from CSV and UFF files (by their ending: :data:`UFF_SUFFIXES`).

    Parameters
    ----------
    paths : iterable of str or os.PathLike
        The files.
    quantity : str, optional
        The quantity where a file does not state it (default receptance).
    units : str, optional
        The units of CSV files that do not state them (default SI).

    Returns
    -------
    list of MeasuredFrf
        Every FRF of every file, in order.

    Raises
    ------
    FrfFileError
        Naming the file and the line or record of the first problem.
    """
    out = []
    for path in paths:
        path = Path(path)
        if path.suffix.lower() in UFF_SUFFIXES:
            out.extend(read_frf_uff(path, quantity))
        else:
            out.append(read_frf_csv(path, quantity, units))
    return out
