"""The feed drive: motor, cascaded current/velocity/position control, filters, feed-forward.

The paper adds to the reduced structure "the motor electrical model and the cascaded current,
velocity and position controllers, depicted as continuous time elements", with the position
gain quoted as Kv = 1 (the machine-tool Kv factor in (m/min)/mm) (Bianchi et al. 2014, sec 3).

The cascade, all in continuous time and SI units::

                 v_ref --[kvff]--+          a_ref --[J_ff/r]--+
                                 |                            |
  x_ref -->(+)--[Kv]-->(+)--[1/r]-->(+)--[Kp (1 + 1/(Ti s))]-->(+)--[LP]--[notch]--> T_set
           -^                    omega_cmd -^                                           |
            |                               |                                      [1/kt] i_cmd
        x_fb (linear encoder                omega_fb (motor encoder:                    |
         or r * motor angle)                rotor - stator speed)          (+)--[PI_i]--> u
                                                                           -^            |
                                                                            i    L di/dt = u - R i
                                                                                      - ke omega
                                                                                         |
                                                          T = kt i  --> rotor (+), stator (-)

Kv [1/s] turns a position error [m] into a slide velocity command [m/s]; the transmission ratio
r [m/rad] (screw lead / 2 pi / belt ratio) turns that into a motor speed command [rad/s]. The
velocity PI (Kp [N m s/rad], Ti [s]) gives a torque set-point [N m], optionally smoothed by a
second-order low-pass and a notch, which the current PI (Kp [V/A], Ti [s]) realises on the motor
winding (R [ohm], L [H], back-EMF ke [V s/rad], torque constant kt [N m/A]).

Every parameter set is a frozen dataclass validated on construction; vary them with
:func:`dataclasses.replace`. The python-control blocks are built by :func:`drive_blocks`.

References
----------
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 3. G. Ellis, Control System Design Guide, 4th ed., Butterworth-Heinemann (2012), ch 6-7
(cascaded servo loops). Y. Altintas, Manufacturing Automation, 2nd ed., Cambridge (2012), ch 6
(feed drives, the Kv factor).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import control
import numpy as np

from .units import KV_PER_M_PER_MIN_PER_MM, kv_from_m_per_min_per_mm, kv_to_m_per_min_per_mm
from .validation import fraction, positive

__all__ = [
    "KV_PER_M_PER_MIN_PER_MM",
    "kv_from_m_per_min_per_mm",
    "kv_to_m_per_min_per_mm",
    "Motor",
    "TorqueSpeedCurve",
    "DriveLimits",
    "PIController",
    "LowPassFilter",
    "NotchFilter",
    "Sampling",
    "winding_block",
    "pi_response",
    "current_loop_response",
    "Drive",
    "drive_blocks",
    "CascadeResponse",
    "cascade_response",
    "current_loop_bandwidth",
]


@dataclass(frozen=True)
class Motor:
    """Servo motor (one equivalent phase, SI).

    Parameters
    ----------
    torque_constant : float
        kt [N m/A].
    back_emf_constant : float
        ke [V s/rad] (equal to kt for an ideal motor in SI units).
    resistance : float
        Winding resistance R [ohm].
    inductance : float
        Winding inductance L [H].
    rotor, stator : str
        Rotation DOFs of the structure between which the torque acts. The rotor inertia is part
        of the structure model. ``stator=None`` means the stator is rigidly grounded.
    """

    torque_constant: float
    back_emf_constant: float
    resistance: float
    inductance: float
    rotor: str = "motor.rotor"
    stator: str | None = "motor.stator"

    def __post_init__(self) -> None:
        units = {"torque_constant": "N m/A", "back_emf_constant": "V s/rad",
                 "resistance": "ohm", "inductance": "H"}
        for name, unit in units.items():
            object.__setattr__(self, name, positive("Motor", name, getattr(self, name), unit))

    @property
    def electrical_time_constant(self) -> float:
        """L/R [s]."""
        return self.inductance / self.resistance


#: Relative tolerance beyond a curve's last speed (or the top speed) still evaluated at it: a
#: rapid speed of speed_max x r, referred back through r, lands a rounding error above it.
_SPEED_TOLERANCE = 2e-6


def _beyond(omega: float, top: float, what: str) -> ValueError:
    return ValueError(f"motor speed {omega:.6g} rad/s ({omega * 60 / (2 * math.pi):.6g} rpm) is "
                      f"beyond {what} ({top:.6g} rad/s, {top * 60 / (2 * math.pi):.6g} rpm): "
                      "the drive cannot go there")


@dataclass(frozen=True)
class TorqueSpeedCurve:
    """The torques a motor and its converter give over the motor speed (SI, at the shaft).

    Linear between the points; not defined beyond the last one (the drive cannot go there).
    Both directions of rotation are alike: the torques depend on ``|omega|``.

    Parameters
    ----------
    speed : sequence of float
        Motor speeds [rad/s], increasing, the first 0; at least two.
    torque_peak : sequence of float
        Peak torque at each speed [N m] (> 0).
    torque_continuous : sequence of float
        Continuous torque at each speed [N m] (> 0, at most the peak torque there).

    Raises
    ------
    ValueError
        Lengths that differ, fewer than two points, speeds not increasing from 0, torques not
        finite and > 0, a continuous torque above the peak torque.

    Examples
    --------
    Flat to 3000 rpm, then falling to two thirds at 4500 rpm:

    >>> curve = TorqueSpeedCurve.from_rpm([0, 3000, 4500], [90, 90, 60], [27, 27, 18])
    >>> round(curve.continuous(3750 * 2 * math.pi / 60), 6)    # half-way: 22.5 N m
    22.5
    """

    speed: tuple[float, ...]
    torque_peak: tuple[float, ...]
    torque_continuous: tuple[float, ...]

    def __post_init__(self) -> None:
        n = len(self.speed)
        for name, unit in (("speed", "rad/s"), ("torque_peak", "N m"),
                           ("torque_continuous", "N m")):
            values = tuple(getattr(self, name))
            if len(values) != n:
                raise ValueError(f"TorqueSpeedCurve.{name} has {len(values)} values, speed {n}: "
                                 "give one torque per speed")
            object.__setattr__(self, name, tuple(
                positive("TorqueSpeedCurve", f"{name}[{i}]", v, unit, allow_zero=(
                    name == "speed" and i == 0)) for i, v in enumerate(values)))
        if n < 2:
            raise ValueError(f"TorqueSpeedCurve needs at least two points, got {n}")
        if self.speed[0] != 0.0 or any(b <= a for a, b in itertools.pairwise(self.speed)):
            raise ValueError(f"TorqueSpeedCurve.speed must increase from 0, got {self.speed}")
        pairs = zip(self.torque_peak, self.torque_continuous, strict=True)
        for i, (p, c) in enumerate(pairs):
            if c > p:
                raise ValueError(f"TorqueSpeedCurve.torque_continuous[{i}] ({c:g} N m) exceeds "
                                 f"torque_peak[{i}] ({p:g} N m)")

    @classmethod
    def from_rpm(cls, speed_rpm, torque_peak, torque_continuous) -> TorqueSpeedCurve:
        """Return the curve from speeds in rpm (a data sheet's unit) and torques in N m.

        Parameters
        ----------
        speed_rpm : sequence of float
            Motor speeds [rpm], increasing from 0.
        torque_peak, torque_continuous : sequence of float
            Torques [N m] at those speeds.

        Returns
        -------
        TorqueSpeedCurve
            With the speeds in rad/s.
        """
        return cls(tuple(float(s) * 2 * math.pi / 60 for s in speed_rpm), tuple(torque_peak),
                   tuple(torque_continuous))

    @property
    def speed_max(self) -> float:
        """The last speed of the curve [rad/s]."""
        return self.speed[-1]

    def _at(self, values, omega: float) -> float:
        w = abs(float(omega))
        if w > self.speed_max * (1 + _SPEED_TOLERANCE):
            raise _beyond(w, self.speed_max, "the torque-speed curve's last point")
        return float(np.interp(min(w, self.speed_max), self.speed, values))

    def peak(self, omega: float) -> float:
        """Return the peak torque [N m] at a motor speed [rad/s].

        Parameters
        ----------
        omega : float
            Motor speed [rad/s], >= 0.

        Returns
        -------
        float
            The peak torque [N m].

        Raises
        ------
        ValueError
            Beyond the last point of the curve.
        """
        return self._at(self.torque_peak, omega)

    def continuous(self, omega: float) -> float:
        """Return the continuous torque [N m] at a motor speed [rad/s].

        Parameters
        ----------
        omega : float
            Motor speed [rad/s], >= 0.

        Returns
        -------
        float
            The continuous torque [N m].

        Raises
        ------
        ValueError
            Beyond the last point of the curve.
        """
        return self._at(self.torque_continuous, omega)


@dataclass(frozen=True)
class DriveLimits:
    """What the motor and its converter can deliver (SI, at the motor shaft).

    The torques over speed (:meth:`peak`, :meth:`continuous`) come from, in this order:

    * ``torque_speed``, the motor's torque-speed curve (a data sheet's table);
    * ``rated_speed``: the rated torques up to it, then falling at constant power
      (``T(w) = T_rated w_rated / w``) up to ``speed_max``;
    * otherwise the rated torques held constant up to ``speed_max`` (a flat curve in the usable
      range: what an axis file with only ``torque_peak``, ``torque_continuous`` and
      ``speed_max_rpm`` says, when its continuous torque is the rated torque at the top speed).

    Parameters
    ----------
    torque_peak : float
        Largest torque for accelerations and short loads [N m] (the converter's current limit
        times kt, or the motor's own maximum, whichever is lower). With ``torque_speed``, the
        largest peak torque of the curve.
    torque_continuous : float
        Torque the motor carries thermally without limit of time [N m] (the rated torque at
        speed; the stall torque M0 at standstill is somewhat higher). With ``torque_speed``,
        the largest continuous torque of the curve.
    speed_max : float, optional
        Largest motor speed [rad/s] (None: not given; with ``torque_speed``, the curve's last
        speed).
    torque_speed : TorqueSpeedCurve, optional
        The torques over speed.
    rated_speed : float, optional
        Speed [rad/s] above which the torques fall at constant power (not with
        ``torque_speed``; at most ``speed_max``).

    Raises
    ------
    ValueError
        Non-positive or non-finite values, a continuous torque above the peak torque, torques
        that are not the largest of ``torque_speed``, a ``speed_max`` beyond the curve's last
        speed, ``rated_speed`` with ``torque_speed`` or above ``speed_max``.

    Examples
    --------
    The thrust at the slide is the torque over the transmission ratio r [m/rad]:

    >>> limits = DriveLimits(torque_peak=90.0, torque_continuous=27.0, speed_max=314.16)
    >>> round(limits.torque_peak / 1.5915e-3)        # N of peak thrust with lead 20 mm, belt 2
    56550
    >>> limits.continuous(314.16) == limits.continuous(0.0) == 27.0   # flat: no curve given
    True

    Constant power above a rated speed: at twice the rated speed, half the torque.

    >>> DriveLimits(90.0, 27.0, speed_max=400.0, rated_speed=200.0).continuous(400.0)
    13.5
    """

    torque_peak: float
    torque_continuous: float
    speed_max: float | None = None
    torque_speed: TorqueSpeedCurve | None = None
    rated_speed: float | None = None

    def __post_init__(self) -> None:
        for name, unit in (("torque_peak", "N m"), ("torque_continuous", "N m"),
                           ("speed_max", "rad/s"), ("rated_speed", "rad/s")):
            if getattr(self, name) is not None or name not in ("speed_max", "rated_speed"):
                object.__setattr__(self, name, positive("DriveLimits", name,
                                                        getattr(self, name), unit))
        if self.torque_continuous > self.torque_peak:
            raise ValueError(f"DriveLimits.torque_continuous ({self.torque_continuous:g} N m) "
                             f"exceeds torque_peak ({self.torque_peak:g} N m)")
        curve = self.torque_speed
        if curve is not None:
            if not isinstance(curve, TorqueSpeedCurve):
                raise ValueError("DriveLimits.torque_speed must be a TorqueSpeedCurve or None")
            if self.rated_speed is not None:
                raise ValueError("DriveLimits.rated_speed with torque_speed: the curve already "
                                 "says how the torque falls; give one of them")
            for name, values in (("torque_peak", curve.torque_peak),
                                 ("torque_continuous", curve.torque_continuous)):
                if not math.isclose(getattr(self, name), max(values), rel_tol=1e-9):
                    raise ValueError(f"DriveLimits.{name} ({getattr(self, name):g} N m) is not "
                                     f"the largest of torque_speed ({max(values):g} N m)")
            if self.speed_max is None:
                object.__setattr__(self, "speed_max", curve.speed_max)
            elif self.speed_max > curve.speed_max * (1 + 1e-9):
                raise ValueError(f"DriveLimits.speed_max ({self.speed_max:.6g} rad/s) is beyond "
                                 f"the torque-speed curve's last point ({curve.speed_max:.6g} "
                                 "rad/s)")
        if (self.rated_speed is not None and self.speed_max is not None
                and self.rated_speed > self.speed_max * (1 + 1e-9)):
            raise ValueError(f"DriveLimits.rated_speed ({self.rated_speed:.6g} rad/s) exceeds "
                             f"speed_max ({self.speed_max:.6g} rad/s)")

    @classmethod
    def from_curve(cls, curve: TorqueSpeedCurve, speed_max: float | None = None) -> DriveLimits:
        """Return the limits of a torque-speed curve (its largest torques, its last speed).

        Parameters
        ----------
        curve : TorqueSpeedCurve
            The torques over speed.
        speed_max : float, optional
            Largest motor speed [rad/s], at most the curve's last speed (default: that).

        Returns
        -------
        DriveLimits
        """
        return cls(max(curve.torque_peak), max(curve.torque_continuous), speed_max, curve)

    def _at(self, rated: float, which: str, omega: float) -> float:
        w = abs(float(omega))
        if self.speed_max is not None and w > self.speed_max * (1 + _SPEED_TOLERANCE):
            raise _beyond(w, self.speed_max, "the motor's top speed")
        if self.torque_speed is not None:
            return getattr(self.torque_speed, which)(w)
        if self.rated_speed is not None and w > self.rated_speed:
            return rated * self.rated_speed / w
        return rated

    def peak(self, omega: float) -> float:
        """Return the peak torque [N m] at a motor speed [rad/s] (see the class docstring).

        Parameters
        ----------
        omega : float
            Motor speed [rad/s], >= 0.

        Returns
        -------
        float
            The peak torque [N m].

        Raises
        ------
        ValueError
            Beyond ``speed_max`` or the curve's last point.
        """
        return self._at(self.torque_peak, "peak", omega)

    def continuous(self, omega: float) -> float:
        """Return the continuous torque [N m] at a motor speed [rad/s] (see the class
        docstring).

        Parameters
        ----------
        omega : float
            Motor speed [rad/s], >= 0.

        Returns
        -------
        float
            The continuous torque [N m].

        Raises
        ------
        ValueError
            Beyond ``speed_max`` or the curve's last point.
        """
        return self._at(self.torque_continuous, "continuous", omega)


@dataclass(frozen=True)
class PIController:
    """PI controller ``kp (1 + 1/(ti s))``; ``ti = inf`` makes it proportional only.

    Parameters
    ----------
    kp : float
        Proportional gain (> 0), units of the loop (V/A for current, N m s/rad for velocity).
    ti : float
        Integral time [s] (> 0, may be ``math.inf``).

    Examples
    --------
    >>> pi = PIController(kp=30.0, ti=0.01)
    >>> abs(complex(pi.transfer_function()(1j * 100.0))) > 30.0  # the integral adds gain
    True
    """

    kp: float
    ti: float = math.inf

    def __post_init__(self) -> None:
        object.__setattr__(self, "kp", positive("PIController", "kp", self.kp))
        object.__setattr__(self, "ti", positive("PIController", "ti", self.ti, "s",
                                                allow_inf=True))

    def transfer_function(self) -> control.TransferFunction:
        """Return the controller as a python-control transfer function.

        Returns
        -------
        control.TransferFunction
            ``kp (ti s + 1) / (ti s)``, or ``kp`` for ``ti = inf``.
        """
        if math.isinf(self.ti):
            return control.tf([self.kp], [1.0])
        return control.tf([self.kp * self.ti, self.kp], [self.ti, 0.0])

    def state_space(self, inputs: str, outputs: str, name: str) -> control.StateSpace:
        """Return the controller as a named state-space block.

        Parameters
        ----------
        inputs : str
            Name of the input signal (the control error).
        outputs : str
            Name of the output signal (the controller's command).
        name : str
            Name of the block; its integrator state is ``<name>_integral``.

        Returns
        -------
        control.StateSpace
            One state (the integral) for a PI controller, none for ``ti = inf``.
        """
        if math.isinf(self.ti):
            return control.ss([], [], [], [[self.kp]], inputs=inputs, outputs=outputs, name=name)
        return control.ss([[0.0]], [[1.0]], [[self.kp / self.ti]], [[self.kp]], inputs=inputs,
                          outputs=outputs, name=name, states=[f"{name}_integral"])


@dataclass(frozen=True)
class LowPassFilter:
    """Second-order low-pass on the torque (current) set-point.

    ``omega_c^2 / (s^2 + 2 zeta omega_c s + omega_c^2)``, omega_c = 2 pi f_hz.
    """

    f_hz: float
    damping_ratio: float = math.sqrt(0.5)

    def __post_init__(self) -> None:
        object.__setattr__(self, "f_hz", positive("LowPassFilter", "f_hz", self.f_hz, "Hz"))
        object.__setattr__(self, "damping_ratio",
                           positive("LowPassFilter", "damping_ratio", self.damping_ratio))

    def transfer_function(self) -> control.TransferFunction:
        """Return the filter as a python-control transfer function (unit static gain).

        Returns
        -------
        control.TransferFunction
            ``omega_c^2 / (s^2 + 2 zeta omega_c s + omega_c^2)``.
        """
        w = 2.0 * math.pi * self.f_hz
        return control.tf([w * w], [1.0, 2.0 * self.damping_ratio * w, w * w])


@dataclass(frozen=True)
class NotchFilter:
    """Notch on the torque set-point.

    ``(s^2 + 2 zeta_z w s + w^2) / (s^2 + 2 zeta_p w s + w^2)`` with w = 2 pi f_hz,
    zeta_p = width/2 (relative -3 dB width) and zeta_z = zeta_p * depth (depth = gain at the
    notch frequency, 0 for a full notch).
    """

    f_hz: float
    width: float = 0.5
    depth: float = 0.1

    def __post_init__(self) -> None:
        object.__setattr__(self, "f_hz", positive("NotchFilter", "f_hz", self.f_hz, "Hz"))
        object.__setattr__(self, "width", positive("NotchFilter", "width", self.width))
        object.__setattr__(self, "depth", fraction(
            "NotchFilter", "depth", self.depth, closed=True,
            hint="it is the gain at the notch frequency (0 for a full notch, 1 for none)"))

    def transfer_function(self) -> control.TransferFunction:
        """Return the notch as a python-control transfer function (gain ``depth`` at f_hz).

        Returns
        -------
        control.TransferFunction
            The notch of the class docstring.
        """
        w = 2.0 * math.pi * self.f_hz
        zp = 0.5 * self.width
        return control.tf([1.0, 2.0 * zp * self.depth * w, w * w], [1.0, 2.0 * zp * w, w * w])


#: Relative tolerance on a sample period being a whole multiple of another.
MULTIPLE_TOLERANCE = 1e-6
#: Rules for the integral of the discrete PI controllers.
INTEGRAL_RULES = ("forward_euler", "tustin")


@dataclass(frozen=True)
class Sampling:
    """The digital drive: sample periods of the three controllers and how they compute.

    Each controller samples its inputs at its instants kT', computes, and applies its output
    ``computation_delay`` whole periods later, held until its next update (zero-order hold);
    the motor voltage is held over each current period. The periods are synchronised whole
    multiples: the velocity period a multiple of the current period, the position period a
    multiple of the velocity period. The speed is the backward difference of the sampled rotor
    angle, optionally smoothed by a first-order filter (``speed_filter`` [s]); the PI
    controllers integrate by forward Euler (default) or Tustin. The conventions in full, and
    the sampled-data model of the loop they make, are in :mod:`servotune.digital`.

    Parameters
    ----------
    current_period, velocity_period, position_period : float
        Sample periods [s]; all three 0 is the continuous drive of the paper.
    computation_delay : int
        Whole periods from sampling to applying the output (1: the output computed from the
        samples of one cycle is applied at the start of the next).
    speed_filter : float
        Time constant [s] of the first-order filter of the measured speed (0: none).
    integral_rule : {"forward_euler", "tustin"}
        How the PI controllers integrate.

    Raises
    ------
    ValueError
        Negative periods, periods given in microseconds, some periods zero and others not,
        a faster controller outside a slower one (the position period shorter than the
        velocity period, or the velocity period shorter than the current period), periods
        that are not whole multiples of each other, a computation delay that is not a whole
        number of periods in [0, 10], or an unknown integral rule.

    Notes
    -----
    Defaults as current industrial servo drives ship them: current and speed controllers at
    125 us, the position controller at 1 ms (SINAMICS S120 with a CU320-2, servo control:
    controller cycle 125 us, with current- and speed-loop -3 dB bandwidths of 650-900 Hz and
    140-250 Hz for 1FK7/1FT7 motors, SINAMICS Engineering Manual, Siemens 2015, sec 6.2.3;
    position controller 1 ms, SINAMICS Function Manual 06/2012, sec 10.7 "System sampling
    times"), one period of computation delay.

    References
    ----------
    K. J. Astrom, B. Wittenmark, Computer-Controlled Systems, 3rd ed., Prentice Hall (1997),
    ch 2, 7 and 8 (sampled-data systems, the zero-order hold, discretised PI). G. Ellis,
    Control System Design Guide, 4th ed. (2012), ch 4 (sampling and computation delay in servo
    loops).

    Examples
    --------
    >>> s = Sampling()
    >>> s.multiples(), s.is_continuous
    ((1, 8), False)
    """

    current_period: float = 125e-6
    velocity_period: float = 125e-6
    position_period: float = 1e-3
    computation_delay: int = 1
    speed_filter: float = 0.0
    integral_rule: str = "forward_euler"

    def __post_init__(self) -> None:
        periods = ("current_period", "velocity_period", "position_period")
        for name in (*periods, "speed_filter"):
            object.__setattr__(self, name, positive("Sampling", name, getattr(self, name), "s",
                                                    allow_zero=True))
            if getattr(self, name) > 1.0:
                raise ValueError(f"Sampling.{name} is {getattr(self, name):g} s; give it in "
                                 "seconds (e.g. 125e-6 for 125 us)")
        delay = self.computation_delay
        if (isinstance(delay, bool) or not isinstance(delay, (int, float))
                or not math.isfinite(delay) or delay != round(delay) or not 0 <= delay <= 10):
            raise ValueError(f"Sampling.computation_delay is {delay!r}; it counts whole sample "
                             "periods from sampling to applying the output: give 0, 1 (the "
                             "usual), 2 ... up to 10")
        object.__setattr__(self, "computation_delay", round(delay))
        if self.integral_rule not in INTEGRAL_RULES:
            raise ValueError(f"Sampling.integral_rule is {self.integral_rule!r}; use one of "
                             f"{list(INTEGRAL_RULES)}")
        zero = [name for name in periods if getattr(self, name) == 0.0]
        if zero and len(zero) < 3:
            raise ValueError(f"Sampling: {', '.join(zero)} zero but not the other periods; "
                             "give all three sample periods, or none (continuous = true) for "
                             "the paper's continuous drive")
        if not zero:
            self.multiples()

    @classmethod
    def continuous(cls) -> Sampling:
        """No sampling, no delays: the continuous drive of the paper (sec 3)."""
        return cls(0.0, 0.0, 0.0, 0, 0.0)

    @property
    def is_continuous(self) -> bool:
        """True for the continuous drive (no sample periods)."""
        return self.current_period == 0.0

    def multiples(self) -> tuple[int, int]:
        """Return the velocity period over the current period and the position period over the
        velocity period.

        Returns
        -------
        (int, int)
            ``(N_v, N_p)``: ``velocity_period = N_v current_period``,
            ``position_period = N_p velocity_period``.

        Raises
        ------
        ValueError
            For a continuous drive, a faster controller outside a slower one, or periods that
            are not whole multiples (within :data:`MULTIPLE_TOLERANCE`).
        """
        if self.is_continuous:
            raise ValueError("a continuous drive has no sample periods")
        pairs = (("velocity_period", "current_period", "the speed controller runs inside the "
                  "current controller's cycle, never faster"),
                 ("position_period", "velocity_period", "the position controller runs "
                  "inside the speed controller's cycle, never faster"))
        out = []
        for slow, fast, why in pairs:
            ts, tf = getattr(self, slow), getattr(self, fast)
            ratio = ts / tf
            n = round(ratio)
            if n < 1:
                raise ValueError(f"Sampling.{slow} ({ts:g} s) is shorter than {fast} "
                                 f"({tf:g} s): {why}; give {slow} >= {tf:g} s")
            if abs(ratio - n) > MULTIPLE_TOLERANCE * ratio:
                raise ValueError(
                    f"Sampling.{slow} ({ts:g} s) is not a whole multiple of {fast} ({tf:g} s): "
                    f"synchronised drive controllers run at whole multiples of each other; "
                    f"give {slow} = {max(n, 1) * tf:g} s (x{max(n, 1)}) or "
                    f"{(n + 1) * tf:g} s (x{n + 1})")
            out.append(int(n))
        return out[0], out[1]

    def to_dict(self) -> dict:
        """SI values.

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        return {"continuous": self.is_continuous, "current_period": self.current_period,
                "velocity_period": self.velocity_period,
                "position_period": self.position_period,
                "computation_delay_periods": self.computation_delay,
                "speed_filter": self.speed_filter, "integral_rule": self.integral_rule}


@dataclass(frozen=True)
class Drive:
    """Motor, transmission and the three cascaded loops of a feed axis.

    Parameters
    ----------
    motor : Motor
        The servo motor (constants, resistance, inductance).
    ratio : float
        Transmission ratio r [m/rad]: slide travel per motor radian.
    current_loop : PIController
        Current PI, kp [V/A], ti [s].
    velocity_loop : PIController
        Velocity PI on the motor encoder, kp [N m s/rad], ti [s].
    kv : float
        Position-loop gain [1/s] (see :func:`kv_from_m_per_min_per_mm`).
    feedback : {"linear", "motor"}
        Position measured by the linear encoder (direct) or by the motor encoder times r
        (indirect).
    encoder : str
        The structure DOF read by the linear encoder [m].
    velocity_feedforward : float
        Gain [-] of the velocity feed-forward (0 = none, 1 = full).
    torque_feedforward_inertia : float
        Inertia [kg m^2] used for the torque feed-forward, referred to the motor (0 = none).
    lowpass : LowPassFilter, optional
        Low-pass on the torque (current) set-point.
    notches : tuple of NotchFilter
        Notches on the torque (current) set-point, applied after the low-pass in their order.
    sampling : Sampling, optional
        The digital drive (sample periods, delays, speed filter); None is the continuous drive
        of the paper.
    limits : DriveLimits, optional
        Peak and continuous torque and the largest motor speed (for the thrust budget).

    Raises
    ------
    ValueError
        Negative or zero gains, Ti <= 0, an unknown feedback, negative feed-forwards.

    Examples
    --------
    Following error at constant feed without feed-forward is v/Kv: with the paper's
    Kv = 1 (m/min)/mm, a 1 m/min feed lags by 1 mm.

    >>> d = Drive(Motor(1.6, 1.6, 0.25, 4e-3), ratio=3.183e-3,
    ...           current_loop=PIController(20.0, 1e-3), velocity_loop=PIController(30.0, 0.01),
    ...           kv=kv_from_m_per_min_per_mm(1.0))
    >>> round(d.following_error(1.0 / 60.0) * 1e3, 6)
    1.0
    """

    motor: Motor
    ratio: float
    current_loop: PIController
    velocity_loop: PIController
    kv: float
    feedback: str = "linear"
    encoder: str = "encoder.x"
    velocity_feedforward: float = 0.0
    torque_feedforward_inertia: float = 0.0
    lowpass: LowPassFilter | None = None
    notches: tuple[NotchFilter, ...] = ()
    sampling: Sampling | None = None
    limits: DriveLimits | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "ratio", positive("Drive", "ratio", self.ratio, "m/rad"))
        for name, kind in (("sampling", Sampling), ("limits", DriveLimits)):
            value = getattr(self, name)
            if value is not None and not isinstance(value, kind):
                raise ValueError(f"Drive.{name} must be a {kind.__name__} or None")
        object.__setattr__(self, "kv", positive("Drive", "kv", self.kv, "1/s"))
        if self.lowpass is not None and not isinstance(self.lowpass, LowPassFilter):
            raise ValueError("Drive.lowpass must be a LowPassFilter or None")
        notches = tuple(self.notches)
        if not all(isinstance(n, NotchFilter) for n in notches):
            raise ValueError("Drive.notches must be a sequence of NotchFilter")
        object.__setattr__(self, "notches", notches)
        if self.feedback not in ("linear", "motor"):
            raise ValueError(f"Drive.feedback must be 'linear' or 'motor', got {self.feedback!r}")
        object.__setattr__(self, "velocity_feedforward", positive(
            "Drive", "velocity_feedforward", self.velocity_feedforward, allow_zero=True))
        object.__setattr__(self, "torque_feedforward_inertia", positive(
            "Drive", "torque_feedforward_inertia", self.torque_feedforward_inertia, "kg m^2",
            allow_zero=True))
        for name, kind in (("motor", Motor), ("current_loop", PIController),
                           ("velocity_loop", PIController)):
            if not isinstance(getattr(self, name), kind):
                raise ValueError(f"Drive.{name} must be a {kind.__name__}")

    @property
    def kv_m_per_min_per_mm(self) -> float:
        """Kv as the machine-tool Kv factor [(m/min)/mm]."""
        return kv_to_m_per_min_per_mm(self.kv)

    def following_error(self, feed: float) -> float:
        """Return the steady following error [m] at a constant feed: (1 - kvff) v / Kv.

        Exact for a type-1 position loop around a velocity loop with integral action (the
        velocity loop then has no steady error at constant speed).

        Parameters
        ----------
        feed : float
            The constant feed speed v [m/s].

        Returns
        -------
        float
            The following error [m].
        """
        return (1.0 - self.velocity_feedforward) * float(feed) / self.kv

    @property
    def digital(self) -> Sampling:
        """The sampling of the drive (the continuous one when there is none)."""
        return self.sampling if self.sampling is not None else Sampling.continuous()

    @property
    def thrust_peak(self) -> float | None:
        """Peak thrust at the slide [N]: peak torque over the transmission ratio."""
        return None if self.limits is None else self.limits.torque_peak / self.ratio

    @property
    def thrust_continuous(self) -> float | None:
        """Continuous thrust at the slide [N]."""
        return None if self.limits is None else self.limits.torque_continuous / self.ratio

    @property
    def speed_max(self) -> float | None:
        """Largest slide speed the motor allows [m/s]."""
        if self.limits is None or self.limits.speed_max is None:
            return None
        return self.limits.speed_max * self.ratio

    @property
    def setpoint_filters(self) -> tuple:
        """The torque set-point filters in their order: the low-pass (if any), then the
        notches."""
        return ((self.lowpass,) if self.lowpass is not None else ()) + self.notches

    def torque_filter(self) -> control.TransferFunction:
        """Return the product of the set-point filters (1 when there are none).

        Returns
        -------
        control.TransferFunction
            The low-pass times the notches, those that are present.
        """
        tf = control.tf([1.0], [1.0])
        for f in self.setpoint_filters:
            tf = tf * f.transfer_function()
        return tf


def drive_blocks(drive: Drive) -> list[control.StateSpace]:
    """Return the continuous cascade as python-control blocks with named signals.

    Signals (SI):

    ========================  =====================================================
    ``x_ref``, ``v_ref``,     position [m], velocity [m/s] and acceleration [m/s^2]
    ``a_ref``                 references (the last two feed the feed-forwards)
    ``x_fb``                  measured position [m]
    ``omega_fb``              motor speed, rotor minus stator [rad/s]
    ``following_error``       x_ref - x_fb [m]
    ``omega_cmd``             motor speed command [rad/s]
    ``torque_set``            torque set-point after feed-forward and filters [N m]
    ``omega_rel``             rotor minus stator speed for the back-EMF [rad/s]
    ``torque``                motor air-gap torque kt i [N m]
    ``current``               winding current [A]
    ========================  =====================================================

    This is the continuous drive of the paper (``Sampling.continuous()``); a digital drive is
    a sampled-data system, not a continuous one: its controllers are the difference equations
    of :func:`servotune.digital.digital_controller` and its loop the sampled-data model of
    :class:`servotune.digital.SampledAxis`. The winding alone is :func:`winding_block`.

    The position feedback ``x_fb`` and the speeds are produced by the plant (see
    :mod:`servotune.plant`); these blocks only compute.

    Parameters
    ----------
    drive : Drive
        The drive (continuous).

    Returns
    -------
    list of control.StateSpace
        The named blocks: the position P controller, the velocity PI, the current PI, the
        filters and feed-forwards, and the winding.

    Raises
    ------
    ValueError
        For a sampled drive.
    """
    if not drive.digital.is_continuous:
        raise ValueError("drive_blocks() is the continuous cascade; this drive is sampled "
                         "([drive.sampling]): use servotune.digital.SampledAxis")
    kv, r = drive.kv, drive.ratio
    blocks = [control.ss(
        [], [], [], [[1.0, -1.0, 0.0], [kv / r, -kv / r, drive.velocity_feedforward / r]],
        inputs=["x_ref", "x_fb", "v_ref"], outputs=["following_error", "omega_cmd_pos"],
        name="position_controller")]
    blocks.append(control.ss([], [], [], [[1.0, -1.0]], inputs=["omega_cmd_pos", "omega_fb"],
                             outputs=["omega_error"], name="velocity_error"))
    blocks.append(drive.velocity_loop.state_space("omega_error", "torque_pi",
                                                  "velocity_controller"))
    blocks.append(control.ss([], [], [], [[1.0, drive.torque_feedforward_inertia / r]],
                             inputs=["torque_pi", "a_ref"], outputs=["torque_unfiltered"],
                             name="torque_feedforward"))
    blocks.append(control.ss(drive.torque_filter(), inputs="torque_unfiltered",
                             outputs="torque_set", name="torque_filter"))
    m, cl = drive.motor, drive.current_loop
    # current PI on i_cmd = T_set / kt:  u = kp (i_cmd - i) + (kp/ti) xi,  d xi/dt = i_cmd - i
    ki = 0.0 if math.isinf(cl.ti) else cl.kp / cl.ti
    gain = [[cl.kp / m.torque_constant, -cl.kp]]
    if ki:
        blocks.append(control.ss([[0.0]], [[1.0 / m.torque_constant, -1.0]], [[ki]], gain,
                                 inputs=["torque_set", "current"], outputs=["voltage"],
                                 states=["current_integral"], name="current_controller"))
    else:
        blocks.append(control.ss([], [], [], gain, inputs=["torque_set", "current"],
                                 outputs=["voltage"], name="current_controller"))
    blocks.append(winding_block(m))
    return blocks


def winding_block(motor: Motor) -> control.StateSpace:
    """Return the motor winding as a named block: ``L di/dt = u - R i - ke omega_rel``.

    Parameters
    ----------
    motor : Motor
        The motor.

    Returns
    -------
    control.StateSpace
        Inputs ``voltage`` [V], ``omega_rel`` [rad/s]; outputs ``torque`` = kt i [N m] and
        ``current`` [A]; one state, the current.
    """
    m = motor
    return control.ss([[-m.resistance / m.inductance]],
                      [[1.0 / m.inductance, -m.back_emf_constant / m.inductance]],
                      [[m.torque_constant], [1.0]], np.zeros((2, 2)),
                      inputs=["voltage", "omega_rel"], outputs=["torque", "current"],
                      states=["current"], name="winding")


@dataclass(frozen=True)
class CascadeResponse:
    """The parts of the continuous cascade at complex frequencies s (arrays).

    With the air-gap torque T, the motor speed omega = s phi and the measured position x_fb::

        T = (a (Kv/r (x_ref - x_fb) - omega) - kt ke omega) / den
        a = current_forward * setpoint * C_v(s)

    Attributes
    ----------
    current_forward : C_i(s), the current PI.
    winding : s L + R + C_i(s), the closed current loop's denominator.
    setpoint : F(s), the torque set-point filters.
    velocity_pi : C_v(s), the velocity PI.
    """

    current_forward: np.ndarray
    winding: np.ndarray
    setpoint: np.ndarray
    velocity_pi: np.ndarray


def _tf_at(tf: control.TransferFunction, s: np.ndarray) -> np.ndarray:
    num = np.asarray(tf.num[0][0], dtype=float)
    den = np.asarray(tf.den[0][0], dtype=float)
    return np.polyval(num, s) / np.polyval(den, s)


def cascade_response(drive: Drive, s) -> CascadeResponse:
    """Return the continuous cascade's transfer functions at complex frequencies ``s`` [rad/s].

    Parameters
    ----------
    drive : Drive
        The drive (continuous; a sampled drive is :class:`servotune.digital.SampledAxis`).
    s : array_like of complex
        Complex frequencies [rad/s] (``1j * omega`` on the imaginary axis).

    Returns
    -------
    CascadeResponse
        The factors of the cascade, each an array of the shape of ``s``.

    Raises
    ------
    ValueError
        For a sampled drive.

    Examples
    --------
    >>> d = Drive(Motor(1.6, 1.6, 0.25, 4e-3), ratio=3.183e-3,
    ...           current_loop=PIController(20.0, 1e-3), velocity_loop=PIController(30.0, 0.01),
    ...           kv=16.7)
    >>> r = cascade_response(d, np.array([100j]))
    >>> complex(r.setpoint[0])
    (1+0j)
    """
    if not drive.digital.is_continuous:
        raise ValueError("cascade_response() is the continuous cascade; this drive is sampled")
    s = np.asarray(s, dtype=complex)
    m = drive.motor
    ci = _tf_at(drive.current_loop.transfer_function(), s)
    return CascadeResponse(
        current_forward=ci, winding=s * m.inductance + m.resistance + ci,
        setpoint=_tf_at(drive.torque_filter(), s),
        velocity_pi=_tf_at(drive.velocity_loop.transfer_function(), s))


def pi_response(pi: PIController, z, period: float, rule: str) -> np.ndarray:
    """Return a discrete PI controller's transfer function at points ``z`` of the unit circle.

    Parameters
    ----------
    pi : PIController
        kp and ti [s].
    z : array_like of complex
        ``exp(j w T)``.
    period : float
        Sample period T [s].
    rule : {"forward_euler", "tustin"}
        ``kp (1 + T/(ti (z - 1)))`` or ``kp (1 + T/(2 ti) (z + 1)/(z - 1))``.

    Returns
    -------
    numpy.ndarray
        The response, shape of ``z``.
    """
    z = np.asarray(z, dtype=complex)
    if math.isinf(pi.ti):
        return np.full(z.shape, pi.kp, dtype=complex)
    q = period / (z - 1.0) if rule == "forward_euler" else 0.5 * period * (z + 1.0) / (z - 1.0)
    return pi.kp * (1.0 + q / pi.ti)


def current_loop_response(drive: Drive, omega) -> np.ndarray:
    """Return the closed current loop i/i_set with the rotor held, at frequencies ``omega``.

    Continuous: ``C_i / (s L + R + C_i)``. Sampled: the winding under zero-order hold,
    ``G(z) = (1 - p) / (R (z - p))`` with ``p = exp(-R T / L)`` (exact at the samples), the
    discrete current PI and its computation delay ``z^-d``:
    ``z^-d C_i(z) G(z) / (1 + z^-d C_i(z) G(z))`` at ``z = exp(j w T)``.

    Parameters
    ----------
    drive : Drive
        The drive.
    omega : array_like
        Angular frequencies [rad/s].

    Returns
    -------
    numpy.ndarray
        Complex, shape of ``omega``.
    """
    omega = np.asarray(omega, dtype=float)
    m = drive.motor
    s = drive.digital
    if s.is_continuous:
        ci = _tf_at(drive.current_loop.transfer_function(), 1j * omega)
        return ci / (1j * omega * m.inductance + m.resistance + ci)
    t = s.current_period
    z = np.exp(1j * omega * t)
    p = math.exp(-m.resistance * t / m.inductance)
    g = (1.0 - p) / (m.resistance * (z - p))
    loop = z ** (-s.computation_delay) * pi_response(drive.current_loop, z, t,
                                                      s.integral_rule) * g
    return loop / (1.0 + loop)


def current_loop_bandwidth(drive: Drive) -> float:
    """Return the closed current loop's -3 dB bandwidth [rad/s] with the rotor held.

    Without back-EMF, ``|i / i_set|`` (:func:`current_loop_response`: continuous, or the
    sampled loop of a digital drive) falls to 1/sqrt2 of its value at low frequency (searched
    on 6001 log-spaced frequencies from 1 rad/s to 1e6 rad/s, or to half the sample rate of a
    digital drive, interpolated log-linearly between the two around the crossing).

    Parameters
    ----------
    drive : Drive
        The drive (motor winding, current PI, sampling).

    Returns
    -------
    float
        The bandwidth [rad/s]; ``inf`` when the gain stays above 1/sqrt2 up to the top.

    Examples
    --------
    A P current loop kp on L, R has the first-order bandwidth (kp + R)/L:

    >>> d = Drive(Motor(1.5, 1.5, 0.25, 4e-3), ratio=1e-3, current_loop=PIController(20.0),
    ...           velocity_loop=PIController(10.0, 0.01), kv=16.7)
    >>> round(current_loop_bandwidth(d) / ((20.0 + 0.25) / 4e-3), 4)
    1.0
    """
    s = drive.digital
    top = 1e6 if s.is_continuous else math.pi / s.current_period
    omega = np.geomspace(1.0, top, 6001)
    t = np.abs(current_loop_response(drive, omega))
    t0 = t[0]
    below = np.nonzero(t < t0 / math.sqrt(2.0))[0]
    if not below.size:
        return math.inf
    i = int(below[0])
    f = (math.log(t0 / math.sqrt(2.0)) - math.log(t[i - 1])) / (math.log(t[i]) - math.log(t[i - 1]))
    return float(omega[i - 1] * (omega[i] / omega[i - 1]) ** f)
