"""Sturm counts (negative pivots of SuperLU's symmetric-mode factors of K - s M) against the
number of eigenvalues below s from dense eigvalsh, and the pivots read in place against scipy's
copy of U."""

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp

from servotune.structure import count_eigenvalues_below, lowest_modes, solvers


def _spd_pencil(n, seed, density=0.02):
    rng = np.random.default_rng(seed)
    a = sp.random_array((n, n), density=density, rng=rng)
    k = (a @ a.T + sp.diags_array(rng.uniform(0.1, 1.0, n))).tocsc()
    b = sp.random_array((n, n), density=density / 2, rng=rng)
    m = (0.1 * (b @ b.T) + sp.diags_array(rng.uniform(0.5, 2.0, n))).tocsc()
    return k, m


def _shifts_between(w, rng, count=6):
    # points in the gaps between eigenvalues (never on one), spread over the spectrum
    gaps = rng.choice(w.size - 1, count, replace=False)
    return 0.5 * (w[gaps] + w[gaps + 1])


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_sturm_count_equals_eigvalsh_on_random_spd_pencils(seed):
    n = 300  # above the dense shortcut of the count (n <= 200): SuperLU's pivots
    k, m = _spd_pencil(n, seed)
    w = scipy.linalg.eigvalsh(k.toarray(), m.toarray())
    rng = np.random.default_rng(seed + 100)
    ordering = solvers.factorise(k, "superlu").ordering
    for value in _shifts_between(w, rng):
        expected = int(np.sum(w < value))
        assert count_eigenvalues_below(k, m, value) == expected
        # the same count in the ordering of K's own factors (reused by lowest_modes)
        assert count_eigenvalues_below(k, m, value, ordering=ordering) == expected


def test_sturm_count_with_repeated_modes():
    # four identical uncoupled blocks: every eigenvalue of a block appears four times
    block, mass = _spd_pencil(60, 7, density=0.08)
    k = sp.block_diag([block] * 4, format="csc")
    m = sp.block_diag([mass] * 4, format="csc")
    w_block = scipy.linalg.eigvalsh(block.toarray(), mass.toarray())
    w = scipy.linalg.eigvalsh(k.toarray(), m.toarray())
    assert np.allclose(np.repeat(w_block, 4), w, rtol=1e-9)
    for j in (0, 4, 17, 40):
        value = 0.5 * (w_block[j] + w_block[j + 1])
        assert count_eigenvalues_below(k, m, value) == int(np.sum(w < value)) == 4 * (j + 1)
    # just above and just below a four-fold eigenvalue
    lam = w_block[10]
    assert count_eigenvalues_below(k, m, lam * (1 + 1e-7)) == 44
    assert count_eigenvalues_below(k, m, lam * (1 - 1e-7)) == 40


def test_a_bad_ordering_is_refused():
    k, m = _spd_pencil(250, 8)
    with pytest.raises(ValueError, match="permutation"):
        count_eigenvalues_below(k, m, 1.0, ordering=np.zeros(250, dtype=int))


def test_pivots_read_in_place_equal_scipys_copy_of_u():
    k, m = _spd_pencil(400, 9)
    w = scipy.linalg.eigvalsh(k.toarray(), m.toarray())
    lu = solvers._superlu(k - w[37] * 1.0001 * m)  # indefinite: 38 negative pivots
    assert np.array_equal(lu.perm_r, lu.perm_c)
    d = solvers._u_diagonal_in_place(lu)
    assert d is not None
    assert np.array_equal(d, lu.U.diagonal())
    assert int(np.sum(d < 0)) == 38


def test_reading_falls_back_to_scipys_copy(monkeypatch):
    monkeypatch.setattr(solvers, "_u_diagonal_in_place", lambda lu: None)
    k, m = _spd_pencil(250, 10)
    w = scipy.linalg.eigvalsh(k.toarray(), m.toarray())
    value = 0.5 * (w[20] + w[21])
    assert count_eigenvalues_below(k, m, value) == 21


def test_lowest_modes_checks_a_count_by_sturm_by_default(monkeypatch):
    monkeypatch.setattr(solvers, "DENSE_MAX", 100)
    n = 600
    k = sp.diags_array([2.0 * np.ones(n), -np.ones(n - 1), -np.ones(n - 1)],
                       offsets=[0, 1, -1]).tocsc()
    m = sp.eye_array(n, format="csc")
    counted = []
    original = solvers.count_eigenvalues_below

    def spy(*args, **kwargs):
        counted.append(kwargs.get("ordering") is not None)
        return original(*args, **kwargs)

    monkeypatch.setattr(solvers, "count_eigenvalues_below", spy)
    modes = lowest_modes(k, m, count=6)
    assert counted == [True]  # one Sturm count, in the ordering of the factors of K
    j = np.arange(1, 7)
    assert np.allclose(modes.eigenvalues, 4 * np.sin(j * np.pi / (2 * (n + 1))) ** 2,
                       rtol=1e-9)
    assert modes.complete_below > modes.eigenvalues[-1]


def test_an_off_diagonal_pivot_moves_the_shift(monkeypatch):
    # K - 5 M has a 2x2 block [[0, 1], [1, 0]]: SuperLU must pivot off the diagonal there, the
    # inertia is then not in diag(U) and the count is repeated at a slightly moved shift
    n = 300
    d = np.linspace(1.0, 10.0, n)
    k = sp.lil_array(sp.diags_array(d))
    k[10, 10] = k[11, 11] = 5.0
    k[10, 11] = k[11, 10] = 1.0
    k, m = k.tocsc(), sp.eye_array(n, format="csc")
    w = scipy.linalg.eigvalsh(k.toarray())
    same = []
    original = solvers._superlu

    def spy(a, *args):
        lu = original(a, *args)
        same.append(bool(np.array_equal(lu.perm_r, lu.perm_c)))
        return lu

    monkeypatch.setattr(solvers, "_superlu", spy)
    assert count_eigenvalues_below(k, m, 5.0) == int(np.sum(w < 5.0))
    assert same[0] is False and same[-1] is True
