"""The closed-loop state matrices of the tuner's stability checks (multi-affine form) against
the plants built by python-control interconnection."""

import dataclasses
from pathlib import Path

import control
import numpy as np
import pytest

from servotune import frequency
from servotune.axis import load_axis
from servotune.design import tuning_problem
from servotune.tuning.solve import ClosedLoopMatrices, model_stability

MODELS = Path(__file__).resolve().parents[1] / "models"


@pytest.fixture(scope="module")
def problem():
    # the multi-affine form is that of the continuous drive (a digital one is a sampled-data
    # loop whose stability comes from its multipliers, servotune.digital)
    axis = load_axis(MODELS / "paper_x_axis").with_continuous_drive()
    s = axis.tuning
    return tuning_problem(axis, s.free, s.chatter_weight, s.bounds)


def _draws(problem, n, seed):
    rng = np.random.default_rng(seed)
    x0 = problem.initial_design()
    for _ in range(n):
        yield dataclasses.replace(x0, **{
            v: float(np.exp(rng.uniform(*np.log(problem.bounds[v])))) for v in problem.free})


def test_the_multi_affine_matrices_equal_the_built_plants_over_the_bounds(problem):
    matrices = ClosedLoopMatrices(problem)
    assert matrices.exact
    stable = []
    for d in _draws(problem, 12, seed=7):
        for a, model in zip(matrices(d), problem.regimes, strict=True):
            built = matrices.build(model, d)
            np.testing.assert_allclose(a, built.A, rtol=0, atol=1e-12 * np.abs(built.A).max())
            # the verdict on stability is the same as from the built plant
            ok = frequency.is_stable_matrix(a)
            assert ok == frequency.is_stable(built)
            stable.append(ok)
    assert any(stable) and not all(stable)  # both outcomes occur among the draws


def test_a_drive_outside_the_form_is_built_design_by_design(problem, monkeypatch):
    # a matrix with a Kv^2 term: the check at the seventh design fails, every design is
    # then built and the stability is that of the built plants
    original = ClosedLoopMatrices.build

    def build(self, model, design):
        plant = original(self, model, design)
        a = plant.A.copy()
        a[0, 0] += 1e-3 * design.kv ** 2
        return control.ss(a, plant.B, plant.C, plant.D)

    monkeypatch.setattr(ClosedLoopMatrices, "build", build)
    matrices = ClosedLoopMatrices(problem)
    assert not matrices.exact
    d = next(_draws(problem, 1, seed=3))
    for a, model in zip(matrices(d), problem.regimes, strict=True):
        np.testing.assert_array_equal(a, build(matrices, model, d).A)
    fresh = dataclasses.replace(problem)  # a new problem object: not the kept matrices
    assert model_stability(fresh, d) == [frequency.is_stable_matrix(a) for a in matrices(d)]
