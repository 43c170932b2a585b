"""Reading table files (CSV): one reader, one error type, messages that name file and line.

Every CSV file servotune reads (measured FRFs, friction measurements, DOF maps, node
coordinates, ports of an FE export) goes through :func:`read_table`: the file is read whole,
blank rows and rows whose first cell starts with ``#`` are skipped, the header is lower-cased
and stripped, and every value problem is raised as :class:`TableFileError` naming the file, the
line and what to write instead.

Examples
--------
>>> import tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "friction.csv"
>>> _ = path.write_text("# a comment\\nv_m_per_s, F_N\\n0.01, 1200\\n0.02, 1150\\n")
>>> table = read_table(path, "friction data")
>>> table.header, table.numbers("f_n").tolist()
(('v_m_per_s', 'f_n'), [1200.0, 1150.0])
>>> _ = path.write_text("v_m_per_s,f_n\\n0.01,1200\\n0.02,fast\\n")
>>> read_table(path, "friction data").numbers("f_n")
Traceback (most recent call last):
    ...
servotune.tablefile.TableFileError: ...friction.csv, line 3: column 'f_n' holds 'fast', not a number
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["TableFileError", "TableFile", "read_table"]


class TableFileError(ValueError):
    """A table file (CSV) that cannot be used; the message names the file, the line and the
    fix."""


@dataclass(frozen=True)
class TableFile:
    """The rows of a CSV file under its header.

    Attributes
    ----------
    path : pathlib.Path
        The file.
    what : str
        What the file holds, in words ("DOF map"), for messages.
    header : tuple of str
        The column names, stripped and lower-cased.
    rows : tuple of tuple of str
        The data rows (each value stripped), comments and blank rows left out.
    lines : tuple of int
        The line number in the file of each data row (1-based).
    error_type : type
        The :class:`TableFileError` (sub)class raised for this file.
    """

    path: Path
    what: str
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    lines: tuple[int, ...]
    error_type: type = TableFileError

    def error(self, message: str, row: int | None = None) -> TableFileError:
        """Return the error for a problem of the file or of one of its rows.

        Parameters
        ----------
        message : str
            What is wrong and how to fix it.
        row : int, optional
            Index of the data row (its file line is named).

        Returns
        -------
        TableFileError
            To be raised by the caller.
        """
        where = str(self.path) if row is None else f"{self.path}, line {self.lines[row]}"
        return self.error_type(f"{where}: {message}")

    def has(self, *names: str) -> bool:
        """Return whether the header has every one of the columns.

        Parameters
        ----------
        *names : str
            Column names (lower case).

        Returns
        -------
        bool
            True when all are present.
        """
        return all(n in self.header for n in names)

    def require(self, *names: str, hint: str = "") -> None:
        """Raise when a column is missing.

        Parameters
        ----------
        *names : str
            Column names (lower case) that must be present.
        hint : str
            What the file should look like, added to the message.

        Raises
        ------
        TableFileError
            Naming the missing columns and those found.
        """
        missing = [n for n in names if n not in self.header]
        if missing:
            raise self.error(f"the {self.what} needs the column(s) {', '.join(missing)}; found "
                             f"{', '.join(self.header) or 'none'}" + (f" ({hint})" if hint else ""))

    def text(self, name: str) -> list[str]:
        """Return the values of a column as text (empty for a short row).

        Parameters
        ----------
        name : str
            Column name (lower case).

        Returns
        -------
        list of str
            One value per data row.
        """
        j = self.header.index(name)
        return [r[j] if j < len(r) else "" for r in self.rows]

    def records(self) -> list[dict[str, str]]:
        """Return each data row as a dict by column name.

        Returns
        -------
        list of dict
            Column name -> value (text; empty for a missing value).
        """
        return [{h: (r[j] if j < len(r) else "") for j, h in enumerate(self.header)}
                for r in self.rows]

    def numbers(self, name: str, finite: bool = True) -> np.ndarray:
        """Return a column as numbers.

        Parameters
        ----------
        name : str
            Column name (lower case).
        finite : bool
            Refuse inf and nan.

        Returns
        -------
        numpy.ndarray
            One float per data row.

        Raises
        ------
        TableFileError
            Naming the line of the first value that is not a (finite) number.
        """
        self.require(name)
        out = np.empty(len(self.rows))
        for i, value in enumerate(self.text(name)):
            try:
                out[i] = float(value)
            except ValueError:
                shown = value if value else "nothing"
                raise self.error(f"column {name!r} holds {shown!r}, not a number", i) from None
            if finite and not math.isfinite(out[i]):
                raise self.error(f"column {name!r} holds {value!r}, not a finite number", i)
        return out


def read_table(path, what: str, min_rows: int = 1, hint: str = "",
               error: type = TableFileError) -> TableFile:
    """Read a CSV file with a header row.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What it holds, in words ("measured FRF"), for messages.
    min_rows : int
        Fewest data rows accepted.
    hint : str
        What the file should look like (e.g. its header), added to the messages about its
        shape.
    error : type
        A subclass of :class:`TableFileError` to raise instead (the error type of the file's
        domain, e.g. :class:`servotune.structure.io.MatrixFileError`).

    Returns
    -------
    TableFile
        The header (lower case) and the data rows with their line numbers.

    Raises
    ------
    TableFileError
        When the file cannot be read (missing, unreadable, not text, not CSV) or has fewer than
        ``min_rows`` data rows.
    """
    if not (isinstance(error, type) and issubclass(error, TableFileError)):
        raise TypeError("read_table: error must be a subclass of TableFileError")
    path = Path(path)
    try:
        with open(path, newline="") as handle:
            raw = list(csv.reader(handle))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise error(f"{path}: cannot read the {what} ({exc})") from None
    kept = [(i + 1, [v.strip() for v in r]) for i, r in enumerate(raw)
            if r and any(v.strip() for v in r) and not r[0].lstrip().startswith("#")]
    suffix = f" ({hint})" if hint else ""
    if not kept:
        raise error(f"{path}: the {what} is empty{suffix}")
    header = tuple(h.lower() for h in kept[0][1])
    rows = kept[1:]
    if len(rows) < min_rows:
        raise error(f"{path}: the {what} needs a header row and at least {min_rows} "
                             f"data row(s), found {len(rows)}{suffix}")
    return TableFile(path, what, header, tuple(tuple(r) for _, r in rows),
                     tuple(line for line, _ in rows), error)
