"""From an axis description to the models the simulation needs.

:func:`axis_setup` takes a loaded :class:`servotune.axis.Axis` and returns the structure, the
:class:`~servotune.drive.Drive` (with full velocity feed-forward unless the axis sets one: the
moving trials impose the speed through the reference), the pad DOFs, the axis-total LuGre
parameters and the viscous-only damping of the "vd" model.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ..drive import Drive
from ..friction.lugre import LuGreParameters
from ..structure.model import ModalModel

__all__ = ["AxisSetup", "axis_setup"]


@dataclass(frozen=True, eq=False)
class AxisSetup:
    """What a simulation of an axis description needs (SI).

    Parameters
    ----------
    name : str
        The axis' name.
    structure : ModalModel
        The structure.
    drive : Drive
        The drive.
    pads : tuple of str
        The guide-way pad DOFs.
    lugre : LuGreParameters
        LuGre parameters of the friction (axis totals).
    viscous : float
        Viscous-only guide-way damping [N s/m] of the "vd" model.
    """

    name: str
    structure: ModalModel
    drive: Drive
    pads: tuple[str, ...]
    lugre: LuGreParameters
    viscous: float


def axis_setup(axis) -> AxisSetup:
    """Return the structure, drive, pads, LuGre parameters and viscous-only damping of an axis.

    The "vd" damping is ``[friction] viscous`` [N s/m] (default: the LuGre sigma2, the viscous
    part of the identified friction). The drive gets full velocity feed-forward unless
    ``[drive.feedforward] velocity`` is given.

    Parameters
    ----------
    axis : Axis
        A loaded axis description (:func:`servotune.axis.load_axis`).

    Returns
    -------
    AxisSetup
        What the simulation needs.

    Raises
    ------
    AxisFormatError
        If the axis has no ``[friction]`` or no ``[drive]``.
    """
    pads = axis.pads  # clear error when [friction] is missing
    drive = axis.require_drive()
    if "velocity" not in axis.tables.get("drive", {}).get("feedforward", {}):
        drive = dataclasses.replace(drive, velocity_feedforward=1.0)
    return AxisSetup(name=axis.name, structure=axis.structure, drive=drive, pads=pads,
                     lugre=axis.friction.lugre, viscous=axis.friction.viscous)
