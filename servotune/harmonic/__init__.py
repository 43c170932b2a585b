"""Harmonic balance of the closed-loop axis with nonlinear guide-way friction.

The periodic response of the axis (structure, drive cascade and motor linear; the friction at
the guide-way pads nonlinear) to a harmonic work-piece force, by multi-harmonic balance with the
alternating frequency-time scheme for the friction forces, condensed to the pad DOFs, and
continued in frequency by pseudo-arc-length:

* :mod:`~servotune.harmonic.linear`: the closed-loop receptance between pads and work piece;
* :mod:`~servotune.harmonic.aft`: time samples and harmonics, and the one function through
  which friction laws are called (:func:`periodic_friction_force`);
* :mod:`~servotune.harmonic.balance`: the balance equations and Newton's method;
* :mod:`~servotune.harmonic.continuation`: predictor-corrector along the arc length;
* :mod:`~servotune.harmonic.compliance`: compliance curves per force level with the linear
  references (:func:`nonlinear_compliance`); :mod:`~servotune.harmonic.plot` their figure.
"""

from .aft import (
    harmonics_from_samples,
    periodic_friction_force,
    periodic_friction_jacobian,
    samples_from_harmonics,
)
from .balance import ConvergenceError, HarmonicSettings, PadBalance
from .compliance import (
    DEFAULT_BAND,
    ComplianceCurve,
    NonlinearCompliance,
    curve_peak,
    nonlinear_compliance,
    presliding_guess,
    refine_peak,
    require_stable_regime,
)
from .continuation import Branch, ContinuationSettings, continue_in_frequency
from .linear import PadReceptance, pad_receptance

__all__ = [
    "DEFAULT_BAND",
    "Branch",
    "ComplianceCurve",
    "ContinuationSettings",
    "ConvergenceError",
    "HarmonicSettings",
    "NonlinearCompliance",
    "PadBalance",
    "PadReceptance",
    "continue_in_frequency",
    "curve_peak",
    "harmonics_from_samples",
    "nonlinear_compliance",
    "pad_receptance",
    "periodic_friction_force",
    "periodic_friction_jacobian",
    "presliding_guess",
    "refine_peak",
    "require_stable_regime",
    "samples_from_harmonics",
]
