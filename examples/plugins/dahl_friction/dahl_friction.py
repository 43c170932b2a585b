"""The Dahl friction model as a servotune friction law, in a package of its own.

Dahl (1968) modelled friction as a stress-strain curve of the contact: the force depends on the
path travelled, not on the speed (rate independent), and reaches the Coulomb force Fc after a
presliding distance of the order of Fc/sigma0::

    dF/dx = sigma0 (1 - F/Fc sgn(v))^alpha          (Olsson et al. 1998, Eq 5)

With the state z = F/sigma0 [m] and ``u = sigma0 z sgn(v) / Fc`` this is, in time::

    dz/dt = v h(u),     h(u) = |1 - u|^alpha sgn(1 - u),     F = sigma0 z + sigma2 v

(the power of a signed base written so that a force above Fc decays back to it; Olsson et al.
1998, Eq 6, for alpha = 1: ``dF/dt = sigma0 (v - |v| F/Fc)``), with a viscous part sigma2 v
beside it (0 by default; the design job of servotune tunes it as the guide ways' damping C).
Steady sliding gives F = Fc sgn(v) + sigma2 v (no Stribeck effect); from rest (the virgin
curve, alpha = 1) a displacement x in one direction gives
``F = Fc (1 - exp(-sigma0 |x| / Fc)) sgn(x)``. alpha = 1 is the usual
choice; alpha > 1 bends the curve more sharply (Olsson et al. 1998). alpha < 1 is refused here:
the rate's derivative in z is then infinite at steady sliding, and the implicit time integration
of servotune needs it.

How servotune takes the law (:class:`servotune.friction.law.FrictionLaw`): a linear block per
pad, ``dz/dt = v - c0 - c_v v - c_z z - r`` and ``F = sigma0 z + sigma2 v``, and the
nonlinear remainder ``r = w(v, z) - (c0 + c_v v + c_z z)`` with ``w = v (1 - h(u))``
(:func:`dahl_remainder`, a numba function the simulation compiles its kernel around). About
rest c0 = c_v = c_z = 0 (the presliding spring sigma0); about steady sliding at v0 the tangent
of w at z0 = sgn(v0) Fc/sigma0:
c_v = 1, c_z = alpha sigma0 |v0| |1 - u0|^(alpha - 1) / Fc (sigma0 |v0| / Fc for alpha = 1, 0
above), c0 = v0 - c_v v0 - c_z z0. The periodic force of harmonic balance is exact: on a path
that is monotone between samples the law has a closed form (:func:`dahl_step`).

Installed (``pip install -e examples/plugins/dahl_friction``), the law is ``[friction.dahl]`` of
an axis file::

    [friction.dahl]
    sigma0 = 5.9e9     # N/m, axis total
    fc = 2198.0        # N, axis total
    alpha = 1.0
    sigma2 = 0.0       # N s/m, axis total (optional)

References
----------
P. R. Dahl, "A solid friction model", Technical Report TOR-0158(3107-18)-1, The Aerospace
Corporation, El Segundo (1968).
H. Olsson, K. J. Astrom, C. Canudas de Wit, M. Gafvert, P. Lischinsky, "Friction models and
friction compensation", European Journal of Control 4 (1998) 176-195, sec 3.2 (the Dahl model),
Eq 5-6.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import control
import numba
import numpy as np

from servotune.friction.law import FrictionLaw
from servotune.structure.model import signal_name

__all__ = ["DahlFriction", "dahl_remainder", "dahl_step"]


@numba.njit(cache=True)
def dahl_remainder(component, v, z, p):
    """Return the Dahl remainder r = w(v, z) - (c0 + c_v v + c_z z) and its partial derivatives.

    ``w = v (1 - h(u))``, ``u = ratio z sgn(v)``, ``h(u) = |1 - u|^alpha sgn(1 - u)``; at v = 0
    the derivative of sgn(v) is taken as 0 (w and its derivatives are 0 there).

    Parameters
    ----------
    component : int
        0 (the law has one remainder per pad).
    v : float
        Pad velocity [m/s].
    z : float
        The state F/sigma0 [m].
    p : numpy.ndarray
        ``(ratio, alpha, c0, c_v, c_z)`` with ratio = sigma0/Fc [1/m].

    Returns
    -------
    (r, dr_dv, dr_dz) : tuple of float
        r [m/s], dr/dv [-], dr/dz [1/s].
    """
    ratio, alpha, c0, cv, cz = p[0], p[1], p[2], p[3], p[4]
    if v > 0.0:
        s = 1.0
    elif v < 0.0:
        s = -1.0
    else:
        return -(c0 + cz * z), -cv, -cz
    gap = 1.0 - ratio * z * s
    size = abs(gap)
    h = size**alpha if gap >= 0.0 else -(size**alpha)
    w = v * (1.0 - h)
    dw_dz = abs(v) * ratio * alpha * size ** (alpha - 1.0)
    return w - (c0 + cv * v + cz * z), (1.0 - h) - cv, dw_dz - cz


@numba.njit(cache=True)
def dahl_step(z, dx, ratio, alpha):
    """Return the state after a displacement dx travelled in one direction (closed form).

    With ``g = 1 - u``, ``u = ratio z sgn(dx)``: ``dg/d|x| = -ratio |g|^alpha sgn(g)``, so
    ``|g|`` decays as ``exp(-ratio |dx|)`` (alpha = 1) or as
    ``(|g|^(1-alpha) + (alpha-1) ratio |dx|)^(1/(1-alpha))`` (alpha > 1), keeping its sign.

    Parameters
    ----------
    z : float
        The state before [m].
    dx : float
        The displacement [m].
    ratio : float
        sigma0/Fc [1/m].
    alpha : float
        The exponent, >= 1.

    Returns
    -------
    float
        The state after [m].
    """
    if dx == 0.0:
        return z
    s = 1.0 if dx > 0.0 else -1.0
    gap = 1.0 - ratio * z * s
    if gap == 0.0:
        return z
    size = abs(gap)
    travel = ratio * abs(dx)
    if alpha == 1.0:
        size = size * math.exp(-travel)
    else:
        size = (size ** (1.0 - alpha) + (alpha - 1.0) * travel) ** (1.0 / (1.0 - alpha))
    gap = size if gap > 0.0 else -size
    return s * (1.0 - gap) / ratio


@numba.njit(cache=True)
def _sweep(z0, x, drift, ratio, alpha, out):
    """States at the points of the path x (one period, then x[0] + drift), from z0; returns
    the state one period later."""
    z = z0
    n = x.size
    for i in range(n):
        out[i] = z
        nxt = x[i + 1] if i + 1 < n else x[0] + drift
        z = dahl_step(z, nxt - x[i], ratio, alpha)
    return z


@dataclass(frozen=True)
class DahlFriction(FrictionLaw):
    """Dahl friction of a guide way (axis totals, shared equally by the pads).

    Parameters
    ----------
    sigma0 : float
        Rest stiffness [N/m], axis total, > 0.
    fc : float
        Coulomb force [N], axis total, > 0.
    alpha : float
        Shape exponent of the stress-strain curve [-], >= 1 (1: the usual model).
    sigma2 : float
        Viscous part [N s/m], axis total, >= 0.

    Raises
    ------
    ValueError
        A value out of range (the message names it).

    Examples
    --------
    >>> law = DahlFriction(sigma0=5.9e9, fc=2198.0)
    >>> law.presliding()
    (5900000000.0, 0.0)
    """

    sigma0: float
    fc: float
    alpha: float = 1.0
    sigma2: float = 0.0
    name = "dahl"
    nonlinear = True
    table_hint = "give sigma0 [N/m], fc [N] (axis totals) and optionally alpha (>= 1)"
    #: Velocity scale [m/s] of the integrator's error control (the law has no velocity of its
    #: own: a Stribeck velocity of guide ways).
    velocity_scale = 1e-3

    def __post_init__(self) -> None:
        for field, low in (("sigma0", 0.0), ("fc", 0.0)):
            value = float(getattr(self, field))
            if not (math.isfinite(value) and value > low):
                raise ValueError(f"DahlFriction.{field} must be finite and > 0, got "
                                 f"{getattr(self, field)!r}")
            object.__setattr__(self, field, value)
        alpha = float(self.alpha)
        if not (math.isfinite(alpha) and alpha >= 1.0):
            raise ValueError(f"DahlFriction.alpha must be finite and >= 1, got {self.alpha!r} "
                             "(below 1 the rate is not differentiable at steady sliding)")
        object.__setattr__(self, "alpha", alpha)
        sigma2 = float(self.sigma2)
        if not (math.isfinite(sigma2) and sigma2 >= 0.0):
            raise ValueError(f"DahlFriction.sigma2 must be finite and >= 0 N s/m, got "
                             f"{self.sigma2!r}")
        object.__setattr__(self, "sigma2", sigma2)

    @property
    def ratio(self) -> float:
        """sigma0 / Fc [1/m]: the inverse presliding distance (the same for any pad's share)."""
        return self.sigma0 / self.fc

    @classmethod
    def from_table(cls, value) -> DahlFriction:
        """Build the law from ``[friction.dahl]``: ``sigma0`` [N/m], ``fc`` [N], ``alpha``,
        ``sigma2`` [N s/m].

        Parameters
        ----------
        value : dict
            The entry of the axis file.

        Returns
        -------
        DahlFriction

        Raises
        ------
        ValueError
            A parameter is missing, unknown or out of range.
        """
        if not isinstance(value, dict) or not {"sigma0", "fc"} <= set(value) <= {
                "sigma0", "fc", "alpha", "sigma2"}:
            raise ValueError(f"give sigma0 and fc (and optionally alpha, sigma2), got {value!r}")
        return cls(**value)

    @property
    def viscous_part(self) -> float:
        """sigma2 [N s/m]."""
        return self.sigma2

    def with_viscous(self, c: float) -> DahlFriction:
        """Return the law with the viscous part ``c`` [N s/m] (the design's C).

        Parameters
        ----------
        c : float
            Viscous damping [N s/m], >= 0.

        Returns
        -------
        DahlFriction
        """
        return dataclasses.replace(self, sigma2=float(c))

    def presliding(self) -> tuple[float, float]:
        """Return the contact at rest, axis totals: the spring sigma0 and the damper sigma2.

        Returns
        -------
        (stiffness, damping) : tuple of float
            Spring [N/m] and damper [N s/m].
        """
        return self.sigma0, self.sigma2

    def sliding_system(self, speed: float) -> control.StateSpace:
        """Return the contact linearised about steady sliding: the viscous part alone.

        While sliding F = Fc sgn(v) + sigma2 v, and a velocity change does not reach z to first
        order (h(1) = 0): the linear contact is the gain sigma2.

        Parameters
        ----------
        speed : float
            Sliding speed v0 [m/s], non-zero.

        Returns
        -------
        control.StateSpace
            SISO static gain sigma2 [N s/m].

        Raises
        ------
        ValueError
            If ``speed`` is 0 or not finite.
        """
        if not (speed and math.isfinite(speed)):
            raise ValueError("the sliding contact needs a finite non-zero speed v0 [m/s]")
        return control.ss([], [], [], [[self.sigma2]])

    def linearisation(self, speed: float = 0.0) -> tuple[float, float, float]:
        """Return (c0, c_v, c_z) of ``w ~ c0 + c_v v + c_z z`` about rest or steady sliding.

        Parameters
        ----------
        speed : float
            Operating speed v0 [m/s] (0: rest, where w = 0 to first order).

        Returns
        -------
        (c0, c_v, c_z) : tuple of float
            c0 [m/s], c_v [-], c_z [1/s].
        """
        speed = float(speed)
        if not math.isfinite(speed):
            raise ValueError(f"the operating speed must be finite, got {speed!r}")
        if speed == 0.0:
            return 0.0, 0.0, 0.0
        z0 = math.copysign(1.0 / self.ratio, speed)
        cz = self.ratio * abs(speed) if self.alpha == 1.0 else 0.0
        return -cz * z0, 1.0, cz

    def pad_block(self, pad: str, n_pads: int, speed: float = 0.0) -> control.StateSpace:
        """Return the linear part for one pad: ``dz/dt = v - (c0 + c_v v + c_z z) - r``,
        ``F = (sigma0 z + sigma2 v) / n_pads``.

        Parameters
        ----------
        pad : str
            The pad DOF.
        n_pads : int
            The number of pads sharing the axis-total law equally.
        speed : float
            Operating speed [m/s] of the linearisation (0: at rest).

        Returns
        -------
        control.StateSpace
            Inputs ``v_<pad>``, ``r_<pad>``, ``one``; outputs ``f_<pad>``, ``F_<pad>``,
            ``z_<pad>``.
        """
        v, r, f, force, z = (signal_name(pad, s) for s in ("v_", "r_", "f_", "F_", "z_"))
        c0, cv, cz = self.linearisation(speed)
        k, c = self.sigma0 / n_pads, self.sigma2 / n_pads
        return control.ss([[-cz]], [[1.0 - cv, -1.0, -c0]], [[-k], [k], [1.0]],
                          [[-c, 0.0, 0.0], [c, 0.0, 0.0], [0.0, 0.0, 0.0]],
                          inputs=[v, r, "one"], outputs=[f, force, z],
                          states=[z], name=f"friction_{signal_name(pad)}")

    def remainder(self):
        """Return the compiled remainder :func:`dahl_remainder`.

        Returns
        -------
        numba dispatcher
            ``(component, v, z, p) -> (r, dr_dv, dr_dz)``.
        """
        return dahl_remainder

    def remainder_parameters(self, speed: float = 0.0) -> np.ndarray:
        """Return ``(sigma0/Fc, alpha, c0, c_v, c_z)`` for a linearisation.

        Parameters
        ----------
        speed : float
            Operating speed [m/s] of the linear part (0: at rest).

        Returns
        -------
        numpy.ndarray
            The remainder's parameter vector.
        """
        return np.array([self.ratio, self.alpha, *self.linearisation(speed)])

    def remainder_states(self, pad: str) -> tuple[str, ...]:
        """Return the state the remainder reads: ``z_<pad>``.

        Parameters
        ----------
        pad : str
            The pad DOF.

        Returns
        -------
        tuple of str
            One state name.
        """
        return (signal_name(pad, "z_"),)

    def spring_states(self, pad: str, n_pads: int) -> tuple[tuple[str, float], ...]:
        """Return the elastic state: ``z_<pad>`` with sigma0 / n_pads.

        Parameters
        ----------
        pad : str
            The pad DOF.
        n_pads : int
            The number of pads sharing the law.

        Returns
        -------
        tuple of (str, float)
            (state name, stiffness [N/m]).
        """
        return ((signal_name(pad, "z_"), self.sigma0 / n_pads),)

    def error_scales(self) -> tuple[float, tuple[float, ...]]:
        """Return the scales of the integrator's error control: :attr:`velocity_scale` and
        the presliding distance Fc/sigma0.

        Returns
        -------
        (v_scale, z_scales) : tuple
            Velocity scale [m/s] and one state scale [m].
        """
        return self.velocity_scale, (1.0 / self.ratio,)

    def newton_tolerance(self, step: float) -> float:
        """Return the tolerance on the remainder in a Newton iteration: a force error of
        1e-10 Fc through sigma0 over a step.

        Parameters
        ----------
        step : float
            The integration step [s].

        Returns
        -------
        float
            Tolerance [m/s].
        """
        return 1e-10 / (self.ratio * step)

    def friction_force(self, v, z):
        """Return the friction force sigma0 z + sigma2 v [N], axis total.

        Parameters
        ----------
        v : array_like
            Pad velocity [m/s].
        z : array_like
            The state [m].

        Returns
        -------
        numpy.ndarray
            Friction force [N].
        """
        return self.sigma0 * np.asarray(z, dtype=float) + self.sigma2 * np.asarray(v, dtype=float)

    def periodic_force(self, velocity, period: float, share: float = 1.0,
                       refine: int = 8) -> np.ndarray:
        """Return the force [N] of one pad carrying ``share`` of the law on its periodic orbit.

        Parameters
        ----------
        velocity : array_like
            Pad velocity [m/s] at N equally spaced instants of one period (periodic).
        period : float
            The period [s], > 0.
        share : float
            The pad's share of the axis-total law (``1 / n_pads``), > 0.
        refine : int
            Points of the path per sample interval.

        Returns
        -------
        numpy.ndarray
            The force [N] at the same N instants.

        Raises
        ------
        ValueError
            Bad velocity samples, period or share.

        Notes
        -----
        The law is rate independent: only the path x(t) matters. x is the trigonometric
        integral of the velocity samples (its mean velocity a drift), at ``refine`` points per
        sample interval, and between two points the path is taken monotone, where
        :func:`dahl_step` is exact. The state on the orbit is the fixed point of the map over
        one period, which is increasing with slope below 1 in z0 (a contraction when the path
        moves): for alpha = 1 the map is affine, ``P(z0) = a z0 + b`` with
        ``a = exp(-sigma0/Fc * total variation)``, solved in closed form; else by bisection on
        [-Fc/sigma0, Fc/sigma0]. A path that does not move keeps the virgin state z = 0; one
        that never reverses is steady sliding, z = sgn(v) Fc/sigma0 (for alpha > 1 the map's
        slope tends to 1 there, and the fixed point is its limit).
        """
        v = np.asarray(velocity, dtype=float)
        period, share = float(period), float(share)
        if v.ndim != 1 or v.size < 2 or not np.all(np.isfinite(v)):
            raise ValueError("velocity must be a 1-D array of at least 2 finite samples [m/s]")
        if not (math.isfinite(period) and period > 0 and math.isfinite(share) and share > 0):
            raise ValueError(f"period [s] and share must be > 0, got {period!r} and {share!r}")
        n = v.size
        fine = n * int(refine)
        spectrum = np.fft.rfft(v) / n
        k = np.arange(spectrum.size)
        integral = np.zeros(fine // 2 + 1, dtype=complex)
        integral[1:spectrum.size] = spectrum[1:] / (2j * math.pi * k[1:] / period)
        if n % 2 == 0:
            integral[n // 2] = 0.0  # the Nyquist sample has no defined integral
        x = np.fft.irfft(integral, n=fine) * fine
        drift = float(spectrum[0].real) * period
        x = x + drift * np.arange(fine) / fine
        ratio, alpha = self.ratio, self.alpha
        out = np.empty(fine)

        def period_map(z0):
            return _sweep(z0, x, drift, ratio, alpha, out)

        steps = np.diff(np.append(x, x[0] + drift))
        variation = float(np.abs(steps).sum())
        if variation * ratio < 1e-300:
            z0 = 0.0
        elif np.all(steps >= 0.0) or np.all(steps <= 0.0):
            z0 = math.copysign(1.0 / ratio, drift)   # no reversal: steady sliding
        elif alpha == 1.0:
            b = period_map(0.0)
            z0 = b / -math.expm1(-ratio * variation)
        else:
            low, high = -1.0 / ratio, 1.0 / ratio
            for _ in range(200):
                mid = 0.5 * (low + high)
                if period_map(mid) > mid:
                    low = mid
                else:
                    high = mid
                if high - low <= 1e-15 / ratio:
                    break
            z0 = 0.5 * (low + high)
        period_map(z0)
        return share * (self.sigma0 * out[::refine] + self.sigma2 * v)
