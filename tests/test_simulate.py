"""The nonlinear simulation against scipy's stiff solvers, python-control's plant, closed forms
(steady-state friction, linear compliance) and its own energy balance."""

import dataclasses
import math
import pickle

import numpy as np
import pytest
import scipy.linalg
from axis_fixtures import PADS, small_axis, small_drive
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp

from servotune.frequency import fast_frequency_response, peak, port_compliance
from servotune.friction import LuGreParameters, sliding_linearisation, steady_state_friction
from servotune.plant import Contact, build_plant
from servotune.simulate import (
    LuGreFriction,
    NonlinearAxis,
    SimulationError,
    ViscousFriction,
    axis_system,
    circle,
    constant_speed,
    custom,
    point_to_point,
    simulate,
    sine_sweep,
    sinusoid,
)
from servotune.simulate.integrator import phi_functions
from servotune.simulate.reference import ode_model

P = LuGreParameters.named("bianchi2014")
OMEGA = 2 * np.pi * np.geomspace(5.0, 2000.0, 200)


def lugre_axis(drive=None):
    return NonlinearAxis(small_axis(), drive or small_drive(velocity_feedforward=1.0), PADS,
                         LuGreFriction(P))


def response(sys, inp="f_wp_x", out="wp_x"):
    return fast_frequency_response(sys, OMEGA, inputs=[inp], outputs=[out]).complex.ravel()


# ---------------------------------------------------------------- the linear part

@pytest.mark.parametrize("speed", [0.0, 0.03])
def test_linear_part_is_build_plants_linearised_axis(speed):
    # r = 0: the LuGre law about rest is the stiction contact, about v0 the sliding one
    sysm = axis_system(small_axis(), small_drive(), LuGreFriction(P), PADS, speed,
                       inputs=["x_ref", "v_ref", "a_ref", "f_wp_x", "t_dist"])
    contact = (Contact.stiction(P.sigma0, P.sigma1, P.sigma2) if speed == 0.0
               else Contact.sliding(sliding_linearisation(P, speed)))
    plant = build_plant(small_axis(), small_drive(), contact, PADS)
    for inp, out in (("f_wp_x", "wp_x"), ("x_ref", "slide_x"), ("f_wp_x", "torque")):
        assert_allclose(response(sysm.system, inp, out), response(plant, inp, out), rtol=1e-7)


def test_viscous_pads_are_build_plants_viscous_contact():
    sysm = axis_system(small_axis(), small_drive(), ViscousFriction(5578.0), PADS)
    plant = build_plant(small_axis(), small_drive(), Contact.viscous(5578.0), PADS)
    assert_allclose(response(sysm.system), response(plant), rtol=1e-9)


def test_phi_functions_against_the_augmented_exponential():
    rng = np.random.default_rng(1)
    z = np.concatenate([rng.normal(size=20) * 0.3 + 1j * rng.normal(size=20) * 0.3,
                        -rng.uniform(0, 1e5, 10) + 1j * rng.normal(size=10) * 100])
    got = phi_functions(z)
    for zz, g in zip(z, got, strict=True):
        m = np.zeros((5, 5), complex)
        m[0, 0] = zz
        m[0, 1] = m[1, 2] = m[2, 3] = m[3, 4] = 1
        assert_allclose(g, scipy.linalg.expm(m)[0, 1:], rtol=1e-12, atol=1e-300)


# ---------------------------------------------------------------- against scipy

def test_linear_axis_matches_a_tight_scipy_solution():
    # viscous pads: the integrator is exact up to the cubic interpolation of the force
    axis = NonlinearAxis(small_axis(), small_drive(), PADS, ViscousFriction(5578.0))
    sc = sine_sweep(200.0, 60.0, 140.0, 0.2)
    ode = ode_model(axis, sc)
    sol = solve_ivp(ode.rhs, (0, 0.2), np.zeros(ode.n), method="LSODA", rtol=1e-11,
                    atol=1e-16, t_eval=[0.1, 0.2])
    r = simulate(axis, sc, step=2.5e-4, record_step=5e-4)
    for k, t in enumerate((0.1, 0.2)):
        i = round(t / 5e-4)
        ref = ode.outputs(t, sol.y[:, k])
        assert_allclose(r["wp_x"][i], ref[ode.output_names.index("wp_x")], rtol=1e-6)
    # the works: trapezoidal quadrature of the powers, error h^2/12 times the change of their
    # slope (the start-up transient rings at kHz)
    assert_allclose(r.work[-1], sol.y[-4:, -1], rtol=2e-4)


def test_lugre_with_sliding_pads_matches_scipy_lsoda():
    # 4 kN p-p near 110 Hz: the pads slip (|v| ~ 0.02 m/s), the hard case for the friction
    axis = lugre_axis(small_drive())
    sc = sine_sweep(4000.0, 100.0, 120.0, 0.05)
    ode = ode_model(axis, sc)
    sol = solve_ivp(ode.rhs, (0, 0.05), np.zeros(ode.n), method="LSODA", jac=ode.jac,
                    rtol=1e-8, atol=1e-14)
    ref_works = sol.y[-4:, -1]
    r = simulate(axis, sc)
    assert np.abs(r["v_pad1_x"]).max() > P.vs           # really sliding
    # energies within 0.5 % of the reference (the accuracy requirement)
    assert_allclose(r.work[-1], ref_works, rtol=5e-3)
    ref_out = ode.outputs(0.05, sol.y[:, -1])
    assert_allclose(r["wp_x"][-1], ref_out[ode.output_names.index("wp_x")], rtol=5e-3)


def test_tighter_tolerance_converges():
    axis = lugre_axis(small_drive())
    sc = sine_sweep(4000.0, 100.0, 120.0, 0.05)
    works = [simulate(axis, sc, tolerance=tol).work[-1] for tol in (1e-3, 1e-4, 1e-7)]
    err = [np.abs(w - works[-1]).max() / np.abs(works[-1]).max() for w in works[:2]]
    assert err[1] < err[0] / 3
    assert err[1] < 5e-3


# ---------------------------------------------------------------- energy and closed forms

@pytest.mark.parametrize("force_pp, speed", [(2000.0, 0.0), (200.0, 0.03)])
def test_energy_balance_residual_is_below_a_thousandth(force_pp, speed):
    r = simulate(lugre_axis(), sine_sweep(force_pp, 40.0, 160.0, 1.0, speed=speed),
                 window=(0.5,))
    e = r.energies(0.5, 1.0)
    assert e.relative_residual < 1e-3
    assert e.damping < 0 and e.friction < 0


def test_moving_friction_work_is_steady_friction_times_distance():
    # remark B on the small axis: constant speed 30 mm/s, 0.5 s window
    v = 0.03
    r = simulate(lugre_axis(), constant_speed(v, 1.0), window=(0.5,))
    e = r.energies(0.5, 1.0)
    expect = -float(steady_state_friction(P, v)) * v * 0.5
    assert e.friction == pytest.approx(expect, rel=2e-3)
    assert e.motor == pytest.approx(-e.friction - e.damping + e.structure_change, rel=1e-3)
    assert e.motor == pytest.approx(-expect, rel=0.02)


def test_presliding_sweep_envelope_is_the_linear_compliance():
    # tiny force: the pads stay in presliding, so the slow sweep's envelope is the closed-loop
    # compliance with the stiction contact (sweep-rate effects below 2 %)
    r = simulate(lugre_axis(), sine_sweep(2.0, 90.0, 130.0, 4.0))
    env = r.sweep_envelope(t_min=0.5)
    omega = 2 * np.pi * np.linspace(90, 130, 2000)
    h = port_compliance(small_axis(), omega, small_drive(),
                        Contact.stiction(P.sigma0, P.sigma1, P.sigma2), PADS)[0]
    mag, w = peak(omega, h)
    assert env.resonance == pytest.approx(w, rel=0.01)
    assert env.peak == pytest.approx(mag, rel=0.03)


# ---------------------------------------------------------------- usability

def test_failure_raises_with_the_partial_result():
    with pytest.raises(SimulationError, match="failed at t =") as info:
        simulate(lugre_axis(), constant_speed(0.03, 0.5), tolerance=1e-15)
    err = info.value
    assert err.result is not None and not err.result.complete
    assert 0.0 <= err.time < 0.5
    assert err.result.t[-1] <= err.time + 1e-12


def test_progress_is_reported_and_results_pickle():
    seen = []
    r = simulate(lugre_axis(), sine_sweep(50.0, 50.0, 60.0, 0.2),
                 progress=lambda t, total: seen.append((t, total)))
    assert seen[-1] == (pytest.approx(0.2), 0.2)
    assert pickle.loads(pickle.dumps(r)).signals.keys() == r.signals.keys()


@pytest.mark.parametrize("bad, match", [
    (dict(step=-1.0), "step"), (dict(record_step=3.3e-4), "multiple"),
    (dict(tolerance=0.0), "tolerance")])
def test_bad_arguments_are_clear_errors(bad, match):
    with pytest.raises(ValueError, match=match):
        simulate(lugre_axis(), sine_sweep(50.0, duration=0.1), **bad)


def test_force_on_a_missing_dof_is_refused():
    with pytest.raises(ValueError, match="wp_y"):
        simulate(lugre_axis(), sine_sweep(50.0, duration=0.1, dof="wp.y"))


# ---------------------------------------------------------------- scenarios

@pytest.mark.parametrize("scenario", [
    point_to_point([0.0, 0.01, -0.005], speed=0.05, acceleration=1.0, dwell=0.05),
    sinusoid(10e-6, 3.7), circle(20e-6, 2.0), constant_speed(0.03, 1.0)])
def test_scenario_velocity_and_acceleration_are_derivatives(scenario):
    t = np.linspace(0, scenario.duration, 40001)
    x, v, a = scenario.motion(t)
    assert x[0] == 0.0 and v[0] == pytest.approx(0.0, abs=1e-12)
    assert_allclose(np.gradient(x, t), v, atol=2e-3 * np.abs(v).max())
    smooth = np.ones_like(a, dtype=bool)      # away from the jumps of a trapezoidal profile
    smooth[1:-1] = (a[:-2] == a[1:-1]) & (a[1:-1] == a[2:]) | (np.abs(np.diff(a, 2)) < 1e-3)
    smooth[[0, -1]] = False
    assert_allclose(np.gradient(v, t)[smooth], a[smooth], atol=2e-2 * np.abs(a).max())


def test_point_to_point_ends_at_the_last_point():
    sc = point_to_point([0.0, 0.01, -0.005], speed=0.05, acceleration=1.0)
    x, v, _ = sc.motion(np.array([sc.duration]))
    assert x[0] == pytest.approx(-0.005) and v[0] == pytest.approx(0.0, abs=1e-12)


def test_custom_scenario_and_sinusoid_follow_the_reference():
    def x_ref(t):
        return 1e-5 * np.sin(2 * np.pi * t) ** 2

    r = simulate(lugre_axis(), custom(1.0, x_ref=x_ref, forces={"wp.x": np.sin}))
    assert_allclose(r["x_ref"], x_ref(r.t), atol=1e-20)
    assert_allclose(r["f_wp_x"], np.sin(r.t), atol=1e-15)
    # the slide follows within the following error of a 1e-5 m, 2 Hz move without feed-forward
    assert np.abs(r["slide_x"] - r["x_ref"]).max() < 2 * (2 * np.pi * 2 * 1e-5) / small_drive().kv
    r2 = simulate(lugre_axis(), dataclasses.replace(sinusoid(10e-6, 0.5), duration=1.0))
    assert r2["x_ref"].max() == pytest.approx(20e-6, rel=1e-3)
    assert math.isfinite(r2.energies(0.5, 1.0).relative_residual)


def test_figures_are_drawn(tmp_path):
    from servotune import plots
    r = simulate(lugre_axis(), sine_sweep(3000.0, 90.0, 130.0, 0.6))
    for kind in ("envelope", "energies", "hysteresis"):
        fig = r.plot(kind)
        assert fig.axes[0].has_data()
        fig.savefig(tmp_path / f"{kind}.png")
    assert plots.plot_sweep_envelope([r.sweep_envelope()], labels=["lg"]).axes


# ---------------------------------------------------------------- velocity-dependent micro-damping

P_VD = dataclasses.replace(P, sigma1_decay_speed=0.01)


@pytest.mark.parametrize("speed", [0.0, 0.03, -0.004])
def test_micro_damping_law_gives_the_lugre_force_and_bristle_rate(speed):
    # the compiled remainders fed into the pad block reproduce the numpy model of
    # servotune.friction (force and dz/dt) at random states, whatever the operating point
    from servotune.friction import lugre_derivative, lugre_force
    law = LuGreFriction(P_VD)
    remainder = law.remainder()
    assert law.n_remainders == 2
    n_pads = 4
    block = law.pad_block("pad1.x", n_pads, speed)
    assert block.input_labels == ["v_pad1_x", "r_pad1_x", "q_pad1_x", "one"]
    p = law.remainder_parameters(speed)
    rng = np.random.default_rng(5)
    for _ in range(40):
        v = rng.uniform(-4, 4) * P.vs
        z = rng.uniform(-1.2, 1.2) * P.fs / P.sigma0
        r = remainder(0, v, z, p)[0]
        q = remainder(1, v, z, p)[0]
        u = np.array([v, r, q, 1.0])
        zdot = float(block.A[0, 0] * z + block.B[0] @ u)
        force = float(block.C[1, 0] * z + block.D[1] @ u)
        share = P_VD.scaled(1.0 / n_pads)
        assert_allclose(zdot, lugre_derivative(share, z, v), rtol=1e-9, atol=1e-12 * P.vs)
        assert_allclose(force, lugre_force(share, z, v), rtol=1e-9, atol=1e-9 * share.fs)
        assert_allclose(law.friction_force(v, z), lugre_force(P_VD, z, v), rtol=1e-14)


def test_micro_damping_remainder_derivatives_match_central_differences():
    law = LuGreFriction(P_VD)
    remainder = law.remainder()
    rng = np.random.default_rng(6)
    for speed in (0.0, 0.03):
        p = law.remainder_parameters(speed)
        for _ in range(30):
            v = rng.uniform(-4, 4) * P.vs
            z = rng.uniform(-1.2, 1.2) * P.fs / P.sigma0
            hv, hz = 1e-7 * P.vs, 1e-7 * P.fs / P.sigma0
            for comp in (0, 1):
                _, dv, dz = remainder(comp, v, z, p)
                fd_v = (remainder(comp, v + hv, z, p)[0]
                        - remainder(comp, v - hv, z, p)[0]) / (2 * hv)
                fd_z = (remainder(comp, v, z + hz, p)[0]
                        - remainder(comp, v, z - hz, p)[0]) / (2 * hz)
                assert_allclose(dv, fd_v, rtol=1e-5, atol=1e-6)
                assert_allclose(dz, fd_z, rtol=1e-5, atol=1e-6 * P.sigma0 * P.vs / P.fs)


def test_linear_part_with_micro_damping_is_the_sliding_linearisation():
    sysm = axis_system(small_axis(), small_drive(), LuGreFriction(P_VD), PADS, 0.03,
                       inputs=["x_ref", "v_ref", "a_ref", "f_wp_x", "t_dist"])
    plant = build_plant(small_axis(), small_drive(),
                        Contact.sliding(sliding_linearisation(P_VD, 0.03)), PADS)
    for inp, out in (("f_wp_x", "wp_x"), ("x_ref", "slide_x")):
        assert_allclose(response(sysm.system, inp, out), response(plant, inp, out), rtol=1e-7)


def test_micro_damping_with_sliding_pads_matches_scipy_lsoda():
    # as the constant-sigma1 case above; the reference ODE takes the law from
    # servotune.friction (numpy), not from the compiled remainders
    axis = NonlinearAxis(small_axis(), small_drive(velocity_feedforward=1.0), PADS,
                         LuGreFriction(P_VD))
    sc = sine_sweep(4000.0, 100.0, 120.0, 0.03)
    ode = ode_model(axis, sc)
    # rtol 1e-6 agrees with rtol 1e-8 to 1e-6 of every work here (measured), far inside 0.5 %
    sol = solve_ivp(ode.rhs, (0, 0.03), np.zeros(ode.n), method="LSODA", jac=ode.jac,
                    rtol=1e-6, atol=1e-12)
    r = simulate(axis, sc, window=(0.015,))
    assert np.abs(r["v_pad1_x"]).max() > P.vs
    assert_allclose(r.work[-1], sol.y[-4:, -1], rtol=5e-3)
    assert r.energies(0.015, 0.03).relative_residual < 1e-3


def test_huge_decay_speed_simulates_as_the_constant_sigma1():
    sc = sine_sweep(3000.0, 90.0, 130.0, 0.2, speed=0.03)
    huge = dataclasses.replace(P, sigma1_decay_speed=1e9)
    a = simulate(lugre_axis(), sc)
    b = simulate(NonlinearAxis(small_axis(), small_drive(velocity_feedforward=1.0), PADS,
                               LuGreFriction(huge)), sc)
    assert_allclose(b.work, a.work, rtol=1e-7, atol=1e-9 * np.abs(a.work).max())
    assert_allclose(b["wp_x"], a["wp_x"], rtol=1e-7, atol=1e-9 * np.abs(a["wp_x"]).max())


def test_a_move_with_feedforwards_matches_the_scipy_reference():
    # a constant-speed move: the references are zero where the scenario leaves them out
    # (the acceleration once the speed is reached); both feed-forwards are on, so a reference
    # read wrongly would drive the reference ODE away from the simulator
    from servotune.simulate.scenario import constant_speed

    drive = small_drive(velocity_feedforward=1.0, torque_feedforward_inertia=0.01)
    axis = NonlinearAxis(small_axis(), drive, PADS, ViscousFriction(5578.0))
    sc = constant_speed(0.03, 0.3)
    ode = ode_model(axis, sc)
    sol = solve_ivp(ode.rhs, (0, 0.3), np.zeros(ode.n), method="LSODA", rtol=1e-10,
                    atol=1e-15, t_eval=[0.3])
    r = simulate(axis, sc, step=2.5e-4, record_step=2.5e-4)
    ref = ode.outputs(0.3, sol.y[:, -1])
    for name in ("slide_x", "wp_x"):
        assert_allclose(r[name][-1], ref[ode.output_names.index(name)], rtol=1e-5)
    assert r["slide_x"][-1] > 0.003      # it moved: about 0.03 m/s for most of 0.3 s
