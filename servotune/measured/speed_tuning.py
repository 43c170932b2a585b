"""The velocity loop tuned on a measured speed plant, without a model (as drive auto-tuners do).

Industrial auto-tuners (Siemens' automatic speed-controller setting, Heidenhain's TNCopt) excite
the axis, measure the speed plant P(jw) (motor speed over motor torque) and set the speed PI on
that measurement. :func:`tune_velocity_loop` does so with servotune's requirements: the drive's
own sampled-data velocity loop closed on the measured plant
(:func:`~servotune.measured.speed_plant.velocity_loop_response`: current loop, filters,
sample-and-hold, delays and speed measurement as the drive has them), and for each integral
time Ti on a grid the largest gain Kp whose loop is stable (Nyquist criterion on the measured
lines, :func:`~servotune.measured.speed_plant.encircled_poles`) with a sensitivity peak Ms at
most the limit; the design is the one of widest closed-loop bandwidth whose Ti times the
bandwidth lies in the requirements' range (the integral action neither eating the phase
margin nor too slow to reject load torques; :class:`servotune.requirements.Requirements`).

What it does not know: the structure beyond the measured lines (above the last line the plant
is taken as the inertia line 1/(j w J)), the position loop, the guide ways in other regimes
than the one measured (a measurement at standstill sees the presliding contact), the cutting.
The model-based ``servotune tune`` judges those; this is the auto-tuner's answer to compare it
with and the start a commissioning engineer would take.

References
----------
K. J. Astrom, T. Hagglund, Advanced PID Control, ISA (2006), sec 7.5 (loop shaping under an Ms
constraint, the largest gain at each integral time).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..drive import Drive, PIController
from ..frequency import LoopAnalysis, analyse_response
from ..units import HZ_PER_RAD_S
from .speed_plant import SpeedPlantResponse, encircled_poles, velocity_loop_response

__all__ = ["VelocityTuning", "tune_velocity_loop"]


@dataclass(frozen=True)
class VelocityTuning:
    """The speed PI set on a measured speed plant.

    Parameters
    ----------
    kp : float
        Velocity-loop gain Kp [N m s/rad].
    ti : float
        Integral time Ti [s].
    analysis : LoopAnalysis
        Margins, Ms and bandwidth of the loop on the measurement.
    ms_limit : float
        The Ms it was held to.
    candidates : tuple of (float, float, float)
        ``(ti, largest kp, bandwidth [rad/s])`` at every integral time tried.
    notes : tuple of str
        What it assumed.
    """

    kp: float
    ti: float
    analysis: LoopAnalysis
    ms_limit: float
    candidates: tuple
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        """Return the tuning as JSON-ready data (SI).

        Returns
        -------
        dict
            ``kp``, ``ti``, ``ms_limit``, the loop on the measurement (``ms``,
            ``phase_margin_deg``, ``gain_margin_db``, ``bandwidth_hz``), ``candidates`` and
            ``notes``.
        """
        a = self.analysis
        return {"kp": self.kp, "ti": self.ti, "ms_limit": self.ms_limit, "ms": a.ms,
                "phase_margin_deg": math.degrees(a.phase_margin),
                "gain_margin_db": (20 * math.log10(a.gain_margin)
                                   if math.isfinite(a.gain_margin) else None),
                "bandwidth_hz": a.bandwidth * HZ_PER_RAD_S,
                "candidates": [{"ti": t, "kp": k, "bandwidth_hz": b * HZ_PER_RAD_S}
                               for t, k, b in self.candidates],
                "notes": list(self.notes)}


def _loop(drive: Drive, response, omega, kp: float, ti: float):
    d = dataclasses.replace(drive, velocity_loop=PIController(kp, ti))
    l_jw = velocity_loop_response(d, response, omega)
    inside = np.isfinite(l_jw)
    return omega[inside], l_jw[inside], d


def _judge(drive, response, omega, kp, ti, ms_limit, nyquist):
    """(ok, analysis) of the loop with (kp, ti): stable on the measurement, Ms <= limit."""
    w, l_jw, d = _loop(drive, response, omega, kp, ti)
    if w.size < 2:
        return False, None
    top = l_jw
    if nyquist is not None and w[-1] < nyquist * (1 - 2e-7):
        edge = np.array([nyquist * (1 - 1e-7)])
        top = np.append(l_jw, velocity_loop_response(d, response, edge))
    poles = encircled_poles(top)
    if poles != 0:
        return False, None
    analysis = analyse_response(w, l_jw, l_jw[0])
    return bool(analysis.ms <= ms_limit), analysis


def tune_velocity_loop(omega, plant, drive: Drive, ms_limit: float,
                       ti_bandwidth: tuple[float, float] = (3.0, 30.0),
                       ti_range: tuple[float, float] = (1e-3, 0.2), n_ti: int = 25,
                       rtol: float = 2e-3) -> VelocityTuning:
    """Set the speed PI on a measured speed plant: the widest loop within Ms and the Ti rule.

    Parameters
    ----------
    omega : array_like
        Angular frequencies of the measurement [rad/s], increasing, > 0.
    plant : array_like of complex
        The measured speed plant P(jw) [rad/(s N m)] at ``omega``.
    drive : Drive
        The axis' drive: its current loop, filters and sampling are kept, its speed PI is set.
    ms_limit : float
        Largest sensitivity peak of the velocity loop (> 1), e.g.
        ``Requirements.ms_limit("velocity")``.
    ti_bandwidth : (float, float)
        Range of Ti times the closed-loop bandwidth [-] (the requirements' ti_bandwidth_min,
        ti_bandwidth_max).
    ti_range : (float, float)
        Integral times tried [s] (log-spaced).
    n_ti : int
        How many.
    rtol : float
        Relative accuracy of the largest Kp (bisection in log Kp).

    Returns
    -------
    VelocityTuning

    Raises
    ------
    ValueError
        Bad arguments, or no integral time with a stable loop within Ms (the message says
        which limit to relax).
    """
    omega = np.asarray(omega, dtype=float)
    plant = np.asarray(plant, dtype=complex)
    if omega.ndim != 1 or omega.size < 4 or omega.shape != plant.shape:
        raise ValueError("give the measurement's frequencies and values as two 1-D arrays of "
                         "the same length (at least 4 lines)")
    if not (math.isfinite(ms_limit) and ms_limit > 1.0):
        raise ValueError(f"ms_limit must be finite and > 1, got {ms_limit!r}")
    response = SpeedPlantResponse(omega, plant)
    nyquist = (None if drive.digital.is_continuous
               else math.pi / (drive.digital.multiples()[0] * drive.digital.current_period))
    kp0 = drive.velocity_loop.kp
    candidates, best = [], None
    for ti in np.geomspace(*ti_range, n_ti):
        ti = float(ti)
        low, high = None, None
        k = kp0
        # bracket the largest Kp within Ms: from the drive's gain, up or down by factors of 2
        ok, _ = _judge(drive, response, omega, k, ti, ms_limit, nyquist)
        for _ in range(40):
            if ok:
                low = k
                k *= 2.0
            else:
                high = k
                k /= 2.0
            if low is not None and high is not None:
                break
            ok, _ = _judge(drive, response, omega, k, ti, ms_limit, nyquist)
        if low is None or high is None:
            continue
        while high / low > 1.0 + rtol:
            mid = math.sqrt(low * high)
            ok, _ = _judge(drive, response, omega, mid, ti, ms_limit, nyquist)
            low, high = (mid, high) if ok else (low, mid)
        ok, analysis = _judge(drive, response, omega, low, ti, ms_limit, nyquist)
        if not ok:
            continue
        candidates.append((ti, low, analysis.bandwidth))
        rule = ti * analysis.bandwidth
        if ti_bandwidth[0] <= rule and (not ti_bandwidth[1] or rule <= ti_bandwidth[1]):
            if best is None or analysis.bandwidth > best[2].bandwidth:
                best = (low, ti, analysis)
    if best is None:
        raise ValueError(
            "no speed PI on the measured plant keeps the velocity loop stable with Ms <= "
            f"{ms_limit:.3g} and Ti x bandwidth in [{ti_bandwidth[0]:g}, {ti_bandwidth[1]:g}] "
            f"for Ti in [{ti_range[0]:g}, {ti_range[1]:g}] s ({len(candidates)} integral times "
            "gave a stable loop within Ms); relax [requirements] ms_velocity_max or the Ti rule, "
            "or add a current set-point filter at the resonance that limits the loop")
    kp, ti, analysis = best
    notes = ("Kp the largest within Ms at each Ti (bisection to "
             f"{rtol:.1%}), Ti from {n_ti} log-spaced values; the design of widest bandwidth "
             "within the Ti rule",
             "the loop is the drive's own (current loop, filters, sampling and delays) closed on "
             "the measurement; above its last line the plant is the inertia line 1/(j w J)")
    return VelocityTuning(float(kp), float(ti), analysis, float(ms_limit), tuple(candidates),
                          notes)
