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

Both steps use one sparse factorisation of K_ii: the constraint modes are n_b solves with it,
and the fixed-interface modes come from shift-invert Lanczos about sigma = 0 whose operator
K_ii^-1 M_ii is applied with the same factors (small interiors are solved densely). The
Lanczos run starts from a random vector and is checked by a Sturm count, with deflated
restarts when modes were missed, so every copy of a repeated eigenvalue (any symmetric
structure has them) is kept (:mod:`servotune.structure.solvers`). The reduced model is exact
for static loads at the boundary DOFs and its eigenvalues approach those of the full model from
above as modes are added (it is a Rayleigh-Ritz projection).

:func:`~servotune.structure.cb_check` checks the reduced matrices on their own (symmetry,
definiteness, rigid-body mass, effective mass), :func:`~servotune.structure.reduction_check`
checks them against the full model, and :func:`~servotune.structure.mode_coverage` tells
whether the kept modes cover a frequency band.

References
----------
R. R. Craig, M. C. C. Bampton, "Coupling of substructures for dynamic analyses", AIAA Journal 6
(1968) 1313-1319.
R. R. Craig, A. J. Kurdila, Fundamentals of Structural Dynamics, 2nd ed., Wiley (2006), ch 18.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse

from ..units import RAD_S_PER_HZ
from .cbcheck import CraigBamptonCheck, cb_check, rigid_body_vectors
from .model import ModalModel, ReductionInfo
from .solvers import SOLVERS, factorise, lowest_modes, pardiso_available

__all__ = [
    "CraigBamptonBasis",
    "craig_bampton",
    "craig_bampton_basis",
    # re-exported from cbcheck (they lived here before)
    "CraigBamptonCheck",
    "cb_check",
    "rigid_body_vectors",
]

_pardiso_available = pardiso_available  # former private name, kept for scripts that use it


def _as_sparse(name: str, a) -> scipy.sparse.csr_array:
    # CSR, the format the blocks are cut from: a CSR input is not copied
    if scipy.sparse.issparse(a):
        a = scipy.sparse.csr_array(a, dtype=float)
    else:
        a = np.asarray(a, dtype=float)
        if a.ndim != 2:
            raise ValueError(f"{name} must be a 2-D matrix, got {a.ndim} dimensions")
        a = scipy.sparse.csr_array(a)
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
    next_omega : float
        The first fixed-interface natural frequency not kept [rad/s] (``inf`` when every mode
        is kept, ``nan`` when unknown).
    complete_below : float
        Every fixed-interface mode below this frequency [rad/s] is kept (verified).
    method : str
        How the fixed-interface modes were computed ("dense", "lanczos",
        "lanczos-unchecked", "none").
    restarts : int
        Deflated Lanczos restarts the Sturm check asked for.
    """

    boundary: np.ndarray
    interior: np.ndarray
    constraint_modes: np.ndarray
    fixed_interface_modes: np.ndarray
    omega: np.ndarray
    mass: np.ndarray
    stiffness: np.ndarray
    next_omega: float = math.nan
    complete_below: float = math.nan
    method: str = "unknown"
    restarts: int = 0

    @property
    def n_full(self) -> int:
        """Number of DOFs of the full model."""
        return self.boundary.size + self.interior.size

    @property
    def info(self) -> ReductionInfo:
        """What the kept fixed-interface modes cover, for :class:`ModalModel`."""
        return ReductionInfo(n_full=self.n_full, n_boundary=self.boundary.size,
                             fixed_interface_hz=tuple(self.omega / RAD_S_PER_HZ),
                             next_hz=self.next_omega / RAD_S_PER_HZ,
                             complete_below_hz=self.complete_below / RAD_S_PER_HZ,
                             method=self.method, restarts=self.restarts)

    def expand(self, reduced) -> np.ndarray:
        """Return the full-model displacements of reduced coordinates (a vector or columns).

        Parameters
        ----------
        reduced : array_like
            Reduced coordinates, shape (n_b + n_m,) or (n_b + n_m, k): the boundary DOFs then the
            modal coordinates.

        Returns
        -------
        numpy.ndarray
            Full-model displacements, shape (n_full,) or (n_full, k).

        Raises
        ------
        ValueError
            When the number of reduced coordinates is wrong.
        """
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


def _fixed_interface_modes(k_ii, m_ii, factor, n_modes, f_max_hz, verify):
    """Lowest modes of (K_ii, M_ii) with the factors of K_ii (see :func:`lowest_modes`).

    With a count the factors have been used for the constraint modes already and are released
    before the Sturm check; with a cut-off they are still lazy, so that the Sturm count (which
    comes first then) does not share the memory with them."""
    if n_modes is not None:
        modes = lowest_modes(k_ii, m_ii, count=n_modes, factor=factor, verify=verify,
                             name="K_ii", release_factor=True)
    else:
        modes = lowest_modes(k_ii, m_ii, below=(RAD_S_PER_HZ * f_max_hz) ** 2, factor=factor,
                             verify=verify, name="K_ii")
    w2, phi = modes.eigenvalues, modes.vectors
    if np.any(w2 <= 0):
        raise ValueError("a fixed-interface eigenvalue is <= 0: K_ii is not positive definite "
                         "(check the signs of the stiffness export)")
    if w2.size and w2[0] < 1e-12 * max(w2[-1], modes.next_eigenvalue if
                                       math.isfinite(modes.next_eigenvalue) else 0.0):
        f0 = math.sqrt(w2[0]) / RAD_S_PER_HZ
        raise ValueError(_MECHANISM + f" (a fixed-interface mode at {f0:.3g} Hz, nearly zero)")
    method = modes.method
    complete = modes.complete_below
    if f_max_hz is not None and method != "lanczos-unchecked":
        complete = max(complete, (RAD_S_PER_HZ * f_max_hz) ** 2)
    nxt = modes.next_eigenvalue
    return (np.sqrt(w2), phi, math.sqrt(nxt) if nxt >= 0 else nxt,
            math.sqrt(complete) if complete >= 0 else complete, method, modes.restarts)


def craig_bampton_basis(mass, stiffness, boundary, n_modes=None, f_max_hz=None,
                        solver: str = "auto", verify: str = "auto") -> CraigBamptonBasis:
    """Return the Craig-Bampton transformation and reduced matrices of a (sparse) FE model.

    Use this function when the constraint and fixed-interface modes are wanted (e.g. to
    recover interior displacements with :meth:`CraigBamptonBasis.expand`).

    Parameters
    ----------
    mass, stiffness : (n, n) sparse matrix or array_like
        Symmetric FE matrices [kg, N/m, ...], as for :func:`craig_bampton`.
    boundary : sequence of int or (n,) bool array
        Indices (0-based) of the boundary DOFs, kept in this order.
    n_modes : int, optional
        Number of fixed-interface modes to keep.
    f_max_hz : float, optional
        Keep every fixed-interface mode up to this frequency [Hz] instead (exactly one of
        ``n_modes`` and ``f_max_hz``).
    solver : {"auto", "superlu", "pardiso"}
        Sparse factorisation of K_ii, as for :func:`craig_bampton`.
    verify : {"auto", "sturm", "deflation", "none"}
        Check of the eigen-solution for missed modes, as for :func:`craig_bampton`.

    Returns
    -------
    CraigBamptonBasis
        The transformation (constraint and fixed-interface modes) and the reduced matrices.

    Raises
    ------
    ValueError
        For the reasons of :func:`craig_bampton`, and an unknown ``solver``.
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
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {SOLVERS}, got {solver!r}")
    mask = np.ones(n, dtype=bool)
    mask[b] = False
    i = np.flatnonzero(mask)
    k_i, m_i = k[i], m[i]  # the interior rows, once
    k_ii, k_ib = k_i[:, i].tocsc(), k_i[:, b].toarray()
    m_ii, m_ib = m_i[:, i].tocsc(), m_i[:, b].toarray()
    del k_i, m_i
    k_bb = k[b][:, b].toarray()
    m_bb = m[b][:, b].toarray()
    del m, k  # only the blocks from here on (the caller's matrices are not copied)

    # with a cut-off the Sturm count comes first: the factors wait until they are needed
    factor = factorise(k_ii, solver, name="K_ii", mechanism=_MECHANISM,
                       lazy=f_max_hz is not None)
    if n_modes is not None:
        psi = -factor.solve(k_ib)
    omega, phi, nxt, complete, method, restarts = _fixed_interface_modes(
        k_ii, m_ii, factor, None if n_modes is None else int(n_modes), f_max_hz, verify)
    if n_modes is None:
        psi = -factor.solve(k_ib)
    factor.release()
    del factor

    m_ii_psi = m_ii @ psi
    mbb = m_bb + m_ib.T @ psi + psi.T @ m_ib + psi.T @ m_ii_psi
    kbb = k_bb + k_ib.T @ psi
    mbm = (m_ib.T + m_ii_psi.T) @ phi
    nb, nm = b.size, omega.size
    mr = np.block([[mbb, mbm], [mbm.T, np.eye(nm)]])
    kr = np.block([[kbb, np.zeros((nb, nm))], [np.zeros((nm, nb)), np.diag(omega**2)]])
    return CraigBamptonBasis(boundary=b, interior=i, constraint_modes=psi,
                             fixed_interface_modes=phi, omega=omega,
                             mass=0.5 * (mr + mr.T), stiffness=0.5 * (kr + kr.T),
                             next_omega=nxt, complete_below=complete, method=method,
                             restarts=restarts)


def craig_bampton(mass, stiffness, boundary, n_modes=None, f_max_hz=None, damping_ratio=0.03,
                  boundary_names=None, solver: str = "auto",
                  verify: str = "auto") -> ModalModel:
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
        of interest (see :func:`~servotune.structure.mode_coverage`).
    damping_ratio : float or array_like
        Modal damping of the reduced model (see :class:`ModalModel`); default 0.03 as the paper.
    boundary_names : sequence of str, optional
        Names of the boundary DOFs (default ``dof.<index>``). Modal DOFs are ``mode.1``, ...
    solver : {"auto", "superlu", "pardiso"}
        Sparse factorisation of K_ii: SuperLU from scipy, or Intel MKL PARDISO through the
        optional ``pypardiso`` package (``pip install 'servotune[fast]'``), much faster on 3D
        solid models of 1e5 DOFs and more. ``"auto"`` takes PARDISO when it is installed and
        K_ii has more than 5000 rows.
    verify : {"auto", "sturm", "deflation", "none"}
        How the iterative eigen-solution is checked for missed modes, which are then added by
        deflated restarts (see :func:`~servotune.structure.lowest_modes`): "auto" and
        "sturm", a Sturm count (with ``f_max_hz`` the count that sizes the run; with
        ``n_modes`` a count of the eigenvalues below a point in the gap above the last kept
        mode: one more factorisation, of K_ii - s M_ii, made after the factors of K_ii are
        freed and in their ordering, so the peak memory stays that of one factorisation);
        "deflation", a deflated Lanczos probe instead (no factorisation, not an exact count).

    Returns
    -------
    ModalModel
        n_b + n_m DOFs: the boundary DOFs, then the modal coordinates (mass-normalised); its
        ``reduction`` (:class:`ReductionInfo`) records what the kept modes cover.

    Raises
    ------
    ValueError
        Mismatched or non-square matrices, bad boundary indices, both or neither of
        ``n_modes``/``f_max_hz``, or a singular K_ii (the structure moves with the boundary held).

    See Also
    --------
    craig_bampton_basis : The transformation itself, to recover interior displacements.
    servotune.structure.cbcheck.cb_check : Checks of the reduced model against the full one.
    servotune.axis.load_axis : Reads an axis, reducing FE matrices by this function on loading.
    servotune.frequency.compliance : The work-piece compliance of the axis built on the model.

    Notes
    -----
    One sparse factorisation of K_ii (SuperLU with a symmetric ordering and no pivoting, or a
    PARDISO Cholesky) gives the constraint modes Psi = -K_ii^-1 K_ib and serves as the
    shift-invert operator of the Lanczos eigen-solution (``scipy.sparse.linalg.eigsh``,
    sigma = 0, random start, checked for missed modes; see :mod:`servotune.structure.solvers`)
    for the
    fixed-interface modes; small interiors, or many modes of a mid-sized one, are solved
    densely instead. With a cut-off frequency the number of modes below it comes first from a
    Sturm count, so the Lanczos run asks for exactly that many. The reduced matrices are given
    in the module docstring (Craig and Bampton 1968).

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
                                solver=solver, verify=verify)
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
    return ModalModel(basis.mass, basis.stiffness, names, damping_ratio=damping_ratio,
                      reduction=basis.info)
