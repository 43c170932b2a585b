"""Zero-order approximation of milling stability (Altintas and Budak 1995): lobes, b_crit, margin.

The regenerative force ``F(t) = -b H(t) (q(t) - q(t - T))`` (see :mod:`servotune.chatter.setup`)
is replaced by its mean, ``H(t) -> D``, the directional matrix. With the tool/work-piece
compliance ``q = G(i w) F`` a vibration at the chatter frequency w is self-sustained when::

    det[ I + b (1 - exp(-i w T)) G(i w) D ] = 0                                   (1)

**Oriented FRF.** Let ``Phi(w)`` be an eigenvalue of ``G(i w) D / K_t`` [m/N] (there are two,
one per "oriented direction"). Then (1) holds when ``1 + b K_t (1 - exp(-i w T)) Phi = 0``.
Because ``1 / (1 - exp(-i theta)) = 1/2 - (i/2) cot(theta/2)``, its real and imaginary parts
give::

    b_lim(w) = -1 / (2 K_t Re Phi(w))                      (needs Re Phi(w) < 0)     (2)
    cot(theta/2) = -Im Phi / Re Phi,   theta = pi + 2 arctan(Im Phi / Re Phi)  in (0, 2 pi)
    w T = theta + 2 pi k,   n_rpm = 60 / (N T) = 60 w / (N (theta + 2 pi k)),  k = 0, 1, ...

Each k traces one lobe (n_rpm(w), b_lim(w)); the lower envelope over k and over both
eigenvalues is the stability limit. Every lobe has the same minimum, the **absolute stability
limit**::

    b_crit = -1 / (2 K_t min_w Re Phi(w))                                           (3)

This is Altintas and Budak's eigenvalue form in other words: their
``Lambda = -N b K_t (1 - exp(-i w T)) / (4 pi)`` solves ``det[I + Lambda G0] = 0`` with
``G0 = [alpha] G`` and ``-(N/(4 pi)) [alpha] = D / K_t``, so ``Lambda = 1 / Phi`` and their
``b_lim = -2 pi Lambda_R (1 + kappa^2) / (N K_t)`` with ``kappa = Lambda_I / Lambda_R`` is (2)
(Altintas and Budak 1995, Eq 19-24; Altintas 2012, Eq 3.70-3.76).

**One flexible direction** (Tlusty): ``Phi = mu_d G_dd`` with the directional factor
``mu_d = D_dd / K_t`` and (2) is ``b_lim = -1 / (2 K_s mu Re G)`` with K_s = K_t. For a single
mode ``G = (1/k) / (1 - r^2 + 2 i zeta r)``, Re G is least at ``w = w_n sqrt(1 + 2 zeta)`` where
it is ``-1 / (4 k zeta (1 + zeta))``, so ``b_crit K_t mu = 2 k zeta (1 + zeta)``.

**The 2 x 2 eigenvalues** in closed form (useful to an optimiser): with ``M = G D / K_t``,
``Phi = tr M / 2 -/+ sqrt(tr(M)^2 / 4 - det M)``.

**A margin an optimiser can differentiate.** b_crit >= b_req is the same as the set of smooth
constraints ``1 + 2 K_t b_req Re Phi(w_i) >= 0`` at every grid frequency w_i; the ratio
``b_crit / b_req`` (:func:`chatter_margin`) is the same statement as a single number.
:func:`critical_depth` is (3) on a grid, the form to mirror in an algebraic modelling language
(there a smooth minimum replaces ``min``).

The approximation neglects the harmonics of H(t). It is accurate when many teeth are in the
cut; at low radial immersion (few teeth cutting, strongly intermittent force) period-doubling
("flip") lobes appear that it cannot predict: use :mod:`servotune.chatter.sdm` there.

References
----------
Y. Altintas, E. Budak, "Analytical prediction of stability lobes in milling", CIRP Annals 44
(1995) 357-362.
Y. Altintas, Manufacturing Automation, 2nd ed., Cambridge University Press (2012), ch 3.
J. Tlusty, M. Polacek, "The stability of machine tools against self-excited vibrations in
machining", Proc ASME Int Research in Production Engineering (1963) 465-474.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np
from scipy import optimize

from ..units import HZ_PER_RAD_S
from .frf import _as_matrix, compliance_matrix, frequency_grid, system_response
from .setup import MillingSetup, directional_matrix

__all__ = [
    "StabilityLobes",
    "absolute_stability_limit",
    "chatter_margin",
    "critical_depth",
    "default_speed_range",
    "oriented_frf",
    "spindle_speeds",
    "stability_lobes",
]

#: the most lobes the automatic choice will trace before asking for a higher lowest speed
MAX_LOBES = 5000
#: lobe points handled at once when the envelope is formed (bounds the memory to ~ 0.3 GB)
_POINTS_PER_CHUNK = 4_000_000


def _check_setup(setup) -> MillingSetup:
    if not isinstance(setup, MillingSetup):
        raise ValueError(f"setup must be a MillingSetup, got {type(setup).__name__}")
    return setup


def oriented_frf(g, setup: MillingSetup) -> np.ndarray:
    """The oriented FRFs Phi(w) [m/N]: the eigenvalues of ``G(i w) D / K_t``.

    Parameters
    ----------
    g : array_like of complex, shape (nfreq, 2, 2)
        The compliance matrix (as returned by :func:`compliance_matrix`).
    setup : MillingSetup
        The milling set-up: its directional matrix D and tangential coefficient K_t.

    Returns
    -------
    numpy.ndarray of complex, shape (nfreq, 2)
        The two eigenvalues at each frequency, each column following one continuous branch
        (the pairing with the previous frequency that moves least).

    Raises
    ------
    ValueError
        When ``g`` is not of shape (nfreq, 2, 2), or ``setup`` is not a MillingSetup.

    Examples
    --------
    One flexible direction: one branch is ``mu G_xx``, the other zero.

    >>> from servotune.chatter.setup import directional_factor
    >>> s = MillingSetup(teeth=2, kt=6e8, kn=2e8)
    >>> g = np.zeros((1, 2, 2), complex); g[0, 0, 0] = -1e-6 - 2e-6j
    >>> phi = sorted(oriented_frf(g, s)[0], key=abs)
    >>> complex(phi[0]), bool(np.isclose(phi[1], directional_factor(s, "x") * g[0, 0, 0]))
    (0j, True)
    """
    setup = _check_setup(setup)
    g = np.asarray(g, dtype=complex)
    if g.ndim != 3 or g.shape[1:] != (2, 2):
        raise ValueError(f"g must have shape (nfreq, 2, 2), got {g.shape}")
    m = g @ (directional_matrix(setup) / setup.kt)
    half_trace = 0.5 * (m[:, 0, 0] + m[:, 1, 1])
    det = m[:, 0, 0] * m[:, 1, 1] - m[:, 0, 1] * m[:, 1, 0]
    root = np.sqrt(half_trace * half_trace - det)
    phi = np.stack([half_trace + root, half_trace - root], axis=1)
    if phi.shape[0] > 1:  # follow each branch through the square root's branch cut
        straight = np.abs(np.diff(phi, axis=0)).sum(axis=1)
        crossed = (np.abs(phi[1:, 0] - phi[:-1, 1]) + np.abs(phi[1:, 1] - phi[:-1, 0]))
        swap = np.concatenate([[False], crossed < straight])
        flip = (np.cumsum(swap) % 2).astype(bool)
        phi[flip] = phi[flip][:, ::-1]
    return phi


def critical_depth(oriented_real_part, kt: float, omega=None) -> float:
    """The absolute stability limit b_crit = -1 / (2 K_t min Re Phi) [m] from a frequency grid.

    Parameters
    ----------
    oriented_real_part : array_like
        Re Phi(w) [m/N] of the oriented FRF on a frequency grid (any shape; for a 2-D
        problem pass both branches).
    kt : float
        Tangential cutting coefficient K_t [N/m^2].
    omega : array_like, optional
        The grid [rad/s] of a 1-D ``oriented_real_part``. When given, the minimum is refined
        by the parabola through the grid minimum and its two neighbours (never above the grid
        minimum). Without it the grid minimum is used as it is.

    Returns
    -------
    float
        b_crit [m].

    Raises
    ------
    ValueError
        If no real part is negative: then no depth of cut is unstable on this grid (by the
        zero-order model), or the grid misses the resonances.

    Examples
    --------
    Tlusty's single mode: ``b_crit K_t mu = 2 k zeta (1 + zeta)``.

    >>> k, zeta, wn, kt, mu = 1e7, 0.02, 1000.0, 1e9, 0.5
    >>> w = np.linspace(900.0, 1100.0, 20001)
    >>> re_g = ((1 / k) / (1 - (w / wn)**2 + 2j * zeta * w / wn)).real
    >>> b = critical_depth(mu * re_g, kt, w)
    >>> round(b * kt * mu / (2 * k * zeta * (1 + zeta)), 9)
    1.0
    """
    kt = float(kt)
    if not math.isfinite(kt) or kt <= 0.0:
        raise ValueError(f"kt must be a positive finite number [N/m^2], got {kt!r}")
    re = np.asarray(oriented_real_part, dtype=float)
    if re.size == 0 or not np.all(np.isfinite(re)):
        raise ValueError("oriented_real_part must be a non-empty array of finite values")
    i = int(np.argmin(re))
    lowest = float(re.flat[i])
    if lowest >= 0.0:
        raise ValueError(
            "the oriented FRF has no negative real part on this frequency grid: the zero-order "
            "model finds no chatter at any depth (check that the grid covers the resonances "
            "and that the compliance and the cutting set-up are right)")
    if omega is not None:
        w = np.asarray(omega, dtype=float)
        if re.ndim != 1 or w.shape != re.shape:
            raise ValueError("omega must be 1-D with the shape of oriented_real_part")
        if 0 < i < re.size - 1:
            lowest = min(lowest, _parabola_minimum(w[i - 1:i + 2], re[i - 1:i + 2]))
    return -1.0 / (2.0 * kt * lowest)


def _parabola_minimum(x, y) -> float:
    """Lowest value of the parabola through three points (x ascending, y[1] the smallest)."""
    (x0, x1, x2), (y0, y1, y2) = x, y
    d01, d12 = (y1 - y0) / (x1 - x0), (y2 - y1) / (x2 - x1)
    curvature = (d12 - d01) / (x2 - x0)
    if curvature <= 0.0:
        return float(y1)
    slope1 = d01 + curvature * (x1 - x0)  # derivative at x1
    return float(y1 - slope1 * slope1 / (4.0 * curvature))


def _oriented_at(system, direction, setup, w: float) -> np.ndarray:
    """Both oriented FRF values at one frequency of a python-control system."""
    g = _as_matrix(system_response(system, np.array([w])), direction, "the system")
    return oriented_frf(g, setup)[0]


def absolute_stability_limit(system, setup: MillingSetup, omega=None,
                             direction: str = "x") -> tuple[float, float]:
    """Return b_crit [m] and the chatter frequency there [rad/s], by Eq (3) of the module docstring.

    For a python-control system the minimum of Re Phi found on the grid is refined by a bounded
    scalar search on the system itself; for measured data by a parabola through the grid
    minimum.

    Parameters
    ----------
    system : control.StateSpace, control.TransferFunction, control.FrequencyResponseData or \
tuple (omega, H)
        The tool/work-piece compliance [m/N], 2 x 2 (x, y) or SISO
        (see :func:`compliance_matrix`).
    setup : MillingSetup
        The milling set-up.
    omega : array_like, optional
        Frequency grid [rad/s] for a python-control system (default: :func:`frequency_grid`).
    direction : {"x", "y"}, optional
        Flexible direction of a SISO compliance (default "x").

    Returns
    -------
    b_crit : float
        The absolute stability limit, the axial depth of cut [m] below which the cut is stable
        at every spindle speed.
    omega_c : float
        The chatter frequency at b_crit [rad/s].

    Raises
    ------
    ValueError
        For bad input (see :func:`compliance_matrix`, :class:`MillingSetup`) or an oriented
        FRF with no negative real part (no chatter limit).

    Examples
    --------
    Tlusty's single mode, ``b_crit K_t mu = 2 k zeta (1 + zeta)`` at ``w_n sqrt(1 + 2 zeta)``:

    >>> from servotune.chatter import Mode, modal_compliance, directional_factor
    >>> wn, zeta, k = 2 * math.pi * 922.0, 0.011, 0.03993 * (2 * math.pi * 922.0)**2
    >>> setup = MillingSetup(teeth=2, kt=6e8, kn=2e8)
    >>> b, wc = absolute_stability_limit(modal_compliance([Mode(wn, zeta, k)]), setup)
    >>> round(b * setup.kt * directional_factor(setup) / (2 * k * zeta * (1 + zeta)), 9)
    1.0
    >>> round(wc / (wn * math.sqrt(1 + 2 * zeta)), 7)
    1.0
    """
    setup = _check_setup(setup)
    w, g = compliance_matrix(system, omega, direction)
    b, wc, _ = _absolute_limit(system, direction, setup, w, oriented_frf(g, setup))
    return b, wc


def _absolute_limit(system, direction, setup, w, phi) -> tuple[float, float, complex]:
    """(b_crit, omega_c, Phi(omega_c)) with the grid minimum refined."""
    re = phi.real
    branch = int(np.argmin(re.min(axis=0)))
    i = int(np.argmin(re[:, branch]))
    b_grid = critical_depth(re[:, branch], setup.kt)  # raises if nothing is negative
    if not 0 < i < w.size - 1:
        return b_grid, float(w[i]), complex(phi[i, branch])
    if isinstance(system, (control.StateSpace, control.TransferFunction)):
        scale = abs(re[i, branch])
        res = optimize.minimize_scalar(
            lambda x: _oriented_at(system, direction, setup, x).real.min() / scale,
            bounds=(w[i - 1], w[i + 1]), method="bounded",
            options={"xatol": 1e-10 * w[i]})
        if res.fun * scale < re[i, branch]:
            wc = float(res.x)
            values = _oriented_at(system, direction, setup, wc)
            phi_c = complex(values[np.argmin(values.real)])
            return float(-1.0 / (2.0 * setup.kt * phi_c.real)), wc, phi_c
        return b_grid, float(w[i]), complex(phi[i, branch])
    b = critical_depth(re[i - 1:i + 2, branch], setup.kt, w[i - 1:i + 2])
    return b, float(w[i]), complex(phi[i, branch])


@dataclass(frozen=True)
class StabilityLobes:
    """Stability lobes of a milling set-up (zero-order approximation or semi-discretisation).

    Attributes
    ----------
    setup : MillingSetup
    method : str
        ``"zoa"`` or ``"sdm"``.
    speed_rpm : numpy.ndarray
        Spindle speeds [rpm], ascending.
    depth_limit : numpy.ndarray
        b_lim [m] at each speed: the largest axial depth of cut that is stable. ``inf`` where no
        lobe was found below the analysed limit (see ``depth_ceiling``).
    chatter_frequency : numpy.ndarray
        Chatter frequency [rad/s] on the limit at each speed (zero-order); NaN where
        ``depth_limit`` is inf, and for the semi-discretisation (not computed).
    b_crit : float
        The smallest b_lim [m]. Zero-order: the absolute limit (3), the same at every lobe
        minimum. Semi-discretisation: the smallest b_lim over the speed range.
    critical_speed_rpm : float
        Zero-order: the highest lobe minimum inside the speed range (all lobe minima have depth
        b_crit); if none lies in the range, where b_lim is least on the grid.
        Semi-discretisation: where b_lim is least.
    critical_frequency : float
        Chatter frequency [rad/s] at b_crit (zero-order; NaN for the semi-discretisation).
    min_depth_limit : float
        The smallest b_lim [m] inside the speed range (>= b_crit; equal when a lobe minimum lies
        in the range).
    lobe_speed_rpm, lobe_depth : numpy.ndarray
        Zero-order: the individual lobes, one row per (lobe number, eigenvalue branch), as
        parametric curves over the frequency grid (inf where Re Phi >= 0), for k = 0, 1, ...
        as far as a memory budget of 4e6 points allows (all of them for ordinary grids).
        Empty for the semi-discretisation.
    lobe_count : int
        Number of lobes traced (zero-order) per eigenvalue branch.
    depth_ceiling : float
        Semi-discretisation: the largest depth [m] examined. Zero-order: inf.
    intervals : int
        Semi-discretisation: intervals per period. Zero-order: 0.
    """

    setup: MillingSetup
    method: str
    speed_rpm: np.ndarray
    depth_limit: np.ndarray
    chatter_frequency: np.ndarray
    b_crit: float
    critical_speed_rpm: float
    critical_frequency: float
    min_depth_limit: float
    lobe_speed_rpm: np.ndarray
    lobe_depth: np.ndarray
    lobe_count: int
    depth_ceiling: float = math.inf
    intervals: int = 0

    def margin(self, required_depth: float) -> float:
        """Return the smallest b_lim in the speed range over a required depth (> 1: stable).

        Parameters
        ----------
        required_depth : float
            Axial depth of cut the process needs [m], positive.

        Returns
        -------
        float
            ``min_depth_limit / required_depth`` [-].

        Raises
        ------
        ValueError
            When ``required_depth`` is not a positive finite number.
        """
        return self.min_depth_limit / _check_depth(required_depth)

    def to_dict(self) -> dict:
        """Return a JSON-ready dictionary in SI (speeds in rpm, frequencies also in Hz).

        Speeds where no limit was found carry ``null``.

        Returns
        -------
        dict
            JSON-ready values (str, numbers, lists, None).
        """
        limit = [float(b) if math.isfinite(b) else None for b in self.depth_limit]
        return {
            "method": self.method,
            "setup": self.setup.to_dict(),
            "b_crit_m": self.b_crit,
            "critical_speed_rpm": self.critical_speed_rpm,
            "critical_frequency_hz": (self.critical_frequency * HZ_PER_RAD_S
                                      if math.isfinite(self.critical_frequency) else None),
            "min_depth_limit_m": self.min_depth_limit,
            "lobe_count": self.lobe_count,
            "intervals": self.intervals,
            "depth_ceiling_m": (self.depth_ceiling if math.isfinite(self.depth_ceiling)
                                else None),
            "speeds_without_limit": int(np.sum(~np.isfinite(self.depth_limit))),
            "lobes": {"speed_rpm": self.speed_rpm.tolist(), "b_lim_m": limit},
        }

    def plot(self, **kwargs):
        """Draw the stability lobe diagram (:func:`servotune.plots.plot_stability_lobes`).

        Parameters
        ----------
        **kwargs
            Passed to :func:`servotune.plots.plot_stability_lobes`.

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        from .. import plots

        return plots.plot_stability_lobes(self, **kwargs)


def _check_depth(depth) -> float:
    depth = float(depth)
    if not math.isfinite(depth) or depth <= 0.0:
        raise ValueError(f"required depth must be a positive finite number [m], got {depth!r}")
    return depth


def _check_speeds(speeds_rpm) -> np.ndarray:
    s = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    if s.ndim != 1 or s.size < 2:
        raise ValueError("speeds_rpm must be a 1-D array of at least 2 spindle speeds [rpm]")
    if not np.all(np.isfinite(s)) or s[0] <= 0.0 or np.any(np.diff(s) <= 0.0):
        raise ValueError("speeds_rpm must be finite, positive and strictly increasing [rpm]")
    return s


def _lobe_minima_speeds(setup, wc, phi_c, lobe_count) -> np.ndarray:
    theta = math.pi + 2.0 * math.atan(phi_c.imag / phi_c.real)
    k = np.arange(lobe_count)
    return 60.0 * wc / (setup.teeth * (theta + 2.0 * math.pi * k))


def _envelope(speeds, lobe_n, depth, omega):
    """Lower envelope of piecewise-linear lobes on a speed grid.

    lobe_n: (L, nf) speeds of the lobe points; depth: (L, nf) with inf where invalid.
    Every segment between two valid neighbours is sampled at the grid speeds it spans (linear
    in 1/b, i.e. in Re Phi, along the speed).
    """
    n_a, n_b = lobe_n[:, :-1].ravel(), lobe_n[:, 1:].ravel()
    d_a, d_b = depth[:, :-1].ravel(), depth[:, 1:].ravel()
    w_a = np.broadcast_to(omega[:-1], lobe_n[:, :-1].shape).ravel()
    w_b = np.broadcast_to(omega[1:], lobe_n[:, 1:].shape).ravel()
    ok = np.isfinite(d_a) & np.isfinite(d_b)
    n_a, n_b, d_a, d_b, w_a, w_b = (v[ok] for v in (n_a, n_b, d_a, d_b, w_a, w_b))
    lo = np.searchsorted(speeds, np.minimum(n_a, n_b), side="left")
    hi = np.searchsorted(speeds, np.maximum(n_a, n_b), side="right")
    count = hi - lo
    keep = count > 0
    n_a, n_b, d_a, d_b, w_a, w_b, lo, count = (
        v[keep] for v in (n_a, n_b, d_a, d_b, w_a, w_b, lo, count))
    seg = np.repeat(np.arange(count.size), count)
    first = np.cumsum(count) - count
    j = lo[seg] + (np.arange(seg.size) - first[seg])
    span = n_b - n_a
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(span[seg] != 0.0, (speeds[j] - n_a[seg]) / span[seg], 0.0)
    # interpolate 1/b (proportional to Re Phi, smooth) rather than b, which grows like 1/x
    # where Re Phi -> 0 on the steep flanks of the lobes
    inv_a, inv_b = 1.0 / d_a, 1.0 / d_b
    b = 1.0 / (inv_a[seg] + t * (inv_b - inv_a)[seg])
    w = w_a[seg] + t * (w_b - w_a)[seg]
    env = np.full(speeds.size, np.inf)
    np.minimum.at(env, j, b)
    freq = np.full(speeds.size, np.nan)
    at_min = b == env[j]
    freq[j[at_min]] = w[at_min]
    return env, freq


def stability_lobes(system, setup: MillingSetup, speeds_rpm=None, *, omega=None,
                    direction: str = "x", lobes: int | None = None) -> StabilityLobes:
    """Zero-order stability lobes (Altintas and Budak 1995) over a range of spindle speeds.

    Parameters
    ----------
    system : control.StateSpace, control.TransferFunction, control.FrequencyResponseData or
        tuple (omega, H)
        The tool/work-piece compliance [m/N], 2 x 2 (x, y) or SISO
        (see :func:`compliance_matrix`).
    setup : MillingSetup
        The milling set-up (teeth, cutting coefficients, immersion).
    speeds_rpm : array_like, optional
        Ascending spindle speeds [rpm] at which to give b_lim. Default: 2000 speeds from 0.8
        times the 10th lobe minimum to 1.5 times the first.
    omega : array_like, optional
        Frequency grid [rad/s] for a python-control system (default: resonances resolved and
        extended so that the first lobe reaches the highest speed).
    direction : {"x", "y"}
        Flexible direction of a SISO compliance.
    lobes : int, optional
        Number of lobes k = 0 .. lobes-1 to trace. Default: enough to reach the lowest speed
        (every lobe part below 20 b_crit).

    Returns
    -------
    StabilityLobes
        b_lim at each speed, b_crit, the critical speed and frequency, and the lobes traced.

    Raises
    ------
    ValueError
        For bad input (see :func:`compliance_matrix`, :class:`MillingSetup`), an oriented FRF
        with no negative real part, or a speed range so low that more than
        ``MAX_LOBES`` lobes would be needed.

    See Also
    --------
    sdm_lobes : The same lobes by semi-discretisation (flip lobes of low immersion).
    chatter_margin : b_crit or the least b_lim in a speed window over a required depth.
    servotune.frequency.compliance : The work-piece compliance of the controlled axis.
    servotune.analysis.compliance_curve : The same for an axis description.

    Notes
    -----
    The lobes are parametric curves over the frequency grid (module docstring, Eq 2); their
    lower envelope on the speed grid is found by sampling every segment of every lobe at the
    grid speeds it spans (1/b linear in speed between lobe points), all at once.

    Examples
    --------
    Lobe minima lie at ``n = 60 w_c / (N (theta + 2 pi k))``; for a single mode
    ``w_c = w_n sqrt(1 + 2 zeta)`` and ``theta = pi + 2 arctan(sqrt(1 + 2 zeta))``, so for the
    Insperger-Stepan benchmark the k = 1 minimum is at 15963 rpm:

    >>> from servotune.chatter import Mode, modal_compliance
    >>> wn, zeta = 2 * math.pi * 922.0, 0.011
    >>> sys = modal_compliance([Mode(wn, zeta, 0.03993 * wn**2)])
    >>> r = stability_lobes(sys, MillingSetup(teeth=2, kt=6e8, kn=2e8),
    ...                     np.linspace(12000, 20000, 801))
    >>> root = math.sqrt(1 + 2 * zeta)
    >>> n1 = 60 * wn * root / (2 * (math.pi + 2 * math.atan(root) + 2 * math.pi))
    >>> round(n1), round(r.critical_speed_rpm / n1, 6), round(r.b_crit * 1e3, 4)
    (15963, 1.0, 0.2981)
    """
    setup = _check_setup(setup)
    if speeds_rpm is not None:
        speeds = _check_speeds(speeds_rpm)
        if (omega is None and isinstance(system, (control.StateSpace, control.TransferFunction))):
            # the first lobe reaches n = 60 w / (N theta) with theta < 2 pi
            w_needed = 1.1 * 2.0 * math.pi * setup.teeth * speeds[-1] / 60.0
            omega = frequency_grid(system, omega_max=w_needed)
    w, g = compliance_matrix(system, omega, direction)
    phi = oriented_frf(g, setup)
    b_crit, wc, phi_c = _absolute_limit(system, direction, setup, w, phi)
    re = phi.real
    if speeds_rpm is None:
        minima = _lobe_minima_speeds(setup, wc, phi_c, 10)
        speeds = np.linspace(0.8 * minima[-1], 1.5 * minima[0], 2000)
        if (omega is None and isinstance(system, (control.StateSpace, control.TransferFunction))):
            w_needed = 1.1 * 2.0 * math.pi * setup.teeth * speeds[-1] / 60.0
            if w_needed > w[-1]:
                w, g = compliance_matrix(system, frequency_grid(system, omega_max=w_needed),
                                         direction)
                phi = oriented_frf(g, setup)

    with np.errstate(divide="ignore"):
        depth = np.where(re < 0.0, -1.0 / (2.0 * setup.kt * re), np.inf)  # (nf, 2)
        theta = math.pi + 2.0 * np.arctan(np.divide(phi.imag, re, out=np.zeros_like(re),
                                                    where=re != 0.0))
    if lobes is None:
        relevant = np.any(depth <= 20.0 * b_crit, axis=1)
        w_top = float(w[relevant].max())
        lobe_count = math.ceil(60.0 * w_top / (2.0 * math.pi * setup.teeth * speeds[0])) + 1
        if lobe_count > MAX_LOBES:
            raise ValueError(
                f"the lowest speed {speeds[0]:g} rpm needs {lobe_count} lobes (more than "
                f"{MAX_LOBES}); raise the lowest speed or give lobes= explicitly")
    else:
        if isinstance(lobes, bool) or int(lobes) != lobes or lobes < 1:
            raise ValueError(f"lobes must be a whole number >= 1, got {lobes!r}")
        lobe_count = int(lobes)
    # lobes in chunks of at most _POINTS_PER_CHUNK points (memory); the curves of the first
    # chunk are kept for plotting
    per_chunk = max(1, _POINTS_PER_CHUNK // (2 * w.size))
    env = np.full(speeds.size, np.inf)
    freq = np.full(speeds.size, np.nan)
    kept_n = kept_d = None
    for first in range(0, lobe_count, per_chunk):
        k = np.arange(first, min(first + per_chunk, lobe_count))[:, None, None]
        # (k, branch, nf): speed of every lobe point
        lobe_n = 60.0 * w[None, None, :] / (setup.teeth * (theta.T[None] + 2.0 * math.pi * k))
        lobe_d = np.broadcast_to(depth.T[None], lobe_n.shape)
        lobe_n = lobe_n.reshape(-1, w.size)
        lobe_d = lobe_d.reshape(-1, w.size)
        env_k, freq_k = _envelope(speeds, lobe_n, lobe_d, w)
        lower = env_k < env
        env[lower], freq[lower] = env_k[lower], freq_k[lower]
        if kept_n is None:
            kept_n, kept_d = lobe_n, np.array(lobe_d)

    minima = _lobe_minima_speeds(setup, wc, phi_c, lobe_count)
    inside = minima[(minima >= speeds[0]) & (minima <= speeds[-1])]
    if inside.size:
        critical_speed, min_limit, critical_freq = float(inside.max()), b_crit, wc
    else:
        i = int(np.argmin(env))
        critical_speed, min_limit, critical_freq = float(speeds[i]), float(env[i]), float(freq[i])
    return StabilityLobes(
        setup=setup, method="zoa", speed_rpm=speeds, depth_limit=env, chatter_frequency=freq,
        b_crit=float(b_crit), critical_speed_rpm=critical_speed,
        critical_frequency=float(critical_freq), min_depth_limit=float(min_limit),
        lobe_speed_rpm=kept_n, lobe_depth=kept_d, lobe_count=lobe_count)


def default_speed_range(system, setup: MillingSetup, *, omega=None,
                        direction: str = "x") -> tuple[float, float]:
    """A spindle-speed range [rpm] that shows the first ten lobes of the zero-order method.

    From 0.8 times the speed of the 10th lobe minimum (k = 9) to 1.5 times the first (k = 0).

    Parameters
    ----------
    system : control.LTI or tuple (omega, H)
        The tool/work-piece compliance [m/N], as for :func:`stability_lobes`.
    setup : MillingSetup
        The milling set-up.
    omega : array_like, optional
        Frequency grid [rad/s] for a python-control system.
    direction : {"x", "y"}, optional
        Flexible direction of a SISO compliance (default "x").

    Returns
    -------
    low, high : float
        The speed range [rpm].

    Raises
    ------
    ValueError
        As for :func:`absolute_stability_limit`.

    Examples
    --------
    >>> from servotune.chatter import Mode, modal_compliance
    >>> wn = 2 * math.pi * 922.0
    >>> lo, hi = default_speed_range(modal_compliance([Mode(wn, 0.011, 0.03993 * wn**2)]),
    ...                              MillingSetup(teeth=2, kt=6e8, kn=2e8))
    >>> round(lo), round(hi)
    (2294, 55796)
    """
    setup = _check_setup(setup)
    w, g = compliance_matrix(system, omega, direction)
    _, wc, phi_c = _absolute_limit(system, direction, setup, w, oriented_frf(g, setup))
    minima = _lobe_minima_speeds(setup, wc, phi_c, 10)
    return 0.8 * float(minima[-1]), 1.5 * float(minima[0])


def spindle_speeds(system, setup: MillingSetup, speed_range_rpm=None, count: int = 2000, *,
                   omega=None, direction: str = "x") -> np.ndarray:
    """Return equally spaced spindle speeds [rpm] over a range, by default the lobes' range.

    Parameters
    ----------
    system : control.LTI or tuple (omega, H)
        The tool/work-piece compliance [m/N], used only when ``speed_range_rpm`` is None.
    setup : MillingSetup
        The milling set-up, used only when ``speed_range_rpm`` is None.
    speed_range_rpm : (float, float), optional
        Lowest and highest speed [rpm]; default :func:`default_speed_range`.
    count : int, optional
        Number of speeds, at least 2 (default 2000).
    omega : array_like, optional
        Frequency grid [rad/s], passed to :func:`default_speed_range`.
    direction : {"x", "y"}, optional
        Flexible direction of a SISO compliance (default "x").

    Returns
    -------
    numpy.ndarray
        ``count`` ascending speeds [rpm].

    Raises
    ------
    ValueError
        If the range is not ``0 < low < high`` or count < 2.
    """
    if isinstance(count, bool) or int(count) != count or count < 2:
        raise ValueError(f"the number of speeds must be a whole number >= 2, got {count!r}")
    if speed_range_rpm is None:
        lo, hi = default_speed_range(system, setup, omega=omega, direction=direction)
    else:
        lo, hi = (float(v) for v in speed_range_rpm)
        if not 0.0 < lo < hi or not math.isfinite(hi):
            raise ValueError(f"the speed range must satisfy 0 < low < high [rpm], got "
                             f"{speed_range_rpm!r}")
    return np.linspace(lo, hi, int(count))


def chatter_margin(system, setup: MillingSetup, required_depth: float, speed_range_rpm=None,
                   *, omega=None, direction: str = "x") -> float:
    """Chatter margin: the stability limit over a required axial depth of cut (> 1: stable).

    Parameters
    ----------
    system, setup
        As for :func:`stability_lobes`.
    required_depth : float
        The axial depth of cut the process needs [m].
    speed_range_rpm : (float, float), optional
        A spindle-speed window. Without it the margin is ``b_crit / required_depth`` (stable at
        every speed); with it, ``min b_lim / required_depth`` over the window (stable
        somewhere in it at the least favourable speed).
    omega, direction
        As for :func:`stability_lobes`.

    Returns
    -------
    float
        The margin [-]; above 1 the required depth is stable.

    Raises
    ------
    ValueError
        When ``required_depth`` is not positive and finite, the window not ``0 < low < high``,
        or for the reasons of :func:`stability_lobes`.

    Examples
    --------
    >>> from servotune.chatter import Mode, modal_compliance
    >>> wn = 2 * math.pi * 922.0
    >>> sys = modal_compliance([Mode(wn, 0.011, 0.03993 * wn**2)])
    >>> setup = MillingSetup(teeth=2, kt=6e8, kn=2e8)
    >>> round(chatter_margin(sys, setup, 0.2e-3), 3)  # b_crit = 0.298 mm
    1.49
    >>> bool(chatter_margin(sys, setup, 0.2e-3, (19000, 23000)) > 4)  # in a stable pocket
    True
    """
    required_depth = _check_depth(required_depth)
    if speed_range_rpm is None:
        b, _ = absolute_stability_limit(system, setup, omega, direction)
        return float(b) / required_depth
    lo, hi = (float(v) for v in speed_range_rpm)
    if not 0.0 < lo < hi:
        raise ValueError(f"speed_range_rpm must satisfy 0 < low < high, got {speed_range_rpm!r}")
    result = stability_lobes(system, setup, np.linspace(lo, hi, 2001), omega=omega,
                             direction=direction)
    return result.margin(required_depth)
