"""Numerical continuation of a harmonic balance solution in frequency (pseudo-arc-length).

The branch ``R(y, w) = 0`` is followed by predictor-corrector steps along its arc length, so
that turning points (where w goes back) are passed (Keller 1977; Krack and Gross 2019,
sec 4.2). In scaled variables ``u = (y / y_s, w / w_s)``:

* tangent ``t``: ``[J_y y_s, J_w w_s; t_prev^T] t = [0; 1]``, normalised, oriented as t_prev;
* predictor ``u_p = u + ds t``;
* corrector: Newton on ``R(u) = 0`` with ``t^T (u - u_p) = 0`` (the plane normal to t);
* step control: ds grows by 1.5 after a corrector of at most ``fast`` iterations, halves after a
  failed one or when the tangent turns by more than ``max_angle`` (this resolves peaks), up to
  ``arc_max``, and the step is shortened so that the frequency moves by at most ``step_max``.

y_s is the largest norm of the response met so far, w_s the width of the band.

References
----------
H. B. Keller, "Numerical solution of bifurcation and nonlinear eigenvalue problems", in
Applications of Bifurcation Theory, Academic Press (1977) 359-384.
M. Krack, J. Gross, "Harmonic Balance for Nonlinear Vibration Problems", Springer (2019),
ch 4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .balance import ConvergenceError, PadBalance

__all__ = ["ContinuationSettings", "Branch", "continue_in_frequency"]


@dataclass(frozen=True)
class ContinuationSettings:
    """Step control of the continuation (angular frequencies in rad/s).

    Parameters
    ----------
    step_max : float
        Largest frequency step [rad/s] (default 2 pi x 5 Hz); the first step moves the
        frequency by at most a quarter of it.
    step_min : float
        Smallest arc-length step, as a frequency [rad/s] (default 2 pi x 1e-4 Hz): a step
        halved below it stops the continuation with an error.
    arc_max : float
        Largest step along the arc in the scaled variables (the response relative to the
        largest met so far, the frequency relative to the band), dimensionless (default 0.5).
    max_angle : float
        Largest turn of the tangent per step [rad] (default 0.5, about 29 degrees; the peak is
        refined afterwards by :func:`servotune.harmonic.compliance.refine_peak`); not
        enforced on a step already at ``step_min``.
    fast : int
        A corrector of at most this many iterations lets the step grow by 1.5 (default 3).
    max_iterations : int
        Corrector iterations before the step is halved (default 8).

    Raises
    ------
    ValueError
        If not ``0 < step_min < step_max``, or ``max_angle`` is not in (0, pi/2).
    """

    step_max: float = 2.0 * math.pi * 5.0
    step_min: float = 2.0 * math.pi * 1e-4
    arc_max: float = 0.5
    max_angle: float = 0.5
    fast: int = 3
    max_iterations: int = 8

    def __post_init__(self) -> None:
        if not (0.0 < self.step_min < self.step_max):
            raise ValueError("continuation needs 0 < step_min < step_max [rad/s]")
        if not (0.0 < self.max_angle < math.pi / 2):
            raise ValueError("max_angle must be in (0, pi/2) rad")
        if not (0.0 < self.arc_max and math.isfinite(self.arc_max)):
            raise ValueError(f"ContinuationSettings.arc_max must be finite and > 0, got "
                             f"{self.arc_max!r}")
        for name in ("fast", "max_iterations"):
            value = getattr(self, name)
            if isinstance(value, bool) or int(value) != value or value < 1:
                raise ValueError(f"ContinuationSettings.{name} must be a whole number >= 1, "
                                 f"got {value!r}")
            object.__setattr__(self, name, int(value))


@dataclass(frozen=True, eq=False)
class Branch:
    """A continued branch of periodic solutions.

    Attributes
    ----------
    omega : numpy.ndarray, shape (K,)
        Angular frequencies of the points [rad/s] (not monotone past a turning point).
    y : numpy.ndarray, shape (K, m)
        The harmonic balance unknowns of :class:`PadBalance` at the points.
    iterations : int
        Newton iterations in all (the correctors, and the fixed-frequency solves at the
        band's start and end).
    rejected : int
        Steps taken again with a smaller step (the corrector failed, left positive
        frequencies, or the tangent turned too far).
    """

    omega: np.ndarray
    y: np.ndarray
    iterations: int
    rejected: int


def _tangent(jy, jw, ys, ws, previous):
    m = jy.shape[0]
    a = np.zeros((m + 1, m + 1))
    a[:m, :m] = jy * ys
    a[:m, m] = jw * ws
    a[m] = previous
    rhs = np.zeros(m + 1)
    rhs[m] = 1.0
    t = np.linalg.solve(a, rhs)
    t /= np.linalg.norm(t)
    return t if t @ previous >= 0 else -t


def continue_in_frequency(balance: PadBalance, omega_start: float, omega_end: float,
                          settings: ContinuationSettings | None = None, y0=None) -> Branch:
    """Follow the periodic response from ``omega_start`` to ``omega_end``.

    Parameters
    ----------
    balance : PadBalance
        The harmonic balance equations.
    omega_start, omega_end : float
        The band [rad/s], ``0 < omega_start < omega_end``.
    settings : ContinuationSettings, optional
        Step control (default ``ContinuationSettings()``).
    y0 : array_like, shape (n 2H,), optional
        Start guess at ``omega_start`` [m] (default: none, see :meth:`PadBalance.solve`).

    Returns
    -------
    Branch
        The points from ``omega_start`` on; its last point is at ``omega_end`` (a
        fixed-frequency solve started from the interpolation of the two points around it).

    Raises
    ------
    ConvergenceError
        If the solve at ``omega_start`` or ``omega_end`` does not converge, the step falls
        below ``step_min`` (the branch cannot be followed), or the branch turns back below
        ``omega_start - step_max``.
    ValueError
        If not ``0 < omega_start < omega_end``.
    """
    cs = settings or ContinuationSettings()
    if not (0.0 < omega_start < omega_end):
        raise ValueError("the continuation needs 0 < omega_start < omega_end [rad/s]")
    ws = omega_end - omega_start
    y, iterations = balance.solve(omega_start, y0)
    omega = omega_start
    ys = max(float(np.linalg.norm(y)), 1e-300)
    points_w, points_y = [omega], [y]
    ds_omega = cs.step_max / ws
    ds_max = cs.arc_max
    ds_min = cs.step_min / ws
    ds = 0.25 * ds_omega
    previous = np.zeros(y.size + 1)
    previous[-1] = 1.0
    rejected = 0
    _, jy, jw = balance.jacobian(y, omega, with_omega=True)
    t = _tangent(jy, jw, ys, ws, previous)
    while omega < omega_end:
        u = np.concatenate([y / ys, [omega / ws]])
        step = min(ds, ds_omega / max(abs(t[-1]), 1e-12))   # frequency step <= step_max
        pred = u + step * t
        v = pred.copy()
        ok = False
        r, jy, jw = balance.jacobian(v[:-1] * ys, v[-1] * ws, with_omega=True)
        used = 0
        for _ in range(cs.max_iterations):
            used += 1
            a = np.zeros((y.size + 1, y.size + 1))
            a[:-1, :-1] = jy * ys
            a[:-1, -1] = jw * ws
            a[-1] = t
            rhs = np.concatenate([-r, [-(t @ (v - pred))]])
            v = v + np.linalg.solve(a, rhs)
            yy, ww = v[:-1] * ys, v[-1] * ws
            if ww <= 0.0:
                break
            # the Jacobian at the new point: its residual decides, and it gives the tangent
            r, jy, jw = balance.jacobian(yy, ww, with_omega=True)
            iterations += 1
            if balance.converged(r, yy):
                ok = True
                break
        if ok:
            t_new = _tangent(jy, jw, max(ys, float(np.linalg.norm(yy))), ws, t)
            if t_new @ t < math.cos(cs.max_angle) and step > ds_min:
                ok = False
        if not ok:
            rejected += 1
            ds = 0.5 * step
            if ds < ds_min:
                raise ConvergenceError(f"the continuation stalled at "
                                       f"{omega / (2 * math.pi):.4g} Hz (step below "
                                       f"{cs.step_min / (2 * math.pi):.2g} Hz)")
            continue
        if ww < omega_start - cs.step_max:
            raise ConvergenceError(f"the branch turned back below the band start "
                                   f"({omega_start / (2 * math.pi):.4g} Hz) at "
                                   f"{omega / (2 * math.pi):.4g} Hz")
        if ww >= omega_end:
            y_end, n_it = balance.solve(omega_end, y + (yy - y) * (omega_end - omega) /
                                        (ww - omega))
            iterations += n_it
            points_w.append(omega_end)
            points_y.append(y_end)
            break
        y, omega = yy, ww
        ys = max(ys, float(np.linalg.norm(y)))
        t = t_new
        points_w.append(omega)
        points_y.append(y)
        if used <= cs.fast:
            ds = min(1.5 * ds, ds_max)
    return Branch(omega=np.array(points_w), y=np.array(points_y), iterations=iterations,
                  rejected=rejected)
