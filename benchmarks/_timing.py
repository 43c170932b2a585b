"""Timing shared by the benchmark scripts (run from this folder's parent, or any folder: the
scripts put their own folder on the import path)."""

import time

__all__ = ["best_time"]


def best_time(fn, repeat):
    """The shortest of ``repeat`` wall-clock times of ``fn()`` [s] and its last result."""
    times, out = [], None
    for _ in range(max(int(repeat), 1)):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out
