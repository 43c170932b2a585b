"""servotune: design of machine-tool feed axes where servo drive, guide-way friction and
structure interact, after Bianchi et al., "Analysis of vibration damping in machine tools",
Procedia CIRP 21 (2014) 367-372.

Use as ``import servotune as st``. SI units throughout (m, N, s, kg, rad).
"""

# structure: Craig-Bampton reduction, matrix files, builder; axis descriptions
from . import analysis, design
from .axis import Axis, AxisFormatError, Cutting, load_axis

# chatter: stability lobes (servotune.chatter)
from .chatter import (
    MillingSetup,
    Mode,
    StabilityLobes,
    StabilityMap,
    absolute_stability_limit,
    chatter_margin,
    critical_depth,
    modal_compliance,
    read_frf_csv,
    sdm_lobes,
    stability_lobes,
    stability_map,
)
from .drive import (
    Drive,
    LowPassFilter,
    Motor,
    NotchFilter,
    PIController,
    kv_from_m_per_min_per_mm,
    kv_to_m_per_min_per_mm,
)
from .frequency import (
    ClosedLoopPoles,
    LoopAnalysis,
    analyse_loop,
    closed_loop_poles,
    compliance,
    fast_frequency_response,
    following_error,
    modal_receptance,
    port_compliance,
)
from .friction import (
    BIANCHI2014,
    CANUDAS1995,
    HysteresisCycle,
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
    stribeck_curve,
)
from .friction.equivalent import (
    describing_function,
    equivalent_damping_stiction,
    stiction_describing_function,
)
from .friction.identify import FrictionFit, fit_presliding, fit_steady_state
from .plant import Contact, GuideWayFriction, UnstableLoopError, build_plant, loop_transfer
from .requirements import Requirements

# simulate
from .simulate import (
    LuGreFriction,
    NonlinearAxis,
    PadFriction,
    Scenario,
    SimulationError,
    SimulationResult,
    SweepEnvelope,
    ViscousFriction,
    WindowEnergies,
    circle,
    constant_speed,
    point_to_point,
    sine_sweep,
    sinusoid,
)
from .structure import (
    CraigBamptonCheck,
    MatrixFileError,
    ModalModel,
    StructureBuilder,
    UnknownDofError,
    cb_check,
    craig_bampton,
    read_structure,
    write_npz,
)
from .twomass import (
    TwoMassAnalysis,
    TwoMassSystem,
    analyse_two_mass,
    fixed_points,
    g_alpha,
    limit_resonances,
    minimax_damping,
    optimal_damping,
    optimal_peak,
    peak_compliance,
    two_mass_compliance,
)

# friction: velocity-dependent micro-damping (servotune.friction.lugre)
from .friction import micro_damping
# (the function is servotune.simulate.simulate: the name servotune.simulate stays the package)

__version__ = "0.1.0"

__all__ = [
    "__version__",
    "analysis",
    "design",
    # drive
    "Drive",
    "LowPassFilter",
    "Motor",
    "NotchFilter",
    "PIController",
    "kv_from_m_per_min_per_mm",
    "kv_to_m_per_min_per_mm",
    # plant
    "Contact",
    "GuideWayFriction",
    "Requirements",
    "UnstableLoopError",
    "build_plant",
    "loop_transfer",
    # frequency
    "ClosedLoopPoles",
    "LoopAnalysis",
    "analyse_loop",
    "closed_loop_poles",
    "compliance",
    "fast_frequency_response",
    "following_error",
    "modal_receptance",
    "port_compliance",
    # structure
    "ModalModel",
    "UnknownDofError",
    # structure: Craig-Bampton reduction, matrix files, builder; axis descriptions
    "craig_bampton",
    "cb_check",
    "CraigBamptonCheck",
    "read_structure",
    "write_npz",
    "MatrixFileError",
    "StructureBuilder",
    "Axis",
    "AxisFormatError",
    "Cutting",
    "load_axis",
    # twomass
    "TwoMassSystem",
    "TwoMassAnalysis",
    "analyse_two_mass",
    "fixed_points",
    "g_alpha",
    "limit_resonances",
    "minimax_damping",
    "optimal_damping",
    "optimal_peak",
    "peak_compliance",
    "two_mass_compliance",
    # friction
    "BIANCHI2014",
    "CANUDAS1995",
    "HysteresisCycle",
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
    "stribeck_curve",
    "describing_function",
    "equivalent_damping_stiction",
    "stiction_describing_function",
    "FrictionFit",
    "fit_presliding",
    "fit_steady_state",
    # chatter
    "MillingSetup",
    "Mode",
    "StabilityLobes",
    "StabilityMap",
    "absolute_stability_limit",
    "chatter_margin",
    "critical_depth",
    "modal_compliance",
    "read_frf_csv",
    "sdm_lobes",
    "stability_lobes",
    "stability_map",
    # simulate
    "LuGreFriction",
    "NonlinearAxis",
    "PadFriction",
    "Scenario",
    "SimulationError",
    "SimulationResult",
    "SweepEnvelope",
    "ViscousFriction",
    "WindowEnergies",
    "circle",
    "constant_speed",
    "point_to_point",
    "sine_sweep",
    "sinusoid",
    # friction: velocity-dependent micro-damping
    "micro_damping",
]
