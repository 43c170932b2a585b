"""servotune: design of machine-tool feed axes where servo drive, guide-way friction and
structure interact, after Bianchi et al., "Analysis of vibration damping in machine tools",
Procedia CIRP 21 (2014) 367-372.

Use as ``import servotune as st``. SI units throughout (m, N, s, kg, rad).
"""

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

__version__ = "0.1.0"

__all__ = [
    "__version__",
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
]
