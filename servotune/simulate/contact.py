"""Guide-way friction laws for the time simulation: linear part plus a nonlinear remainder.

The simulator (:mod:`servotune.simulate.integrator`) integrates the linear part of the axis
exactly and treats what is nonlinear implicitly, through one scalar input per pad. A friction law
therefore comes in two parts:

* a **linear block** per pad (python-control), with inputs the pad velocity ``v_<pad>``, the
  nonlinear remainder ``r_<pad>`` and a constant ``one``, and outputs the force on the pad DOF
  ``f_<pad>``, the friction force ``F_<pad>`` and the internal state ``z_<pad>``;
* a **remainder** ``r(v, z)`` [m/s], a compiled (numba) scalar function with its two partial
  derivatives, evaluated per pad by the integrator (absent for linear laws).

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

References
----------
C. Canudas de Wit, H. Olsson, K. J. Astrom, P. Lischinsky, "A new model for control of systems
with friction", IEEE Trans. Automatic Control 40(3) (1995) 419-425.
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
Eq 3 and sec 5.3.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numba
import numpy as np

from ..friction.lugre import LuGreParameters, lugre_jacobian, stribeck_curve
from ..structure.model import signal_name

__all__ = ["PadFriction", "LuGreFriction", "ViscousFriction", "lugre_remainder",
           "evaluate_remainder", "LAW_IDS"]


class PadFriction:
    """Interface of a guide-way friction law for :func:`servotune.simulate.simulate`.

    Subclasses give :attr:`name`, :meth:`pad_block` and, when nonlinear, :meth:`remainder`
    (a numba-compiled ``f(v, z, params) -> (r, dr_dv, dr_dz)``) registered in
    :data:`LAW_IDS` / :func:`evaluate_remainder` under :attr:`law_id`, with
    :meth:`remainder_parameters` and :meth:`tolerances`. Values are axis totals shared equally
    by the pads.
    """

    name = "friction"
    nonlinear = False
    law_id = -1

    def pad_block(self, pad: str, n_pads: int, speed: float = 0.0) -> control.StateSpace:
        """The linear part for one pad (see the module docstring for its signals)."""
        raise NotImplementedError

    def remainder(self):
        """The compiled remainder function (nonlinear laws only)."""
        raise NotImplementedError

    def remainder_parameters(self, speed: float = 0.0) -> np.ndarray:
        """Parameters of :meth:`remainder` for the linearisation about ``speed`` [m/s]."""
        raise NotImplementedError

    def friction_force(self, v, z):
        """Friction force [N] of the axis total for pad velocity v and state z (per pad
        values times the number of pads); used to check a result."""
        raise NotImplementedError


def _signals(pad: str):
    return (signal_name(pad, "v_"), signal_name(pad, "r_"), signal_name(pad, "f_"),
            signal_name(pad, "F_"), signal_name(pad, "z_"))


@dataclass(frozen=True)
class ViscousFriction(PadFriction):
    """Viscous guide-way damping: F = c v (c [N s/m] axis total), the paper's "vd" model.

    Examples
    --------
    >>> float(ViscousFriction(5578.0).pad_block("pad1.x", 4).D[0, 0])   # pad force per velocity
    -1394.5
    """

    c: float
    name = "viscous"

    def __post_init__(self) -> None:
        c = float(self.c)
        if not (math.isfinite(c) and c >= 0.0):
            raise ValueError(f"ViscousFriction.c must be finite and >= 0 N s/m, got {self.c!r}")
        object.__setattr__(self, "c", c)

    def pad_block(self, pad: str, n_pads: int, speed: float = 0.0) -> control.StateSpace:
        v, _, f, force, _ = _signals(pad)
        share = self.c / n_pads
        return control.ss([], [], [], [[-share], [share]], inputs=[v], outputs=[f, force],
                          name=f"friction_{signal_name(pad)}")

    def friction_force(self, v, z=None):
        return self.c * np.asarray(v, dtype=float)


@numba.njit(cache=True)
def lugre_remainder(v, z, p):
    """LuGre remainder r = a(v) z - (c0 + c_v v + c_z z) and its partial derivatives.

    ``p = (sigma0, fc, fs, vs, delta, c0, c_v, c_z)`` (sigma0, fc, fs of any share: only their
    ratios enter). At v = 0 the derivative of |v| is taken as 0.
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


#: Compiled remainders known to the integrator, by :attr:`PadFriction.law_id`. A new nonlinear
#: law adds its numba function here and a branch in :func:`evaluate_remainder` (a direct call
#: is several times faster than calling a function passed as an argument).
LAW_IDS = {"lugre": 0}


@numba.njit(cache=True)
def evaluate_remainder(law, v, z, p):
    """The remainder of law number ``law`` (see :data:`LAW_IDS`) and its partial derivatives."""
    if law == 0:
        return lugre_remainder(v, z, p)
    return math.nan, math.nan, math.nan


@dataclass(frozen=True)
class LuGreFriction(PadFriction):
    """LuGre guide-way friction (axis-total parameters, shared equally by the pads).

    Parameters
    ----------
    params : LuGreParameters
        Axis total, e.g. ``LuGreParameters.named("bianchi2014")``.

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

    def __post_init__(self) -> None:
        if not isinstance(self.params, LuGreParameters):
            raise ValueError("LuGreFriction needs LuGreParameters, e.g. "
                             "LuGreParameters.named('bianchi2014')")

    def linearisation(self, speed: float = 0.0) -> tuple[float, float, float]:
        """(c0, c_v, c_z) of ``w ~ c0 + c_v v + c_z z`` about rest (0, 0, 0) or steady sliding
        at ``speed`` [m/s] (tangent at v0, z_ss = sgn(v0) g(v0)/sigma0)."""
        speed = float(speed)
        if not math.isfinite(speed):
            raise ValueError(f"the operating speed must be finite, got {speed!r}")
        if speed == 0.0:
            return 0.0, 0.0, 0.0
        p = self.params
        z0 = math.copysign(float(stribeck_curve(p, speed)), speed) / p.sigma0
        jac = lugre_jacobian(p, z0, speed)
        # dz/dt = v - w  =>  dw/dv = 1 - d(zdot)/dv, dw/dz = -d(zdot)/dz
        cv = 1.0 - float(jac.dzdot_dv)
        cz = -float(jac.dzdot_dz)
        w0 = speed  # steady sliding: dz/dt = 0
        return w0 - cv * speed - cz * z0, cv, cz

    def pad_block(self, pad: str, n_pads: int, speed: float = 0.0) -> control.StateSpace:
        v, r, f, force, z = _signals(pad)
        p = self.params.scaled(1.0 / n_pads)
        c0, cv, cz = self.linearisation(speed)
        # dz/dt = v - (c0 + cv v + cz z + r);  F = s0 z + s1 dz/dt + s2 v;  f = -F
        a = [[-cz]]
        b = [[1.0 - cv, -1.0, -c0]]
        c_force = [p.sigma0 - p.sigma1 * cz]
        d_force = [p.sigma1 * (1.0 - cv) + p.sigma2, -p.sigma1, -p.sigma1 * c0]
        return control.ss(a, b, [[-c_force[0]], c_force, [1.0]],
                          [[-d for d in d_force], d_force, [0.0, 0.0, 0.0]],
                          inputs=[v, r, "one"], outputs=[f, force, z], states=[z],
                          name=f"friction_{signal_name(pad)}")

    law_id = LAW_IDS["lugre"]

    def remainder(self):
        return lugre_remainder

    def remainder_parameters(self, speed: float = 0.0) -> np.ndarray:
        p = self.params
        return np.array([p.sigma0, p.fc, p.fs, p.vs, p.delta, *self.linearisation(speed)])

    def friction_force(self, v, z):
        """F [N], axis total, for velocity v [m/s] and bristle deflection z [m]."""
        p = self.params
        v = np.asarray(v, dtype=float)
        z = np.asarray(z, dtype=float)
        zdot = v - p.sigma0 * np.abs(v) * z / stribeck_curve(p, v)
        return p.sigma0 * z + p.sigma1 * zdot + p.sigma2 * v
