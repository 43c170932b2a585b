"""Frequency responses and loop analysis against closed forms and python-control."""

import math

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from servotune.frequency import (
    analyse_loop,
    closed_loop_poles,
    fast_frequency_response,
    peak,
    require_stable,
)
from servotune.plant import UnstableLoopError


def random_stable_system(n=40, p=3, m=2, seed=1):
    """A seeded random stable system with a direct term."""
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((n, n))
    a = a - (np.max(np.linalg.eigvals(a).real) + 0.5) * np.eye(n)
    return control.ss(a, rng.standard_normal((n, m)), rng.standard_normal((p, n)),
                      rng.standard_normal((p, m)))


def test_fast_response_equals_direct_evaluation():
    sys = random_stable_system()
    omega = np.geomspace(1e-2, 1e3, 500)
    fast = fast_frequency_response(sys, omega).complex
    direct = np.stack([sys(1j * w) for w in omega], axis=-1)
    assert_allclose(fast, direct, rtol=1e-9, atol=1e-12 * np.abs(direct).max())


def test_fast_response_falls_back_for_a_defective_matrix():
    # a Jordan block: eigenvectors are parallel, so the modal formula is unusable
    a = np.array([[-1.0, 1.0, 0.0], [0.0, -1.0, 1.0], [0.0, 0.0, -1.0]])
    sys = control.ss(a, [[0.0], [0.0], [1.0]], [[1.0, 0.0, 0.0]], 0.0)
    omega = np.linspace(0.0, 10.0, 50)
    exact = 1.0 / (1j * omega + 1.0) ** 3
    assert_allclose(fast_frequency_response(sys, omega).complex.ravel(), exact, rtol=1e-12)


def test_phase_margin_and_ms_of_a_second_order_loop():
    # L = k/(s (s + a)): |L| = 1 at wc^2 = (-a^2 + sqrt(a^4 + 4 k^2))/2,
    # PM = 90 deg - atan(wc/a); |S| peak from a dense direct evaluation
    k, a = 4.0, 1.0
    loop = control.ss(control.tf([k], [1.0, a, 0.0]))
    result = analyse_loop(loop, omega=np.geomspace(1e-3, 1e3, 20001))
    wc = math.sqrt((-a**2 + math.sqrt(a**4 + 4 * k**2)) / 2)
    assert result.crossover == pytest.approx(wc, rel=1e-6)
    assert result.phase_margin_deg == pytest.approx(90.0 - math.degrees(math.atan(wc / a)),
                                                    rel=1e-6)
    assert math.isinf(result.gain_margin)
    # |S|^2 = |s(s+a)|^2/|s^2 + a s + k|^2 peaks where its derivative vanishes; brute force
    w = np.geomspace(1e-2, 1e2, 2_000_001)
    s = 1j * w
    assert result.ms == pytest.approx(np.abs(s * (s + a) / (s * s + a * s + k)).max(), rel=1e-7)


def test_gain_margin_of_a_third_order_lag():
    # L = k/(s+1)^3 crosses -180 deg at w = sqrt(3) where |L| = k/8: GM = 8/k
    k = 2.0
    result = analyse_loop(control.ss(control.tf([k], [1.0, 3.0, 3.0, 1.0])))
    assert result.gain_margin == pytest.approx(8.0 / k, rel=1e-5)
    assert result.phase_crossover == pytest.approx(math.sqrt(3.0), rel=1e-5)


def test_upper_and_lower_gain_margins_of_a_conditionally_stable_loop():
    # L = 20 (s+1)^2 / (s^3 (s/100+1)^2) is stable only for gain factors g in (g_low, g_up);
    # reference: the gains where a root of den + g num crosses the imaginary axis (root locus
    # by bisection on the largest real part), independent of the phase crossings
    from scipy.optimize import brentq

    num = 20.0 * np.polymul([1.0, 1.0], [1.0, 1.0])
    den = np.polymul([1.0, 0.0, 0.0, 0.0], np.polymul([0.01, 1.0], [0.01, 1.0]))

    def largest_real_part(g):
        return np.roots(np.polyadd(den, g * num)).real.max()

    assert largest_real_part(1.0) < 0.0  # the nominal loop is stable
    g_low = brentq(largest_real_part, 1e-3, 1.0, xtol=1e-12)
    g_up = brentq(largest_real_part, 1.0, 100.0, xtol=1e-12)
    result = analyse_loop(control.ss(control.tf(num, den)), omega=np.geomspace(1e-2, 1e4, 20001))
    assert result.gain_margin == pytest.approx(g_up, rel=1e-5)
    assert result.gain_margin_lower == pytest.approx(g_low, rel=1e-5)
    assert result.gain_margin_lower_db < 0.0 < result.gain_margin_db


def test_bandwidth_of_a_first_order_closed_loop():
    # L = wb/s gives T = wb/(s + wb): -3 dB at wb
    result = analyse_loop(control.ss(control.tf([25.0], [1.0, 0.0])))
    assert result.bandwidth == pytest.approx(25.0, rel=1e-5)


def test_unstable_closed_loop_is_refused():
    with pytest.raises(UnstableLoopError, match="right half plane"):
        analyse_loop(control.ss(control.tf([20.0], [1.0, 3.0, 3.0, 1.0])))
    with pytest.raises(UnstableLoopError):
        require_stable(control.ss([[1.0]], [[1.0]], [[1.0]], 0.0))


def test_poles_and_damping_ratios():
    wn, zeta = 30.0, 0.05
    sys = control.ss(control.tf([wn**2], [1.0, 2 * zeta * wn, wn**2]))
    poles = closed_loop_poles(sys)
    assert_allclose(poles.natural_frequencies, [wn, wn], rtol=1e-12)
    assert poles.least_damped[1] == pytest.approx(zeta, rel=1e-12)
    assert poles.stable


def test_peak_refinement_finds_a_resonance_between_grid_points():
    wn, zeta = 100.0, 0.02
    omega = np.geomspace(10.0, 1000.0, 400)
    h = 1.0 / (wn**2 - omega**2 + 2j * zeta * wn * omega)
    value, where = peak(omega, h)
    exact_w = wn * math.sqrt(1 - 2 * zeta**2)
    exact = 1.0 / (2 * zeta * wn**2 * math.sqrt(1 - zeta**2))
    # one mode: the parabola in (omega^2, 1/|H|^2) is exact
    assert where == pytest.approx(exact_w, rel=1e-9)
    assert value == pytest.approx(exact, rel=1e-9)
    assert np.abs(h).max() < 0.995 * exact  # the grid alone misses it


def test_fast_response_deflates_a_jordan_block_at_zero():
    # a double integrator (a Jordan block at s = 0, as a rigid body under an open loop) in
    # series with a lightly damped mode: the eigenvectors are useless, the deflated modal form
    # is exact
    wn, zeta = 300.0, 0.02
    sys = control.ss(control.tf([1.0], [1.0, 0.0, 0.0]) *
                     control.tf([wn**2], [1.0, 2 * zeta * wn, wn**2]))
    omega = np.geomspace(0.1, 3e3, 2000)
    s = 1j * omega
    exact = wn**2 / (s**2 * (s**2 + 2 * zeta * wn * s + wn**2))
    assert_allclose(fast_frequency_response(sys, omega).complex.ravel(), exact, rtol=1e-9)
    from servotune.frequency import _deflated_form, _modal_form

    lam = np.linalg.eigvals(sys.A)
    deflated = _deflated_form(sys.A, sys.B, sys.C, lam, np.abs(lam) < 1e-6)
    assert deflated is not None and deflated.t.shape == (2, 2)
    assert_allclose(deflated.response(omega).ravel(), exact, rtol=1e-9)
    with np.errstate(all="ignore"):
        plain = _modal_form(sys.A, sys.B, sys.C)
        assert plain is None or not np.allclose(plain.response(omega).ravel(), exact,
                                                rtol=1e-9)


def accurate_response(sys, omega):
    """Reference: LU solves with two steps of iterative refinement whose residual is formed in
    extended precision (numpy's long double), so rounding of the solve does not limit it."""
    a, b, c = sys.A, sys.B[:, 0], sys.C[0]
    out = []
    for w in omega:
        m = 1j * w * np.eye(a.shape[0]) - a
        x = np.linalg.solve(m, b)
        ml = m.astype(np.clongdouble)
        for _ in range(2):
            r = b.astype(np.clongdouble) - ml @ x.astype(np.clongdouble)
            x = x + np.linalg.solve(m, r.astype(complex))
        out.append(complex(c.astype(np.clongdouble) @ x.astype(np.clongdouble)) + sys.D[0, 0])
    return np.array(out)


def test_open_velocity_loop_with_a_rigid_body_is_accurate():
    # the open velocity loop of a free axis: a PI controller (integrator at s = 0) drives a
    # free, viscously guided body, with a flexible mode on top, and the loop reads the body's
    # velocity. Its position (another eigenvalue at 0) is not observed: the two eigenvalues
    # at 0 make the eigenvectors nearly parallel, which the plain modal form cannot handle.
    # The result at the default rtol must match an accurate reference to the conditioning of
    # the data.
    m1, m2, k, c, d = 4000.0, 1000.0, 4e8, 6e3, 2e3
    kp, ti = 8e4, 0.02
    # states: x1, x2, v1, v2, integrator; input u: the velocity error into the PI; output:
    # the body velocity v1 (L = PI(s) G(s), the loop opened at its feedback)
    a = np.zeros((5, 5))
    a[0, 2] = a[1, 3] = 1.0
    a[2, :4] = [-k / m1, k / m1, -(c + d) / m1, d / m1]
    a[3, :4] = [k / m2, -k / m2, d / m2, -d / m2]
    a[2, 4] = kp / ti / m1
    b = np.zeros((5, 1))
    b[2, 0] = kp / m1
    b[4, 0] = 1.0
    sys = control.ss(a, b, [[0.0, 0.0, 1.0, 0.0, 0.0]], 0.0)
    assert np.sum(np.abs(np.linalg.eigvals(a)) < 1e-6) == 2   # integrator and rigid position
    omega = 2 * math.pi * np.geomspace(0.1, 3000.0, 4001)
    got = fast_frequency_response(sys, omega).complex.ravel()
    idx = np.linspace(0, omega.size - 1, 41).astype(int)
    ref = accurate_response(sys, omega[idx])
    assert_allclose(got[idx], ref, rtol=1e-9)


def test_receptance_and_port_coupling_with_a_physical_damping_matrix():
    # pad dampers added as a physical matrix make the damping non-modal: the receptance then
    # comes from direct solves, and the port coupling must still equal the state-space plant
    from axis_fixtures import PADS, small_axis, small_drive

    from servotune.frequency import compliance, modal_receptance, port_compliance
    from servotune.plant import Contact, build_plant

    structure = small_axis().with_added(damping={p: 3e4 for p in PADS})
    omega = 2 * np.pi * np.geomspace(1.0, 2000.0, 200)
    ports = ["wp.x", "pad1.x", "motor.rotor"]
    direct = np.moveaxis(structure.receptance(omega, ports, ports), 0, -1)
    assert_allclose(modal_receptance(structure, omega, ports, ports), direct, rtol=1e-12)
    drive = small_drive()
    contact = Contact.viscous(2e4)
    plant = build_plant(structure, drive, contact, PADS)
    assert_allclose(port_compliance(structure, omega, drive, contact, PADS)[0],
                    compliance(plant, omega), rtol=1e-9)


def test_a_badly_scaled_input_row_does_not_spoil_the_modal_form():
    # the velocity loop of a tuned small axis: balancing A alone scales one row of B by
    # ~1e20, and the modal sum then loses digits to cancellation while its own residual looks
    # small; the response must still equal the direct solve of the unbalanced system
    import math

    from axis_fixtures import PADS, small_axis, small_drive

    from servotune.plant import Contact, loop_transfer
    from servotune.tuning import Design, TuningProblem

    structure = small_axis()
    problem = TuningProblem(structure, PADS, c=5e4, drive=small_drive(),
                            free=("c", "kv", "kp", "ti"))
    d = Design(c=5.266e5, kv=63.22, kp=7.293, ti=2.933e-3)
    lt = loop_transfer(structure, problem.drive_for(d), Contact.viscous(d.c), PADS, "velocity")
    omega = 2 * math.pi * np.geomspace(1.0, 3000.0, 400)
    got = fast_frequency_response(lt, omega).complex.ravel()
    # the reference: a direct solve of the balanced system (unbalanced, the solve itself is
    # off by ~1e-5 here), which the port-coupled model of the tuning reproduces to 1e-9
    import scipy.linalg as sl

    a, t = sl.matrix_balance(lt.A, permute=False, separate=True)
    b, c = lt.B / t[0][:, None], lt.C * t[0][None, :]
    direct = np.array([(c @ np.linalg.solve(1j * w * np.eye(a.shape[0]) - a, b))[0, 0]
                       + lt.D[0, 0] for w in omega])
    np.testing.assert_allclose(got, direct, rtol=1e-6, atol=1e-8 * np.abs(direct).max())
    from servotune.tuning import ResponseModel

    port = ResponseModel(problem, omega)(d)["loop_velocity"][0]
    np.testing.assert_allclose(port, direct, rtol=1e-6, atol=1e-8 * np.abs(direct).max())
