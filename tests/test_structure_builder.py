"""StructureBuilder against closed forms: spring-mass chains, a ball-screw lever, the rigid-body
mass of beams and the natural frequencies of a cantilever (Euler-Bernoulli, axial, torsion).

References: the fixed-free chain of n equal masses and springs has
omega_j = 2 sqrt(k/m) sin((2j - 1) pi / (2 (2n + 1))), j = 1..n (e.g. Meirovitch, Fundamentals
of Vibrations, 2001, sec 8.9 on lumped chains); a cantilever of length L has bending frequencies
(beta_j L)^2 sqrt(E I / (rho A L^4)) with beta_1 L = 1.875104, beta_2 L = 4.694091, and
axial and torsional ones (2j - 1) pi / (2 L) sqrt(E/rho) and sqrt(G/rho) (Blevins, Formulas for
Natural Frequency and Mode Shape, 1979, tables 8-1 and 8-19).
"""

import math

import numpy as np
import pytest
import scipy.linalg
from numpy.testing import assert_allclose

from servotune.structure.builder import NODE_DOFS, StructureBuilder
from servotune.structure.model import ModalModel


def _model(builder, held=()):
    m, k, dofs = builder.assemble()
    model = ModalModel(m.toarray(), k.toarray(), dofs, damping_ratio=0.0)
    return model.locked(list(held)) if held else model


@pytest.mark.parametrize("n", [1, 2, 5, 12])
def test_fixed_free_chain_has_the_closed_form_frequencies(n):
    m, k = 3.0, 2e6
    b = StructureBuilder()
    for i in range(n):
        b.add_dof(f"m{i}.x")
        b.add_mass(f"m{i}.x", m)
        b.add_spring({f"m{i}.x": 1.0} if i == 0 else {f"m{i}.x": 1.0, f"m{i - 1}.x": -1.0}, k)
    j = np.arange(1, n + 1)
    expected = 2 * math.sqrt(k / m) * np.sin((2 * j - 1) * math.pi / (2 * (2 * n + 1)))
    assert_allclose(_model(b).natural_frequencies(), expected, rtol=1e-12)


def test_free_free_pair_has_a_rigid_mode_and_the_reduced_mass_frequency():
    # two masses joined by one spring: 0 and sqrt(k (m1 + m2) / (m1 m2))
    b = StructureBuilder()
    for name, mass in (("a.x", 2.0), ("b.x", 5.0)):
        b.add_dof(name)
        b.add_mass(name, mass)
    b.add_spring({"a.x": 1.0, "b.x": -1.0}, 7e5)
    omega = _model(b).natural_frequencies()
    assert omega[0] == 0.0
    assert_allclose(omega[1], math.sqrt(7e5 * 7.0 / 10.0), rtol=1e-12)


def test_ball_screw_lever_refers_the_slide_to_the_motor():
    # a nut spring on x_nut - p theta between a slide (mass m) and a rotor (inertia J) held by a
    # torsion spring: with the nut rigid the pair moves as one inertia J + m p^2 on kt
    p, m, j, kt = 10e-3 / (2 * math.pi), 500.0, 0.01, 4e4
    b = StructureBuilder()
    for name, mass in (("slide.x", m), ("rotor", j)):
        b.add_dof(name)
        b.add_mass(name, mass)
    b.add_spring({"slide.x": 1.0, "rotor": -p}, 1e14)  # a nut far stiffer than the rest
    b.add_spring({"rotor": 1.0}, kt)
    omega = _model(b).natural_frequencies()
    assert_allclose(omega[0], math.sqrt(kt / (j + m * p * p)), rtol=1e-6)


def test_spring_energy_is_half_k_times_the_squared_combination():
    rng = np.random.default_rng(4)
    b = StructureBuilder()
    for name in ("a", "b", "c"):
        b.add_dof(name)
    coefficients = {"a": 1.0, "b": -0.3, "c": 2.5}
    b.add_spring(coefficients, 8e3)
    _, k, dofs = b.assemble()
    u = rng.normal(size=3)
    c = np.array([coefficients[d] for d in dofs])
    assert_allclose(0.5 * u @ k.toarray() @ u, 0.5 * 8e3 * (c @ u) ** 2, rtol=1e-12)


STEEL = dict(e=2.1e11, rho=7850.0, nu=0.3)


def _cantilever(length=1.2, n_elements=24, direction=(1.0, 0.0, 0.0), area=2e-3, iy=4e-7,
                iz=9e-7, torsion=1.3e-6):
    b = StructureBuilder()
    b.add_node("root", (0.0, 0.0, 0.0))
    b.add_node("tip", tuple(length * np.asarray(direction)))
    b.add_beam("root", "tip", area=area, iy=iy, iz=iz, torsion=torsion,
               n_elements=n_elements, **STEEL)
    return b


@pytest.mark.parametrize("direction", [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.6, 0.0, 0.8)])
def test_beam_carries_its_mass_rho_a_l_in_every_translation(direction):
    length, area = 1.2, 2e-3
    b = _cantilever(length, 6, direction, area)
    m, _, dofs = b.assemble()
    for c in ("x", "y", "z"):
        u = np.array([1.0 if d.endswith(f".{c}") else 0.0 for d in dofs])
        assert_allclose(u @ m.toarray() @ u, STEEL["rho"] * area * length, rtol=1e-12)


def test_beam_stiffness_has_six_rigid_body_modes():
    # a free beam moves as a rigid body without strain: K has six zero eigenvalues, and the
    # next ones are far from zero
    _, k, _ = _cantilever(1.2, 4, (0.6, 0.0, 0.8)).assemble()
    eig = np.linalg.eigvalsh(k.toarray())
    scale = abs(eig).max()
    assert np.all(np.abs(eig[:6]) < 1e-9 * scale) and eig[6] > 1e-6 * scale


def test_cantilever_frequencies_match_the_closed_forms():
    length, area, iy, iz, torsion = 1.2, 2e-3, 4e-7, 9e-7, 1.3e-6
    e, rho, nu = STEEL["e"], STEEL["rho"], STEEL["nu"]
    g = e / (2 * (1 + nu))
    model = _model(_cantilever(length, 24, area=area, iy=iy, iz=iz, torsion=torsion),
                   held=[f"root.{c}" for c in NODE_DOFS])
    omega = model.natural_frequencies()
    phi = model.mode_shapes()
    dofs = model.dofs

    def frequencies_of(component, count):
        """The lowest modes whose motion is mostly in that DOF component (tip excluded)."""
        rows = np.array([d.endswith(f".{component}") for d in dofs])
        share = np.sum((model.mass @ phi) * phi * rows[:, None], axis=0)  # modal mass share
        return omega[share > 0.9][:count]

    def bending(i):
        return np.array([1.875104068711961, 4.694091132974175]) ** 2 * math.sqrt(
            e * i / (rho * area * length**4))

    # beam along x, up = z: deflection along y bends about z (Iz), along z about y (Iy)
    assert_allclose(frequencies_of("y", 2), bending(iz), rtol=1e-4)
    assert_allclose(frequencies_of("z", 2), bending(iy), rtol=1e-4)
    axial = np.array([1, 3]) * math.pi / (2 * length) * math.sqrt(e / rho)
    assert_allclose(frequencies_of("x", 2), axial, rtol=2e-3)
    # torsion: G J / (rho (Iy + Iz)) with the section's polar inertia as its rotary inertia
    twist = math.pi / (2 * length) * math.sqrt(g * torsion / (rho * (iy + iz)))
    assert_allclose(frequencies_of("rx", 1), [twist], rtol=2e-3)


def test_rigid_link_makes_the_offset_node_follow_the_master():
    # a point mass m on a rigid arm of length a from a hub held in all but rz: a grounded
    # torsion spring kt on rz swings the mass in y at sqrt(kt / (m a^2 + J)), J the rotary
    # inertia of hub and arm about z
    m, a, kt, j = 4.0, 0.25, 3e3, 1e-3
    b = StructureBuilder()
    b.add_node("hub", (0.0, 0.0, 0.0))
    b.add_node("arm", (a, 0.0, 0.0))
    b.add_rigid_link("hub", "arm", stiffness=1e10)
    b.add_mass("hub", j, inertia=(j, j, j))
    b.add_mass("arm", m, inertia=(j, j, j))
    b.add_spring({"hub.rz": 1.0}, kt)
    for c in ("x", "y", "z", "rx", "ry"):
        b.add_spring({f"hub.{c}": 1.0}, 1e10)  # the hub held apart from rz
    model = _model(b)
    assert_allclose(model.natural_frequencies()[0], math.sqrt(kt / (m * a * a + 2 * j)),
                    rtol=1e-5)
    shape = model.mode_shapes()[:, 0]
    rz, y = shape[model.index("hub.rz")], shape[model.index("arm.y")]
    # theta_z x (a, 0, 0) = (0, a theta_z, 0), to the give of the 1e10 N/m penalty springs
    assert_allclose(y / rz, a, rtol=1e-4)


def test_assembled_matrices_are_symmetric_and_scipy_agrees_on_the_chain():
    # second method for the eigenvalues: scipy's generalised symmetric solver on the sparse
    # matrices as assembled
    b = StructureBuilder()
    for i in range(4):
        b.add_dof(f"m{i}")
        b.add_mass(f"m{i}", 1.0 + i)
        b.add_spring({f"m{i}": 1.0} if i == 0 else {f"m{i}": 1.0, f"m{i - 1}": -1.0}, 1e4)
    m, k, dofs = b.assemble()
    assert dofs == ("m0", "m1", "m2", "m3")
    assert abs(k - k.T).max() == 0 and abs(m - m.T).max() == 0
    w2 = scipy.linalg.eigh(k.toarray(), m.toarray(), eigvals_only=True)
    assert_allclose(_model(b).natural_frequencies(), np.sqrt(w2), rtol=1e-10)
