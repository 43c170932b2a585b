"""Measured data in the loop: FRFs read from files (:mod:`~servotune.measured.frf`) and the
modes identified from them (:mod:`~servotune.measured.ema`); the axis' reduced model updated
to match a measurement (:mod:`~servotune.measured.update`); the drive's measured speed plant
against the model's, with the velocity loop closed on it (:mod:`~servotune.measured.speed_plant`);
the closed-loop work-piece compliance as a test configuration of the updating
(:mod:`~servotune.measured.closed_loop`); their figures (:mod:`~servotune.measured.figures`).
"""

from .closed_loop import ClosedLoopTest
from .ema import IdentifiedMode, ModalIdentification, SelectionRule, identify_modes
from .frf import FrfFileError, MeasuredFrf, read_frfs
from .speed_plant import (
    SpeedPlantComparison,
    compare_speed_plant,
    model_speed_plant,
    velocity_loop_response,
)
from .update import ModelUpdate, StructureTest, UpdateBounds, update_model, write_updated_axis

__all__ = ["ClosedLoopTest", "FrfFileError", "IdentifiedMode", "MeasuredFrf",
           "ModalIdentification", "ModelUpdate", "SelectionRule", "SpeedPlantComparison",
           "StructureTest", "UpdateBounds", "compare_speed_plant", "identify_modes",
           "model_speed_plant", "read_frfs", "update_model", "velocity_loop_response",
           "write_updated_axis"]
