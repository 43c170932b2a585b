"""Sparse factorisations, Sturm counts and the lowest modes of K phi = lambda M phi.

The modes of a structure are computed as the structural-dynamics codes do it, with every copy
of a repeated eigenvalue kept and the result checked:

* **dense or iterative, chosen up front.** Small problems (n <= ``DENSE_MAX``) and problems
  where many modes of a mid-sized model are wanted (count >= ``DENSE_FRACTION`` n with
  n <= ``DENSE_LIMIT``) are solved densely (LAPACK, all modes at once); everything else by
  shift-invert Lanczos (ARPACK's ``eigsh``) with one sparse factorisation of K - sigma M that
  the caller may hand in (the Craig-Bampton reduction reuses the factors of K_ii it needs for
  the constraint modes). When the modes are wanted below a frequency, their number is known
  before the Lanczos run from a Sturm count (below), so no run is repeated with a larger count.
* **a random start vector.** A Krylov method only finds eigenvectors present in its start
  vector; a structured start such as all ones has no component on the antisymmetric modes of
  a symmetric structure, and a single-vector Lanczos finds one vector of a repeated eigenvalue
  per run in exact arithmetic (Bai et al. 2000, sec 4.4.4). The start is a seeded Gaussian
  vector, so runs are reproducible.
* **a Sturm sequence check.** By Sylvester's law of inertia the number of negative pivots of an
  LDL^T factorisation of K - s M is the number of eigenvalues below s (K positive definite or
  semi-definite, M semi-definite). After the Lanczos run this count is compared with the modes
  found below s (s in a gap above the last wanted mode); the check is what MSC/NX Nastran
  (``EIGRL`` ``SCHECK``) and Ansys (``LANBOPTION,,ON``) perform to make sure no mode is missed.
  The factors of K used by the Lanczos run are freed first, and the count's factorisation
  reuses their fill-reducing ordering, so the check adds no memory and no second ordering.
* **deflated restarts.** When the count shows missed modes (copies of a repeated eigenvalue),
  Lanczos is run again on the operator with the modes found so far projected out (the first
  remedy of Bai et al. 2000, sec 4.4.4), until the count agrees.

The Sturm count uses SuperLU with a symmetric ordering, diagonal pivots only and
``SymmetricMode``: the factors are then P A P^T = L D L^T with D the diagonal of U, and the
same-permutation condition is checked (a zero pivot would make SuperLU pivot off the diagonal;
the shift is then moved slightly and the count repeated). The diagonal of U is read from
SuperLU's own supernodal storage in place (scipy hands U out only as a converted copy of both
factors, as large as the factors themselves); the reading checks the layout it relies on and
falls back to scipy's copy when anything does not match.

References
----------
Z. Bai, J. Demmel, J. Dongarra, A. Ruhe, H. van der Vorst (eds.), Templates for the Solution of
Algebraic Eigenvalue Problems, SIAM (2000), sec 4.4.4 (multiple eigenvalues) and 4.5
(spectral transformation).
R. G. Grimes, J. G. Lewis, H. D. Simon, "A shifted block Lanczos algorithm for solving sparse
symmetric generalized eigenproblems", SIAM J. Matrix Anal. Appl. 15 (1994) 228-272 (the
algorithm of MSC Nastran, with its Sturm sequence checks).
"""

from __future__ import annotations

import ctypes
import math
import sys
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

__all__ = [
    "DENSE_MAX",
    "DENSE_FRACTION",
    "DENSE_LIMIT",
    "SOLVERS",
    "Modes",
    "count_eigenvalues_below",
    "factorise",
    "lowest_modes",
    "pardiso_available",
]

SOLVERS = ("auto", "superlu", "pardiso")
#: Up to this size the modes are always computed densely.
DENSE_MAX = 1500
#: Above DENSE_MAX and up to DENSE_LIMIT, dense when at least this share of the modes is wanted.
DENSE_FRACTION = 0.1
DENSE_LIMIT = 8000
#: Above this size the pivots of a factorisation are not checked (see _SuperLUFactor).
PIVOT_CHECK_MAX = DENSE_MAX
#: Restarts with deflation after a failed check before giving up.
MAX_RESTARTS = 20
_SEED = 20140101  # start vectors are reproducible


def pardiso_available() -> bool:
    """Return whether the optional ``pypardiso`` package (Intel MKL PARDISO) can be imported.

    Returns
    -------
    bool
        True when it can be imported.
    """
    try:
        import pypardiso  # noqa: F401
    except ImportError:
        return False
    return True


class _SuperLUFactor:
    """SuperLU factors with diagonal pivots in a symmetric ordering (an LDL^T in effect).

    Factorised on construction, or at the first :meth:`solve` when ``lazy``; :meth:`release`
    frees the factors and a later :meth:`solve` factorises again."""

    def __init__(self, a, name, mechanism, lazy=False):
        self._a = scipy.sparse.csc_array(a)
        self._name, self._mechanism = name, mechanism
        self._lu = None
        #: The symmetric fill-reducing ordering of the factors (SuperLU's perm_c), once known.
        self.ordering = None
        if not lazy:
            self._factorise()

    def _factorise(self):
        try:
            lu = _superlu(self._a)
        except RuntimeError as exc:
            raise ValueError(self._mechanism) from exc
        self.ordering = lu.perm_c.copy()
        if self._a.shape[0] > PIVOT_CHECK_MAX:
            # on large models an indefinite or nearly singular matrix shows in the eigenvalues
            # instead
            self._lu = lu
            return
        pivots = lu.U.diagonal()
        scale = np.abs(pivots).max() if pivots.size else 1.0
        if np.any(pivots < -1e-13 * scale):
            raise ValueError(
                f"the matrix {self._name} is not positive definite ({int(np.sum(pivots < 0))} "
                "negative pivots): check the signs and units of the stiffness export")
        if not np.all(np.isfinite(pivots)) or np.abs(pivots).min() <= 1e-13 * scale:
            raise ValueError(self._mechanism + " (singular to working precision)")
        self._lu = lu

    def solve(self, b):
        if self._lu is None:
            self._factorise()
        b = np.asarray(b, dtype=float)
        if b.ndim == 1:
            return self._lu.solve(b)
        # scipy's SuperLU solves several right-hand sides 2-3x slower than one at a time
        out = np.empty_like(b)
        for j in range(b.shape[1]):
            out[:, j] = self._lu.solve(np.ascontiguousarray(b[:, j]))
        return out

    def release(self) -> None:
        self._lu = None


class _PardisoFactor:
    """Cholesky factors of an SPD matrix by Intel MKL PARDISO (optional, ``pypardiso``)."""

    def __init__(self, a, name, mechanism, lazy=False):
        self._upper = scipy.sparse.triu(a, format="csr")
        self._upper.sort_indices()
        self._mechanism = mechanism
        self._solver = None
        if not lazy:
            self._factorise()

    def _factorise(self):
        import pypardiso

        self._solver = pypardiso.PyPardisoSolver(mtype=2)  # real symmetric positive definite
        try:
            self._solver.factorize(self._upper)
        except pypardiso.pardiso_wrapper.PyPardisoError as exc:
            self._solver = None
            raise ValueError(self._mechanism + f" (PARDISO: {exc})") from None
        self._solver.set_phase(33)  # solves only from here on

    def solve(self, b):
        if self._solver is None:
            self._factorise()
        b = np.asfortranarray(b, dtype=float)
        # pypardiso's public solve() compares the whole matrix with the factorised one on every
        # call; the factors are known to be current here, so the solve phase is called directly
        return self._solver._call_pardiso(self._upper, b)

    def release(self) -> None:
        if self._solver is not None:
            self._solver.free_memory(everything=True)
            self._solver = None


def _superlu(a, permc_spec="MMD_AT_PLUS_A"):
    return scipy.sparse.linalg.splu(scipy.sparse.csc_array(a), permc_spec=permc_spec,
                                    diag_pivot_thresh=0.0, options={"SymmetricMode": True})


# Layout of scipy's SuperLU object and of SuperLU's supernodal L (scipy/sparse/linalg/_dsolve/
# _superluobject.h, SuperLU's supermatrix.h): PyObject_HEAD, npy_intp m, n, SuperMatrix L, U
# (Stype, Dtype, Mtype, nrow, ncol as 32-bit ints, then the Store pointer), int *perm_r, ...
_SLU_SC, _SLU_D, _SLU_TRLU = 3, 1, 1
_LU_DIAGONAL_IN_PLACE = None  # decided by a self-test on first use


def _int32_view(address, size):
    return np.frombuffer((ctypes.c_int32 * size).from_address(address), dtype=np.int32)


def _u_diagonal_in_place(lu):
    """diag(U) of scipy's SuperLU factors read from the supernodal L in place, or None when the
    object does not have the expected layout (checked field by field before any pointer is
    followed: sizes, storage type, and perm_r against the array scipy reports)."""
    n = lu.shape[0]
    base = id(lu)  # CPython: the object's address
    if tuple((ctypes.c_ssize_t * 2).from_address(base + 16)) != (n, n):
        return None
    header = tuple((ctypes.c_int32 * 5).from_address(base + 32))
    if header != (_SLU_SC, _SLU_D, _SLU_TRLU, n, n):
        return None
    store = ctypes.c_void_p.from_address(base + 56).value
    perm_r = ctypes.c_void_p.from_address(base + 96).value
    if not store or not perm_r or not np.array_equal(_int32_view(perm_r, n), lu.perm_r):
        return None
    nsuper = ctypes.c_int32.from_address(store + 4).value
    if not 0 <= nsuper < n:
        return None
    nzval, nzval_colptr, rowind, rowind_colptr, col_to_sup, sup_to_col = (
        ctypes.c_void_p * 6).from_address(store + 8)
    if not all((nzval, nzval_colptr, rowind, rowind_colptr, col_to_sup, sup_to_col)):
        return None
    sup_to_col = _int32_view(sup_to_col, nsuper + 2)
    col_to_sup = _int32_view(col_to_sup, n)
    nzval_colptr = _int32_view(nzval_colptr, n + 1)
    rowind_colptr = _int32_view(rowind_colptr, n + 1)
    if (sup_to_col[0] != 0 or sup_to_col[-1] != n or np.any(np.diff(sup_to_col) <= 0)
            or col_to_sup.min() < 0 or col_to_sup.max() > nsuper
            or nzval_colptr[0] != 0 or np.any(np.diff(nzval_colptr) <= 0)
            or rowind_colptr[0] != 0 or np.any(np.diff(rowind_colptr) < 0)):
        return None
    cols = np.arange(n)
    first = sup_to_col[col_to_sup]  # first column of each column's supernode
    offset = cols - first
    if np.any(offset < 0) or np.any(cols >= sup_to_col[col_to_sup + 1]):
        return None
    # each supernode lists its diagonal block's rows first, in order: row j of column j is at
    # position j - first in both the row subscripts and the column's values
    row_of_diagonal = _int32_view(rowind, int(rowind_colptr[-1]))[rowind_colptr[first] + offset]
    if not np.array_equal(row_of_diagonal, cols):
        return None
    values = np.frombuffer((ctypes.c_double * int(nzval_colptr[-1])).from_address(nzval),
                           dtype=float)
    return values[nzval_colptr[:-1] + offset].copy()


def _in_place_reading_works() -> bool:
    """Compare the in-place reading with scipy's copy of U on a small random factorisation."""
    rng = np.random.default_rng(_SEED)
    n = 120
    a = scipy.sparse.random_array((n, n), density=0.03, rng=rng)
    a = (a @ a.T + scipy.sparse.diags_array(rng.uniform(-1.0, 2.0, n))).tocsc()
    try:
        lu = _superlu(a)
        d = _u_diagonal_in_place(lu)
        return d is not None and np.array_equal(d, lu.U.diagonal())
    except (RuntimeError, IndexError, ValueError, OverflowError):  # use scipy's copy
        return False


def _u_diagonal(lu) -> np.ndarray:
    """The diagonal of U of scipy's SuperLU factors, without copying the factors when
    possible."""
    global _LU_DIAGONAL_IN_PLACE
    if _LU_DIAGONAL_IN_PLACE is None:
        _LU_DIAGONAL_IN_PLACE = (sys.implementation.name == "cpython" and sys.maxsize > 2**32
                                 and _in_place_reading_works())
    if _LU_DIAGONAL_IN_PLACE:
        try:
            d = _u_diagonal_in_place(lu)
        except (IndexError, ValueError, OverflowError):  # an index outside the views
            d = None
        if d is not None:
            return d
    return lu.U.diagonal()


def factorise(a, solver: str = "auto", *, name: str = "K_ii", mechanism: str | None = None,
              lazy: bool = False):
    """Factorise a sparse symmetric positive definite matrix.

    Parameters
    ----------
    a : (n, n) sparse matrix
        Symmetric positive definite (a stiffness, possibly shifted: K - sigma M, sigma < 0).
    solver : {"auto", "superlu", "pardiso"}
        SuperLU (scipy; symmetric ordering, no pivoting, so the pivots are those of an LDL^T)
        or PARDISO (``pypardiso``, optional); "auto" takes PARDISO for n > 5000 when installed.
    name : str
        What the matrix is, for the error messages.
    mechanism : str, optional
        The message for a singular matrix (default: a generic one naming ``name``).
    lazy : bool
        Factorise at the first solve instead of now (then the errors come from there).

    Returns
    -------
    object
        The factors, with the methods ``solve(b)`` (K^-1 b for a vector or an (n, k) array)
        and ``release()`` (frees the factors).

    Raises
    ------
    ValueError
        A singular or indefinite matrix, with the message saying what that means (when
        ``lazy``, at the first solve); an unknown ``solver``, or "pardiso" without pypardiso.
    """
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {SOLVERS}, got {solver!r}")
    mechanism = mechanism or (f"the matrix {name} is singular: the structure can move without "
                              "straining (a mechanism or a rigid-body motion); add supports")
    if solver == "pardiso" or (solver == "auto" and pardiso_available() and a.shape[0] > 5000):
        if not pardiso_available():
            raise ValueError("solver='pardiso' needs the pypardiso package "
                             "(pip install 'servotune[fast]'), or use solver='superlu'")
        return _PardisoFactor(a, name, mechanism, lazy)
    return _SuperLUFactor(a, name, mechanism, lazy)


def count_eigenvalues_below(k, m, value: float, *, ordering=None) -> int:
    """Number of eigenvalues lambda of K phi = lambda M phi below ``value`` (Sturm count).

    The count of negative pivots of an LDL^T factorisation of K - value M (Sylvester's law of
    inertia); K symmetric positive semi-definite, M symmetric positive semi-definite. Dense
    eigenvalues for n <= 200.

    Parameters
    ----------
    k : (n, n) sparse matrix or array_like
        Stiffness K, symmetric positive semi-definite.
    m : (n, n) sparse matrix or array_like
        Mass M, symmetric positive semi-definite.
    value : float
        The shift lambda = omega^2 [rad^2/s^2].
    ordering : (n,) array_like of int, optional
        A symmetric fill-reducing ordering for the pattern of K - value M (SuperLU's ``perm_c``
        of a factorisation of K, e.g. ``factorise(k).ordering``): reused instead of computing
        a new one (default: SuperLU's minimum degree on A^T + A).

    Returns
    -------
    int
        The number of eigenvalues below ``value``.

    Raises
    ------
    ValueError
        When SuperLU cannot factorise K - value M with diagonal pivots at six shifts near
        ``value`` (n > 200 only).

    Examples
    --------
    Three uncoupled unit masses on springs 1, 4 and 9: two eigenvalues lie below 5.

    >>> import scipy.sparse as sp
    >>> count_eigenvalues_below(sp.diags_array([1.0, 4.0, 9.0]), sp.eye_array(3), 5.0)
    2
    """
    k = scipy.sparse.csc_array(k, dtype=float)
    m = scipy.sparse.csc_array(m, dtype=float)
    n = k.shape[0]
    if n <= 200:
        # K - value M congruent to a diagonal: inertia from the dense symmetric eigenvalues
        w = np.linalg.eigvalsh((k - value * m).toarray())
        return int(np.sum(w < 0))
    if ordering is not None:
        # P (K - s M) P^T in the given order: a congruence, same inertia, no new ordering
        ordering = np.asarray(ordering)
        if ordering.shape != (n,) or not np.array_equal(np.sort(ordering), np.arange(n)):
            raise ValueError(f"ordering must be a permutation of 0..{n - 1}")
        inverse = np.argsort(ordering)
    step = 1e-10 * max(abs(value), 1e-300)
    for attempt in range(6):
        shifted = value + attempt * step * (-1) ** attempt
        a = (k - shifted * m).tocsc()
        if ordering is not None:
            a = a[inverse][:, inverse].tocsc()
        try:
            lu = _superlu(a, "NATURAL" if ordering is not None else "MMD_AT_PLUS_A")
        except RuntimeError:
            continue  # exactly singular: an eigenvalue at the shift; move it slightly
        finally:
            del a
        if not np.array_equal(lu.perm_r, lu.perm_c):
            del lu
            continue  # SuperLU pivoted off the diagonal: the inertia is not in diag(U)
        d = _u_diagonal(lu)
        del lu
        if np.all(np.isfinite(d)) and np.all(d != 0):
            return int(np.sum(d < 0))
    raise ValueError(f"the Sturm count at {value:.6g} failed (SuperLU could not factorise "
                     "K - s M with diagonal pivots near that shift)")


@dataclass(frozen=True, eq=False)
class Modes:
    """Lowest modes of K phi = lambda M phi.

    Attributes
    ----------
    eigenvalues : (k,) ndarray
        lambda = omega^2 [rad^2/s^2], ascending.
    vectors : (n, k) ndarray
        Mass-normalised mode shapes (phi^T M phi = I).
    method : str
        "dense" or "lanczos".
    complete_below : float
        Every eigenvalue below this value is among ``eigenvalues`` (from the dense solution
        or a Sturm count); ``inf`` when all modes of the model are there.
    next_eigenvalue : float
        The first eigenvalue not returned (``inf`` when there is none, ``nan`` when unknown).
    restarts : int
        Deflated Lanczos restarts the Sturm check asked for (0 when the first run found all).
    """

    eigenvalues: np.ndarray
    vectors: np.ndarray
    method: str
    complete_below: float
    next_eigenvalue: float
    restarts: int = 0


def _dense_modes(k, m, shift, count=None):
    """All finite modes of (K, M), K - shift M positive definite, M only semi-definite: the
    eigenvalues mu = 1/(lambda - shift) of L^-1 M L^-T, K - shift M = L L^T (massless DOFs have
    none)."""
    a = (k - shift * m).toarray() if scipy.sparse.issparse(k) else np.asarray(k - shift * m)
    mm = m.toarray() if scipy.sparse.issparse(m) else np.asarray(m)
    try:
        low = np.linalg.cholesky(0.5 * (a + a.T))
    except np.linalg.LinAlgError:
        raise ValueError("the stiffness is not positive definite: the structure with the "
                         "boundary DOFs held still has a mechanism; add boundary DOFs or "
                         "supports") from None
    c = scipy.linalg.solve_triangular(low, scipy.linalg.solve_triangular(low, mm, lower=True).T,
                                      lower=True)
    c = 0.5 * (c + c.T)
    n = c.shape[0]
    if count is not None and count + 1 < n:  # only the largest mu (the lowest modes) and one
        mu, v = scipy.linalg.eigh(c, subset_by_index=[n - count - 1, n - 1])
    else:
        mu, v = np.linalg.eigh(c)
    mu, v = mu[::-1], v[:, ::-1]
    finite = int(np.sum(mu > 1e-12 * max(mu[0], 1e-300)))
    phi = scipy.linalg.solve_triangular(low.T, v[:, :finite], lower=False)
    return shift + 1.0 / mu[:finite], phi / np.sqrt(mu[:finite])  # phi^T M phi = I


def _m_normalise(phi, m):
    norms = np.sqrt(np.einsum("ij,ij->j", phi, m @ phi))
    return phi / norms


def _rayleigh_ritz(k, m, basis):
    """Ritz pairs of (K, M) on the span of ``basis`` (columns), ascending, M-normalised."""
    mb = m @ basis
    kb = k @ basis
    g_m = basis.T @ mb
    g_k = basis.T @ kb
    w, y = scipy.linalg.eigh(0.5 * (g_k + g_k.T), 0.5 * (g_m + g_m.T))
    return w, _m_normalise(basis @ y, m)


def _lanczos(k, m, count, shift, factor, v0, tol, deflate=None):
    """``count`` eigenpairs nearest ``shift`` by shift-invert ARPACK; with ``deflate`` (found
    M-orthonormal modes) they are projected out of the operator and the start vector."""
    n = k.shape[0]

    if deflate is None:
        matvec = factor.solve
    else:
        md = m @ deflate

        def matvec(x):
            y = factor.solve(x)
            return y - deflate @ (md.T @ y)

        v0 = v0 - deflate @ (md.T @ v0)
    op = scipy.sparse.linalg.LinearOperator((n, n), matvec=matvec, dtype=float)
    # tol on the Ritz values of (K - sigma M)^-1 M: eigenvector errors ~1e-8, eigenvalues
    # (Rayleigh quotients, refined below) exact to ~1e-15; it saves about a sixth of the solves
    # of tol = 0 (machine precision)
    w, phi = scipy.sparse.linalg.eigsh(k, k=count, M=m, sigma=shift, which="LM", OPinv=op,
                                       v0=v0, tol=tol)
    return w, phi


VERIFY = ("auto", "sturm", "deflation", "none")


def lowest_modes(k, m, *, count: int | None = None, below: float | None = None,
                 shift: float = 0.0, factor=None, solver: str = "auto", tol: float = 1e-8,
                 verify: str = "auto", v0=None, name: str = "K",
                 release_factor: bool = False) -> Modes:
    """The lowest modes of K phi = lambda M phi, every copy of a repeated eigenvalue kept.

    Parameters
    ----------
    k, m : (n, n) sparse matrix
        Symmetric stiffness (K - shift M positive definite) and mass (semi-definite allowed).
    count : int, optional
        Number of modes wanted.
    below : float, optional
        Instead of ``count``: every mode with lambda < ``below`` [rad^2/s^2].
    shift : float
        Shift sigma of the spectral transformation (0 for a supported structure; < 0 when the
        structure has rigid-body modes).
    factor : object with ``solve(b)``, optional
        Factors of K - shift M to reuse (from :func:`factorise`, possibly lazy).
    solver : {"auto", "superlu", "pardiso"}
        Factorisation when ``factor`` is not given.
    tol : float
        Relative accuracy asked of ARPACK (eigenvalues come out as Rayleigh quotients, far more
        accurate).
    verify : {"auto", "sturm", "deflation", "none"}
        How the iterative result is checked for missed modes (a dense solution needs no
        check). "sturm": a Sturm count at a point above the last wanted mode (one more
        factorisation, an exact count). "deflation": a further Lanczos run from a new random
        vector on the operator with the modes found projected out; any eigenvalue it finds
        below the last wanted one was missed (no factorisation, no extra memory). Either way
        missed modes are added by deflated restarts. "auto": "sturm" (with ``below`` the
        Sturm count that sizes the run is the check; with ``count`` a count in the gap above
        the last wanted mode, with the fill-reducing ordering of ``factor`` when it has one).
        "none" only for tests and timing.
    v0 : (n,) array_like, optional
        Start vector (default: seeded Gaussian). Meant for tests that reproduce the failure of a
        structured start.
    name : str
        What K is, for error messages.
    release_factor : bool
        Free the factors of K - shift M before a Sturm count (whose own factorisation then
        does not add to the peak memory); they are rebuilt only if a restart needs them (the
        ordering is kept for the count).

    Returns
    -------
    Modes

    Notes
    -----
    The path is chosen before any work: dense for n <= ``DENSE_MAX``, or for count >=
    ``DENSE_FRACTION`` n with n <= ``DENSE_LIMIT``; otherwise shift-invert Lanczos. With
    ``below`` on the iterative path the count comes from a Sturm count at ``below``.
    """
    if (count is None) == (below is None):
        raise ValueError("give exactly one of count or below")
    if verify not in VERIFY:
        raise ValueError(f"verify must be one of {VERIFY}, got {verify!r}")
    k = scipy.sparse.csc_array(k, dtype=float)
    m = scipy.sparse.csc_array(m, dtype=float)
    n = k.shape[0]
    if count is not None:
        count = int(count)
        if count < 0:
            raise ValueError(f"count must be >= 0, got {count}")
        count = min(count, n)
        if count == 0:
            return Modes(np.zeros(0), np.zeros((n, 0)), "none", -math.inf, math.nan)
    dense = n <= DENSE_MAX or (count is not None and count >= DENSE_FRACTION * n
                               and n <= DENSE_LIMIT)
    sturm = None
    if not dense and below is not None:
        sturm = (below, count_eigenvalues_below(k, m, below))
        count = sturm[1]
        if count == 0:
            return Modes(np.zeros(0), np.zeros((n, 0)), "sturm", below, math.nan)
        dense = count >= DENSE_FRACTION * n and n <= DENSE_LIMIT
    if dense:
        w, phi = _dense_modes(k, m, shift, count if below is None else None)
        total = w.size if below is not None or w.size <= count else n
        if below is not None:
            count = int(np.sum(w < below))
        count = min(count, total)
        nxt = float(w[count]) if count < total else math.inf
        return Modes(w[:count], phi[:, :count], "dense",
                     math.inf if count == total else nxt, nxt)

    if factor is None:
        factor = factorise(k - shift * m, solver, name=f"{name} - sigma M" if shift else name)
    if v0 is None:
        v0 = np.random.default_rng(_SEED).standard_normal(n)
    v0 = np.asarray(v0, dtype=float)
    # with a count, one mode more than wanted: the gap above the last wanted one
    want = min(count + (0 if below is not None else 1), n - 1)
    w, phi = _lanczos(k, m, want, shift, factor, v0, tol)
    w, phi = _rayleigh_ritz(k, m, phi)
    if verify == "auto":
        verify = "sturm"
    rng = np.random.default_rng(_SEED + 1)
    restarts = 0

    def merge(w, phi, extra_count):
        _w2, phi2 = _lanczos(k, m, extra_count, shift, factor, rng.standard_normal(n), tol,
                            deflate=phi)
        q, _ = np.linalg.qr(np.hstack([phi, phi2]))
        return _rayleigh_ritz(k, m, q)

    if verify == "sturm":
        if release_factor and hasattr(factor, "release") and sturm is None:
            factor.release()
        if sturm is None:
            point = _sturm_point(w, count)
            sturm = (point, count_eigenvalues_below(k, m, point,
                                                    ordering=getattr(factor, "ordering", None)))
        point, expected = sturm
        while int(np.sum(w < point)) < expected:
            if restarts >= MAX_RESTARTS:
                raise ValueError(
                    f"{name}: {expected} eigenvalues lie below {point:.6g} but only "
                    f"{int(np.sum(w < point))} were found after {restarts} restarts")
            restarts += 1
            missing = expected - int(np.sum(w < point))
            extra = min(missing + 1, n - w.size - 1)
            if extra <= 0:
                break
            w, phi = merge(w, phi, extra)
            keep = max(want, expected)
            w, phi = w[:keep], phi[:, :keep]
        complete = point
    elif verify == "deflation":
        # the lowest eigenvalues of the operator with the found modes projected out: any
        # below the last wanted mode was missed
        size = PROBE
        probe = min(size, n - w.size - 1)
        complete = -math.inf
        while probe > 0:
            w2, phi2 = _lanczos(k, m, probe, shift, factor, rng.standard_normal(n), tol,
                                deflate=phi)
            w2 = np.sort(w2)
            last = w[count - 1]
            if w2[0] > last * (1 + 1e-9) + 1e-300:
                complete = float(w2[0])
                break
            if restarts >= MAX_RESTARTS:
                raise ValueError(f"{name}: modes below {last:.6g} still turn up after "
                                 f"{restarts} deflated restarts")
            restarts += 1
            if w2[-1] < last:  # every probe mode was a missed one: look for more next time
                size *= 2
            q, _ = np.linalg.qr(np.hstack([phi, phi2]))
            w, phi = _rayleigh_ritz(k, m, q)
            w, phi = w[:max(want, count)], phi[:, :max(want, count)]
            probe = min(size, n - w.size - 1)
    else:
        complete = float(w[count - 1])
    if w.size > count:  # the returned modes are the first count: the next one is left out
        complete = min(complete, float(w[count])) if complete > -math.inf else float(w[count])
    nxt = float(w[count]) if w.size > count else math.nan
    method = "lanczos" if verify != "none" else "lanczos-unchecked"
    return Modes(w[:count], phi[:, :count], method, complete, nxt, restarts)


#: Modes a deflation check looks for beyond those found.
PROBE = 3


def _sturm_point(w, count):
    """A shift for the Sturm check in the gap between the wanted modes' last eigenvalue and the
    next one found (or just above the last one)."""
    last = w[count - 1]
    if w.size > count and w[count] > last * (1 + 1e-6) + 1e-300:
        return float(0.5 * (last + w[count]))
    return float(last * (1 + 1e-6) + 1e-12)
