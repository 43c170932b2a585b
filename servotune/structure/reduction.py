"""Craig-Bampton reduction of sparse finite-element mass and stiffness matrices.

The DOFs of a large FE model split into *boundary* DOFs b (kept as physical coordinates: the
guide-way pads, the work-piece point, the motor) and *interior* DOFs i. The interior motion is
approximated by the static response to boundary motion (constraint modes) plus a few vibration
modes of the structure with the boundary held fixed (fixed-interface modes)::

    [u_b]   [ I     0   ] [u_b]        Psi = -K_ii^-1 K_ib            (constraint modes)
    [u_i] = [ Psi  Phi  ] [ q ]        K_ii Phi = M_ii Phi Omega^2,  Phi^T M_ii Phi = I

and the reduced matrices are T^T M T and T^T K T::

    M_r = [ M_bb + M_bi Psi + Psi^T M_ib + Psi^T M_ii Psi    (M_bi + Psi^T M_ii) Phi ]
          [ sym.                                              I                       ]
    K_r = [ K_bb + K_bi Psi                                   0                       ]
          [ 0                                                 Omega^2                 ]

Both steps use one sparse LU factorisation of K_ii: the constraint modes are n_b solves with it,
and the fixed-interface modes come from shift-invert Lanczos (``scipy.sparse.linalg.eigsh``)
about sigma = 0, whose operator K_ii^-1 M_ii is applied with the same factors. The reduced
model is exact for static loads at the boundary DOFs and its eigenvalues approach those of the
full model from above as modes are added (it is a Rayleigh-Ritz projection).

:func:`cb_check` reports the checks that a reduced model should pass before it is used, in the
spirit of pyyeti's ``cb.cbcheck``: symmetry, definiteness, rigid-body mass and centre of
gravity, fixed-base frequencies and modal effective mass.

References
----------
R. R. Craig, M. C. C. Bampton, "Coupling of substructures for dynamic analyses", AIAA Journal 6
(1968) 1313-1319.
R. R. Craig, A. J. Kurdila, Fundamentals of Structural Dynamics, 2nd ed., Wiley (2006), ch 18.
T. P. Widrick, pyYeti, ``pyyeti.cb.cbcheck`` (checks of Craig-Bampton models).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from .model import ModalModel

__all__ = [
    "CraigBamptonBasis",
    "CraigBamptonCheck",
    "cb_check",
    "craig_bampton",
    "craig_bampton_basis",
    "rigid_body_vectors",
]

_TWO_PI = 2.0 * math.pi
_TRANSLATIONS = {"x": 0, "y": 1, "z": 2}
_ROTATIONS = {"rx": 0, "ry": 1, "rz": 2}


def _as_sparse(name: str, a) -> scipy.sparse.csc_array:
    if scipy.sparse.issparse(a):
        a = scipy.sparse.csc_array(a, dtype=float)
    else:
        a = np.asarray(a, dtype=float)
        if a.ndim != 2:
            raise ValueError(f"{name} must be a 2-D matrix, got {a.ndim} dimensions")
        a = scipy.sparse.csc_array(a)
    if a.shape[0] != a.shape[1]:
        raise ValueError(f"{name} must be square, got shape {a.shape}")
    if not np.all(np.isfinite(a.data)):
        raise ValueError(f"{name} has NaN or infinite entries")
    return a


def _boundary_indices(boundary, n: int) -> np.ndarray:
    b = np.asarray(boundary)
    if b.dtype == bool:
        if b.shape != (n,):
            raise ValueError(f"a boolean boundary mask must have {n} entries, got {b.shape}")
        b = np.flatnonzero(b)
    else:
        if b.ndim != 1 or (b.size and not np.issubdtype(b.dtype, np.integer)):
            raise ValueError("boundary must be a 1-D sequence of integer DOF indices "
                             "(or a boolean mask)")
        b = b.astype(int)
    if b.size == 0:
        raise ValueError("boundary is empty: give at least one boundary DOF index")
    if b.min() < 0 or b.max() >= n:
        raise ValueError(f"boundary indices must lie in 0..{n - 1}, got {b.min()}..{b.max()}")
    if np.unique(b).size != b.size:
        raise ValueError("boundary indices contain duplicates")
    if b.size == n:
        raise ValueError("every DOF is a boundary DOF: nothing to reduce")
    return b


@dataclass(frozen=True, eq=False)
class CraigBamptonBasis:
    """The Craig-Bampton transformation of a model and its reduced matrices.

    Attributes
    ----------
    boundary, interior : ndarray of int
        Indices of the boundary and interior DOFs in the full model.
    constraint_modes : (n_i, n_b) ndarray
        Psi = -K_ii^-1 K_ib: interior displacement for a unit displacement of each boundary DOF.
    fixed_interface_modes : (n_i, n_m) ndarray
        Phi, mass-normalised on M_ii.
    omega : (n_m,) ndarray
        Fixed-interface natural frequencies [rad/s], ascending.
    mass, stiffness : (n_b + n_m, n_b + n_m) ndarray
        Reduced matrices, boundary DOFs first, then the modal coordinates.
    """

    boundary: np.ndarray
    interior: np.ndarray
    constraint_modes: np.ndarray
    fixed_interface_modes: np.ndarray
    omega: np.ndarray
    mass: np.ndarray
    stiffness: np.ndarray

    @property
    def n_full(self) -> int:
        """Number of DOFs of the full model."""
        return self.boundary.size + self.interior.size

    def expand(self, reduced) -> np.ndarray:
        """Full-model displacements from reduced coordinates (vector or columns)."""
        reduced = np.asarray(reduced, dtype=float)
        nb = self.boundary.size
        if reduced.shape[0] != nb + self.omega.size:
            raise ValueError(f"expected {nb + self.omega.size} reduced coordinates, "
                             f"got {reduced.shape[0]}")
        full = np.zeros((self.n_full, *reduced.shape[1:]))
        full[self.boundary] = reduced[:nb]
        full[self.interior] = (self.constraint_modes @ reduced[:nb]
                               + self.fixed_interface_modes @ reduced[nb:])
        return full


_MECHANISM = ("the interior stiffness K_ii is singular: the structure with the boundary DOFs "
              "held still can still move (a mechanism or a rigid-body motion the boundary does "
              "not restrain); add boundary DOFs or supports")
SOLVERS = ("auto", "superlu", "pardiso")


def _pardiso_available() -> bool:
    try:
        import pypardiso  # noqa: F401
    except ImportError:
        return False
    return True


class _PardisoFactor:
    """Cholesky factors of an SPD matrix by Intel MKL PARDISO (optional, ``pypardiso``)."""

    def __init__(self, k_ii):
        import pypardiso

        self._upper = scipy.sparse.triu(k_ii, format="csr")
        self._upper.sort_indices()
        self._solver = pypardiso.PyPardisoSolver(mtype=2)  # real symmetric positive definite
        try:
            self._solver.factorize(self._upper)
        except pypardiso.pardiso_wrapper.PyPardisoError as exc:
            raise ValueError(_MECHANISM + f" (PARDISO: {exc})") from None
        self._solver.set_phase(33)  # solves only from here on

    def solve(self, b):
        b = np.asfortranarray(b, dtype=float)
        # pypardiso's public solve() compares the whole matrix with the factorised one on every
        # call; the factors are known to be current here, so the solve phase is called directly
        return self._solver._call_pardiso(self._upper, b)


def _factorise(k_ii, solver: str = "auto"):
    """Factors of K_ii with a ``solve(b)`` method: SuperLU (scipy; symmetric ordering, no
    pivoting, so the pivots are those of an LDL^T) or PARDISO when installed."""
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {SOLVERS}, got {solver!r}")
    if solver == "pardiso" or (solver == "auto" and _pardiso_available()
                               and k_ii.shape[0] > 5000):
        if not _pardiso_available():
            raise ValueError("solver='pardiso' needs the pypardiso package "
                             "(pip install 'servotune[fast]'), or use solver='superlu'")
        return _PardisoFactor(k_ii)
    try:
        lu = scipy.sparse.linalg.splu(k_ii, permc_spec="MMD_AT_PLUS_A",
                                      diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    except RuntimeError as exc:
        raise ValueError(_MECHANISM) from exc
    pivots = lu.U.diagonal()
    scale = np.abs(pivots).max()
    if np.any(pivots < -1e-13 * scale):
        raise ValueError(
            f"the interior stiffness K_ii is not positive definite ({int(np.sum(pivots < 0))} "
            "negative pivots): check the signs and units of the stiffness export")
    if not np.all(np.isfinite(pivots)) or np.abs(pivots).min() <= 1e-13 * scale:
        raise ValueError(_MECHANISM + " (singular to working precision)")
    return lu


def _dense_lowest_modes(k, m, count):
    """Lowest modes of (K, M) with K positive definite and M only semi-definite: the largest
    eigenvalues 1/omega^2 of L^-1 M L^-T, K = L L^T (massless DOFs have none)."""
    try:
        low = np.linalg.cholesky(k)
    except np.linalg.LinAlgError:
        raise ValueError("the interior stiffness K_ii is not positive definite: the structure "
                         "with the boundary DOFs held still has a mechanism; add boundary "
                         "DOFs or supports") from None
    c = scipy.linalg.solve_triangular(low, scipy.linalg.solve_triangular(low, m, lower=True).T,
                                      lower=True)
    mu, v = np.linalg.eigh(0.5 * (c + c.T))
    mu, v = mu[::-1], v[:, ::-1]
    count = min(count, int(np.sum(mu > 1e-12 * max(mu[0], 1e-300))))
    phi = scipy.linalg.solve_triangular(low.T, v[:, :count], lower=False)
    return 1.0 / mu[:count], phi


def _fixed_interface_modes(k_ii, m_ii, lu, n_modes, f_max_hz):
    """Lowest modes of (K_ii, M_ii) by shift-invert Lanczos about 0 with the factors of K_ii."""
    n_i = k_ii.shape[0]
    op_inv = scipy.sparse.linalg.LinearOperator((n_i, n_i), matvec=lu.solve, dtype=float)

    def solve(k):
        if k >= n_i - 1 or n_i <= 200:  # small interiors: dense, exact
            return _dense_lowest_modes(k_ii.toarray(), m_ii.toarray(), k)
        # In shift-invert mode eigsh uses A only for its shape; OPinv applies K_ii^-1.
        # tol = 1e-8 on the Ritz values of K_ii^-1 M_ii: the eigenvector error is then
        # ~1e-8 and the eigenvalues, Rayleigh quotients, are exact to ~1e-15; it saves about
        # a sixth of the solves of tol = 0 (machine precision).
        w2, phi = scipy.sparse.linalg.eigsh(k_ii, k=k, M=m_ii, sigma=0.0, which="LM",
                                            OPinv=op_inv, v0=np.ones(n_i), tol=1e-8)
        order = np.argsort(w2)
        return w2[order], phi[:, order]

    if n_modes is not None:
        if n_modes == 0:
            return np.zeros(0), np.zeros((n_i, 0))
        w2, phi = solve(min(n_modes, n_i))
    else:
        omega_max = _TWO_PI * f_max_hz
        k = min(20, n_i)
        while True:
            w2, phi = solve(k)
            if w2[-1] > omega_max**2 or k >= n_i:
                break
            k = min(2 * k, n_i)
        keep = w2 <= omega_max**2
        w2, phi = w2[keep], phi[:, keep]
    if np.any(w2 <= 0):
        raise ValueError("a fixed-interface eigenvalue is <= 0: K_ii is not positive definite "
                         "(check the signs of the stiffness export)")
    norms = np.sqrt(np.einsum("ij,ij->j", phi, m_ii @ phi))  # M_ii-normalise against round-off
    return np.sqrt(w2), phi / norms


def craig_bampton_basis(mass, stiffness, boundary, n_modes=None, f_max_hz=None,
                        solver: str = "auto") -> CraigBamptonBasis:
    """The Craig-Bampton transformation and reduced matrices of a (sparse) FE model.

    Parameters are those of :func:`craig_bampton` (without names and damping); use this
    function when the constraint and
    fixed-interface modes are wanted (e.g. to recover interior displacements with
    :meth:`CraigBamptonBasis.expand`).
    """
    m = _as_sparse("mass", mass)
    k = _as_sparse("stiffness", stiffness)
    if m.shape != k.shape:
        raise ValueError(f"mass {m.shape} and stiffness {k.shape} differ in size")
    n = m.shape[0]
    b = _boundary_indices(boundary, n)
    if (n_modes is None) == (f_max_hz is None):
        raise ValueError("give exactly one of n_modes (a count) or f_max_hz (a cut-off "
                         "frequency in Hz) for the fixed-interface modes")
    if n_modes is not None and (int(n_modes) != n_modes or n_modes < 0):
        raise ValueError(f"n_modes must be a non-negative integer, got {n_modes!r}")
    if f_max_hz is not None and not (math.isfinite(f_max_hz) and f_max_hz > 0):
        raise ValueError(f"f_max_hz must be a positive frequency, got {f_max_hz!r}")
    mask = np.ones(n, dtype=bool)
    mask[b] = False
    i = np.flatnonzero(mask)
    m, k = m.tocsr(), k.tocsr()
    k_ii = k[i][:, i].tocsc()
    k_ib = k[i][:, b].toarray()
    m_ii = m[i][:, i].tocsc()
    m_ib = m[i][:, b].toarray()
    k_bb = k[b][:, b].toarray()
    m_bb = m[b][:, b].toarray()

    lu = _factorise(k_ii, solver)
    psi = -lu.solve(k_ib)
    omega, phi = _fixed_interface_modes(k_ii, m_ii, lu,
                                        None if n_modes is None else int(n_modes), f_max_hz)

    m_ii_psi = m_ii @ psi
    mbb = m_bb + m_ib.T @ psi + psi.T @ m_ib + psi.T @ m_ii_psi
    kbb = k_bb + k_ib.T @ psi
    mbm = (m_ib.T + m_ii_psi.T) @ phi
    nb, nm = b.size, omega.size
    mr = np.block([[mbb, mbm], [mbm.T, np.eye(nm)]])
    kr = np.block([[kbb, np.zeros((nb, nm))], [np.zeros((nm, nb)), np.diag(omega**2)]])
    return CraigBamptonBasis(boundary=b, interior=i, constraint_modes=psi,
                             fixed_interface_modes=phi, omega=omega,
                             mass=0.5 * (mr + mr.T), stiffness=0.5 * (kr + kr.T))


def craig_bampton(mass, stiffness, boundary, n_modes=None, f_max_hz=None, damping_ratio=0.03,
                  boundary_names=None, solver: str = "auto") -> ModalModel:
    """Reduce a (sparse) FE model to its boundary DOFs plus fixed-interface modes.

    Parameters
    ----------
    mass, stiffness : (n, n) sparse matrix or array_like
        Symmetric FE matrices [kg, N/m, ...]. The mass may be semi-definite (lumped masses
        without rotary inertia); the stiffness with the boundary held must be positive definite.
    boundary : sequence of int or (n,) bool array
        Indices (0-based) of the boundary DOFs, kept as physical coordinates in this order.
    n_modes : int, optional
        Number of fixed-interface modes to keep.
    f_max_hz : float, optional
        Keep every fixed-interface mode up to this frequency [Hz] instead (exactly one of
        ``n_modes`` and ``f_max_hz``). A common rule is 1.5 to 2 times the highest frequency
        of interest.
    damping_ratio : float or array_like
        Modal damping of the reduced model (see :class:`ModalModel`); default 0.03 as the paper.
    boundary_names : sequence of str, optional
        Names of the boundary DOFs (default ``dof.<index>``). Modal DOFs are ``mode.1``, ...
    solver : {"auto", "superlu", "pardiso"}
        Sparse factorisation of K_ii: SuperLU from scipy, or Intel MKL PARDISO through the
        optional ``pypardiso`` package (``pip install 'servotune[fast]'``), much faster on 3D
        solid models of 1e5 DOFs and more. ``"auto"`` takes PARDISO when it is installed and
        K_ii has more than 5000 rows.
    Returns
    -------
    ModalModel
        n_b + n_m DOFs: the boundary DOFs, then the modal coordinates (mass-normalised).

    Raises
    ------
    ValueError
        Mismatched or non-square matrices, bad boundary indices, both or neither of
        ``n_modes``/``f_max_hz``, or a singular K_ii (the structure moves with the boundary held).

    Notes
    -----
    One sparse factorisation of K_ii (SuperLU with a symmetric ordering and no pivoting, or a
    PARDISO Cholesky) gives the constraint modes Psi = -K_ii^-1 K_ib and serves as the
    shift-invert operator of the Lanczos eigen-solution (``scipy.sparse.linalg.eigsh``,
    sigma = 0) for the fixed-interface modes. With a cut-off
    frequency the number of modes is doubled from 20 until the cut-off is passed. The reduced
    matrices are given in the module docstring (Craig and Bampton 1968).

    Examples
    --------
    Ten equal masses in a chain fixed at one end; keeping the free end and three modes gives a
    first frequency within 0.03 % of the full model's, and never below it:

    >>> import numpy as np, scipy.sparse as sp
    >>> n, m, k = 10, 1.0, 1e4
    >>> K = sp.diags([2 * k * np.ones(n), -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, 1, -1])
    >>> K = sp.lil_array(K); K[n - 1, n - 1] = k
    >>> M = m * sp.eye_array(n)
    >>> reduced = craig_bampton(M, K, [n - 1], n_modes=3, boundary_names=["tip.x"])
    >>> exact = 2 * np.sqrt(k / m) * np.sin(np.pi / (2 * (2 * n + 1)))
    >>> w1 = reduced.natural_frequencies()[0]
    >>> bool(exact <= w1 < exact * (1 + 3e-4))
    True
    >>> reduced.dofs[:2]
    ('tip.x', 'mode.1')
    """
    basis = craig_bampton_basis(mass, stiffness, boundary, n_modes=n_modes, f_max_hz=f_max_hz,
                                solver=solver)
    nb = basis.boundary.size
    if boundary_names is None:
        boundary_names = [f"dof.{j}" for j in basis.boundary]
    boundary_names = [str(x) for x in boundary_names]
    if len(boundary_names) != nb:
        raise ValueError(f"{len(boundary_names)} boundary names for {nb} boundary DOFs")
    clash = [x for x in boundary_names if x.startswith("mode.")]
    if clash:
        raise ValueError(f"boundary names may not start with 'mode.' (reserved for modal "
                         f"DOFs): {clash}")
    names = boundary_names + [f"mode.{j + 1}" for j in range(basis.omega.size)]
    return ModalModel(basis.mass, basis.stiffness, names, damping_ratio=damping_ratio)


# -- checks ----------------------------------------------------------------------------------
def rigid_body_vectors(dofs, coordinates, reference=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Geometric rigid-body motions of named DOFs: an (n, 6) array, columns X, Y, Z
    translation and rotation about X, Y, Z through ``reference``.

    A DOF named ``<node>.<x|y|z|rx|ry|rz>`` whose node is in ``coordinates`` (a mapping
    node -> (x, y, z) [m]) moves as a point of a rigid body: a translation t and a small
    rotation theta displace the point p by t + theta x (p - reference). Any other DOF (modal
    coordinates, relative or drive DOFs) gets a zero row.

    Examples
    --------
    A point 2 m along Y moves -2 m in X when the body turns 1 rad about Z:

    >>> r = rigid_body_vectors(["n1.x", "n1.y"], {"n1": (0.0, 2.0, 0.0)})
    >>> r[0].tolist()
    [1.0, 0.0, 0.0, 0.0, 0.0, -2.0]
    """
    ref = np.asarray(reference, dtype=float)
    if ref.shape != (3,):
        raise ValueError(f"reference must be a point (x, y, z), got {reference!r}")
    coords = {str(k): np.asarray(v, dtype=float) for k, v in dict(coordinates).items()}
    for node, p in coords.items():
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"coordinates of node {node!r} must be 3 finite numbers, got {p}")
    out = np.zeros((len(dofs), 6))
    for row, name in enumerate(dofs):
        node, _, comp = str(name).rpartition(".")
        if node not in coords:
            continue
        r = coords[node] - ref
        if comp in _TRANSLATIONS:
            e = np.eye(3)[_TRANSLATIONS[comp]]
            out[row, :3] = e
            out[row, 3:] = np.cross(r, e)  # e . (theta x r) = theta . (r x e)
        elif comp in _ROTATIONS:
            out[row, 3 + _ROTATIONS[comp]] = 1.0
    return out


@dataclass(frozen=True, eq=False)
class CraigBamptonCheck:
    """What :func:`cb_check` found; ``str()`` gives a readable report.

    Attributes
    ----------
    n_boundary, n_modes : int
        Boundary (physical) and modal DOFs of the model.
    mass_asymmetry, stiffness_asymmetry : float
        max |A - A^T| / max |A|.
    mass_min_eigenvalue, stiffness_min_eigenvalue : float
        Smallest eigenvalue over the largest (M must be > 0, K >= 0 to round-off).
    mass_positive_definite, stiffness_positive_semidefinite : bool
    free_free_frequencies_hz : ndarray
        Lowest natural frequencies of the model with nothing held [Hz] (rigid-body modes ~ 0).
    fixed_base_frequencies_hz : ndarray
        Natural frequencies with the boundary DOFs held [Hz].
    directions : tuple of str
        Labels of the rigid-body motions.
    rigid_body_mass : ndarray or None
        R^T M_bb R: the mass matrix of the rigid-body motions (6x6 about the reference point for
        geometric ones) [kg, kg m, kg m^2].
    center_of_gravity : ndarray or None
        From the geometric rigid-body mass [m], relative to the reference point.
    rigid_body_stiffness_residual : float or None
        max |K_bb R| / (max |K| max |R|): a rigid-body motion must not strain the model
        (grounding check).
    effective_mass : ndarray or None
        (n_modes, n_rb) modal effective mass L^2 / m_j, L = M_qb R [kg, kg m^2].
    effective_mass_fraction : ndarray or None
        Effective mass over the rigid-body mass of each direction.
    """

    n_boundary: int
    n_modes: int
    mass_asymmetry: float
    stiffness_asymmetry: float
    mass_min_eigenvalue: float
    stiffness_min_eigenvalue: float
    mass_positive_definite: bool
    stiffness_positive_semidefinite: bool
    free_free_frequencies_hz: np.ndarray
    fixed_base_frequencies_hz: np.ndarray
    directions: tuple
    rigid_body_mass: np.ndarray | None
    center_of_gravity: np.ndarray | None
    rigid_body_stiffness_residual: float | None
    effective_mass: np.ndarray | None
    effective_mass_fraction: np.ndarray | None

    @property
    def passed(self) -> bool:
        """Symmetric to 1e-8, M > 0, K >= 0, rigid-body motions strain-free to 1e-6."""
        ok = (self.mass_asymmetry < 1e-8 and self.stiffness_asymmetry < 1e-8
              and self.mass_positive_definite and self.stiffness_positive_semidefinite)
        if self.rigid_body_stiffness_residual is not None:
            ok = ok and self.rigid_body_stiffness_residual < 1e-6
        return bool(ok)

    def to_dict(self) -> dict:
        """Plain values for JSON (SI; frequencies in Hz as the names say)."""
        out = {}
        for key in self.__dataclass_fields__:
            value = getattr(self, key)
            out[key] = value.tolist() if isinstance(value, np.ndarray) else value
        out["directions"] = list(self.directions)
        out["passed"] = self.passed
        return out

    def __str__(self) -> str:
        def yes(flag):
            return "ok" if flag else "FAILED"

        lines = [
            f"Craig-Bampton model check: {self.n_boundary} boundary DOFs, {self.n_modes} modes",
            f"  symmetry      M: max|M-M^T|/max|M| = {self.mass_asymmetry:.2e} "
            f"({yes(self.mass_asymmetry < 1e-8)})",
            f"                K: max|K-K^T|/max|K| = {self.stiffness_asymmetry:.2e} "
            f"({yes(self.stiffness_asymmetry < 1e-8)})",
            f"  definiteness  M: min/max eigenvalue = {self.mass_min_eigenvalue:.2e} "
            f"({yes(self.mass_positive_definite)}: must be > 0)",
            f"                K: min/max eigenvalue = {self.stiffness_min_eigenvalue:.2e} "
            f"({yes(self.stiffness_positive_semidefinite)}: must be >= 0)",
            "  free-free frequencies [Hz]: "
            + ", ".join(f"{f:.4g}" for f in self.free_free_frequencies_hz[:10]),
        ]
        if self.rigid_body_mass is not None:
            lines.append("  rigid-body mass R^T M R (" + ", ".join(self.directions) + "):")
            for row in self.rigid_body_mass:
                lines.append("    " + " ".join(f"{v:12.5g}" for v in row))
            if self.center_of_gravity is not None:
                lines.append("  centre of gravity [m]: "
                             + ", ".join(f"{v:.5g}" for v in self.center_of_gravity))
            lines.append(f"  grounding: max|K_bb R|/(max|K| max|R|) = "
                         f"{self.rigid_body_stiffness_residual:.2e} "
                         f"({yes(self.rigid_body_stiffness_residual < 1e-6)})")
        else:
            lines.append("  rigid-body mass: not computed (give node coordinates or "
                         "rigid-body vectors)")
        if self.n_modes:
            header = "  mode   f_fixed [Hz]"
            if self.effective_mass_fraction is not None:
                header += "".join(f"  {d:>7s} %" for d in self.directions)
            lines.append(header)
            for j, f in enumerate(self.fixed_base_frequencies_hz):
                row = f"  {j + 1:4d} {f:14.5g}"
                if self.effective_mass_fraction is not None:
                    row += "".join(f"  {100 * v:9.3f}" for v in self.effective_mass_fraction[j])
                lines.append(row)
            if self.effective_mass_fraction is not None:
                lines.append("  total          "
                             + "".join(f"  {100 * v:9.3f}"
                                       for v in self.effective_mass_fraction.sum(axis=0)))
        lines.append(f"  result: {'passed' if self.passed else 'FAILED'}")
        return "\n".join(lines)


def _relative_min_eig(a: np.ndarray) -> float:
    w = np.linalg.eigvalsh(0.5 * (a + a.T))
    return float(w[0] / max(abs(w).max(), 1e-300))


def cb_check(model, stiffness=None, dofs=None, *, coordinates=None, rigid_body=None,
             reference=(0.0, 0.0, 0.0), directions=None) -> CraigBamptonCheck:
    """Check a Craig-Bampton (or any reduced) model before use.

    Boundary DOFs are those not named ``mode.*``; the modal DOFs are the fixed-interface modes.

    Parameters
    ----------
    model : ModalModel or (n, n) array_like
        The reduced model (e.g. from :func:`craig_bampton`), or its mass matrix as read from a
        file, with ``stiffness`` and ``dofs`` (then the symmetry check sees the matrices as
        they are; a :class:`ModalModel` is symmetric by construction).
    stiffness : (n, n) array_like, optional
        Stiffness matrix when ``model`` is a mass matrix.
    dofs : sequence of str, optional
        DOF names when ``model`` is a mass matrix.
    coordinates : mapping node -> (x, y, z), optional
        Node positions [m] for geometric rigid-body motions of boundary DOFs named
        ``<node>.<x|y|z|rx|ry|rz>`` (see :func:`rigid_body_vectors`).
    rigid_body : (n_b, n_rb) array_like, optional
        Rigid-body motions of the boundary DOFs given directly, one column each (instead of
        ``coordinates``). For a feed axis, the one motion along the axis is: 1 at every
        absolute and relative X DOF that moves with the slide, 1/ratio [rad/m] at the motor
        rotor, 0 at the stator and at Y and Z.
    reference : (3,) array_like
        Reference point of the geometric rigid-body motions [m].
    directions : sequence of str, optional
        Labels of the rigid-body columns (default X, Y, Z, RX, RY, RZ for geometric ones).

    Returns
    -------
    CraigBamptonCheck

    Notes
    -----
    Modal effective mass of fixed-interface mode j in rigid-body direction k:
    L_jk^2 / m_jj with L = M_qb R (Craig and Kurdila 2006, sec 18.5); summed over all modes of
    the full model it approaches the rigid-body mass less the part carried statically by the
    boundary. The centre of gravity follows from the coupling terms of the 6x6 rigid-body mass
    about the reference point, e.g. c_x = M[Y, RZ]/M[Y, Y] = -M[Z, RY]/M[Z, Z] (the two
    estimates are averaged), as pyyeti's ``cb.cbcheck`` reports it.
    """
    if isinstance(model, ModalModel):
        if stiffness is not None or dofs is not None:
            raise ValueError("give stiffness and dofs only with a mass matrix, not a ModalModel")
        m, k, names = model.mass, model.stiffness, model.dofs
    else:
        if stiffness is None or dofs is None:
            raise ValueError("with a mass matrix, cb_check needs stiffness and dofs as well")
        m = np.asarray(model.toarray() if scipy.sparse.issparse(model) else model, dtype=float)
        k = np.asarray(stiffness.toarray() if scipy.sparse.issparse(stiffness) else stiffness,
                       dtype=float)
        names = tuple(str(d) for d in dofs)
        if m.ndim != 2 or m.shape[0] != m.shape[1] or m.shape != k.shape \
                or len(names) != m.shape[0]:
            raise ValueError(f"mass {m.shape}, stiffness {k.shape} and {len(names)} DOF names "
                             "do not match")
        if not (np.all(np.isfinite(m)) and np.all(np.isfinite(k))):
            raise ValueError("mass or stiffness has NaN or infinite entries")
    is_mode = np.array([d.startswith("mode.") for d in names])
    b, q = np.flatnonzero(~is_mode), np.flatnonzero(is_mode)
    m_asym = float(np.abs(m - m.T).max() / np.abs(m).max())
    k_asym = float(np.abs(k - k.T).max() / max(np.abs(k).max(), 1e-300))
    m, k = 0.5 * (m + m.T), 0.5 * (k + k.T)
    m_min, k_min = _relative_min_eig(m), _relative_min_eig(k)
    if m_min > 0:
        w2 = scipy.linalg.eigvalsh(k, m)
        free = np.sqrt(np.clip(w2, 0, None)) / _TWO_PI
    else:
        free = np.zeros(0)
    if q.size and m_min > 0:
        w2 = scipy.linalg.eigvalsh(k[np.ix_(q, q)], m[np.ix_(q, q)])
        fixed = np.sqrt(np.clip(w2, 0, None)) / _TWO_PI
    else:
        fixed = np.zeros(0)

    r = None
    if rigid_body is not None and coordinates is not None:
        raise ValueError("give either coordinates or rigid_body, not both")
    if coordinates is not None:
        r = rigid_body_vectors([names[i] for i in b], coordinates, reference)
        directions = ("X", "Y", "Z", "RX", "RY", "RZ") if directions is None else directions
        used = np.abs(r).sum(axis=0) > 0
        if not used.any():
            raise ValueError("no boundary DOF is named <node>.<x|y|z|rx|ry|rz> with a node "
                             f"in coordinates; boundary DOFs are {[names[i] for i in b]}")
    elif rigid_body is not None:
        r = np.asarray(rigid_body, dtype=float)
        if r.ndim == 1:
            r = r[:, None]
        if r.shape[0] != b.size or not np.all(np.isfinite(r)):
            raise ValueError(f"rigid_body must have {b.size} finite rows (one per boundary "
                             f"DOF), got shape {r.shape}")
        directions = tuple(f"rb{j + 1}" for j in range(r.shape[1])) if directions is None \
            else directions
    rb_mass = cg = residual = eff = frac = None
    if r is not None:
        directions = tuple(str(d) for d in directions)
        if len(directions) != r.shape[1]:
            raise ValueError(f"{len(directions)} direction labels for {r.shape[1]} motions")
        m_bb, k_bb = m[np.ix_(b, b)], k[np.ix_(b, b)]
        rb_mass = r.T @ m_bb @ r
        residual = float(np.abs(k_bb @ r).max()
                         / max(np.abs(k).max() * np.abs(r).max(), 1e-300))
        if coordinates is not None and np.all(np.diag(rb_mass)[:3] > 0):
            d = np.diag(rb_mass)
            cg = np.array([(rb_mass[1, 5] / d[1] - rb_mass[2, 4] / d[2]) / 2,
                           (rb_mass[2, 3] / d[2] - rb_mass[0, 5] / d[0]) / 2,
                           (rb_mass[0, 4] / d[0] - rb_mass[1, 3] / d[1]) / 2])
        if q.size:
            participation = m[np.ix_(q, b)] @ r
            eff = participation**2 / np.diag(m)[q][:, None]
            with np.errstate(divide="ignore", invalid="ignore"):
                frac = np.where(np.diag(rb_mass) > 0, eff / np.diag(rb_mass), 0.0)
    return CraigBamptonCheck(
        n_boundary=int(b.size), n_modes=int(q.size), mass_asymmetry=m_asym,
        stiffness_asymmetry=k_asym, mass_min_eigenvalue=m_min, stiffness_min_eigenvalue=k_min,
        mass_positive_definite=bool(m_min > 0), stiffness_positive_semidefinite=bool(
            k_min > -1e-9), free_free_frequencies_hz=free, fixed_base_frequencies_hz=fixed,
        directions=tuple(directions) if r is not None else (), rigid_body_mass=rb_mass,
        center_of_gravity=cg, rigid_body_stiffness_residual=residual, effective_mass=eff,
        effective_mass_fraction=frac)
