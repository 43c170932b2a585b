"""Figures rendered in several processes (servotune.report.render_figures): the same bytes as
rendered one after the other here, in the order given, also when a child fails. (A figure is
compared in its first rendering: a second one of the same figure object can differ, as the
constrained layout starts from the first's result.)"""

import os

import numpy as np
import pytest
from matplotlib.figure import Figure

from servotune import report


def _figures(n):
    out = []
    for k in range(n):
        fig = Figure(figsize=(3.0, 2.0), layout="constrained")
        ax = fig.subplots()
        x = np.geomspace(1.0, 1e3, 50 + 400 * k)  # different sizes: shared out unevenly
        ax.loglog(x, 1.0 / (1.0 + (x / (10.0 * (k + 1))) ** 2))
        ax.set_title(f"figure {k}")
        out.append(fig)
    return out


def _serial(n):
    return report.render_figures(_figures(n), workers=1)


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs os.fork")
@pytest.mark.parametrize("workers", [2, 3, 8])
def test_forked_rendering_gives_the_serial_bytes_in_order(workers):
    want = _serial(5)
    assert len({len(b) for b in want}) > 1 and all(b.startswith(b"\x89PNG") for b in want)
    assert report.render_figures(_figures(5), workers=workers) == want


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs os.fork")
def test_a_failing_child_leaves_its_figures_to_this_process(monkeypatch):
    # the children's share is rendered here when a child ends without its file (here: every
    # child exits at once with status 1, before rendering anything)
    want = _serial(4)
    parent = os.getpid()
    real_fork = os.fork

    def failing_fork():
        pid = real_fork()
        if pid == 0:
            os._exit(1)
        return pid

    monkeypatch.setattr(os, "fork", failing_fork)
    assert report.render_figures(_figures(4), workers=2) == want
    assert os.getpid() == parent


def test_no_figures_and_one_worker():
    assert report.render_figures([], workers=4) == []
    assert report.render_figures(_figures(1), workers=4) == _serial(1)


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs os.fork")
def test_no_process_to_be_had_renders_everything_here(monkeypatch):
    def no_fork():
        raise OSError("Resource temporarily unavailable")

    monkeypatch.setattr(os, "fork", no_fork)
    assert report.render_figures(_figures(3), workers=3) == _serial(3)
