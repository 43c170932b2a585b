"""servotune.progress: bars only when asked for and only for long work; tasks say what runs."""

import io
import time

import pytest

from servotune import progress


def test_tasks_are_silent_unless_reporting_is_on():
    stream = io.StringIO()
    with progress.reporting(False, stream=stream), progress.task("work", total=3) as t:
        for _ in range(3):
            t.update()
    assert t.done == 3 and stream.getvalue() == ""
    assert not progress.enabled()


def test_a_long_task_shows_a_bar_on_the_stream(monkeypatch):
    monkeypatch.setattr(progress, "DELAY", 0.0)
    stream = io.StringIO()
    with progress.reporting(True, stream=stream), progress.task("trials", total=4,
                                                                unit="trial") as t:
        assert progress.enabled()
        for _ in range(4):
            t.update()
            time.sleep(0.25)  # beyond tqdm's minimum refresh interval
    text = stream.getvalue()
    assert "trials" in text and "/4" in text


def test_a_short_task_shows_nothing(monkeypatch):
    monkeypatch.setattr(progress, "DELAY", 60.0)
    stream = io.StringIO()
    with progress.reporting(True, stream=stream), progress.task("quick", total=2) as t:
        t.update(2)
    assert stream.getvalue() == ""


def test_a_task_without_total_shows_its_elapsed_time(monkeypatch):
    monkeypatch.setattr(progress, "DELAY", 0.0)
    monkeypatch.setattr(progress, "_TICK", 0.05)
    stream = io.StringIO()
    with progress.reporting(True, stream=stream), progress.task("eigen-solve"):
        time.sleep(0.3)
    assert "eigen-solve: 00:00" in stream.getvalue()


def test_report_is_a_done_total_callback():
    with progress.task("sweep", total=20.0, unit="s") as t:
        for done in (2.5, 10.0, 20.0):
            t.report(done, 20.0)
        assert str(t) == "sweep (20/20 s)"
        assert progress.current() == "sweep (20/20 s)"
    assert progress.current() is None


def test_the_innermost_interrupted_task_is_remembered():
    with progress.reporting(False):
        with pytest.raises(KeyboardInterrupt):
            with progress.task("study", total=3) as outer:
                outer.update()
                with progress.task("case 2 of 3: eigen-solve"):
                    raise KeyboardInterrupt
        assert progress.current() == "case 2 of 3: eigen-solve"
    assert progress.current() is None  # forgotten outside the reporting block
