"""Semi-discretisation of milling stability (Insperger and Stepan): the monodromy matrix.

With the compliance in state-space form, ``x' = A x + B F``, ``q = C x`` (q the tool/work-piece
displacement in the flexible directions, F the cutting force there) and the regenerative force
``F = -b H(t) (q(t) - q(t - T))`` of :mod:`servotune.chatter.setup`, the cutting process is the
time-periodic delay-differential equation (period = delay = T, the tooth passing period)::

    x'(t) = (A - b B H(t) C) x(t) + b B H(t) C x(t - T)                            (1)

**First-order semi-discretisation** (Insperger and Stepan 2004): split T into m intervals of
length dt = T/m; on interval i replace H(t) by its mean H_i over the interval
(:func:`~servotune.chatter.setup.periodic_directional_matrix`), keep the present state exact and
interpolate the delayed displacement linearly between the samples q_(i-m) and q_(i-m+1)::

    x' = A_i x + B u(s),   A_i = A - b B H_i C,
    u(s) = b H_i (q_(i-m) + (s/dt) (q_(i-m+1) - q_(i-m))),   0 <= s <= dt.

The exact solution over the interval is ``x_(i+1) = P_i x_i + G1_i u(0) + G2_i u'``, with
``P_i = exp(A_i dt)``, ``G1_i = int_0^dt exp(A_i (dt-s)) ds B`` and
``G2_i = int_0^dt exp(A_i (dt-s)) s ds B``, all read from one matrix exponential (Van Loan 1978)::

    expm( [[A_i, B, 0], [0, 0, I], [0, 0, 0]] dt ) = [[P_i, G1_i, G2_i], [0, I, dt I], [0, 0, I]]

so that ``x_(i+1) = P_i x_i + (G1_i - G2_i/dt) b H_i q_(i-m) + (G2_i/dt) b H_i q_(i-m+1)``.
With the state ``y_i = (x_i, q_(i-1), ..., q_(i-m))`` one period is the linear map
``y_m = Phi y_0``; Phi is the *monodromy matrix* and the cut is stable when its spectral radius
is below 1. A multiplier leaving the unit circle at -1 is a period-doubling (flip) bifurcation,
at a complex pair a secondary Hopf bifurcation (the ordinary chatter that the zero-order method
also finds).

Implementation: the matrix exponentials of every interval and every grid point are formed at
once (a batched Pade scaling-and-squaring, Higham 2005), Phi is built by stepping all grid points
together through the m intervals (the delayed samples are unit selections, so only the present
state is multiplied), and the spectral radii come from one batched eigenvalue call.

References
----------
T. Insperger, G. Stepan, "Semi-discretization method for delayed systems", Int J Numer Meth
Engng 55 (2002) 503-518.
T. Insperger, G. Stepan, "Updated semi-discretization method for periodic delay-differential
equations with discrete delay", Int J Numer Meth Engng 61 (2004) 117-141.
T. Insperger, G. Stepan, Semi-Discretization for Time-Delay Systems, Springer (2011), ch 5.
C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE Trans Autom
Control 23 (1978) 395-404.
N. J. Higham, "The scaling and squaring method for the matrix exponential revisited", SIAM J
Matrix Anal Appl 26 (2005) 1179-1193.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import control
import numpy as np
from scipy import linalg, optimize
from scipy.sparse import linalg as sparse_linalg

from .frf import _check_stable
from .setup import MillingSetup, _direction_index, periodic_directional_matrix
from .zoa import (
    StabilityLobes,
    _check_setup,
    _check_speeds,
    absolute_stability_limit,
    default_speed_range,
)

__all__ = [
    "DEFAULT_INTERVALS",
    "MIN_INTERVALS",
    "INTERVALS_PER_MODE_PERIOD",
    "CuttingStateSpace",
    "SdmLobes",
    "StabilityMap",
    "choose_intervals",
    "cutting_state_space",
    "monodromy_spectral_radius",
    "sdm_lobes",
    "stability_map",
]

#: intervals per tooth period when none are given: chosen per speed (:func:`choose_intervals`),
#: and for the lobes refined until the estimated error of b_lim is below 1 % (:func:`sdm_lobes`)
DEFAULT_INTERVALS = None
#: the fewest intervals per tooth period the automatic choice uses
MIN_INTERVALS = 40
#: intervals per period of the highest significant mode in the automatic choice: the error of
#: b_lim was measured up to 6.2 (T f / m)^2 (benchmarks/README.md), so 30 per mode period keep
#: it below 1 % where the convergence is of second order (sdm_lobes checks and refines)
INTERVALS_PER_MODE_PERIOD = 30
#: the automatic refinement stops at this many intervals per tooth period
_MAX_INTERVALS = 4096
#: the automatic choice takes m from this ladder (steps of sqrt 2 from MIN_INTERVALS)
_LADDER = np.unique(np.round(MIN_INTERVALS * 2.0 ** (np.arange(16) / 2.0) / 2.0).astype(int) * 2)
#: matrices per batch of matrix exponentials (bounds the memory of one batch to ~ 50 MB)
_BATCH = 200_000
#: monodromy matrices per batch bounded to this many elements (~40 MB)
_BATCH_ELEMENTS = 5_000_000
#: from this size of the monodromy matrix on, its largest eigenvalues come from ARPACK
_ARNOLDI_SIZE = 90

_PADE13 = np.array([64764752532480000.0, 32382376266240000.0, 7771770303897600.0,
                    1187353796428800.0, 129060195264000.0, 10559470521600.0, 670442572800.0,
                    33522128640.0, 1323241920.0, 40840800.0, 960960.0, 16380.0, 182.0, 1.0])
_THETA13 = 5.371920351148152


def _expm(a: np.ndarray) -> np.ndarray:
    """Matrix exponentials of a stack of small matrices (..., k, k): Pade [13/13] with scaling
    and squaring (Higham 2005, Algorithm 2.3), each matrix scaled by its own 1-norm."""
    norm = np.abs(a).sum(axis=-2).max(axis=-1)
    with np.errstate(divide="ignore"):
        s = np.where(norm > _THETA13, np.ceil(np.log2(norm / _THETA13)), 0.0).astype(int)
    a = a / np.exp2(s)[..., None, None]
    b = _PADE13
    eye = np.broadcast_to(np.eye(a.shape[-1]), a.shape)
    a2 = a @ a
    a4 = a2 @ a2
    a6 = a4 @ a2
    u = a @ (a6 @ (b[13] * a6 + b[11] * a4 + b[9] * a2)
             + b[7] * a6 + b[5] * a4 + b[3] * a2 + b[1] * eye)
    v = a6 @ (b[12] * a6 + b[10] * a4 + b[8] * a2) + b[6] * a6 + b[4] * a4 + b[2] * a2 \
        + b[0] * eye
    r = np.linalg.solve(v - u, v + u)
    for step in range(int(s.max()) if s.size else 0):
        square = (s > step)[..., None, None]
        r = np.where(square, r @ r, r)
    return r


@dataclass(frozen=True)
class CuttingStateSpace:
    """The compliance in the form the semi-discretisation needs (SI).

    Attributes
    ----------
    a : numpy.ndarray (n, n)
        State matrix [1/s], balanced (a diagonal similarity that leaves (1) unchanged).
    b : numpy.ndarray (n, r)
        Input matrix from the cutting forces in the flexible directions [N] to dx/dt.
    c : numpy.ndarray (r, n)
        Output matrix to the displacements [m] in the flexible directions.
    directions : tuple of int
        The flexible directions (0 = x, 1 = y); rigid ones are left out of the state.
    mode_frequency : float
        Natural frequency [rad/s] of the highest significant mode: the largest |lambda| among
        the eigenvalues whose resonance (residue over |Re lambda|) reaches 1 % of the largest
        one's (what :func:`choose_intervals` resolves).
    """

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    directions: tuple[int, ...]
    mode_frequency: float = math.nan


def cutting_state_space(system, direction: str = "x") -> CuttingStateSpace:
    """State-space compliance for the semi-discretisation, rigid directions removed.

    Parameters
    ----------
    system : control.StateSpace or control.TransferFunction
        SISO (one flexible ``direction``) or 2 x 2 (outputs x, y; inputs Fx, Fy), stable and
        strictly proper (a displacement cannot respond instantly to a force).
    direction : {"x", "y"}
        Flexible direction of a SISO system.

    Returns
    -------
    CuttingStateSpace
        The balanced (a, b, c) of the flexible directions and the highest significant mode.

    Raises
    ------
    ValueError
        For measured data (the method needs a state-space model), an unstable or not strictly
        proper system, or a shape that is neither SISO nor 2 x 2.
    """
    if isinstance(system, control.TransferFunction):
        system = control.ss(system)
    if not isinstance(system, control.StateSpace):
        raise ValueError(
            "the semi-discretisation needs a state-space model of the compliance "
            "(control.StateSpace or TransferFunction), not measured data; fit modes to the "
            "FRF or use the zero-order method")
    _check_stable(system)
    a, b, c, d = (np.asarray(m, dtype=float) for m in (system.A, system.B, system.C, system.D))
    if np.any(d != 0.0):
        raise ValueError("the compliance must be strictly proper (D = 0): a displacement "
                         "cannot respond instantly to a force")
    if (system.noutputs, system.ninputs) == (1, 1):
        directions = (_direction_index(direction),)
    elif (system.noutputs, system.ninputs) == (2, 2):
        directions = tuple(i for i in range(2)
                           if np.any(c[i] != 0.0) and np.any(b[:, i] != 0.0))
        b, c = b[:, directions], c[directions, :]
    else:
        raise ValueError("the compliance must be SISO or 2 x 2 (outputs x, y; inputs Fx, Fy), "
                         f"got {system.noutputs} outputs x {system.ninputs} inputs")
    if not directions:
        raise ValueError("the compliance is zero in both directions")
    scale = linalg.matrix_balance(a, permute=False, separate=True)[1][0]
    a, b, c = a * scale[None, :] / scale[:, None], b / scale[:, None], c * scale[None, :]
    return CuttingStateSpace(a=a, b=b, c=c, directions=directions,
                             mode_frequency=_highest_significant_mode(a, b, c))


def _highest_significant_mode(a, b, c) -> float:
    """The largest |lambda| [rad/s] among the eigenvalues whose resonance height, the norm of
    the residue C v w^T B over |Re lambda|, is at least 1 % of the largest one."""
    lam, v = np.linalg.eig(a)
    try:
        w = np.linalg.inv(v)
    except np.linalg.LinAlgError:
        return float(np.abs(lam).max())
    residue = np.abs(c @ v).max(axis=0) * np.abs(w @ b).max(axis=1)
    height = residue / np.maximum(np.abs(lam.real), 1e-12 * np.abs(lam))
    if not np.all(np.isfinite(height)):
        return float(np.abs(lam).max())
    return float(np.abs(lam[height >= 1e-2 * height.max()]).max())


def choose_intervals(model: CuttingStateSpace, period) -> np.ndarray:
    """Return the intervals per tooth period for the semi-discretisation at each tooth period.

    ``m >= max(MIN_INTERVALS, INTERVALS_PER_MODE_PERIOD T f)`` with f = ``model.mode_frequency``
    / 2 pi, the highest significant mode, rounded up on a ladder of steps of sqrt 2 from
    MIN_INTERVALS (so that speeds share matrices). The first-order semi-discretisation
    interpolates the delayed displacement linearly over T/m; its error in b_lim was measured
    to fall as K (T f / m)^2 with K up to 6.2 (benchmarks/README.md), which this keeps below
    1 %; :func:`sdm_lobes` checks it and refines further where the convergence is slower.

    Parameters
    ----------
    model : CuttingStateSpace
        The compliance; its ``mode_frequency`` [rad/s] sets the resolution needed.
    period : array_like
        Tooth periods T [s].

    Returns
    -------
    numpy.ndarray of int
        Intervals m per tooth period, shape of ``period``.

    Examples
    --------
    The Insperger-Stepan benchmark (922 Hz) at 3,000 rpm with two teeth spans 9.2 periods of
    its mode per tooth period:

    >>> from servotune.chatter import Mode, modal_compliance
    >>> wn = 2 * math.pi * 922.0
    >>> model = cutting_state_space(modal_compliance([Mode(wn, 0.011, 0.03993 * wn**2)]))
    >>> choose_intervals(model, [60 / (2 * 3000.0), 60 / (2 * 30000.0)]).tolist()
    [320, 40]
    """
    period = np.asarray(period, dtype=float)
    need = INTERVALS_PER_MODE_PERIOD * period * model.mode_frequency / (2.0 * math.pi)
    need = np.maximum(np.nan_to_num(need, nan=0.0), MIN_INTERVALS)
    return _LADDER[np.minimum(np.searchsorted(_LADDER, need), _LADDER.size - 1)]


def _check_intervals(intervals) -> int:
    if (isinstance(intervals, bool) or not isinstance(intervals, int | np.integer | float)
            or int(intervals) != intervals or intervals < 2):
        raise ValueError(f"intervals (per tooth period) must be a whole number >= 2, "
                         f"got {intervals!r}")
    return int(intervals)


def monodromy_spectral_radius(model: CuttingStateSpace, h, period, depth,
                              return_multiplier: bool = False):
    """Spectral radius of the semi-discretised monodromy matrix at (period, depth) points.

    Parameters
    ----------
    model : CuttingStateSpace
        The compliance in state-space form (:func:`cutting_state_space`).
    h : array_like, shape (m, r, r) or (m, 2, 2)
        Mean directional matrix of each of the m intervals of one period [N/m^2] (a constant
        stack gives the time-invariant, zero-order process). 2 x 2 matrices are reduced to the
        flexible directions of ``model``.
    period : array_like
        Delay = principal period T [s] of each point (> 0).
    depth : array_like
        Axial depth of cut b [m] of each point (>= 0); broadcast against ``period``.
    return_multiplier : bool
        Also return the critical multiplier (the eigenvalue of largest modulus) of each point.

    Returns
    -------
    numpy.ndarray
        Spectral radius, shape ``np.broadcast(period, depth).shape``; < 1 is stable. With
        ``return_multiplier``, a tuple (radius, multiplier).

    Examples
    --------
    With no cut (b = 0) the multipliers are those of the free structure, exp(lambda T):

    >>> from servotune.chatter import Mode, modal_compliance
    >>> model = cutting_state_space(modal_compliance([Mode(1000.0, 0.05, 1e6)]))
    >>> h = np.zeros((10, 1, 1))
    >>> rho = monodromy_spectral_radius(model, h, 0.01, 0.0)
    >>> bool(np.isclose(rho, math.exp(-0.05 * 1000.0 * 0.01)))
    True
    """
    h = np.asarray(h, dtype=float)
    if h.ndim != 3 or h.shape[0] < 2:
        raise ValueError("h must be a stack (m, r, r) of m >= 2 directional matrices")
    if h.shape[1:] == (2, 2) and len(model.directions) == 1:
        h = h[:, model.directions][:, :, model.directions]
    r = model.b.shape[1]
    if h.shape[1:] != (r, r):
        raise ValueError(f"h must be (m, {r}, {r}) for this model, got {h.shape}")
    period, depth = np.broadcast_arrays(np.asarray(period, dtype=float),
                                        np.asarray(depth, dtype=float))
    shape = period.shape
    period, depth = period.ravel(), depth.ravel()
    if np.any(~np.isfinite(period)) or np.any(period <= 0.0):
        raise ValueError("period must be positive and finite [s]")
    if np.any(~np.isfinite(depth)) or np.any(depth < 0.0):
        raise ValueError("depth must be finite and >= 0 [m]")
    m = h.shape[0]
    size = model.a.shape[0] + m * r
    points_per_batch = max(1, min(_BATCH // m, _BATCH_ELEMENTS // (size * size)))
    radius = np.empty(period.size)
    multiplier = np.empty(period.size, dtype=complex)
    for start in range(0, period.size, points_per_batch):
        sl = slice(start, start + points_per_batch)
        radius[sl], multiplier[sl] = _monodromy_batch(model, h, period[sl], depth[sl])
    radius = radius.reshape(shape)
    if return_multiplier:
        return radius, multiplier.reshape(shape)
    return radius


def _monodromy_batch(model, h, period, depth):
    a, bf, c = model.a, model.b, model.c
    n, r = bf.shape
    m = h.shape[0]
    p = period.size
    dt = period / m                                              # (p,)
    bh = depth[:, None, None, None] * h[None]                    # (p, m, r, r)  b H_i
    k = n + 2 * r
    aug = np.zeros((p, m, k, k))
    aug[:, :, :n, :n] = a - bf @ bh @ c                          # A_i
    aug[:, :, :n, n:n + r] = bf
    aug[:, :, n:n + r, n + r:] = np.eye(r)
    e = _expm(aug * dt[:, None, None, None])
    p_i = e[:, :, :n, :n]
    g1 = e[:, :, :n, n:n + r]
    g2 = e[:, :, :n, n + r:] / dt[:, None, None, None]
    r0 = (g1 - g2) @ bh                                          # weight of q_(i-m)
    r1 = g2 @ bh                                                 # weight of q_(i-m+1)

    size = n + m * r
    x = np.zeros((p, n, size))
    x[:, :, :n] = np.eye(n)
    rows = [None] * m                                            # q_i = C x_i, i = 0..m-1
    for i in range(m):
        rows[i] = c @ x
        x_next = p_i[:, i] @ x
        off = n + (m - i - 1) * r
        x_next[:, :, off:off + r] += r0[:, i]
        if i < m - 1:
            off = n + (m - i - 2) * r
            x_next[:, :, off:off + r] += r1[:, i]
        else:                                                    # q_0 = C x_0
            x_next[:, :, :n] += r1[:, i] @ c
        x = x_next
    phi = np.concatenate([x, *rows[::-1]], axis=1)               # (p, size, size)
    critical = _critical_multipliers(phi)
    return np.abs(critical), critical


def _critical_multipliers(phi: np.ndarray) -> np.ndarray:
    """The eigenvalue of largest modulus of each matrix of a stack (p, N, N).

    Small matrices: all eigenvalues at once (LAPACK). From N = _ARNOLDI_SIZE on, where the
    history of many intervals makes the dense eigenvalue problem costly (O(N^3)), the few
    largest by implicitly restarted Arnoldi (ARPACK, scipy.sparse.linalg.eigs), with the dense
    solution as the fallback where it does not converge.
    """
    p, size = phi.shape[0], phi.shape[1]
    if size < _ARNOLDI_SIZE:
        eig = np.linalg.eigvals(phi)
        return eig[np.arange(p), np.argmax(np.abs(eig), axis=1)]
    out = np.empty(p, dtype=complex)
    for k in range(p):
        try:
            eig = sparse_linalg.eigs(phi[k], k=4, which="LM", return_eigenvectors=False,
                                     tol=1e-12, ncv=min(size - 1, 24))
        except (sparse_linalg.ArpackNoConvergence, sparse_linalg.ArpackError):
            eig = np.linalg.eigvals(phi[k])
        out[k] = eig[np.argmax(np.abs(eig))]
    return out


def _tooth_period(setup: MillingSetup, speed_rpm) -> np.ndarray:
    return 60.0 / (setup.teeth * np.asarray(speed_rpm, dtype=float))


def _warn_helix(setup: MillingSetup) -> None:
    if setup.helix_angle != 0.0:
        warnings.warn("the helix angle is ignored: the semi-discretisation here models straight "
                      "flutes", UserWarning, stacklevel=3)


@dataclass(frozen=True)
class StabilityMap:
    """Spectral radius of the monodromy matrix over a (speed, depth) grid.

    Attributes
    ----------
    setup : MillingSetup
    speed_rpm : numpy.ndarray (ns,)
        Spindle speeds [rpm].
    depth : numpy.ndarray (nd,)
        Axial depths of cut [m].
    spectral_radius : numpy.ndarray (ns, nd)
        Largest Floquet multiplier modulus; < 1 is stable.
    multiplier : numpy.ndarray (ns, nd) of complex
        The critical multiplier (near -1 at a flip boundary, a complex pair at a Hopf one).
    intervals : int
        Intervals per tooth period (the largest used).
    intervals_by_speed : numpy.ndarray of int (ns,)
        Intervals per tooth period at each speed.
    """

    setup: MillingSetup
    speed_rpm: np.ndarray
    depth: np.ndarray
    spectral_radius: np.ndarray
    multiplier: np.ndarray
    intervals: int
    intervals_by_speed: np.ndarray | None = None

    @property
    def stable(self) -> np.ndarray:
        """Boolean (ns, nd): spectral radius below 1."""
        return self.spectral_radius < 1.0

    def to_dict(self) -> dict:
        """JSON-ready dictionary (SI; speeds in rpm).

        Returns
        -------
        dict
            JSON-ready values (str, numbers, lists, None).
        """
        by_speed = (None if self.intervals_by_speed is None
                    else np.asarray(self.intervals_by_speed).tolist())
        return {"method": "sdm", "setup": self.setup.to_dict(), "intervals": self.intervals,
                "intervals_by_speed": by_speed,
                "speed_rpm": self.speed_rpm.tolist(), "depth_m": self.depth.tolist(),
                "spectral_radius": self.spectral_radius.tolist()}

    def plot(self, **kwargs):
        """Draw the spectral radius with the boundary ``|mu| = 1``.

        Parameters
        ----------
        **kwargs
            Passed to :func:`servotune.plots.plot_stability_map`.

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        from .. import plots

        return plots.plot_stability_map(self, **kwargs)


def _intervals_for(model, setup, speeds, intervals) -> np.ndarray:
    """Intervals per tooth period at each speed: given, or :func:`choose_intervals`."""
    if intervals is None:
        return choose_intervals(model, _tooth_period(setup, speeds))
    return np.full(np.shape(speeds), _check_intervals(intervals), dtype=int)


def stability_map(system, setup: MillingSetup, speeds_rpm, depths, *,
                  intervals: int | None = DEFAULT_INTERVALS,
                  direction: str = "x") -> StabilityMap:
    """Semi-discretisation over a grid of spindle speeds and depths of cut.

    Parameters
    ----------
    system : control.StateSpace or control.TransferFunction
        Tool/work-piece compliance (see :func:`cutting_state_space`).
    setup : MillingSetup
        The milling set-up (teeth, cutting coefficients, immersion).
    speeds_rpm : array_like
        Ascending spindle speeds [rpm].
    depths : array_like
        Axial depths of cut [m], >= 0.
    intervals : int, optional
        Intervals m per tooth period (>= 2); the error falls roughly as 1/m^2. Default: chosen
        per speed from the tooth period and the highest significant mode
        (:func:`choose_intervals`).
    direction : {"x", "y"}
        Flexible direction of a SISO compliance.

    Returns
    -------
    StabilityMap
        The spectral radius (and the critical multiplier) at every (depth, speed) point.

    Examples
    --------
    Below the absolute zero-order limit (0.298 mm for the Insperger-Stepan benchmark) a full
    slot is stable at every speed; 2 mm chatters near the lobe minima, not in the pocket
    between them:

    >>> from servotune.chatter import Mode, modal_compliance
    >>> wn = 2 * math.pi * 922.0
    >>> sys = modal_compliance([Mode(wn, 0.011, 0.03993 * wn**2)])
    >>> r = stability_map(sys, MillingSetup(teeth=2, kt=6e8, kn=2e8),
    ...                   [10000, 12000, 16000], [0.1e-3, 2e-3], intervals=20)
    >>> r.stable.tolist()
    [[True, False], [True, True], [True, False]]
    """
    setup = _check_setup(setup)
    _warn_helix(setup)
    speeds = _check_speeds(speeds_rpm)
    depths = np.atleast_1d(np.asarray(depths, dtype=float))
    if depths.ndim != 1 or np.any(~np.isfinite(depths)) or np.any(depths < 0.0):
        raise ValueError("depths must be a 1-D array of finite depths >= 0 [m]")
    model = cutting_state_space(system, direction)
    m_by = _intervals_for(model, setup, speeds, intervals)
    rho = np.empty((speeds.size, depths.size))
    mult = np.empty((speeds.size, depths.size), dtype=complex)
    for m in np.unique(m_by):
        sel = m_by == m
        h = periodic_directional_matrix(setup, int(m))
        rho[sel], mult[sel] = monodromy_spectral_radius(
            model, h, _tooth_period(setup, speeds[sel])[:, None], depths[None, :],
            return_multiplier=True)
    return StabilityMap(setup=setup, speed_rpm=speeds, depth=depths, spectral_radius=rho,
                        multiplier=mult, intervals=int(m_by.max()), intervals_by_speed=m_by)


def _limit_depths(model, h, period, depth_max, scan, tol):
    """Per period: the first depth at which the spectral radius reaches 1 (bisection after a
    uniform scan of ``scan`` depths up to depth_max); inf if stable up to depth_max."""
    grid = depth_max * np.arange(1, scan + 1) / scan
    rho = monodromy_spectral_radius(model, h, period[:, None], grid[None, :])
    unstable = rho >= 1.0
    found = unstable.any(axis=1)
    first = np.argmax(unstable, axis=1)
    hi = np.where(found, grid[first], np.inf)
    lo = np.where(first > 0, grid[np.maximum(first - 1, 0)], 0.0)
    idx = np.flatnonzero(found)
    lo_f, hi_f, per_f = lo[idx], hi[idx], period[idx]
    while idx.size and np.max(hi_f - lo_f) > tol * depth_max:
        mid = 0.5 * (lo_f + hi_f)
        bad = monodromy_spectral_radius(model, h, per_f, mid) >= 1.0
        hi_f = np.where(bad, mid, hi_f)
        lo_f = np.where(bad, lo_f, mid)
    out = np.full(period.size, np.inf)
    out[idx] = 0.5 * (lo_f + hi_f)
    return out


@dataclass(frozen=True)
class SdmLobes(StabilityLobes):
    """:class:`~servotune.chatter.zoa.StabilityLobes` of the semi-discretisation, with the
    intervals used at each speed and the estimated error of b_lim.

    Attributes
    ----------
    intervals_by_speed : numpy.ndarray of int
        Intervals per tooth period at each speed (``intervals`` is the largest).
    error_estimate : numpy.ndarray
        Estimated relative error of b_lim at each speed (NaN where not estimated: fixed
        intervals given), from the change of b_lim over the last refinement.
    max_error_estimate : float
        The largest of them over the speeds with a finite limit (NaN if none was estimated).
    """

    intervals_by_speed: np.ndarray | None = None
    error_estimate: np.ndarray | None = None
    max_error_estimate: float = math.nan

    def to_dict(self) -> dict:
        """Return :meth:`StabilityLobes.to_dict` with the intervals and error estimates by speed.

        Returns
        -------
        dict
            JSON-ready values (str, numbers, lists, None).
        """
        out = super().to_dict()
        out["intervals_by_speed"] = (None if self.intervals_by_speed is None
                                     else np.asarray(self.intervals_by_speed).tolist())
        out["max_error_estimate"] = (self.max_error_estimate
                                     if math.isfinite(self.max_error_estimate) else None)
        return out


def _limits_by_intervals(model, setup, periods, m_by, depth_max, scan, tol):
    """b_lim at each period with its own number of intervals (grouped by m)."""
    out = np.empty(periods.size)
    for m in np.unique(m_by):
        sel = m_by == m
        out[sel] = _limit_depths(model, periodic_directional_matrix(setup, int(m)),
                                 periods[sel], depth_max, scan, tol)
    return out


def _relative_change(fine, coarse):
    """Estimated relative error of ``fine`` (m intervals) from ``coarse`` (m / 2), at first
    order (see :func:`sdm_lobes`)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        change = np.abs(coarse - fine) / fine
    both_inf = ~np.isfinite(fine) & ~np.isfinite(coarse)
    return np.where(both_inf, 0.0, np.where(np.isnan(change), np.inf, change))


def sdm_lobes(system, setup: MillingSetup, speeds_rpm=None, depth_max: float | None = None,
              *, intervals: int | None = DEFAULT_INTERVALS, direction: str = "x",
              scan: int = 16, tol: float = 1e-4, rtol: float = 0.01) -> SdmLobes:
    """Stability limit b_lim(n) by semi-discretisation: the lowest depth that is unstable.

    At each speed the spectral radius is scanned on ``scan`` equal depth steps up to
    ``depth_max``; the first unstable step is refined by bisection to ``tol * depth_max``. The
    smallest limit over the speed grid is then refined by a bounded search over speed between
    the neighbouring grid speeds.

    By default the number of intervals per tooth period is chosen per speed
    (:func:`choose_intervals`) and checked: b_lim is computed also with half the intervals,
    and the change between the two estimates the error of the finer one (Richardson: for
    convergence at order p the error of b(m) is ``|b(m/2) - b(m)| / (2^p - 1)``). The method
    converges at second order where the cut is long (full slot) but more slowly and less
    regularly at low immersion, where the tooth enters and leaves inside an interval (order
    1.35 measured at a/D = 0.05, benchmarks/README.md; b(m) then wanders with m), so the
    estimate takes p = 1, the change itself. Where it exceeds ``rtol`` the intervals are
    doubled and the estimate taken again, until it does not (or m reaches 4096). The
    estimates are returned; they are estimates, not bounds.

    Parameters
    ----------
    system, setup
        As for :func:`stability_map`.
    speeds_rpm : array_like, optional
        Ascending spindle speeds [rpm]; default 200 speeds over
        :func:`~servotune.chatter.zoa.default_speed_range`.
    depth_max : float, optional
        Deepest cut examined [m]; speeds stable up to it get ``inf``. Default five times the
        zero-order b_crit.
    intervals : int, optional
        Intervals per tooth period (>= 2) at every speed, without the check; default
        automatic, as above.
    direction : {"x", "y"}
        Flexible direction of a SISO compliance.
    scan : int
        Depth steps of the initial scan (an unstable island thinner than depth_max/scan
        below the first boundary could be missed).
    tol : float
        Bisection tolerance relative to depth_max.
    rtol : float
        Relative error of b_lim allowed by the automatic choice of intervals (default 1 %).

    Returns
    -------
    SdmLobes
        ``method="sdm"``; ``chatter_frequency`` is NaN (not computed); the intervals and the
        error estimate at each speed.

    Raises
    ------
    ValueError
        For a compliance the method cannot use (see :func:`cutting_state_space`), bad speeds,
        depths, intervals, or the reasons of :class:`MillingSetup`.

    See Also
    --------
    servotune.chatter.zoa.stability_lobes : The zero-order lobes, faster and smooth.
    stability_map : The spectral radius over a grid of speeds and depths.
    servotune.frequency.compliance : The work-piece compliance of the controlled axis.

    Examples
    --------
    In a full slot the zero-order minimum (0.298 mm for the Insperger-Stepan benchmark) is
    close to the semi-discretisation's, and on the safe side:

    >>> from servotune.chatter import Mode, modal_compliance
    >>> wn = 2 * math.pi * 922.0
    >>> sys = modal_compliance([Mode(wn, 0.011, 0.03993 * wn**2)])
    >>> r = sdm_lobes(sys, MillingSetup(teeth=2, kt=6e8, kn=2e8),
    ...               np.linspace(14000, 18000, 9), 1e-3)
    >>> round(r.b_crit / 0.29805e-3, 2), bool(r.max_error_estimate < 0.01)
    (1.07, True)
    """
    setup = _check_setup(setup)
    _warn_helix(setup)
    model = cutting_state_space(system, direction)
    if speeds_rpm is None:
        speeds_rpm = np.linspace(*default_speed_range(system, setup, direction=direction), 200)
    speeds = _check_speeds(speeds_rpm)
    if depth_max is None:
        depth_max = 5.0 * absolute_stability_limit(system, setup, direction=direction)[0]
    depth_max = float(depth_max)
    if not math.isfinite(depth_max) or depth_max <= 0.0:
        raise ValueError(f"depth_max must be a positive depth [m], got {depth_max!r}")
    if isinstance(scan, bool) or int(scan) != scan or scan < 2:
        raise ValueError(f"scan must be a whole number >= 2, got {scan!r}")
    if not 0.0 < tol < 0.1:
        raise ValueError(f"tol must lie in (0, 0.1), got {tol!r}")
    if not 0.0 < rtol < 1.0:
        raise ValueError(f"rtol must lie in (0, 1), got {rtol!r}")
    periods = _tooth_period(setup, speeds)
    m_by = _intervals_for(model, setup, speeds, intervals)
    limit = _limits_by_intervals(model, setup, periods, m_by, depth_max, int(scan), tol)
    error = np.full(speeds.size, np.nan)
    if intervals is None:
        coarse = _limits_by_intervals(model, setup, periods, m_by // 2, depth_max, int(scan),
                                      tol)
        error = _relative_change(limit, coarse)
        todo = np.flatnonzero((error > rtol) & (m_by < _MAX_INTERVALS))
        while todo.size:
            m_by[todo] *= 2
            finer = _limits_by_intervals(model, setup, periods[todo], m_by[todo], depth_max,
                                         int(scan), tol)
            error[todo] = _relative_change(finer, limit[todo])
            limit[todo] = finer
            todo = todo[(error[todo] > rtol) & (m_by[todo] < _MAX_INTERVALS)]
    i = int(np.argmin(limit))
    b_min, n_min = float(limit[i]), float(speeds[i])
    if math.isfinite(b_min) and 0 < i < speeds.size - 1:
        h = periodic_directional_matrix(setup, int(m_by[i]))

        def at(n):
            return float(_limit_depths(model, h, _tooth_period(setup, np.array([n])),
                                       depth_max, int(scan), tol)[0])
        res = optimize.minimize_scalar(at, bounds=(speeds[i - 1], speeds[i + 1]),
                                       method="bounded",
                                       options={"xatol": 1e-6 * speeds[i], "maxiter": 40})
        if res.fun < b_min:
            b_min, n_min = float(res.fun), float(res.x)
    finite = np.isfinite(limit) & np.isfinite(error)
    return SdmLobes(
        setup=setup, method="sdm", speed_rpm=speeds, depth_limit=limit,
        chatter_frequency=np.full(speeds.size, np.nan), b_crit=b_min,
        critical_speed_rpm=n_min, critical_frequency=math.nan, min_depth_limit=b_min,
        lobe_speed_rpm=np.empty((0, 0)), lobe_depth=np.empty((0, 0)), lobe_count=0,
        depth_ceiling=depth_max, intervals=int(m_by.max()), intervals_by_speed=m_by,
        error_estimate=error,
        max_error_estimate=float(error[finite].max()) if finite.any() else math.nan)
