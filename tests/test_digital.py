"""servotune.digital against references written from the conventions alone.

The references (``tests/sampled_reference.py``) never call servotune.digital: the axis is
assembled from the structure's M, K, D matrices, discretised with ``scipy.linalg.expm``, and
the drive is the conventions' difference equations iterated sample by sample (zero-order hold
of the voltage, each controller's output applied d of its periods after its sample and held,
slower controllers first at a shared instant, PI by forward Euler or Tustin, speed as the
backward difference of the sampled angle with its first-order filter). Where a closed form
exists (the PI, the prewarped Tustin filter, the zero-order hold of a rigid inertia behind its
winding) it is written out by hand.
"""

import dataclasses
import math
from pathlib import Path

import control
import numpy as np
import pytest
from axis_fixtures import PADS, RATIO, small_axis, small_drive
from numpy.testing import assert_allclose
from sampled_reference import (
    DigitalLoop,
    growth_per_frame,
    largest_stable,
    margins,
    open_plant,
    pi_sequence,
    pi_z,
    speed_z,
    velocity_loop,
    with_cosine_force,
    zoh,
)

from servotune.digital import SampledAxis, discrete_filter, discrete_pi
from servotune.drive import LowPassFilter, Motor, NotchFilter, PIController, Sampling
from servotune.plant import Contact
from servotune.structure import ModalModel

# ------------------------------------------------------------------------ the small axis

#: Sampling set-ups: the industrial default (one rate for current and speed, position 8x
#: slower); a multi-rate drive (speed 2x, position 8x the current period) with a speed filter
#: and Tustin integrals; two periods of computation delay at every level; torque set-point
#: filters (a low-pass and a notch on the 410 Hz mode) in the current controller.
CONFIGS = {
    "s120": (Sampling(), {}),
    "multirate": (Sampling(100e-6, 200e-6, 800e-6, computation_delay=1, speed_filter=3e-4,
                           integral_rule="tustin"), {}),
    "delay2": (Sampling(125e-6, 250e-6, 1e-3, computation_delay=2),
               {"current_loop": PIController(5.0, 2e-3)}),
    "filters": (Sampling(125e-6, 250e-6, 1e-3, integral_rule="tustin"),
                {"lowpass": LowPassFilter(1200.0, 0.7),
                 "notches": (NotchFilter(410.0, width=0.5, depth=0.1),
                             NotchFilter(950.0, width=0.3, depth=0.2))}),
}
MODELS = Path(__file__).resolve().parents[1] / "models"
CONTACT = Contact.viscous(2e4)  # viscous guide ways [N s/m], shared by the two pads


def small(config: str, kp_scale: float = 1.0, kv_scale: float = 1.0):
    """The flexible six-DOF axis of ``axis_fixtures`` with a sampled drive."""
    sampling, changes = CONFIGS[config]
    drive = small_drive(sampling=sampling, **changes)
    vel = drive.velocity_loop
    return dataclasses.replace(drive, kv=drive.kv * kv_scale,
                               velocity_loop=PIController(vel.kp * kp_scale, vel.ti))


def reference_loop(drive, position_loop=True, plant=None) -> DigitalLoop:
    """The brute-force drive on the small axis (own plant, own zero-order hold)."""
    plant = open_plant(small_axis(), drive, CONTACT, PADS) if plant is None else plant
    ad, bd = zoh(plant.a, plant.b_u, drive.sampling.current_period)
    return DigitalLoop(ad, bd, plant.c_meas, drive, position_loop)


def sampled(drive) -> SampledAxis:
    return SampledAxis(small_axis(), drive, CONTACT, PADS)


# ------------------------------------------------------------------------ 1. controllers


@pytest.mark.parametrize("ti", [7e-3, math.inf])
@pytest.mark.parametrize("rule", ["forward_euler", "tustin"])
def test_discrete_pi_is_its_difference_equation(rule, ti):
    """Reference: the loop u_k = Kp (e_k + (T/Ti) S_k) (forward Euler) or
    Kp (e_k + (T/Ti) (S_k + e_k/2)) (Tustin), S_k = sum_{j<k} e_j, on a seeded random error
    sequence; the discrete block simulated by python-control's forced_response."""
    rng = np.random.default_rng(7)
    e = rng.standard_normal(400)
    kp, period = 2.5, 1e-3
    block = discrete_pi(PIController(kp, ti), period, rule, "e", "u", "pi")
    u = np.asarray(control.forced_response(block, U=e).outputs).reshape(-1)
    ref = pi_sequence(kp, ti, period, rule, e)
    # the same sums in another order: rounding of a few eps of the largest |u| only
    assert_allclose(u, ref, rtol=0, atol=1e-12 * np.abs(ref).max())


@pytest.mark.parametrize("f", [LowPassFilter(700.0, 0.6), NotchFilter(900.0, 0.5, 0.1)],
                         ids=["lowpass", "notch"])
def test_setpoint_filter_is_prewarped_tustin(f):
    """Reference: the bilinear substitution s = (w0/tan(w0 T/2)) (z - 1)/(z + 1) into the
    filter written by hand (Astrom-Wittenmark sec 8.2), so the response at w0 is the
    continuous one exactly."""
    period, w0 = 125e-6, 2 * math.pi * f.f_hz
    block = discrete_filter(f.transfer_function(), period, w0, "a", "b", "filter")
    w = 2 * math.pi * np.array([10.0, 300.0, f.f_hz, 1500.0, 3500.0])
    z = np.exp(1j * w * period)
    s = w0 / math.tan(0.5 * w0 * period) * (z - 1) / (z + 1)
    if isinstance(f, LowPassFilter):
        ref = w0**2 / (s**2 + 2 * f.damping_ratio * w0 * s + w0**2)
    else:
        zp = 0.5 * f.width
        ref = (s**2 + 2 * zp * f.depth * w0 * s + w0**2) / (s**2 + 2 * zp * w0 * s + w0**2)
    a, b, c, d = (np.atleast_2d(np.asarray(m, dtype=float)) for m in
                  (block.A, block.B, block.C, block.D))
    got = np.array([(c @ np.linalg.solve(zk * np.eye(a.shape[0]) - a, b) + d)[0, 0]
                    for zk in z])
    assert_allclose(got, ref, rtol=1e-9)
    assert abs(got[2]) == pytest.approx(abs(ref[2]), rel=1e-9)  # 1 / depth at w0


@pytest.mark.parametrize("config", list(CONFIGS))
def test_controller_with_references_is_the_difference_equations(config):
    """Reference: the brute-force drive (own difference equations, own plant and hold) with
    the velocity and torque feed-forwards, driven by seeded random references x_ref, v_ref,
    a_ref. DigitalController.step on the same plant gives the same voltages, and the
    closed-loop maps of sample_maps, iterated, the same plant states (to rounding)."""
    drive = dataclasses.replace(small(config), velocity_feedforward=0.7,
                                torque_feedforward_inertia=0.01)
    plant = open_plant(small_axis(), drive, CONTACT, PADS)
    loop = reference_loop(drive, plant=plant)
    refs = np.random.default_rng(11).standard_normal((5 * loop.frame, 3)) * [1e-4, 1e-2, 1.0]
    z = np.zeros((loop.size, 1))
    voltages, states = [], []
    for k, r in enumerate(refs):
        loop.step(z, k, references=r)
        voltages.append(z[loop.slices["voltage"], 0][0])
        states.append(z[loop.slices["plant"], 0].copy())
    ctl = sampled(drive).controller
    x = np.zeros(plant.a.shape[0])
    level_states = [np.zeros(lv.a.shape[0]) for lv in ctl.levels]
    held = np.zeros(len(ctl.levels))
    got = []
    for k, r in enumerate(refs):
        ctl.step(k, level_states, held, plant.c_meas @ x, r)
        got.append(held[-1])
        x = loop.ad @ x + loop.bd * held[-1]
    assert_allclose(got, voltages, rtol=0, atol=1e-12 * np.abs(voltages).max())
    maps = ctl.sample_maps(loop.ad, loop.bd[:, None], plant.c_meas)
    xi = np.zeros(maps[0][0].shape[0])
    lifted = []
    for k, r in enumerate(refs):
        phi, gamma = maps[k % ctl.frame]
        xi = phi @ xi + gamma @ r
        lifted.append(xi[:plant.a.shape[0]])
    assert_allclose(lifted, states, rtol=0, atol=1e-10 * np.abs(states).max())


# ------------------------------------------------------------------------ 2. stability

STABILITY_CASES = [  # (config, Kp scale, Kv scale, stable by the brute force)
    ("s120", 1.0, 1.0, True), ("s120", 4.0, 1.0, True), ("s120", 1.0, 10.0, True),
    ("s120", 6.0, 1.0, False), ("s120", 8.0, 1.0, False), ("s120", 1.0, 30.0, False),
    ("multirate", 1.0, 1.0, True), ("multirate", 2.0, 1.0, True),
    ("multirate", 4.0, 1.0, False),
    ("delay2", 0.5, 1.0, True), ("delay2", 1.0, 1.0, True), ("delay2", 3.0, 1.0, False),
    ("filters", 1.0, 1.0, True), ("filters", 8.0, 1.0, False),
]


@pytest.mark.parametrize("config, kp_scale, kv_scale, stable", STABILITY_CASES)
def test_monodromy_stability_matches_brute_force_iteration(config, kp_scale, kv_scale, stable):
    """Reference: the difference equations iterated sample by sample for 1200 frames from a
    seeded random state (plant, delay lines, sums, held outputs), normalised every frame; the
    mean growth per frame over the last 600 frames is the largest multiplier's modulus (power
    iteration). It decays exactly where is_stable() says so, and matches the spectral radius of
    the monodromy to 1 % (what is left of the slower modes and of the beating of a complex
    pair after 600 frames)."""
    drive = small(config, kp_scale, kv_scale)
    loop = reference_loop(drive)
    growth = growth_per_frame(loop, np.random.default_rng(3).standard_normal(loop.size),
                              frames=1200, burn=600)
    assert (growth < 1.0) == stable  # the case is what it is meant to be
    axis = sampled(drive)
    assert axis.is_stable() == (growth < 1.0)
    rho = np.abs(np.linalg.eigvals(axis.monodromy)).max()
    assert growth == pytest.approx(rho, rel=1e-2)
    assert abs(rho - 1.0) > 1e-2  # far enough from the boundary for the 1 % to decide


@pytest.mark.parametrize("config", list(CONFIGS))
def test_monodromy_multipliers_are_those_of_the_simulated_frame(config):
    """Reference: the state transition over one frame obtained by simulating the difference
    equations from every unit initial state. Its non-zero eigenvalues are the monodromy's (the
    two state vectors differ, their dynamics not): the leading ones agree to rounding."""
    for kp_scale in (1.0, 4.0):
        drive = small(config, kp_scale)
        mine = np.linalg.eigvals(reference_loop(drive).frame_map())
        theirs = np.linalg.eigvals(sampled(drive).monodromy)
        mine = mine[np.abs(mine) > 0.05]
        theirs = theirs[np.abs(theirs) > 0.05]
        assert mine.size == theirs.size
        for mu in mine:
            assert np.abs(theirs - mu).min() < 1e-8


BISECTIONS = [  # (config, gain, a stable and an unstable multiple of the nominal gain)
    ("s120", "kp", 5.0, 6.0), ("multirate", "kp", 2.0, 3.0), ("delay2", "kp", 1.0, 2.0),
    ("filters", "kp", 5.0, 6.0), ("s120", "kv", 10.0, 20.0),
]


@pytest.mark.parametrize("config, gain, low, high", BISECTIONS)
def test_largest_stable_gain_matches_brute_force(config, gain, low, high):
    """Reference: bisection on the gain (Kp of the velocity loop or Kv) with the brute-force
    verdict, the spectral radius of the simulated frame transition below 1. Bisection with
    is_stable() over the same bracket lands on the same gain: both bisect to 0.1 %, so they
    agree to 0.2 % (a 2 % disagreement would already be a different stability limit)."""
    def drive(x):
        return small(config, **{f"{gain}_scale": x})

    def brute(x):
        return np.abs(np.linalg.eigvals(reference_loop(drive(x)).frame_map())).max() < 1.0

    def monodromy(x):
        return sampled(drive(x)).is_stable()

    assert largest_stable(monodromy, low, high) == pytest.approx(
        largest_stable(brute, low, high), rel=2e-3)


# ------------------------------------------------------------------------ 3. compliance


def stepped_sine(drive, f_hz: float, periods: int, substeps: int = 16) -> complex:
    """The fundamental of wp.x per cos(w t) at wp.x, from the brute-force simulation.

    The force is generated by two oscillator states inside the plant, so the zero-order hold
    stays exact; the periodic steady state over the window (whole excitation periods and
    whole frames) is solved by shooting: the window's transition is the simulation of every
    unit state, and the state that returns to itself (the oscillator starting at cos = 1) is
    the steady state. That window is then simulated with ``substeps`` exact sub-steps per
    current period and wp.x projected on exp(-j w t).
    """
    w = 2 * math.pi * f_hz
    plant = with_cosine_force(open_plant(small_axis(), drive, CONTACT, PADS), w)
    period = drive.sampling.current_period
    loop = reference_loop(drive, plant=plant)
    steps = round(periods / f_hz / period)
    assert steps % loop.frame == 0 and steps * period * f_hz == pytest.approx(periods)
    window = loop.map(steps)
    n = plant.a.shape[0]
    osc = [n - 2, n - 1]
    rest = [i for i in range(loop.size) if i not in osc]
    z0 = np.zeros(loop.size)
    z0[n - 2] = 1.0
    z0[rest] = np.linalg.solve(np.eye(len(rest)) - window[np.ix_(rest, rest)],
                               window[np.ix_(rest, osc)] @ z0[osc])
    z = z0[:, None].copy()
    ad_h, bd_h = zoh(plant.a, plant.b_u, period / substeps)
    record = []
    for k in range(steps):
        loop.step(z, k, fine=(ad_h, bd_h, plant.c_out, substeps), record=record)
    assert_allclose(z[:, 0], z0, atol=1e-10 * np.abs(z0).max())  # periodic indeed
    y = np.array(record)[:, 0, 0]
    t = np.arange(y.size) * period / substeps
    return complex(2.0 * np.mean(y * np.exp(-1j * w * t)))


@pytest.mark.parametrize("config", list(CONFIGS))
def test_compliance_is_the_fundamental_of_a_stepped_sine(config):
    """Reference: a stepped sine on the brute-force sampled-data simulation (continuous force,
    held voltage, exact integration between and within samples), its periodic steady state,
    and the Fourier projection of the continuous wp.x over a window of whole excitation
    periods and whole frames (so the aliases at +-w + k 2 pi / T_frame are orthogonal to the
    fundamental; no frequency is a multiple of half the frame rate, where an alias would fall
    on it). Both sides are exact, so they agree to rounding, not to a stepped sine's usual
    1 %: 1e-6 leaves room for the shooting solve and the projection only."""
    drive = small(config)
    frame = drive.sampling.position_period
    cases = [(62.5, 1), (125.0, 1), (375.0, 3)]  # [Hz], excitation periods in the window
    for f, _ in cases:
        assert (2 * f * frame) % 1 != 0  # not a multiple of half the frame rate
    got = sampled(drive).compliance(2 * math.pi * np.array([f for f, _ in cases]))[0]
    ref = np.array([stepped_sine(drive, f, n) for f, n in cases])
    assert_allclose(got, ref, rtol=1e-6)


# ------------------------------------------------------------------------ 4. loops

J_RIGID = 0.012 + 1100.0 * RATIO**2  # rotor plus slide and work piece at the motor [kg m^2]


def rigid_velocity_loop(drive, omega):
    """The velocity loop of a rigid inertia J behind its winding, in closed form.

    Continuous: Delta(s) = J L s^2 + J R s + kt ke, i/u = J s / Delta, phi/u = kt/(s Delta).
    Zero-order hold, G(z) = (1 - 1/z) Z{G(s)/s}, by partial fractions with
    Z{1/s^2} = T z/(z - 1)^2, Z{1/s} = z/(z - 1), Z{1/(s - p)} = z/(z - e^{pT}):

        G_phi(z) = T/(ke (z - 1)) - J R/(kt ke^2) + sum_p kt/(p^2 Delta'(p)) (z-1)/(z-e^{pT})
        G_i(z)   = sum_p J/Delta'(p) (z - 1)/(z - e^{pT})

    Current loop u = z^-d C_i (T_set/kt - i), speed M(z) = (1 - 1/z)/T (and its filter), so

        L_v = z^-d C_v M  z^-d C_i G_phi / (kt (1 + z^-d C_i G_i)).
    """
    m, s = drive.motor, drive.sampling
    t, d = s.current_period, s.computation_delay
    kt, ke, r, ind, j = (m.torque_constant, m.back_emf_constant, m.resistance,
                         m.inductance, J_RIGID)
    z = np.exp(1j * np.asarray(omega, dtype=float) * t)
    g_phi = t / (ke * (z - 1)) - j * r / (kt * ke**2) + 0j
    g_i = 0j * z
    for p in np.roots([j * ind, j * r, kt * ke]):
        slope = 2 * j * ind * p + j * r
        fraction = (z - 1) / (z - np.exp(p * t))
        g_phi = g_phi + kt / (p**2 * slope) * fraction
        g_i = g_i + j / slope * fraction
    ci = pi_z(drive.current_loop.kp, drive.current_loop.ti, t, s.integral_rule, z)
    cv = pi_z(drive.velocity_loop.kp, drive.velocity_loop.ti, t, s.integral_rule, z)
    inner = z**-d * ci * g_phi / (kt * (1 + z**-d * ci * g_i))
    return z**-d * cv * speed_z(t, s.speed_filter, z) * inner


RIGID_CASES = {  # sampling, current PI, velocity Kp as a share of J 2 pi 40 Hz
    "s120": (Sampling(), PIController(15.0, 2e-3), 1.0),
    "delay2_filter_tustin": (Sampling(125e-6, 125e-6, 1e-3, computation_delay=2,
                                      speed_filter=2e-4, integral_rule="tustin"),
                             PIController(7.0, 2e-3), 0.5),
    "fast_filter_tustin": (Sampling(100e-6, 100e-6, 400e-6, speed_filter=1.5e-4,
                                    integral_rule="tustin"), PIController(15.0, 2e-3), 1.0),
    "no_delay": (Sampling(125e-6, 125e-6, 1e-3, computation_delay=0),
                 PIController(15.0, 2e-3), 1.0),
}


@pytest.mark.parametrize("case", list(RIGID_CASES))
def test_rigid_inertia_velocity_loop_closed_form(case):
    """Reference: the closed form of :func:`rigid_velocity_loop` (zero-order hold of winding
    and inertia by partial fractions, the PI and speed difference equations in z) for L_v,
    and its Ms, phase and gain margins found by root finding on that closed form. The
    margins of analyse_loop are interpolated on its 800-per-decade grid (relative steps of
    0.3 %: errors of order 1e-5), hence 1e-3."""
    sampling, current, share = RIGID_CASES[case]
    rigid = ModalModel([[J_RIGID]], [[0.0]], ["motor.rotor"], damping_ratio=0.0)
    drive = small_drive(motor=Motor(1.2, 1.2, 0.4, 3e-3, stator=None), feedback="motor",
                        sampling=sampling, current_loop=current,
                        velocity_loop=PIController(2 * math.pi * 40.0 * J_RIGID * share, 12e-3))
    axis = SampledAxis(rigid, drive)
    nyquist = math.pi / sampling.velocity_period
    w = np.geomspace(2 * math.pi * 0.5, 0.999 * nyquist, 300)
    assert_allclose(axis.loop_response("velocity", w), rigid_velocity_loop(drive, w),
                    rtol=1e-7)
    assert np.isnan(axis.loop_response("velocity", np.array([1.01 * nyquist]))).all()
    ref = margins(lambda v: rigid_velocity_loop(drive, v), nyquist * (1 - 1e-6))
    got = axis.analyse_loop("velocity")
    assert got.ms == pytest.approx(ref.ms, rel=1e-3)
    assert got.phase_margin_deg == pytest.approx(ref.phase_margin_deg, rel=1e-3)
    assert got.gain_margin == pytest.approx(10 ** (ref.gain_margin_db / 20), rel=1e-3)
    assert got.crossover == pytest.approx(ref.crossover, rel=1e-3)


@pytest.mark.parametrize("config", list(CONFIGS))
def test_loops_match_the_lifted_brute_force(config):
    """Reference for the velocity loop: the closed current loop from the held torque
    set-point to the sampled angle, held over N_v current periods, x <- A^N x + sum A^j B T
    (exact for a held input), with the velocity PI, speed difference and delay in z. For the
    position loop: the frame transition of the brute-force simulation with the velocity loop
    closed, split into the state and the held speed command (x <- Phi x + Gamma omega_cmd),
    sampled x_fb per command, times Kv/r z^-d. Exact both: agreement to rounding. The
    position loop's margins and Ms from that reference by root finding."""
    drive = small(config)
    axis = sampled(drive)
    s = drive.sampling
    plant = open_plant(small_axis(), drive, CONTACT, PADS)
    ad, bd = zoh(plant.a, plant.b_u, s.current_period)
    w = np.geomspace(2 * math.pi * 1.0, 0.99 * math.pi / s.velocity_period, 60)
    assert_allclose(axis.loop_response("velocity", w),
                    velocity_loop(ad, bd, plant.c_meas, drive, w), rtol=1e-7)
    position = reference_loop(drive, position_loop=False)

    def position_loop(v):
        z = np.exp(1j * v * s.position_period)
        return drive.kv / drive.ratio * z**-s.computation_delay * position.position_plant(v)

    w = np.geomspace(2 * math.pi * 0.1, 0.99 * math.pi / s.position_period, 60)
    assert_allclose(axis.loop_response("position", w), position_loop(w), rtol=1e-7)
    ref = margins(position_loop, math.pi / s.position_period * (1 - 1e-6))
    got = axis.analyse_loop("position")  # grid interpolation as in the rigid case: 1e-3
    assert got.ms == pytest.approx(ref.ms, rel=1e-3)
    assert got.phase_margin_deg == pytest.approx(ref.phase_margin_deg, rel=1e-3)
    assert got.gain_margin == pytest.approx(10 ** (ref.gain_margin_db / 20), rel=1e-3)


# ------------------------------------------------------------------------ 5. bundled axis


def test_bundled_axis_velocity_margins_in_sliding_regime():
    """Reference: an own sampled-data computation of the velocity loop of the bundled axis
    with the tuned design (C = 5578 N s/m, Kv = 25.51 1/s, Kp = 5.849 N m s/rad,
    Ti = 26.68 ms) feeding at 6.67 mm/s (sliding contact): the plant assembled from the
    structure's matrices, the four pad contacts and the winding, own zero-order hold, the
    lifted current loop and the velocity controller in z (:func:`velocity_loop`), margins by
    root finding. It gives Ms 1.652 at 974.8 Hz, PM 66.47 deg (crossover 215.9 Hz), GM
    9.294 dB at 965.1 Hz, as the independent model of the same conventions reported (Ms 1.65
    at 975 Hz, PM 66.5 deg, GM 9.3 dB at 965 Hz). analyse_loop interpolates on its grid
    (0.3 % steps) next to the 975 Hz resonance, so its GM is 0.1 % off (0.5 % allowed); Ms,
    PM and their frequencies agree to 1e-4 (0.2 % allowed)."""
    from servotune.axis import load_axis
    from servotune.design import axis_regimes

    axis = load_axis(MODELS / "paper_x_axis")
    regime = axis_regimes(axis)[2]
    assert regime.regime == "feeding 6.67 mm/s" and regime.kind == "sliding"
    contact = regime.contact(5578.0)
    drive = dataclasses.replace(axis.drive, kv=25.51, velocity_loop=PIController(5.849, 26.68e-3))
    plant = open_plant(axis.structure, drive, contact, axis.pads)
    ad, bd = zoh(plant.a, plant.b_u, drive.sampling.current_period)
    nyquist = math.pi / drive.sampling.velocity_period
    ref = margins(lambda v: velocity_loop(ad, bd, plant.c_meas, drive, v), nyquist * (1 - 1e-6))
    got = SampledAxis(axis.structure, drive, contact, axis.pads).analyse_loop("velocity")
    assert got.ms == pytest.approx(ref.ms, rel=2e-3)
    assert got.ms_frequency == pytest.approx(ref.ms_frequency, rel=2e-3)
    assert got.phase_margin_deg == pytest.approx(ref.phase_margin_deg, rel=2e-3)
    assert got.gain_margin == pytest.approx(10 ** (ref.gain_margin_db / 20), rel=5e-3)
    assert got.phase_crossover == pytest.approx(ref.phase_crossover, rel=2e-3)


@pytest.mark.parametrize("f_hz", [40.0, 120.0, 250.0])
def test_time_simulation_with_sample_and_hold_is_the_sampled_data_compliance(f_hz):
    """servotune's time simulation (controllers computed at their samples inside the
    integrator, the voltage held) against SampledAxis.compliance: a stepped sine on the small
    axis with linear (viscous) pads, its fundamental by least squares over the last ten
    periods, within 1 % (observed 1e-6 to 2e-3: what is left is the response's aliases, which
    the fit at the recording rate partly takes for the fundamental)."""
    from servotune.simulate import NonlinearAxis, ViscousFriction, custom, simulate

    drive = small_drive(sampling=Sampling())
    c = 2e4
    axis = NonlinearAxis(small_axis(), drive, PADS, ViscousFriction(c))
    w = 2 * math.pi * f_hz
    duration = math.ceil(30.0 / f_hz * 1000.0) / 1000.0
    scenario = custom(duration, forces={"wp.x": lambda t: 100.0 * np.sin(w * t)})
    result = simulate(axis, scenario, step=125e-6, record_step=125e-6)
    t, x = result.t, result.signals["wp_x"]
    last = t >= t[-1] - 10.0 / f_hz + 1e-12
    basis = np.column_stack([np.sin(w * t[last]), np.cos(w * t[last]), np.ones(last.sum())])
    a, b, _ = np.linalg.lstsq(basis, x[last], rcond=None)[0]
    measured = (a + 1j * b) / 100.0
    model = SampledAxis(small_axis(), drive, Contact.viscous(c), PADS)
    assert model.is_stable()
    expected = complex(model.compliance([w])[0, 0])
    assert abs(measured / expected - 1.0) < 0.01
