"""servotune: design of machine-tool feed axes where servo drive, guide-way friction and
structure interact, after Bianchi et al., "Analysis of vibration damping in machine tools",
Procedia CIRP 21 (2014) 367-372.

Use as ``import servotune as st``. SI units throughout (m, N, s, kg, rad).
"""

from .structure import ModalModel, UnknownDofError

# structure: Craig-Bampton reduction, matrix files, builder; axis descriptions
from .axis import Axis, AxisFormatError, load_axis
from .structure import (
    CraigBamptonCheck,
    MatrixFileError,
    StructureBuilder,
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

__version__ = "0.1.0"

__all__ = [
    "__version__",
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
]
