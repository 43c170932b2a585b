"""Measured data in the loop: FRFs read from files (:mod:`~servotune.measured.frf`) and the
modes identified from them (:mod:`~servotune.measured.ema`); the axis' reduced model updated
to match a measurement (:mod:`~servotune.measured.update`); their figures
(:mod:`~servotune.measured.figures`).
"""

from .ema import IdentifiedMode, ModalIdentification, SelectionRule, identify_modes
from .frf import FrfFileError, MeasuredFrf, read_frfs
from .update import ModelUpdate, UpdateBounds, update_model, write_updated_axis

__all__ = ["FrfFileError", "IdentifiedMode", "MeasuredFrf", "ModalIdentification",
           "ModelUpdate", "SelectionRule", "UpdateBounds", "identify_modes", "read_frfs",
           "update_model", "write_updated_axis"]
