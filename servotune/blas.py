"""One BLAS thread for servotune's work on small matrices.

The tuning, its checks, the design job and harmonic balance solve many small problems (tens to
a few hundred states): there threaded BLAS only adds the cost of waking its threads (the design
job of the bundled axis took 8.2 s with OpenBLAS on two threads against 5.8 s on one; on a
loaded machine five times as long). The ``servotune`` command sets the thread variables before
numpy is loaded; :func:`one_thread` gives library calls the same, for their duration only
(``threadpoolctl``), and restores the caller's limits afterwards. Large sparse work (the
Craig-Bampton reduction of an FE model) keeps the caller's threads.
"""

from __future__ import annotations

import functools

__all__ = ["one_thread"]


def one_thread(func):
    """Decorate a function to run with BLAS limited to one thread.

    Parameters
    ----------
    func : callable
        The function.

    Returns
    -------
    callable
        The function, with ``threadpoolctl.threadpool_limits(1, "blas")`` around each call
        (the previous limits restored when it returns or raises).
    """

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        from threadpoolctl import threadpool_limits

        with threadpool_limits(limits=1, user_api="blas"):
            return func(*args, **kwargs)

    return wrapper
