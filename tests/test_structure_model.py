"""ModalModel against closed forms: spring-mass chains, modal damping, locking, state space."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from servotune.structure import ModalModel, UnknownDofError


def chain(n=4, m=2.0, k=5e4, grounded=True, zeta=0.03):
    """n equal masses in a chain of equal springs, the first grounded (or free)."""
    kk = np.zeros((n, n))
    for i in range(n - 1):
        kk[i:i + 2, i:i + 2] += k * np.array([[1, -1], [-1, 1]])
    if grounded:
        kk[0, 0] += k
    return ModalModel(m * np.eye(n), kk, [f"m{i}.x" for i in range(n)], damping_ratio=zeta)


def test_chain_frequencies_are_the_closed_form():
    # fixed-free chain: omega_j = 2 sqrt(k/m) sin((2j-1) pi / (2(2n+1)))
    n, m, k = 5, 2.0, 5e4
    j = np.arange(1, n + 1)
    expected = 2 * np.sqrt(k / m) * np.sin((2 * j - 1) * np.pi / (2 * (2 * n + 1)))
    assert_allclose(chain(n, m, k).natural_frequencies(), expected, rtol=1e-12)


def test_modal_damping_is_what_was_asked_for():
    model = chain(zeta=[0.01, 0.02, 0.03, 0.05])
    assert_allclose(model.modal_damping_ratios(), [0.01, 0.02, 0.03, 0.05], rtol=1e-10)
    # and the damped poles of the state space have those damping ratios
    poles = model.to_state_space().poles()
    upper = poles[poles.imag > 0]
    upper = upper[np.argsort(np.abs(upper))]
    assert_allclose(-upper.real / np.abs(upper), [0.01, 0.02, 0.03, 0.05], rtol=1e-8)


def test_rigid_body_mode_is_undamped_and_found():
    model = chain(grounded=False)
    assert model.natural_frequencies()[0] == 0.0
    assert np.isnan(model.modal_damping_ratios()[0])
    # a uniform translation costs no damping force
    assert_allclose(model.damping @ np.ones(model.n), 0.0, atol=1e-9)


def test_locking_keeps_physical_damping_and_gives_sub_chain():
    free = chain(grounded=False, n=3, k=1e4, m=1.0)
    locked = free.locked(["m0.x"])
    # two masses hanging from a locked one: a grounded chain of two
    reference = chain(n=2, k=1e4, m=1.0)
    assert_allclose(locked.natural_frequencies(), reference.natural_frequencies(), rtol=1e-12)
    assert_allclose(locked.damping, free.damping[1:, 1:])
    assert locked.dofs == ("m1.x", "m2.x")


def test_state_space_matches_direct_receptance():
    model = chain()
    sys = model.to_state_space(inputs=["m3.x"], outputs=["m3.x", "m1.x"])
    omega = np.linspace(1.0, 400.0, 50)
    frf = np.stack([sys(1j * w) for w in omega])  # (n_omega, 2, 1)
    assert_allclose(frf, model.receptance(omega, ["m3.x"], ["m3.x", "m1.x"]), rtol=1e-9)
    assert sys.input_labels == ["f_m3_x"] and sys.output_labels == ["m3_x", "m1_x"]


def test_static_compliance_of_grounded_chain_is_series_springs():
    n, k = 4, 5e4
    sys = chain(n=n, k=k).to_state_space(inputs=["m3.x"], outputs=["m3.x"])
    assert_allclose(sys.dcgain(), n / k, rtol=1e-10)


def test_added_pad_damper_changes_only_its_dof():
    model = chain(grounded=False)
    damped = model.with_added(damping={"m0.x": 1e3}, stiffness={"m0.x": 2e4})
    assert damped.damping[0, 0] == pytest.approx(model.damping[0, 0] + 1e3)
    assert damped.stiffness[0, 0] == pytest.approx(model.stiffness[0, 0] + 2e4)
    assert_allclose(damped.damping[1:, 1:], model.damping[1:, 1:])


@pytest.mark.parametrize("mass, stiffness, dofs, message", [
    ([[1.0, 0.1], [0.0, 1.0]], np.eye(2), "ab", "mass is not symmetric"),
    (np.eye(2), [[1.0, 2.0], [0.0, 1.0]], "ab", "stiffness is not symmetric"),
    ([[1.0, 0.0], [0.0, -1.0]], np.eye(2), "ab", "not positive definite"),
    (np.eye(2), [[1.0, 0.0], [0.0, -1.0]], "ab", "indefinite"),
    (np.eye(3), np.eye(3), "ab", "3x3 but the model has 2 DOFs"),
    (np.ones((2, 3)), np.eye(2), "ab", "square"),
    ([[np.nan, 0.0], [0.0, 1.0]], np.eye(2), "ab", "NaN"),
])
def test_bad_matrices_are_refused(mass, stiffness, dofs, message):
    with pytest.raises(ValueError, match=message):
        ModalModel(mass, stiffness, list(dofs))


def test_unknown_dof_names_the_known_ones():
    model = chain()
    with pytest.raises(UnknownDofError, match=r"unknown DOF 'wp.x'.*m0.x"):
        model.locked(["wp.x"])
    with pytest.raises(ValueError, match="duplicate"):
        ModalModel(np.eye(2), np.eye(2), ["a", "a"])
    with pytest.raises(ValueError, match="damping_ratio"):
        ModalModel(np.eye(2), np.eye(2), ["a", "b"], damping_ratio=-0.1)


# -- port receptance: modes and a port-sized solve against the direct solution --------------------
def random_model(n=40, seed=5, zeta=0.02):
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((n, n))
    k = a @ a.T + n * np.eye(n)
    m = np.diag(rng.uniform(1.0, 2.0, n))
    return ModalModel(m, k, [f"d{i}" for i in range(n)], damping_ratio=zeta)


@pytest.mark.parametrize("derive", [
    lambda m: m,
    lambda m: m.locked(["d2", "d9"]),
    lambda m: m.with_added(stiffness={"d3": 50.0}, damping={"d1": 20.0, "d7": 5.0}),
    lambda m: m.locked(["d2"]).with_added(damping={"d3": 10.0}).locked(["d4"]),
], ids=["modal", "locked", "added", "chained"])
def test_port_receptance_equals_the_direct_solution(derive):
    model = derive(random_model())
    omega = np.linspace(0.5, 15.0, 300)
    outputs = [d for d in ("d1", "d5", "d6") if d in model.dofs]
    direct = model.receptance(omega, ["d6", "d3"], outputs)
    fast = model.port_receptance(omega, ["d6", "d3"], outputs)
    assert_allclose(fast, direct, rtol=1e-9, atol=1e-12 * np.abs(direct).max())


def test_port_receptance_of_a_free_model_and_its_rigid_body_mode():
    free = chain(grounded=False)
    omega = np.geomspace(0.1, 500.0, 200)
    direct = free.receptance(omega, ["m0.x"], ["m3.x"])
    assert_allclose(free.port_receptance(omega, ["m0.x"], ["m3.x"]), direct, rtol=1e-7)
    # at low frequency the free chain is its total mass: X/F -> -1 / (4 m w^2)
    assert_allclose(free.port_receptance([0.1], ["m0.x"], ["m0.x"])[0, 0, 0].real,
                    -1 / (4 * 2.0 * 0.01), rtol=1e-4)
    with pytest.raises(ValueError, match="infinite at omega = 0"):
        free.port_receptance([0.0], ["m0.x"], ["m0.x"])
