"""Structural models: the reduced modal model, Craig-Bampton reduction and its checks, matrix
files and the ports of an FE export."""

from .builder import StructureBuilder
from .cbcheck import CraigBamptonCheck, cb_check, rigid_body_vectors
from .coverage import BandCoverage, fixed_interface_frequencies, mode_coverage
from .io import (
    MatrixFileError,
    StructureMatrices,
    read_coordinates,
    read_dof_map,
    read_harwell_boeing,
    read_matrix,
    read_op4,
    read_structure,
    write_npz,
)
from .model import ModalModel, ReductionInfo, UnknownDofError, signal_name
from .ports import (
    Port,
    PortError,
    apply_signs,
    name_ports,
    normalise_direction,
    port_signs,
    read_ports,
    signed_direction,
)
from .reduction import CraigBamptonBasis, craig_bampton, craig_bampton_basis
from .reduction_check import ReductionCheck, reduction_check
from .solvers import Modes, count_eigenvalues_below, lowest_modes

__all__ = [
    "ModalModel",
    "ReductionInfo",
    "UnknownDofError",
    "signal_name",
    # reduction
    "CraigBamptonBasis",
    "craig_bampton",
    "craig_bampton_basis",
    # eigen-solutions
    "Modes",
    "lowest_modes",
    "count_eigenvalues_below",
    # checks
    "CraigBamptonCheck",
    "cb_check",
    "rigid_body_vectors",
    "BandCoverage",
    "mode_coverage",
    "fixed_interface_frequencies",
    "ReductionCheck",
    "reduction_check",
    # io
    "MatrixFileError",
    "StructureMatrices",
    "read_matrix",
    "read_op4",
    "read_dof_map",
    "read_coordinates",
    "read_structure",
    "read_harwell_boeing",
    "write_npz",
    # ports of an FE export
    "Port",
    "PortError",
    "name_ports",
    "port_signs",
    "apply_signs",
    "normalise_direction",
    "signed_direction",
    "read_ports",
    # builder
    "StructureBuilder",
]
