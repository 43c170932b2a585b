"""Viscous guide-way damping, F = c v: the paper's viscous-only ("vd") model as a linear law.

References
----------
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 4.1 (the guide ways as a damper C).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np

from ...structure.model import signal_name
from ..law import FrictionLaw

__all__ = ["ViscousFriction"]


@dataclass(frozen=True)
class ViscousFriction(FrictionLaw):
    """Viscous guide-way damping: F = c v (c [N s/m] axis total), the paper's "vd" model.

    Parameters
    ----------
    c : float
        Axis-total damping [N s/m], finite and >= 0.

    Raises
    ------
    ValueError
        If c is negative or not finite.

    Examples
    --------
    >>> float(ViscousFriction(5578.0).pad_block("pad1.x", 4).D[0, 0])   # pad force per velocity
    -1394.5
    """

    c: float
    name = "viscous"

    def __post_init__(self) -> None:
        c = float(self.c)
        if not (math.isfinite(c) and c >= 0.0):
            raise ValueError(f"ViscousFriction.c must be finite and >= 0 N s/m, got {self.c!r}")
        object.__setattr__(self, "c", c)

    @classmethod
    def from_table(cls, value) -> ViscousFriction:
        """``[friction.viscous]`` with ``c`` [N s/m]."""
        if not (isinstance(value, dict) and set(value) == {"c"}):
            raise ValueError(f"give c = <damping in N s/m>, got {value!r}")
        return cls(value["c"])

    @property
    def viscous_part(self) -> float:
        """c [N s/m]."""
        return self.c

    def presliding(self) -> tuple[float, float]:
        """No spring, the damper c."""
        return 0.0, self.c

    def sliding_system(self, speed: float) -> control.StateSpace:
        """The damper c at any speed (a static gain from velocity to force)."""
        return control.ss([], [], [], [[self.c]], inputs=["velocity"], outputs=["force"])

    def describing_function(self, amplitude: float, omega: float,
                            n_samples: int = 512) -> tuple[float, float]:
        """Ceq = c, Keq = 0 at every amplitude and frequency."""
        return self.c, 0.0

    def periodic_force(self, velocity, period: float, share: float = 1.0) -> np.ndarray:
        """``share c v`` (memoryless)."""
        return share * self.c * np.asarray(velocity, dtype=float)

    def pad_block(self, pad: str, n_pads: int, speed: float = 0.0) -> control.StateSpace:
        v, f, force = (signal_name(pad, pre) for pre in ("v_", "f_", "F_"))
        share = self.c / n_pads
        return control.ss([], [], [], [[-share], [share]], inputs=[v], outputs=[f, force],
                          name=f"friction_{signal_name(pad)}")

    def friction_force(self, v, z=None):
        """c v [N], axis total."""
        return self.c * np.asarray(v, dtype=float)
