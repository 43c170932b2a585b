"""Structural models: the reduced modal model, Craig-Bampton reduction and matrix files."""

from .model import ModalModel, UnknownDofError, signal_name

__all__ = ["ModalModel", "UnknownDofError", "signal_name"]
