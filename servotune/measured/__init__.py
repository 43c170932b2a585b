"""Measured data in the loop: FRFs read from files (:mod:`~servotune.measured.frf`) and the
modes identified from them (:mod:`~servotune.measured.ema`); their figures
(:mod:`~servotune.measured.figures`).

Updating an axis description from identified modes is not here yet.
"""

from .ema import IdentifiedMode, ModalIdentification, SelectionRule, identify_modes
from .frf import FrfFileError, MeasuredFrf, read_frfs

__all__ = ["FrfFileError", "IdentifiedMode", "MeasuredFrf", "ModalIdentification",
           "SelectionRule", "identify_modes", "read_frfs"]
