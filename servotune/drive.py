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

import functools
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
    "DriveLimits",
    "PIController",
    "LowPassFilter",
    "NotchFilter",
    "Sampling",
    "pade_delay",
    "pade_order",
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


@dataclass(frozen=True)
class DriveLimits:
    """What the motor and its converter can deliver (SI, at the motor shaft).

    Parameters
    ----------
    torque_peak : float
        Largest torque for accelerations and short loads [N m] (the converter's current limit
        times kt, or the motor's own maximum, whichever is lower).
    torque_continuous : float
        Torque the motor carries thermally without limit of time [N m] (the rated torque at
        speed; the stall torque M0 at standstill is somewhat higher).
    speed_max : float, optional
        Largest motor speed [rad/s] (None: not given).

    Raises
    ------
    ValueError
        Non-positive or non-finite values, or a continuous torque above the peak torque.

    Examples
    --------
    The thrust at the slide is the torque over the transmission ratio r [m/rad]:

    >>> limits = DriveLimits(torque_peak=90.0, torque_continuous=27.0, speed_max=314.16)
    >>> round(limits.torque_peak / 1.5915e-3)        # N of peak thrust with lead 20 mm, belt 2
    56550
    """

    torque_peak: float
    torque_continuous: float
    speed_max: float | None = None

    def __post_init__(self) -> None:
        for name, unit in (("torque_peak", "N m"), ("torque_continuous", "N m"),
                           ("speed_max", "rad/s")):
            if getattr(self, name) is not None or name != "speed_max":
                object.__setattr__(self, name, positive("DriveLimits", name,
                                                        getattr(self, name), unit))
        if self.torque_continuous > self.torque_peak:
            raise ValueError(f"DriveLimits.torque_continuous ({self.torque_continuous:g} N m) "
                             f"exceeds torque_peak ({self.torque_peak:g} N m)")


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
            "NotchFilter", "depth", self.depth,
            hint="it is the gain at the notch frequency (0 for a full notch)"))

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


#: Phase error [deg] a Pade approximation of a delay may have within its range of validity.
PADE_PHASE_TOLERANCE_DEG = 1.0
#: Highest Pade order used (higher orders gain little and conditioning suffers).
PADE_MAX_ORDER = 6


@functools.cache
def _pade_unit(order: int):
    """Pade approximation of the unit delay e^-s as a balanced (A, B, C, D) (cached: read
    only)."""
    num, den = control.pade(1.0, order)
    sys = control.ss(control.tf(num, den))
    out = tuple(np.array(m, dtype=float) for m in (sys.A, sys.B, sys.C, sys.D))
    for m in out:
        m.flags.writeable = False
    return out


@functools.lru_cache(maxsize=256)
def pade_order(delay: float, omega_max: float,
               tolerance_deg: float = PADE_PHASE_TOLERANCE_DEG) -> int:
    """Return the lowest Pade order whose phase error stays within a tolerance up to a frequency.

    The error is checked up to ``min(omega_max, pi/delay)`` [rad/s] (above half the sample rate
    of a delay of one sample a continuous model of the sampled loop has no meaning anyway).
    The (n, n) Pade approximant is all-pass (its gain is exactly 1), so its only error is the
    phase; it is computed here, not estimated.

    Parameters
    ----------
    delay : float
        The delay T [s], > 0.
    omega_max : float
        Highest frequency [rad/s] where the phase error is to stay within the tolerance.
    tolerance_deg : float, optional
        Largest phase error [deg] (default ``PADE_PHASE_TOLERANCE_DEG``, 1 deg).

    Returns
    -------
    int
        The order, at most ``PADE_MAX_ORDER`` (returned also when even that order misses the
        tolerance).

    Raises
    ------
    ValueError
        When ``delay`` is not finite and > 0.

    Examples
    --------
    A 187.5 us delay (1.5 periods of a 125 us current loop) up to 3 kHz:

    >>> pade_order(187.5e-6, 2 * math.pi * 3000.0)
    4
    """
    delay = positive("pade_order", "delay", delay, "s")
    x = min(float(omega_max) * delay, math.pi)
    for order in range(1, PADE_MAX_ORDER + 1):
        num, den = control.pade(1.0, order)
        grid = np.linspace(0.0, x, 64)
        value = np.polyval(num, 1j * grid) / np.polyval(den, 1j * grid)
        error = np.abs(np.angle(value * np.exp(1j * grid)))
        if np.degrees(error.max()) <= tolerance_deg:
            return order
    return PADE_MAX_ORDER


def pade_delay(delay: float, order: int, inputs: str, outputs: str,
               name: str) -> control.StateSpace:
    """Return a delay of ``delay`` seconds as a Pade state-space block of the given order.

    Built from the Pade approximant of the unit delay and scaled in time (s -> s T), which keeps
    the realisation well conditioned for any delay.

    Parameters
    ----------
    delay : float
        The delay T [s], > 0.
    order : int
        Order of the (n, n) Pade approximant (:func:`pade_order` chooses it).
    inputs : str
        Name of the input signal.
    outputs : str
        Name of the output signal.
    name : str
        Name of the block; its states are ``<name>_0``, ``<name>_1``, ...

    Returns
    -------
    control.StateSpace
        ``order`` states, gain 1 at every frequency, phase ``-omega T`` at low frequency.

    Raises
    ------
    ValueError
        When ``delay`` is not finite and > 0.

    Examples
    --------
    >>> block = pade_delay(1e-3, 3, "u", "y", "delay")
    >>> z = complex(block(2j * math.pi * 50.0))                  # 50 Hz through 1 ms
    >>> round(abs(z), 9), round(math.degrees(np.angle(z)), 3)     # gain 1, phase -18 deg
    (1.0, -18.0)
    """
    a, b, c, d = _pade_unit(order)
    t = positive("pade_delay", "delay", delay, "s")
    return control.ss(a / t, b / t, c, d, inputs=inputs, outputs=outputs, name=name,
                      states=[f"{name}_{i}" for i in range(a.shape[0])])


@dataclass(frozen=True)
class Sampling:
    """The digital drive: sample periods of the three controllers and what they delay.

    Each controller computes from samples and applies its output after a computation delay of
    ``computation_delay`` periods and then holds it for one period (zero-order hold): for
    frequencies well below half the sample rate the sampled loop acts as the continuous one
    delayed by ``(computation_delay + 1/2) T``. The speed is measured as the difference of two
    encoder positions one velocity period apart, a moving average that delays it by half a
    period, optionally smoothed by a first-order filter (``speed_filter`` [s]). The delays
    enter the linear models as Pade approximations of the order :func:`pade_order` picks for
    1 deg of phase error up to ``pade_frequency`` (or half the sample rate), and the
    frequency-domain models of the tuning as exact exp(-j w T).

    Parameters
    ----------
    current_period, velocity_period, position_period : float
        Sample periods [s]; 0 makes that controller continuous.
    computation_delay : float
        Delay from sampling to applying the output, in periods (1: the output computed from the
        samples of one cycle is applied at the start of the next).
    speed_filter : float
        Time constant [s] of a first-order filter of the measured speed (0: none).
    pade_frequency : float
        Angular frequency [rad/s] up to which the Pade approximations keep 1 deg of phase.

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
    sec 7.5 (the zero-order hold as a half-period delay). G. Ellis, Control System Design Guide,
    4th ed. (2012), ch 4 (sampling and computation delay in servo loops).

    Examples
    --------
    >>> s = Sampling()
    >>> s.current_delay, s.velocity_delay, s.speed_measurement_delay, s.position_delay
    (0.0001875, 0.0001875, 6.25e-05, 0.0015)
    """

    current_period: float = 125e-6
    velocity_period: float = 125e-6
    position_period: float = 1e-3
    computation_delay: float = 1.0
    speed_filter: float = 0.0
    pade_frequency: float = 2.0 * math.pi * 3000.0

    def __post_init__(self) -> None:
        for name in ("current_period", "velocity_period", "position_period",
                     "computation_delay", "speed_filter"):
            unit = "periods" if name == "computation_delay" else "s"
            object.__setattr__(self, name, positive("Sampling", name, getattr(self, name), unit,
                                                    allow_zero=True))
        object.__setattr__(self, "pade_frequency",
                           positive("Sampling", "pade_frequency", self.pade_frequency, "rad/s"))
        for name in ("current_period", "velocity_period", "position_period", "speed_filter"):
            if getattr(self, name) > 1.0:
                raise ValueError(f"Sampling.{name} is {getattr(self, name):g} s; give it in "
                                 "seconds (e.g. 125e-6 for 125 us)")
        if self.computation_delay > 10:
            raise ValueError(f"Sampling.computation_delay is {self.computation_delay:g} "
                             "periods; it is counted in sample periods (typically 0.5 to 2)")

    @classmethod
    def continuous(cls) -> Sampling:
        """No sampling, no delays: the continuous drive of the paper (sec 3)."""
        return cls(0.0, 0.0, 0.0, 0.0, 0.0)

    @property
    def is_continuous(self) -> bool:
        return not any((self.current_delay, self.velocity_delay, self.speed_measurement_delay,
                        self.position_delay, self.speed_filter))

    @property
    def current_delay(self) -> float:
        """Delay of the current controller's voltage output [s]."""
        return (self.computation_delay + 0.5) * self.current_period

    @property
    def velocity_delay(self) -> float:
        """Delay of the velocity controller's torque set-point [s]."""
        return (self.computation_delay + 0.5) * self.velocity_period

    @property
    def speed_measurement_delay(self) -> float:
        """Delay of the speed measured by differencing positions one period apart [s]."""
        return 0.5 * self.velocity_period

    @property
    def position_delay(self) -> float:
        """Delay of the position controller's speed command [s]."""
        return (self.computation_delay + 0.5) * self.position_period

    def velocity_loop_delay(self) -> float:
        """Return the total pure delay around the velocity loop outside the current loop [s].

        Returns
        -------
        float
            ``velocity_delay + speed_measurement_delay`` [s].
        """
        return self.velocity_delay + self.speed_measurement_delay

    def delay_block(self, delay: float, inputs: str, outputs: str,
                    name: str) -> control.StateSpace | None:
        """Return a Pade block for one of the delays (None for a zero delay).

        Parameters
        ----------
        delay : float
            The delay [s]; <= 0 gives None.
        inputs : str
            Name of the input signal.
        outputs : str
            Name of the output signal.
        name : str
            Name of the block.

        Returns
        -------
        control.StateSpace or None
            :func:`pade_delay` of the order :func:`pade_order` chooses up to
            ``pade_frequency``.
        """
        if delay <= 0.0:
            return None
        return pade_delay(delay, pade_order(delay, self.pade_frequency), inputs, outputs, name)

    def delay_response(self, delay: float, s) -> np.ndarray:
        """Return the exact delay exp(-s T) at complex frequencies ``s``.

        Parameters
        ----------
        delay : float
            The delay T [s].
        s : array_like of complex
            Complex frequencies [rad/s] (``1j * omega`` on the imaginary axis).

        Returns
        -------
        numpy.ndarray
            exp(-s T), shape of ``s``.
        """
        return np.exp(-np.asarray(s) * delay)

    def speed_filter_response(self, s) -> np.ndarray:
        """Return the speed measurement's response: half-period delay times the first-order filter.

        Parameters
        ----------
        s : array_like of complex
            Complex frequencies [rad/s].

        Returns
        -------
        numpy.ndarray
            ``exp(-s T_v / 2) / (1 + s T_f)``, shape of ``s`` (T_v the velocity period, T_f the
            speed filter).
        """
        s = np.asarray(s)
        return self.delay_response(self.speed_measurement_delay, s) / (1.0 + s * self.speed_filter)

    def to_dict(self) -> dict:
        """SI values, with the derived delays.

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        return {"current_period": self.current_period, "velocity_period": self.velocity_period,
                "position_period": self.position_period,
                "computation_delay_periods": self.computation_delay,
                "speed_filter": self.speed_filter, "current_delay": self.current_delay,
                "velocity_delay": self.velocity_delay,
                "speed_measurement_delay": self.speed_measurement_delay,
                "position_delay": self.position_delay}


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
    lowpass, notch : LowPassFilter or NotchFilter, optional
        Filters on the torque (current) set-point.
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
    notch: NotchFilter | None = None
    sampling: Sampling | None = None
    limits: DriveLimits | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "ratio", positive("Drive", "ratio", self.ratio, "m/rad"))
        for name, kind in (("sampling", Sampling), ("limits", DriveLimits)):
            value = getattr(self, name)
            if value is not None and not isinstance(value, kind):
                raise ValueError(f"Drive.{name} must be a {kind.__name__} or None")
        object.__setattr__(self, "kv", positive("Drive", "kv", self.kv, "1/s"))
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

    def torque_filter(self) -> control.TransferFunction:
        """Return the product of the set-point filters (1 when there are none).

        Returns
        -------
        control.TransferFunction
            The low-pass times the notch, those that are present.
        """
        tf = control.tf([1.0], [1.0])
        for f in (self.lowpass, self.notch):
            if f is not None:
                tf = tf * f.transfer_function()
        return tf


def drive_blocks(drive: Drive) -> list[control.StateSpace]:
    """Return the cascade as python-control blocks with named signals, for ``control.interconnect``.

    Signals (SI):

    ========================  =====================================================
    ``x_ref``, ``v_ref``,     position [m], velocity [m/s] and acceleration [m/s^2]
    ``a_ref``                 references (the last two feed the feed-forwards)
    ``x_fb``                  measured position [m]
    ``omega_fb``              motor speed, rotor minus stator [rad/s], before the speed
                              measurement (delay, filter) of a digital drive
    ``following_error``       x_ref - x_fb [m]
    ``omega_cmd``             motor speed command [rad/s]
    ``torque_set``            torque set-point after feed-forward and filters [N m]
    ``omega_rel``             rotor minus stator speed for the back-EMF [rad/s]
    ``torque``                motor air-gap torque kt i [N m]
    ``current``               winding current [A]
    ========================  =====================================================

    With a digital drive (:attr:`Drive.sampling`) the controllers' outputs pass through Pade
    blocks of their delays (``position_delay``, ``velocity_delay``, ``current_delay``) and the
    measured speed through the half-period delay of the speed measurement and the speed filter
    (see :class:`Sampling`).

    The position feedback ``x_fb`` and the speeds are produced by the plant (see
    :mod:`servotune.plant`); these blocks only compute.

    Parameters
    ----------
    drive : Drive
        The drive.

    Returns
    -------
    list of control.StateSpace
        The named blocks: the position P controller, the velocity PI, the current PI and
        winding, the filters and feed-forwards, and the delay blocks of a digital drive.
    """
    kv, r = drive.kv, drive.ratio
    sampling = drive.digital
    blocks = []

    def delayed(delay, signal, name):
        """The signal name after a delay block (the block appended), or the signal itself."""
        block = sampling.delay_block(delay, f"{signal}_raw", signal, name)
        if block is None:
            return signal, signal
        blocks.append(block)
        return f"{signal}_raw", signal

    pos_out, _ = delayed(sampling.position_delay, "omega_cmd_pos", "position_delay")
    blocks.append(control.ss(
        [], [], [], [[1.0, -1.0, 0.0], [kv / r, -kv / r, drive.velocity_feedforward / r]],
        inputs=["x_ref", "x_fb", "v_ref"], outputs=["following_error", pos_out],
        name="position_controller"))
    # speed measurement: half-period delay of the position difference, then the filter
    measured = "omega_fb"
    block = sampling.delay_block(sampling.speed_measurement_delay, "omega_fb",
                                 "omega_fb_delayed", "speed_measurement_delay")
    if block is not None:
        blocks.append(block)
        measured = "omega_fb_delayed"
    if sampling.speed_filter > 0.0:
        tau = sampling.speed_filter
        blocks.append(control.ss([[-1.0 / tau]], [[1.0 / tau]], [[1.0]], [[0.0]],
                                 inputs=measured, outputs="omega_measured", name="speed_filter",
                                 states=["speed_filter"]))
        measured = "omega_measured"
    blocks.append(control.ss([], [], [], [[1.0, -1.0]], inputs=["omega_cmd_pos", measured],
                             outputs=["omega_error"], name="velocity_error"))
    vel_out, _ = delayed(sampling.velocity_delay, "torque_pi", "velocity_delay")
    blocks.append(drive.velocity_loop.state_space("omega_error", vel_out, "velocity_controller"))
    blocks.append(control.ss([], [], [], [[1.0, drive.torque_feedforward_inertia / r]],
                             inputs=["torque_pi", "a_ref"], outputs=["torque_unfiltered"],
                             name="torque_feedforward"))
    blocks.append(control.ss(drive.torque_filter(), inputs="torque_unfiltered",
                             outputs="torque_set", name="torque_filter"))
    m, cl = drive.motor, drive.current_loop
    # current PI on i_cmd = T_set / kt:  u = kp (i_cmd - i) + (kp/ti) xi,  d xi/dt = i_cmd - i
    ki = 0.0 if math.isinf(cl.ti) else cl.kp / cl.ti
    volt_out, _ = delayed(sampling.current_delay, "voltage", "current_delay")
    gain = [[cl.kp / m.torque_constant, -cl.kp]]
    if ki:
        blocks.append(control.ss([[0.0]], [[1.0 / m.torque_constant, -1.0]], [[ki]], gain,
                                 inputs=["torque_set", "current"], outputs=[volt_out],
                                 states=["current_integral"], name="current_controller"))
    else:
        blocks.append(control.ss([], [], [], gain, inputs=["torque_set", "current"],
                                 outputs=[volt_out], name="current_controller"))
    # winding:  L di/dt = u - R i - ke omega_rel;  torque = kt i
    blocks.append(control.ss([[-m.resistance / m.inductance]],
                             [[1.0 / m.inductance, -m.back_emf_constant / m.inductance]],
                             [[m.torque_constant], [1.0]], np.zeros((2, 2)),
                             inputs=["voltage", "omega_rel"], outputs=["torque", "current"],
                             states=["current"], name="winding"))
    return blocks


@dataclass(frozen=True)
class CascadeResponse:
    """The parts of the cascade at complex frequencies s (arrays), for frequency-domain models.

    With the air-gap torque T, the motor speed omega = s phi and the measured position x_fb::

        T = (a (D_p Kv/r (x_ref - x_fb) - M_v omega) - kt ke omega) / den
        a = current_forward * setpoint * C_v(s)

    Attributes
    ----------
    current_forward : C_i(s) D_i(s), the current PI and the delay of its output.
    winding : s L + R + C_i(s) D_i(s), the closed current loop's denominator.
    setpoint : F(s) D_v(s), the torque set-point filters and the velocity controller's delay.
    speed_measurement : M_v(s), the speed measurement's delay and filter.
    position_delay : D_p(s), the delay of the position controller's output.
    velocity_pi : C_v(s), the velocity PI.
    """

    current_forward: np.ndarray
    winding: np.ndarray
    setpoint: np.ndarray
    speed_measurement: np.ndarray
    position_delay: np.ndarray
    velocity_pi: np.ndarray


def _tf_at(tf: control.TransferFunction, s: np.ndarray) -> np.ndarray:
    num = np.asarray(tf.num[0][0], dtype=float)
    den = np.asarray(tf.den[0][0], dtype=float)
    return np.polyval(num, s) / np.polyval(den, s)


def cascade_response(drive: Drive, s, exact_delays: bool = True) -> CascadeResponse:
    """Return the cascade's transfer functions at complex frequencies ``s`` [rad/s].

    The digital drive's delays are exact exponentials (``exact_delays=True``) or the Pade
    approximations the state-space blocks of :func:`drive_blocks` use (False): the second
    reproduces the state-space model to rounding, the first is the sampled drive it stands for.

    Parameters
    ----------
    drive : Drive
        The drive; its ``digital`` sampling gives the delays (all zero when continuous).
    s : array_like of complex
        Complex frequencies [rad/s] (``1j * omega`` on the imaginary axis).
    exact_delays : bool, optional
        Exact delays (default) or their Pade approximations.

    Returns
    -------
    CascadeResponse
        The factors of the cascade, each an array of the shape of ``s``.

    Examples
    --------
    Without sampling the delays are 1:

    >>> d = Drive(Motor(1.6, 1.6, 0.25, 4e-3), ratio=3.183e-3,
    ...           current_loop=PIController(20.0, 1e-3), velocity_loop=PIController(30.0, 0.01),
    ...           kv=16.7)
    >>> r = cascade_response(d, np.array([100j]))
    >>> complex(r.position_delay[0]), complex(r.speed_measurement[0])
    ((1+0j), (1+0j))
    """
    s = np.asarray(s, dtype=complex)
    sampling = drive.digital

    def delay(value):
        if value <= 0.0:
            return np.ones_like(s)
        if exact_delays:
            return np.exp(-s * value)
        order = pade_order(value, sampling.pade_frequency)
        num, den = control.pade(1.0, order)
        return np.polyval(num, s * value) / np.polyval(den, s * value)

    m = drive.motor
    ci = _tf_at(drive.current_loop.transfer_function(), s) * delay(sampling.current_delay)
    measurement = delay(sampling.speed_measurement_delay) / (1.0 + s * sampling.speed_filter)
    return CascadeResponse(
        current_forward=ci, winding=s * m.inductance + m.resistance + ci,
        setpoint=_tf_at(drive.torque_filter(), s) * delay(sampling.velocity_delay),
        speed_measurement=measurement, position_delay=delay(sampling.position_delay),
        velocity_pi=_tf_at(drive.velocity_loop.transfer_function(), s))


def current_loop_bandwidth(drive: Drive, exact_delays: bool = True) -> float:
    """Return the closed current loop's -3 dB bandwidth [rad/s] with the rotor held.

    Without back-EMF, ``|C_i D_i / (s L + R + C_i D_i)|`` falls to 1/sqrt2 of its value at low
    frequency (searched on 6001 log-spaced frequencies from 1 to 1e6 rad/s, interpolated
    log-linearly between the two around the crossing).

    Parameters
    ----------
    drive : Drive
        The drive (motor winding, current PI, and the current controller's delay).
    exact_delays : bool, optional
        Exact delays (default) or their Pade approximations (:func:`cascade_response`).

    Returns
    -------
    float
        The bandwidth [rad/s]; ``inf`` when the gain stays above 1/sqrt2 up to 1e6 rad/s.

    Examples
    --------
    A P current loop kp on L, R has the first-order bandwidth (kp + R)/L:

    >>> d = Drive(Motor(1.5, 1.5, 0.25, 4e-3), ratio=1e-3, current_loop=PIController(20.0),
    ...           velocity_loop=PIController(10.0, 0.01), kv=16.7)
    >>> round(current_loop_bandwidth(d) / ((20.0 + 0.25) / 4e-3), 4)
    1.0
    """
    omega = np.geomspace(1.0, 1e6, 6001)
    parts = cascade_response(drive, 1j * omega, exact_delays=exact_delays)
    t = np.abs(parts.current_forward / parts.winding)
    t0 = t[0]
    below = np.nonzero(t < t0 / math.sqrt(2.0))[0]
    if not below.size:
        return math.inf
    i = int(below[0])
    f = (math.log(t0 / math.sqrt(2.0)) - math.log(t[i - 1])) / (math.log(t[i]) - math.log(t[i - 1]))
    return float(omega[i - 1] * (omega[i] / omega[i - 1]) ** f)
