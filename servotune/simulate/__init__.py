"""Nonlinear time simulation of the feed axis with LuGre guide-way friction (paper sec 5.3)."""

from .contact import LuGreFriction, PadFriction, ViscousFriction
from .result import SimulationError, SimulationResult, SweepEnvelope, WindowEnergies
from .scenario import (
    Scenario,
    circle,
    constant_speed,
    custom,
    point_to_point,
    sine_sweep,
    sinusoid,
)
from .simulator import NonlinearAxis, simulate
from .system import AxisSystem, axis_system

__all__ = [
    "AxisSystem",
    "LuGreFriction",
    "NonlinearAxis",
    "PadFriction",
    "Scenario",
    "SimulationError",
    "SimulationResult",
    "SweepEnvelope",
    "ViscousFriction",
    "WindowEnergies",
    "axis_system",
    "circle",
    "constant_speed",
    "custom",
    "point_to_point",
    "simulate",
    "sine_sweep",
    "sinusoid",
]
