"""The LuGre friction law (Canudas de Wit et al. 1995; Bianchi et al. 2014, Eq 3) as a plug-in.

The simulator (:mod:`servotune.simulate.integrator`) integrates the linear part of the axis
exactly and treats what is nonlinear implicitly, through one scalar input per pad. A friction law
therefore comes in two parts:

* a **linear block** per pad (python-control), with inputs the pad velocity ``v_<pad>``, the
  nonlinear remainder ``r_<pad>`` and a constant ``one``, and outputs the force on the pad DOF
  ``f_<pad>``, the friction force ``F_<pad>`` and the internal state ``z_<pad>``;
* a **remainder** ``r(v, z)`` [m/s], a compiled (numba) scalar function with its two partial
  derivatives, evaluated per pad by the integrator (absent for linear laws). A law may have
  more than one remainder per pad (:attr:`~servotune.friction.law.FrictionLaw.n_remainders`),
  each an input of the linear block and a function of the same ``(v, z)``.

LuGre (Bianchi et al. 2014, Eq 3; Canudas de Wit et al. 1995)::

    dz/dt = v - w,     w = a(v) z,     a(v) = sigma0 |v| / g(v)
    F     = sigma0 z + sigma1 (v - w) + sigma2 v

w [m/s] is the bristle relaxation rate. It is split into a linearisation about an operating
point and a remainder, ``w = c0 + c_v v + c_z z + r``: about rest (c0 = c_v = c_z = 0) the linear
part is the presliding contact (a spring sigma0 with a damper sigma1 + sigma2, as
:func:`servotune.friction.presliding_linearisation`); about steady sliding at v0 it is
:func:`servotune.friction.sliding_linearisation`, so that the large and stiff cancellation of
sigma1 v by sigma1 w while sliding is carried exactly by the linear part and the remainder stays
small. The axis-total parameters are shared equally by the pads (``params.scaled(1/n)``); the
rate a(v) does not change with the share.

With a velocity-dependent micro-damping (``LuGreParameters.sigma1_decay_speed = v_d``, Olsson
et al. 1998) the force carries a second nonlinearity, ``sigma1 m`` with ``m = e(v) (v - w)``
and ``e(v) = exp(-(v/v_d)^2)``::

    F = sigma0 z + sigma1 m + sigma2 v,     m = m0 + m_v v + m_z z - q

so the law has a second remainder ``q_<pad>`` [m/s] (component 1 of
:func:`lugre_damping_remainder`):
``q = m0 + m_v v + m_z z - e(v) (v - a(v) z)``, linearised about the same operating point as
w (about rest m ~ v, the presliding damper sigma1; about steady sliding at v0 the damper
sigma1 e(v0) of :func:`servotune.friction.sliding_linearisation`).

References
----------
C. Canudas de Wit, H. Olsson, K. J. Astrom, P. Lischinsky, "A new model for control of systems
with friction", IEEE Trans. Automatic Control 40(3) (1995) 419-425.
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
Eq 3 and sec 5.3.
H. Olsson, K. J. Astrom, C. Canudas de Wit, M. Gafvert, P. Lischinsky, "Friction models and
friction compensation", European Journal of Control 4 (1998) 176-195.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import control
import numpy as np

from ...cache import cached_njit
from ...structure.model import signal_name
from ..equivalent import describing_function
from ..law import FrictionLaw
from ..lugre import (
    LuGreParameters,
    lugre_force,
    lugre_jacobian,
    sliding_linearisation,
    steady_state_friction,
    steady_state_slope,
    stribeck_curve,
)

__all__ = ["LuGreFriction", "lugre_remainder", "lugre_damping_remainder"]


@cached_njit
def lugre_remainder(v, z, p):
    """Return the LuGre remainder r = a(v) z - (c0 + c_v v + c_z z) and its partial derivatives.

    At v = 0 the derivative of |v| is taken as 0.

    Parameters
    ----------
    v : float
        Pad velocity [m/s].
    z : float
        Bristle deflection [m].
    p : numpy.ndarray
        ``(sigma0, fc, fs, vs, delta, c0, c_v, c_z, ...)`` (sigma0, fc, fs of any share: only
        their ratios enter).

    Returns
    -------
    (r, dr_dv, dr_dz) : tuple of float
        r [m/s], dr/dv [-], dr/dz [1/s].
    """
    sigma0, fc, fs, vs, delta, c0, cv, cz = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    av = abs(v)
    if av > 0.0:
        e = math.exp(-((av / vs) ** delta))
        g = fc + (fs - fc) * e
        s = 1.0 if v > 0.0 else -1.0
        # d|v|/dv = s; dg/dv = -(fs - fc) delta (|v|/vs)^(delta-1) / vs * e * s
        dg = -(fs - fc) * delta * (av / vs) ** (delta - 1.0) / vs * e * s
        a = sigma0 * av / g
        da = sigma0 * (s / g - av * dg / (g * g))
    else:
        a = 0.0
        da = 0.0
    r = a * z - (c0 + cv * v + cz * z)
    return r, da * z - cv, a - cz


@cached_njit
def lugre_damping_remainder(component, v, z, p):
    """Return a remainder of LuGre with micro-damping sigma1 e(v), e(v) = exp(-(v/v_d)^2).

    Component 0 is :func:`lugre_remainder`; component 1 is
    ``q = m0 + m_v v + m_z z - e(v) (v - a(v) z)`` with its partial derivatives.

    Parameters
    ----------
    component : int
        0 (r) or 1 (q).
    v : float
        Pad velocity [m/s].
    z : float
        Bristle deflection [m].
    p : numpy.ndarray
        ``(sigma0, fc, fs, vs, delta, c0, c_v, c_z, v_d, m0, m_v, m_z)`` (the first eight alone
        for component 0).

    Returns
    -------
    (value, d_dv, d_dz) : tuple of float
        The remainder [m/s] and its partial derivatives [-], [1/s].
    """
    r, dr_dv, dr_dz = lugre_remainder(v, z, p)
    if component == 0:
        return r, dr_dv, dr_dz
    vd, m0, mv, mz = p[8], p[9], p[10], p[11]
    # a z = r + c0 + c_v v + c_z z, and its derivatives likewise
    az = r + p[5] + p[6] * v + p[7] * z
    daz_dv = dr_dv + p[6]
    a = dr_dz + p[7]
    x = v / vd
    e = math.exp(-x * x)
    de = -2.0 * x / vd * e
    zdot = v - az
    q = m0 + mv * v + mz * z - e * zdot
    return q, mv - de * zdot - e * (1.0 - daz_dv), mz + e * a



@dataclass(frozen=True)
class LuGreFriction(FrictionLaw):
    """LuGre guide-way friction (axis-total parameters, shared equally by the pads).

    Parameters
    ----------
    params : LuGreParameters
        Axis total, e.g. ``LuGreParameters.named("bianchi2014")``. With
        ``sigma1_decay_speed`` set the law has the second remainder of the micro-damping (see
        the module docstring).

    Examples
    --------
    About rest the linear part is the presliding contact: spring sigma0 and damper
    sigma1 + sigma2, shared by the pads.

    >>> law = LuGreFriction(LuGreParameters.named("bianchi2014"))
    >>> block = law.pad_block("pad1.x", 4)
    >>> float(block.C[1, 0]) * 4, float(block.D[1, 0]) * 4     # dF/dz, dF/dv (total)
    (5900000000.0, 16005578.0)
    """

    params: LuGreParameters
    name = "lugre"
    nonlinear = True
    remainder_prefixes = ("r_", "q_")
    table_hint = ("give a named set ('bianchi2014', 'canudas1995') or a table {fc, fs, vs, delta, "
                  "sigma0, sigma1, sigma2} in SI units")

    def __post_init__(self) -> None:
        if not isinstance(self.params, LuGreParameters):
            raise ValueError("LuGreFriction needs LuGreParameters, e.g. "
                             "LuGreParameters.named('bianchi2014')")

    @property
    def n_remainders(self) -> int:
        """1 (r) with a constant sigma1, 2 (r and q) with the micro-damping."""
        return 1 if self.params.sigma1_decay_speed is None else 2

    def _operating_point(self, speed: float):
        speed = float(speed)
        if not math.isfinite(speed):
            raise ValueError(f"the operating speed must be finite, got {speed!r}")
        if speed == 0.0:
            return speed, 0.0, None
        p = self.params
        z0 = math.copysign(float(stribeck_curve(p, speed)), speed) / p.sigma0
        return speed, z0, lugre_jacobian(p, z0, speed)

    def linearisation(self, speed: float = 0.0) -> tuple[float, float, float]:
        """Return (c0, c_v, c_z) of ``w ~ c0 + c_v v + c_z z`` about rest or steady sliding.

        Parameters
        ----------
        speed : float
            Operating speed v0 [m/s]: 0 for rest (0, 0, 0), else the tangent at v0 and
            z_ss = sgn(v0) g(v0)/sigma0.

        Returns
        -------
        (c0, c_v, c_z) : tuple of float
            c0 [m/s], c_v [-], c_z [1/s].
        """
        speed, z0, jac = self._operating_point(speed)
        if jac is None:
            return 0.0, 0.0, 0.0
        # dz/dt = v - w  =>  dw/dv = 1 - d(zdot)/dv, dw/dz = -d(zdot)/dz
        cv = 1.0 - float(jac.dzdot_dv)
        cz = -float(jac.dzdot_dz)
        w0 = speed  # steady sliding: dz/dt = 0
        return w0 - cv * speed - cz * z0, cv, cz

    def damping_linearisation(self, speed: float = 0.0) -> tuple[float, float, float]:
        """Return (m0, m_v, m_z) of ``e(v) dz/dt ~ m0 + m_v v + m_z z`` about rest or steady
        sliding.

        Parameters
        ----------
        speed : float
            Operating speed v0 [m/s]: 0 for rest (0, 1, 0); while sliding dz/dt = 0, so the slope of
            e does not enter.

        Returns
        -------
        (m0, m_v, m_z) : tuple of float
            m0 [m/s], m_v [-], m_z [1/s].
        """
        speed, z0, jac = self._operating_point(speed)
        if jac is None:
            return 0.0, 1.0, 0.0
        vd = self.params.sigma1_decay_speed
        e0 = 1.0 if vd is None else math.exp(-((speed / vd) ** 2))
        mv = e0 * float(jac.dzdot_dv)
        mz = e0 * float(jac.dzdot_dz)
        return -(mv * speed + mz * z0), mv, mz

    def pad_block(self, pad: str, n_pads: int, speed: float = 0.0) -> control.StateSpace:
        """Return the linear part for one pad: the bristle state, linearised about rest or steady
        sliding (module docstring).

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
            Inputs ``v_<pad>``, ``r_<pad>`` (and ``q_<pad>`` with the micro-damping), ``one`` ;
            outputs ``f_<pad>``, ``F_<pad>``, ``z_<pad>``.
        """
        v, f, force, z = (signal_name(pad, pre) for pre in ("v_", "f_", "F_", "z_"))
        remainders = list(self.remainder_signals(pad))
        p = self.params.scaled(1.0 / n_pads)
        c0, cv, cz = self.linearisation(speed)
        a = [[-cz]]
        if self.n_remainders == 1:
            # dz/dt = v - (c0 + cv v + cz z + r);  F = s0 z + s1 dz/dt + s2 v;  f = -F
            b = [[1.0 - cv, -1.0, -c0]]
            c_force = [p.sigma0 - p.sigma1 * cz]
            d_force = [p.sigma1 * (1.0 - cv) + p.sigma2, -p.sigma1, -p.sigma1 * c0]
        else:
            # F = s0 z + s1 (m0 + mv v + mz z - q) + s2 v
            m0, mv, mz = self.damping_linearisation(speed)
            b = [[1.0 - cv, -1.0, 0.0, -c0]]
            c_force = [p.sigma0 + p.sigma1 * mz]
            d_force = [p.sigma1 * mv + p.sigma2, 0.0, -p.sigma1, p.sigma1 * m0]
        zeros = [0.0] * len(d_force)
        return control.ss(a, b, [[-c_force[0]], c_force, [1.0]],
                          [[-d for d in d_force], d_force, zeros],
                          inputs=[v, *remainders, "one"], outputs=[f, force, z], states=[z],
                          name=f"friction_{signal_name(pad)}")

    def remainder(self):
        """Return the compiled remainder: :func:`lugre_damping_remainder` (whose component 0 is
        :func:`lugre_remainder`).

        Returns
        -------
        numba dispatcher
            ``(component, v, z, p) -> (r, dr_dv, dr_dz)``.
        """
        return lugre_damping_remainder

    def remainder_states(self, pad: str) -> tuple[str, ...]:
        """Return the state each remainder component reads: both remainders read the bristle
        deflection ``z_<pad>``.

        Parameters
        ----------
        pad : str
            The pad DOF.

        Returns
        -------
        tuple of str
            One state name per remainder component.
        """
        return (signal_name(pad, "z_"),) * self.n_remainders

    def spring_states(self, pad: str, n_pads: int) -> tuple[tuple[str, float], ...]:
        """Return one pad's elastic states with their stiffnesses: the bristles ``z_<pad>`` with
        sigma0 / n_pads.

        Parameters
        ----------
        pad : str
            The pad DOF.
        n_pads : int
            The number of pads sharing the law.

        Returns
        -------
        tuple of (str, float)
            (state name, stiffness [N/m]) pairs.
        """
        return ((signal_name(pad, "z_"), self.params.sigma0 / n_pads),)

    def error_scales(self) -> tuple[float, tuple[float, ...]]:
        """Return the scales of the integrator's error control: the Stribeck velocity vs and the
        presliding deflection Fs/sigma0.

        Returns
        -------
        (v_scale, z_scales) : tuple
            Velocity scale [m/s] and one state scale [m] per remainder component.
        """
        p = self.params
        return p.vs, (p.fs / p.sigma0,) * self.n_remainders

    def newton_tolerance(self, step: float) -> float:
        """Return the tolerance on the remainders in the Newton iteration: a force error of 1e-10 Fc
        through sigma1 + sigma0 h.

        Parameters
        ----------
        step : float
            The integration step [s].

        Returns
        -------
        float
            Tolerance [m/s].
        """
        p = self.params
        return 1e-10 * p.fc / (p.sigma1 + p.sigma0 * step)

    def remainder_parameters(self, speed: float = 0.0) -> np.ndarray:
        """Return the parameters of :meth:`remainder` for a linearisation: ``(sigma0, fc, fs, vs,
        delta, c0, c_v, c_z[, v_d, m0, m_v, m_z])``.

        Parameters
        ----------
        speed : float
            Operating speed [m/s] of the linear part (0: at rest).

        Returns
        -------
        numpy.ndarray
            The remainder's parameter vector.
        """
        p = self.params
        head = [p.sigma0, p.fc, p.fs, p.vs, p.delta, *self.linearisation(speed)]
        if self.n_remainders == 1:
            return np.array(head)
        return np.array([*head, p.sigma1_decay_speed, *self.damping_linearisation(speed)])

    @classmethod
    def from_table(cls, value) -> LuGreFriction:
        """Build the law from ``[friction.lugre]`` of an axis description: a parameter table
        (:class:`LuGreParameters`, SI) or the name of a published set (``lugre = "bianchi2014"``).

        Parameters
        ----------
        value : dict or str
            The entry of the axis file.

        Returns
        -------
        LuGreFriction

        Raises
        ------
        ValueError
            A parameter is missing, unknown or out of range.
        """
        if isinstance(value, str):
            return cls(LuGreParameters.named(value))
        if isinstance(value, dict):
            return cls(LuGreParameters(**value))
        raise ValueError(f"give a parameter table or one of {LuGreParameters.names()}, got "
                         f"{value!r}")

    @property
    def lugre_parameters(self) -> LuGreParameters:
        """The LuGre parameters (for what is written for LuGre alone: the tuning regimes)."""
        return self.params

    @property
    def viscous_part(self) -> float:
        """sigma2 [N s/m]."""
        return self.params.sigma2

    def with_viscous(self, c: float) -> LuGreFriction:
        """Return the law with sigma2 = ``c`` [N s/m].

        Parameters
        ----------
        c : float
            Viscous damping [N s/m], >= 0.

        Returns
        -------
        LuGreFriction
        """
        return LuGreFriction(dataclasses.replace(self.params, sigma2=float(c)))

    def steady_force(self, speed: float) -> float:
        """Return ``g(v) sgn(v) + sigma2 v`` [N]
        (:func:`servotune.friction.lugre.steady_state_friction`).

        Parameters
        ----------
        speed : float
            Sliding speed v [m/s].

        Returns
        -------
        float
        """
        return float(steady_state_friction(self.params, float(speed)))

    def steady_slope(self, speed: float) -> float:
        """Return ``g'(v) sgn(v) + sigma2`` [N s/m]
        (:func:`servotune.friction.lugre.steady_state_slope`; at 0 the slope of g is taken as 0).

        Parameters
        ----------
        speed : float
            Sliding speed v [m/s].

        Returns
        -------
        float
        """
        return float(steady_state_slope(self.params, float(speed)))

    def presliding(self) -> tuple[float, float]:
        """Return the contact linearised at rest, axis totals: spring sigma0 and damper sigma1 +
        sigma2 (:func:`servotune.friction.presliding_linearisation`).

        Returns
        -------
        (stiffness, damping) : tuple of float
            Spring [N/m] and damper [N s/m].
        """
        p = self.params
        return p.sigma0, p.sigma1 + p.sigma2

    def sliding_system(self, speed: float) -> control.StateSpace:
        """Return the contact linearised about steady sliding at a speed, axis total:
        :func:`servotune.friction.sliding_linearisation`.

        Parameters
        ----------
        speed : float
            Sliding speed v0 [m/s], non-zero.

        Returns
        -------
        control.StateSpace
            SISO, from the velocity deviation [m/s] to the force deviation [N].

        Raises
        ------
        ValueError
            If ``speed`` is 0.
        """
        if not speed:
            raise ValueError("the sliding contact needs a non-zero speed v0 [m/s]")
        return sliding_linearisation(self.params, speed)

    def describing_function(self, amplitude: float, omega: float,
                            n_samples: int = 512) -> tuple[float, float]:
        """Return the equivalent damping and stiffness under ``x = A sin(omega t)``:
        :func:`servotune.friction.describing_function` (the periodic LuGre cycle, Eq 8-10 of the
        paper).

        Parameters
        ----------
        amplitude : float
            Displacement amplitude A [m], > 0.
        omega : float
            Angular frequency [rad/s], > 0.
        n_samples : int
            Samples of the period (not used: the LuGre cycle has its own graded steps).

        Returns
        -------
        (ceq, keq) : tuple of float
            Ceq [N s/m] and Keq [N/m], axis totals.
        """
        ceq, keq = describing_function(self.params, amplitude, omega)
        return float(ceq), float(keq)

    def periodic_force(self, velocity, period: float, share: float = 1.0) -> np.ndarray:
        """Return the force of one pad carrying ``share`` of the law on its periodic orbit:
        :func:`servotune.friction.periodic.lugre_periodic_force` with ``params.scaled(share)``.

        Parameters
        ----------
        velocity : array_like
            Pad velocity [m/s] at N equally spaced instants of one period (periodic).
        period : float
            The period [s], > 0.
        share : float
            The pad's share of the axis-total law (``1 / n_pads``), > 0.

        Returns
        -------
        numpy.ndarray
            The force [N] at the same instants.
        """
        from ..periodic import lugre_periodic_force

        return lugre_periodic_force(self.params.scaled(share), velocity, period)

    def periodic_force_jacobian(self, velocity, period: float, share: float = 1.0):
        """Return :meth:`periodic_force` and its exact derivative by the velocity samples.

        Harmonic balance uses it for its Newton steps (without it, it differentiates
        :meth:`periodic_force` numerically).

        Parameters
        ----------
        velocity : array_like
            Pad velocity [m/s] at N equally spaced instants of one period (periodic).
        period : float
            The period [s], > 0.
        share : float
            The pad's share of the axis-total law (``1 / n_pads``), > 0.

        Returns
        -------
        force : numpy.ndarray
            The force [N] at the same instants.
        jacobian : numpy.ndarray
            (N, N) derivative of the force by the velocity samples [N s/m]
            (:func:`servotune.friction.periodic.lugre_periodic_jacobian`).
        """
        from ..periodic import lugre_periodic_jacobian

        return lugre_periodic_jacobian(self.params.scaled(share), velocity, period)

    def friction_force(self, v, z):
        """Return the friction force [N], axis total: :func:`servotune.friction.lugre_force`.

        Parameters
        ----------
        v : array_like
            Pad velocity [m/s].
        z : array_like
            Bristle deflection [m].

        Returns
        -------
        numpy.ndarray
            Friction force [N].
        """
        return lugre_force(self.params, z, v)
