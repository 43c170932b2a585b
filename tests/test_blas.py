"""The library's work on small matrices runs on one BLAS thread (servotune.blas.one_thread),
and the caller's limits come back afterwards, also when the work raises."""

import numpy as np  # noqa: F401  (BLAS loaded, so that threadpoolctl sees it)
import pytest
from axis_fixtures import PADS, small_axis, small_drive
from threadpoolctl import threadpool_info, threadpool_limits

from servotune.blas import one_thread
from servotune.tuning import Requirements, TuningProblem, solve


def _blas_threads() -> int:
    return max(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")


@pytest.fixture
def two_threads():
    with threadpool_limits(limits=2, user_api="blas"):
        if _blas_threads() != 2:
            pytest.skip("this BLAS cannot be set to two threads")
        yield


def test_one_thread_inside_and_the_callers_limit_after(two_threads):
    seen = []

    @one_thread
    def work(x):
        seen.append(_blas_threads())
        return 2 * x

    assert work(3) == 6
    assert seen == [1] and _blas_threads() == 2


def test_tune_runs_on_one_thread_and_restores_the_limit_when_it_raises(two_threads, monkeypatch):
    seen = []

    class Stop(Exception):
        pass

    def first_stage(*args, **kwargs):
        seen.append(_blas_threads())
        raise Stop

    monkeypatch.setattr(solve, "stable_starts", first_stage)
    problem = TuningProblem(small_axis(), PADS, c=5e4, drive=small_drive(), free=("c", "kp"),
                            requirements=Requirements())
    with pytest.raises(Stop):
        solve.tune(problem)
    assert seen == [1] and _blas_threads() == 2
