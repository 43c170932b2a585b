"""Ctrl-C that is honoured everywhere: a flag that long-running code polls, and worker pools
that stop at once.

Python turns Ctrl-C (SIGINT) into ``KeyboardInterrupt``, but native code can swallow it:
casadi's IPOPT interface catches it, stops the solve and returns a failed status
("NonIpopt_Exception_Thrown") to the caller, which may go on with the next start. Inside
:func:`handling`, Ctrl-C also sets a flag, so that code after such a call (or inside an
iteration callback) can tell an interruption from a failure with :func:`requested` and end the
run with :func:`check`::

    with interrupt.handling():          # the servotune command does this around every run
        for start in starts:
            sol = solver(**args)        # IPOPT stops within one iteration on Ctrl-C ...
            interrupt.check("tuning")   # ... and this raises Interrupted instead of going on

Worker processes ignore Ctrl-C (:func:`ignore_in_worker`); :func:`process_pool` ends them at
once when the parent is interrupted, so the command returns within about a second instead of
waiting for every running job.

Examples
--------
>>> from servotune import interrupt
>>> interrupt.requested()
False
>>> interrupt.check()              # nothing pressed: returns
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator

__all__ = ["Interrupted", "handling", "requested", "check", "clear", "restore_stderr",
           "ignore_in_worker", "process_pool", "casadi_iteration_callback"]

_flag = threading.Event()
_mute = False          # silence native code's stderr once Ctrl-C is pressed (handling(...))
_saved_stderr = None   # the real file descriptor 2 while it is silenced


class Interrupted(KeyboardInterrupt):
    """The user pressed Ctrl-C; ``what`` names the work that was interrupted."""

    def __init__(self, what: str | None = None):
        super().__init__(what or "interrupted")
        self.what = what


def _silence_stderr() -> None:
    """Send file descriptor 2 to the null device until :func:`restore_stderr`."""
    global _saved_stderr
    if _saved_stderr is not None:
        return
    try:
        with contextlib.suppress(Exception):
            sys.stderr.flush()
        saved = os.dup(2)
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 2)
        os.close(null)
        _saved_stderr = saved
    except OSError:  # no file descriptor 2 to silence
        pass


def restore_stderr() -> None:
    """Give file descriptor 2 back after an interruption silenced it (see :func:`handling`);
    call it before printing what was interrupted."""
    global _saved_stderr
    if _saved_stderr is None:
        return
    with contextlib.suppress(Exception):
        sys.stderr.flush()
    os.dup2(_saved_stderr, 2)
    os.close(_saved_stderr)
    _saved_stderr = None


def _on_sigint(signum, frame):
    _flag.set()
    if _mute:
        _silence_stderr()
    raise KeyboardInterrupt


@contextlib.contextmanager
def handling(silence_native_stderr: bool = False) -> Iterator[None]:
    """Inside the block, Ctrl-C raises ``KeyboardInterrupt`` as usual and also sets the flag
    of :func:`requested`. Outside the main thread, or when another handler than Python's
    default one is installed, the block changes nothing (the flag is still cleared on entry).

    Parameters
    ----------
    silence_native_stderr : bool
        From the Ctrl-C on, send standard error (file descriptor 2) to the null device until
        :func:`restore_stderr` or the end of the block: native code that the interruption
        passes through writes its own lines there (scipy's f2py callbacks "capi_return is
        NULL", casadi's "KeyboardInterruptException"), and a command wants to end with one
        line of its own. The ``servotune`` command sets it.
    """
    global _mute
    _flag.clear()
    installed = False
    muted = _mute
    if threading.current_thread() is threading.main_thread():
        previous = signal.getsignal(signal.SIGINT)
        if previous in (signal.default_int_handler, _on_sigint):
            signal.signal(signal.SIGINT, _on_sigint)
            installed = True
            _mute = silence_native_stderr
    try:
        yield
    finally:
        if installed:
            signal.signal(signal.SIGINT, previous)
            _mute = muted
        restore_stderr()


def requested() -> bool:
    """Return whether Ctrl-C was pressed since :func:`handling` was entered (or :func:`clear`).

    Returns
    -------
    bool
        True after a Ctrl-C.
    """
    return _flag.is_set()


def check(what: str | None = None) -> None:
    """Raise :class:`Interrupted` if Ctrl-C was pressed; call it after native code that may
    have swallowed the ``KeyboardInterrupt`` (an IPOPT solve) and in long loops.

    Parameters
    ----------
    what : str, optional
        The work being interrupted, for the message ("tuning, start 3 of 4").
    """
    if _flag.is_set():
        raise Interrupted(what)


def clear() -> None:
    """Forget an earlier Ctrl-C."""
    _flag.clear()


def ignore_in_worker() -> None:
    """Initializer of worker processes: ignore Ctrl-C there (the parent ends them)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def process_pool(workers: int) -> Iterator[object]:
    """A ``concurrent.futures.ProcessPoolExecutor`` whose workers ignore Ctrl-C and are
    terminated at once when the block ends with an exception (Ctrl-C included), instead of
    being waited for.

    Parameters
    ----------
    workers : int
        Number of processes (>= 1).
    """
    from concurrent.futures import ProcessPoolExecutor

    pool = ProcessPoolExecutor(max_workers=workers, initializer=ignore_in_worker)
    try:
        yield pool
    except BaseException:
        # the executor has no public way to stop running jobs: end its processes
        processes = list((getattr(pool, "_processes", None) or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            with contextlib.suppress(Exception):
                process.terminate()
        for process in processes:
            with contextlib.suppress(Exception):
                process.join(timeout=2.0)
                if process.is_alive():  # a loaded machine: make sure
                    process.kill()
                    process.join(timeout=2.0)
        # the executor's own thread may reap a worker at the same time (then this thread's
        # wait sees no child and the exit code arrives a moment later): wait for every code
        deadline = time.monotonic() + 5.0
        while any(p.exitcode is None for p in processes) and time.monotonic() < deadline:
            time.sleep(0.02)
        raise
    else:
        pool.shutdown(wait=True)


def casadi_iteration_callback(name: str = "servotune_interrupt", n_x: int = 0,
                              n_g: int = 0, stop=None):
    """Return a casadi ``iteration_callback`` that asks IPOPT to stop when Ctrl-C was pressed.

    casadi's IPOPT interface already stops on Ctrl-C by itself; this callback also stops it
    when the flag was set elsewhere (another thread, a worker that reported an interruption).
    Pass it as ``nlpsol(..., {"iteration_callback": cb})`` and keep a reference to it while the
    solver lives; follow the solve by :func:`check`.

    Parameters
    ----------
    name : str
        Name of the casadi function.
    n_x, n_g : int
        Number of variables and constraints of the NLP (0: the callback does not read them).
    stop : callable, optional
        Called at every iteration without arguments; a true result stops IPOPT too (e.g. an
        iteration limit per solve).

    Returns
    -------
    casadi.Callback
        The callback; it returns 1 (stop) once the interruption flag is set or ``stop()`` is
        true, else 0.
    """
    import casadi as ca

    class _Callback(ca.Callback):
        def __init__(self):
            ca.Callback.__init__(self)
            self.construct(name, {})

        def get_n_in(self):
            return ca.nlpsol_n_out()

        def get_n_out(self):
            return 1

        def get_name_in(self, i):
            return ca.nlpsol_out(i)

        def get_name_out(self, i):
            return "ret"

        def get_sparsity_in(self, i):
            label = ca.nlpsol_out(i)
            if label == "f":
                return ca.Sparsity.scalar()
            if label in ("x", "lam_x"):
                return ca.Sparsity.dense(n_x)
            if label in ("g", "lam_g"):
                return ca.Sparsity.dense(n_g)
            return ca.Sparsity(0, 0)

        def eval(self, arg):
            return [1 if _flag.is_set() or (stop is not None and stop()) else 0]

    return _Callback()
