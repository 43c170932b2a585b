"""Mass and stiffness matrix files: NumPy ``.npz``, MatrixMarket, Harwell-Boeing, MATLAB.

Users bring the FE matrices of their own machine. This module reads them, with a DOF map that
names the rows, and checks them before anything is computed with them:

* ``.npz``: arrays ``mass``, ``stiffness`` and optionally ``dofs`` (what :func:`write_npz`
  writes; sparse matrices are stored as ``<name>_data/_indices/_indptr/_shape`` CSR parts), or a
  single matrix saved with ``scipy.sparse.save_npz``.
* ``.mtx`` / ``.mmf``: MatrixMarket coordinate or array files, general or symmetric storage
  (Ansys ``*EXPORT,Matrix,MMF,file`` writes one triangle of a symmetric matrix).
* ``.hb`` / ``.rsa`` / ``.rua`` / ``.hbmat``: Harwell-Boeing, assembled real matrices, symmetric
  (``RSA``: one triangle stored, as Ansys ``HBMAT`` writes it) or unsymmetric (``RUA``). The
  reader is our own: ``scipy.io.hb_read`` refuses symmetric storage.
  Files written by ``scipy.io.hb_write`` are read too: their fields are narrower than the
  Fortran format they declare (24 characters under ``E25.16``), so a section whose
  blank-separated numbers match the declared count is read by them, any other by the fixed
  Fortran widths (where fields may touch).
* ``.mat``: MATLAB files (v5-v7.2, via ``scipy.io.loadmat``), dense or sparse variables; the
  mass is the variable ``M``/``mass`` and the stiffness ``K``/``stiffness`` unless named.
* ``.op4``: Nastran OUTPUT4 files, ASCII or binary, dense or sparse, through pyyeti's reader
  (``pyyeti.nastran.op4``); one file may hold both matrices (``MAA``/``KAA``, ``MGG``/``KGG``,
  ``M``/``K``, ``MASS``/``STIFFNESS``, or named).

A DOF map is a CSV file with a header row and either a ``name`` column or ``node`` and ``dof``
columns (the name is then ``<node>.<dof>``, e.g. ``12.ux``); an optional ``index`` column
(1-based, like Ansys' "Matrix Eqn" mapping) orders the rows. Without a map the DOFs are named
``dof.1``, ``dof.2``, ... The rows servotune needs under its own names (``pad1.x``, ``wp.x``,
``motor.rotor``, ``encoder.x``) are named from their node numbers and directions by a ports
file (``ports=`` of :func:`read_structure`; see :mod:`servotune.structure.ports`).

References
----------
R. F. Boisvert, R. Pozo, K. A. Remington, "The Matrix Market exchange formats: initial design",
NISTIR 5935 (1996).
I. S. Duff, R. G. Grimes, J. G. Lewis, "Users' guide for the Harwell-Boeing sparse matrix
collection", CERFACS TR/PA/92/86 (1992).
MSC Nastran DMAP Programmer's Guide, OUTPUT4 module (the op4 format); T. P. Widrick, pyYeti,
``pyyeti.nastran.op4`` (the reader used).
"""

from __future__ import annotations

import io
import os
import re
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse
import scipy.sparse.linalg

from ..tablefile import TableFileError, read_table
from .model import ModalModel, UnknownDofError
from .ports import (
    PortError,
    apply_signs,
    name_ports,
    normalise_direction,
    normalise_node,
    port_signs,
    read_ports,
)

__all__ = [
    "MatrixFileError",
    "StructureMatrices",
    "read_coordinates",
    "read_dof_map",
    "read_harwell_boeing",
    "read_matrix",
    "read_op4",
    "read_structure",
    "write_npz",
]

SYMMETRY_TOLERANCE = 1e-8  # max |A - A^T| relative to max |A|
_MTX = (".mtx", ".mmf", ".mm")
_HB = (".hb", ".rsa", ".rua", ".hbmat", ".hbm")
_OP4 = (".op4",)
_MASS_NAMES = ("mass", "m", "mass_matrix", "maa", "mgg", "mff", "mll", "mhh")
_STIFFNESS_NAMES = ("stiffness", "k", "stiffness_matrix", "kaa", "kgg", "kff", "kll", "khh")
#: How to name a matrix the default names miss.
NAME_HINT = ("name it: [structure] mass_name / stiffness_name in axis.toml, --mass-name / "
             "--stiffness-name of servotune check, or mass_name= / stiffness_name= of "
             "read_structure")
_BOTH = (".npz", ".mat", ".op4")  # files that may hold both matrices


class MatrixFileError(TableFileError):
    """A matrix or DOF-map file that cannot be used; the message names the file and the fix."""


# -- single matrices ----------------------------------------------------------------------------
def _fortran_fields(fmt: str, path) -> tuple[int, int]:
    """(count per line, width) of a Fortran format such as ``(8I10)`` or ``(1P,4E20.12)``."""
    m = re.search(r"(\d*)\s*[IEDFG](\d+)", fmt.upper().split(",")[-1])
    if not m:
        raise MatrixFileError(f"{path}: cannot read the Fortran format {fmt.strip()!r}")
    return int(m.group(1) or 1), int(m.group(2))


def _numbers(tokens) -> bool:
    try:
        for t in tokens:
            float(t.upper().replace("D", "E"))
    except ValueError:
        return False
    return True


def _read_fixed(lines, n_values, fmt, path, kind):
    """The values of one section: by blanks when that gives exactly the declared count of
    numbers (scipy's ``hb_write`` writes fields narrower than its declared format), else by the
    Fortran field widths (which is what a format with touching fields needs)."""
    tokens = " ".join(lines).split()
    if len(tokens) == n_values and _numbers(tokens):
        return tokens
    per_line, width = _fortran_fields(fmt, path)
    values = []
    for line in lines:
        line = line.rstrip("\n").rstrip("\r")
        for j in range(per_line):
            field = line[j * width:(j + 1) * width].strip()
            if field:
                values.append(field)
        if len(values) >= n_values:
            break
    if len(values) < n_values:
        raise MatrixFileError(f"{path}: {kind} section ends after {len(values)} of {n_values} "
                              "values; the file is truncated")
    return values[:n_values]


def read_harwell_boeing(path) -> scipy.sparse.csc_array:
    """Read an assembled real Harwell-Boeing matrix, symmetric (RSA) or not (RUA).

    For RSA files (one triangle stored, as Ansys ``HBMAT`` writes) the other triangle is
    filled in, so the result is the full symmetric matrix.

    Parameters
    ----------
    path : str or os.PathLike
        The Harwell-Boeing file.

    Returns
    -------
    scipy.sparse.csc_array
        The matrix.

    Raises
    ------
    MatrixFileError
        Unsupported type (complex, pattern, elemental), malformed header or truncated data.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise MatrixFileError(f"{path}: cannot read the file ({exc})") from None
    lines = text.splitlines()
    try:
        counts = [int(lines[1][14 * j:14 * (j + 1)] or 0) for j in range(5)]
        mxtype = lines[2][:3].upper()
        nrow, ncol, nnz = (int(lines[2][14 + 14 * j:28 + 14 * j]) for j in range(3))
        ptrfmt, indfmt, valfmt = lines[3][:16], lines[3][16:32], lines[3][32:52]
    except (IndexError, ValueError):
        raise MatrixFileError(f"{path}: not a Harwell-Boeing file (the 4-line header cannot be "
                              "read)") from None
    _, ptrcrd, indcrd, valcrd, rhscrd = counts
    if mxtype not in ("RSA", "RUA"):
        raise MatrixFileError(f"{path}: matrix type {mxtype!r} is not supported; export a real "
                              "assembled matrix (RSA or RUA)")
    if valcrd == 0:
        raise MatrixFileError(f"{path}: the file holds no values (pattern only)")
    start = 5 if rhscrd > 0 else 4
    body = lines[start:]
    try:
        ptr = np.array(_read_fixed(body[:ptrcrd], ncol + 1, ptrfmt, path, "pointer"), dtype=int)
        ind = np.array(_read_fixed(body[ptrcrd:ptrcrd + indcrd], nnz, indfmt, path, "index"),
                       dtype=int)
        raw = _read_fixed(body[ptrcrd + indcrd:ptrcrd + indcrd + valcrd], nnz, valfmt, path,
                          "value")
        val = np.array([float(v.upper().replace("D", "E")) for v in raw])
    except ValueError as exc:
        if isinstance(exc, MatrixFileError):
            raise
        raise MatrixFileError(f"{path}: a number cannot be read ({exc})") from None
    if ptr[0] != 1 or ptr[-1] != nnz + 1 or np.any(np.diff(ptr) < 0) or ind.min() < 1 \
            or ind.max() > nrow:
        raise MatrixFileError(f"{path}: inconsistent column pointers or row indices")
    a = scipy.sparse.csc_array((val, ind - 1, ptr - 1), shape=(nrow, ncol))
    if mxtype == "RSA":
        off = a - scipy.sparse.diags_array(a.diagonal())
        a = a + off.T
    return scipy.sparse.csc_array(a)


def read_op4(path) -> dict:
    """Read all matrices of a Nastran OUTPUT4 file (ASCII or binary), by lower-case name.

    Read by pyyeti's ``pyyeti.nastran.op4.read``; dense matrices stay dense arrays, sparse
    ones come as ``scipy.sparse`` arrays.

    Parameters
    ----------
    path : str or os.PathLike
        The OUTPUT4 file.

    Returns
    -------
    dict
        Lower-case matrix name -> numpy.ndarray or scipy.sparse array.

    Raises
    ------
    MatrixFileError
        The file cannot be read as op4.
    """
    path = Path(path)
    if not path.is_file():
        raise MatrixFileError(f"{path}: no such file")
    try:
        from pyyeti.nastran import op4
    except ImportError:  # a dependency; only a broken installation lacks it
        raise MatrixFileError(f"{path}: reading .op4 files needs the pyyeti package "
                              "(pip install pyyeti)") from None
    try:
        data = op4.read(str(path), sparse=None)
    except Exception as exc:
        raise MatrixFileError(f"{path}: cannot read as a Nastran OUTPUT4 (.op4) file "
                              f"({type(exc).__name__}: {exc})") from None
    if not data:
        raise MatrixFileError(f"{path}: the op4 file holds no matrix")
    return {str(k).lower(): v for k, v in data.items()}


def _from_op4(path, names):
    data = read_op4(path)
    for n in names:
        if n.lower() in data:
            return data[n.lower()]
    raise MatrixFileError(f"{path}: none of the matrices {[n.upper() for n in names]} is in "
                          f"the file (it holds {sorted(k.upper() for k in data)}); "
                          f"{NAME_HINT}")


def _from_npz(path, name):
    try:
        data = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as exc:
        if not zipfile.is_zipfile(path):
            raise MatrixFileError(f"{path}: not an .npz archive (numpy.savez writes one: a zip "
                                  "of .npy arrays)") from None
        raise MatrixFileError(f"{path}: cannot read as .npz ({exc})") from None
    with data:
        keys = set(data.files)
        if {"data", "indices", "indptr", "shape", "format"} <= keys:  # scipy.sparse.save_npz
            return scipy.sparse.load_npz(path)
        if name in keys:
            return data[name]
        if f"{name}_data" in keys:
            shape = tuple(int(x) for x in data[f"{name}_shape"])
            return scipy.sparse.csr_array((data[f"{name}_data"], data[f"{name}_indices"],
                                           data[f"{name}_indptr"]), shape=shape)
    raise MatrixFileError(f"{path}: no matrix {name!r} in the file (it holds {sorted(keys)}); "
                          f"save it under the name {name!r}")


def _from_mat(path, names):
    try:
        data = scipy.io.loadmat(path)
    except (OSError, ValueError, NotImplementedError, TypeError,
            scipy.io.matlab.MatReadError) as exc:
        hint = " (MATLAB v7.3 files are HDF5: save with -v7)" if "7.3" in str(exc) \
            or "HDF" in str(exc) else ""
        raise MatrixFileError(f"{path}: cannot read as a MATLAB file ({exc}){hint}") from None
    lookup = {k.lower(): k for k in data if not k.startswith("__")}
    for n in names:
        if n.lower() in lookup:
            return data[lookup[n.lower()]]
    raise MatrixFileError(f"{path}: none of the variables {list(names)} is in the file (it "
                          f"holds {sorted(lookup.values())}); {NAME_HINT}")


def read_matrix(path, name: str | None = None):
    """Read one matrix from a file; the format follows the suffix.

    Parameters
    ----------
    path : path-like
        ``.npz``, ``.mtx``/``.mmf``, a Harwell-Boeing suffix, ``.mat`` or ``.op4``.
    name : str, optional
        The variable or array name in ``.npz``/``.mat``/``.op4`` files (default the mass:
        ``mass``/``M``/``MAA``/``MGG``).

    Returns
    -------
    scipy.sparse.csr_array
    """
    path = Path(path)
    if not path.is_file():
        raise MatrixFileError(f"{path}: no such file")
    suffix = path.suffix.lower()
    try:
        if suffix == ".npz":
            name = name or "mass"
            a = _from_npz(path, name)
        elif suffix in _MTX:
            try:
                a = scipy.io.mmread(path)
            except (ValueError, OSError, IndexError, TypeError) as exc:
                raise MatrixFileError(f"{path}: not a readable MatrixMarket file ({exc})") \
                    from None
        elif suffix in _HB:
            a = read_harwell_boeing(path)
        elif suffix == ".mat":
            a = _from_mat(path, [name] if name else _MASS_NAMES)
        elif suffix in _OP4:
            a = _from_op4(path, [name] if name else _MASS_NAMES)
        else:
            raise MatrixFileError(
                f"{path}: unknown matrix file type {suffix!r}; use .npz, .mtx/.mmf (Matrix"
                f"Market), {'/'.join(_HB)} (Harwell-Boeing), .mat (MATLAB) or .op4 (Nastran "
                "OUTPUT4)")
    except UnicodeDecodeError:
        raise MatrixFileError(f"{path}: not a text file of the expected format") from None
    if scipy.sparse.issparse(a):
        a = scipy.sparse.csr_array(a, dtype=float)
    else:
        a = np.asarray(a)
        if a.dtype.kind not in "iuf" or a.ndim != 2:
            raise MatrixFileError(f"{path}: {name or 'matrix'} is not a real 2-D matrix "
                                  f"(dtype {a.dtype}, {a.ndim} dimensions)")
        a = scipy.sparse.csr_array(a.astype(float))
    if not np.all(np.isfinite(a.data)):
        raise MatrixFileError(f"{path}: the matrix has NaN or infinite entries")
    return a


def read_dof_map(path) -> tuple[str, ...]:
    """Read DOF names from a CSV map.

    The columns are ``name``, or ``node`` and ``dof``; an optional 1-based ``index`` orders the
    rows.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.

    Returns
    -------
    tuple of str
        The DOF names in row order (by ``index`` when given).

    Raises
    ------
    MatrixFileError
        When the file cannot be read or is empty, lacks the columns, has a bad ``index``, an
        empty or a duplicate name, or a ``dof`` that is no direction.
    """
    table = read_table(path, "DOF map", hint="a header row, then one row per DOF",
                       error=MatrixFileError)
    path = table.path
    if table.has("name"):
        names = table.text("name")
    elif table.has("node", "dof"):
        codes = table.text("dof")
        for row, code in enumerate(codes):
            if normalise_direction(code) is None:
                raise MatrixFileError(
                    f"{path}: row {row + 1} of the DOF map has the direction {code!r}, which "
                    "is none of x, y, z, rx, ry, rz (or UX, ..., ROTX, ..., T1-T3, R1-R3, or "
                    "the component numbers 1-6); fix the 'dof' column")
        names = [f"{normalise_node(n)}.{d.lower()}"
                 for n, d in zip(table.text("node"), codes, strict=True)]
    else:
        raise table.error("the DOF map needs a 'name' column or 'node' and 'dof' columns, "
                          f"found {list(table.header)}")
    if table.has("index"):
        try:
            index = [int(v) for v in table.text("index")]
        except ValueError:
            raise table.error("the 'index' column must hold integers") from None
        if sorted(index) != list(range(1, len(index) + 1)):
            raise MatrixFileError(f"{path}: 'index' must number the rows 1..{len(index)} once "
                                  "each")
        names = [n for _, n in sorted(zip(index, names, strict=True))]
    if any(not n for n in names):
        raise MatrixFileError(f"{path}: a DOF name is empty")
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise MatrixFileError(f"{path}: duplicate DOF names {dup[:5]}")
    return tuple(names)


# -- checked pairs --------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class StructureMatrices:
    """Checked FE mass and stiffness (sparse CSR, symmetric) with named DOFs.

    Attributes
    ----------
    mass, stiffness : scipy.sparse.csr_array
    dofs : tuple of str
    source : str
        Where they were read from (for messages).
    """

    mass: scipy.sparse.csr_array
    stiffness: scipy.sparse.csr_array
    dofs: tuple[str, ...]
    source: str = ""

    @property
    def n(self) -> int:
        """Number of DOFs."""
        return len(self.dofs)

    def index(self, names) -> np.ndarray:
        """Return the row indices of DOF names.

        Parameters
        ----------
        names : sequence of str
            DOF names (a sequence; a single str is not taken as one name).

        Returns
        -------
        numpy.ndarray of int
            Their rows (0-based).

        Raises
        ------
        UnknownDofError
            For names the matrices do not have; the message names the file and lists a few
            known names.
        """
        lookup = {d: i for i, d in enumerate(self.dofs)}
        missing = [x for x in names if x not in lookup]
        if missing:
            raise UnknownDofError(f"{self.source}: unknown DOF names {missing}; the DOF map has "
                                  f"{list(self.dofs[:8])}{' ...' if self.n > 8 else ''}")
        return np.array([lookup[x] for x in names], dtype=int)

    def to_modal_model(self, damping_ratio=0.03) -> ModalModel:
        """Return the matrices as a (dense) ModalModel, for models of a few thousand DOFs.

        Parameters
        ----------
        damping_ratio : float or array_like, optional
            Modal damping (see :class:`~servotune.structure.model.ModalModel`; default 0.03).

        Returns
        -------
        ModalModel
            The dense model.

        Raises
        ------
        ValueError
            For more than 5000 DOFs (reduce them first with
            :func:`~servotune.structure.reduction.craig_bampton`).
        """
        if self.n > 5000:
            raise ValueError(f"{self.source}: {self.n} DOFs is too many for a dense model; "
                             "reduce it first with craig_bampton")
        return ModalModel(self.mass.toarray(), self.stiffness.toarray(), self.dofs,
                          damping_ratio=damping_ratio)


def _symmetric(a, label, source, tolerance):
    scale = np.abs(a.data).max() if a.nnz else 0.0
    diff = a - a.T
    asym = np.abs(diff.data).max() if diff.nnz else 0.0
    if asym > tolerance * scale:
        raise MatrixFileError(
            f"{source}: the {label} matrix is not symmetric (max |A - A^T| = {asym:.3g}, "
            f"{asym / scale:.2g} of max |A|, tolerance {tolerance:g}); export the full "
            "symmetric matrix, or check that rows and columns use the same DOF order")
    return scipy.sparse.csr_array((a + a.T) * 0.5)


def _negative_eigenvalues(a) -> int:
    """Number of eigenvalues of symmetric ``a`` below -1e-10 max|diag|, by Sylvester's law of
    inertia on an LDL^T-like factorisation (SuperLU without pivoting, symmetric ordering)."""
    n = a.shape[0]
    diag = np.abs(a.diagonal())
    shift = 1e-10 * max(diag.max(), 1e-300)
    if n <= 3000:
        w = np.linalg.eigvalsh(a.toarray())
        return int(np.sum(w < -shift))
    shifted = scipy.sparse.csc_array(a + shift * scipy.sparse.eye_array(n))
    try:
        lu = scipy.sparse.linalg.splu(shifted, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                      options={"SymmetricMode": True})
    except RuntimeError:
        return 1  # a zero pivot without pivoting: not positive definite
    return int(np.sum(lu.U.diagonal() < 0))


def read_structure(mass, stiffness=None, dof_map=None, *, mass_name=None, stiffness_name=None,
                   symmetry_tolerance: float = SYMMETRY_TOLERANCE, ports=None,
                   coordinates=None, port_tolerance: float = 1e-3) -> StructureMatrices:
    """Read and check a mass/stiffness pair with its DOF names.

    Parameters
    ----------
    mass : path-like
        The mass matrix file; ``.npz``, ``.mat`` and ``.op4`` files may hold both matrices
        (and an ``.npz`` the ``dofs``), then ``stiffness`` may be omitted.
    stiffness : path-like, optional
        The stiffness matrix file.
    dof_map : path-like, optional
        CSV DOF map (see the module docstring); overrides ``dofs`` stored in an ``.npz``.
    mass_name, stiffness_name : str, optional
        Variable names inside ``.npz``/``.mat`` files.
    symmetry_tolerance : float
        Largest accepted max |A - A^T| / max |A|.
    ports : path-like or sequence of Port, optional
        Names for rows of the DOF map given by node number (or position) and direction (see
        :mod:`servotune.structure.ports`), e.g. ``pad1.x`` for node 1204 UX; a port with a
        minus sign (``-UX``) is the negative of its row: its row and column of M and K are
        multiplied by -1 (:func:`~servotune.structure.ports.apply_signs`).
    coordinates : path-like or mapping node -> (x, y, z), optional
        Node positions [m] (CSV ``node,x,y,z``), for ports given by position.
    port_tolerance : float
        Largest distance [m] between a port's position and its node.

    Returns
    -------
    StructureMatrices
        The checked matrices (sparse CSR, symmetric) with the DOF names (ports renamed) and
        the source.

    Raises
    ------
    MatrixFileError
        Unreadable file; non-square, mismatched, asymmetric matrices; a mass matrix with a
        negative eigenvalue (indefinite); a DOF map of the wrong length; a port that is not in
        the export.

    Examples
    --------
    Ports named from node numbers of an export (``ports.csv``: ``port,node,direction`` rows
    ``wp.x,1207,UX`` and ``motor.rotor,9001,ROTX``)::

        data = read_structure("M.mtx", "K.mtx", "dofs.csv", ports="ports.csv")
        data.index(["wp.x", "motor.rotor"])
    """
    mass = Path(mass)
    stiffness_path = mass if stiffness is None else Path(stiffness)
    source = str(mass) if stiffness is None else f"{mass} + {stiffness_path}"
    if stiffness is None and mass.suffix.lower() not in _BOTH:
        raise MatrixFileError(f"{mass}: give the stiffness file too (only .npz, .mat and .op4 "
                              "files hold both matrices)")
    m = read_matrix(mass, mass_name)
    if stiffness_path.suffix.lower() in (".mat", ".op4"):
        reader = _from_mat if stiffness_path.suffix.lower() == ".mat" else _from_op4
        k = reader(stiffness_path, [stiffness_name] if stiffness_name else _STIFFNESS_NAMES)
        k = scipy.sparse.csr_array(k, dtype=float)
        if not np.all(np.isfinite(k.data)):
            raise MatrixFileError(f"{stiffness_path}: the matrix has NaN or infinite entries")
    else:
        k = read_matrix(stiffness_path, stiffness_name or "stiffness")
    for label, a, p in (("mass", m, mass), ("stiffness", k, stiffness_path)):
        if a.shape[0] != a.shape[1]:
            raise MatrixFileError(f"{p}: the {label} matrix is not square (shape {a.shape})")
    if m.shape != k.shape:
        raise MatrixFileError(f"{source}: mass is {m.shape[0]}x{m.shape[0]} but stiffness is "
                              f"{k.shape[0]}x{k.shape[0]}; both must describe the same DOFs")
    m = _symmetric(m, "mass", mass, symmetry_tolerance)
    k = _symmetric(k, "stiffness", stiffness_path, symmetry_tolerance)
    if _negative_eigenvalues(m):
        raise MatrixFileError(f"{mass}: the mass matrix is indefinite (it has a negative "
                              "eigenvalue); check the export (mass units, sign of entries)")
    if dof_map is not None:
        dofs = read_dof_map(dof_map)
    elif mass.suffix.lower() == ".npz" and "dofs" in np.load(mass, allow_pickle=False).files:
        dofs = tuple(str(x) for x in np.load(mass, allow_pickle=False)["dofs"])
    else:
        dofs = tuple(f"dof.{j + 1}" for j in range(m.shape[0]))
    if len(dofs) != m.shape[0]:
        raise MatrixFileError(f"{dof_map or mass}: the DOF map names {len(dofs)} DOFs but the "
                              f"matrices have {m.shape[0]}")
    if ports is not None:
        if coordinates is not None and isinstance(coordinates, (str, os.PathLike)):
            coordinates = read_coordinates(coordinates)
        try:
            given = read_ports(ports) if isinstance(ports, (str, os.PathLike)) else ports
            signs = port_signs(dofs, given, coordinates, port_tolerance)
            dofs = name_ports(dofs, given, coordinates, port_tolerance)
        except PortError as exc:
            where = f"{ports}: " if isinstance(ports, (str, os.PathLike)) \
                and str(ports) not in str(exc) else ""
            raise MatrixFileError(f"{where}{exc}") from None
        m, k = apply_signs(m, signs), apply_signs(k, signs)  # -UX: q_port = -q_export
    return StructureMatrices(m, k, dofs, source)


def write_npz(path, mass, stiffness, dofs, force: bool = False) -> Path:
    """Write mass, stiffness and DOF names to ``.npz``.

    Dense arrays stay dense, sparse ones are stored as CSR parts; the file is written to a
    temporary name and renamed, and an existing file is never overwritten unless ``force``.

    Parameters
    ----------
    path : str or os.PathLike
        The file, ending in ``.npz``; missing parent folders are created.
    mass, stiffness : (n, n) sparse matrix or array_like
        The matrices [kg, N/m, ...].
    dofs : sequence of str
        The n DOF names.
    force : bool, optional
        Overwrite an existing file (default False).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ValueError
        When the name does not end in ``.npz`` or a matrix is not n x n.
    FileExistsError
        When the file exists and ``force`` is False.
    """
    path = Path(path)
    if path.suffix.lower() != ".npz":
        raise ValueError(f"{path}: the file name must end in .npz")
    if path.exists() and not force:
        raise FileExistsError(f"{path} exists; pass force=True (--force) to overwrite it")
    dofs = np.array([str(d) for d in dofs])
    arrays = {"dofs": dofs}
    for name, a in (("mass", mass), ("stiffness", stiffness)):
        if scipy.sparse.issparse(a):
            a = scipy.sparse.csr_array(a, dtype=float)
            if a.shape != (dofs.size, dofs.size):
                raise ValueError(f"{name} is {a.shape} but there are {dofs.size} DOF names")
            arrays.update({f"{name}_data": a.data, f"{name}_indices": a.indices,
                           f"{name}_indptr": a.indptr, f"{name}_shape": np.array(a.shape)})
        else:
            a = np.asarray(a, dtype=float)
            if a.shape != (dofs.size, dofs.size):
                raise ValueError(f"{name} is {a.shape} but there are {dofs.size} DOF names")
            arrays[name] = a
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(buffer.getvalue())
        os.replace(tmp, path)  # atomic: a crash never leaves half a file
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path



def read_coordinates(path) -> dict[str, np.ndarray]:
    """Read node coordinates [m] from a CSV file with a header ``node,x,y,z``.

    For the geometric rigid-body motions of :func:`servotune.structure.cb_check` and for ports
    given by position. Integer node ids are normalised (``"0012"`` and ``"12.0"`` are node 12).

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.

    Returns
    -------
    dict
        Node id (str) -> position, numpy array (3,) [m].

    Raises
    ------
    MatrixFileError
        When the file cannot be read, lacks the header, or a node is missing, listed twice or
        has a coordinate that is not a finite number.
    """
    hint = "a header row node,x,y,z and one row per node"
    table = read_table(path, "coordinates", hint=hint, error=MatrixFileError)
    table.require("node", "x", "y", "z", hint=hint)
    out = {}
    for i, r in enumerate(table.records()):
        node = normalise_node(r["node"])
        if not node:
            raise table.error("a row has no node id", i)
        if node in out:
            raise table.error(f"node {node} is listed twice", i)
        try:
            out[node] = np.array([float(r[c]) for c in "xyz"])
        except ValueError:
            raise table.error(f"node {r['node']!r} has a coordinate that is not a number",
                              i) from None
        if not np.all(np.isfinite(out[node])):
            raise table.error(f"node {node} has a coordinate that is not finite", i)
    return out
