"""The friction of an axis as its description holds it: the pads and the law that acts there.

The axis description (:mod:`servotune.axis`) keeps its guide-way friction as a
:class:`GuideWayFriction`: the pad DOFs, the friction law (any registered
:class:`~servotune.friction.law.FrictionLaw`, axis totals shared equally by the pads) and the
viscous-only damping of the paper's "vd" model. The linear contacts of the plant are built from
it by :func:`servotune.plant.friction_contact`; the time simulation and harmonic balance take
its law.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .law import FrictionLaw, friction_law, friction_law_names
from .lugre import LuGreParameters

__all__ = ["GuideWayFriction", "law_and_lugre"]


def law_and_lugre(law, lugre, owner: str):
    """Return ``(law, lugre)`` from a friction law or LuGre parameters, whichever is given.

    Parameters
    ----------
    law : FrictionLaw or None
        The friction law.
    lugre : LuGreParameters or None
        LuGre parameters (the law is then the LuGre law of them).
    owner : str
        The class asking, for messages.

    Returns
    -------
    (FrictionLaw, LuGreParameters or None)
        The law, and its LuGre parameters when it is LuGre.

    Raises
    ------
    ValueError
        Neither given, both given and different, or a law that is not a FrictionLaw.
    """
    if law is None:
        if not isinstance(lugre, LuGreParameters):
            raise ValueError(f"{owner} needs a friction law (law=...) or LuGre parameters "
                             "(lugre=LuGreParameters(...))")
        law = friction_law("lugre")(lugre)
    elif not isinstance(law, FrictionLaw):
        raise ValueError(f"{owner}.law must be a FrictionLaw (one of {friction_law_names()}), "
                         f"got {law!r}")
    own = getattr(law, "lugre_parameters", None)
    if lugre is not None and own != lugre:
        raise ValueError(f"{owner}: give the friction law or the LuGre parameters, not both")
    return law, own


@dataclass(frozen=True)
class GuideWayFriction:
    """The friction of an axis, lumped at its guide-way pads (paper, sec 3).

    Parameters
    ----------
    pads : tuple of str
        Relative-X DOFs of the pads; the friction is shared equally among them.
    lugre : LuGreParameters, optional
        Axis-total LuGre parameters: the law is then
        :class:`~servotune.friction.laws.lugre.LuGreFriction`. Filled in from ``law`` when
        that is LuGre, else None.
    viscous : float, optional
        Axis-total damping of the viscous-only model [N s/m] (default: the law's viscous part,
        :attr:`~servotune.friction.law.FrictionLaw.viscous_part`).
    law : FrictionLaw, optional
        The friction law (axis totals), any registered one
        (:func:`servotune.friction.law.friction_law`); give it or ``lugre``.

    Raises
    ------
    ValueError
        Pads not distinct, neither or conflicting ``lugre`` and ``law``, a negative viscous
        damping.

    See Also
    --------
    servotune.plant.friction_contact : the linear contact of a kind built from it.
    """

    pads: tuple[str, ...]
    lugre: LuGreParameters | None = None
    viscous: float | None = None
    law: FrictionLaw | None = None

    def __post_init__(self) -> None:
        pads = tuple(self.pads)
        if not pads or len(set(pads)) != len(pads):
            raise ValueError(f"GuideWayFriction.pads must be distinct DOF names, got {pads!r}")
        object.__setattr__(self, "pads", pads)
        law, lugre = law_and_lugre(self.law, self.lugre, "GuideWayFriction")
        object.__setattr__(self, "law", law)
        object.__setattr__(self, "lugre", lugre)
        viscous = law.viscous_part if self.viscous is None else float(self.viscous)
        if not (viscous >= 0 and math.isfinite(viscous)):
            raise ValueError(f"GuideWayFriction.viscous must be finite and >= 0 N s/m, got "
                             f"{self.viscous!r}")
        object.__setattr__(self, "viscous", viscous)

    @property
    def per_pad(self) -> LuGreParameters:
        """One pad's share of the LuGre parameters (a LuGre law only)."""
        if self.lugre is None:
            raise ValueError(f"the axis' friction law is {self.law.name!r}, not LuGre")
        return self.lugre.scaled(1.0 / len(self.pads))
