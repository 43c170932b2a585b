"""Checks of servotune.frequency and servotune.analysis on inputs that cannot give a meaningful
compliance: a pad contact without pads, an unstable loop, a grid outside the band, and the
stability criterion of a slow pole next to fast ones."""

import math
from pathlib import Path

import control
import numpy as np
import pytest
import scipy.linalg
from axis_fixtures import PADS, small_axis, small_drive
from numpy.testing import assert_allclose

from servotune import analysis
from servotune.axis import load_axis
from servotune.frequency import (
    closed_loop_poles,
    compliance,
    fast_frequency_response,
    is_stable,
    modal_receptance,
    port_compliance,
    require_stable,
)
from servotune.plant import Contact, UnstableLoopError, build_plant

MODELS = Path(__file__).resolve().parents[1] / "models"
OMEGA = 2 * np.pi * np.geomspace(5.0, 500.0, 200)


# -- a contact that acts at the pads needs the pads --------------------------------------------

@pytest.mark.parametrize("contact", [Contact.viscous(2e4), Contact.stiction(1e8, 1e4, 0.0),
                                     Contact.locked()], ids=["viscous", "stiction", "locked"])
def test_port_compliance_refuses_a_pad_contact_without_pads_as_build_plant_does(contact):
    with pytest.raises(ValueError, match="needs the pad DOFs") as plant_error:
        build_plant(small_axis(), None, contact, ())
    with pytest.raises(ValueError, match="needs the pad DOFs") as port_error:
        port_compliance(small_axis(), OMEGA, None, contact, ())
    assert str(port_error.value) == str(plant_error.value)


def test_a_free_contact_needs_no_pads():
    # the free contact adds nothing: the response is the structure's receptance itself
    h = port_compliance(small_axis(), OMEGA, None, Contact.free(), ())[0]
    assert_allclose(h, modal_receptance(small_axis(), OMEGA, ["wp.x"], ["wp.x"])[0, 0],
                    rtol=1e-12)


# -- stability of the port model ---------------------------------------------------------------

def test_port_compliance_names_the_unstable_poles_of_the_closed_loop():
    # Kv = 300 1/s destabilises the small axis: the plant's eigenvalues are the reference
    drive, contact = small_drive(kv=300.0), Contact.viscous(2e4)
    poles = closed_loop_poles(build_plant(small_axis(), drive, contact, PADS)).poles
    unstable = poles[poles.real > 0]
    assert unstable.size == 2
    with pytest.raises(UnstableLoopError, match="2 pole") as info:
        port_compliance(small_axis(), OMEGA, drive, contact, PADS, check_stability=True)
    assert f"{unstable[0].real:.3g}" in str(info.value)


def test_unchecked_port_compliance_is_the_response_formula_of_the_unstable_plant():
    # with the check off (the default), the coupling still equals C (jw - A)^-1 B + D
    drive, contact = small_drive(kv=300.0), Contact.viscous(2e4)
    plant = build_plant(small_axis(), drive, contact, PADS)
    ref = fast_frequency_response(plant, OMEGA, inputs=["f_wp_x"], outputs=["wp_x"]).complex
    got = port_compliance(small_axis(), OMEGA, drive, contact, PADS, check_stability=False)[0]
    assert_allclose(got, np.ravel(ref), rtol=1e-8)


def test_checked_port_compliance_of_a_stable_loop_equals_the_plant_compliance():
    drive, contact = small_drive(), Contact.viscous(2e4)
    plant = build_plant(small_axis(), drive, contact, PADS)
    assert_allclose(port_compliance(small_axis(), OMEGA, drive, contact, PADS,
                                    check_stability=True)[0],
                    compliance(plant, OMEGA), rtol=1e-9)


def test_a_sliding_contact_with_negative_damping_is_found_unstable_without_a_drive():
    # a falling friction characteristic, F = -c v with c > 0 larger than the structure's own
    # damping, makes the uncontrolled axis diverge: the plant has a pole in the right half plane
    contact = Contact.sliding(control.ss(control.tf([-5e5], [1.0])))
    poles = closed_loop_poles(build_plant(small_axis(), None, contact, PADS)).poles
    assert np.any(poles.real > 1.0)
    with pytest.raises(UnstableLoopError, match="sliding contact"):
        port_compliance(small_axis(), OMEGA, None, contact, PADS, check_stability=True)


# -- the stability criterion -------------------------------------------------------------------

def fast_mode_and_pole(p_slow: float, wn: float = 1e6, zeta: float = 0.02) -> control.StateSpace:
    """A lightly damped mode at wn [rad/s] in companion form beside a real pole p_slow."""
    a = np.zeros((3, 3))
    a[0, 1] = 1.0
    a[1, 0], a[1, 1] = -wn**2, -2 * zeta * wn
    a[2, 2] = p_slow
    return control.ss(a, np.ones((3, 1)), np.ones((1, 3)), 0.0)


@pytest.mark.parametrize("p_slow", [1e-4, 5e-4, 1e-2])
def test_a_slow_unstable_pole_beside_a_fast_stable_mode_is_found(p_slow):
    # the poles are -zeta wn +- j wn sqrt(1 - zeta^2) and p_slow by construction; a tolerance
    # scaled by the largest pole (1e-9 x 1e6 = 1e-3 rad/s) passed the first two
    sys = fast_mode_and_pole(p_slow)
    with pytest.raises(UnstableLoopError, match="1 pole") as info:
        require_stable(sys)
    assert f"{p_slow:.3g}+0j" in str(info.value)


def test_a_slow_stable_pole_beside_a_fast_mode_is_accepted():
    require_stable(fast_mode_and_pole(-1e-4))


@pytest.mark.parametrize("k", [1e4, 5e11])
def test_the_rigid_body_mode_of_a_free_pair_of_masses_is_accepted(k):
    # two unit masses on a spring k: poles 0, 0 (the free motion, a Jordan block) and
    # +-j sqrt(2 k) (undamped), all on the imaginary axis: stable in the accepted sense
    a = np.zeros((4, 4))
    a[0, 2] = a[1, 3] = 1.0
    a[2, :2] = [-k, k]
    a[3, :2] = [k, -k]
    sys = control.ss(a, [[0.0], [0.0], [1.0], [0.0]], [[1.0, 0.0, 0.0, 0.0]], 0.0)
    assert_allclose(np.sort(np.abs(closed_loop_poles(sys).poles))[-1], math.sqrt(2 * k),
                    rtol=1e-9)
    require_stable(sys)


def test_integrators_beside_a_fast_mode_are_accepted():
    double_integrator = control.ss(control.tf([1.0], [1.0, 0.0, 0.0]))
    require_stable(control.append(double_integrator, fast_mode_and_pole(-1.0)))


def test_the_uncontrolled_paper_axis_with_its_rigid_body_mode_is_stable():
    # the reduced structure's rigid-body mode is singular only to rounding (its computed poles
    # are +-1.5e-4 rad/s): the uncontrolled compliance must equal the modal sum at wp.x
    structure = load_axis(MODELS / "paper_x_axis").structure
    omega = 2 * np.pi * np.geomspace(5.0, 300.0, 50)
    h = compliance(build_plant(structure), omega)
    assert_allclose(h, modal_receptance(structure, omega, ["wp.x"], ["wp.x"])[0, 0],
                    rtol=1e-7)


# -- a frequency grid outside the requirement band --------------------------------------------

@pytest.fixture(scope="module")
def axis():
    return load_axis(MODELS / "paper_x_axis").with_continuous_drive()


def test_compliance_curve_refuses_a_grid_outside_the_band(axis):
    lo, hi = axis.requirements.band
    omega = np.linspace(2 * hi, 4 * hi, 30)
    with pytest.raises(ValueError, match="requirement band") as info:
        analysis.compliance_curve(axis, Contact.viscous(1e5), omega=omega)
    message = str(info.value)
    assert f"{lo:.4g} to {hi:.4g} rad/s" in message
    assert f"{omega[0]:.4g} to {omega[-1]:.4g} rad/s, 30 points" in message


def test_uncontrolled_compliance_refuses_a_grid_outside_the_band(axis):
    lo, _ = axis.requirements.band
    omega = np.linspace(lo / 4, lo / 2, 10)
    with pytest.raises(ValueError, match=f"{lo:.4g} to .* rad/s") as info:
        analysis.uncontrolled_compliance(axis, [1e5], omega=omega)
    assert f"{omega[0]:.4g} to {omega[-1]:.4g} rad/s, 10 points" in str(info.value)


def test_a_grid_with_one_point_in_the_band_gives_that_point(axis):
    # the peak over a band holding one grid point is the compliance there (no refinement)
    lo, hi = axis.requirements.band
    omega = np.array([lo / 2, math.sqrt(lo * hi), 2 * hi])
    curve = analysis.uncontrolled_compliance(axis, [1e5], omega=omega)[0]
    assert curve.peak_frequency == omega[1]
    assert curve.peak_compliance == pytest.approx(abs(curve.values[1]), rel=1e-12)


def _unstable_by_the_full_check(a: np.ndarray) -> bool:
    """The criterion of require_stable evaluated with eigenvectors for every matrix (no quick
    pass by the eigenvalues alone)."""
    from servotune.frequency import _pole_resolution

    lam, resolution = _pole_resolution(a)
    return bool((lam.real > 1e-9 * np.abs(lam) + 10.0 * resolution).any())


@pytest.mark.parametrize("seed", range(40))
def test_the_quick_pass_of_require_stable_agrees_with_the_full_check(seed):
    # poles straddling the imaginary axis by amounts around the rounding tolerance (real parts
    # from -0.1 to +0.1 of |p| and down to 1e-14 |p|), in a random non-normal basis: the
    # quick passes (stable by the eigenvalues alone, unstable beyond any rounding) and the
    # full check are all taken
    rng = np.random.default_rng(seed)
    n = 6
    wn = 10.0 ** rng.uniform(-1, 4, n // 2)
    re = rng.choice([-1.0, 1.0], n // 2) * wn * 10.0 ** rng.uniform(-14, -1, n // 2)
    blocks = [np.array([[r, w], [-w, r]]) for r, w in zip(re, wn, strict=True)]
    d = scipy.linalg.block_diag(*blocks)
    v = rng.normal(size=(n, n)) + 3 * np.eye(n)
    a = v @ d @ np.linalg.inv(v)
    sys = control.ss(a, np.ones((n, 1)), np.ones((1, n)), 0.0)
    unstable = _unstable_by_the_full_check(a)
    assert is_stable(sys) is not unstable
    if unstable:
        with pytest.raises(UnstableLoopError):
            require_stable(sys)
    else:
        require_stable(sys)


@pytest.mark.parametrize("n, m, seed", [(1, 1, 0), (2, 3, 1), (40, 2, 2), (99, 4, 3)])
def test_the_hessenberg_solves_of_the_check_agree_with_dense_lu(n, m, seed):
    # C (jw I - A)^-1 B by the Hessenberg form against scipy's dense LU, including a frequency
    # on an eigenvalue of A (a singular system: NaN, which the check reads as a failed form)
    from servotune.frequency import _DirectSolves

    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, n)) * 10.0 ** rng.uniform(-3, 3, (n, 1))
    b, c = rng.normal(size=(n, m)), rng.normal(size=(2, n))
    omega = np.geomspace(1e-2, 1e3, 17)
    got = _DirectSolves(a, b, c)(omega)
    want = np.stack([c @ scipy.linalg.solve(1j * w * np.eye(n) - a, b) for w in omega], axis=-1)
    cond = max(np.linalg.cond(1j * w * np.eye(n) - a) for w in omega)
    assert_allclose(got, want, rtol=0, atol=1e3 * cond * np.finfo(float).eps
                    * np.abs(want).max())
    singular = np.zeros((2, 2))
    singular[0, 1] = -3.0
    singular[1, 0] = 3.0  # eigenvalues +-3j
    assert np.isnan(_DirectSolves(singular, np.ones((2, 1)), np.ones((1, 2)))(
        np.array([3.0]))).all()
