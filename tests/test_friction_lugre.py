"""The LuGre model against closed forms, finite differences, scipy's stiff solvers and the
published examples of Canudas de Wit et al. (1995)."""

import dataclasses
import itertools
import math

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp

from servotune.friction import lugre
from servotune.friction.lugre import BIANCHI2014, CANUDAS1995, LuGreParameters

W20 = 2 * math.pi * 20.0


def g_ref(p, v):
    """Stribeck curve written out here (Canudas de Wit et al. 1995, Eq 4)."""
    return p.fc + (p.fs - p.fc) * np.exp(-np.abs(v / p.vs) ** p.delta)


# ---------------------------------------------------------------- parameters

def test_negative_sigma1_is_refused_as_energy_generating():
    with pytest.raises(ValueError, match="generate energy"):
        dataclasses.replace(BIANCHI2014, sigma1=-1.6e7)


@pytest.mark.parametrize("field, value, match", [
    ("fc", 0.0, "fc"), ("fs", 1000.0, "fs"), ("vs", 0.0, "vs"), ("delta", -1.0, "delta"),
    ("sigma0", 0.0, "sigma0"), ("sigma2", -1.0, "sigma2"), ("fc", math.nan, "finite")])
def test_bad_parameters_are_refused(field, value, match):
    with pytest.raises(ValueError, match=match):
        dataclasses.replace(BIANCHI2014, **{field: value})


def test_named_sets_are_the_published_values():
    # Bianchi et al. 2014, table after Fig 8 (sigma1 sign corrected); Canudas de Wit et al. 1995
    p = LuGreParameters.named("bianchi2014")
    assert (p.fc, p.fs, p.vs, p.delta, p.sigma0, p.sigma1, p.sigma2) == (
        2198.0, 6013.0, 0.01, 1.0, 5.9e9, 1.6e7, 5578.0)
    assert dict(lugre.BIANCHI2014_SPREAD) == {"fs": 258.0, "sigma0": 1.17e9, "sigma1": 1.3e6}
    c = LuGreParameters.named("Canudas1995")
    assert (c.sigma0, c.sigma1, c.sigma2, c.fc, c.fs, c.vs) == (
        1e5, math.sqrt(1e5), 0.4, 1.0, 1.5, 0.001)
    with pytest.raises(ValueError, match="unknown parameter set"):
        LuGreParameters.named("nope")


def test_scaled_pads_in_parallel_give_the_total_force():
    # n identical pads of factor 1/n moving together carry the force of the total element
    t = np.linspace(0.0, 0.1, 801)
    x = 4e-6 * np.sin(2 * math.pi * 20.0 * t) + 1e-4 * t
    total = lugre.simulate_lugre(BIANCHI2014, t, displacement=x).force
    pad = lugre.simulate_lugre(BIANCHI2014.scaled(0.25), t, displacement=x).force
    assert_allclose(4.0 * pad, total, rtol=1e-12, atol=1e-9 * BIANCHI2014.fs)
    s = BIANCHI2014.scaled(0.5)
    assert (s.vs, s.delta) == (BIANCHI2014.vs, BIANCHI2014.delta)
    with pytest.raises(ValueError):
        BIANCHI2014.scaled(0.0)


# ---------------------------------------------------------------- steady state

@pytest.mark.parametrize("p", [BIANCHI2014, CANUDAS1995], ids=["bianchi", "canudas"])
@pytest.mark.parametrize("v_over_vs", [-20.0, -1.0, 0.1, 0.7, 3.0])
def test_simulated_steady_state_is_the_stribeck_curve(p, v_over_vs):
    v = v_over_vs * p.vs
    # run for 40 bristle time constants g/(sigma0 |v|) plus a little
    t_end = 40.0 * g_ref(p, v) / (p.sigma0 * abs(v))
    t = np.linspace(0.0, t_end, 400)
    r = lugre.simulate_lugre(p, t, velocity=lambda tt: np.full_like(tt, v))
    expected = g_ref(p, v) * np.sign(v) + p.sigma2 * v
    assert_allclose(r.force[-1], expected, rtol=1e-12)
    assert_allclose(lugre.steady_state_friction(p, v), expected, rtol=1e-14)


def test_steady_state_slope_is_the_derivative_of_the_curve():
    v = np.array([-0.3, -0.004, 0.0005, 0.01, 0.2])
    h = 1e-7 * np.abs(v)
    fd = (lugre.steady_state_friction(BIANCHI2014, v + h)
          - lugre.steady_state_friction(BIANCHI2014, v - h)) / (2 * h)
    assert_allclose(lugre.steady_state_slope(BIANCHI2014, v), fd, rtol=1e-6)
    assert np.all(lugre.steady_state_slope(BIANCHI2014, [0.002, 0.008]) < 0.0)  # Stribeck dip


# ---------------------------------------------------------------- derivative and Jacobian

def test_jacobian_matches_central_differences():
    rng = np.random.default_rng(7)
    for p in (BIANCHI2014, CANUDAS1995):
        v = rng.uniform(-5, 5, 30) * p.vs
        z = rng.uniform(-1.5, 1.5, 30) * p.fs / p.sigma0
        j = lugre.lugre_jacobian(p, z, v)
        hz, hv = 1e-6 * p.fs / p.sigma0, 1e-6 * p.vs
        for fun, dz, dv in ((lugre.lugre_derivative, j.dzdot_dz, j.dzdot_dv),
                            (lugre.lugre_force, j.dforce_dz, j.dforce_dv)):
            fd_z = (fun(p, z + hz, v) - fun(p, z - hz, v)) / (2 * hz)
            fd_v = (fun(p, z, v + hv) - fun(p, z, v - hv)) / (2 * hv)
            assert_allclose(dz, fd_z, rtol=1e-6, atol=1e-9 * np.max(np.abs(fd_z)))
            assert_allclose(dv, fd_v, rtol=1e-5, atol=1e-7 * np.max(np.abs(fd_v)))


def test_force_is_the_defining_sum():
    z, v = 3e-7, 0.004
    zdot = v - BIANCHI2014.sigma0 * abs(v) * z / g_ref(BIANCHI2014, v)
    expected = BIANCHI2014.sigma0 * z + BIANCHI2014.sigma1 * zdot + BIANCHI2014.sigma2 * v
    assert_allclose(lugre.lugre_force(BIANCHI2014, z, v), expected, rtol=1e-13)


# ---------------------------------------------------------------- linearisations

def test_canudas_presliding_natural_frequency_and_damping():
    # Canudas de Wit et al. 1995, sec III: a unit mass on the bristles has
    # w_n = sqrt(sigma0/m), zeta = (sigma1 + sigma2) / (2 sqrt(sigma0 m))
    m = 1.0
    p = CANUDAS1995
    friction = lugre.presliding_linearisation(p)
    mass = control.ss([[0.0]], [[1.0 / m]], [[1.0]], [[0.0]], inputs=["f"], outputs=["velocity"])
    loop = control.feedback(mass, friction)  # m dv/dt = f - F
    wn, zeta, _ = control.damp(loop, doprint=False)
    assert_allclose(wn, math.sqrt(p.sigma0 / m), rtol=1e-10)
    assert_allclose(zeta, (p.sigma1 + p.sigma2) / (2 * math.sqrt(p.sigma0 * m)), rtol=1e-10)
    assert friction.input_labels == ["velocity"] and friction.output_labels == ["force"]


@pytest.mark.parametrize("v0", [-0.2, -0.006, 0.0005, 0.004, 0.05])
@pytest.mark.parametrize("p", [BIANCHI2014, dataclasses.replace(BIANCHI2014,
                                                                sigma1_decay_speed=0.01)],
                         ids=["constant-sigma1", "micro-damping"])
def test_sliding_linearisation_against_the_nonlinear_model(p, v0):
    sys = lugre.sliding_linearisation(p, v0)
    # DC gain: slope of the steady-state curve by central differences
    h = 1e-6 * abs(v0)
    slope = float((lugre.steady_state_friction(p, v0 + h)
                   - lugre.steady_state_friction(p, v0 - h)) / (2 * h))
    assert_allclose(float(sys.dcgain()), slope, rtol=1e-6)
    # pole: the bristle rate sigma0 |v0| / g(v0)
    assert_allclose(sys.poles().real, [-p.sigma0 * abs(v0) / g_ref(p, v0)], rtol=1e-12)
    # small-signal response against the simulated nonlinear element: a velocity step of 0.1 %
    dv = 1e-3 * abs(v0)
    tau = g_ref(p, v0) / (p.sigma0 * abs(v0))
    t = np.linspace(0.0, 6 * tau, 301)
    z_ss = g_ref(p, v0) * np.sign(v0) / p.sigma0
    r = lugre.simulate_lugre(p, t, velocity=lambda tt: np.full_like(tt, v0 + dv), z0=z_ss)
    lin = control.step_response(sys, t).outputs * dv
    df = r.force - float(lugre.steady_state_friction(p, v0))
    assert_allclose(df[1:], lin[1:], rtol=5e-3, atol=5e-3 * np.max(np.abs(lin)))


def test_sliding_linearisation_refuses_zero_speed():
    with pytest.raises(ValueError, match="presliding"):
        lugre.sliding_linearisation(BIANCHI2014, 0.0)


# ---------------------------------------------------------------- simulation

def reference_simulation(p, t_eval, vfun, z0=0.0):
    """Radau with tight tolerances, the reversals handled by dense stepping."""
    def rhs(t, y):
        return lugre.lugre_derivative(p, y, vfun(t))

    def jac(t, y):
        return [[float(lugre.lugre_jacobian(p, y[0], vfun(t)).dzdot_dz)]]

    sol = solve_ivp(rhs, (t_eval[0], t_eval[-1]), [z0], method="Radau", jac=jac, rtol=1e-10,
                    atol=1e-12 * p.fs / p.sigma0, t_eval=t_eval)
    return sol.y[0]


def test_simulation_converges_to_the_stiff_reference_at_high_order():
    # reversals fall between the samples; the history is given as a function of time
    p = CANUDAS1995
    def vfun(t):
        return 0.01 * np.sin(2 * math.pi * 3.0 * t) + 0.004 * np.cos(2 * math.pi * 7.3 * t)
    t_ref = np.linspace(0.0, 0.5, 11)
    z_ref = reference_simulation(p, t_ref, vfun)
    errors = []
    for n in (251, 501, 1001):
        t = np.linspace(0.0, 0.5, n)
        r = lugre.simulate_lugre(p, t, velocity=vfun)
        z = np.interp(t_ref, t, r.z)
        errors.append(np.max(np.abs(z - z_ref)) / (p.fs / p.sigma0))
    assert errors[-1] < 5e-7
    order = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(order > 3.0), (errors, order)  # fourth order observed


def test_simulation_from_displacement_samples_matches_velocity_form():
    p = BIANCHI2014
    t = np.linspace(0.0, 0.1, 4001)
    w = W20
    x = 3e-6 * np.sin(w * t)
    r_x = lugre.simulate_lugre(p, t, displacement=x)
    r_v = lugre.simulate_lugre(p, t, velocity=lambda tt: 3e-6 * w * np.cos(w * tt))
    assert_allclose(r_x.force, r_v.force, atol=2e-4 * p.fs)
    assert_allclose(r_v.displacement, x, atol=1e-9 * 3e-6)


def test_simulation_refuses_bad_input():
    t = np.linspace(0, 1, 10)
    with pytest.raises(ValueError, match="exactly one"):
        lugre.simulate_lugre(BIANCHI2014, t)
    with pytest.raises(ValueError, match="increasing"):
        lugre.simulate_lugre(BIANCHI2014, t[::-1], velocity=np.ones(10))
    with pytest.raises(ValueError, match="shape"):
        lugre.simulate_lugre(BIANCHI2014, t, velocity=np.ones(9))


def periodic_reference(p, amplitude, omega):
    """Energy per cycle and Keq by Radau: shooting for the periodic state, then one cycle
    (with sigma1(v) = sigma1 exp(-(v/v_d)^2) when the parameters have a decay speed)."""
    period = 2 * math.pi / omega
    knots = [-period / 4, period / 4, 3 * period / 4]

    def v(t):
        return amplitude * omega * math.cos(omega * t)

    def rate(t):
        vv = v(t)
        return p.sigma0 * abs(vv) / g_ref(p, vv)

    def rhs1(t, y):
        return [v(t) - rate(t) * y[0], rate(t)]

    def jac1(t, y):
        return [[-rate(t), 0.0], [0.0, 0.0]]

    zs = p.fs / p.sigma0
    y = [0.0, 0.0]
    for a, b in itertools.pairwise(knots):
        y = solve_ivp(rhs1, (a, b), y, method="Radau", jac=jac1, rtol=1e-10,
                      atol=[1e-12 * zs, 1e-12]).y[:, -1]
    z0 = y[0] / -math.expm1(-y[1])

    def sigma1(vv):  # written out here, independent of the module's micro_damping
        if p.sigma1_decay_speed is None:
            return p.sigma1
        return p.sigma1 * math.exp(-((vv / p.sigma1_decay_speed) ** 2))

    def rhs2(t, y):
        zd = v(t) - rate(t) * y[0]
        f = p.sigma0 * y[0] + sigma1(v(t)) * zd + p.sigma2 * v(t)
        return [zd, f * v(t), f * math.sin(omega * t)]

    def jac2(t, y):
        df = p.sigma0 - sigma1(v(t)) * rate(t)
        return [[-rate(t), 0, 0], [df * v(t), 0, 0], [df * math.sin(omega * t), 0, 0]]

    y = [z0, 0.0, 0.0]
    for a, b in itertools.pairwise(knots):
        y = solve_ivp(rhs2, (a, b), y, method="Radau", jac=jac2, rtol=1e-10,
                      atol=[1e-12 * zs, 1e-12 * p.fs * amplitude,
                            1e-12 * p.fs * period]).y[:, -1]
    return y[1], y[2] * omega / (math.pi * amplitude)


@pytest.mark.parametrize("amplitude", [0.2e-6, 2e-6, 50e-6])
def test_periodic_cycle_matches_radau_shooting(amplitude):
    energy, keq = periodic_reference(BIANCHI2014, amplitude, W20)
    cycle = lugre.lugre_cycle(BIANCHI2014, amplitude, W20)
    assert_allclose(cycle.energy, energy, rtol=1e-7)
    assert_allclose(cycle.keq, keq, rtol=1e-6, atol=1e-7 * BIANCHI2014.sigma0)


def test_periodic_cycle_is_periodic_and_converges_at_fourth_order():
    # the state returned for theta = 3 pi / 2 is the one at -pi / 2
    c = lugre.lugre_cycle(BIANCHI2014, np.array([1e-6, 5e-6]), W20, n_steps=256)
    assert_allclose(c.z[..., -1], c.z[..., 0], rtol=1e-10)
    energies = [lugre.lugre_cycle(BIANCHI2014, 5e-6, W20, n_steps=n).energy
                for n in (64, 128, 256, 4096)]
    err = np.abs(np.array(energies[:3]) - energies[3])
    assert np.all(np.log2(err[:-1] / err[1:]) > 3.5), err


def test_canudas_stick_slip_benchmark():
    # Canudas de Wit et al. 1995, sec IV: unit mass pulled through a 2 N/m spring whose end
    # moves at 0.1 m/s shows periodic stick-slip; the spring breaks the mass free near Fs.
    p = CANUDAS1995
    k, vp = 2.0, 0.1

    def rhs(t, y):
        x, v, z = y
        f = lugre.lugre_force(p, z, v)
        return [v, k * (vp * t - x) - f, lugre.lugre_derivative(p, z, v)]

    def jac(t, y):
        _, v, z = y
        j = lugre.lugre_jacobian(p, z, v)
        return [[0, 1, 0], [-k, -float(j.dforce_dv), -float(j.dforce_dz)],
                [0, float(j.dzdot_dv), float(j.dzdot_dz)]]

    t = np.linspace(0.0, 30.0, 30001)
    sol = solve_ivp(rhs, (0.0, 30.0), [0.0, 0.0, 0.0], method="Radau", jac=jac, rtol=1e-8,
                    atol=[1e-10, 1e-10, 1e-12], t_eval=t)
    spring = k * (vp * t - sol.y[0])
    v = sol.y[1]
    late = t > 10.0
    # breakaway peaks of the spring force (local maxima), in the periodic regime
    s = spring[late]
    peaks = s[1:-1][(s[1:-1] > s[:-2]) & (s[1:-1] >= s[2:]) & (s[1:-1] > 1.2)]
    assert peaks.size >= 3, "no periodic stick-slip"
    assert_allclose(peaks, peaks.mean(), rtol=2e-3)  # periodic
    assert_allclose(peaks.mean(), p.fs, rtol=0.05)   # breakaway close to Fs
    # sticking phases: the mass nearly stops while the spring end moves on
    assert np.min(np.abs(v[late])) < 0.01 * vp
    assert np.max(v[late]) > 2.0 * vp                # and slips fast


# ---------------------------------------------------------------- velocity-dependent micro-damping
# sigma1(v) = sigma1 exp(-(v/v_d)^2) (Olsson et al. 1998), written out here for the references

def s1_ref(p, v):
    return p.sigma1 * np.exp(-(np.asarray(v) / p.sigma1_decay_speed) ** 2)


BIANCHI_VD = dataclasses.replace(BIANCHI2014, sigma1_decay_speed=0.01)
CANUDAS_VD = dataclasses.replace(CANUDAS1995, sigma1_decay_speed=2e-3)
HUGE_VD = 1e9  # exp(-(v/v_d)^2) = 1 to 1e-21 for |v| < 0.1 m/s


@pytest.mark.parametrize("value, match", [
    (0.0, "> 0"), (-0.01, "> 0"), (math.nan, "finite"), (math.inf, "finite"),
    (True, "speed")])
def test_bad_decay_speed_is_refused(value, match):
    with pytest.raises(ValueError, match=match):
        dataclasses.replace(BIANCHI2014, sigma1_decay_speed=value)


def test_decay_speed_is_kept_by_scaling_and_in_the_dictionary():
    p = BIANCHI_VD
    assert p.sigma1_decay_speed == 0.01 and BIANCHI2014.sigma1_decay_speed is None
    assert p.scaled(0.25).sigma1_decay_speed == 0.01      # a speed: not shared by the pads
    assert p.to_dict()["sigma1_decay_speed"] == 0.01
    assert BIANCHI2014.to_dict()["sigma1_decay_speed"] is None
    assert LuGreParameters(**p.to_dict()) == p            # round trip (as axis.toml does)
    assert p != BIANCHI2014 and dataclasses.replace(p, sigma1_decay_speed=None) == BIANCHI2014
    assert LuGreParameters(**{**BIANCHI2014.to_dict(), "sigma1_decay_speed": "0.01"}) == p


def test_force_with_micro_damping_is_the_defining_sum():
    rng = np.random.default_rng(11)
    p = BIANCHI_VD
    v = rng.uniform(-5, 5, 50) * p.vs
    z = rng.uniform(-1.2, 1.2, 50) * p.fs / p.sigma0
    zdot = v - p.sigma0 * np.abs(v) * z / g_ref(p, v)
    expected = p.sigma0 * z + s1_ref(p, v) * zdot + p.sigma2 * v
    assert_allclose(lugre.lugre_force(p, z, v), expected, rtol=1e-12, atol=1e-9 * p.fs)
    assert_allclose(lugre.micro_damping(p, v), s1_ref(p, v), rtol=1e-15)
    assert_allclose(lugre.micro_damping(BIANCHI2014, v), BIANCHI2014.sigma1, rtol=0)


@pytest.mark.parametrize("p", [BIANCHI_VD, CANUDAS_VD], ids=["bianchi", "canudas"])
def test_jacobian_with_micro_damping_matches_central_differences(p):
    rng = np.random.default_rng(8)
    v = rng.uniform(-5, 5, 30) * p.vs
    z = rng.uniform(-1.5, 1.5, 30) * p.fs / p.sigma0
    j = lugre.lugre_jacobian(p, z, v)
    hz, hv = 1e-6 * p.fs / p.sigma0, 1e-6 * p.vs
    fd_z = (lugre.lugre_force(p, z + hz, v) - lugre.lugre_force(p, z - hz, v)) / (2 * hz)
    fd_v = (lugre.lugre_force(p, z, v + hv) - lugre.lugre_force(p, z, v - hv)) / (2 * hv)
    assert_allclose(j.dforce_dz, fd_z, rtol=1e-6, atol=1e-9 * np.max(np.abs(fd_z)))
    assert_allclose(j.dforce_dv, fd_v, rtol=1e-5, atol=1e-7 * np.max(np.abs(fd_v)))


def test_huge_decay_speed_is_the_constant_sigma1():
    p = dataclasses.replace(BIANCHI2014, sigma1_decay_speed=HUGE_VD)
    rng = np.random.default_rng(3)
    v = rng.uniform(-10, 10, 40) * p.vs
    z = rng.uniform(-1, 1, 40) * p.fs / p.sigma0
    assert_allclose(lugre.lugre_force(p, z, v), lugre.lugre_force(BIANCHI2014, z, v),
                    rtol=1e-12, atol=1e-12 * p.fs)
    for a, b in zip(lugre.lugre_jacobian(p, z, v), lugre.lugre_jacobian(BIANCHI2014, z, v),
                    strict=True):
        assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.max(np.abs(b)))
    for v0 in (-0.004, 0.03):
        a, b = lugre.sliding_linearisation(p, v0), lugre.sliding_linearisation(BIANCHI2014, v0)
        for m in "ABCD":
            assert_allclose(getattr(a, m), getattr(b, m), rtol=1e-12)
    c1 = lugre.lugre_cycle(p, [0.3e-6, 3e-6, 60e-6], W20)
    c0 = lugre.lugre_cycle(BIANCHI2014, [0.3e-6, 3e-6, 60e-6], W20)
    assert_allclose(c1.energy, c0.energy, rtol=1e-12)
    assert_allclose(c1.keq, c0.keq, rtol=1e-12)


def test_presliding_linearisation_keeps_the_full_sigma1():
    # sigma1(0) = sigma1 with zero slope: the contact at rest does not change
    a = lugre.presliding_linearisation(BIANCHI_VD)
    b = lugre.presliding_linearisation(BIANCHI2014)
    assert_allclose(a.D, b.D, rtol=0) and assert_allclose(a.C, b.C, rtol=0)
    j = lugre.lugre_jacobian(BIANCHI_VD, 0.0, 0.0)
    assert float(j.dforce_dv) == BIANCHI2014.sigma1 + BIANCHI2014.sigma2


@pytest.mark.parametrize("v_d", [1e-3, 3e-3, 1e-2])
def test_sliding_damping_at_30_mm_s_is_no_longer_negative(v_d):
    # the feed-through of the sliding linearisation, sigma1(v0) v0 g'(v0)/g(v0) + sigma2, is the
    # contact's damping at frequencies well above its bristle rate; with g' by central
    # differences of the Stribeck curve written out here
    v0, h = 0.03, 1e-7
    p = BIANCHI2014
    b = v0 * (g_ref(p, v0 + h) - g_ref(p, v0 - h)) / (2 * h) / g_ref(p, v0)
    constant = float(lugre.sliding_linearisation(p, v0).D[0, 0])
    assert_allclose(constant, p.sigma1 * b + p.sigma2, rtol=1e-6)
    assert constant < -3.5e6                 # about -3.8e6 N s/m: negative damping
    q = dataclasses.replace(p, sigma1_decay_speed=v_d)
    faded = float(lugre.sliding_linearisation(q, v0).D[0, 0])
    assert_allclose(faded, s1_ref(q, v0) * b + p.sigma2, rtol=1e-6)
    assert faded >= 0.0
    # the DC gain (slope of F_ss) does not depend on the micro-damping
    assert_allclose(float(lugre.sliding_linearisation(q, v0).dcgain()),
                    float(lugre.sliding_linearisation(p, v0).dcgain()), rtol=1e-12)


@pytest.mark.parametrize("v0", [-0.006, 0.004, 0.03])
def test_sliding_linearisation_with_micro_damping_has_the_written_out_feedthrough(v0):
    # at steady sliding dz/dt = 0, so dF = sigma0 dz + sigma1(v0) d(dz/dt) + sigma2 dv with
    # d(dz/dt)/dv = v0 g'(v0) / g(v0) (z0 = g sgn(v0) / sigma0): the instantaneous gain of the
    # linearisation is sigma1(v0) v0 g'(v0) / g(v0) + sigma2, with the decayed sigma1(v0);
    # g'(v) = -(Fs - Fc) delta |v|^(delta-1) sgn(v) / vs^delta exp(-|v/vs|^delta)
    p = BIANCHI_VD
    sys = control.ss(lugre.sliding_linearisation(p, v0))
    e = np.exp(-abs(v0 / p.vs) ** p.delta)
    dg = -(p.fs - p.fc) * p.delta * abs(v0) ** (p.delta - 1) * np.sign(v0) / p.vs**p.delta * e
    expected = s1_ref(p, v0) * v0 * dg / g_ref(p, v0) + p.sigma2
    assert_allclose(float(sys.D[0, 0]), expected, rtol=1e-10)
    # the bristle pole does not depend on sigma1: -sigma0 |v0| / g(v0)
    assert_allclose(sys.poles().real, [-p.sigma0 * abs(v0) / g_ref(p, v0)], rtol=1e-12)
    # and the feedthrough differs from the constant-sigma1 one by the decay of sigma1 alone
    constant = control.ss(lugre.sliding_linearisation(BIANCHI2014, v0))
    assert_allclose(float(constant.D[0, 0]) - p.sigma2, (expected - p.sigma2)
                    * BIANCHI2014.sigma1 / s1_ref(p, v0), rtol=1e-9)


@pytest.mark.parametrize("amplitude, f_hz", [(2e-6, 20.0), (50e-6, 20.0), (20e-6, 200.0)])
def test_periodic_cycle_with_micro_damping_matches_radau_shooting(amplitude, f_hz):
    p = dataclasses.replace(BIANCHI2014, sigma1_decay_speed=1e-3)
    omega = 2 * math.pi * f_hz
    energy, _ = periodic_reference(p, amplitude, omega)
    assert_allclose(lugre.lugre_cycle(p, amplitude, omega).energy, energy, rtol=1e-6)
    # and it differs from the constant-sigma1 cycle where the pads slide faster than v_d
    if amplitude * omega > 1e-3:
        assert abs(lugre.lugre_cycle(BIANCHI2014, amplitude, omega).energy / energy - 1) > 1e-3


def test_decay_below_the_dissipativity_bound_makes_every_instant_dissipative():
    # with the bristle energy sigma0 z^2/2 as storage, F v - sigma0 z dz/dt =
    # sigma0 a z^2 - sigma1(v) a z v + (sigma1(v) + sigma2) v^2 (a = sigma0 |v|/g) is >= 0 for
    # all z when sigma1(v)^2 |v| <= 4 g (sigma1(v) + sigma2); sufficient: sigma1(v) |v| <= 4 Fc,
    # i.e. v_d <= 4 sqrt(2 e) Fc / sigma1 (the maximum of |v| exp(-(v/v_d)^2) is
    # v_d / sqrt(2 e))
    p0 = dataclasses.replace(BIANCHI2014, sigma2=0.0)
    bound = 4 * math.sqrt(2 * math.e) * p0.fc / p0.sigma1
    assert_allclose(bound, 1.281e-3, rtol=1e-3)
    v = np.geomspace(1e-6, 1.0, 400)[:, None] * np.array([1.0, -1.0])
    v = v.ravel()[:, None]
    z = np.linspace(-1.2, 1.2, 241)[None, :] * p0.fs / p0.sigma0

    def supply(p):
        return lugre.lugre_force(p, z, v) * v - p.sigma0 * z * lugre.lugre_derivative(p, z, v)

    scale = p0.fc * np.abs(v)
    assert np.min(supply(dataclasses.replace(p0, sigma1_decay_speed=bound)) / scale) >= -1e-9
    # the constant sigma1 of the paper is not dissipative at every instant
    assert np.min(supply(p0) / scale) < -1.0
