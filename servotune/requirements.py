"""Design requirements of a feed axis: loop robustness, minimum Kv, bands, depth of cut.

SI inside (rad/s, 1/s, m); margins are given in the units engineers quote them (deg, dB) under
suffixed names. Gain and phase margin requirements are turned into Ms limits through the Ms
disk: a Nyquist curve outside the circle of radius 1/Ms about -1 has
``GM >= Ms/(Ms - 1)`` and ``PM >= 2 asin(1/(2 Ms))`` (Astrom and Murray, Feedback Systems,
2nd ed., sec 13.3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Requirements"]


@dataclass(frozen=True)
class Requirements:
    """Robustness and performance requirements (SI; margins at the edges in deg and dB).

    Parameters
    ----------
    ms_velocity_max, ms_position_max : float
        Largest allowed sensitivity peak of the velocity and the position loop (> 1).
    phase_margin_min_deg, gain_margin_min_db : float, optional
        Smallest allowed margins; enforced through the Ms disk (each tightens the Ms limit).
    kv_min : float
        Smallest allowed position gain Kv [1/s].
    depth_required : float, optional
        Required axial depth of cut [m] (for the chatter margin).
    band : (float, float)
        Frequency band [rad/s] of the compliance-peak objective.
    loop_band : (float, float)
        Frequency range [rad/s] on which the loop constraints are imposed.
    """

    ms_velocity_max: float = 2.0
    ms_position_max: float = 1.5
    phase_margin_min_deg: float | None = None
    gain_margin_min_db: float | None = None
    kv_min: float = 0.0
    band: tuple[float, float] = (2 * math.pi * 5.0, 2 * math.pi * 300.0)
    loop_band: tuple[float, float] = (2 * math.pi * 0.1, 2 * math.pi * 3000.0)
    depth_required: float | None = None

    def __post_init__(self) -> None:
        for name in ("ms_velocity_max", "ms_position_max"):
            value = float(getattr(self, name))
            if not value > 1.0 or not math.isfinite(value):
                raise ValueError(f"Requirements.{name} must be finite and > 1, got {value!r}")
        if self.phase_margin_min_deg is not None and not 0 < self.phase_margin_min_deg < 90:
            raise ValueError("Requirements.phase_margin_min_deg must lie in (0, 90) deg")
        if self.gain_margin_min_db is not None and not self.gain_margin_min_db > 0:
            raise ValueError("Requirements.gain_margin_min_db must be > 0 dB")
        if self.depth_required is not None and not (
                self.depth_required > 0 and math.isfinite(self.depth_required)):
            raise ValueError("Requirements.depth_required must be > 0 m")
        if not self.kv_min >= 0:
            raise ValueError("Requirements.kv_min must be >= 0 1/s")
        for name in ("band", "loop_band"):
            lo, hi = (float(v) for v in getattr(self, name))
            if not 0 < lo < hi < math.inf:
                raise ValueError(f"Requirements.{name} must be (low, high) with 0 < low < high "
                                 f"rad/s, got {getattr(self, name)!r}")
            object.__setattr__(self, name, (lo, hi))

    def ms_limit(self, loop: str) -> float:
        """The Ms limit of a loop including what the margin requirements imply."""
        limit = self.ms_velocity_max if loop == "velocity" else self.ms_position_max
        if self.phase_margin_min_deg is not None:
            limit = min(limit, 1.0 / (2.0 * math.sin(math.radians(self.phase_margin_min_deg) / 2)))
        if self.gain_margin_min_db is not None:
            gm = 10.0 ** (self.gain_margin_min_db / 20.0)
            limit = min(limit, gm / (gm - 1.0))
        return limit
