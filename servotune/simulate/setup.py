"""From an axis description to the models the simulation needs.

:func:`axis_setup` takes a loaded :class:`servotune.axis.Axis` and returns the structure, the
:class:`~servotune.drive.Drive` (with full velocity feed-forward unless the axis sets one: the
moving trials impose the speed through the reference), the pad DOFs, the axis' friction law
(axis totals; its LuGre parameters when it is LuGre) and the viscous-only damping of the "vd"
model.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ..drive import Drive
from ..friction.guideway import law_and_lugre
from ..friction.law import FrictionLaw
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
    lugre : LuGreParameters or None
        LuGre parameters of the friction (axis totals); None for another law.
    viscous : float
        Viscous-only guide-way damping [N s/m] of the "vd" model.
    law : FrictionLaw, optional
        The friction law (axis totals); default the LuGre law of ``lugre``.

    Raises
    ------
    ValueError
        Neither ``lugre`` nor ``law``, or both and different.
    """

    name: str
    structure: ModalModel
    drive: Drive
    pads: tuple[str, ...]
    lugre: LuGreParameters | None
    viscous: float
    law: FrictionLaw | None = None

    def __post_init__(self) -> None:
        law, lugre = law_and_lugre(self.law, self.lugre, "AxisSetup")
        object.__setattr__(self, "law", law)
        object.__setattr__(self, "lugre", lugre)


def axis_setup(axis) -> AxisSetup:
    """Return the structure, drive, pads, friction law and viscous-only damping of an axis.

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
                     lugre=axis.friction.lugre, viscous=axis.friction.viscous,
                     law=axis.friction.law)
