"""Design requirements of a feed axis: loop robustness, loop hierarchy, the thrust reserve,
minimum Kv, bands, depth of cut, and how closely the nonlinear axis must hold the claims.

SI inside (rad/s, 1/s, m); margins are given in the units engineers quote them (deg, dB) under
suffixed names. Gain and phase margin requirements are turned into Ms limits through the Ms
disk: a Nyquist curve outside the circle of radius 1/Ms about -1 has
``GM >= Ms/(Ms - 1)`` and ``PM >= 2 asin(1/(2 Ms))`` (Astrom and Murray, Feedback Systems,
2nd ed., sec 13.3).

Loop hierarchy, with their defaults and where they come from:

* ``bandwidth_ratio_min`` = 4: the closed velocity loop at least 4 times as wide as the closed
  position loop. Practice asks the inner loop of a cascade to be 3 to 5 (some say 5 to 10)
  times faster than the outer one; for a position loop Kv/s around a velocity loop of time
  constant T, the aperiodic setting Kv T = 1/4 (no overshoot) gives a bandwidth ratio of 3.1
  (Ellis, Control System Design Guide, 4th ed., 2012, ch 17; Schroeder, Elektrische Antriebe -
  Regelung von Antriebssystemen, 4th ed., Springer 2015, ch 3, the damping optimum).
* ``current_bandwidth_ratio_min`` = 3: the current loop likewise above the velocity loop
  (industrial servo drives ship current loops of 650-900 Hz over speed loops of 140-250 Hz,
  ratios 3 to 5: SINAMICS Engineering Manual, Siemens 2015, sec 6.2.3).
* ``ti_bandwidth_min`` = 3 and ``ti_bandwidth_max`` = 30 bound Ti times the velocity loop's
  closed-loop bandwidth w_b. The symmetric optimum sets Ti = a^2 T_sum for a crossover
  w_c = 1/(a T_sum), with a = 2 to 4 (Kessler 1958; Schroeder 2015, ch 3); its closed loop then
  has Ti w_b = 3.4 to 6.1 (computed for the ideal loop). Below 3 the integrator eats the phase
  margin; far above 30 the integral action no longer rejects load torques (friction) within a
  few time constants of the loop. The bandwidth is used, not the gain crossover, because with a
  resonant load the velocity loop's gain crosses 1 several times while its closed-loop
  bandwidth stays well defined.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from .validation import positive

__all__ = ["Requirements", "Setting"]


@dataclass(frozen=True)
class Setting:
    """A setting a requirement declares: a key of ``[requirements]`` in an axis file.

    A requirement of another package (:class:`servotune.tuning.constraint.Requirement`,
    ``settings``) declares what it reads; the axis file's validation, ``servotune init``'s
    template and the report take name, unit, default, range and help from here.

    Parameters
    ----------
    name : str
        The key (a lower-case identifier, SI value; a unit suffix such as ``_m`` is welcome).
    unit : str
        The SI unit, as text (``"m"``, ``"1/s"``, ``"-"``).
    default : float or None
        The value when the axis file does not give one; None: the requirement is off then.
    low, high : float
        The accepted range (inclusive): a plausibility range that catches unit slips.
    help : str
        One line on what it means and where its default comes from.

    Raises
    ------
    ValueError
        A name that is not a lower-case identifier, ``low > high`` or a default outside the
        range.

    Examples
    --------
    >>> s = Setting("following_error_max_m", "m", None, 1e-7, 1e-2,
    ...             "largest following error at the highest feed speed")
    >>> s.parse(2e-4)
    0.0002
    >>> s.parse(0.2)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: following_error_max_m = 0.2 m is outside [1e-07, 0.01] m (largest ...)
    """

    name: str
    unit: str
    default: float | None
    low: float
    high: float
    help: str

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name.isidentifier()
                and self.name == self.name.lower()):
            raise ValueError(f"a setting's name must be a lower-case identifier, got "
                             f"{self.name!r}")
        low, high = float(self.low), float(self.high)
        if not low <= high:
            raise ValueError(f"setting {self.name}: low ({low!r}) must not exceed high "
                             f"({high!r})")
        object.__setattr__(self, "low", low)
        object.__setattr__(self, "high", high)
        if self.default is not None:
            object.__setattr__(self, "default", self.parse(self.default))

    def parse(self, value) -> float:
        """Return the value as a float, or refuse it naming the key, the range and the unit.

        Parameters
        ----------
        value : object
            The value as the axis file gives it.

        Returns
        -------
        float

        Raises
        ------
        ValueError
            Not a finite number, or outside ``[low, high]``.
        """
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{self.name} must be a number in {self.unit}, got {value!r} "
                             f"({self.help})")
        value = float(value)
        if not (math.isfinite(value) and self.low <= value <= self.high):
            raise ValueError(f"{self.name} = {value!r} {self.unit} is outside [{self.low:g}, "
                             f"{self.high:g}] {self.unit} ({self.help})")
        return value

    def to_dict(self) -> dict:
        """Return the declaration as JSON-ready data (SI).

        Returns
        -------
        dict
            ``name``, ``unit``, ``default``, ``low``, ``high``, ``help``.
        """
        return {"name": self.name, "unit": self.unit, "default": self.default,
                "low": self.low, "high": self.high, "help": self.help}


@dataclass(frozen=True)
class Requirements:
    """Robustness and performance requirements (SI; margins at the edges in deg and dB).

    Parameters
    ----------
    ms_velocity_max, ms_position_max : float
        Largest allowed sensitivity peak of the velocity and the position loop (finite, > 1).
    phase_margin_min_deg, gain_margin_min_db : float, optional
        Smallest allowed phase margin [deg], in (0, 90), and gain margin [dB], > 0; enforced
        through the Ms disk (each can only tighten the Ms limit, see `ms_limit`).
    kv_min : float
        Smallest allowed position gain Kv [1/s], finite and >= 0.
    band : (float, float)
        Frequency band (low, high) [rad/s] of the compliance-peak objective, 0 < low < high.
    loop_band : (float, float)
        Frequency range (low, high) [rad/s] on which the loop constraints are imposed.
    depth_required : float, optional
        Required axial depth of cut [m], > 0 (for the chatter margin).
    thrust_margin : float
        Fraction of the motor's thrust kept in reserve, in [0, 1) (0.2: the needs may use
        80 %).
    bandwidth_ratio_min : float
        Velocity-loop over position-loop closed-loop bandwidth, at least (0: not required,
        else >= 1).
    current_bandwidth_ratio_min : float
        Current-loop over velocity-loop closed-loop bandwidth, at least (0: not required, else
        >= 1).
    ti_bandwidth_min, ti_bandwidth_max : float
        Range of Ti times the velocity loop's closed-loop bandwidth [s x rad/s] (0: no bound;
        a nonzero maximum must exceed the minimum).
    nonlinear_tolerance : float
        How far above the design's claim the nonlinear axis may peak, >= 0 (0.3: 30 %).
    settings : Mapping of str to float, or pairs
        The values the axis file gives for settings that requirements of other packages
        declare (:class:`Setting`), by name, validated against their declarations when the
        axis is read; kept as sorted (name, value) pairs (hashable, picklable); read them with
        :meth:`value`.

    Raises
    ------
    ValueError
        When a field lies outside the range given above, or is not finite.
    """

    ms_velocity_max: float = 2.0
    ms_position_max: float = 1.5
    phase_margin_min_deg: float | None = None
    gain_margin_min_db: float | None = None
    kv_min: float = 0.0
    band: tuple[float, float] = (2 * math.pi * 5.0, 2 * math.pi * 300.0)
    loop_band: tuple[float, float] = (2 * math.pi * 0.1, 2 * math.pi * 3000.0)
    depth_required: float | None = None
    thrust_margin: float = 0.2
    bandwidth_ratio_min: float = 4.0
    current_bandwidth_ratio_min: float = 3.0
    ti_bandwidth_min: float = 3.0
    ti_bandwidth_max: float = 30.0
    nonlinear_tolerance: float = 0.3
    settings: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        pairs = dict(self.settings.items() if isinstance(self.settings, Mapping)
                     else self.settings)
        object.__setattr__(self, "settings", tuple(sorted((str(k), float(v))
                                                          for k, v in pairs.items())))
        for name in ("thrust_margin", "bandwidth_ratio_min", "current_bandwidth_ratio_min",
                     "ti_bandwidth_min", "ti_bandwidth_max", "nonlinear_tolerance"):
            object.__setattr__(self, name, positive("Requirements", name, getattr(self, name),
                                                    allow_zero=True))
        if not self.thrust_margin < 1:
            raise ValueError("Requirements.thrust_margin is a fraction of the thrust in [0, 1)")
        for name in ("bandwidth_ratio_min", "current_bandwidth_ratio_min"):
            if 0 < getattr(self, name) < 1:
                raise ValueError(f"Requirements.{name} must be 0 (not required) or >= 1 (the "
                                 f"inner loop at least as wide), got {getattr(self, name)!r}")
        if self.ti_bandwidth_max and self.ti_bandwidth_max <= self.ti_bandwidth_min:
            raise ValueError("Requirements.ti_bandwidth_max must exceed ti_bandwidth_min (or "
                             "be 0: no upper bound)")
        for name in ("ms_velocity_max", "ms_position_max"):
            value = float(getattr(self, name))
            if not value > 1.0 or not math.isfinite(value):
                raise ValueError(f"Requirements.{name} must be finite and > 1, got {value!r}")
        if self.phase_margin_min_deg is not None and not 0 < self.phase_margin_min_deg < 90:
            raise ValueError("Requirements.phase_margin_min_deg must lie in (0, 90) deg")
        if self.gain_margin_min_db is not None and not self.gain_margin_min_db > 0:
            raise ValueError("Requirements.gain_margin_min_db must be > 0 dB")
        if self.depth_required is not None:
            object.__setattr__(self, "depth_required", positive(
                "Requirements", "depth_required", self.depth_required, "m",
                "leave it out (None) when no depth is required"))
        object.__setattr__(self, "kv_min", positive("Requirements", "kv_min", self.kv_min, "1/s",
                                                    allow_zero=True))
        for name in ("band", "loop_band"):
            lo, hi = (float(v) for v in getattr(self, name))
            if not 0 < lo < hi < math.inf:
                raise ValueError(f"Requirements.{name} must be (low, high) with 0 < low < high "
                                 f"rad/s, got {getattr(self, name)!r}")
            object.__setattr__(self, name, (lo, hi))

    def value(self, setting: Setting) -> float | None:
        """Return a declared setting's value: the axis file's, else its default.

        Parameters
        ----------
        setting : Setting
            The declaration.

        Returns
        -------
        float or None
            None when neither is given (the requirement is off).
        """
        return dict(self.settings).get(setting.name, setting.default)

    def ms_limit(self, loop: str) -> float:
        """Return the Ms limit of a loop, tightened by the margin requirements.

        A Nyquist curve outside the disk of radius 1/Ms about -1 has a phase margin of at least
        ``2 asin(1/(2 Ms))`` and a gain margin of at least ``Ms/(Ms - 1)``; inverted, a phase
        margin PM asks ``Ms <= 1/(2 sin(PM/2))`` and a gain margin GM (as a ratio)
        ``Ms <= GM/(GM - 1)`` (Astrom and Murray, Feedback Systems, 2nd ed., sec 13.3).

        Parameters
        ----------
        loop : str
            ``"velocity"`` for the velocity loop; any other value gives the position loop's
            limit.

        Returns
        -------
        float
            The smallest of the loop's own Ms limit (`ms_velocity_max` or `ms_position_max`)
            and those the margin requirements imply.

        Examples
        --------
        A 45 deg phase margin asks Ms <= 1/(2 sin 22.5 deg) = 1.307:

        >>> round(Requirements(phase_margin_min_deg=45.0).ms_limit("velocity"), 3)
        1.307
        """
        limit = self.ms_velocity_max if loop == "velocity" else self.ms_position_max
        if self.phase_margin_min_deg is not None:
            limit = min(limit, 1.0 / (2.0 * math.sin(math.radians(self.phase_margin_min_deg) / 2)))
        if self.gain_margin_min_db is not None:
            gm = 10.0 ** (self.gain_margin_min_db / 20.0)
            limit = min(limit, gm / (gm - 1.0))
        return limit
