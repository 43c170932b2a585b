"""Guide-way friction: the LuGre model, equivalent viscous damping, identification.

``lugre`` holds the model (parameters, steady state, dynamics, linearisations, simulation under
an imposed motion), ``equivalent`` the describing functions (the paper's stiction cycle in closed
form and the LuGre element numerically), ``identify`` the fits to measurements.
"""

from .lugre import (
    BIANCHI2014,
    BIANCHI2014_SPREAD,
    CANUDAS1995,
    HysteresisCycle,
    LuGreJacobian,
    LuGreParameters,
    LuGreResponse,
    lugre_cycle,
    lugre_derivative,
    lugre_force,
    lugre_jacobian,
    presliding_linearisation,
    simulate_lugre,
    sliding_linearisation,
    steady_state_friction,
    steady_state_slope,
    stribeck_curve,
)

__all__ = [
    "BIANCHI2014",
    "BIANCHI2014_SPREAD",
    "CANUDAS1995",
    "HysteresisCycle",
    "LuGreJacobian",
    "LuGreParameters",
    "LuGreResponse",
    "lugre_cycle",
    "lugre_derivative",
    "lugre_force",
    "lugre_jacobian",
    "presliding_linearisation",
    "simulate_lugre",
    "sliding_linearisation",
    "steady_state_friction",
    "steady_state_slope",
    "stribeck_curve",
]
