"""Guide-way friction laws for the time simulation: linear part plus a nonlinear remainder.

The laws are plug-ins of :mod:`servotune.friction.laws` on the interface
:class:`servotune.friction.law.FrictionLaw` (here also named :class:`PadFriction`). The simulator
(:mod:`servotune.simulate.integrator`) integrates the linear part of the axis exactly and treats
what is nonlinear implicitly, through a few scalar inputs per pad. A law therefore comes in two
parts:

* a **linear block** per pad (python-control, :meth:`~PadFriction.pad_block`), with inputs the
  pad velocity ``v_<pad>``, the nonlinear remainders (``r_<pad>``, ...) and a constant ``one``,
  and outputs the force on the pad DOF ``f_<pad>``, the friction force ``F_<pad>`` and the
  law's internal states;
* a **remainder** ``r(component, v, z, p)`` [m/s], a compiled (numba) scalar function with its
  two partial derivatives, of the pad velocity and of the state its component reads
  (:meth:`~PadFriction.remainder_states`); the integrator's kernel is compiled around it
  (:func:`servotune.simulate.integrator.chunk_kernel`). Linear laws have none.

This module keeps the names the simulation has always exported; the laws themselves live in
:mod:`servotune.friction.laws.lugre` (LuGre, Bianchi et al. 2014 Eq 3) and
:mod:`servotune.friction.laws.viscous`.
"""

from __future__ import annotations

from ..friction.law import FrictionLaw as PadFriction
from ..friction.law import friction_law, friction_law_names
from ..friction.laws.lugre import LuGreFriction, lugre_damping_remainder, lugre_remainder
from ..friction.laws.viscous import ViscousFriction

__all__ = ["PadFriction", "LuGreFriction", "ViscousFriction", "lugre_remainder",
           "lugre_damping_remainder", "friction_law", "friction_law_names"]
