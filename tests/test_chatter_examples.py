"""The milling-benchmark example runs (coarse settings) and shows the documented facts."""

import importlib.util
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_milling_stability_benchmark(tmp_path):
    figure = tmp_path / "benchmark.png"
    rows = load("milling_stability_benchmark").main(
        immersions=(1.0, 0.05), speed_range_rpm=(15000.0, 19000.0), speeds=21, intervals=30,
        depth_max=3e-3, figure=figure)
    slot, narrow = rows
    # full slot: close agreement, instability by a complex pair of multipliers
    assert slot["sdm_instability"] == "Hopf"
    assert slot["sdm_over_zoa"] == pytest.approx(1.07, abs=0.04)
    # a/D = 0.05: a flip lobe far below the zero-order limit
    assert narrow["sdm_instability"] == "flip"
    assert narrow["sdm_over_zoa"] < 0.7
    assert figure.stat().st_size > 50_000
