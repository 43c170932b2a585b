"""Regenerative chatter in milling: stability lobes from the tool/work-piece compliance.

The paper's measure of performance is the material removal capability, the regenerative-chatter
stability limit computed from the dynamic compliance at the tool/work-piece contact (Bianchi
et al. 2014, sec 2, "stability lobes diagrams"). This subpackage computes it two ways:

- :mod:`~servotune.chatter.zoa`: the zero-order approximation of Altintas and Budak (1995),
  fast and smooth in the compliance, with the absolute limit b_crit and a margin for tuning;
- :mod:`~servotune.chatter.sdm`: the semi-discretisation of Insperger and Stepan (2002, 2004),
  which keeps the time-periodic cutting force and finds the period-doubling (flip) lobes of low
  radial immersion.

:mod:`~servotune.chatter.setup` holds the milling set-up and the directional matrices;
:mod:`~servotune.chatter.frf` turns python-control systems, measured FRFs and arrays into the
2 x 2 compliance the analyses use.
"""

from .frf import (
    Mode,
    compliance_matrix,
    frequency_grid,
    modal_compliance,
    read_frf_csv,
    system_response,
)
from .sdm import (
    DEFAULT_INTERVALS,
    CuttingStateSpace,
    StabilityMap,
    cutting_state_space,
    monodromy_spectral_radius,
    sdm_lobes,
    stability_map,
)
from .setup import (
    MillingSetup,
    directional_factor,
    directional_matrix,
    periodic_directional_matrix,
)
from .zoa import (
    StabilityLobes,
    absolute_stability_limit,
    chatter_margin,
    critical_depth,
    default_speed_range,
    oriented_frf,
    spindle_speeds,
    stability_lobes,
)

__all__ = [
    "DEFAULT_INTERVALS",
    "CuttingStateSpace",
    "MillingSetup",
    "Mode",
    "StabilityLobes",
    "StabilityMap",
    "absolute_stability_limit",
    "chatter_margin",
    "compliance_matrix",
    "critical_depth",
    "cutting_state_space",
    "default_speed_range",
    "directional_factor",
    "directional_matrix",
    "frequency_grid",
    "modal_compliance",
    "monodromy_spectral_radius",
    "oriented_frf",
    "periodic_directional_matrix",
    "read_frf_csv",
    "sdm_lobes",
    "spindle_speeds",
    "stability_lobes",
    "stability_map",
    "system_response",
]
