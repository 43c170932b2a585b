"""Stepped-sine compliance by time simulation: the second method that checks harmonic balance.

At each frequency the nonlinear axis (:func:`servotune.simulate.simulate`, LuGre at every pad)
is driven from rest by ``F(t) = F_pp/2 sin(w t)`` at the work piece (standing still, or after a
smooth start to the feed speed) until its response is periodic: the fundamental of the
work-piece displacement (least squares on ``1, t, cos, sin`` over whole cycles, as
:meth:`servotune.simulate.SimulationResult.sweep_envelope` measures it) over the last two
windows of cycles agrees within ``tolerance``; otherwise the run is repeated twice as long. A
stepped sine, not a sweep: each value is a steady state.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..simulate import NonlinearAxis, Scenario, simulate

__all__ = ["SteppedSine", "stepped_sine"]

START = 0.2      # [s] smooth start to the feed speed
SETTLE = 0.3     # [s] before the force starts while feeding
STEP = 5e-4      # [s] run durations are whole multiples of it (recorded at STEP / 2)


@dataclass(frozen=True, eq=False)
class SteppedSine:
    """Steady-state compliance at given frequencies by time simulation (SI).

    Attributes
    ----------
    omega : numpy.ndarray
        Frequencies [rad/s].
    compliance : numpy.ndarray
        Fundamental work-piece displacement per force amplitude [m/N].
    durations : numpy.ndarray
        Simulated time after the force starts [s] of the run that reached the steady state at
        each frequency (while feeding, the run is 0.3 s longer: the force starts once the
        feed is steady).
    wall_time : float
        Seconds spent.
    """

    omega: np.ndarray
    compliance: np.ndarray
    durations: np.ndarray
    wall_time: float


def _fundamental(t, x, omega, t0, t1):
    sel = (t >= t0) & (t < t1)
    tt, mid = t[sel], 0.5 * (t0 + t1)
    basis = np.column_stack([np.ones_like(tt), tt - mid, np.cos(omega * tt), np.sin(omega * tt)])
    coef = np.linalg.lstsq(basis, x[sel], rcond=None)[0]
    return math.hypot(coef[2], coef[3])


def _scenario(force_pp: float, omega: float, speed: float, duration: float) -> Scenario:
    amplitude = 0.5 * force_pp
    t_force = SETTLE if speed else 0.0

    def force(t):
        t = np.asarray(t, dtype=float)
        return np.where(t >= t_force, amplitude * np.sin(omega * (t - t_force)), 0.0)

    motion = None
    if speed:
        def motion(t):
            t = np.asarray(t, dtype=float)
            s = np.clip(t / START, 0.0, 1.0)
            v = speed * (3 * s**2 - 2 * s**3)
            a = speed * (6 * s - 6 * s**2) / START
            x = np.where(t < START, speed * START * (s**3 - 0.5 * s**4),
                         speed * (t - 0.5 * START))
            return x, v, a
    total = math.ceil((duration + t_force) / STEP) * STEP      # whole steps of the simulation
    return Scenario(duration=total, motion=motion, forces={"wp.x": force},
                    speed=speed, name=f"stepped sine {omega / (2 * math.pi):.4g} Hz")


def stepped_sine(setup, force_pp: float, omega, speed: float = 0.0, tolerance: float = 1e-3,
                 law=None, window_cycles: int = 10, first: float = 0.6,
                 longest: float = 20.0) -> SteppedSine:
    """Steady-state compliance of the nonlinear axis at each frequency by time simulation.

    Parameters
    ----------
    setup : servotune.simulate.setup.AxisSetup
        Structure, drive, pads and friction of the axis.
    force_pp : float
        Work-piece force, peak to peak [N].
    omega : array_like, shape (K,)
        Frequencies [rad/s], > 0.
    speed : float
        Feed speed [m/s] (0 at rest; otherwise reached by a smooth start in 0.2 s, and the
        force starts at 0.3 s).
    tolerance : float
        Relative change of the fundamental between the last two windows that counts as steady
        (``|last - before| <= tolerance last``).
    law : PadFriction, optional
        The friction law of every pad (default the law of ``setup``).
    window_cycles : int
        Cycles of the force per window.
    first : float
        Shortest first run [s], simulated time after the force starts; the first run is
        ``max(first, 3 windows)``, doubled until steady.
    longest : float
        Longest simulated time after the force starts [s]: a run that would have to be
        doubled beyond it gives up.

    Returns
    -------
    SteppedSine
        The compliance ``|X_wp,1| / (F_pp / 2)`` [m/N] and the durations at each frequency.

    Raises
    ------
    RuntimeError
        If a frequency does not reach its steady state within ``longest`` seconds.

    See Also
    --------
    servotune.harmonic.compliance.nonlinear_compliance : the harmonic balance it checks.
    """
    t_start = time.perf_counter()
    law = setup.law if law is None else law
    axis = NonlinearAxis(setup.structure, setup.drive, setup.pads, law)
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    comp, durations = np.empty(omega.size), np.empty(omega.size)
    for i, w in enumerate(omega):
        period = 2.0 * math.pi / w
        window = window_cycles * period
        duration = max(first, 3.0 * window)
        while True:
            result = simulate(axis, _scenario(force_pp, w, speed, duration),
                              record_step=STEP / 2, record=("wp_x",))
            t, x = result.t, result["wp_x"]
            end = float(t[-1])
            last = _fundamental(t, x, w, end - window, end + 1e-12)
            before = _fundamental(t, x, w, end - 2 * window, end - window)
            if abs(last - before) <= tolerance * last:
                break
            duration *= 2.0
            if duration > longest:
                raise RuntimeError(f"no steady state at {w / (2 * math.pi):.4g} Hz within "
                                   f"{longest:g} s")
        comp[i] = last / (0.5 * force_pp)
        durations[i] = duration
    return SteppedSine(omega=omega, compliance=comp, durations=durations,
                       wall_time=time.perf_counter() - t_start)
