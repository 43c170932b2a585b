"""Equivalent viscous damping: the stiction cycle against an exactly integrated elasto-plastic
element, the LuGre describing function against closed forms and its limits."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from servotune.friction import equivalent
from servotune.friction.lugre import BIANCHI2014, LuGreParameters, lugre_cycle

W20 = 2 * math.pi * 20.0


def loop_area(x, f):
    """int F dx by the trapezoid rule, exact for F piecewise linear in x."""
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x)))


@pytest.mark.parametrize("ratio", [0.5, 1.0, 1.3, 2.0, 5.0, 40.0])
def test_stiction_area_is_the_elasto_plastic_loop(ratio):
    fs, sigma0 = 6013.0, 5.9e9
    a = fs / sigma0
    amplitude = ratio * a
    theta = np.linspace(-0.5 * math.pi, 3.5 * math.pi, 8001)
    x = amplitude * np.sin(theta)
    # exact return mapping with the yield points inserted
    xs, forces = [x[0]], [-min(fs, sigma0 * amplitude)]
    f = forces[0]
    for i in range(1, x.size):
        trial = f + sigma0 * (x[i] - x[i - 1])
        if abs(trial) > fs > abs(f):
            xs.append(x[i - 1] + (math.copysign(fs, trial) - f) / sigma0)
            forces.append(math.copysign(fs, trial))
        f = float(np.clip(trial, -fs, fs))
        xs.append(x[i])
        forces.append(f)
    xs, forces = np.array(xs), np.array(forces)
    half = xs.size // 2
    area = loop_area(xs[half:], forces[half:])  # second period: settled
    expected = 4 * fs * max(amplitude - a, 0.0)
    assert_allclose(area, expected, rtol=1e-9, atol=1e-12 * fs * amplitude)
    ceq = equivalent.equivalent_damping_stiction(fs, sigma0, amplitude, W20)
    assert_allclose(ceq, area / (math.pi * W20 * amplitude**2), rtol=1e-9,
                    atol=1e-12 * sigma0 / W20)


@pytest.mark.parametrize("ratio", [0.7, 1.0, 1.5, 2.0, 4.0, 30.0])
def test_stiction_keq_is_the_first_harmonic_of_the_elasto_plastic_force(ratio):
    fs, sigma0 = 1.0, 1.0
    amplitude = ratio * fs / sigma0
    n = 200_000
    theta = np.linspace(-0.5 * math.pi, 3.5 * math.pi, 2 * n + 1)
    x = amplitude * np.sin(theta)
    f = np.empty_like(x)
    f[0] = -min(fs, sigma0 * amplitude)
    for i in range(1, x.size):  # fine steps; first-order error in the yield point only
        f[i] = min(max(f[i - 1] + sigma0 * (x[i] - x[i - 1]), -fs), fs)
    th, ff = theta[n:], f[n:]
    dth = th[1] - th[0]
    keq = np.sum((ff * np.sin(th))[:-1]) * dth / (math.pi * amplitude)
    ceq_num = np.sum((ff * np.cos(th))[:-1]) * dth / (math.pi * amplitude * 1.0)
    ceq, keq_cf = equivalent.stiction_describing_function(fs, sigma0, amplitude, 1.0)
    assert_allclose(keq_cf, keq, rtol=1e-4, atol=1e-5)
    assert_allclose(ceq, ceq_num, rtol=1e-4, atol=1e-5)


def test_stiction_peak_and_its_place():
    fs, sigma0 = 6013.0, 5.9e9
    amplitude = np.geomspace(0.5, 20.0, 200001) * fs / sigma0
    ceq = equivalent.equivalent_damping_stiction(fs, sigma0, amplitude, W20)
    i = int(np.argmax(ceq))
    a_peak, c_peak = equivalent.stiction_peak_damping(fs, sigma0, W20)
    assert_allclose(amplitude[i], a_peak, rtol=1e-4)
    assert_allclose(ceq[i], c_peak, rtol=1e-9)
    assert_allclose(c_peak, sigma0 / (math.pi * W20), rtol=1e-14)
    assert np.all(ceq[amplitude <= fs / sigma0] == 0.0)


def test_stiction_tends_to_the_coulomb_describing_function():
    # a Coulomb slider's first harmonic is 4 Fs / pi in phase with the velocity (square wave):
    # Ceq = 4 Fs / (pi w A) when the bristle deflection is negligible
    fs, sigma0 = 6013.0, 5.9e9
    amplitude = 1e5 * fs / sigma0
    ceq = equivalent.equivalent_damping_stiction(fs, sigma0, amplitude, W20)
    assert_allclose(ceq, 4 * fs / (math.pi * W20 * amplitude), rtol=2e-5)


def test_stiction_refuses_bad_input():
    with pytest.raises(ValueError, match="amplitude"):
        equivalent.equivalent_damping_stiction(6013.0, 5.9e9, -1e-6, W20)
    with pytest.raises(ValueError, match="sigma0"):
        equivalent.equivalent_damping_stiction(6013.0, 0.0, 1e-6, W20)


@pytest.mark.parametrize("ratio", [0.05, 0.5, 1.0, 3.0, 20.0])
def test_lugre_with_constant_g_follows_the_exponential_presliding_curve(ratio):
    # sigma1 = sigma2 = 0 and Fc = Fs: dz/dx = 1 - sgn(v) z / a with a = Fs / sigma0, whose loop
    # encloses 4 Fs (A - a tanh(A / a)) (integrate the exponential branches from -A to A)
    p = LuGreParameters(fc=6013.0, fs=6013.0, vs=0.01, delta=1.0, sigma0=5.9e9, sigma1=0.0,
                        sigma2=0.0)
    a = p.fs / p.sigma0
    amplitude = ratio * a
    ceq, _ = equivalent.describing_function(p, amplitude, W20)
    area = 4 * p.fs * (amplitude - a * math.tanh(amplitude / a))
    assert_allclose(ceq * math.pi * W20 * amplitude**2, area, rtol=1e-8)


def test_lugre_small_amplitude_is_the_presliding_linearisation():
    # the spring sigma0 and damper sigma1 + sigma2, with an error of order A sigma0 / Fs
    amplitude = np.array([1e-10, 1e-11])
    ceq, keq = equivalent.describing_function(BIANCHI2014, amplitude, W20)
    eps = amplitude * BIANCHI2014.sigma0 / BIANCHI2014.fs
    assert np.all(np.abs(keq / BIANCHI2014.sigma0 - 1.0) < 2 * eps)
    assert np.all(np.abs(ceq / (BIANCHI2014.sigma1 + BIANCHI2014.sigma2) - 1.0) < 2 * eps)


def test_lugre_large_amplitude_tends_to_coulomb_and_viscous():
    # far beyond presliding and at speeds far above vs: F ~ Fc sgn(v) + sigma2 v
    amplitude, omega = 0.05, 2 * math.pi * 20.0   # peak speed 6.3 m/s = 630 vs
    ceq, _ = equivalent.describing_function(BIANCHI2014, amplitude, omega, n_steps=4096)
    coulomb = 4 * BIANCHI2014.fc / (math.pi * omega * amplitude) + BIANCHI2014.sigma2
    assert_allclose(ceq, coulomb, rtol=2e-3)


def test_describing_function_broadcasts_as_a_table():
    amplitude = np.array([0.5e-6, 2e-6, 8e-6])
    omega = 2 * math.pi * np.array([5.0, 20.0])
    ceq, keq = equivalent.describing_function(BIANCHI2014, amplitude[:, None], omega[None, :],
                                              n_steps=256)
    assert ceq.shape == keq.shape == (3, 2)
    for i, a in enumerate(amplitude):
        for j, w in enumerate(omega):
            c1, k1 = equivalent.describing_function(BIANCHI2014, a, w, n_steps=256)
            assert_allclose([ceq[i, j], keq[i, j]], [c1, k1], rtol=1e-13)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(fc=st.floats(0.1, 1e4), fs_ratio=st.floats(1.0, 5.0), vs=st.floats(1e-4, 1e-1),
       delta=st.floats(0.5, 2.5), sigma0=st.floats(1e3, 1e10), sigma1=st.floats(0.0, 1e8),
       sigma2=st.floats(0.0, 1e4), amp_ratio=st.floats(0.01, 100.0),
       omega=st.floats(0.1, 1e4))
def test_dissipated_energy_is_never_negative(fc, fs_ratio, vs, delta, sigma0, sigma1, sigma2,
                                             amp_ratio, omega):
    # over a periodic cycle sigma0 z v integrates to int sigma0 a z^2 >= 0 and sigma1 zdot v to
    # sigma1 (int zdot^2 - int z^2 da/2); the loop area must not be negative
    p = LuGreParameters(fc=fc, fs=fc * fs_ratio, vs=vs, delta=delta, sigma0=sigma0,
                        sigma1=sigma1, sigma2=sigma2)
    amplitude = amp_ratio * p.fs / p.sigma0
    ceq, _ = equivalent.describing_function(p, amplitude, omega, n_steps=256)
    assert ceq >= 0.0


def test_paper_values_at_1_2_5_um():
    # closed form against the paper's parameters (Ceq_max = sigma0 / (pi w) near 2 um) and the
    # LuGre element dissipating more (bristle damping and the exponential presliding curve)
    amplitude = np.array([1e-6, 2e-6, 5e-6])
    closed = equivalent.equivalent_damping_stiction(BIANCHI2014.fs, BIANCHI2014.sigma0,
                                                    amplitude, W20)
    a = BIANCHI2014.fs / BIANCHI2014.sigma0
    assert closed[0] == 0.0  # 1 um < Fs / sigma0 = 1.019 um: no sliding in the idealised cycle
    assert_allclose(closed[1:], 4 * 6013.0 * (amplitude[1:] - a)
                    / (math.pi * W20 * amplitude[1:] ** 2), rtol=1e-14)
    ceq, _ = equivalent.describing_function(BIANCHI2014, amplitude, W20)
    assert np.all(ceq > closed)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(fc=st.floats(0.1, 1e4), fs_ratio=st.floats(1.0, 5.0), vs=st.floats(1e-4, 1e-1),
       delta=st.floats(0.5, 2.5), sigma0=st.floats(1e3, 1e10), sigma1=st.floats(0.0, 1e8),
       sigma2=st.floats(0.0, 1e4), vd_ratio=st.floats(1e-3, 1e3),
       amp_ratio=st.floats(0.01, 100.0), omega=st.floats(0.1, 1e4))
def test_dissipated_energy_with_micro_damping_is_never_negative(
        fc, fs_ratio, vs, delta, sigma0, sigma1, sigma2, vd_ratio, amp_ratio, omega):
    # sigma1(v) = sigma1 exp(-(v/v_d)^2) with v_d from 1e-3 to 1e3 Stribeck velocities
    p = LuGreParameters(fc=fc, fs=fc * fs_ratio, vs=vs, delta=delta, sigma0=sigma0,
                        sigma1=sigma1, sigma2=sigma2, sigma1_decay_speed=vd_ratio * vs)
    amplitude = amp_ratio * p.fs / p.sigma0
    ceq, _ = equivalent.describing_function(p, amplitude, omega, n_steps=256)
    assert ceq >= 0.0


def test_describing_function_with_micro_damping_limits():
    p = dataclasses.replace(BIANCHI2014, sigma1_decay_speed=1e-3)
    # tiny motions (v << v_d): the presliding contact with the full sigma1
    amplitude = np.array([1e-11, 1e-10])
    ceq, keq = equivalent.describing_function(p, amplitude, W20)
    eps = amplitude * p.sigma0 / p.fs
    assert np.all(np.abs(ceq / (p.sigma1 + p.sigma2) - 1.0) < 2 * eps)
    assert np.all(np.abs(keq / p.sigma0 - 1.0) < 2 * eps)
    # v_d -> infinity: the constant-sigma1 describing function
    huge = dataclasses.replace(BIANCHI2014, sigma1_decay_speed=1e9)
    a = np.geomspace(1e-7, 1e-4, 7)
    for x, y in zip(equivalent.describing_function(huge, a, W20),
                    equivalent.describing_function(BIANCHI2014, a, W20), strict=True):
        assert_allclose(x, y, rtol=1e-12)
    # large strokes (v >> v_d): the bristle damping drops out, Coulomb plus viscous remain
    big = 5e-3
    omega = np.array([W20, 10 * W20])
    ceq, _ = equivalent.describing_function(p, big, omega, n_steps=4096)
    coulomb = 4 * p.fc / (math.pi * omega * big) + p.sigma2
    assert_allclose(ceq, coulomb, rtol=0.02)


# the default steps per period, against an independent stiff solution (Radau at rtol 1e-10,
# shooting for the periodic state; tests/test_friction_lugre.py): cases from the convergence
# study of describing_function, the worst one (a 1 mm stroke at 30 Hz, 19 vs) included
DEFAULT_CASES = [
    (BIANCHI2014, 2e-6, 20.0),
    (BIANCHI2014, 1e-3, 30.0),
    (LuGreParameters.named("canudas1995"), 1e-3, 100.0),
    (dataclasses.replace(BIANCHI2014, sigma1_decay_speed=1e-3), 20e-6, 200.0),
]


@pytest.mark.parametrize("p, amplitude, f_hz", DEFAULT_CASES)
def test_describing_function_at_its_default_steps_against_radau(p, amplitude, f_hz):
    from test_friction_lugre import periodic_reference

    omega = 2 * math.pi * f_hz
    energy, keq_ref = periodic_reference(p, amplitude, omega)
    ceq_ref = energy / (math.pi * omega * amplitude**2)
    ceq, keq = equivalent.describing_function(p, amplitude, omega)
    n_ref = keq_ref + 1j * omega * ceq_ref
    # the documented accuracy of the default: N = Keq + j w Ceq within 1e-4, Ceq within 1e-6
    assert abs(keq + 1j * omega * ceq - n_ref) / abs(n_ref) < 1e-4
    assert_allclose(ceq, ceq_ref, rtol=1e-6)


@pytest.mark.parametrize("p, amplitude, f_hz", DEFAULT_CASES)
def test_half_period_with_graded_steps_agrees_with_the_full_uniform_cycle(p, amplitude, f_hz):
    # two discretisations of the same periodic state (half a period with graded steps, the
    # full period with uniform ones) converge to the same describing function
    omega = 2 * math.pi * f_hz
    ceq, keq = equivalent.describing_function(p, amplitude, omega, n_steps=16384)
    cycle = lugre_cycle(p, amplitude, omega, n_steps=16384)
    n_ref = cycle.keq + 1j * omega * cycle.ceq
    assert abs(keq + 1j * omega * ceq - n_ref) / abs(n_ref) < 1e-7
    assert_allclose(ceq, cycle.ceq, rtol=1e-8)


@pytest.mark.parametrize("amplitude, f_hz", [(5e-6, 20.0), (1e-3, 30.0)])
def test_graded_steps_converge_at_fourth_order(amplitude, f_hz):
    omega = 2 * math.pi * f_hz
    # (the fast stroke is pre-asymptotic below 256 steps)
    fine = equivalent.describing_function(BIANCHI2014, amplitude, omega, n_steps=16384)[0]
    err = np.array([abs(equivalent.describing_function(BIANCHI2014, amplitude, omega,
                                                       n_steps=n)[0] - fine)
                    for n in (256, 512, 1024)])
    assert np.all(np.log2(err[:-1] / err[1:]) > 3.5), err
