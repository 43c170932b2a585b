"""The generalized Maxwell-slip law (Al-Bender, Lampaert and Swevers 2005) against its published
behaviour: the virgin presliding curve of parallel elasto-slide elements, hysteresis with
non-local memory (wiping-out), the Stribeck curve while sliding; its linear contacts, its pieces
for the time simulation, its periodic orbit, and the bundled axis simulated with it."""

import dataclasses
import math
import re
import shutil

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp

from servotune.friction.law import friction_law
from servotune.friction.laws.gms import (
    BIANCHI2014_GMS,
    GMSFriction,
    gms_remainder,
    gms_states,
)

P = BIANCHI2014_GMS
# the paper's micro-damping spread over the elements, for the checks of the force expression
P_DAMPED = dataclasses.replace(P, damping=(1.0e6, 2.0e6, 3.0e6, 4.0e6))


def stribeck(p, v):
    """The published Stribeck curve, written out: Fc + (Fs - Fc) exp(-(|v|/vs)^delta)."""
    return p.fc + (p.fs - p.fc) * np.exp(-(np.abs(v) / p.vs) ** p.delta)


def element_rate(p, i, v, z):
    """Element i written out from the papers' stick and slip laws (memoryless form: the slower
    of the two rates, in the direction of v)."""
    if v == 0:
        return 0.0
    dlt = p.fractions[i] * stribeck(p, v) / p.stiffness[i]
    sgn = math.copysign(1.0, v)
    return sgn * min(abs(v), p.attraction * (1.0 - sgn * z / dlt))


def play_operator(p, x_path, s):
    """Quasi-static Maxwell slip: each element a play operator of half-width alpha_i s / k_i
    (Lampaert et al. 2003, sec III); the force at each point of the displacement path."""
    width = np.array(p.fractions) * s / np.array(p.stiffness)
    z = np.zeros(p.n_elements)
    out = []
    x_prev = 0.0
    for x in x_path:
        z = np.clip(z + (x - x_prev), -width, width)
        x_prev = x
        out.append(float(np.dot(p.stiffness, z)))
    return np.array(out)


def path(turns, speed, dt):
    """Times and velocities that move through the turning points at a constant speed."""
    v, x = [], 0.0
    for target in turns:
        n = round(abs(target - x) / (speed * dt))
        v += [math.copysign(speed, target - x)] * n
        x = target
    v = np.array([*v, v[-1]])
    return np.arange(v.size) * dt, v


def test_parameters_are_validated_with_the_fix_in_the_message():
    with pytest.raises(ValueError, match="sum to 1"):
        dataclasses.replace(P, fractions=(0.1, 0.2, 0.3, 0.3))
    with pytest.raises(ValueError, match="one value per element"):
        dataclasses.replace(P, damping=(0.0,) * 3)
    with pytest.raises(ValueError, match=r"fs .* must be >= fc"):
        dataclasses.replace(P, fs=1000.0)
    with pytest.raises(ValueError, match="attraction must be > 0"):
        dataclasses.replace(P, attraction=0.0)


def test_virgin_curve_is_parallel_elasto_slide_elements():
    # slow loading from the virgin state: F(x) = sum k_i min(x, Delta_i) + rate terms, the
    # piecewise-linear curve of the Maxwell-slip model; initial slope sum k_i, saturation at
    # the static level s(v) ~ Fs
    p = P_DAMPED
    v = 1e-6
    t = np.linspace(0.0, 3.0, 3001)                      # up to 3 um, beyond every Delta_i
    _, force = gms_states(p, t, np.full(t.size, v))
    x = v * t
    width = np.array(p.fractions) * stribeck(p, v) / np.array(p.stiffness)
    sticking = x[:, None] < width[None, :]
    reference = (np.minimum(x[:, None], width[None, :]) @ np.array(p.stiffness)
                 + (sticking * np.array(p.damping)[None, :]).sum(axis=1) * v + p.sigma2 * v)
    assert_allclose(force, reference, atol=1e-4 * p.fs)
    slope = (force[5] - force[1]) / (x[5] - x[1])
    assert_allclose(slope, sum(p.stiffness), rtol=1e-9)
    assert_allclose(force[-1], stribeck(p, v) + p.sigma2 * v, rtol=1e-9)
    assert abs(force[-1] - p.fs) < 1e-3 * p.fs


def test_hysteresis_has_non_local_memory_and_wipes_out_inner_loops():
    # outer branch 0 -> +3 um -> -0.5 um, an inner loop -0.5 -> +0.9 -> -0.5 um, then on to
    # -3 um: the inner loop closes where it started and the curve continues as if it had not
    # been (wiping-out, Preisach-type hysteresis: Al-Bender et al. 2005, sec III)
    v, dt = 1e-6, 2e-4
    turns_loop = [3e-6, -0.5e-6, 0.9e-6, -0.5e-6, -3e-6]
    turns_direct = [3e-6, -0.5e-6, -3e-6]
    t1, v1 = path(turns_loop, v, dt)
    t2, v2 = path(turns_direct, v, dt)
    _, f1 = gms_states(P, t1, v1)
    _, f2 = gms_states(P, t2, v2)
    # the displacement the law sees (velocity linear between the samples)
    x1 = np.concatenate([[0.0], np.cumsum(0.5 * dt * (v1[:-1] + v1[1:]))])
    # against the play operators (quasi-static, s at the loading speed)
    quasi = play_operator(P, x1, stribeck(P, v)) + P.sigma2 * v1
    assert_allclose(f1, quasi, atol=2e-3 * P.fs)
    # non-local memory: the force at x = 0.2 um differs on the inner loop's two branches
    up = np.flatnonzero((np.abs(x1 - 0.2e-6) < 0.5 * v * dt) & (v1 > 0))
    down = np.flatnonzero((np.abs(x1 - 0.2e-6) < 0.5 * v * dt) & (v1 < 0))
    assert f1[up[0]] - f1[down[-1]] > 0.2 * P.fs
    # wiping-out: the last leg from -0.5 um equals the direct path's
    n_tail = round(2.5e-6 / (v * dt))
    assert_allclose(f1[-n_tail:], f2[-n_tail:], atol=1e-6 * P.fs)
    # and the inner loop closed: at its end the force is the one where it began
    turns = np.flatnonzero(np.diff(np.sign(v1)) != 0) + 1
    assert len(turns) == 3                                # at +3, -0.5 and +0.9 um
    # (compared with the last sample before the reversal, moving the same way; the reversal's
    # sample interval leaves the sticking elements v dt / 4 = 5e-11 m apart from x)
    closed = turns[2] + np.argmin(np.abs(x1[turns[2]:] - x1[turns[1]]))
    assert_allclose(x1[closed], x1[turns[1] - 1], atol=1e-15)
    assert_allclose(f1[closed], f1[turns[1] - 1], atol=1e-4 * P.fs)
    assert abs(f1[turns[2]] - f1[turns[1]]) > 0.3 * P.fs


@pytest.mark.parametrize("delta", [1.0, 2.0])
@pytest.mark.parametrize("speed", [-0.03, -0.002, 0.001, 0.01, 0.05])
def test_steady_sliding_follows_the_stribeck_curve(speed, delta):
    p = dataclasses.replace(P_DAMPED, delta=delta)
    law = GMSFriction(p)
    expected = math.copysign(stribeck(p, speed), speed) + p.sigma2 * speed
    # on the periodic orbit of a constant velocity, and after a start from the virgin state
    assert_allclose(law.periodic_force(np.full(8, speed), 0.01), expected, rtol=1e-12)
    t = np.linspace(0.0, 0.01, 101)
    _, force = gms_states(p, t, np.full(t.size, speed))
    assert_allclose(force[-1], expected, rtol=1e-12)


def test_linear_contacts_are_the_stick_and_slip_tangents():
    law = GMSFriction(P_DAMPED)
    p = P_DAMPED
    assert law.presliding() == (sum(p.stiffness), sum(p.damping) + p.sigma2)
    for v0 in (0.004, -0.004, 0.03):
        sys = law.sliding_system(v0)
        # DC gain: the slope of the steady Stribeck curve (central difference of the formula)
        h = 1e-7
        slope = ((math.copysign(stribeck(p, v0 + h), v0) - math.copysign(stribeck(p, v0 - h),
                                                                          v0)) / (2 * h)
                 + p.sigma2)
        assert_allclose(float(sys.dcgain()), slope, rtol=1e-6)
        # each slipping element relaxes with the time constant Delta_i(v0) / C
        widths = np.array(p.fractions) * stribeck(p, v0) / np.array(p.stiffness)
        assert_allclose(np.sort(np.linalg.eigvals(sys.A).real), np.sort(-p.attraction / widths),
                        rtol=1e-12)
    with pytest.raises(ValueError, match="non-zero speed"):
        law.sliding_system(0.0)


def test_describing_function_at_small_amplitude_is_the_presliding_contact():
    # below every slip deflection all elements stick: Keq = sum k_i, Ceq = sum sigma1_i + sigma2
    law = GMSFriction(P_DAMPED)
    ceq, keq = law.describing_function(1e-8, 2 * math.pi * 50.0)
    k, c = law.presliding()
    # (to the midpoint rule of the sub-steps over the sampled period, ~(w h)^2 / 24)
    assert_allclose(keq, k, rtol=1e-7)
    assert_allclose(ceq, c, rtol=1e-7)
    # above them, slowly (rate terms negligible), the elements that slip dissipate the area of
    # their parallelogram loops, 4 k_i Delta_i (A - Delta_i) per cycle
    law = GMSFriction(P)
    amp, w = 1.2e-6, 2 * math.pi * 1.0
    ceq, keq = law.describing_function(amp, w, n_samples=1024)
    widths = np.array(P.slip_deflections(0.0))
    slips = widths < amp
    energy = float(np.sum(4 * np.array(P.stiffness)[slips] * widths[slips]
                          * (amp - widths[slips]))) + P.sigma2 * math.pi * w * amp**2
    assert_allclose(ceq, energy / (math.pi * w * amp**2), rtol=2e-3)
    assert 0 < keq < 0.8 * sum(P.stiffness)


@pytest.mark.parametrize("speed", [0.0, 0.02, -0.004])
def test_pad_block_and_remainders_give_the_law(speed):
    # the linear block with the compiled remainders fed in reproduces the element rates and
    # the force written out from the papers, at random states, about any operating point
    law = GMSFriction(P_DAMPED)
    p = P_DAMPED
    n_pads = 4
    share = p.scaled(1.0 / n_pads)
    block = law.pad_block("pad1.x", n_pads, speed)
    assert block.input_labels == ["v_pad1_x", "r1_pad1_x", "r2_pad1_x", "r3_pad1_x",
                                  "r4_pad1_x", "one"]
    params = law.remainder_parameters(speed)
    rng = np.random.default_rng(3)
    widths = np.array(p.slip_deflections(0.0))
    for _ in range(40):
        v = rng.uniform(-4, 4) * p.vs
        z = rng.uniform(-1.1, 1.1, 4) * widths
        r = [gms_remainder(i, v, z[i], params)[0] for i in range(4)]
        u = np.array([v, *r, 1.0])
        zdot = block.A @ z + block.B @ u
        rates = [element_rate(p, i, v, z[i]) for i in range(4)]
        assert_allclose(zdot, rates, rtol=1e-9, atol=1e-12 * p.vs)
        force = float(block.C[1] @ z + block.D[1] @ u)
        expected = float(np.dot(share.stiffness, z) + np.dot(share.damping, rates)
                         + share.sigma2 * v)
        assert_allclose(force, expected, rtol=1e-9, atol=1e-9 * share.fs)
        # the remainders' partial derivatives against central differences
        for i in range(4):
            _, dv, dz = gms_remainder(i, v, z[i], params)
            hv, hz = 1e-9 * p.vs, 1e-9 * widths[i]
            fd_v = (gms_remainder(i, v + hv, z[i], params)[0]
                    - gms_remainder(i, v - hv, z[i], params)[0]) / (2 * hv)
            fd_z = (gms_remainder(i, v, z[i] + hz, params)[0]
                    - gms_remainder(i, v, z[i] - hz, params)[0]) / (2 * hz)
            assert_allclose(dv, fd_v, rtol=1e-4, atol=1e-6)
            assert_allclose(dz, fd_z, rtol=1e-4, atol=1e-3 * p.attraction / widths[i])


def test_periodic_force_is_the_limit_of_a_long_time_integration():
    # x = A sin(w t) from the virgin state, integrated by LSODA with the element law written out
    # for 6 periods (elements 1-2 slip, 3-4 stick); the last period against the orbit
    p = P_DAMPED
    law = GMSFriction(p)
    amp, w = 1.0e-6, 2 * math.pi * 40.0
    period = 2 * math.pi / w
    n = 128

    def velocity(t):
        return amp * w * math.cos(w * t)

    def rhs(t, z):
        return [element_rate(p, i, velocity(t), z[i]) for i in range(4)]

    t_eval = 5 * period + period * np.arange(n) / n
    sol = solve_ivp(rhs, (0.0, 6 * period), np.zeros(4), method="LSODA", t_eval=t_eval,
                    rtol=1e-10, atol=1e-18, max_step=period / 400)
    v = amp * w * np.cos(w * t_eval)
    reference = np.array([
        np.dot(p.stiffness, z) + sum(p.damping[i] * element_rate(p, i, vv, z[i])
                                     for i in range(4)) + p.sigma2 * vv
        for vv, z in zip(v, sol.y.T, strict=True)])
    share = 0.25
    got = law.periodic_force(v, period, share)
    assert_allclose(got, share * reference, atol=2e-4 * share * p.fs)
    # elements 3 and 4 stick through the cycle, 1 and 2 slip: the orbit is not linear
    widths = np.array(p.slip_deflections(0.0))
    assert widths[1] < amp < widths[2]


def test_the_axis_file_selects_the_law(tmp_path):
    from servotune.analysis import axis_contact
    from servotune.axis import AxisFormatError, load_axis

    folder = tmp_path / "axis"
    shutil.copytree("models/paper_x_axis", folder)
    # a variation of the identified LuGre set has no meaning for a GMS law: left out
    text = re.sub(r"variation = \{[^}]*\}[^\n]*\n(\s+#[^\n]*\n)*", "",
                  (folder / "axis.toml").read_text())
    start = text.index("[friction.lugre]")
    end = text.index("[drive]")
    table = "\n".join(f"{k} = {v!r}" for k, v in (
        ("stiffness", list(P.stiffness)), ("fractions", list(P.fractions)),
        ("damping", list(P.damping)), ("fc", P.fc), ("fs", P.fs), ("vs", P.vs),
        ("delta", P.delta), ("sigma2", P.sigma2), ("attraction", P.attraction)))
    (folder / "axis.toml").write_text(text[:start] + "[friction.gms]\n" + table + "\n\n"
                                      + text[end:])
    axis = load_axis(folder)
    assert axis.friction.law == GMSFriction(P)
    assert friction_law("gms") is GMSFriction
    stiction = axis_contact(axis, "stiction")
    assert (stiction.stiffness, stiction.damping) == (sum(P.stiffness), P.sigma2)
    sliding = axis_contact(axis, "sliding", speed=0.03)
    assert sliding.system.nstates == P.n_elements
    (folder / "axis.toml").write_text(text[:start] + 'gms = "nonsense"\n\n' + text[end:])
    with pytest.raises(AxisFormatError, match=r"\[friction\] gms.*unknown GMS set 'nonsense'"):
        load_axis(folder)


def test_bundled_axis_simulated_with_gms_keeps_to_the_periodic_orbit():
    # the paper's axis (continuous drive) moved sinusoidally, 20 um in 0.1 s, with the GMS law
    # at its four pads: the pad force of the last period against the law's own periodic orbit
    # under the pad velocity the simulation recorded
    from servotune.axis import load_axis
    from servotune.simulate import NonlinearAxis, simulate, sinusoid
    from servotune.simulate.setup import axis_setup

    setup = axis_setup(load_axis("models/paper_x_axis").with_continuous_drive())
    law = GMSFriction(P)
    axis = NonlinearAxis(setup.structure, setup.drive, setup.pads, law)
    period, record = 0.1, 2.5e-4
    run = simulate(axis, sinusoid(20e-6, period, 4), record_step=record)
    assert run.friction == "gms"
    n = round(period / record)
    share = P.fs / len(setup.pads)
    for pad in setup.pads:
        name = pad.replace(".", "_")
        v = run.signals[f"v_{name}"][-n:]
        force = run.signals[f"F_{name}"][-n:]
        orbit = law.periodic_force(v, period, 1.0 / len(setup.pads))
        err = np.abs(force - orbit)
        assert err.max() < 0.05 * share
        assert np.sqrt(np.mean(err**2)) < 0.01 * share
        assert np.abs(force).max() > 0.95 * share          # the pads slide: all elements slip


def test_simulation_with_four_remainders_per_pad_matches_lsoda():
    # the integrator with one remainder per element (8 on two pads) against LSODA on the same
    # equations (linear part of axis_system, remainders of the law), the pads slipping
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from axis_fixtures import PADS, small_axis, small_drive

    from servotune.simulate import NonlinearAxis, axis_system, simulate, sine_sweep

    law = GMSFriction(P_DAMPED)
    drive = small_drive(velocity_feedforward=1.0)
    scenario = sine_sweep(20000.0, 40.0, 40.0, 0.05)
    run = simulate(NonlinearAxis(small_axis(), drive, PADS, law), scenario, record_step=2.5e-4)
    sysm = axis_system(small_axis(), drive, law, PADS, 0.0, inputs=["f_wp_x", "one"])
    a, b = sysm.system.A, sysm.system.B
    params = law.remainder_parameters(0.0)
    force = scenario.forces["wp.x"]

    def rhs(t, x):
        v, z = sysm.remainder_velocity @ x, sysm.remainder_state @ x
        r = [gms_remainder(k // len(PADS), v[k], z[k], params)[0] for k in range(v.size)]
        return a @ x + b[:, 0] * float(force(t)) + b[:, 1] + b[:, 2:] @ np.array(r)

    sol = solve_ivp(rhs, (0.0, 0.05), np.zeros(a.shape[0]), method="LSODA", rtol=1e-9,
                    atol=1e-15, t_eval=run.t)
    wp = sysm.system.C[sysm.outputs.index("wp_x")] @ sol.y
    # element 1 slips (its deflection reaches its slip level)
    assert np.abs(run.signals["z1_pad1_x"]).max() > 0.9 * P_DAMPED.slip_deflections()[0]
    assert_allclose(run.signals["wp_x"], wp, atol=1e-3 * np.abs(wp).max())
