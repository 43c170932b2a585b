"""Progress of long work on standard error, through tqdm; library code reports, the caller decides.

Library code wraps work that may take more than a second or two in :func:`task` and reports
steps on it; it knows nothing about the command line. Whether anything is shown is decided by
the caller with :func:`reporting` (the ``servotune`` command turns it on unless ``--quiet``,
``--json`` or standard error is not a terminal); without it, tasks only record what is going on,
so that an interruption can say what it interrupted (:func:`current`).

A bar appears only once its task has run for :data:`DELAY` seconds, so quick work stays silent,
and disappears when the task ends. A task without a total (one long eigen-solve, a reduction)
shows the elapsed time, refreshed twice a second.

Examples
--------
A loop over trials, and a callback for functions that take ``progress(done, total)``:

>>> from servotune import progress
>>> with progress.task("trials", total=3) as t:
...     for _ in range(3):
...         t.update()
>>> t.done
3
>>> with progress.task("sweep", total=20.0, unit="s") as t:
...     t.report(5.0, 20.0)          # e.g. simulate(..., progress=t.report)
...     str(t)
'sweep (5/20 s)'
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from collections.abc import Iterator
from contextvars import ContextVar

__all__ = ["DELAY", "Task", "reporting", "enabled", "task", "current"]

DELAY = 1.0      # [s] a task shows a bar only after running this long
_TICK = 0.5      # [s] refresh of a bar without a total (elapsed time)

_enabled: ContextVar[bool] = ContextVar("servotune_progress_enabled", default=False)
_stream: ContextVar[object] = ContextVar("servotune_progress_stream", default=None)
_active: ContextVar[tuple] = ContextVar("servotune_progress_active", default=())
_interrupted: ContextVar[list | None] = ContextVar("servotune_progress_interrupted",
                                                  default=None)


@contextlib.contextmanager
def reporting(enabled: bool = True, stream=None) -> Iterator[None]:
    """Show (or hide) progress bars of the tasks started inside the block.

    Parameters
    ----------
    enabled : bool
        True shows bars of tasks longer than :data:`DELAY`; False records tasks only.
    stream : file-like, optional
        Where bars go (default: standard error at the time a bar starts).
    """
    token_e = _enabled.set(bool(enabled))
    token_s = _stream.set(stream)
    token_i = _interrupted.set([])
    try:
        yield
    finally:
        _interrupted.reset(token_i)
        _stream.reset(token_s)
        _enabled.reset(token_e)


def enabled() -> bool:
    """Return whether tasks started now show a bar.

    Returns
    -------
    bool
        True when bars are shown.
    """
    return _enabled.get()


def _number(value) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


class Task:
    """A piece of long work in progress: what it is, how far it got.

    Created by :func:`task`; report with :meth:`update` (steps) or :meth:`report`
    (``(done, total)``, the form of callbacks such as ``simulate(..., progress=...)``).
    """

    def __init__(self, description: str, total=None, unit: str = "", bar=None):
        self.description = str(description)
        self.total = total
        self.unit = unit
        self.done = 0
        self._bar = bar

    def update(self, n=1) -> None:
        """Report ``n`` more steps done.

        Parameters
        ----------
        n : int or float, optional
            The increment (default 1).
        """
        self.done += n
        if self._bar is not None:
            self._bar.update(n)

    def report(self, done, total=None) -> None:
        """Report ``done`` of ``total`` steps (or seconds, or ...) done; a progress callback.

        Parameters
        ----------
        done : int or float
            Steps done so far (not an increment); the bar advances by the difference.
        total : int or float, optional
            The number of steps, when it changed or became known (default: unchanged).
        """
        if total is not None and total != self.total:
            self.total = total
            if self._bar is not None:
                self._bar.total = total
        step = done - self.done
        self.done = done
        if self._bar is not None and step:
            self._bar.update(step)

    def __str__(self) -> str:
        if self.total is None:
            return self.description
        unit = f" {self.unit}" if self.unit else ""
        return f"{self.description} ({_number(self.done)}/{_number(self.total)}{unit})"


def _bar(description: str, total, unit: str):
    from tqdm import tqdm

    stream = _stream.get() or sys.stderr
    return tqdm(desc=description, total=total, unit=unit or "it", file=stream, delay=DELAY,
                leave=False, dynamic_ncols=True, mininterval=0.2,
                bar_format=None if total is not None else "{desc}: {elapsed}")


def _ticker(bar, stop: threading.Event) -> None:
    """Refresh a bar without a total so that its elapsed time moves."""
    start = time.monotonic()
    while not stop.wait(_TICK):
        if time.monotonic() - start >= DELAY:
            bar.refresh()


@contextlib.contextmanager
def task(description: str, total=None, unit: str = "") -> Iterator[Task]:
    """Run a piece of long work as a task that reports its progress.

    Parameters
    ----------
    description : str
        What is being done, in words a user understands ("Craig-Bampton reduction of 51234
        DOFs"); also the text of an interruption message.
    total : int or float, optional
        Steps (or seconds of simulated time, ...) to do; None for work without steps (the bar
        then shows the elapsed time).
    unit : str
        Unit of the steps ("trial", "s").

    Yields
    ------
    Task
    """
    bar = _bar(description, total, unit) if _enabled.get() else None
    t = Task(description, total, unit, bar)
    token = _active.set((*_active.get(), t))
    stop = ticker = None
    if bar is not None and total is None:
        stop = threading.Event()
        ticker = threading.Thread(target=_ticker, args=(bar, stop), daemon=True)
        ticker.start()
    try:
        yield t
    except KeyboardInterrupt:
        record = _interrupted.get()
        if record is not None and not record:  # the innermost task is the one to name
            record.append(str(t))
        raise
    finally:
        if ticker is not None:
            stop.set()
            ticker.join()
        if bar is not None:
            bar.close()
        _active.reset(token)


def current() -> str | None:
    """Return the innermost task running now, as words with its progress.

    Or the one the last Ctrl-C inside the :func:`reporting` block interrupted.

    Returns
    -------
    str or None
        The task's description and progress, None when idle.
    """
    active = _active.get()
    if active:
        return str(active[-1])
    record = _interrupted.get()
    return record[0] if record else None
