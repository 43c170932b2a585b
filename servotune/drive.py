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

import math
from dataclasses import dataclass

import control
import numpy as np

__all__ = [
    "KV_PER_M_PER_MIN_PER_MM",
    "kv_from_m_per_min_per_mm",
    "kv_to_m_per_min_per_mm",
    "Motor",
    "PIController",
    "LowPassFilter",
    "NotchFilter",
    "Drive",
    "drive_blocks",
]

#: 1 (m/min)/mm of machine-tool Kv factor in 1/s: (1/60 m/s) / (1e-3 m) = 1000/60.
KV_PER_M_PER_MIN_PER_MM = 1000.0 / 60.0


def kv_from_m_per_min_per_mm(kv_m_per_min_per_mm: float) -> float:
    """Position-loop gain Kv [1/s] from the machine-tool Kv factor [(m/min)/mm].

    Examples
    --------
    The paper's Kv = 1 (m/min)/mm: a 1 mm following error per 1 m/min of feed.

    >>> round(kv_from_m_per_min_per_mm(1.0), 4)
    16.6667
    """
    return float(kv_m_per_min_per_mm) * KV_PER_M_PER_MIN_PER_MM


def kv_to_m_per_min_per_mm(kv: float) -> float:
    """The machine-tool Kv factor [(m/min)/mm] of a position-loop gain Kv [1/s]."""
    return float(kv) / KV_PER_M_PER_MIN_PER_MM


def _positive(owner: str, name: str, value, allow_zero: bool = False,
              allow_inf: bool = False) -> float:
    value = float(value)
    ok = (value >= 0.0 if allow_zero else value > 0.0) and not math.isnan(value)
    if not ok or (math.isinf(value) and not allow_inf):
        need = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{owner}.{name} must be finite and {need}, got {value!r}")
    return value


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
        for name in ("torque_constant", "back_emf_constant", "resistance", "inductance"):
            object.__setattr__(self, name, _positive("Motor", name, getattr(self, name)))

    @property
    def electrical_time_constant(self) -> float:
        """L/R [s]."""
        return self.inductance / self.resistance


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
        object.__setattr__(self, "kp", _positive("PIController", "kp", self.kp))
        object.__setattr__(self, "ti", _positive("PIController", "ti", self.ti, allow_inf=True))

    def transfer_function(self) -> control.TransferFunction:
        """The controller as a python-control transfer function."""
        if math.isinf(self.ti):
            return control.tf([self.kp], [1.0])
        return control.tf([self.kp * self.ti, self.kp], [self.ti, 0.0])

    def state_space(self, inputs: str, outputs: str, name: str) -> control.StateSpace:
        """The controller as a named state-space block (integrator state ``<name>_integral``)."""
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
        object.__setattr__(self, "f_hz", _positive("LowPassFilter", "f_hz", self.f_hz))
        object.__setattr__(self, "damping_ratio",
                           _positive("LowPassFilter", "damping_ratio", self.damping_ratio))

    def transfer_function(self) -> control.TransferFunction:
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
        object.__setattr__(self, "f_hz", _positive("NotchFilter", "f_hz", self.f_hz))
        object.__setattr__(self, "width", _positive("NotchFilter", "width", self.width))
        depth = _positive("NotchFilter", "depth", self.depth, allow_zero=True)
        if depth >= 1.0:
            raise ValueError(f"NotchFilter.depth must be in [0, 1), got {depth!r}")
        object.__setattr__(self, "depth", depth)

    def transfer_function(self) -> control.TransferFunction:
        w = 2.0 * math.pi * self.f_hz
        zp = 0.5 * self.width
        return control.tf([1.0, 2.0 * zp * self.depth * w, w * w], [1.0, 2.0 * zp * w, w * w])


@dataclass(frozen=True)
class Drive:
    """Motor, transmission and the three cascaded loops of a feed axis.

    Parameters
    ----------
    motor : Motor
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

    def __post_init__(self) -> None:
        object.__setattr__(self, "ratio", _positive("Drive", "ratio", self.ratio))
        object.__setattr__(self, "kv", _positive("Drive", "kv", self.kv))
        if self.feedback not in ("linear", "motor"):
            raise ValueError(f"Drive.feedback must be 'linear' or 'motor', got {self.feedback!r}")
        object.__setattr__(self, "velocity_feedforward", _positive(
            "Drive", "velocity_feedforward", self.velocity_feedforward, allow_zero=True))
        object.__setattr__(self, "torque_feedforward_inertia", _positive(
            "Drive", "torque_feedforward_inertia", self.torque_feedforward_inertia,
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
        """Steady following error [m] at a constant feed [m/s]: (1 - kvff) v / Kv.

        Exact for a type-1 position loop around a velocity loop with integral action (the
        velocity loop then has no steady error at constant speed).
        """
        return (1.0 - self.velocity_feedforward) * float(feed) / self.kv

    def torque_filter(self) -> control.TransferFunction:
        """Product of the set-point filters (1 when there are none)."""
        tf = control.tf([1.0], [1.0])
        for f in (self.lowpass, self.notch):
            if f is not None:
                tf = tf * f.transfer_function()
        return tf


def drive_blocks(drive: Drive) -> list[control.StateSpace]:
    """The cascade as python-control blocks with named signals, for ``control.interconnect``.

    Signals (SI):

    ========================  =====================================================
    ``x_ref``, ``v_ref``,     position [m], velocity [m/s] and acceleration [m/s^2]
    ``a_ref``                 references (the last two feed the feed-forwards)
    ``x_fb``                  measured position [m]
    ``omega_fb``              measured motor speed, rotor minus stator [rad/s]
    ``following_error``       x_ref - x_fb [m]
    ``omega_cmd``             motor speed command [rad/s]
    ``torque_set``            torque set-point after feed-forward and filters [N m]
    ``omega_rel``             rotor minus stator speed for the back-EMF [rad/s]
    ``torque``                motor air-gap torque kt i [N m]
    ``current``               winding current [A]
    ========================  =====================================================

    The position feedback ``x_fb`` and the speeds are produced by the plant (see
    :mod:`servotune.plant`); these blocks only compute.
    """
    kv, r = drive.kv, drive.ratio
    position = control.ss(
        [], [], [], [[1.0, -1.0, 0.0], [kv / r, -kv / r, drive.velocity_feedforward / r]],
        inputs=["x_ref", "x_fb", "v_ref"], outputs=["following_error", "omega_cmd_pos"],
        name="position_controller")
    velocity_error = control.ss([], [], [], [[1.0, -1.0]], inputs=["omega_cmd_pos", "omega_fb"],
                                outputs=["omega_error"], name="velocity_error")
    velocity = drive.velocity_loop.state_space("omega_error", "torque_pi", "velocity_controller")
    torque_sum = control.ss([], [], [], [[1.0, drive.torque_feedforward_inertia / r]],
                            inputs=["torque_pi", "a_ref"], outputs=["torque_unfiltered"],
                            name="torque_feedforward")
    filt = control.ss(drive.torque_filter(), inputs="torque_unfiltered", outputs="torque_set",
                      name="torque_filter")
    m, cl = drive.motor, drive.current_loop
    # states: current-PI integral of the current error, winding current
    # u = kp (i_cmd - i) + (kp/ti) xi;   L di/dt = u - R i - ke omega_rel;   i_cmd = T_set / kt
    ki = 0.0 if math.isinf(cl.ti) else cl.kp / cl.ti
    a = np.array([[0.0, -1.0], [ki / m.inductance, -(cl.kp + m.resistance) / m.inductance]])
    b = np.array([[1.0 / m.torque_constant, 0.0],
                  [cl.kp / (m.torque_constant * m.inductance),
                   -m.back_emf_constant / m.inductance]])
    c = np.array([[0.0, m.torque_constant], [0.0, 1.0]])
    if ki == 0.0:  # P-only current loop: the integral state is unobservable; drop it
        a, b, c = a[1:, 1:], b[1:], c[:, 1:]
    states = (["current_integral"] if ki else []) + ["current"]
    motor = control.ss(a, b, c, np.zeros((2, 2)), inputs=["torque_set", "omega_rel"],
                       outputs=["torque", "current"], states=states, name="current_loop")
    return [position, velocity_error, velocity, torque_sum, filt, motor]
