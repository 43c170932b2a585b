"""The LuGre friction model: parameters, steady state, dynamics, linearisations, simulation.

The LuGre model (Canudas de Wit et al. 1995; Bianchi et al. 2014, Eq 3) describes friction
as the mean deflection z of elastic bristles::

    dz/dt = v - sigma0 |v| z / g(v)
    g(v)  = Fc + (Fs - Fc) exp(-|v / vs|^delta)              (Stribeck curve)
    F     = sigma0 z + sigma1 dz/dt + sigma2 v

v is the sliding velocity, F the friction force (same sign as v when sliding). At constant
velocity z settles at ``z_ss = sgn(v) g(v) / sigma0`` and F at the steady-state friction
``F_ss(v) = g(v) sgn(v) + sigma2 v`` (the paper's Fig 7). For small motions the bristles act as
a spring sigma0 with a damper sigma1 + sigma2 (presliding, the paper's Fig 2 and Fig 6).

Velocity-dependent micro-damping
--------------------------------
Optionally (``LuGreParameters.sigma1_decay_speed = v_d``) the bristle damping fades out with
the sliding speed (Canudas de Wit et al. 1995; Olsson et al. 1998)::

    F = sigma0 z + sigma1(v) dz/dt + sigma2 v,      sigma1(v) = sigma1 exp(-(v / v_d)^2)

It keeps the presliding damper sigma1 for |v| << v_d and removes, while sliding, the term
sigma1 d(dz/dt)/dv = sigma1 |v| g'(v) / g(v), which is a negative damping in the Stribeck
region and can drive a lightly damped local mode into stick-slip oscillation. v_d = None (the
default) is the paper's constant sigma1. The steady state (dz/dt = 0) does not depend on it.

Simulation under an imposed motion
----------------------------------
:func:`simulate_lugre` and :func:`lugre_cycle` integrate the bristle equation for an imposed
displacement or velocity history. The equation is stiff while sliding (its rate
``sigma0 |v| / g`` reaches 1e4 1/s on the paper's axis) but linear in z, so it is integrated
with an *exponential integrator* in the bristle time ``phi = int sigma0 |v| / g dt``: exact
when the steady deflection is constant, unconditionally stable, of high order in the step
(fourth order observed against Radau at tight tolerance), with no
Newton iterations and no step-size control; each step is an affine map of z, and a whole history
is solved by a vectorised prefix scan (see ``servotune/friction/_exponential.py``). Velocity
reversals are put on step boundaries, where ``|v|`` has its kink. Many amplitudes and
frequencies are integrated at once as rows of one array; the periodic steady state follows from
one period without simulating the transient.

References
----------
C. Canudas de Wit, H. Olsson, K. J. Astrom, P. Lischinsky, "A new model for control of systems
with friction", IEEE Trans. Automatic Control 40(3) (1995) 419-425.
G. Bianchi, S. Cagna, N. Cau, F. Paolucci, "Analysis of vibration damping in machine tools",
Procedia CIRP 21 (2014) 367-372, Eq 3 and the table after Fig 8.
K. J. Astrom, C. Canudas de Wit, "Revisiting the LuGre friction model", IEEE Control Systems
Magazine 28(6) (2008) 101-114.
H. Olsson, K. J. Astrom, C. Canudas de Wit, M. Gafvert, P. Lischinsky, "Friction models and
friction compensation", European Journal of Control 4 (1998) 176-195 (velocity-dependent
micro-damping for passivity).
"""

from __future__ import annotations

import dataclasses
import math
import types
from dataclasses import dataclass
from typing import NamedTuple

import control
import numpy as np
from scipy import interpolate

from ..validation import finite, finite_array, positive, positive_array
from . import _exponential

__all__ = [
    "BIANCHI2014",
    "BIANCHI2014_SPREAD",
    "CANUDAS1995",
    "HysteresisCycle",
    "LuGreJacobian",
    "LuGreParameters",
    "LuGreResponse",
    "lugre_cycle",
    "lugre_derivative",
    "lugre_force",
    "lugre_jacobian",
    "micro_damping",
    "presliding_linearisation",
    "simulate_lugre",
    "sliding_linearisation",
    "steady_state_friction",
    "steady_state_slope",
    "stribeck_curve",
]

DEFAULT_CYCLE_STEPS = 1024


@dataclass(frozen=True)
class LuGreParameters:
    """The seven LuGre parameters, in SI units, and an optional micro-damping decay speed.

    Parameters
    ----------
    fc : float
        Coulomb friction force Fc [N], > 0.
    fs : float
        Static (breakaway) friction force Fs [N], >= Fc.
    vs : float
        Stribeck velocity vs [m/s], > 0.
    delta : float
        Stribeck exponent [-], > 0 (1 on the paper's axis, 2 in Canudas de Wit et al. 1995).
    sigma0 : float
        Bristle stiffness [N/m], > 0.
    sigma1 : float
        Bristle (micro-)damping [N s/m], >= 0.
    sigma2 : float
        Viscous friction [N s/m], >= 0.
    sigma1_decay_speed : float or None
        Velocity v_d [m/s], > 0, of the velocity-dependent micro-damping
        ``sigma1(v) = sigma1 exp(-(v / v_d)^2)`` (Olsson et al. 1998; see the module
        docstring). None (default): constant sigma1, the form of the paper and of
        Canudas de Wit et al. (1995).

    Raises
    ------
    ValueError
        If a value is not finite or violates the bounds above. A negative sigma1 (printed in
        the paper's table) is refused: it makes the contact generate energy.

    Examples
    --------
    The paper's axis: the bristles reach the breakaway force after Fs/sigma0, about 1 um.

    >>> p = LuGreParameters.named("bianchi2014")
    >>> round(p.presliding_displacement * 1e6, 3)
    1.019

    Sharing the axis total among four guide-way pads:

    >>> p.scaled(0.25).fs
    1503.25

    With the micro-damping fading at v_d = vs, sliding at 3 vs keeps exp(-9) of sigma1:

    >>> q = dataclasses.replace(p, sigma1_decay_speed=0.01)
    >>> round(float(micro_damping(q, 0.03)) / q.sigma1, 6), float(micro_damping(q, 0.0))
    (0.000123, 16000000.0)
    """

    fc: float
    fs: float
    vs: float
    delta: float
    sigma0: float
    sigma1: float
    sigma2: float
    sigma1_decay_speed: float | None = None

    def __post_init__(self) -> None:
        owner = "LuGreParameters"
        checks = {
            "fc": ("fc (Coulomb friction)", "N", False, ""),
            "fs": ("fs (static friction)", "N", True, ""),
            "vs": ("vs (Stribeck velocity)", "m/s", False, ""),
            "delta": ("delta (Stribeck exponent)", "", False, ""),
            "sigma0": ("sigma0 (bristle stiffness)", "N/m", False, ""),
            "sigma1": ("sigma1 (bristle damping)", "N s/m", True,
                       "a negative sigma1 makes the contact generate energy at small amplitude "
                       "(non-passive); the paper's table prints -1.6e7, use +1.6e7"),
            "sigma2": ("sigma2 (viscous friction)", "N s/m", True, ""),
            "sigma1_decay_speed": ("sigma1_decay_speed (micro-damping decay speed v_d)", "m/s",
                                   False, "leave it out (None) for a constant sigma1"),
        }
        for name, (label, unit, allow_zero, hint) in checks.items():
            value = getattr(self, name)
            if name == "sigma1_decay_speed" and value is None:
                continue
            if isinstance(value, str):   # a number written as text (a table cell)
                value = float(value)
            object.__setattr__(self, name, positive(owner, label, value, unit, hint,
                                                    allow_zero=allow_zero))
        if self.fs < self.fc:
            raise ValueError(
                f"fs (static friction, {self.fs!r} N) must be >= fc (Coulomb friction, "
                f"{self.fc!r} N)")

    @classmethod
    def named(cls, name: str) -> LuGreParameters:
        """Return a published parameter set: ``"bianchi2014"`` or ``"canudas1995"``.

        Parameters
        ----------
        name : str
            The set's name, case-insensitive (:meth:`names`).

        Returns
        -------
        LuGreParameters
            :data:`BIANCHI2014` (axis totals, Bianchi et al. 2014, table after Fig 8) or
            :data:`CANUDAS1995` (Canudas de Wit et al. 1995, sec IV, unit mass).

        Raises
        ------
        ValueError
            For an unknown name.
        """
        key = str(name).lower()
        if key not in _NAMED:
            raise ValueError(f"unknown parameter set {name!r}; choose one of {sorted(_NAMED)}")
        return _NAMED[key]

    @staticmethod
    def names() -> tuple[str, ...]:
        """Return the names accepted by :meth:`named`.

        Returns
        -------
        tuple of str
            The names, sorted.
        """
        return tuple(sorted(_NAMED))

    def scaled(self, factor: float) -> LuGreParameters:
        """Return the same contact with every force and coefficient multiplied by ``factor``.

        Fc, Fs, sigma0, sigma1 and sigma2 scale; vs, delta and sigma1_decay_speed do not. Use it
        to share an axis-total friction (as identified in the paper, where all friction is
        lumped at the guide-way pads) among n pads with ``factor = 1/n``: n scaled elements in
        parallel moving together give back the total force for every motion.

        Parameters
        ----------
        factor : float
            The scale [-], finite and > 0.

        Returns
        -------
        LuGreParameters
            The scaled parameters.

        Raises
        ------
        ValueError
            If ``factor`` is not finite and > 0.
        """
        factor = positive("LuGreParameters.scale:", "factor", factor)
        return dataclasses.replace(
            self, fc=self.fc * factor, fs=self.fs * factor, sigma0=self.sigma0 * factor,
            sigma1=self.sigma1 * factor, sigma2=self.sigma2 * factor)

    @property
    def presliding_displacement(self) -> float:
        """Fs/sigma0 [m]: the elastic bristle deflection that carries the static force."""
        return self.fs / self.sigma0

    def to_dict(self) -> dict:
        """Return the parameters as a plain dictionary.

        Returns
        -------
        dict
            Field name -> value (SI; ``sigma1_decay_speed`` None when sigma1 is constant).
        """
        return dataclasses.asdict(self)


#: The axis-total friction identified by Bianchi et al. (2014), table after Fig 8. sigma1 is
#: printed there as -1.6e7 N s/m; it is used positive (see :class:`LuGreParameters`).
BIANCHI2014 = LuGreParameters(fc=2198.0, fs=6013.0, vs=0.01, delta=1.0, sigma0=5.9e9,
                              sigma1=1.6e7, sigma2=5578.0)

#: The spread ("var") of the stiction parameters over the paper's six identification tests, SI.
BIANCHI2014_SPREAD = types.MappingProxyType({"fs": 258.0, "sigma0": 1.17e9, "sigma1": 1.3e6})

#: The canonical example of Canudas de Wit et al. (1995), sec IV (unit mass).
CANUDAS1995 = LuGreParameters(fc=1.0, fs=1.5, vs=0.001, delta=2.0, sigma0=1e5,
                              sigma1=math.sqrt(1e5), sigma2=0.4)

_NAMED = types.MappingProxyType({"bianchi2014": BIANCHI2014, "canudas1995": CANUDAS1995})


def _stribeck_exp(params: LuGreParameters, v: np.ndarray) -> np.ndarray:
    return np.exp(-np.abs(v / params.vs) ** params.delta)


def stribeck_curve(params: LuGreParameters, v) -> np.ndarray:
    """Return the Stribeck curve g(v) = Fc + (Fs - Fc) exp(-|v/vs|^delta) [N].

    g is the magnitude of the steady sliding friction without its viscous part (Bianchi et al.
    2014, Eq 3).

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element.
    v : array_like
        Sliding velocity [m/s], finite.

    Returns
    -------
    numpy.ndarray
        g(v) [N], of the shape of ``v``.

    Raises
    ------
    ValueError
        If ``v`` is not finite.

    Examples
    --------
    >>> p = LuGreParameters.named("bianchi2014")
    >>> float(stribeck_curve(p, 0.0)), round(float(stribeck_curve(p, 1.0)), 6)
    (6013.0, 2198.0)
    """
    v = finite_array("stribeck_curve:", "v", v, "m/s")
    return params.fc + (params.fs - params.fc) * _stribeck_exp(params, v)


def _stribeck_derivative(params: LuGreParameters, v: np.ndarray) -> np.ndarray:
    """dg/dv; 0 at v = 0 by convention (one-sided values differ there for delta <= 1)."""
    av = np.abs(v)
    with np.errstate(divide="ignore", invalid="ignore"):
        dg = (-(params.fs - params.fc) * params.delta * av ** (params.delta - 1.0)
              / params.vs ** params.delta * _stribeck_exp(params, v) * np.sign(v))
    return np.where(v == 0.0, 0.0, dg)


def steady_state_friction(params: LuGreParameters, v) -> np.ndarray:
    """Return the sliding friction at constant velocity, F_ss(v) = g(v) sgn(v) + sigma2 v [N].

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element.
    v : array_like
        Sliding velocity [m/s], finite.

    Returns
    -------
    numpy.ndarray
        F_ss(v) [N], of the shape of ``v`` (0 at v = 0).

    Raises
    ------
    ValueError
        If ``v`` is not finite.

    Examples
    --------
    Fast sliding on the paper's axis: Coulomb plus viscous friction.

    >>> p = LuGreParameters.named("bianchi2014")
    >>> round(float(steady_state_friction(p, 0.5)), 1) == round(2198.0 + 5578.0 * 0.5, 1)
    True
    """
    v = finite_array("steady_state_friction:", "v", v, "m/s")
    return stribeck_curve(params, v) * np.sign(v) + params.sigma2 * v


def steady_state_slope(params: LuGreParameters, v) -> np.ndarray:
    """Return the slope of the steady-state friction, dF_ss/dv = g'(v) sgn(v) + sigma2 [N s/m].

    It is negative in the Stribeck region. At v = 0 the slope of g is taken as 0 (its
    one-sided values differ in sign there), so the slope there is sigma2.

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element.
    v : array_like
        Sliding velocity [m/s], finite.

    Returns
    -------
    numpy.ndarray
        dF_ss/dv [N s/m], of the shape of ``v``.

    Raises
    ------
    ValueError
        If ``v`` is not finite.
    """
    v = finite_array("steady_state_slope:", "v", v, "m/s")
    return _stribeck_derivative(params, v) * np.sign(v) + params.sigma2


def lugre_derivative(params: LuGreParameters, z, v) -> np.ndarray:
    """Return the bristle rate dz/dt = v - sigma0 |v| z / g(v) [m/s] (Bianchi et al. 2014, Eq 3).

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element.
    z : array_like
        Bristle deflection [m], finite.
    v : array_like
        Sliding velocity [m/s], finite; broadcast against ``z``.

    Returns
    -------
    numpy.ndarray
        dz/dt [m/s], of the broadcast shape.

    Raises
    ------
    ValueError
        If ``z`` or ``v`` is not finite.

    Examples
    --------
    At the steady deflection the bristles stop moving:

    >>> p = LuGreParameters.named("canudas1995")
    >>> z_ss = float(stribeck_curve(p, 0.01)) / p.sigma0
    >>> abs(float(lugre_derivative(p, z_ss, 0.01))) < 1e-15
    True
    """
    z = finite_array("lugre_derivative:", "z", z, "m")
    v = finite_array("lugre_derivative:", "v", v, "m/s")
    return v - params.sigma0 * np.abs(v) * z / stribeck_curve(params, v)


def micro_damping(params: LuGreParameters, v) -> np.ndarray:
    """Return the bristle damping sigma1(v) [N s/m].

    sigma1, or ``sigma1 exp(-(v/v_d)^2)`` with ``v_d = params.sigma1_decay_speed`` (Olsson et
    al. 1998; see the module docstring).

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element.
    v : array_like
        Sliding velocity [m/s], finite.

    Returns
    -------
    numpy.ndarray
        sigma1(v) [N s/m], of the shape of ``v``.

    Raises
    ------
    ValueError
        If ``v`` is not finite.

    Examples
    --------
    At v = v_d the damping has fallen to 1/e of its presliding value:

    >>> p = dataclasses.replace(BIANCHI2014, sigma1_decay_speed=0.01)
    >>> bool(abs(float(micro_damping(p, -0.01)) - p.sigma1 / math.e) < 1e-6)
    True
    """
    v = finite_array("micro_damping:", "v", v, "m/s")
    if params.sigma1_decay_speed is None:
        return np.full_like(v, params.sigma1)
    return params.sigma1 * np.exp(-((v / params.sigma1_decay_speed) ** 2))


def _micro_damping_slope(params: LuGreParameters, v: np.ndarray) -> np.ndarray:
    """d sigma1(v) / dv = -2 v / v_d^2 sigma1(v) [N s^2/m^2] (0 for a constant sigma1)."""
    if params.sigma1_decay_speed is None:
        return np.zeros_like(v)
    return -2.0 * v / params.sigma1_decay_speed**2 * micro_damping(params, v)


def lugre_force(params: LuGreParameters, z, v) -> np.ndarray:
    """Return the friction force F = sigma0 z + sigma1(v) dz/dt + sigma2 v [N] (Eq 3).

    sigma1(v) is :func:`micro_damping` (the constant sigma1 unless ``sigma1_decay_speed`` is
    set), dz/dt is :func:`lugre_derivative` (Bianchi et al. 2014, Eq 3).

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element.
    z : array_like
        Bristle deflection [m], finite.
    v : array_like
        Sliding velocity [m/s], finite; broadcast against ``z``.

    Returns
    -------
    numpy.ndarray
        F [N], of the broadcast shape.

    Raises
    ------
    ValueError
        If ``z`` or ``v`` is not finite.
    """
    z = finite_array("lugre_force:", "z", z, "m")
    v = finite_array("lugre_force:", "v", v, "m/s")
    return (params.sigma0 * z + micro_damping(params, v) * lugre_derivative(params, z, v)
            + params.sigma2 * v)


class LuGreJacobian(NamedTuple):
    """Partial derivatives of the LuGre state derivative f = dz/dt and of the force F."""

    dzdot_dz: np.ndarray
    """df/dz [1/s]"""
    dzdot_dv: np.ndarray
    """df/dv [-]"""
    dforce_dz: np.ndarray
    """dF/dz [N/m]"""
    dforce_dv: np.ndarray
    """dF/dv [N s/m]"""


def lugre_jacobian(params: LuGreParameters, z, v) -> LuGreJacobian:
    """Return the partial derivatives of dz/dt and F with respect to z and v.

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element.
    z : array_like
        Bristle deflection [m], finite.
    v : array_like
        Sliding velocity [m/s], finite; broadcast against ``z``.

    Returns
    -------
    LuGreJacobian
        ``(dzdot_dz, dzdot_dv, dforce_dz, dforce_dv)``, broadcast over z and v.

    Notes
    -----
    With a = sigma0 |v| / g(v)::

        df/dz = -a
        df/dv = 1 - sigma0 z (sgn(v) / g - |v| g' / g^2)
        dF/dz = sigma0 + sigma1(v) df/dz,   dF/dv = sigma1(v) df/dv + sigma1'(v) f + sigma2

    (sigma1' = 0 for a constant sigma1).

    At v = 0, where |v| has a kink, sgn(0) = 0 is used: df/dv = 1, the mean of the one-sided
    derivatives.

    Examples
    --------
    Sliding at v0, the DC gain of the linearised force equals the slope of F_ss:

    >>> p = LuGreParameters.named("canudas1995")
    >>> v0 = 0.002
    >>> z0 = float(stribeck_curve(p, v0)) / p.sigma0
    >>> j = lugre_jacobian(p, z0, v0)
    >>> dc = float(j.dforce_dv - j.dforce_dz * j.dzdot_dv / j.dzdot_dz)
    >>> bool(abs(dc - float(steady_state_slope(p, v0))) < 1e-9)
    True
    """
    z = finite_array("lugre_jacobian:", "z", z, "m")
    v = finite_array("lugre_jacobian:", "v", v, "m/s")
    g = stribeck_curve(params, v)
    dg = _stribeck_derivative(params, v)
    dzdot_dz = -params.sigma0 * np.abs(v) / g
    dzdot_dv = 1.0 - params.sigma0 * z * (np.sign(v) / g - np.abs(v) * dg / g**2)
    dzdot_dz, dzdot_dv = np.broadcast_arrays(dzdot_dz, dzdot_dv)
    s1 = micro_damping(params, v)
    ds1 = _micro_damping_slope(params, v)
    zdot = v - params.sigma0 * np.abs(v) * z / g
    dforce_dz, dforce_dv = np.broadcast_arrays(
        params.sigma0 + s1 * dzdot_dz, s1 * dzdot_dv + ds1 * zdot + params.sigma2)
    return LuGreJacobian(dzdot_dz=dzdot_dz, dzdot_dv=dzdot_dv, dforce_dz=dforce_dz,
                         dforce_dv=dforce_dv)


def presliding_linearisation(params: LuGreParameters) -> control.StateSpace:
    """Return the LuGre contact linearised at rest: a spring sigma0 with a damper sigma1 + sigma2.

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element.

    Returns
    -------
    control.StateSpace
        Input ``"velocity"`` (relative sliding velocity [m/s]), output ``"force"`` (friction
        force [N]), state ``"z"`` (bristle deflection [m], equal to the relative displacement
        from the rest position)::

            dz/dt = v,      F = sigma0 z + (sigma1 + sigma2) v

    Notes
    -----
    At v = 0, z = 0 the term sigma0 |v| z / g is of second order. Connected to a mass m
    (m dv/dt = f - F) it gives w_n = sqrt(sigma0 / m), zeta = (sigma1 + sigma2) /
    (2 sqrt(sigma0 m)) (Canudas de Wit et al. 1995, sec III). A velocity-dependent
    micro-damping has its full value sigma1(0) = sigma1 here (and zero slope), so the
    presliding contact does not depend on ``sigma1_decay_speed``.

    Examples
    --------
    >>> sys = presliding_linearisation(LuGreParameters.named("bianchi2014"))
    >>> sys.input_labels, sys.output_labels
    (['velocity'], ['force'])
    >>> complex(sys(1j * 100.0))   # F/v at 100 rad/s: damper sigma1 + sigma2, spring sigma0/(j w)
    (16005578-59000000j)
    """
    return control.ss([[0.0]], [[1.0]], [[params.sigma0]], [[params.sigma1 + params.sigma2]],
                      inputs=["velocity"], outputs=["force"], states=["z"],
                      name="lugre_presliding")


def sliding_linearisation(params: LuGreParameters, v0: float) -> control.StateSpace:
    """Return the LuGre contact linearised while sliding at constant velocity v0 != 0.

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element.
    v0 : float
        Sliding velocity [m/s], finite and non-zero.

    Returns
    -------
    control.StateSpace
        Input ``"velocity"`` (velocity deviation from v0 [m/s]), output ``"force"`` (force
        deviation from F_ss(v0) [N]), state ``"z"`` (bristle deflection deviation [m])::

            dz/dt = -a z + b v,     F = (sigma0 - s1 a) z + (s1 b + sigma2) v
            a = sigma0 |v0| / g(v0),   b = v0 g'(v0) / g(v0),   s1 = sigma1(v0)

        a first-order lag with time constant 1/a whose DC gain is
        ``sigma0 b / a + sigma2 = dF_ss/dv`` at v0 (negative in the Stribeck region). Its
        high-frequency damping, the feed-through ``s1 b + sigma2``, is negative in the
        Stribeck region for a large constant sigma1 (b < 0 there); a micro-damping that fades
        with speed (``sigma1_decay_speed``, s1 = sigma1(v0)) removes that. The slope of
        sigma1(v) does not enter: it multiplies dz/dt, which is 0 in steady sliding.

    Raises
    ------
    ValueError
        If v0 is 0 (use :func:`presliding_linearisation`) or not finite.

    Examples
    --------
    Below the Stribeck speed friction falls with speed: negative damping at DC.

    >>> p = LuGreParameters.named("bianchi2014")
    >>> float(sliding_linearisation(p, 0.005).dcgain()) < 0.0
    True

    At 30 mm/s the constant sigma1 gives a negative high-frequency damping; fading it out
    above v_d = vs leaves about sigma2:

    >>> round(float(sliding_linearisation(p, 0.03).D[0, 0]) / 1e6, 2)
    -3.81
    >>> q = dataclasses.replace(p, sigma1_decay_speed=0.01)
    >>> round(float(sliding_linearisation(q, 0.03).D[0, 0]))
    5107
    """
    v0 = finite("sliding_linearisation:", "v0", v0, "m/s")
    if v0 == 0.0:
        raise ValueError("v0 must be non-zero for the sliding linearisation; at rest use "
                         "presliding_linearisation()")
    g = float(stribeck_curve(params, v0))
    a = params.sigma0 * abs(v0) / g
    b = v0 * float(_stribeck_derivative(params, np.array(v0))) / g
    s1 = float(micro_damping(params, v0))
    return control.ss([[-a]], [[b]], [[params.sigma0 - s1 * a]], [[s1 * b + params.sigma2]],
                      inputs=["velocity"], outputs=["force"], states=["z"],
                      name="lugre_sliding")


@dataclass(frozen=True)
class LuGreResponse:
    """A LuGre contact driven by an imposed motion (SI arrays on the time grid ``t``)."""

    t: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    z: np.ndarray
    zdot: np.ndarray
    force: np.ndarray

    @property
    def dissipated_energy(self) -> float:
        """int F v dt over the record [J] (composite trapezoid on the grid)."""
        return float(np.trapezoid(self.force * self.velocity, self.t))

    def plot(self):
        """Return the plot of force against displacement (a hysteresis plot).

        Returns
        -------
        matplotlib.figure.Figure
            The figure of :func:`servotune.plots.plot_response_hysteresis`.
        """
        from .. import plots

        return plots.plot_response_hysteresis(self)


def _steady_deflection(params: LuGreParameters, v: np.ndarray) -> np.ndarray:
    return np.sign(v) * stribeck_curve(params, v) / params.sigma0


def _rate(params: LuGreParameters, v: np.ndarray) -> np.ndarray:
    return params.sigma0 * np.abs(v) / stribeck_curve(params, v)


def _history(t: np.ndarray, displacement, velocity):
    """Displacement and velocity functions of time from samples or callables."""
    if (displacement is None) == (velocity is None):
        raise ValueError("give exactly one of displacement= or velocity=")
    given = displacement if displacement is not None else velocity
    name = "displacement" if displacement is not None else "velocity"
    if callable(given):
        if displacement is not None:
            raise ValueError("displacement must be samples on t; a callable is accepted for "
                             "velocity only")
        vfun = given
        samples = finite_array("simulate_lugre:", "velocity(t)", vfun(t), "m/s")
        spline = interpolate.CubicSpline(t, samples)
        xfun = spline.antiderivative()
        return xfun, vfun, spline
    samples = finite_array("simulate_lugre:", name, given,
                           "m" if displacement is not None else "m/s")
    if samples.shape != t.shape:
        raise ValueError(f"{name} must have the shape of t {t.shape}, got {samples.shape}")
    spline = interpolate.CubicSpline(t, samples)
    if displacement is not None:
        vspline = spline.derivative()
        return spline, vspline, vspline
    return spline.antiderivative(), spline, spline


def simulate_lugre(params: LuGreParameters, t, *, displacement=None, velocity=None,
                   z0: float = 0.0) -> LuGreResponse:
    """Integrate the LuGre contact under an imposed displacement or velocity history.

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element.
    t : array_like
        Strictly increasing sample times [s].
    displacement : array_like, optional
        Relative displacement samples on ``t`` [m]; interpolated by a cubic spline, whose
        derivative is the velocity.
    velocity : array_like or callable, optional
        Relative velocity [m/s], samples on ``t`` (interpolated by a cubic spline) or a
        vectorised function of time. Give exactly one of ``displacement`` and ``velocity``.
    z0 : float
        Bristle deflection at ``t[0]`` [m].

    Returns
    -------
    LuGreResponse
        Displacement (from 0 at t[0] when a velocity is given), velocity, z, dz/dt and F on t.

    Raises
    ------
    ValueError
        If ``t`` is not 1-D, strictly increasing with at least 2 times, a value is not finite,
        not exactly one of ``displacement`` and ``velocity`` is given, ``displacement`` is a
        callable, or samples do not have the shape of ``t``.

    Notes
    -----
    Exponential integrator in the bristle time (module docstring): every velocity reversal
    between samples (a root of the interpolated velocity) is inserted into the grid, so that the
    kink of |v| falls on a step boundary. The error falls with the fourth power of the sampling
    step in the tests and does not depend on the stiffness sigma0 |v| / g.

    Examples
    --------
    Sliding at constant speed, the force settles at the steady-state friction:

    >>> p = LuGreParameters.named("canudas1995")
    >>> t = np.linspace(0.0, 0.2, 501)   # 27 bristle time constants g / (sigma0 v)
    >>> r = simulate_lugre(p, t, velocity=np.full_like(t, 0.002))
    >>> bool(abs(r.force[-1] - float(steady_state_friction(p, 0.002))) < 1e-9)
    True
    """
    t = finite_array("simulate_lugre:", "t", t, "s")
    if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0.0):
        raise ValueError("t must be a 1-D strictly increasing array of at least 2 times [s]")
    z0 = finite("simulate_lugre:", "z0", z0, "m")
    xfun, vfun, vspline = _history(t, displacement, velocity)
    # put every velocity reversal on a step boundary
    roots = np.asarray(vspline.roots(extrapolate=False), dtype=float)
    roots = roots[np.isfinite(roots) & (roots > t[0]) & (roots < t[-1])]
    grid = np.union1d(t, roots)
    keep = np.searchsorted(grid, t)

    def rate(tt):
        return _rate(params, np.asarray(vfun(tt), dtype=float))

    t0, t1 = grid[:-1], grid[1:]
    h1, h2 = _exponential.half_step_increments(rate, t0, t1)
    v_nodes = np.asarray(vfun(grid), dtype=float)
    v_mid = np.asarray(vfun(0.5 * (t0 + t1)), dtype=float)
    v_nodes[np.isin(grid, roots)] = 0.0  # reversals found between samples
    zss = _steady_deflection(params, v_nodes)
    zss_mid = _steady_deflection(params, v_mid)
    # at a reversal z_ss is set-valued (+-Fs/sigma0): take the side the step moves to
    side = np.sign(v_mid) * params.fs / params.sigma0
    zss0 = np.where(v_nodes[:-1] == 0.0, side, zss[:-1])
    zss1 = np.where(v_nodes[1:] == 0.0, side, zss[1:])
    alpha, beta = _exponential.step_coefficients(h1, h2, zss0, zss_mid, zss1)
    p, b = _exponential.affine_scan(alpha, beta)
    z = np.concatenate([[z0], p * z0 + b])[keep]
    v = v_nodes[keep]
    x = np.asarray(xfun(t), dtype=float)
    if displacement is None:
        x = x - x[0]
    zdot = lugre_derivative(params, z, v)
    force = params.sigma0 * z + micro_damping(params, v) * zdot + params.sigma2 * v
    return LuGreResponse(t=t, displacement=x, velocity=v, z=z, zdot=zdot, force=force)


@dataclass(frozen=True)
class HysteresisCycle:
    """The periodic steady state of a LuGre contact under x = A sin(w t).

    Arrays have shape ``batch + (n_steps + 1,)`` over one period starting at the reversal
    x = -A (phase ``theta = w t`` from -pi/2 to 3 pi/2); scalars have the batch shape.

    Attributes
    ----------
    amplitude, omega : numpy.ndarray
        A [m] and w [rad/s].
    theta : numpy.ndarray
        Phase w t [rad], shape (n_steps + 1,).
    displacement, velocity, z, force : numpy.ndarray
        x [m], v [m/s], bristle deflection z [m], friction force F [N].
    energy : numpy.ndarray
        Energy dissipated per cycle, the loop area int F dx [J].
    ceq, keq : numpy.ndarray
        First-harmonic equivalent damping [N s/m] and stiffness [N/m]:
        F ~ keq x + ceq v, ceq = energy / (pi w A^2).
    """

    amplitude: np.ndarray
    omega: np.ndarray
    theta: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    z: np.ndarray
    force: np.ndarray
    energy: np.ndarray
    ceq: np.ndarray
    keq: np.ndarray

    def plot(self):
        """Return the plot of the hysteresis loops F(x) (the paper's Fig 2 / Fig 6 style).

        Returns
        -------
        matplotlib.figure.Figure
            The figure of :func:`servotune.plots.plot_hysteresis`.
        """
        from .. import plots

        return plots.plot_hysteresis(self)


def _simpson_periodic(y: np.ndarray, dtheta: float) -> np.ndarray:
    """Composite Simpson rule over one period given n + 1 nodes (n divisible by 4).

    Applied per half-period so that the kinks at the reversals (nodes 0, n/2, n) lie on panel
    boundaries.
    """
    w = np.ones(y.shape[-1])
    w[1:-1:2] = 4.0
    w[2:-1:2] = 2.0
    n = y.shape[-1] - 1
    w[n // 2] = 2.0
    return (dtheta / 3.0) * (y @ w)


def lugre_cycle(params: LuGreParameters, amplitude, omega,
                n_steps: int = DEFAULT_CYCLE_STEPS) -> HysteresisCycle:
    """Periodic steady state of the LuGre contact under x = A sin(w t), vectorised.

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element.
    amplitude : array_like
        Displacement amplitudes A [m], > 0.
    omega : array_like
        Angular frequencies w [rad/s], > 0; broadcast against ``amplitude``.
    n_steps : int
        Steps per period (a multiple of 4, >= 8). The default 1024 gives the energy per cycle
        to about 1e-7 relative on the paper's parameters (see the tests); 128 already gives
        1e-4.

    Returns
    -------
    HysteresisCycle
        The cycle over one period, batch shape the broadcast shape of ``amplitude`` and
        ``omega``.

    Raises
    ------
    ValueError
        If an amplitude or frequency is not finite and > 0, or ``n_steps`` is not a multiple
        of 4 >= 8.

    Notes
    -----
    The steps are uniform in phase, with the reversals at x = -A and x = +A on nodes. The cycle
    is closed exactly: with ``z -> P z + B`` the map of one period, the periodic state at the
    start is ``B / (1 - P)``, so no transient is simulated. Energy and first harmonics use the
    composite Simpson rule on each half period::

        energy = A int F cos(theta) dtheta,   keq = (1 / (pi A)) int F sin(theta) dtheta

    Examples
    --------
    Tiny motions stay in presliding, where the contact is a spring sigma0 and a damper
    sigma1 + sigma2:

    >>> p = LuGreParameters.named("bianchi2014")
    >>> c = lugre_cycle(p, 1e-10, 2 * np.pi * 20.0)
    >>> round(float(c.keq) / p.sigma0, 3), round(float(c.ceq) / (p.sigma1 + p.sigma2), 3)
    (1.0, 1.0)
    """
    amplitude = positive_array("lugre_cycle:", "amplitude", amplitude, "m")
    omega = positive_array("lugre_cycle:", "omega", omega, "rad/s")
    n_steps = int(n_steps)
    if n_steps < 8 or n_steps % 4:
        raise ValueError(f"n_steps must be a multiple of 4 and >= 8, got {n_steps}")
    amplitude, omega = np.broadcast_arrays(amplitude, omega)
    shape = amplitude.shape
    a_col = amplitude.reshape(-1, 1)
    w_col = omega.reshape(-1, 1)
    dtheta = 2.0 * math.pi / n_steps
    theta = -0.5 * math.pi + dtheta * np.arange(n_steps + 1)
    theta[n_steps // 2] = 0.5 * math.pi  # exact reversals
    theta[-1] = 1.5 * math.pi

    def velocity(th):  # th of shape (..., rows, steps) or (steps,)
        return a_col * w_col * np.cos(th)

    def rate(th):  # bristle time per radian of phase
        return _rate(params, velocity(th)) / w_col

    th0 = np.broadcast_to(theta[:-1], (a_col.shape[0], n_steps))
    th1 = np.broadcast_to(theta[1:], (a_col.shape[0], n_steps))
    h1, h2 = _exponential.half_step_increments(rate, th0, th1)
    v_nodes = velocity(theta)
    v_nodes[:, [0, n_steps // 2, n_steps]] = 0.0
    v_mid = velocity(0.5 * (th0 + th1))
    zss_mid = _steady_deflection(params, v_mid)
    side = np.sign(v_mid) * params.fs / params.sigma0
    zss = _steady_deflection(params, v_nodes)
    zss0 = np.where(v_nodes[:, :-1] == 0.0, side, zss[:, :-1])
    zss1 = np.where(v_nodes[:, 1:] == 0.0, side, zss[:, 1:])
    alpha, beta = _exponential.step_coefficients(h1, h2, zss0, zss_mid, zss1)
    p, b = _exponential.affine_scan(alpha, beta)
    total = h1.sum(axis=-1) + h2.sum(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        z_start = b[:, -1] / -np.expm1(-total)
    z = np.concatenate([z_start[:, None], p * z_start[:, None] + b], axis=-1)
    zdot = v_nodes - _rate(params, v_nodes) * z
    force = params.sigma0 * z + micro_damping(params, v_nodes) * zdot + params.sigma2 * v_nodes
    x = a_col * np.sin(theta)
    energy = a_col[:, 0] * _simpson_periodic(force * np.cos(theta), dtheta)
    keq = _simpson_periodic(force * np.sin(theta), dtheta) / (math.pi * a_col[:, 0])
    ceq = energy / (math.pi * w_col[:, 0] * a_col[:, 0] ** 2)
    full = (*shape, n_steps + 1)
    return HysteresisCycle(
        amplitude=amplitude.copy(), omega=omega.copy(), theta=theta,
        displacement=x.reshape(full), velocity=v_nodes.reshape(full), z=z.reshape(full),
        force=force.reshape(full), energy=energy.reshape(shape), ceq=ceq.reshape(shape),
        keq=keq.reshape(shape))
