"""The sampled-data cascade at one frequency: loops and the fundamental of the response.

The algebra of the multi-rate loop, written once for any arithmetic that has ``+ - * /`` (numpy
complex arrays, or the (real, imaginary) pairs of casadi expressions the tuning uses), so the
checks and the optimiser evaluate the same model.

Signals and their rates (T the current period, T_v = N_v T, T_p = N_p T_v)::

    continuous:  F (the exciting force), y (a continuous output), the held voltage u(t)
    rate 1/T:    U (voltage), i, phi, x (sampled current, rotor angle, position), T_f (held
                 torque set-point)
    rate 1/T_v:  T_v (torque set-point), phi_v (sampled angle), omega_v (held speed command)
    rate 1/T_p:  omega_p (speed command), x_p (sampled position)

For a sinusoidal force F e^(j w t) the steady state of every signal of rate 1/T' is a sum of
components at w + l 2 pi / T'; the *fundamental* is the one at w. The plant under the
zero-order hold of the voltage is exact at the samples: ``i = G_i(w) U + i_F(w) F`` (and so
for phi, x), G the zero-order-hold equivalent of the continuous plant, evaluated at
``exp(j w T)``; its continuous outputs carry the held voltage's fundamental
``h0(w) U``, ``h0 = (1 - exp(-j w T)) / (j w T)``.

A faster loop seen from a slower controller is *lifted*: an input of rate 1/(N T') held for N
periods and the output sampled every N periods give, in the slower rate,

    G_lift(w) = (1/N) sum_{l=0}^{N-1} B_N(w_l) G(w_l),   w_l = w + l 2 pi / (N T'),
    B_N(v) = sum_{n=0}^{N-1} exp(-j v n T')

is exact (every component the hold creates, folded back by the sampler); the fundamental of
the held input in the faster rate is ``B_N(w) / N`` times the slower one. The levels then
close as::

    current:   R_c = 1 / (1 - K_ci G_i)                   (K_ci: voltage per sampled current)
               phi_T = G_phi K_ct R_c,  x_T = G_x K_ct R_c (per held set-point; K_ct)
    velocity:  L_v = -K_vphi lift_Nv(phi_T),  R_v = 1 / (1 + L_v)
               x_omega = lift_Nv(x_T) K_vomega R_v          (per held speed command)
    position:  L_p = -K_px lift_Np(x_omega),  R_p = 1 / (1 + L_p)

with K the controllers' transfer functions at their own rates (e.g. ``K_vphi = -D_v C_v M``,
D the computation delay, C the PI, M the speed measurement), and the fundamental response to
F follows back down the levels (:func:`fundamental`).

What the fundamental leaves out: the components at w + l 2 pi / T' that the holds create in
the continuous outputs (aliases). Their size is what
:meth:`servotune.digital.sampled.SampledAxis.alias_fraction` reports; on the bundled axis they
stay below 1e-6 of the fundamental over the requirements band (``docs/digital_drive.md``).

References
----------
T. Chen, B. Francis, Optimal Sampled-Data Control Systems, Springer (1995), ch 8 (lifting) and
sec 10.5 (frequency response of sampled-data systems). K. J. Astrom, B. Wittenmark,
Computer-Controlled Systems, 3rd ed. (1997), sec 7.3 (aliasing and the hold's spectrum).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["CurrentLevel", "VelocityLevel", "PositionLevel", "current_level",
           "velocity_level", "position_level", "fundamental"]


@dataclass(frozen=True)
class CurrentLevel:
    """The closed current loop at one (fast-rate) frequency.

    ``r_c = 1 / (1 - K_ci G_i)``; ``phi_t``, ``x_t``: sampled angle and position per held
    torque set-point; ``k_ct``: voltage per held set-point before closing; ``g_phi``,
    ``g_x``: the plant's sampled angle and position per held voltage."""

    r_c: object
    phi_t: object
    x_t: object
    k_ct: object
    g_phi: object
    g_x: object


def current_level(g_i, g_phi, g_x, k_ci, k_ct) -> CurrentLevel:
    """Close the current loop: the plant's sampled responses to the held voltage and the
    current controller's transfer functions.

    Parameters
    ----------
    g_i, g_phi, g_x : complex-like
        Zero-order-hold responses from the voltage to the sampled current, angle, position.
    k_ci, k_ct : complex-like
        Voltage per sampled current and per held torque set-point.

    Returns
    -------
    CurrentLevel
    """
    r_c = 1.0 / (1.0 - k_ci * g_i)
    return CurrentLevel(r_c, g_phi * k_ct * r_c, g_x * k_ct * r_c, k_ct, g_phi, g_x)


@dataclass(frozen=True)
class VelocityLevel:
    """The velocity loop at one (velocity-rate) frequency: its loop ``l_v``, the return
    ``r_v = 1/(1 + l_v)`` and ``x_omega``, the sampled position per held speed command."""

    l_v: object
    r_v: object
    x_omega: object
    g_vphi: object
    g_vx: object


def velocity_level(g_vphi, g_vx, k_vphi, k_vomega) -> VelocityLevel:
    """Close the velocity loop around the lifted current level.

    Parameters
    ----------
    g_vphi, g_vx : complex-like
        Sampled angle and position per held torque set-point, lifted to the velocity rate.
    k_vphi, k_vomega : complex-like
        Torque set-point per sampled angle and per held speed command.

    Returns
    -------
    VelocityLevel
    """
    l_v = -k_vphi * g_vphi
    r_v = 1.0 / (1.0 + l_v)
    return VelocityLevel(l_v, r_v, g_vx * k_vomega * r_v, g_vphi, g_vx)


@dataclass(frozen=True)
class PositionLevel:
    """The position loop at one (position-rate) frequency."""

    l_p: object
    r_p: object
    g_px: object


def position_level(g_px, k_px) -> PositionLevel:
    """Close the position loop around the lifted velocity level.

    Parameters
    ----------
    g_px : complex-like
        Sampled position per held speed command, lifted to the position rate.
    k_px : complex-like
        Speed command per sampled position.

    Returns
    -------
    PositionLevel
    """
    l_p = -k_px * g_px
    return PositionLevel(l_p, 1.0 / (1.0 + l_p), g_px)


def fundamental(cur: CurrentLevel, vel: VelocityLevel, pos: PositionLevel | None, *,
                k_ci, k_vphi, k_vomega, k_px, i_f, phi_f, x_f, y_f, y_u, h0, hold_v, hold_p):
    """Return the fundamental of a continuous output per unit exciting force.

    Parameters
    ----------
    cur, vel, pos : CurrentLevel, VelocityLevel, PositionLevel or None
        The closed levels at the excitation frequency w (``pos`` None: position loop open).
    k_ci, k_vphi, k_vomega, k_px : complex-like
        The controllers at w (as for the levels).
    i_f, phi_f, x_f : complex-like
        Continuous responses of current, angle and position to the force, voltage held at
        zero (their samples are exact: a sinusoid's steady state sampled).
    y_f, y_u : complex-like
        Continuous responses of the output to the force and to the voltage.
    h0 : complex-like
        The zero-order hold's fundamental at w.
    hold_v, hold_p : complex-like
        ``B_N(w)/N`` of the velocity and of the position controller's hold (1 for N = 1).

    Returns
    -------
    complex-like
        The output's fundamental per force.
    """
    # current loop closed, torque set-point zero
    u_f = k_ci * i_f * cur.r_c
    phi_fc = phi_f + cur.g_phi * u_f
    x_fc = x_f + cur.g_x * u_f
    # velocity loop closed, speed command zero
    t_vf = k_vphi * phi_fc * vel.r_v
    x_vf = x_fc + vel.g_vx * t_vf
    t_v = t_vf
    if pos is not None:
        omega_p = k_px * x_vf * pos.r_p
        t_v = t_v + k_vomega * vel.r_v * hold_p * omega_p
    u = u_f + cur.k_ct * cur.r_c * hold_v * t_v
    return y_f + y_u * h0 * u
