"""Structural models: the reduced modal model, Craig-Bampton reduction and matrix files."""

from .builder import StructureBuilder
from .io import (
    MatrixFileError,
    StructureMatrices,
    read_coordinates,
    read_dof_map,
    read_harwell_boeing,
    read_matrix,
    read_structure,
    write_npz,
)
from .model import ModalModel, UnknownDofError, signal_name
from .reduction import (
    CraigBamptonBasis,
    CraigBamptonCheck,
    cb_check,
    craig_bampton,
    craig_bampton_basis,
    rigid_body_vectors,
)

__all__ = [
    "ModalModel",
    "UnknownDofError",
    "signal_name",
    # reduction
    "CraigBamptonBasis",
    "CraigBamptonCheck",
    "craig_bampton",
    "craig_bampton_basis",
    "cb_check",
    "rigid_body_vectors",
    # io
    "MatrixFileError",
    "StructureMatrices",
    "read_matrix",
    "read_dof_map",
    "read_coordinates",
    "read_structure",
    "read_harwell_boeing",
    "write_npz",
    # builder
    "StructureBuilder",
]
