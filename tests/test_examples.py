"""Every example runs, and its key numbers are checked against their references."""

import importlib.util
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_check_copt_against_fixed_points():
    rows = load("check_copt_against_fixed_points").main(alphas=(0.3, 0.6))
    for row in rows:
        # alpha < 1: the fixed-point optimum is the exact minimax optimum
        assert row["c_relative_difference"] == pytest.approx(0.0, abs=1e-5)
        assert row["peak_minimax"] == pytest.approx(row["peak_closed_form"], rel=1e-9)
    assert rows[0]["c_opt_closed_form"] == pytest.approx(4.912e5, rel=1e-4)  # paper, Fig 5
