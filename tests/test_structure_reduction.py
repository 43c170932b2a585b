"""Craig-Bampton reduction and its check report against closed forms, published numbers,
the full model, and pyyeti's cb.cbcheck."""

import io
import math

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp
from numpy.testing import assert_allclose

from servotune.structure import (
    ModalModel,
    StructureBuilder,
    cb_check,
    craig_bampton,
    craig_bampton_basis,
    rigid_body_vectors,
)

TWO_PI = 2 * math.pi


def chain(n, m=2.0, k=5e4):
    """n equal masses, equal springs, the first grounded: sparse M, K."""
    main = np.full(n, 2 * k)
    main[-1] = k
    stiffness = sp.diags_array([main, -k * np.ones(n - 1), -k * np.ones(n - 1)],
                               offsets=[0, 1, -1]).tocsr()
    return m * sp.eye_array(n).tocsr(), stiffness


def frame(n_elements=4):
    """An L-shaped steel frame with a 50 kg tip mass, base node free (6 DOFs)."""
    b = StructureBuilder()
    points = {"base": (0.3, 0.2, 0.1), "top": (0.3, 0.2, 1.1), "arm": (1.0, 0.2, 1.1),
              "tip": (1.0, 0.8, 1.1)}
    for name, p in points.items():
        b.add_node(name, p)
    section = dict(e=2.1e11, area=1e-3, iy=2e-7, iz=3e-7, torsion=3e-7, rho=7850.0,
                   n_elements=n_elements)
    b.add_beam("base", "top", **section)
    b.add_beam("top", "arm", **section)
    b.add_beam("arm", "tip", **section)
    b.add_mass("tip", 50.0, (1.0, 2.0, 3.0))
    return b


def lowest_omega(stiffness, mass, count):
    """Reference frequencies by dense LAPACK on M phi = (1/omega^2) K phi: the low modes are
    the largest eigenvalues there, which the solver gets to full relative accuracy (eigh(K, M)
    loses about cond(M) eps on them with the tiny rotary masses of a consistent beam mass)."""
    lam = scipy.linalg.eigh(mass, stiffness, eigvals_only=True)[::-1]
    return 1.0 / np.sqrt(lam[:count])


def base_dofs(b):
    return [b.index(f"base.{c}") for c in ("x", "y", "z", "rx", "ry", "rz")]


# -- closed forms ----------------------------------------------------------------------------
def test_chain_fixed_interface_modes_are_the_fixed_fixed_chain():
    # boundary = the free end: the interior is a chain of n-1 masses held at both ends,
    # omega_j = 2 sqrt(k/m) sin(j pi / (2 n))
    n, m, k = 12, 2.0, 5e4
    mass, stiffness = chain(n, m, k)
    basis = craig_bampton_basis(mass, stiffness, [n - 1], n_modes=5)
    j = np.arange(1, 6)
    assert_allclose(basis.omega, 2 * np.sqrt(k / m) * np.sin(j * np.pi / (2 * n)), rtol=1e-12)


def test_chain_with_all_modes_has_the_analytic_frequencies():
    # fixed-free chain: omega_j = 2 sqrt(k/m) sin((2j-1) pi / (2 (2n+1)))
    n, m, k = 12, 2.0, 5e4
    mass, stiffness = chain(n, m, k)
    model = craig_bampton(mass, stiffness, [n - 1], n_modes=n - 1, damping_ratio=0.0)
    j = np.arange(1, n + 1)
    exact = 2 * np.sqrt(k / m) * np.sin((2 * j - 1) * np.pi / (2 * (2 * n + 1)))
    assert_allclose(model.natural_frequencies(), exact, rtol=1e-11)


def test_eigenvalues_converge_from_above_as_modes_are_added():
    # Rayleigh-Ritz: each reduced eigenvalue is >= the full one and falls as modes are added
    b = frame(n_elements=10)
    mass, stiffness, dofs = b.assemble()
    ground = base_dofs(b)
    keep = np.setdiff1d(np.arange(len(dofs)), ground)
    tip = [dofs.index(f"tip.{c}") for c in ("x", "y", "z")]
    sub = np.ix_(keep, keep)
    full = lowest_omega(stiffness.toarray()[sub], mass.toarray()[sub], 6)
    boundary = [int(np.flatnonzero(keep == t)[0]) for t in tip]
    m_sub, k_sub = mass[keep][:, keep], stiffness[keep][:, keep]
    previous = None
    for n_modes in (4, 8, 16, 32, 64):
        w = craig_bampton(m_sub, k_sub, boundary, n_modes=n_modes).natural_frequencies()[:6]
        assert np.all(w >= full * (1 - 1e-9))
        if previous is not None:
            assert np.all(w <= previous * (1 + 1e-9))
        previous = w
    assert_allclose(previous, full, rtol=2e-3)


def test_static_boundary_loads_are_reproduced_exactly():
    b = frame(n_elements=6)
    mass, stiffness, dofs = b.assemble()
    ground = base_dofs(b)
    keep = np.setdiff1d(np.arange(len(dofs)), ground)
    k_sub, m_sub = stiffness[keep][:, keep].tocsc(), mass[keep][:, keep]
    names = [dofs[i] for i in keep]
    boundary = [names.index(n) for n in ("tip.x", "tip.y", "tip.z", "arm.rz")]
    basis = craig_bampton_basis(m_sub, k_sub, boundary, n_modes=3)
    rng = np.random.default_rng(7)
    f_b = rng.normal(size=(len(boundary), 3)) * 1e3
    f = np.zeros((k_sub.shape[0], 3))
    f[boundary] = f_b
    u_full = sp.linalg.spsolve(k_sub, f)
    # the reduced static problem: K_bb,red u_b = f_b (modal coordinates carry no static load)
    u_b = np.linalg.solve(basis.stiffness[:4, :4], f_b)
    assert_allclose(u_b, u_full[boundary], rtol=1e-9)
    q = np.vstack([u_b, np.zeros((3, 3))])
    assert_allclose(basis.expand(q), u_full, rtol=1e-8, atol=1e-12 * np.abs(u_full).max())


def test_cut_off_keeps_exactly_the_modes_below_it():
    b = frame(n_elements=12)  # interior > 200 DOFs: the sparse Lanczos path
    mass, stiffness, dofs = b.assemble()
    boundary = base_dofs(b)
    interior = np.setdiff1d(np.arange(len(dofs)), boundary)
    assert interior.size > 200
    sub = np.ix_(interior, interior)
    w_dense = lowest_omega(stiffness.toarray()[sub], mass.toarray()[sub], 31)
    f_max = (w_dense[29] + w_dense[30]) / 2 / TWO_PI  # 30 modes: needs a second Lanczos round
    basis = craig_bampton_basis(mass, stiffness, boundary, f_max_hz=f_max)
    expected = w_dense[:30]
    assert basis.omega.size == 30
    assert_allclose(basis.omega, expected, rtol=1e-9)
    # fixed-interface modes are mass-normalised: Phi^T M_ii Phi = I
    m_ii = mass[interior][:, interior]
    phi = basis.fixed_interface_modes
    assert_allclose(phi.T @ (m_ii @ phi), np.eye(phi.shape[1]), atol=1e-9)


# -- a published case: welib's one-element beam ---------------------------------------------------
def welib_beam():
    # E. Branlard, welib, tests of welib/FEM/reduction.py (test_MeKe): a 2D Euler-Bernoulli
    # element, L = 100 m, EI = 1868211939147.334 N m^2, 8828.201296825122 kg/m
    length, ei, mu = 100.0, 1868211939147.334, 8828.201296825122
    L = length
    k = ei / L**3 * np.array([[12, 6 * L, -12, 6 * L], [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                              [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L * L, -6 * L, 4 * L * L]])
    m = mu * L / 420 * np.array([[156, 22 * L, 54, -13 * L],
                                 [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                                 [54, 13 * L, 156, -22 * L],
                                 [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    return m, k


def test_welib_one_element_beam():
    m, k = welib_beam()
    basis = craig_bampton_basis(m, k, [2, 3], n_modes=2)
    assert_allclose(basis.omega / TWO_PI, [0.817914, 8.058651], atol=5e-6)  # welib: 5 decimals
    assert_allclose(basis.mass[0, 0], 882820.12968, rtol=1e-10)             # total mass mu L
    # Guyan (boundary-only) frequencies of the free element are rigid-body: [0, 0]
    w2 = scipy.linalg.eigvalsh(basis.stiffness[:2, :2], basis.mass[:2, :2])
    assert_allclose(np.sqrt(np.abs(w2)) / TWO_PI, [0, 0], atol=1e-5)


def test_welib_pinned_beam():
    # welib, same test: first DOF removed (pinned), boundary = the other end;
    # f_CB = [4.74484], Guyan frequencies [0, 5.304894]
    m, k = welib_beam()
    m, k = m[1:, 1:], k[1:, 1:]
    basis = craig_bampton_basis(m, k, [1, 2], n_modes=1)
    assert_allclose(basis.omega / TWO_PI, [4.74484], atol=5e-6)
    w2 = scipy.linalg.eigvalsh(basis.stiffness[:2, :2], basis.mass[:2, :2])
    assert_allclose(np.sqrt(np.abs(w2)) / TWO_PI, [0.0, 5.304894], atol=5e-5)


# -- errors ------------------------------------------------------------------------------------
def test_a_boundary_that_does_not_restrain_the_structure_is_refused():
    b = frame()
    mass, stiffness, dofs = b.assemble()
    with pytest.raises(ValueError, match=r"mechanism|singular"):
        craig_bampton(mass, stiffness, [dofs.index("tip.x")], n_modes=2)


@pytest.mark.parametrize("kwargs, message", [
    ({"n_modes": 2, "f_max_hz": 10.0}, "exactly one"),
    ({}, "exactly one"),
    ({"n_modes": -1}, "non-negative"),
    ({"f_max_hz": -5.0}, "positive"),
    ({"n_modes": 1, "boundary_names": ["mode.9"]}, "reserved"),
    ({"n_modes": 1, "boundary_names": ["a", "b"]}, "2 boundary names for 1"),
])
def test_bad_arguments_are_clear_errors(kwargs, message):
    mass, stiffness = chain(5)
    with pytest.raises(ValueError, match=message):
        craig_bampton(mass, stiffness, [4], **kwargs)


@pytest.mark.parametrize("boundary, message", [
    ([7], "0..4"), ([1, 1], "duplicates"), ([], "empty"), ([0, 1, 2, 3, 4], "nothing to reduce"),
    ([0.5], "integer"),
])
def test_bad_boundaries_are_clear_errors(boundary, message):
    mass, stiffness = chain(5)
    with pytest.raises(ValueError, match=message):
        craig_bampton(mass, stiffness, boundary, n_modes=1)


def test_mismatched_matrices_are_refused():
    mass, stiffness = chain(5)
    with pytest.raises(ValueError, match="differ in size"):
        craig_bampton(mass[:4, :4], stiffness, [3], n_modes=1)


# -- the check report ---------------------------------------------------------------------------
def free_frame_model(n_modes=12):
    b = frame()
    mass, stiffness, dofs = b.assemble()
    boundary = base_dofs(b)
    model = craig_bampton(mass, stiffness, boundary, n_modes=n_modes,
                          boundary_names=[dofs[i] for i in boundary])
    return b, mass, model


def test_rigid_body_vectors_are_small_rotations():
    r = rigid_body_vectors(["p.x", "p.y", "p.z", "p.rz", "other"], {"p": (1.0, 2.0, 3.0)},
                           reference=(1.0, 0.0, 0.0))
    theta = np.array([0.0, 0.0, 0.0, 0.1, -0.2, 0.3])
    # displacement of p = theta x (p - ref) for the rotations
    expected = np.cross(theta[3:], np.array([0.0, 2.0, 3.0]))
    assert_allclose(r[:3] @ theta, expected)
    assert_allclose(r[3], [0, 0, 0, 0, 0, 1])
    assert_allclose(r[4], 0.0)


def test_rigid_body_mass_and_centre_of_gravity_are_the_physical_ones():
    b, _mass, model = free_frame_model()
    check = cb_check(model, coordinates=b.nodes)
    # independent: beam masses rho A L at their midpoints plus the 50 kg tip mass
    pts = {k: np.array(v) for k, v in {"base": (0.3, 0.2, 0.1), "top": (0.3, 0.2, 1.1),
                                       "arm": (1.0, 0.2, 1.1), "tip": (1.0, 0.8, 1.1)}.items()}
    segments = [("base", "top"), ("top", "arm"), ("arm", "tip")]
    masses = [7850 * 1e-3 * np.linalg.norm(pts[b2] - pts[a]) for a, b2 in segments] + [50.0]
    centres = [(pts[a] + pts[b2]) / 2 for a, b2 in segments] + [pts["tip"]]
    total = sum(masses)
    cg = sum(m * c for m, c in zip(masses, centres, strict=True)) / total
    assert_allclose(np.diag(check.rigid_body_mass)[:3], total, rtol=1e-10)
    assert_allclose(check.center_of_gravity, cg, rtol=1e-10)
    assert check.rigid_body_stiffness_residual < 1e-9  # a free structure: strain-free rigid motion
    assert check.passed
    text = str(check)
    assert "centre of gravity" in text and "passed" in text and "RZ" in text


def test_effective_mass_adds_up_to_the_rigid_body_mass():
    # with every fixed-interface mode kept (Phi Phi^T = M_ii^-1), the effective masses add up
    # to the rigid-body mass less R^T (M_bb - M_bi M_ii^-1 M_ib) R, the mass the boundary
    # carries itself (derived from L = Phi^T (M_ib + M_ii Psi) R)
    b = frame(n_elements=2)
    mass, stiffness, dofs = b.assemble()
    boundary = base_dofs(b)
    n_i = len(dofs) - 6
    model = craig_bampton(mass, stiffness, boundary, n_modes=n_i,
                          boundary_names=[dofs[i] for i in boundary])
    check = cb_check(model, coordinates=b.nodes)
    r = rigid_body_vectors([dofs[i] for i in boundary], b.nodes)
    full = mass.toarray()
    interior = np.setdiff1d(np.arange(len(dofs)), boundary)
    m_bi = full[np.ix_(boundary, interior)]
    schur = full[np.ix_(boundary, boundary)] - m_bi @ np.linalg.solve(
        full[np.ix_(interior, interior)], m_bi.T)
    own = np.diag(r.T @ schur @ r)
    assert_allclose(check.effective_mass.sum(axis=0) + own, np.diag(check.rigid_body_mass),
                    rtol=1e-8)


def test_grounded_model_fails_the_grounding_check():
    b, _mass, model = free_frame_model()
    grounded = model.with_added(stiffness={"base.x": 1e9})
    check = cb_check(grounded, coordinates=b.nodes)
    assert check.rigid_body_stiffness_residual > 1e-3
    assert not check.passed and "FAILED" in str(check)


def test_raw_matrices_asymmetric_or_indefinite_are_reported():
    m = np.diag([1.0, 2.0, 3.0])
    k = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    bad_k = k.copy()
    bad_k[0, 1] += 1e-3
    check = cb_check(m, bad_k, ["a", "b", "c"])
    assert check.stiffness_asymmetry > 1e-4 and not check.passed
    check = cb_check(np.diag([1.0, -2.0, 3.0]), k, ["a", "b", "c"])
    assert not check.mass_positive_definite and not check.passed


def test_axis_rigid_body_vector_gives_the_moving_mass():
    # a slide (pad.x) and a motor (rotor) geared by ratio r: the rigid motion along the axis
    # has generalised mass m + J / r^2
    m_slide, j_rotor, ratio, k = 500.0, 0.01, 2e-3, 1e8
    mass = np.diag([m_slide, j_rotor, 1.0])
    stiffness = np.array([[k, -k * ratio, 0], [-k * ratio, k * ratio**2, 0], [0, 0, 1e4]])
    model = ModalModel(mass, stiffness, ["pad.x", "motor.rotor", "mode.1"])
    check = cb_check(model, rigid_body=[1.0, 1.0 / ratio])
    assert_allclose(check.rigid_body_mass, [[m_slide + j_rotor / ratio**2]])
    assert check.rigid_body_stiffness_residual < 1e-12


@pytest.mark.filterwarnings("ignore:k >= N")  # pyyeti falls back to dense eigh
def test_cross_check_with_pyyeti_cbcheck():
    cb = pytest.importorskip("pyyeti.cb", reason="pyyeti is a test-only cross-check")
    n2p = pytest.importorskip("pyyeti.nastran.n2p")
    b, _mass, model = free_frame_model()
    ours = cb_check(model, coordinates=b.nodes, reference=(0.0, 0.0, 0.0))
    uset = n2p.addgrid(None, 1, "b", 0, list(b.nodes["base"]), 0)
    theirs = cb.cbcheck(io.StringIO(), model.mass, model.stiffness, np.arange(6), np.arange(6),
                        uset=uset, uref=(0.0, 0.0, 0.0))
    assert_allclose(ours.fixed_base_frequencies_hz, theirs.cb_frq, rtol=1e-9)
    assert_allclose(ours.effective_mass, np.asarray(theirs.effmass, dtype=float)[:12, :6],
                    rtol=1e-8, atol=1e-10 * ours.effective_mass.max())
    rbg = np.asarray(theirs.rbg)[:6]
    assert_allclose(rbg, rigid_body_vectors(model.dofs[:6], b.nodes), atol=1e-12)
    assert_allclose(rbg.T @ model.mass[:6, :6] @ rbg, ours.rigid_body_mass, rtol=1e-10)
