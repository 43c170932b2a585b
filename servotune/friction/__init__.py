"""Guide-way friction: the LuGre model, equivalent viscous damping, identification.

``lugre`` holds the model (parameters, steady state, dynamics, linearisations, simulation under
an imposed motion), ``equivalent`` the describing functions (the paper's stiction cycle in closed
form and the LuGre element numerically), ``identify`` the fits to measurements.
"""

from .equivalent import (
    describing_function,
    equivalent_damping_stiction,
    stiction_describing_function,
    stiction_peak_damping,
)
from .identify import (
    FrictionData,
    FrictionFit,
    IdentificationError,
    fit_presliding,
    fit_steady_state,
    read_friction_csv,
)
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
    micro_damping,
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
    "FrictionData",
    "FrictionFit",
    "HysteresisCycle",
    "IdentificationError",
    "LuGreJacobian",
    "LuGreParameters",
    "LuGreResponse",
    "describing_function",
    "equivalent_damping_stiction",
    "fit_presliding",
    "fit_steady_state",
    "lugre_cycle",
    "lugre_derivative",
    "lugre_force",
    "lugre_jacobian",
    "micro_damping",
    "presliding_linearisation",
    "read_friction_csv",
    "simulate_lugre",
    "sliding_linearisation",
    "steady_state_friction",
    "steady_state_slope",
    "stiction_describing_function",
    "stiction_peak_damping",
    "stribeck_curve",
]
