"""LuGre on its periodic orbit (servotune.friction.periodic) against independent references:
the Stribeck curve in steady sliding (closed form), the presliding linearisation at tiny
amplitude (closed form), a stiff ODE solver run to its periodic state (second method, with the
second-order convergence of the exact-step scheme), and finite differences of its Jacobian."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp

from servotune.friction.lugre import LuGreParameters
from servotune.friction.periodic import (
    lugre_periodic_force,
    lugre_periodic_jacobian,
    lugre_periodic_state,
)

PAPER = LuGreParameters.named("bianchi2014")


@pytest.mark.parametrize("v", [-0.2, -0.03, 0.004, 0.03, 0.5])
def test_steady_sliding_gives_the_stribeck_curve(v):
    # Canudas de Wit et al. (1995): F_ss(v) = g(v) sgn(v) + sigma2 v
    g = PAPER.fc + (PAPER.fs - PAPER.fc) * math.exp(-abs(v / PAPER.vs) ** PAPER.delta)
    force = lugre_periodic_force(PAPER, np.full(32, v), 0.05)
    assert_allclose(force, math.copysign(g, v) + PAPER.sigma2 * v, rtol=1e-10)


def test_tiny_presliding_motion_is_the_spring_and_damper():
    # x = A cos(w t) with A << Fs/sigma0: F_1 = (sigma0 + j w (sigma1 + sigma2)) A
    # (the presliding linearisation; without micro-damping decay)
    p = dataclasses.replace(PAPER, sigma1_decay_speed=None)
    w, amp, n = 2 * math.pi * 57.0, 1e-11, 512
    t = np.arange(n) / n * (2 * math.pi / w)
    force = lugre_periodic_force(p, -amp * w * np.sin(w * t), 2 * math.pi / w)
    f1 = 2.0 * np.fft.rfft(force)[1] / n
    expected = (p.sigma0 + 1j * w * (p.sigma1 + p.sigma2)) * amp
    assert abs(f1 - expected) <= 2e-3 * abs(expected)


def _ode_periodic(p, velocity, period):
    """Reference: Radau (rtol 1e-11) of the bristle equation over one period. The equation is
    linear in z, so the end value is Phi z0 + psi: two runs (z0 = 0 and z0 = Fs/sigma0) give
    the periodic start, a third run samples the orbit."""
    def rhs(t, z):
        v = velocity(t)
        g = p.fc + (p.fs - p.fc) * math.exp(-abs(v / p.vs) ** p.delta)
        return [v - p.sigma0 * abs(v) / g * z[0]]

    def jac(t, z):
        v = velocity(t)
        g = p.fc + (p.fs - p.fc) * math.exp(-abs(v / p.vs) ** p.delta)
        return [[-p.sigma0 * abs(v) / g]]

    def run(z0, t_eval=None):
        return solve_ivp(rhs, (0.0, period), [z0], method="Radau", jac=jac, rtol=1e-11,
                         atol=1e-18, t_eval=t_eval, max_step=period / 400).y[0]

    z1 = p.fs / p.sigma0
    psi = run(0.0)[-1]
    phi = (run(z1)[-1] - psi) / z1
    return run(psi / (1.0 - phi), np.arange(64) / 64 * period)


@pytest.mark.parametrize("amplitude", [2e-7, 3e-6])
def test_the_orbit_matches_a_stiff_solver_with_second_order_convergence(amplitude):
    p = dataclasses.replace(PAPER, sigma1_decay_speed=None).scaled(0.25)
    w = 2 * math.pi * 50.0
    period = 2 * math.pi / w

    def velocity(t):
        return -amplitude * w * (np.sin(w * t) + 0.3 * np.sin(3 * w * t + 0.4))

    ref = _ode_periodic(p, velocity, period)
    errors = []
    for n in (256, 512, 1024):
        z, _ = lugre_periodic_state(p, velocity(np.arange(n) / n * period), period)
        errors.append(np.abs(z[:: n // 64] - ref).max() / np.abs(ref).max())
    assert errors[-1] < 2e-3
    # second order in h = T/N (velocity held at the interval mean): over two halvings of h the
    # error falls by about 16 (the kinks of |v| at the reversals blur single halvings)
    assert errors[0] > errors[1] > errors[2]
    assert math.log2(errors[0] / errors[2]) / 2 > 1.5, errors


@pytest.mark.parametrize("v", [
    lambda t: 1e-5 * np.sin(2 * np.pi * t) + 3e-6 * np.cos(6 * np.pi * t),
    lambda t: 0.03 + 0.05 * np.sin(2 * np.pi * t),
    lambda t: 1e-7 * np.sin(2 * np.pi * t)])
def test_the_jacobian_is_the_derivative_of_the_force(v):
    p = PAPER.scaled(0.25)
    vel = v(np.arange(64) / 64)
    force, jac = lugre_periodic_jacobian(p, vel, 0.02)
    assert_allclose(force, lugre_periodic_force(p, vel, 0.02), rtol=1e-12, atol=1e-9)
    fd = np.empty_like(jac)
    step = 1e-7 * np.abs(vel).max()
    for j in range(vel.size):
        up, down = vel.copy(), vel.copy()
        up[j] += step
        down[j] -= step
        fd[:, j] = (lugre_periodic_force(p, up, 0.02) - lugre_periodic_force(p, down, 0.02)) \
            / (2 * step)
    assert np.abs(jac - fd).max() <= 1e-5 * np.abs(fd).max()
    basis = np.random.default_rng(1).standard_normal((vel.size, 3))
    assert_allclose(lugre_periodic_jacobian(p, vel, 0.02, basis)[1], jac @ basis, rtol=1e-9,
                    atol=1e-9 * np.abs(jac).max())


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="period"):
        lugre_periodic_force(PAPER, np.zeros(8), 0.0)
    with pytest.raises(ValueError, match="1-D"):
        lugre_periodic_force(PAPER, np.zeros((2, 2, 8)), 0.1)
    with pytest.raises(ValueError, match="finite"):
        lugre_periodic_force(PAPER, np.array([0.0, np.nan]), 0.1)


def test_rows_are_contacts_of_their_own():
    rng = np.random.default_rng(3)
    v = 1e-4 * rng.standard_normal((3, 64))
    p = PAPER.scaled(0.25)
    assert_allclose(lugre_periodic_force(p, v, 0.02),
                    [lugre_periodic_force(p, row, 0.02) for row in v], rtol=1e-14, atol=1e-12)
    basis = rng.standard_normal((64, 5))
    f, jac = lugre_periodic_jacobian(p, v, 0.02, basis)
    for row, fr, jr in zip(v, f, jac, strict=True):
        f1, j1 = lugre_periodic_jacobian(p, row, 0.02, basis)
        assert_allclose(fr, f1, rtol=1e-14, atol=1e-12)
        assert_allclose(jr, j1, rtol=1e-12, atol=1e-12 * np.abs(j1).max())
    with pytest.raises(TypeError, match="LuGreParameters"):
        lugre_periodic_force({"fc": 1.0}, np.zeros(8), 0.1)
