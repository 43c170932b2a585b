"""The digital drive as the sampled-data system it is.

A servo drive computes its current, velocity and position controllers from samples, each at
its own period (whole multiples of the current controller's), applies each output a
computation delay later and holds it; the motor voltage is held over each current period.
This package models exactly that:

* :mod:`servotune.digital.controller`: the controllers' difference equations per rate
  (discrete PI by forward Euler or Tustin, the speed as the backward difference of the sampled
  rotor angle with its filter, the current set-point filters by prewarped Tustin, the delays),
  one :class:`DigitalController` used by the frequency responses, the stability and the time
  simulation alike;
* :mod:`servotune.digital.cascade`: the multi-rate loop's algebra at one frequency (lifting,
  the fundamental of the sampled-data response), shared by the checks and the tuning;
* :mod:`servotune.digital.sampled`: :class:`SampledAxis`, the axis with its digital drive:
  stability from the monodromy matrix over the slowest period, loops and margins from the
  exact discrete responses, the work-piece compliance as the fundamental of the response.

The paper's continuous drive (``[drive.sampling] continuous = true``) stays the continuous
python-control model of :mod:`servotune.plant`.
"""

from .cascade import fundamental
from .controller import (
    MEASURED,
    REFERENCES,
    ControllerLevel,
    DigitalController,
    digital_controller,
    discrete_filter,
    discrete_pi,
)
from .sampled import SampledAxis, discrete_response, hold_fundamental, lift, multipliers_stable

__all__ = ["MEASURED", "REFERENCES", "ControllerLevel", "DigitalController", "SampledAxis",
           "digital_controller", "discrete_filter", "discrete_pi", "discrete_response",
           "fundamental", "hold_fundamental", "lift", "multipliers_stable"]
