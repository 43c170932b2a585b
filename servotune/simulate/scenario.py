"""Scenarios of the time simulation: references of the position loop and forces at the work piece.

A :class:`Scenario` gives, as vectorised functions of time, the position reference with its
velocity and acceleration (``x_ref``, ``v_ref``, ``a_ref``; the last two feed the drive's
feed-forwards) and the forces at the work-piece DOFs. Constructors cover the paper's trials:

* :func:`sine_sweep`: a force at the work piece swept linearly in frequency (Table 3: 10 -> 100 Hz
  in 20 s, amplitude given peak to peak), standing still or with the axis moving at constant
  speed (the paper's "imposed motion speed": a position ramp with velocity feed-forward);
* :func:`constant_speed`, :func:`point_to_point` (moves and reversals), :func:`sinusoid` and
  :func:`circle` (Fig 2, Fig 8: a 10 um sinusoid of 3.7 s period; circles of 20 and 5 um
  radius, whose X component the axis follows);
* :func:`custom`: any user-given reference and force functions.

Motions start from rest: a constant speed is reached by a smooth start (velocity
``V (3 s^2 - 2 s^3)``, s = t/t_start), so that the reference has no velocity step.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..validation import finite, positive

__all__ = ["Scenario", "sine_sweep", "constant_speed", "point_to_point", "sinusoid", "circle",
           "custom", "sweep_phase", "sweep_frequency", "SweepPlan", "sweep_plan",
           "planned_sweep"]

DEFAULT_START = 0.2   # [s] smooth start to a constant speed


def _zero(t):
    return np.zeros_like(np.asarray(t, dtype=float))


@dataclass(frozen=True, eq=False)
class Scenario:
    """Reference and force histories for :func:`servotune.simulate.simulate` (SI).

    Parameters
    ----------
    duration : float
        End time [s] (the simulation starts at rest at t = 0).
    motion : callable, optional
        ``motion(t) -> (x_ref, v_ref, a_ref)`` arrays [m, m/s, m/s^2]; None: hold at 0.
    forces : dict, optional
        ``{dof: force(t)}`` [N] at work-piece DOFs (``"wp.x"``, ``"wp.y"``, ``"wp.z"``).
    speed : float
        Nominal sliding speed [m/s] of the guide ways, about which the friction law is
        linearised (0 standing still). Only the split of the law changes, not the model.
    name : str
        A label for reports.
    sweep : tuple or SweepPlan, optional
        ``(f_start_hz, f_end_hz, t_start, t_end, amplitude)`` of a linear sine sweep of the
        force, or the :class:`SweepPlan` of a variable-rate one, which
        :meth:`SimulationResult.sweep_envelope` uses.

    Raises
    ------
    ValueError
        If the duration is not finite and > 0, the speed is not finite, or a force or the
        motion is not callable.
    """

    duration: float
    motion: Callable | None = None
    forces: dict = field(default_factory=dict)
    speed: float = 0.0
    name: str = "custom"
    sweep: tuple | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "duration", positive("Scenario", "duration", self.duration, "s"))
        object.__setattr__(self, "speed", finite("Scenario", "speed", self.speed, "m/s"))
        forces = dict(self.forces)
        for dof, fun in forces.items():
            if not callable(fun):
                raise ValueError(f"the force at {dof!r} must be a function of time t [s] -> N")
        object.__setattr__(self, "forces", forces)
        if self.motion is not None and not callable(self.motion):
            raise ValueError("motion must be a function t -> (x_ref, v_ref, a_ref)")

    def signals(self, t) -> dict[str, np.ndarray]:
        """Return the input signals on the times t, keyed by plant input name.

        Parameters
        ----------
        t : array_like
            Times [s].

        Returns
        -------
        dict of str to numpy.ndarray
            ``x_ref`` [m], ``v_ref`` [m/s], ``a_ref`` [m/s^2] (each left out when zero at every
            time) and ``f_<dof>`` [N] per force (``f_wp_x`` for ``"wp.x"``), on the shape of
            ``t``.

        Raises
        ------
        ValueError
            If a signal is not finite.
        """
        t = np.asarray(t, dtype=float)
        out = {}
        if self.motion is not None:
            x, v, a = (np.broadcast_to(np.asarray(s, dtype=float), t.shape)
                       for s in self.motion(t))
            for name, s in (("x_ref", x), ("v_ref", v), ("a_ref", a)):
                if np.any(s != 0.0):
                    out[name] = s
        for dof, fun in self.forces.items():
            s = np.broadcast_to(np.asarray(fun(t), dtype=float), t.shape)
            out["f_" + dof.replace(".", "_")] = s
        for name, s in out.items():
            if not np.all(np.isfinite(s)):
                raise ValueError(f"the scenario's {name} is not finite on [0, {self.duration}] s")
        return out


def sweep_phase(t, f_start_hz: float, f_end_hz: float, duration: float):
    """Return the phase of a linear sweep, 2 pi (f0 t + (f1 - f0) t^2 / (2 T)).

    Parameters
    ----------
    t : array_like
        Times [s] from the start of the sweep.
    f_start_hz, f_end_hz : float
        Start and end frequency f0, f1 [Hz].
    duration : float
        Sweep time T [s].

    Returns
    -------
    numpy.ndarray
        Phase [rad], the shape of ``t``.
    """
    t = np.asarray(t, dtype=float)
    return 2.0 * math.pi * (f_start_hz * t + 0.5 * (f_end_hz - f_start_hz) * t * t / duration)


def sweep_frequency(t, f_start_hz: float, f_end_hz: float, duration: float):
    """Return the instantaneous frequency of a linear sweep, f0 + (f1 - f0) t / T.

    Parameters
    ----------
    t : array_like
        Times [s] from the start of the sweep.
    f_start_hz, f_end_hz : float
        Start and end frequency f0, f1 [Hz].
    duration : float
        Sweep time T [s].

    Returns
    -------
    numpy.ndarray
        Frequency [Hz], the shape of ``t``.
    """
    return f_start_hz + (f_end_hz - f_start_hz) * np.asarray(t, dtype=float) / duration


def _smooth_start(speed: float, t_start: float):
    """Motion at constant speed reached smoothly: v = V (3 s^2 - 2 s^3) for s = t/t_start < 1."""

    def motion(t):
        t = np.asarray(t, dtype=float)
        if t_start == 0.0:
            return speed * t, np.full_like(t, speed), np.zeros_like(t)
        s = np.clip(t / t_start, 0.0, 1.0)
        v = speed * (3 * s**2 - 2 * s**3)
        a = speed * (6 * s - 6 * s**2) / t_start
        x = np.where(t < t_start, speed * t_start * (s**3 - 0.5 * s**4),
                     speed * (t - 0.5 * t_start))
        return x, v, a

    return motion


def sine_sweep(force_pp: float, f_start_hz: float = 10.0, f_end_hz: float = 100.0,
               duration: float = 20.0, speed: float = 0.0, dof: str = "wp.x",
               start: float = DEFAULT_START) -> Scenario:
    """Return a sine-sweep force at the work piece, standing still or moving (Table 3).

    Parameters
    ----------
    force_pp : float
        Force amplitude peak to peak [N] (the paper's 50 ... 2000 N).
    f_start_hz, f_end_hz : float
        Start and end frequency of the linear sweep [Hz] (default 10 and 100).
    duration : float
        Sweep time [s] (default 20).
    speed : float
        Constant axis speed [m/s] during the sweep (0: standing still; the paper's 30 mm/s is
        0.03), reached by a smooth start over ``start`` seconds.
    dof : str
        Work-piece DOF of the force.
    start : float
        Duration [s] of the smooth start to ``speed``.

    Returns
    -------
    Scenario
        The force ``(force_pp / 2) sin(sweep_phase(t))`` (:func:`sweep_phase`) from t = 0 to
        ``duration``, with the sweep recorded for the envelope.

    Raises
    ------
    ValueError
        If the force, a frequency or the duration is not finite and > 0, or ``start`` is
        negative.

    Examples
    --------
    >>> sc = sine_sweep(100.0)
    >>> float(np.max(sc.forces["wp.x"](np.linspace(0, 20, 200001))))   # amplitude = pp / 2
    50.0
    """
    force_pp = positive("sine_sweep:", "force_pp", force_pp, "N")
    f_start_hz = positive("sine_sweep:", "f_start_hz", f_start_hz, "Hz")
    f_end_hz = positive("sine_sweep:", "f_end_hz", f_end_hz, "Hz")
    duration = positive("sine_sweep:", "duration", duration, "s")
    amplitude = 0.5 * force_pp

    def force(t):
        return amplitude * np.sin(sweep_phase(t, f_start_hz, f_end_hz, duration))

    motion = (_smooth_start(float(speed), positive("sine_sweep:", "start", start, "s",
                                                   allow_zero=True)) if speed else None)
    label = (f"sine sweep {f_start_hz:g}-{f_end_hz:g} Hz in {duration:g} s, {force_pp:g} N "
             f"p-p, {speed * 1e3:g} mm/s")
    return Scenario(duration=duration, motion=motion, forces={dof: force}, speed=float(speed),
                    name=label, sweep=(f_start_hz, f_end_hz, 0.0, duration, amplitude))


@dataclass(frozen=True, eq=False)
class SweepPlan:
    """A sine sweep with a rate that varies with frequency, as a phase table.

    ``phase`` [rad] on the times ``t`` [s] from 0 to ``duration``; the instantaneous frequency
    is ``frequency_hz``. :meth:`servotune.simulate.SimulationResult.sweep_envelope` reads the
    cycle boundaries (phase = 2 pi k) from it.

    Parameters
    ----------
    t : numpy.ndarray
        Times [s] of the table, increasing.
    phase : numpy.ndarray
        Phase [rad] at ``t``.
    frequency_hz : numpy.ndarray
        Instantaneous frequency [Hz] at ``t``.
    amplitude : float
        Force amplitude [N] (half the peak to peak).
    slow : tuple of (float, float)
        The ``(f_low_hz, f_high_hz)`` windows swept slowly.
    """

    t: np.ndarray
    phase: np.ndarray
    frequency_hz: np.ndarray
    amplitude: float
    slow: tuple = ()   # the (f_low_hz, f_high_hz) windows swept slowly

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    @property
    def f_start_hz(self) -> float:
        return float(self.frequency_hz[0])

    @property
    def f_end_hz(self) -> float:
        return float(self.frequency_hz[-1])

    def phase_at(self, t) -> np.ndarray:
        """Return the phase at times t, interpolated linearly in the table.

        Parameters
        ----------
        t : array_like
            Times [s]; outside the table the end values hold.

        Returns
        -------
        numpy.ndarray
            Phase [rad].
        """
        return np.interp(np.asarray(t, dtype=float), self.t, self.phase)

    def frequency_at(self, t) -> np.ndarray:
        """Return the instantaneous frequency at times t, interpolated linearly in the table.

        Parameters
        ----------
        t : array_like
            Times [s]; outside the table the end values hold.

        Returns
        -------
        numpy.ndarray
            Frequency [Hz].
        """
        return np.interp(np.asarray(t, dtype=float), self.t, self.frequency_hz)

    def cycle_times(self, t_end: float) -> np.ndarray:
        """Return the times where the phase passes 2 pi k, up to ``t_end``.

        Parameters
        ----------
        t_end : float
            Last time [s].

        Returns
        -------
        numpy.ndarray
            The cycle boundaries [s], k = 0, 1, ... (the first is the table's start).
        """
        end = float(np.interp(t_end, self.t, self.phase))
        k = np.arange(0, math.floor(end / (2 * math.pi)) + 1)
        return np.interp(2 * math.pi * k, self.phase, self.t)

    def in_slow_window(self, f_hz: float) -> bool:
        """Return whether a frequency lies in one of the slowly swept windows.

        Parameters
        ----------
        f_hz : float
            Frequency [Hz].

        Returns
        -------
        bool
            True when ``f_low_hz <= f_hz <= f_high_hz`` for a window of ``slow``.
        """
        return any(lo <= f_hz <= hi for lo, hi in self.slow)


def sweep_plan(f_start_hz: float, f_end_hz: float, amplitude: float, resonances=(),
               base_damping: float = 0.1, time_constants: float = 4.0,
               window: float = 0.15, step: float = 5e-5) -> SweepPlan:
    """Return a sweep that passes every resonance slowly enough to show its steady-state peak.

    A resonance of frequency f and damping ratio zeta has a half-power band 2 zeta f and a
    time constant 1/(2 pi zeta f); a sweep shows its steady amplitude when it takes several
    time constants to cross that band, i.e. at a rate ``df/dt <= 4 pi zeta^2 f^2 / N``
    (N = ``time_constants``). The rate is set so everywhere for ``base_damping`` (any
    resonance at least that damped is shown right), and within ``window + 3 zeta`` (relative)
    of each expected resonance ``(f_hz, zeta)`` for its own damping when that is slower. The
    rate is laid out on 4000 log-spaced frequencies; the time to each follows from
    ``dt = df / rate`` (trapezoidal rule) and the phase from ``2 pi int f dt``.

    Parameters
    ----------
    f_start_hz, f_end_hz : float
        Start and end frequency [Hz], 0 < start < end.
    amplitude : float
        Force amplitude [N] (half the peak to peak).
    resonances : sequence of (float, float)
        Expected resonances ``(frequency [Hz], damping ratio)``; those with a value not
        finite and > 0 are skipped.
    base_damping : float
        Damping ratio the rate is set for everywhere.
    time_constants : float
        Number N of time constants spent crossing a half-power band.
    window : float
        Relative half-width of the slow window about a resonance, before the ``3 zeta``.
    step : float
        Time step [s] of the phase table.

    Returns
    -------
    SweepPlan
        The phase table and the slow windows (clipped to the band).

    Raises
    ------
    ValueError
        If a frequency is not finite and > 0, or ``f_start_hz >= f_end_hz``.

    Examples
    --------
    A 3 % resonance at 50 Hz is crossed at 4 pi zeta^2 f^2 / 4 = 7.1 Hz/s:

    >>> plan = sweep_plan(10.0, 100.0, 50.0, resonances=[(50.0, 0.03)])
    >>> i = int(np.argmin(np.abs(plan.frequency_hz - 50.0)))
    >>> rate = np.gradient(plan.frequency_hz, plan.t)[i]
    >>> round(float(rate), 2), round(4 * math.pi * 0.03**2 * 50**2 / 4, 2)
    (7.07, 7.07)
    """
    f0 = positive("sweep_plan:", "f_start_hz", f_start_hz, "Hz")
    f1 = positive("sweep_plan:", "f_end_hz", f_end_hz, "Hz")
    if not f1 > f0:
        raise ValueError(f"the sweep needs f_start_hz < f_end_hz, got {f0:g}, {f1:g}")
    f = np.geomspace(f0, f1, 4000)
    rate = 4 * math.pi * base_damping**2 * f**2 / time_constants
    slow = []
    for fr, zeta in resonances:
        if not (math.isfinite(fr) and fr > 0 and math.isfinite(zeta) and zeta > 0):
            continue
        lo, hi = fr * (1 - window - 3 * zeta), fr * (1 + window + 3 * zeta)
        sel = (f >= lo) & (f <= hi)
        rate[sel] = np.minimum(rate[sel], 4 * math.pi * zeta**2 * f[sel] ** 2 / time_constants)
        if sel.any():
            slow.append((max(lo, f0), min(hi, f1)))
    # time to each frequency: dt = df / rate (trapezoid in f), then phase = 2 pi int f dt
    t_f = np.concatenate([[0.0], np.cumsum(0.5 * (1 / rate[1:] + 1 / rate[:-1]) * np.diff(f))])
    t = np.arange(0.0, t_f[-1] + step, step)
    t[-1] = min(t[-1], t_f[-1])
    freq = np.interp(t, t_f, f)
    phase = np.concatenate([[0.0], np.cumsum(np.pi * (freq[1:] + freq[:-1]) * np.diff(t))])
    return SweepPlan(t, phase, freq, float(amplitude), tuple(slow))


def planned_sweep(force_pp: float, plan: SweepPlan, speed: float = 0.0, dof: str = "wp.x",
                  settle: float = 0.0, ring_down: float = 0.0,
                  start: float = DEFAULT_START) -> Scenario:
    """Return a force sweep at the work piece following a :class:`SweepPlan`.

    Parameters
    ----------
    force_pp : float
        Force amplitude peak to peak [N] (replaces the plan's amplitude).
    plan : SweepPlan
        The sweep (from :func:`sweep_plan`).
    speed : float
        Constant axis speed [m/s] (0: standing still), reached by a smooth start.
    dof : str
        Work-piece DOF of the force.
    settle : float
        Time [s] of motion before the sweep (the slide reaches its speed).
    ring_down : float
        Time [s] without force after the sweep (to see the response decay).
    start : float
        Duration [s] of the smooth start to ``speed``.

    Returns
    -------
    Scenario
        Duration ``settle + plan.duration + ring_down``; the force acts from ``settle`` to
        the plan's end, and the plan, shifted by ``settle``, is the scenario's ``sweep``.

    Raises
    ------
    ValueError
        If ``force_pp`` is not finite and > 0, or ``settle``, ``ring_down`` or ``start`` is
        negative.
    """
    force_pp = positive("planned_sweep:", "force_pp", force_pp, "N")
    amplitude = 0.5 * force_pp
    t0 = positive("planned_sweep:", "settle", settle, "s", allow_zero=True)
    plan = SweepPlan(plan.t + t0, plan.phase, plan.frequency_hz, amplitude, plan.slow)
    t_end = float(plan.t[-1])

    def force(t):
        t = np.asarray(t, dtype=float)
        on = (t >= t0) & (t <= t_end)
        return np.where(on, amplitude * np.sin(plan.phase_at(t)), 0.0)

    motion = (_smooth_start(float(speed), positive("planned_sweep:", "start", start, "s",
                                                   allow_zero=True)) if speed else None)
    label = (f"sine sweep {plan.f_start_hz:g}-{plan.f_end_hz:g} Hz in "
             f"{plan.duration - t0:.3g} s, {force_pp:g} N p-p, {speed * 1e3:g} mm/s")
    ring_down = positive("planned_sweep:", "ring_down", ring_down, "s", allow_zero=True)
    return Scenario(duration=t_end + ring_down, motion=motion,
                    forces={dof: force}, speed=float(speed), name=label, sweep=plan)


def constant_speed(speed: float, duration: float, start: float = DEFAULT_START) -> Scenario:
    """Return a move at constant speed, reached by a smooth start.

    Parameters
    ----------
    speed : float
        Axis speed [m/s] (its sign is the direction).
    duration : float
        End time [s].
    start : float
        Duration [s] of the smooth start, ``v = V (3 s^2 - 2 s^3)`` with s = t/start.

    Returns
    -------
    Scenario
        The motion, no force.

    Raises
    ------
    ValueError
        If ``duration`` is not finite and > 0, ``start`` is negative, or ``speed`` is not
        finite.
    """
    start = positive("constant_speed:", "start", start, "s", allow_zero=True)
    return Scenario(duration=duration, motion=_smooth_start(float(speed), start),
                    speed=float(speed), name=f"constant speed {speed * 1e3:g} mm/s")


def point_to_point(points, speed: float, acceleration: float, dwell: float = 0.0,
                   duration: float | None = None) -> Scenario:
    """Return moves through positions with a trapezoidal velocity profile (reversals included).

    Each move from ``points[i]`` to ``points[i+1]`` accelerates at ``acceleration`` up to
    ``speed`` (or to ``sqrt(distance acceleration)`` on short moves), decelerates alike, then
    dwells ``dwell`` seconds. The axis starts at points[0] = its rest position (must be 0).

    Parameters
    ----------
    points : array_like
        Positions [m], at least two, the first 0.
    speed : float
        Largest speed [m/s], > 0.
    acceleration : float
        Acceleration and deceleration [m/s^2], > 0.
    dwell : float
        Rest [s] after each move.
    duration : float, optional
        End time [s]; default the end of the last dwell.

    Returns
    -------
    Scenario
        The motion, no force, at nominal speed 0.

    Raises
    ------
    ValueError
        If ``points`` is not as above, or a speed, acceleration, dwell or duration is out of
        range.
    """
    points = np.asarray(points, dtype=float)
    if points.ndim != 1 or points.size < 2 or points[0] != 0.0:
        raise ValueError("points must list at least two positions [m], starting at 0")
    speed = positive("point_to_point:", "speed", speed, "m/s")
    acc = positive("point_to_point:", "acceleration", acceleration, "m/s^2")
    dwell = positive("point_to_point:", "dwell", dwell, "s", allow_zero=True)
    segs = []   # (t0, x0, direction, t_acc, v_peak, t_flat)
    t0 = 0.0
    for x0, x1 in itertools.pairwise(points):
        dist = abs(x1 - x0)
        vp = min(speed, math.sqrt(dist * acc))
        ta = vp / acc
        tf = (dist - vp * ta) / vp if vp > 0 else 0.0
        segs.append((t0, x0, math.copysign(1.0, x1 - x0), ta, vp, tf))
        t0 += 2 * ta + tf + dwell
    total = t0 if duration is None else positive("point_to_point:", "duration", duration, "s")
    starts = np.array([seg[0] for seg in segs])

    def motion(t):
        t = np.asarray(t, dtype=float)
        x, v, a = np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)
        which = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(segs) - 1)
        for k, (s0, x0, sgn, ta, vp, tf) in enumerate(segs):
            sel = which == k
            tau = np.maximum(t[sel] - s0, 0.0)
            d_acc = 0.5 * acc * ta**2
            t3 = np.clip(tau - ta - tf, 0.0, ta)
            pos = np.where(tau < ta, 0.5 * acc * tau**2,
                           np.where(tau < ta + tf, d_acc + vp * (tau - ta),
                                    d_acc + vp * tf + vp * t3 - 0.5 * acc * t3**2))
            vel = np.where(tau < ta, acc * tau, np.where(tau < ta + tf, vp, vp - acc * t3))
            ac = np.where(tau < ta, acc, np.where(tau < ta + tf, 0.0,
                                                  np.where(tau < 2 * ta + tf, -acc, 0.0)))
            x[sel], v[sel], a[sel] = x0 + sgn * pos, sgn * vel, sgn * ac
        return x, v, a

    return Scenario(duration=total, motion=motion,
                    name=f"point to point through {points.tolist()} m")


def sinusoid(amplitude: float, period: float, cycles: float = 2.0) -> Scenario:
    """Return the position reference ``x = A (1 - cos(2 pi t / T))``.

    An oscillation of amplitude A about A, starting at rest, with a velocity reversal every
    half period (the paper's Fig 8: 10 um, 3.7 s).

    Parameters
    ----------
    amplitude : float
        Amplitude A [m], > 0.
    period : float
        Period T [s], > 0.
    cycles : float
        Number of periods simulated, > 0.

    Returns
    -------
    Scenario
        The motion, no force, duration ``cycles T``.

    Raises
    ------
    ValueError
        If a value is not finite and > 0.
    """
    amplitude = positive("sinusoid:", "amplitude", amplitude, "m")
    period = positive("sinusoid:", "period", period, "s")
    w = 2.0 * math.pi / period

    def motion(t):
        t = np.asarray(t, dtype=float)
        return (amplitude * (1 - np.cos(w * t)), amplitude * w * np.sin(w * t),
                amplitude * w * w * np.cos(w * t))

    return Scenario(duration=positive("sinusoid:", "cycles", cycles, "") * period, motion=motion,
                    name=f"sinusoid {amplitude * 1e6:g} um, {period:g} s")


def circle(radius: float, period: float, cycles: float = 2.0) -> Scenario:
    """Return the X component of a circle, started at its X extreme.

    ``x = R (cos(2 pi t / T) - 1)``, from 0 to -2R and back (the paper's Fig 2 circles of 20
    and 5 um).

    Parameters
    ----------
    radius : float
        Radius R [m], > 0.
    period : float
        Time T [s] of one circle, > 0.
    cycles : float
        Number of circles simulated, > 0.

    Returns
    -------
    Scenario
        The motion, no force, duration ``cycles T``.

    Raises
    ------
    ValueError
        If a value is not finite and > 0.
    """
    radius = positive("circle:", "radius", radius, "m")
    period = positive("circle:", "period", period, "s")
    w = 2.0 * math.pi / period

    def motion(t):
        t = np.asarray(t, dtype=float)
        return (radius * (np.cos(w * t) - 1), -radius * w * np.sin(w * t),
                -radius * w * w * np.cos(w * t))

    return Scenario(duration=positive("circle:", "cycles", cycles, "") * period, motion=motion,
                    name=f"circle X, radius {radius * 1e6:g} um, {period:g} s")


def custom(duration: float, x_ref=None, v_ref=None, a_ref=None, forces=None,
           speed: float = 0.0, name: str = "custom") -> Scenario:
    """Return a scenario from user functions of time.

    Parameters
    ----------
    duration : float
        End time [s].
    x_ref, v_ref, a_ref : callable, optional
        Position [m], velocity [m/s] and acceleration [m/s^2] references as functions of t
        [s] (the last two feed the feed-forwards); zero when not given.
    forces : dict, optional
        ``{dof: f(t)}`` [N] at work-piece DOFs.
    speed : float
        Nominal sliding speed [m/s] (see :class:`Scenario`).
    name : str
        A label for reports.

    Returns
    -------
    Scenario
        The scenario.

    Raises
    ------
    ValueError
        If a reference or force is not callable, or the duration or speed is out of range.
    """
    motion = None
    if any(f is not None for f in (x_ref, v_ref, a_ref)):
        for label, f in (("x_ref", x_ref), ("v_ref", v_ref), ("a_ref", a_ref)):
            if f is not None and not callable(f):
                raise ValueError(f"{label} must be a function of time t [s]")

        def motion(t):
            return tuple((f if f is not None else _zero)(t) for f in (x_ref, v_ref, a_ref))

    return Scenario(duration=duration, motion=motion, forces=dict(forces or {}), speed=speed,
                    name=name)
