"""Lowest modes with repeated eigenvalues, Sturm counts and the dense/iterative choice, against
closed forms (a symmetric star of identical arms) and dense LAPACK."""

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp
from numpy.testing import assert_allclose
from structure_star import arm_frequencies, star

from servotune.structure import count_eigenvalues_below, lowest_modes, solvers
from servotune.structure.solvers import DENSE_MAX


@pytest.fixture(scope="module")
def interior():
    """The star with its hub held: 8 identical fixed-free arms of 200 masses (1600 DOFs)."""
    mass, stiffness, _ = star()
    return mass[1:, 1:].tocsc(), stiffness[1:, 1:].tocsc()


def test_every_copy_of_a_repeated_eigenvalue_is_kept(interior):
    m_ii, k_ii = interior
    assert k_ii.shape[0] > DENSE_MAX  # the Lanczos path
    modes = lowest_modes(k_ii, m_ii, count=24)
    assert modes.method == "lanczos"
    # closed form: each fixed-free arm frequency 8 times (one per arm)
    expected = np.repeat(arm_frequencies(count=3), 8)
    assert_allclose(np.sqrt(modes.eigenvalues), expected, rtol=1e-10)
    # mass-normalised, and the copies span the 8-dimensional eigenspaces (independent)
    assert_allclose(modes.vectors.T @ (m_ii @ modes.vectors), np.eye(24), atol=1e-9)
    # the Sturm check holds: 24 modes below the point between the 3rd and 4th arm frequency
    point = np.mean(arm_frequencies(count=4)[2:4]) ** 2
    assert count_eigenvalues_below(k_ii, m_ii, point) == 24


@pytest.mark.parametrize("verify", ["deflation", "sturm"])
def test_a_structured_start_loses_copies_and_the_check_recovers_them(interior, verify):
    m_ii, k_ii = interior
    ones = np.ones(k_ii.shape[0])
    # the failure of a fixed all-ones start: the arms move alike, most copies never show up
    old = lowest_modes(k_ii, m_ii, count=24, v0=ones, verify="none")
    found = np.sqrt(old.eigenvalues)
    first = arm_frequencies(count=1)[0]
    assert np.sum(np.isclose(found, first, rtol=1e-8)) < 8
    assert found[-1] > 1.5 * arm_frequencies(count=3)[-1]  # higher modes fill the gap
    # the same start, checked (a deflated probe or a Sturm count shows the misses) and fixed
    # by deflated restarts
    fixed = lowest_modes(k_ii, m_ii, count=24, v0=ones, verify=verify)
    assert fixed.restarts >= 1
    assert_allclose(np.sqrt(fixed.eigenvalues), np.repeat(arm_frequencies(count=3), 8),
                    rtol=1e-10)


def test_modes_below_a_frequency_come_from_a_sturm_count(interior):
    m_ii, k_ii = interior
    f = arm_frequencies(count=6)
    cut = 0.5 * (f[4] + f[5])  # between the 5th and 6th arm frequencies: 40 modes
    modes = lowest_modes(k_ii, m_ii, below=cut**2)
    assert modes.eigenvalues.size == 40
    assert_allclose(np.sqrt(modes.eigenvalues), np.repeat(f[:5], 8), rtol=1e-10)
    assert modes.complete_below == pytest.approx(cut**2)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_sturm_count_equals_the_dense_count(seed):
    rng = np.random.default_rng(seed)
    n = 400  # above the dense shortcut of the count (n <= 200): the LDL^T inertia
    a = sp.random_array((n, n), density=0.01, rng=rng)
    k = (a @ a.T + sp.diags_array(rng.uniform(0.5, 2.0, n))).tocsc()
    m = sp.diags_array(rng.uniform(0.5, 2.0, n)).tocsc()
    w = scipy.linalg.eigh(k.toarray(), m.toarray(), eigvals_only=True)
    for value in rng.uniform(w[0], w[-1], 5):
        assert count_eigenvalues_below(k, m, value) == int(np.sum(w < value))


def test_dense_path_for_small_problems_and_many_modes(monkeypatch):
    # the rule at a small size: always dense below DENSE_MAX, else dense for >= 10 % of n
    monkeypatch.setattr(solvers, "DENSE_MAX", 100)
    n = 600
    k = sp.diags_array([2.0 * np.ones(n), -np.ones(n - 1), -np.ones(n - 1)], offsets=[0, 1, -1])
    m = sp.eye_array(n)
    few = lowest_modes(k, m, count=5)
    many = lowest_modes(k, m, count=80)  # >= 10 % of n at n <= 8000: dense, chosen up front
    assert many.next_eigenvalue > many.eigenvalues[-1]
    assert few.method == "lanczos" and many.method == "dense"
    j = np.arange(1, 81)
    exact = 4 * np.sin(j * np.pi / (2 * (n + 1))) ** 2  # fixed-fixed chain
    assert_allclose(many.eigenvalues, exact, rtol=1e-9)
    assert_allclose(few.eigenvalues, exact[:5], rtol=1e-9)


def test_shifted_solution_finds_rigid_body_modes():
    # a free chain: one rigid-body mode (lambda = 0), found with a negative shift
    n = 1800
    k = sp.diags_array([np.r_[1.0, 2.0 * np.ones(n - 2), 1.0], -np.ones(n - 1), -np.ones(n - 1)],
                       offsets=[0, 1, -1])
    modes = lowest_modes(k, sp.eye_array(n), count=4, shift=-1e-4)
    j = np.arange(4)
    assert_allclose(modes.eigenvalues, 4 * np.sin(j * np.pi / (2 * n)) ** 2, atol=1e-12,
                    rtol=1e-9)


def test_bad_requests_are_clear_errors(interior):
    m_ii, k_ii = interior
    with pytest.raises(ValueError, match="exactly one"):
        lowest_modes(k_ii, m_ii)
    with pytest.raises(ValueError, match=">= 0"):
        lowest_modes(k_ii, m_ii, count=-1)
