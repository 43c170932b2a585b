"""The paper's simplified two-mass layouts: fixed points, optimal damping, g(alpha).

Bianchi et al. (2014), sec 4.1, map guide-way friction onto a viscous damper C between two
masses and a spring. Two layouts are analysed:

Layout B (Eq 1-7), the one the paper maps onto the axis::

    ground --C-- M1 --K-- M2 = alpha M1        force f2 on M2, output x2

M1 is the slide near the guide ways, M2 the structure near the work piece and C the viscous
guide-way friction. The dynamic compliance x2/f2 has two *fixed points* whose magnitude does
not depend on C; the optimal C puts a horizontal tangent at the second one.

Layout A::

    ground --K-- M2 --C-- M1                   force f2 on M2, output x2

The paper's figure of layout A is unreadable. This module *interprets* it as a Lanchester
damper: the text says that increasing C "progressively connects M2 to M1" and that the
resonance frequency then decreases, which this reading reproduces (sqrt(K/M2) for C = 0,
sqrt(K/(M1+M2)) for C -> infinity). Sec 5.2 of the paper says the opposite (mode A rises with
C), so results for layout A are an interpretation, not the paper's.

In both layouts alpha = M2/M1 (the paper's M_WP/M_GW). Everything is SI: masses in kg,
stiffness in N/m, damping in N s/m, angular frequencies in rad/s, compliance in m/N.

References
----------
G. Bianchi, S. Cagna, N. Cau, F. Paolucci, "Analysis of vibration damping in machine tools",
Procedia CIRP 21 (2014) 367-372, doi:10.1016/j.procir.2014.03.158.
J. P. Den Hartog, Mechanical Vibrations, 4th ed., McGraw-Hill (1956), sec 3.12 (Lanchester
damper).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from .validation import positive

__all__ = [
    "TwoMassSystem",
    "TwoMassAnalysis",
    "two_mass_compliance",
    "fixed_points",
    "optimal_damping",
    "optimal_peak",
    "limit_resonances",
    "peak_compliance",
    "minimax_damping",
    "analyse_two_mass",
    "g_alpha",
]

LAYOUTS = ("A", "B")


@dataclass(frozen=True)
class TwoMassSystem:
    """The two masses, the spring and the layout of the paper's sec 4.1.

    Parameters
    ----------
    m1 : float
        Mass M1 near the guide ways [kg].
    k : float
        Spring stiffness K [N/m].
    alpha : float
        Mass ratio M2/M1 [-] (M2 is the mass near the work piece).
    layout : {"B", "A"}
        ``"B"``: ground --C-- M1 --K-- M2 (the paper's Eq 1-7). ``"A"``: ground --K-- M2 --C-- M1
        (an interpretation of the paper's unreadable figure, see the module docstring).

    Raises
    ------
    ValueError
        If a parameter is not a positive finite number or the layout is unknown.

    Examples
    --------
    The paper's Fig 5 system; with the slide held fixed (C -> infinity) M2 rings on K alone:

    >>> s = TwoMassSystem(m1=5000.0, k=16e6, alpha=0.3)
    >>> s.m2
    1500.0
    >>> round(math.sqrt(s.k / s.m2) / (2 * math.pi), 2)
    16.44
    """

    m1: float
    k: float
    alpha: float
    layout: str = "B"

    def __post_init__(self) -> None:
        for name, unit in (("m1", "kg"), ("k", "N/m"), ("alpha", "(M2/M1)")):
            object.__setattr__(self, name, positive("TwoMassSystem", name, getattr(self, name),
                                                    unit))
        layout = str(self.layout).upper()
        if layout not in LAYOUTS:
            raise ValueError(f"TwoMassSystem.layout must be 'A' or 'B', got {self.layout!r}")
        object.__setattr__(self, "layout", layout)

    @property
    def m2(self) -> float:
        """Mass M2 = alpha M1 near the work piece [kg]."""
        return self.alpha * self.m1

    @property
    def omega0(self) -> float:
        """sqrt(K/M1) [rad/s]: the natural frequency with M2 fixed to ground (paper, Eq 3)."""
        return math.sqrt(self.k / self.m1)


def _as_damping(c) -> np.ndarray:
    c = np.asarray(c, dtype=float)
    if not np.all(np.isfinite(c)) or np.any(c < 0.0):
        raise ValueError(f"c (viscous damping) must be finite and >= 0 N s/m, got {c!r}")
    return c


def _as_omega(omega) -> np.ndarray:
    omega = np.asarray(omega, dtype=float)
    if not np.all(np.isfinite(omega)) or np.any(omega < 0.0):
        raise ValueError("omega must be finite and >= 0 rad/s")
    return omega


def two_mass_compliance(system: TwoMassSystem, omega, c) -> np.ndarray:
    """Dynamic compliance x2/f2 [m/N] at the work-piece mass M2.

    Vectorised: ``omega`` and ``c`` broadcast against each other (pass ``c[:, None]`` and
    ``omega[None, :]`` for a table over damping and frequency).

    Parameters
    ----------
    system : TwoMassSystem
        The two-mass system (M1, K, alpha, layout).
    omega : array_like
        Angular frequencies [rad/s], >= 0.
    c : array_like
        Viscous damping C [N s/m], >= 0.

    Returns
    -------
    numpy.ndarray of complex
        x2/f2 [m/N], shape ``np.broadcast(omega, c).shape``.

    Notes
    -----
    Layout B (paper, Eq 1), with M2 = alpha M1::

        x2/f2 = (K - M1 w^2 + j w C)
                / (alpha M1^2 w^4 - (1 + alpha) K M1 w^2 + j w C (K - alpha M1 w^2))

    Layout A (ground --K-- M2 --C-- M1)::

        x2/f2 = (-M1 w^2 + j w C) / (-M1 w^2 (K - M2 w^2) + j w C (K - (M1 + M2) w^2))

    Examples
    --------
    At zero frequency layout B is a free-floating pair held only by the damper, so the static
    compliance of layout A is the spring's:

    >>> s = TwoMassSystem(m1=5000.0, k=16e6, alpha=0.3, layout="A")
    >>> complex(two_mass_compliance(s, 0.0, 1e5)) * s.k
    (1+0j)
    """
    w = _as_omega(omega)
    c = _as_damping(c)
    m1, k, m2 = system.m1, system.k, system.m2
    w2 = w * w
    if system.layout == "B":
        num = k - m1 * w2 + 1j * w * c
        den = m1 * m2 * w2 * w2 - (m1 + m2) * k * w2 + 1j * w * c * (k - m2 * w2)
    else:
        num = -m1 * w2 + 1j * w * c
        den = -m1 * w2 * (k - m2 * w2) + 1j * w * c * (k - (m1 + m2) * w2)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = num / den
    if system.layout == "A":
        # the 0/0 at w = 0 is the static compliance of the spring, 1/K, for any C
        h = np.where(w2 == 0.0, 1.0 / k + 0j, h)
    return h


def fixed_points(system: TwoMassSystem) -> np.ndarray:
    """Angular frequencies [rad/s] where |x2/f2| does not depend on C (paper, Eq 2-3).

    Parameters
    ----------
    system : TwoMassSystem
        The two-mass system (M1, K, alpha, layout).

    Returns
    -------
    numpy.ndarray
        Layout B: ``[w_f1, w_f2]`` with
        ``w_f1,2 = w0 sqrt((1 + alpha -/+ sqrt(1 + alpha^2)) / (2 alpha))``, w0 = sqrt(K/M1).
        Layout A: ``[w_f]`` with ``w_f^2 = 2K/(M1 + 2 M2)``.

    Notes
    -----
    With x2/f2 = (a + j w C)/(b + j w C d), |x2/f2| is independent of C where a/b = -1/d
    (a/b = +1/d is impossible for K > 0). For layout B this is
    ``2 alpha u^2 - 2 (1 + alpha) u + 1 = 0`` in u = M1 w^2/K.

    Examples
    --------
    >>> s = TwoMassSystem(m1=5000.0, k=16e6, alpha=0.3)
    >>> [round(float(w) / (2 * math.pi), 3) for w in fixed_points(s)]
    [5.88, 17.795]
    """
    a = system.alpha
    if system.layout == "B":
        root = math.sqrt(1.0 + a * a)
        u = np.array([(1.0 + a - root), (1.0 + a + root)]) / (2.0 * a)
        return system.omega0 * np.sqrt(u)
    return np.array([math.sqrt(2.0 * system.k / (system.m1 + 2.0 * system.m2))])


def optimal_damping(system: TwoMassSystem) -> float:
    """Closed-form optimal viscous damping Copt [N s/m] (paper, Eq 4).

    Copt puts a horizontal tangent on |x2/f2| at the (second) fixed point.

    Parameters
    ----------
    system : TwoMassSystem
        The two-mass system (M1, K, alpha, layout).

    Returns
    -------
    float
        Copt [N s/m].

    See Also
    --------
    minimax_damping : The same optimum found numerically, without the closed form.
    analyse_two_mass : Fixed points, Copt, the optimal peak and the limit resonances.
    servotune.design.tune_axis : Tunes the damping C of a full axis, checked against Copt.

    Notes
    -----
    The closed forms minimise the true peak (over w >= w_f1) only for alpha <= 1: for
    alpha > 1 the first fixed point, 1/(K (1 - alpha u1)), is the higher one and bounds the peak
    from below for every C (the paper's Fig 4 plots alpha in (0, 1] only).

    Layout B: ``Copt = sqrt(K M1) f(alpha)`` with
    ``f(alpha) = sqrt((3 sqrt(1 + alpha^2) + alpha - 1) / (2 alpha (alpha + sqrt(1 + alpha^2))))``.
    The paper calls f "transcendental" and does not print it; it is algebraic (derived by
    setting d|H|^2/dw = 0 at w_f2 and solving for C^2).

    Layout A (Lanchester damper, Den Hartog sec 3.12):
    ``Copt = sqrt(K M2) sqrt(2 / ((1 + alpha) (1 + 2 alpha)))``.

    Examples
    --------
    The paper's Fig 5 draws C = 4.912e5 N s/m as the optimum:

    >>> round(optimal_damping(TwoMassSystem(m1=5000.0, k=16e6, alpha=0.3)), -2)
    491200.0
    """
    a = system.alpha
    if system.layout == "B":
        root = math.sqrt(1.0 + a * a)
        f = math.sqrt((3.0 * root + a - 1.0) / (2.0 * a * (a + root)))
        return math.sqrt(system.k * system.m1) * f
    return math.sqrt(system.k * system.m2) * math.sqrt(2.0 / ((1.0 + a) * (1.0 + 2.0 * a)))


def g_alpha(alpha) -> np.ndarray:
    """Dynamic amplification g(alpha) at the work piece with C = Copt, layout B (paper, Eq 7).

    ``g(alpha) = (1 - alpha + sqrt(1 + alpha^2)) / alpha``, so that the optimal peak
    compliance is g(alpha)/K (the paper's Fig 4).

    Parameters
    ----------
    alpha : array_like
        Mass ratio M2/M1 [-], > 0.

    Returns
    -------
    numpy.ndarray
        g(alpha) [-], shape of ``alpha``.

    Examples
    --------
    Equal masses leave an amplification of sqrt(2):

    >>> round(float(g_alpha(1.0)), 6) == round(math.sqrt(2.0), 6)
    True
    """
    alpha = np.asarray(alpha, dtype=float)
    if np.any(~np.isfinite(alpha)) or np.any(alpha <= 0.0):
        raise ValueError("alpha must be positive and finite")
    return (1.0 - alpha + np.sqrt(1.0 + alpha * alpha)) / alpha


def optimal_peak(system: TwoMassSystem) -> float:
    """Return the peak |x2/f2| [m/N] reached with C = Copt: the compliance at the fixed point.

    Layout B: g(alpha)/K (paper, Eq 7). Layout A: (1 + 2 alpha)/K.

    Parameters
    ----------
    system : TwoMassSystem
        The two-mass system (M1, K, alpha, layout).

    Returns
    -------
    float
        The peak compliance [m/N].

    Examples
    --------
    >>> s = TwoMassSystem(m1=5000.0, k=16e6, alpha=0.3)
    >>> round(optimal_peak(s) * s.k, 4)
    5.8134
    """
    if system.layout == "B":
        return float(g_alpha(system.alpha)) / system.k
    return (1.0 + 2.0 * system.alpha) / system.k


def limit_resonances(system: TwoMassSystem) -> tuple[float, float]:
    """Undamped resonance [rad/s] that moves the work piece for C -> 0 and for C -> infinity.

    Parameters
    ----------
    system : TwoMassSystem
        The two-mass system (M1, K, alpha, layout).

    Returns
    -------
    (omega_c0, omega_cinf) : tuple of float
        Layout B: C -> 0 leaves a free-free pair, ``sqrt((1 + alpha) K / M2)``; C -> infinity
        clamps M1, leaving ``sqrt(K / M2)``. Layout A: ``sqrt(K / M2)`` and
        ``sqrt(K / (M1 + M2))``. In both layouts the resonance falls as C grows.

    Examples
    --------
    >>> s = TwoMassSystem(m1=5000.0, k=16e6, alpha=0.3)
    >>> [round(w / (2 * math.pi), 2) for w in limit_resonances(s)]
    [18.74, 16.44]
    """
    k, m1, m2 = system.k, system.m1, system.m2
    if system.layout == "B":
        return math.sqrt((m1 + m2) * k / (m1 * m2)), math.sqrt(k / m2)
    return math.sqrt(k / m2), math.sqrt(k / (m1 + m2))


def _band_start(system: TwoMassSystem) -> float:
    # Layout B: |H| ~ 1/(w C) as w -> 0, so the peak is sought above the first fixed point.
    return float(fixed_points(system)[0]) if system.layout == "B" else 0.0


def peak_compliance(system: TwoMassSystem, c: float, omega_min: float | None = None,
                    omega_max: float | None = None) -> tuple[float, float]:
    """The true peak of |x2/f2| over a frequency band, found numerically.

    Parameters
    ----------
    system : TwoMassSystem
        The two-mass system (M1, K, alpha, layout).
    c : float
        Viscous damping [N s/m].
    omega_min, omega_max : float, optional
        Band [rad/s]. Default: from the first fixed point (layout B) or 0 (layout A) to four
        times the highest limit resonance.

    Returns
    -------
    (peak, omega_peak) : tuple of float
        Peak compliance [m/N] and where it occurs [rad/s].

    Raises
    ------
    ValueError
        When the band is not ``0 <= omega_min < omega_max`` or ``c`` is negative.

    Notes
    -----
    A dense logarithmic grid brackets the maximum, which bounded Brent search then refines.
    This is the independent (numeric) check of the closed forms.
    """
    c = float(_as_damping(c))
    lo = _band_start(system) if omega_min is None else float(omega_min)
    hi = 4.0 * max(limit_resonances(system)) if omega_max is None else float(omega_max)
    if not 0.0 <= lo < hi:
        raise ValueError(f"empty frequency band [{lo}, {hi}] rad/s")
    grid = np.concatenate([[lo], np.geomspace(max(lo, 1e-3 * hi), hi, 4001)])
    mag = np.abs(two_mass_compliance(system, grid, c))
    i = int(np.argmax(mag))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    if a == b:
        return float(mag[i]), float(grid[i])
    res = optimize.minimize_scalar(
        lambda w: -abs(complex(two_mass_compliance(system, w, c))),
        bounds=(a, b), method="bounded", options={"xatol": 1e-12 * b})
    if -res.fun >= mag[i]:
        return float(-res.fun), float(res.x)
    return float(mag[i]), float(grid[i])


def minimax_damping(system: TwoMassSystem, c_bounds: tuple[float, float] | None = None,
                    ) -> tuple[float, float]:
    """The C that minimises the true peak of |x2/f2| (over w >= w_f1 for layout B), numerically.

    This does not use the closed form: it minimises :func:`peak_compliance` over log C.

    Parameters
    ----------
    system : TwoMassSystem
        The two-mass system (M1, K, alpha, layout).
    c_bounds : (float, float), optional
        Search interval [N s/m]; default two decades either side of sqrt(K M1).

    Returns
    -------
    (c, peak) : tuple of float
        The minimax damping [N s/m] and its peak compliance [m/N].

    Raises
    ------
    ValueError
        If ``c_bounds`` is not ``0 < low < high``.
    RuntimeError
        If the minimum lies on a bound of the search interval.
    """
    scale = math.sqrt(system.k * system.m1)
    lo, hi = c_bounds if c_bounds is not None else (1e-2 * scale, 1e2 * scale)
    if not 0.0 < lo < hi:
        raise ValueError(f"c_bounds must satisfy 0 < low < high, got {c_bounds!r}")
    logs = np.linspace(math.log(lo), math.log(hi), 81)
    peaks = np.array([peak_compliance(system, math.exp(s))[0] for s in logs])
    i = int(np.argmin(peaks))
    if i in (0, logs.size - 1):
        raise RuntimeError(
            f"the minimax damping lies on the search bound {math.exp(logs[i]):.4g} N s/m; "
            "widen c_bounds")
    res = optimize.minimize_scalar(
        lambda s: peak_compliance(system, math.exp(s))[0] * system.k,
        bracket=(logs[i - 1], logs[i], logs[i + 1]), method="brent",
        options={"xtol": 1e-10})
    c = math.exp(res.x)
    return c, peak_compliance(system, c)[0]


@dataclass(frozen=True)
class TwoMassAnalysis:
    """Everything sec 4.1 of the paper says about one two-mass system (SI units).

    Attributes
    ----------
    system : TwoMassSystem
    fixed_points : tuple of float
        Fixed-point angular frequencies [rad/s].
    c_opt : float
        Closed-form optimal damping [N s/m].
    peak_compliance : float
        Peak |x2/f2| at C = Copt [m/N] (closed form).
    peak_frequency : float
        Where that peak occurs [rad/s]: the (second) fixed point.
    resonance_c0, resonance_cinf : float
        Resonance [rad/s] for C -> 0 and C -> infinity.
    """

    system: TwoMassSystem
    fixed_points: tuple[float, ...]
    c_opt: float
    peak_compliance: float
    peak_frequency: float
    resonance_c0: float
    resonance_cinf: float

    def to_dict(self) -> dict:
        """JSON-ready dictionary, SI values; frequencies also in Hz under ``*_hz`` keys.

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        hz = 1.0 / (2.0 * math.pi)
        return {
            "layout": self.system.layout,
            "m1": self.system.m1,
            "m2": self.system.m2,
            "k": self.system.k,
            "alpha": self.system.alpha,
            "fixed_points": list(self.fixed_points),
            "fixed_points_hz": [w * hz for w in self.fixed_points],
            "c_opt": self.c_opt,
            "peak_compliance": self.peak_compliance,
            "peak_frequency": self.peak_frequency,
            "peak_frequency_hz": self.peak_frequency * hz,
            "resonance_c0": self.resonance_c0,
            "resonance_c0_hz": self.resonance_c0 * hz,
            "resonance_cinf": self.resonance_cinf,
            "resonance_cinf_hz": self.resonance_cinf * hz,
        }

    def plot(self, kind: str = "compliance", **kwargs):
        """Draw the paper's Fig 5 (``"compliance"``) or Fig 4 (``"g_alpha"``) for this system.

        Parameters
        ----------
        kind : {"compliance", "g_alpha"}, optional
            The figure (default "compliance").
        **kwargs
            Passed to :func:`servotune.plots.plot_two_mass_compliance` or
            :func:`servotune.plots.plot_g_alpha`.

        Returns
        -------
        matplotlib.figure.Figure
            The figure.

        Raises
        ------
        ValueError
            For another ``kind``.
        """
        from . import plots

        if kind == "compliance":
            return plots.plot_two_mass_compliance(self, **kwargs)
        if kind == "g_alpha":
            return plots.plot_g_alpha(mark=self.system.alpha, **kwargs)
        raise ValueError(f"kind must be 'compliance' or 'g_alpha', got {kind!r}")


def analyse_two_mass(system: TwoMassSystem) -> TwoMassAnalysis:
    """Return the fixed points, Copt, optimal peak and limit resonances of a two-mass system.

    Parameters
    ----------
    system : TwoMassSystem
        The two-mass system (M1, K, alpha, layout).

    Returns
    -------
    TwoMassAnalysis
        The closed-form results of sec 4.1.

    Examples
    --------
    >>> a = analyse_two_mass(TwoMassSystem(m1=5000.0, k=16e6, alpha=0.3))
    >>> round(a.c_opt / 1e5, 3), round(a.peak_frequency / (2 * math.pi), 2)
    (4.912, 17.8)
    """
    fp = fixed_points(system)
    if system.layout == "B" and system.alpha > 1.0:
        warnings.warn(
            f"alpha = {system.alpha:g} > 1: the first fixed point is higher than the second, so "
            "Copt and g(alpha)/K (paper, Eq 4-7) no longer give the smallest peak; use "
            "minimax_damping() for the true optimum", UserWarning, stacklevel=2)
    return TwoMassAnalysis(
        system=system,
        fixed_points=tuple(float(w) for w in fp),
        c_opt=optimal_damping(system),
        peak_compliance=optimal_peak(system),
        peak_frequency=float(fp[-1]),
        resonance_c0=limit_resonances(system)[0],
        resonance_cinf=limit_resonances(system)[1],
    )
