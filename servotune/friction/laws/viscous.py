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
        """Build the law from ``[friction.viscous]`` of an axis description: ``c`` [N s/m].

        Parameters
        ----------
        value : dict
            The entry of the axis file.

        Returns
        -------
        ViscousFriction

        Raises
        ------
        ValueError
            A parameter is missing, unknown or out of range.
        """
        if not (isinstance(value, dict) and set(value) == {"c"}):
            raise ValueError(f"give c = <damping in N s/m>, got {value!r}")
        return cls(value["c"])

    @property
    def viscous_part(self) -> float:
        """c [N s/m]."""
        return self.c

    def with_viscous(self, c: float) -> ViscousFriction:
        """Return the law with damping ``c`` [N s/m] (the whole law is viscous).

        Parameters
        ----------
        c : float
            Viscous damping [N s/m], >= 0.

        Returns
        -------
        ViscousFriction
        """
        return ViscousFriction(c)

    def steady_force(self, speed: float) -> float:
        """Return c v [N].

        Parameters
        ----------
        speed : float
            Sliding speed v [m/s].

        Returns
        -------
        float
        """
        return self.c * float(speed)

    def steady_slope(self, speed: float) -> float:
        """Return c [N s/m] at every speed.

        Parameters
        ----------
        speed : float
            Sliding speed v [m/s] (not used).

        Returns
        -------
        float
        """
        return self.c

    def presliding(self) -> tuple[float, float]:
        """Return the contact linearised at rest, axis totals: no spring, the damper c.

        Returns
        -------
        (stiffness, damping) : tuple of float
            Spring [N/m] and damper [N s/m].
        """
        return 0.0, self.c

    def sliding_system(self, speed: float) -> control.StateSpace:
        """Return the contact linearised about steady sliding at a speed, axis total: the damper c
        at any speed (a static gain).

        Parameters
        ----------
        speed : float
            Sliding speed v0 [m/s].

        Returns
        -------
        control.StateSpace
            SISO, from the velocity deviation [m/s] to the force deviation [N].
        """
        return control.ss([], [], [], [[self.c]], inputs=["velocity"], outputs=["force"])

    def describing_function(self, amplitude: float, omega: float,
                            n_samples: int = 512) -> tuple[float, float]:
        """Return the equivalent damping and stiffness under ``x = A sin(omega t)``: Ceq = c, Keq =
        0 at every amplitude and frequency.

        Parameters
        ----------
        amplitude : float
            Displacement amplitude A [m], > 0.
        omega : float
            Angular frequency [rad/s], > 0.
        n_samples : int
            Samples of the period (not used).

        Returns
        -------
        (ceq, keq) : tuple of float
            Ceq [N s/m] and Keq [N/m], axis totals.
        """
        return self.c, 0.0

    def periodic_force(self, velocity, period: float, share: float = 1.0) -> np.ndarray:
        """Return the force of one pad carrying ``share`` of the law on its periodic orbit: ``share
        c v`` (memoryless).

        Parameters
        ----------
        velocity : array_like
            Pad velocity [m/s] at N equally spaced instants of one period (periodic).
        period : float
            The period [s], > 0.
        share : float
            The pad's share of the axis-total law (``1 / n_pads``), > 0.

        Returns
        -------
        numpy.ndarray
            The force [N] at the same instants.
        """
        return share * self.c * np.asarray(velocity, dtype=float)

    def pad_block(self, pad: str, n_pads: int, speed: float = 0.0) -> control.StateSpace:
        """Return the linear part for one pad: a static gain, share c / n_pads.

        Parameters
        ----------
        pad : str
            The pad DOF.
        n_pads : int
            The number of pads sharing the axis-total law equally.
        speed : float
            Operating speed [m/s] of the linearisation (0: at rest).

        Returns
        -------
        control.StateSpace
            Inputs ``v_<pad>``; outputs ``f_<pad>``, ``F_<pad>``.
        """
        v, f, force = (signal_name(pad, pre) for pre in ("v_", "f_", "F_"))
        share = self.c / n_pads
        return control.ss([], [], [], [[-share], [share]], inputs=[v], outputs=[f, force],
                          name=f"friction_{signal_name(pad)}")

    def friction_force(self, v, z=None):
        """Return the friction force [N], axis total: c v.

        Parameters
        ----------
        v : array_like
            Pad velocity [m/s].
        z : array_like
            Not used (no state).

        Returns
        -------
        numpy.ndarray
            Friction force [N].
        """
        return self.c * np.asarray(v, dtype=float)
