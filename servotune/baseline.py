"""The baseline a tuned design must beat: what commissioning gives, and the textbook hand rule.

A machine builder adopts servotune's design only if it is measurably better than what a
commissioning engineer, or the drive's own auto-tuner, sets in an afternoon. This module writes
that procedure down as rules, each with its source, evaluated on the same model the tuner uses
(the sampled-data axis of a digital drive, :class:`servotune.digital.SampledAxis`, or the
continuous one; :func:`servotune.closed_loop.closed_loop`):

1. **Current loop, technical optimum** (Betragsoptimum): ``Ti_i = L/R`` cancels the electrical
   pole, ``Kp_i = L / (2 T_sigma_i)`` with the current loop's small time constant
   ``T_sigma_i = (d + 1/2) T`` (computation delay d periods, half a period of the held
   voltage).
2. **Velocity loop, symmetric optimum** on the rigid inertia at the motor
   ``J = m r^2`` (m the moving mass, :func:`servotune.thrust.moving_mass`):
   ``Kp = J / (a T_sigma_v)``, ``Ti = a^2 T_sigma_v``, a = 2, with the velocity loop's small time
   constant ``T_sigma_v = 2 T_sigma_i + (d + 1/2) T_v (+ hold, speed filter, set-point
   low-pass)``. Then, as the auto-tuners do, the speed loop is *measured* (the loop response
   of the model in the sliding regime at the lowest feed speed) and

   a. ``a`` is raised (Kp falls as 1/a, Ti rises as a^2: the symmetric optimum's own damping
      knob) until the measured velocity loop is stable with ``Ms <= ms_limit("velocity")``;
   b. if the measured speed plant (torque set-point -> measured speed) has a sharp resonance
      above three times the velocity bandwidth so found, ONE current set-point notch is put on
      it and step a is repeated; the notch stays only if it lets Kp rise.
3. **Position loop**: ``Kv = w_b / 4`` (w_b the measured velocity-loop bandwidth: the cascade
   hierarchy, the inner loop 4 times the outer), lowered until the position loop's Ms meets
   ``ms_limit("position")``, its step response does not overshoot (at most 1 %) and its
   measured closed-loop bandwidth keeps the hierarchy, at most ``w_b / bandwidth_ratio_min``
   (:attr:`servotune.requirements.Requirements.bandwidth_ratio_min`: the closed position loop
   is wider than Kv when the velocity loop is lightly damped).
4. The guide ways keep their own damping: ``C = [friction] viscous`` (no damper is added).

:func:`textbook_design` is the hand rule the project has compared against so far:
``Kp = J 2 pi 25 Hz``, ``Ti = 25 ms``, ``Kv = 25 1/s``. The procedure::

    current PI (TO) --> velocity PI (SO, a = 2) --> measure L_v: raise a until Ms <= limit
        --> measured speed plant P: a sharp resonance above 3 w_b?  --> notch it, raise a
            again from 2, keep the notch if a ends lower (Kp higher)
        --> Kv = w_b / 4, lowered until Ms_p <= limit, no overshoot, bandwidth <= w_b / 4

References
----------
D. Schroeder, Elektrische Antriebe - Regelung von Antriebssystemen, 4th ed., Springer (2015),
the chapters on the technical and the symmetric optimum (TO: Kp = L/(2 T_sigma), Ti = L/R, the
closed loop's equivalent time constant 2 T_sigma; SO: Kp = J/(a T_sigma), Ti = a^2 T_sigma,
phase margin asin((a^2-1)/(a^2+1))) and on digital current and speed control (computation
delay, hold and speed measurement as small time constants). C. Kessler, "Das symmetrische
Optimum", Regelungstechnik 6 (1958) 395-400, 432-436. G. Ellis, Control System Design Guide,
4th ed., Butterworth-Heinemann (2012): delay in digital controllers (half a sample of hold plus
the computation time), mechanical resonance and notch filters on the current command, cascaded
loops (the inner loop 3-5 times the outer). H. Gross, J. Hamann, G. Wiegaertner, Electrical
Feed Drives in Automation, Publicis MCD (2001): commissioning of feed drives (speed loop by
the symmetric optimum, reduced for the mechanics; Kv from the speed loop, no overshoot).
Siemens, SINAMICS S120 Function Manual Drive Functions, "Automatic speed controller
optimization" and "One Button Tuning" (p5271-p5274: the speed loop's frequency response is
measured, current set-point filters are set on its resonances, Kp follows the inertia and a
dynamic factor, Tn the loop's dynamic response). Heidenhain, TNC technical manual and TNCopt,
"optimizing the control loops" (speed loop first with its filters, Kv last, without
overshoot).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .axis import Axis
from .closed_loop import closed_loop
from .drive import (
    Drive,
    LowPassFilter,
    Motor,
    NotchFilter,
    PIController,
    Sampling,
    current_loop_bandwidth,
    kv_to_m_per_min_per_mm,
    pi_response,
)
from .frequency import LoopAnalysis, peak
from .plant import Contact, UnstableLoopError
from .structure.model import ModalModel
from .thrust import moving_mass
from .units import HZ_PER_RAD_S
from .validation import positive

__all__ = [
    "SO_PARAMETER",
    "KV_BANDWIDTH_RATIO",
    "OVERSHOOT_MAX",
    "NOTCH_BANDWIDTH_FACTOR",
    "BaselineDesign",
    "commissioning_design",
    "textbook_design",
    "technical_optimum",
    "symmetric_optimum",
    "current_small_time_constant",
    "velocity_small_time_constant",
    "speed_plant_response",
    "resonance_notch",
    "position_step_overshoot",
    "compliance_peaks",
]

#: The symmetric optimum's normalising parameter a to start from: the classic choice
#: (Kessler 1958; Schroeder 2015), phase margin asin(3/5) = 36.9 deg, Ms 1.68 on the ideal loop.
SO_PARAMETER = 2.0
#: Velocity-loop over position-loop bandwidth: Kv = w_b / 4 (Ellis 2012: 3 to 5; the
#: default of :attr:`servotune.requirements.Requirements.bandwidth_ratio_min`).
KV_BANDWIDTH_RATIO = 4.0
#: Largest overshoot of the position loop's step response (1 % of the step: none to the eye on
#: a commissioning trace).
OVERSHOOT_MAX = 0.01
#: A resonance is notched only when it lies this many times above the velocity bandwidth
#: (a notch of width 0.2 and depth 0.1 then costs less than 4 deg of phase at the bandwidth).
NOTCH_BANDWIDTH_FACTOR = 3.0
#: Step of the commissioning searches: a (or 1/Kv) grows by sqrt 2 (3 dB of gain) until the
#: requirement holds, then the last step is halved until it is below 2 %.
_STEP = math.sqrt(2.0)
_RESOLUTION = 1.02
#: A resonance counts as sharp when its half-power width is below 20 % of its frequency
#: (damping ratio below 0.1).
_SHARP_WIDTH = 0.2


# ---------------------------------------------------------------------------- the rules
def current_small_time_constant(sampling: Sampling) -> float:
    """Return the current loop's sum of small time constants T_sigma_i [s].

    ``T_sigma_i = (d + 1/2) T``: the current is sampled at kT, the voltage computed from it is
    applied d periods later (computation delay) and held for one period (zero-order hold:
    on average half a period late). The model samples the current without an anti-aliasing or
    averaging filter, so nothing else lags (a drive that averages the current over a PWM period
    adds another T/2).

    Parameters
    ----------
    sampling : Sampling
        A digital drive's sampling (not the continuous one).

    Returns
    -------
    float
        T_sigma_i [s].

    Examples
    --------
    A SINAMICS-class drive, 125 us and one period of delay:

    >>> current_small_time_constant(Sampling()) * 1e6
    187.5
    """
    return (sampling.computation_delay + 0.5) * sampling.current_period


def velocity_small_time_constant(sampling: Sampling, t_sigma_current: float,
                                 lowpass: LowPassFilter | None = None) -> float:
    """Return the velocity loop's sum of small time constants T_sigma_v [s].

    ``T_sigma_v = 2 T_sigma_i + d T_v + T_v/2 + (T_v - T)/2 + tau_f + 2 zeta / w_lp``:

    * ``2 T_sigma_i``: the current loop set by the technical optimum,
      ``1 / (1 + 2 T_sigma_i s + 2 T_sigma_i^2 s^2)``, is to first order a lag 2 T_sigma_i
      (its equivalent time constant; Schroeder 2015, technical optimum);
    * ``d T_v``: the torque set-point is applied d velocity periods after the speed sample;
    * ``T_v/2``: the speed is the backward difference of the sampled rotor angle over one
      velocity period, the mean speed of that period, half a period old;
    * ``(T_v - T)/2``: the set-point held over a velocity period as the faster current
      controller samples it (0 when both run at one rate);
    * ``tau_f``: the speed filter; ``2 zeta / w_lp``: a current set-point low-pass (its
      equivalent time constant).

    Parameters
    ----------
    sampling : Sampling
        A digital drive's sampling.
    t_sigma_current : float
        T_sigma_i [s] of the current loop.
    lowpass : LowPassFilter, optional
        The current set-point low-pass, if the drive has one.

    Returns
    -------
    float
        T_sigma_v [s].

    Examples
    --------
    >>> s = Sampling()
    >>> round(velocity_small_time_constant(s, current_small_time_constant(s)) * 1e6, 6)
    562.5
    """
    t_v = sampling.velocity_period
    total = (2.0 * t_sigma_current + (sampling.computation_delay + 0.5) * t_v
             + 0.5 * (t_v - sampling.current_period) + sampling.speed_filter)
    if lowpass is not None:
        total += 2.0 * lowpass.damping_ratio / (2.0 * math.pi * lowpass.f_hz)
    return total


def technical_optimum(motor: Motor, t_sigma: float) -> PIController:
    """Return the current PI by the technical optimum (Betragsoptimum).

    The winding is ``1 / (R (1 + s L/R))``; the PI's zero cancels its pole, ``Ti = L/R``, and
    the loop ``Kp / (s L (1 + s T_sigma))`` gets the damping 1/sqrt 2 with ``Kp = L /
    (2 T_sigma)`` (crossover 1/(2 T_sigma), overshoot 4.3 %). The back-EMF is left out (the
    mechanical time constant is far longer than the electrical one).

    Parameters
    ----------
    motor : Motor
        Winding resistance R [ohm] and inductance L [H].
    t_sigma : float
        The current loop's small time constant [s] (:func:`current_small_time_constant`).

    Returns
    -------
    PIController
        Kp [V/A] and Ti [s].

    Examples
    --------
    L = 4 mH, R = 0.25 ohm, T_sigma = 187.5 us:

    >>> pi = technical_optimum(Motor(1.5, 1.5, 0.25, 4e-3), 187.5e-6)
    >>> round(pi.kp, 4), pi.ti
    (10.6667, 0.016)
    """
    return PIController(kp=motor.inductance / (2.0 * t_sigma),
                        ti=motor.inductance / motor.resistance)


def symmetric_optimum(inertia: float, t_sigma: float, a: float = SO_PARAMETER) -> PIController:
    """Return the velocity PI by the symmetric optimum on a rigid inertia.

    For the plant ``1 / (J s (1 + s T_sigma))`` the PI ``Kp (1 + 1/(Ti s))`` with
    ``Kp = J / (a T_sigma)`` and ``Ti = a^2 T_sigma`` puts the gain crossover
    ``w_c = 1/(a T_sigma)`` at the geometric mean of 1/Ti and 1/T_sigma, where the phase is
    highest: phase margin ``asin((a^2 - 1)/(a^2 + 1))`` (36.9 deg at a = 2, 53.1 deg at a = 3).

    Parameters
    ----------
    inertia : float
        J [kg m^2] at the motor.
    t_sigma : float
        The velocity loop's small time constant [s] (:func:`velocity_small_time_constant`).
    a : float
        The normalising parameter, > 1.

    Returns
    -------
    PIController
        Kp [N m s/rad] and Ti [s].

    Examples
    --------
    >>> pi = symmetric_optimum(0.04, 500e-6, a=2.0)
    >>> round(pi.kp, 6), round(pi.ti, 9)
    (40.0, 0.002)
    """
    if not a > 1.0:
        raise ValueError(f"the symmetric optimum needs a > 1, got {a!r}")
    return PIController(kp=inertia / (a * t_sigma), ti=a * a * t_sigma)


# ---------------------------------------------------------------------------- measurements
def _velocity_pi_at(drive: Drive, omega: np.ndarray) -> np.ndarray:
    """The velocity PI as the drive computes it, at frequencies omega."""
    s = drive.digital
    if s.is_continuous:
        pi = drive.velocity_loop
        return pi.kp * (1.0 + 1.0 / (pi.ti * 1j * omega))
    z = np.exp(1j * omega * s.velocity_period)
    return pi_response(drive.velocity_loop, z, s.velocity_period, s.integral_rule)


def speed_plant_response(model, drive: Drive, omega) -> np.ndarray:
    """Return the measured speed plant: torque set-point -> measured speed, at ``omega``.

    What a drive's speed-loop measurement gives: the velocity loop's response (position loop
    open, :meth:`SampledAxis.loop_response <servotune.digital.SampledAxis.loop_response>`)
    divided by the velocity PI, ``P = L_v / C_v``: the set-point filters, the closed current
    loop, the mechanics from motor torque to rotor speed, the speed measurement and the
    delays, exact at the velocity controller's samples.

    Parameters
    ----------
    model : SampledAxis or ContinuousAxis
        The controlled axis (:func:`servotune.closed_loop.closed_loop`) built with ``drive``.
    drive : Drive
        Its drive (for the velocity PI).
    omega : array_like
        Angular frequencies [rad/s], below the velocity loop's Nyquist frequency.

    Returns
    -------
    numpy.ndarray
        Complex [rad/s per N m], shape of ``omega``.
    """
    omega = np.asarray(omega, dtype=float)
    return model.loop_response("velocity", omega) / _velocity_pi_at(drive, omega)


@dataclass(frozen=True)
class _Resonance:
    omega: float
    magnitude: float
    amplification: float
    width: float


def _resonances(omega: np.ndarray, plant: np.ndarray, inertia: float) -> list[_Resonance]:
    """Local maxima of |P| with their amplification over the rigid line and relative
    half-power width (inf when |P| does not fall to 1/sqrt 2 of the peak on both sides before
    rising again)."""
    mag = np.abs(plant)
    out = []
    for i in range(1, mag.size - 1):
        if not (mag[i] > mag[i - 1] and mag[i] >= mag[i + 1]):
            continue
        m_pk, w_pk = peak(omega[i - 1:i + 2], plant[i - 1:i + 2])
        half = m_pk / math.sqrt(2.0)
        edges = []
        for step in (-1, 1):
            # walk down the flank while |P| falls; stop at the half-power level
            j = i
            while (0 <= j + step < mag.size and mag[j + step] <= mag[j]
                   and mag[j + step] > half):
                j += step
            k = j + step
            if not 0 <= k < mag.size or mag[k] > half:
                edges.append(None)  # the flank rises again (or ends) above half power
                continue
            f = (math.log(half) - math.log(mag[j])) / (math.log(mag[k]) - math.log(mag[j]))
            edges.append(float(omega[j] * (omega[k] / omega[j]) ** f))
        width = (math.inf if None in edges else (edges[1] - edges[0]) / w_pk)
        out.append(_Resonance(w_pk, m_pk, m_pk * w_pk * inertia, width))
    return out


def resonance_notch(omega, plant, inertia: float, above: float,
                    below: float) -> tuple[NotchFilter | None, str]:
    """Return the current set-point notch for the measured speed plant's sharpest resonance.

    Rules (Ellis 2012 on mechanical resonance and notch filters; the SINAMICS speed-loop
    measurement sets its current set-point filters from the same response):

    * candidates: local maxima of |P| between ``above`` and ``below`` that are *sharp*
      (half-power width under 20 % of the frequency, i.e. damping under 0.1) and stand above
      the rigid-body line ``1/(w J)`` (amplification ``A = |P| w J > 1``: there the loop gain
      exceeds what the rigid design expects);
    * the one with the largest A is notched: frequency at its peak; width (the notch's relative
      -3 dB width) twice the resonance's half-power width, at least 0.2, so that the notch still
      covers the resonance when it moves by +-10 % with the slide position, the load or the
      friction regime; depth = the ratio of |P| at the notch's band edges (geometric mean) to
      the peak, between 0.05 and 0.5: the notch takes off the resonance's rise and no more.

    Parameters
    ----------
    omega : array_like
        The measurement's frequencies [rad/s], increasing, dense (0.3 % steps or finer).
    plant : array_like
        The measured speed plant at ``omega`` (:func:`speed_plant_response`).
    inertia : float
        J [kg m^2] at the motor (the rigid-body line).
    above, below : float
        The band [rad/s] in which resonances are notched.

    Returns
    -------
    (NotchFilter or None, str)
        The notch (None when no resonance qualifies) and a line saying what was found.
    """
    omega = np.asarray(omega, dtype=float)
    plant = np.asarray(plant, dtype=complex)
    found = [r for r in _resonances(omega, plant, inertia) if above < r.omega < below]
    sharp = [r for r in found if r.width < _SHARP_WIDTH and r.amplification > 1.0]
    listed = ", ".join(f"{r.omega * HZ_PER_RAD_S:.1f} Hz (A = {r.amplification:.3g}, "
                       f"width {r.width:.3g})" for r in found) or "none"
    band = f"{above * HZ_PER_RAD_S:.1f}-{below * HZ_PER_RAD_S:.0f} Hz"
    if not sharp:
        return None, f"resonances of the speed plant in {band}: {listed}; none sharp: no notch"
    best = max(sharp, key=lambda r: r.amplification)
    width = min(max(2.0 * best.width, 0.2), 1.0)
    lo, hi = best.omega * (1 - width / 2), best.omega * (1 + width / 2)
    edge = np.exp(np.interp(np.log([lo, hi]), np.log(omega), np.log(np.abs(plant))))
    depth = min(max(float(np.sqrt(edge[0] * edge[1])) / best.magnitude, 0.05), 0.5)
    notch = NotchFilter(best.omega * HZ_PER_RAD_S, width=width, depth=depth)
    return notch, (f"resonances of the speed plant in {band}: {listed}; notch on the sharpest "
                   f"above the rigid line: {notch.f_hz:.1f} Hz, width {width:.3g} (2 x its "
                   f"half-power width, >= 0.2), depth {depth:.3g} (band edges / peak)")


def position_step_overshoot(model, n: int = 4097, duration: float | None = None) -> float:
    """Return the overshoot of the position loop's step response (fraction of the step).

    The closed position loop ``T = L_p / (1 + L_p)`` (velocity loop closed) from a position
    step to the measured position. For a digital drive, exact at the position controller's
    samples: the impulse response is the inverse DFT of T on n points of the unit circle at the
    position rate (the response over n T_p, wrapped: n T_p must exceed its settling time). For
    a continuous drive, the step response of the python-control closed loop over
    ``duration``.

    Parameters
    ----------
    model : SampledAxis or ContinuousAxis
        The controlled axis, stable.
    n : int
        DFT length (odd; 4097 position periods = 4.1 s at 1 ms).
    duration : float, optional
        Length [s] of the continuous step response (default 4 s).

    Returns
    -------
    float
        ``max(y) - 1`` (0 when the response never exceeds the step).
    """
    if hasattr(model, "position_period"):
        tp = model.position_period
        k = np.arange(1, (n - 1) // 2 + 1)
        lp = model.loop_response("position", 2 * math.pi * k / (n * tp))
        half = lp / (1.0 + lp)
        spectrum = np.concatenate([[1.0], half, np.conj(half[::-1])])
        y = np.cumsum(np.fft.ifft(spectrum).real)
    else:
        import control

        from .plant import loop_transfer

        loop = loop_transfer(model.structure, model.drive, model.contact, model.pads,
                             "position")
        t = np.linspace(0.0, duration or 4.0, 20001)
        y = control.step_response(control.feedback(loop, 1.0), T=t).outputs.reshape(-1)
    return max(float(np.max(y)) - 1.0, 0.0)


# ---------------------------------------------------------------------------- the result
@dataclass(frozen=True)
class BaselineDesign:
    """A baseline design: the drive a rule set gives, the guide ways' own damping, and how.

    Attributes
    ----------
    rule : str
        ``"commissioning"`` or ``"textbook"``.
    drive : Drive
        The drive with the rule's current PI, velocity PI, Kv and set-point filters.
    c : float
        Guide-way damping C [N s/m] (axis total): the guide ways' own.
    steps : tuple of str
        What each rule gave, with its numbers, in order.
    measured_in : str
        The regime model the loops were measured in.
    velocity, position : LoopAnalysis or None
        The loops measured there (None: unstable).
    position_overshoot : float or None
        Overshoot of the position step response [-] (None: not measured).
    inertia : float
        J [kg m^2]: the moving mass referred to the motor.
    """

    rule: str
    drive: Drive
    c: float
    steps: tuple[str, ...]
    measured_in: str
    velocity: LoopAnalysis | None
    position: LoopAnalysis | None
    position_overshoot: float | None
    inertia: float

    def __post_init__(self) -> None:
        if self.rule not in ("commissioning", "textbook"):
            raise ValueError(f"BaselineDesign.rule must be 'commissioning' or 'textbook', got "
                             f"{self.rule!r}")
        if not isinstance(self.drive, Drive):
            raise ValueError("BaselineDesign.drive must be a Drive")
        object.__setattr__(self, "c", positive("BaselineDesign", "c", self.c, "N s/m",
                                               allow_zero=True))
        object.__setattr__(self, "inertia", positive("BaselineDesign", "inertia",
                                                     self.inertia, "kg m^2"))
        object.__setattr__(self, "steps", tuple(str(s) for s in self.steps))

    def design(self):
        """Return the design variables as a :class:`servotune.tuning.Design` (C, Kv, Kp, Ti).

        Returns
        -------
        servotune.tuning.Design
        """
        from .tuning import Design

        return Design(c=self.c, kv=self.drive.kv, kp=self.drive.velocity_loop.kp,
                      ti=self.drive.velocity_loop.ti)

    def to_dict(self) -> dict:
        """Return the design JSON-ready (SI; the loops as :meth:`LoopAnalysis.to_dict`).

        Returns
        -------
        dict
            ``rule``, ``c``, ``kv`` [1/s] (and ``kv_m_per_min_per_mm``), ``velocity_kp``,
            ``velocity_ti``, ``current_kp``, ``current_ti``, ``notch`` and ``lowpass``
            (``f_hz``, ...) or None, ``inertia``, ``measured_in``, ``velocity_loop``,
            ``position_loop``, ``position_overshoot``, ``steps``.
        """
        d = self.drive
        return {
            "rule": self.rule, "c": self.c, "kv": d.kv,
            "kv_m_per_min_per_mm": kv_to_m_per_min_per_mm(d.kv),
            "velocity_kp": d.velocity_loop.kp, "velocity_ti": d.velocity_loop.ti,
            "current_kp": d.current_loop.kp, "current_ti": d.current_loop.ti,
            "notches": [dataclasses.asdict(n) for n in d.notches],
            "lowpass": None if d.lowpass is None else dataclasses.asdict(d.lowpass),
            "inertia": self.inertia, "measured_in": self.measured_in,
            "velocity_loop": None if self.velocity is None else self.velocity.to_dict(),
            "position_loop": None if self.position is None else self.position.to_dict(),
            "position_overshoot": self.position_overshoot,
            "steps": list(self.steps),
        }


# ---------------------------------------------------------------------------- the procedure
@dataclass(frozen=True)
class _Setting:
    """Where the loops are measured: structure, pads, the regime's contact at C, the limits."""

    structure: ModalModel
    pads: tuple
    contact: Contact | None
    measured_in: str
    c: float
    ms_velocity: float
    ms_position: float


def _setting(axis: Axis, structure, pads, regime) -> _Setting:
    structure = axis.structure if structure is None else structure
    pads = tuple(axis.pads if pads is None and axis.friction is not None else (pads or ()))
    c = float(axis.friction.viscous) if axis.friction is not None else 0.0
    if regime is None and pads:
        from .regimes import axis_regimes

        models = axis_regimes(axis, c)
        sliding = [m for m in models if m.kind == "sliding" and m.sample == "nominal"]
        regime = (min(sliding, key=lambda m: m.speed) if sliding else
                  next((m for m in models if m.kind == "viscous"), models[0]))
    contact = regime.contact(c) if regime is not None and pads else None
    name = regime.name if contact is not None else "no guide-way contact"
    req = axis.requirements
    return _Setting(structure, pads, contact, name, c, req.ms_limit("velocity"),
                    req.ms_limit("position"))


def _model(setting: _Setting, drive: Drive):
    return closed_loop(setting.structure, drive, setting.contact, setting.pads)


def _analysis(model, loop: str) -> LoopAnalysis | None:
    try:
        return model.analyse_loop(loop)
    except UnstableLoopError:
        return None


def _fmt_pi(pi: PIController) -> str:
    return f"Kp = {pi.kp:.4g} N m s/rad, Ti = {pi.ti * 1e3:.4g} ms"


def _verdict(an: LoopAnalysis | None, limit: float, what: str) -> tuple[bool, str]:
    if an is None:
        return False, f"{what} unstable"
    ok = an.ms <= limit
    return ok, (f"{what} Ms = {an.ms:.3f} {'<=' if ok else '>'} {limit:.3f}, PM "
                f"{an.phase_margin_deg:.1f} deg, bandwidth {an.bandwidth_hz:.1f} Hz")


def _search(start: float, evaluate):
    """Smallest x >= start (within 2 %) with evaluate(x)[0] true: x grows by sqrt 2 until it
    holds, then the last bracket is halved in log x. Returns (x, result, log lines)."""
    x, lines, lower = start, [], None
    ok, result, line = evaluate(x)
    lines.append(line)
    while not ok:
        if x > start * 1e4:
            raise ValueError("the commissioning search found no setting that meets the "
                             "requirements (gain lowered by 1e4); " + line)
        lower, x = x, x * _STEP
        ok, result, line = evaluate(x)
        lines.append(line)
    upper, best = x, result
    while lower is not None and upper / lower > _RESOLUTION:
        mid = math.sqrt(lower * upper)
        ok, result, line = evaluate(mid)
        lines.append(line)
        if ok:
            upper, best = mid, result
        else:
            lower = mid
    return upper, best, lines


def _current_stage(drive: Drive, rules: Sampling, steps: list) -> tuple[Drive, float]:
    """Rule 1: the technical optimum; the drive with it (no notch) and T_sigma_i."""
    ts_i = current_small_time_constant(rules)
    current = technical_optimum(drive.motor, ts_i)
    base = dataclasses.replace(drive, current_loop=current, notches=())
    m = drive.motor
    steps.append(
        f"current loop, technical optimum: T_sigma_i = (d + 1/2) T = ({rules.computation_delay}"
        f" + 0.5) x {rules.current_period * 1e6:.4g} us = {ts_i * 1e6:.4g} us; Ti = L/R = "
        f"{m.inductance * 1e3:.4g} mH / {m.resistance:.4g} ohm = {current.ti * 1e3:.4g} ms; "
        f"Kp = L/(2 T_sigma_i) = {current.kp:.4g} V/A (closed-loop bandwidth "
        f"{current_loop_bandwidth(base) * HZ_PER_RAD_S:.0f} Hz)")
    return base, ts_i


def _velocity_stage(setting: _Setting, base: Drive, inertia: float, ts_v: float, a: float,
                    steps: list) -> tuple[Drive, LoopAnalysis]:
    """Rule 2: the symmetric optimum, a raised until Ms holds; a notch if it lets Kp rise."""
    so = symmetric_optimum(inertia, ts_v, a)
    steps.append(f"velocity loop, symmetric optimum a = {a:g}: Kp = J/(a T_sigma_v), Ti = a^2 "
                 f"T_sigma_v: {_fmt_pi(so)}")
    steps.append(f"measured in '{setting.measured_in}' with C = {setting.c:.5g} N s/m; "
                 f"velocity-loop Ms limit {setting.ms_velocity:.3f}")

    def search(notch):
        def evaluate(x):
            pi = symmetric_optimum(inertia, ts_v, x)
            trial = dataclasses.replace(base, velocity_loop=pi,
                                        notches=() if notch is None else (notch,))
            an = _analysis(_model(setting, trial), "velocity")
            ok, text = _verdict(an, setting.ms_velocity, "velocity loop")
            return ok, (trial, an), f"  a = {x:.4g}: {_fmt_pi(pi)}: {text}"
        x, best, lines = _search(a, evaluate)
        steps.extend(lines)
        return x, best

    a1, (drive1, an1) = search(None)
    steps.append(f"velocity loop without a notch: a = {a1:.4g}, {_fmt_pi(drive1.velocity_loop)}, "
                 f"bandwidth {an1.bandwidth_hz:.1f} Hz")
    model = _model(setting, drive1)
    top = min(model.nyquist("velocity"), 2 * math.pi * 5000.0)
    omega = 2 * math.pi * np.geomspace(1.0, 0.999 * top * HZ_PER_RAD_S, 3000)
    notch, text = resonance_notch(omega, speed_plant_response(model, drive1, omega), inertia,
                                  NOTCH_BANDWIDTH_FACTOR * an1.bandwidth, 0.8 * top)
    steps.append(text)
    if notch is None:
        return drive1, an1
    a2, (drive2, an2) = search(notch)
    if a2 >= a1:
        steps.append(f"with the notch a = {a2:.4g} >= {a1:.4g}: Kp cannot rise, notch removed")
        return drive1, an1
    steps.append(f"with the notch: a = {a2:.4g}, {_fmt_pi(drive2.velocity_loop)} (Kp x "
                 f"{a1 / a2:.3g}), bandwidth {an2.bandwidth_hz:.1f} Hz: notch kept")
    return drive2, an2


def _position_stage(setting: _Setting, drive: Drive, velocity: LoopAnalysis, kv_ratio: float,
                    ratio_min: float, overshoot_max: float, steps: list):
    """Rule 3: Kv = w_b / kv_ratio, lowered until Ms, overshoot and hierarchy hold."""
    kv0 = velocity.bandwidth / kv_ratio
    bw_max = velocity.bandwidth / ratio_min if ratio_min else math.inf
    steps.append(f"position loop: Kv = w_b,v / {kv_ratio:g} = {velocity.bandwidth:.4g} / "
                 f"{kv_ratio:g} = {kv0:.4g} 1/s; Ms limit {setting.ms_position:.3f}, overshoot "
                 f"at most {overshoot_max:.1%}, closed-loop bandwidth at most w_b,v / "
                 f"{ratio_min:g} = {bw_max * HZ_PER_RAD_S:.3g} Hz")

    def evaluate(x):
        trial = dataclasses.replace(drive, kv=kv0 / x)
        model = _model(setting, trial)
        an = _analysis(model, "position")
        if an is None:
            return False, (trial, None, None), f"  Kv = {trial.kv:.4g} 1/s: position loop unstable"
        over = position_step_overshoot(model)
        ok_ms, text = _verdict(an, setting.ms_position, "position loop")
        ok_bw = an.bandwidth <= bw_max
        return (ok_ms and ok_bw and over <= overshoot_max, (trial, an, over),
                f"  Kv = {trial.kv:.4g} 1/s: {text} ({'<=' if ok_bw else '>'} "
                f"{bw_max * HZ_PER_RAD_S:.3g} Hz), overshoot {over:.2%}")

    _, result, lines = _search(1.0, evaluate)
    steps.extend(lines)
    return result


def commissioning_design(axis: Axis, drive: Drive | None = None,
                         structure: ModalModel | None = None, pads=None, *, regime=None,
                         a: float = SO_PARAMETER, kv_ratio: float = KV_BANDWIDTH_RATIO,
                         overshoot_max: float = OVERSHOOT_MAX) -> BaselineDesign:
    """Return the design a commissioning engineer or a drive's auto-tuner would produce.

    The rules of the module docstring, in order: the current PI by the technical optimum; the
    velocity PI by the symmetric optimum on the rigid inertia, measured on the model and made
    robust (a raised until the velocity loop's Ms meets the limit; one notch on the speed
    plant's sharpest resonance above three times the velocity bandwidth, kept when it lets Kp
    rise); Kv from the velocity bandwidth, lowered until the position loop meets its Ms limit,
    the hierarchy and no overshoot; the guide ways' own damping. Every rule is evaluated on the
    sampled-data model when the drive is digital, on the continuous one otherwise
    (:func:`servotune.closed_loop.closed_loop`).

    Parameters
    ----------
    axis : Axis
        The axis: its requirements (Ms limits, bandwidth ratio), friction (C, regime models)
        and, unless given, its drive, structure and pads.
    drive : Drive, optional
        The drive whose motor, transmission, sampling, feedback, feed-forwards and low-pass are
        kept (default ``axis.drive``); its gains and notch are replaced.
    structure : ModalModel, optional
        The structure (default ``axis.structure``).
    pads : sequence of str, optional
        The pad DOFs (default ``axis.pads``).
    regime : RegimeModel, optional
        The model the loops are measured in (default: the sliding model of the nominal friction
        at the lowest feed speed of :func:`servotune.regimes.axis_regimes`; the viscous pads
        when the axis has no feed speeds).
    a : float
        The symmetric optimum's parameter to start from (2, the classic choice).
    kv_ratio : float
        Velocity bandwidth over Kv to start from (4).
    overshoot_max : float
        Largest overshoot of the position step response (0.01).

    Returns
    -------
    BaselineDesign
        The drive, C and the steps with their numbers.

    Raises
    ------
    AxisFormatError
        The axis has no drive and none is given.
    ValueError
        No setting meets the requirements (a gain lowered by 1e4 without success).

    Notes
    -----
    A continuous drive model has no small time constants of its own; the rules then count
    those of a current industrial drive (:class:`~servotune.drive.Sampling` defaults: 125 us
    current and speed periods, one period of computation delay), the drive the engineer
    commissions, and the loops are evaluated on the continuous model.
    """
    drive = axis.require_drive() if drive is None else drive
    setting = _setting(axis, structure, pads, regime)
    steps = []
    rules = drive.sampling if not drive.digital.is_continuous else Sampling()
    if drive.digital.is_continuous:
        steps.append("the drive model is continuous: the rules count the small time constants "
                     "of a current industrial drive (125 us current and speed periods, one "
                     "period of computation delay)")
    base, ts_i = _current_stage(drive, rules, steps)
    mass = moving_mass(setting.structure, setting.pads or [drive.encoder])
    inertia = mass * drive.ratio ** 2
    ts_v = velocity_small_time_constant(rules, ts_i, drive.lowpass)
    steps.append(f"inertia at the motor: moving mass {mass:.5g} kg x r^2 (r = "
                 f"{drive.ratio:.5g} m/rad) = {inertia:.4g} kg m^2")
    steps.append(
        f"velocity loop small time constant: 2 T_sigma_i + (d + 1/2) T_v + (T_v - T)/2 + "
        f"speed filter{' + low-pass' if drive.lowpass else ''} = {ts_v * 1e6:.4g} us")
    tuned, velocity = _velocity_stage(setting, base, inertia, ts_v, a, steps)
    final, position, over = _position_stage(setting, tuned, velocity, kv_ratio,
                                            axis.requirements.bandwidth_ratio_min,
                                            overshoot_max, steps)
    steps.append(f"result: Kv = {final.kv:.4g} 1/s ({kv_to_m_per_min_per_mm(final.kv):.3g} "
                 f"(m/min)/mm), {_fmt_pi(final.velocity_loop)}, notch "
                 + (", ".join(f"{n.f_hz:.1f} Hz" for n in final.notches) or "none")
                 + f"; C = {setting.c:.5g} N s/m (the guide ways' own)")
    if final.kv < axis.requirements.kv_min:
        steps.append(f"note: Kv = {final.kv:.4g} 1/s is below the required kv_min = "
                     f"{axis.requirements.kv_min:.4g} 1/s")
    return BaselineDesign("commissioning", final, setting.c, tuple(steps), setting.measured_in,
                          velocity, position, over, inertia)


def textbook_design(axis: Axis, drive: Drive | None = None, structure: ModalModel | None = None,
                    pads=None, *, regime=None) -> BaselineDesign:
    """Return the independent textbook design: Kp = J 2 pi 25 Hz, Ti = 25 ms, Kv = 25 1/s.

    The hand rule the project has compared against: a velocity loop of 25 Hz on the rigid
    inertia at the motor (J = moving mass x r^2, :func:`servotune.thrust.moving_mass`), an
    integral time of 25 ms, and Kv = 25 1/s (1.5 (m/min)/mm, a usual value for a machine-tool
    axis); nothing measured, no filters added; the current loop, the other drive data and the
    guide ways (C = ``[friction] viscous``) as the axis has them. The loops are then measured
    as :func:`commissioning_design` measures them (they may fail the requirements: the rule
    does not look).

    Parameters
    ----------
    axis : Axis
        The axis.
    drive, structure, pads, regime : optional
        As :func:`commissioning_design`.

    Returns
    -------
    BaselineDesign
    """
    drive = axis.require_drive() if drive is None else drive
    setting = _setting(axis, structure, pads, regime)
    mass = moving_mass(setting.structure, setting.pads or [drive.encoder])
    inertia = mass * drive.ratio ** 2
    pi = PIController(kp=inertia * 2 * math.pi * 25.0, ti=25e-3)
    final = dataclasses.replace(drive, velocity_loop=pi, kv=25.0)
    steps = [f"J = moving mass {mass:.5g} kg x r^2 = {inertia:.4g} kg m^2",
             f"Kp = J x 2 pi x 25 Hz = {pi.kp:.4g} N m s/rad, Ti = 25 ms, Kv = 25 1/s",
             f"C = {setting.c:.5g} N s/m (the guide ways' own)"]
    model = _model(setting, final)
    an_v, an_p = _analysis(model, "velocity"), _analysis(model, "position")
    over = None if an_p is None else position_step_overshoot(model)
    for an, limit, what in ((an_v, setting.ms_velocity, "velocity loop"),
                            (an_p, setting.ms_position, "position loop")):
        steps.append(f"measured in '{setting.measured_in}': {_verdict(an, limit, what)[1]}")
    return BaselineDesign("textbook", final, setting.c, tuple(steps), setting.measured_in,
                          an_v, an_p, over, inertia)


def compliance_peaks(axis: Axis, design: BaselineDesign, omega=None) -> tuple[dict, ...]:
    """Return the work-piece compliance peak of a baseline in each regime model of the axis.

    Each model of :func:`servotune.regimes.axis_regimes` with its contact at the design's C
    (``model.contact(C)``), the design's drive, the closed loop of
    :func:`servotune.closed_loop.closed_loop` (sampled-data for a digital drive).

    Parameters
    ----------
    axis : Axis
        The axis.
    design : BaselineDesign
        The design.
    omega : array_like, optional
        Frequencies [rad/s] (default 600 log-spaced points over the requirements' band).

    Returns
    -------
    tuple of dict
        Per model: ``model`` (its name), ``stable``, ``peak`` [m/N] and ``frequency_hz``
        (None when unstable).
    """
    from .regimes import axis_regimes

    band = axis.requirements.band
    omega = np.geomspace(*band, 600) if omega is None else np.asarray(omega, dtype=float)
    out = []
    for model in axis_regimes(axis, design.c):
        cl = closed_loop(axis.structure, design.drive, model.contact(design.c), axis.pads)
        row = {"model": model.name, "stable": bool(cl.is_stable()), "peak": None,
               "frequency_hz": None}
        if row["stable"]:
            h, w = peak(omega, cl.compliance(omega)[0])
            row.update(peak=h, frequency_hz=w * HZ_PER_RAD_S)
        out.append(row)
    return tuple(out)
