"""The nonlinear axis as a plain ODE for scipy's ``solve_ivp`` (reference and baseline).

:func:`ode_model` writes the same model as :func:`servotune.simulate.simulate` integrates, in
the original states X and without any splitting::

    dX/dt = A0 X + B_u u(t) + B_w w(X),      w_p = a(v_p) z_p = sigma0 |v_p| z_p / g(v_p)

where A0 is the linear part about rest (presliding contacts) and w the full LuGre relaxation
rate per pad, with the analytic Jacobian ``A0 + B_w dw/dX``. With a velocity-dependent
micro-damping w carries, per pad, also ``q_p = v_p - e(v_p) dz_p/dt`` (the damper sigma1 of
the presliding contact minus sigma1(v) dz/dt, over sigma1), written here from
:mod:`servotune.friction.lugre` (not from the compiled law). The energy powers are appended as
extra states, so that a stiff solver at tight tolerance gives the reference energies. It is the
baseline of ``benchmarks/simulate_sweep.py`` and the independent check of the tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..friction.lugre import lugre_derivative, lugre_jacobian, stribeck_curve
from .scenario import Scenario
from .simulator import NonlinearAxis
from .system import axis_system

__all__ = ["OdeModel", "ode_model"]


@dataclass(frozen=True, eq=False)
class OdeModel:
    """Right-hand side, Jacobian and readouts of the axis as one ODE (see module docstring).

    The state is ``[X, W]`` with W the four cumulative works (force, motor, friction,
    damping) [J].

    Parameters
    ----------
    n : int
        Length of the state ``[X, W]``.
    rhs : callable
        ``rhs(t, y) -> dy/dt``, t [s].
    jac : callable
        ``jac(t, y) -> (n, n)`` Jacobian of ``rhs`` in X (the rows and columns of W are zero:
        the works do not feed back).
    outputs : callable
        ``outputs(t, y) -> array`` of the plant outputs.
    output_names : tuple of str
        Names of the outputs.
    structure_energy : callable
        ``structure_energy(y) -> T + V`` [J] of the structure.
    bristle_energy : callable
        ``bristle_energy(y) -> sum sigma0 z^2 / 2`` [J] of the bristles (0 without a nonlinear
        law).
    """

    n: int
    rhs: object
    jac: object
    outputs: object
    output_names: tuple
    structure_energy: object
    bristle_energy: object


def ode_model(axis: NonlinearAxis, scenario: Scenario) -> OdeModel:
    """Return the axis and scenario as ``f(t, y)``, ``J(t, y)`` for ``scipy.integrate.solve_ivp``.

    Parameters
    ----------
    axis : NonlinearAxis
        Structure, drive, pads and friction law.
    scenario : Scenario
        References and forces; its inputs are those nonzero somewhere on 2001 points over
        ``[0, duration]``.

    Returns
    -------
    OdeModel
        The right-hand side, its Jacobian, the readouts and the energies; the initial state
        is zero (rest).
    """
    sig_names = list(scenario.signals(np.linspace(0.0, scenario.duration, 2001)))
    friction = axis.friction
    nonlinear = friction is not None and friction.nonlinear
    sysm = axis_system(axis.structure, axis.drive, friction, axis.pads, 0.0,
                       inputs=sig_names + (["one"] if nonlinear else []))
    a0 = sysm.system.A
    nu = len(sysm.inputs)
    bu = sysm.system.B[:, :nu]
    bw = sysm.system.B[:, nu:]
    c, d = sysm.system.C, sysm.system.D
    n = a0.shape[0]
    pv, pz = sysm.pad_velocity, sysm.pad_state
    n_pads = len(sysm.pads)
    n_force = len(sysm.wp_force_inputs)
    force_idx = list(sysm.wp_force_inputs)
    p = friction.params if nonlinear else None

    def inputs(t):
        s = scenario.signals(np.atleast_1d(float(t)))
        # a signal the scenario leaves out is zero at that instant; "one" is the constant 1
        return np.array([s[k][0] if k in s else (1.0 if k == "one" else 0.0)
                         for k in sysm.inputs])

    def w_of(x):
        if not nonlinear:
            return np.zeros(0), np.zeros(0), np.zeros(0)
        v = pv @ x
        z = pz @ x
        g = stribeck_curve(p, v)
        w = p.sigma0 * np.abs(v) * z / g
        # derivatives
        av = np.abs(v)
        e = np.exp(-np.abs(v / p.vs) ** p.delta)
        with np.errstate(divide="ignore", invalid="ignore"):
            dg = np.where(av > 0, -(p.fs - p.fc) * p.delta * (av / p.vs) ** (p.delta - 1) / p.vs
                          * e * np.sign(v), 0.0)
        dw_dv = p.sigma0 * z * (np.sign(v) / g - av * dg / g**2)
        dw_dz = p.sigma0 * av / g
        if friction.n_remainders == 1:
            return w, dw_dv, dw_dz
        # micro-damping e(v) = exp(-(v/v_d)^2): q = v - e(v) dz/dt
        vd = p.sigma1_decay_speed
        ev = np.exp(-((v / vd) ** 2))
        dev = -2.0 * v / vd**2 * ev
        zdot = lugre_derivative(p, z, v)
        j = lugre_jacobian(p, z, v)
        q = v - ev * zdot
        dq_dv = 1.0 - dev * zdot - ev * j.dzdot_dv
        dq_dz = -ev * j.dzdot_dz
        return (np.concatenate([w, q]), np.concatenate([dw_dv, dq_dv]),
                np.concatenate([dw_dz, dq_dz]))

    def outputs_of(x, u, w):
        return c @ x + d @ np.concatenate([u, w])

    def powers(x, u, w):
        pw = np.zeros(4)
        if n_force:
            pw[0] = float(u[force_idx] @ (sysm.wp_velocity @ x))
        pw[1] = float((sysm.motor_rows[0] @ x) * (sysm.motor_rows[1] @ x))
        force = sysm.force_rows @ x + sysm.force_du @ u + (sysm.force_dr @ w if w.size else 0.0)
        pw[2] = -float(force @ (pv @ x)) if n_pads else 0.0
        pw[3] = -float(np.sum((sysm.damping_rows @ x) ** 2))
        return pw

    def rhs(t, y):
        x = y[:n]
        u = inputs(t)
        w, _, _ = w_of(x)
        dx = a0 @ x + bu @ u + (bw @ w if w.size else 0.0)
        return np.concatenate([dx, powers(x, u, w)])

    def jac(t, y):
        x = y[:n]
        j = np.zeros((n + 4, n + 4))
        j[:n, :n] = a0
        if nonlinear:
            _, dv, dz = w_of(x)
            k = friction.n_remainders
            j[:n, :n] += bw @ (dv[:, None] * np.tile(pv, (k, 1))
                               + dz[:, None] * np.tile(pz, (k, 1)))
        # the work states do not feed back; their rows are left out of the Newton matrix
        return j

    def outputs(t, y):
        x = y[:n]
        return outputs_of(x, inputs(t), w_of(x)[0])

    def structure_energy(y):
        return 0.5 * float(np.sum((sysm.energy_rows @ y[:n]) ** 2))

    def bristle_energy(y):
        if not nonlinear:
            return 0.0
        return 0.5 * p.sigma0 / n_pads * float(np.sum((pz @ y[:n]) ** 2))

    return OdeModel(n=n + 4, rhs=rhs, jac=jac, outputs=outputs,
                    output_names=tuple(sysm.outputs), structure_energy=structure_energy,
                    bristle_energy=bristle_energy)
