"""Shared test set-up: a backend with no screen."""

import matplotlib

matplotlib.use("Agg")

from pathlib import Path

import pytest

MODELS = Path(__file__).resolve().parents[1] / "models"


@pytest.fixture(autouse=True)
def _results_in_a_temporary_folder(tmp_path, monkeypatch):
    """A command run without --out writes into the test's temporary folder, never into the
    working copy's ./out."""
    from servotune.cli import _common

    monkeypatch.setattr(_common, "DEFAULT_OUT", str(tmp_path / "out"))


@pytest.fixture(scope="session")
def bundled_job():
    """The bundled axis tuned once for the whole session, with the nonlinear verdict (the
    main job of ``make demo``): (axis, AxisTuning)."""
    from servotune.axis import load_axis
    from servotune.design import tune_axis

    axis = load_axis(MODELS / "paper_x_axis")
    return axis, tune_axis(axis, starts=2, simulate=True)
