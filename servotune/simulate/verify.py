"""Nonlinear verification of a tuned design against the linear predictions it was tuned on.

A design (guide-way damping C, Kv, velocity Kp and Ti; :class:`servotune.tuning.Design`) is
tuned on linear models. :func:`verify_design` simulates it with the axis' friction law (LuGre in
the paper) at the pads under
sine sweeps standing still, and compares each sweep's resonance and peak oscillation per force
with four linear predictions of the closed loop (:func:`servotune.closed_loop.axis_compliance`):

* ``locked``: pads held rigidly;
* ``presliding``: pads on the law's presliding contact (LuGre: spring sigma0, damper sigma1 +
  C), the small-amplitude limit (the paper's remark A);
* ``viscous``: pads as the viscous damper C the design assumes;
* ``describing``: pads as the law's describing function (Ceq, Keq; for LuGre paper Eq 8-10) at
  the pad vibration amplitude the simulation shows at its resonance.

Reading of C in the nonlinear model: the design's C is the viscous part of the guide-way
friction (:meth:`~servotune.friction.law.FrictionLaw.with_viscous`): the LuGre law keeps Fc, Fs,
vs, delta, sigma0 and sigma1 of the axis and takes sigma2 = C. Agreement: resonance within
``freq_tol`` (relative) and peak within ``peak_tol``; the swept envelope is not a steady-state
response (the sweep passes a resonance in a finite time), so the tolerances are loose by
design.
"""

from __future__ import annotations

import dataclasses
import math

import control
import numpy as np

from ..closed_loop import axis_compliance
from ..drive import PIController
from ..frequency import peak
from ..plant import Contact
from ..units import HZ_PER_RAD_S
from .scenario import sine_sweep
from .setup import AxisSetup
from .simulator import NonlinearAxis, simulate

__all__ = ["design_setup", "verify_design", "DEFAULT_FORCES"]

DEFAULT_FORCES = (50.0, 600.0, 2000.0)


def design_setup(setup: AxisSetup, c: float, kv: float | None = None, kp: float | None = None,
                 ti: float | None = None, notch=None, lowpass=None) -> AxisSetup:
    """Return the axis set-up with a design's values.

    Parameters
    ----------
    setup : AxisSetup
        The axis set-up (:func:`servotune.simulate.setup.axis_setup`).
    c : float
        Guide-way damping C [N s/m]: the law's viscous part (LuGre sigma2) and the
        viscous-only damping.
    kv : float, optional
        Position gain Kv [1/s].
    kp : float, optional
        Velocity-loop gain Kp [N m s/rad].
    ti : float, optional
        Velocity-loop integral time Ti [s] (inf: no integral action).
    notch : servotune.drive.NotchFilter, optional
        A tuned current set-point notch, after the drive's own filters.
    lowpass : servotune.drive.LowPassFilter, optional
        A tuned current set-point low-pass, in place of the drive's own.

    Returns
    -------
    AxisSetup
        The set-up with these values; values left None keep the axis'.

    Raises
    ------
    ValueError
        If a value given is not finite and > 0 (Ti may be inf).
    """
    for name, value in (("c", c), ("kv", kv), ("kp", kp), ("ti", ti)):
        if value is not None and not ((math.isfinite(value) and value > 0) or
                                      (name == "ti" and value == math.inf)):
            raise ValueError(f"design {name} must be a positive number, got {value!r}")
    drive = setup.drive
    drive = dataclasses.replace(
        drive, kv=drive.kv if kv is None else float(kv),
        velocity_loop=PIController(drive.velocity_loop.kp if kp is None else float(kp),
                                   drive.velocity_loop.ti if ti is None else float(ti)),
        notches=drive.notches + (() if notch is None else (notch,)),
        lowpass=drive.lowpass if lowpass is None else lowpass)
    law = setup.law.with_viscous(float(c))
    return dataclasses.replace(setup, drive=drive, lugre=None, law=law, viscous=float(c))


def verify_design(setup: AxisSetup, forces=DEFAULT_FORCES, f_start_hz: float = 10.0,
                  f_end_hz: float = 100.0, duration: float = 20.0, freq_tol: float = 0.05,
                  peak_tol: float = 0.2, executor=None) -> dict:
    """Simulate the design (already in ``setup``, see :func:`design_setup`) and compare.

    Each force gives one sine sweep (:func:`servotune.simulate.scenario.sine_sweep`), standing
    still; its envelope from 10 % of the duration on gives the resonance and peak, and the
    pads' envelopes at the resonance the pad amplitude. The predictions are peaks of
    :func:`servotune.closed_loop.axis_compliance` on 3000 points over the swept band. A
    prediction agrees when the simulated resonance lies within ``freq_tol`` and the peak
    within ``peak_tol`` of it (relative).

    Parameters
    ----------
    setup : AxisSetup
        The axis with the design (:func:`design_setup`).
    forces : sequence of float
        Peak-to-peak work-piece forces [N], one sweep each.
    f_start_hz, f_end_hz : float
        Swept band [Hz].
    duration : float
        Duration of each sweep [s].
    freq_tol : float
        Relative tolerance on the resonance.
    peak_tol : float
        Relative tolerance on the peak.
    executor : concurrent.futures.Executor, optional
        Runs the sweeps in parallel.

    Returns
    -------
    dict
        ``linear``: the locked, presliding and viscous predictions (resonance [Hz], peak
        [m/N]);
        ``sweeps``: per force, the simulated resonance and peak, the pad amplitude at the
        resonance, the describing-function prediction at that amplitude, and for each
        prediction whether it agrees (``agrees_<name>``); ``freq_tol``, ``peak_tol`` and
        the ``design`` (C, Kv, Kp, Ti).
    """
    omega = 2 * math.pi * np.linspace(f_start_hz, f_end_hz, 3000)

    def predict(contact):
        h = axis_compliance(setup.structure, omega, setup.drive, contact, setup.pads)[0]
        mag, w = peak(omega, h)
        return {"resonance_hz": w * HZ_PER_RAD_S, "peak_m_per_n": mag}

    k, d = setup.law.presliding()
    linear = {"locked": predict(Contact.locked()),
              "presliding": predict(Contact.stiction(k, d, 0.0)),
              "viscous": predict(Contact.viscous(setup.viscous))}
    axis = NonlinearAxis(setup.structure, setup.drive, setup.pads, setup.law)
    jobs = [(axis, float(f), f_start_hz, f_end_hz, duration) for f in forces]
    if executor is None:
        sims = [_sweep(*job) for job in jobs]
    else:
        sims = [fut.result() for fut in [executor.submit(_sweep, *job) for job in jobs]]
    sweeps = []
    for f, sim in zip(forces, sims, strict=True):
        ceq, keq = setup.law.describing_function(sim["pad_amplitude_m"],
                                                 2 * math.pi * sim["resonance_hz"])
        row = dict(sim)
        row["force_pp_n"] = float(f)
        # F = Keq x + Ceq v as a contact from velocity (Keq of the LuGre element may be
        # negative at large sigma1, which a spring Contact refuses)
        element = control.ss([[0.0]], [[1.0]], [[float(keq)]], [[float(ceq)]])
        row["describing"] = predict(Contact.sliding(element))
        row["describing"].update({"ceq": float(ceq), "keq": float(keq)})
        for name, pred in [*linear.items(), ("describing", row["describing"])]:
            row[f"agrees_{name}"] = bool(
                abs(sim["resonance_hz"] / pred["resonance_hz"] - 1) <= freq_tol
                and abs(sim["peak_m_per_n"] / pred["peak_m_per_n"] - 1) <= peak_tol)
        sweeps.append(row)
    return {"linear": linear, "sweeps": sweeps, "freq_tol": freq_tol, "peak_tol": peak_tol,
            "friction_law": setup.law.name,
            "design": {"c": setup.viscous, "kv": setup.drive.kv,
                       "kp": setup.drive.velocity_loop.kp, "ti": setup.drive.velocity_loop.ti}}


def _sweep(axis: NonlinearAxis, force_pp: float, f0: float, f1: float, duration: float) -> dict:
    result = simulate(axis, sine_sweep(force_pp, f0, f1, duration))
    env = result.sweep_envelope(t_min=0.1 * duration)
    pads = [result.sweep_envelope(p.replace(".", "_"), t_min=0.1 * duration) for p in axis.pads]
    i = int(np.argmin(np.abs(env.frequency - env.resonance)))
    amplitude = float(np.mean([p.amplitude[i] for p in pads])) * 0.5 * force_pp
    return {"resonance_hz": env.resonance_hz, "peak_m_per_n": env.peak,
            "pad_amplitude_m": max(amplitude, 1e-12)}
