"""The paper's Table 3: 15 simulated sine-sweep trials, run in parallel, and its remarks A-C.

Bianchi et al. (2014), sec 5.3, simulate the full axis with a force at the work piece in X swept
10 -> 100 Hz in 20 s, at 50, 100, 200, 600 and 2000 N peak to peak, with the full LuGre friction
("lg") standing still and moving at 30 mm/s, and with viscous damping only ("vd") standing
still. Energies are taken over a fixed 18 s window (here t = 2 .. 20 s, after the initial
transient). Reading of "vd": the pads carry the viscous damping ``[friction] viscous`` of the
axis (the paper's sigma2 = 5578 N s/m) and nothing else. Reading of "lg" for an axis with
another friction law (``[friction.gms]``, a plug-in's): the pads carry that law, and remark B
takes its own steady sliding friction
(:meth:`~servotune.friction.law.FrictionLaw.steady_force`).

:func:`table3` submits one job per trial to any executor with ``submit(fn, *args)`` returning
futures with ``result()``: a ``concurrent.futures`` executor or a ``dask.distributed.Client``.
Jobs are the top-level :func:`run_trial` with plain, picklable data (the axis set-up, a
:class:`Trial`, a :class:`SweepSettings`); each returns a plain dict.

The remarks are checked by :func:`check_remarks` against independent linear predictions: the
closed-loop compliance peak with the pads locked (stiction at low force) and with viscous pads
(:func:`servotune.closed_loop.axis_compliance`), and the steady-state friction F_ss(v) times the
distance travelled in the window (:func:`servotune.friction.steady_state_friction`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..closed_loop import axis_compliance
from ..frequency import peak
from ..plant import Contact
from ..units import HZ_PER_RAD_S
from .contact import ViscousFriction
from .scenario import sine_sweep
from .setup import AxisSetup
from .simulator import DEFAULT_STEP, DEFAULT_TOLERANCE, NonlinearAxis, simulate

__all__ = ["Trial", "SweepSettings", "PAPER_TABLE3", "TRIALS", "run_trial", "table3",
           "linear_references", "check_remarks", "Table3"]



@dataclass(frozen=True)
class Trial:
    """One row of Table 3: the friction model, the force and the speed.

    Parameters
    ----------
    model : {"lg", "vd"}
        LuGre friction, or the viscous damping ``[friction] viscous`` alone.
    force_pp : float
        Peak-to-peak force at the work piece [N], > 0.
    speed : float
        Axis speed [m/s] (0: standing still).

    Raises
    ------
    ValueError
        If the model is unknown or the force is not finite and > 0.
    """

    model: str
    force_pp: float
    speed: float

    def __post_init__(self) -> None:
        if self.model not in ("lg", "vd"):
            raise ValueError(f"Trial.model must be 'lg' or 'vd', got {self.model!r}")
        if not (self.force_pp > 0 and math.isfinite(self.force_pp)):
            raise ValueError("Trial.force_pp must be a positive force [N]")


@dataclass(frozen=True)
class SweepSettings:
    """The sweep and the energy window (defaults: the paper's 10 -> 100 Hz in 20 s, 2 .. 20 s).

    Parameters
    ----------
    f_start_hz, f_end_hz : float
        Start and end frequency [Hz] of the linear sweep, 0 < start < end.
    duration : float
        Sweep time [s].
    window : (float, float)
        Energy window [s] within ``[0, duration]``.
    step : float
        Integration step [s] of :func:`servotune.simulate.simulator.simulate`.
    tolerance : float
        Local error allowed per step in the pad motion, relative to vs and Fs/sigma0 (see
        :func:`servotune.simulate.simulator.simulate`).

    Raises
    ------
    ValueError
        If the window does not lie within the sweep or the frequencies are out of order.
    """

    f_start_hz: float = 10.0
    f_end_hz: float = 100.0
    duration: float = 20.0
    window: tuple[float, float] = (2.0, 20.0)
    step: float = DEFAULT_STEP
    tolerance: float = DEFAULT_TOLERANCE

    def __post_init__(self) -> None:
        t0, t1 = (float(t) for t in self.window)
        if not 0 <= t0 < t1 <= self.duration:
            raise ValueError(f"the window {self.window} must lie within the sweep "
                             f"[0, {self.duration}] s")
        if not 0 < self.f_start_hz < self.f_end_hz:
            raise ValueError("the sweep needs 0 < f_start_hz < f_end_hz")
        object.__setattr__(self, "window", (t0, t1))


#: Table 3 of Bianchi et al. (2014), as printed (energies [J], resonance [Hz], WP oscillation
#: per force converted from mm/N to m/N; row 13 lists two resonances, 38 and 56 Hz).
PAPER_TABLE3 = (
    ("lg", 50, 0.0, -0.017, -0.005, "57", 5.96e-8),
    ("vd", 50, 0.0, -0.001, -0.028, "32", 6.14e-8),
    ("lg", 50, 0.03, -1380, 1380, "32", 6.641e-8),
    ("lg", 100, 0.0, -0.07, -0.019, "57", 5.89e-8),
    ("vd", 100, 0.0, -0.004, -0.112, "32", 6.14e-8),
    ("lg", 100, 0.03, -1380, 1380, "32", 6.64e-8),
    ("lg", 200, 0.0, -0.281, -0.073, "57", 5.73e-8),
    ("vd", 200, 0.0, -0.016, -0.483, "32", 6.14e-8),
    ("lg", 200, 0.03, -1380, 1380, "32", 6.643e-8),
    ("lg", 600, 0.0, -3.02, -0.581, "57", 4.7e-8),
    ("vd", 600, 0.0, -0.14, -3.94, "32", 6.14e-8),
    ("lg", 600, 0.03, -1380, 1380, "32", 6.65e-8),
    ("lg", 2000, 0.0, -40.5, -4.16, "38 / 56", 1.9e-8),
    ("vd", 2000, 0.0, -1.60, -43.8, "32", 6.14e-8),
    ("lg", 2000, 0.03, -1290, 1340, "32", 6.8e-8),
)

TRIALS = tuple(Trial(m, float(f), float(v)) for m, f, v, *_ in PAPER_TABLE3)


def run_trial(setup: AxisSetup, trial: Trial, settings: SweepSettings) -> dict:
    """Simulate one trial and return its row. Picklable in and out, so any executor can run it.

    Parameters
    ----------
    setup : AxisSetup
        The axis.
    trial : Trial
        Friction model, force and speed.
    settings : SweepSettings
        Sweep, energy window, step and tolerance.

    Returns
    -------
    dict
        The JSON row: model, force [N], speed [m/s], the works over the window [J]
        (friction, motor, force, damping), the structure's energy change and the friction
        dissipation [J], the balance's relative residual, the resonance [Hz] and peak
        oscillation per force [m/N] of the envelope (cycles from ``min(window[0],
        duration / 4)`` on), the number of steps and the wall time [s].

    Raises
    ------
    SimulationError
        If the integration stops before the end.
    """
    friction = setup.law if trial.model == "lg" else ViscousFriction(setup.viscous)
    axis = NonlinearAxis(setup.structure, setup.drive, setup.pads, friction)
    scenario = sine_sweep(trial.force_pp, settings.f_start_hz, settings.f_end_hz,
                          settings.duration, speed=trial.speed)
    result = simulate(axis, scenario, step=settings.step, tolerance=settings.tolerance,
                      window=settings.window)
    e = result.energies(*settings.window)
    env = result.sweep_envelope(t_min=min(settings.window[0], 0.25 * settings.duration))
    return {
        "model": trial.model, "force_pp_n": trial.force_pp, "speed_m_per_s": trial.speed,
        "energy_friction_j": e.friction, "energy_motor_j": e.motor,
        "resonance_hz": env.resonance_hz, "wp_oscillation_per_force_m_per_n": env.peak,
        "energy_force_j": e.force, "energy_damping_j": e.damping,
        "energy_structure_change_j": e.structure_change,
        "friction_dissipated_j": e.friction_dissipated,
        "balance_relative_residual": e.relative_residual,
        "steps": result.stats["steps"], "wall_time_s": result.stats["wall_time_s"],
    }


def linear_references(setup: AxisSetup, settings: SweepSettings) -> dict:
    """Return the compliance peaks of the linear closed loop within the sweep band.

    Pads locked (stiction at low force), LuGre presliding (spring sigma0, damper
    sigma1 + sigma2) and viscous-only pads, on 2000 points over the band
    (:func:`servotune.closed_loop.axis_compliance`).

    Parameters
    ----------
    setup : AxisSetup
        The axis.
    settings : SweepSettings
        The sweep band.

    Returns
    -------
    dict
        ``{"locked" | "presliding" | "viscous": {"resonance_hz", "compliance_m_per_n"}}``.
    """
    omega = 2 * math.pi * np.linspace(settings.f_start_hz, settings.f_end_hz, 2000)
    k, d = setup.law.presliding()
    out = {}
    for key, contact in (("locked", Contact.locked()),
                         ("presliding", Contact.stiction(k, d, 0.0)),
                         ("viscous", Contact.viscous(setup.viscous))):
        h = axis_compliance(setup.structure, omega, setup.drive, contact, setup.pads)[0]
        mag, w = peak(omega, h)
        out[key] = {"resonance_hz": w * HZ_PER_RAD_S, "compliance_m_per_n": mag}
    return out


def check_remarks(rows: list[dict], references: dict, setup: AxisSetup,
                  settings: SweepSettings) -> dict:
    """Return the paper's remarks A-C checked on simulated rows.

    A: standing still at the lowest force, LuGre resonates nearer the locked-pad frequency than
       the viscous-only one and most of the injected energy is dissipated by friction
       (|E_friction| > |E_motor|), whereas viscous-only resonates nearer the viscous-pad
       frequency and the motor absorbs most (|E_motor| > |E_friction|).
    B: moving, every LuGre row has E_friction within 5 % of -F_ss(v) v T_window and
       E_motor within 5 % of -E_friction.
    C: standing still at the largest force, LuGre's oscillation per force is below LuGre's at
       the lowest force (friction at large amplitude damps more than stiction holds); whether
       it is also below viscous-only's at the same force (as in the paper) is reported as
       ``below_viscous``, which depends on the axis.

    A remark whose rows are missing is left out.

    Parameters
    ----------
    rows : list of dict
        Rows of :func:`run_trial`; at least one standing still.
    references : dict
        From :func:`linear_references`.
    setup : AxisSetup
        The axis (its LuGre parameters for F_ss).
    settings : SweepSettings
        The energy window.

    Returns
    -------
    dict
        ``{"A" | "B" | "C": {"holds": bool, "detail": str}}``; C also has
        ``below_viscous``.

    Raises
    ------
    ValueError
        If no row stands still.
    """
    locked = references["locked"]["resonance_hz"]
    viscous = references["viscous"]["resonance_hz"]
    still = [r for r in rows if r["speed_m_per_s"] == 0.0]
    out = {}
    f_low = min(r["force_pp_n"] for r in still)
    lg = next((r for r in still if r["model"] == "lg" and r["force_pp_n"] == f_low), None)
    vd = next((r for r in still if r["model"] == "vd" and r["force_pp_n"] == f_low), None)
    if lg and vd:
        a_lg = (abs(lg["resonance_hz"] - locked) < abs(lg["resonance_hz"] - viscous)
                and abs(lg["energy_friction_j"]) > abs(lg["energy_motor_j"]))
        a_vd = (abs(vd["resonance_hz"] - viscous) < abs(vd["resonance_hz"] - locked)
                and abs(vd["energy_motor_j"]) > abs(vd["energy_friction_j"]))
        out["A"] = {"holds": bool(a_lg and a_vd), "detail": (
            f"{f_low:g} N p-p standing still: lg resonance {lg['resonance_hz']:.1f} Hz "
            f"(locked pads {locked:.1f} Hz), E_friction {lg['energy_friction_j']:.3g} J vs "
            f"E_motor {lg['energy_motor_j']:.3g} J; vd resonance {vd['resonance_hz']:.1f} Hz "
            f"(viscous pads {viscous:.1f} Hz), E_friction {vd['energy_friction_j']:.3g} J vs "
            f"E_motor {vd['energy_motor_j']:.3g} J")}
    moving = [r for r in rows if r["speed_m_per_s"] != 0.0 and r["model"] == "lg"]
    if moving:
        t = settings.window[1] - settings.window[0]
        checks, parts = [], []
        for r in moving:
            v = r["speed_m_per_s"]
            expect = -float(setup.law.steady_force(v)) * abs(v) * t
            ok = (abs(r["energy_friction_j"] / expect - 1) < 0.05
                  and abs(r["energy_motor_j"] / -r["energy_friction_j"] - 1) < 0.05)
            checks.append(ok)
            parts.append(f"{r['force_pp_n']:g} N: E_friction {r['energy_friction_j']:.4g} J "
                         f"(F_ss v T = {expect:.4g} J), E_motor {r['energy_motor_j']:.4g} J")
        out["B"] = {"holds": bool(all(checks)), "detail": "; ".join(parts)}
    f_high = max(r["force_pp_n"] for r in still)
    lg_hi = next((r for r in still if r["model"] == "lg" and r["force_pp_n"] == f_high), None)
    vd_hi = next((r for r in still if r["model"] == "vd" and r["force_pp_n"] == f_high), None)
    if lg and lg_hi and vd_hi and f_high > f_low:
        c = lg_hi["wp_oscillation_per_force_m_per_n"] < lg["wp_oscillation_per_force_m_per_n"]
        below = (lg_hi["wp_oscillation_per_force_m_per_n"]
                 < vd_hi["wp_oscillation_per_force_m_per_n"])
        out["C"] = {"holds": bool(c), "below_viscous": bool(below), "detail": (
            f"{f_high:g} N p-p standing still: lg {lg_hi['wp_oscillation_per_force_m_per_n']:.3g}"
            f" m/N vs lg at {f_low:g} N {lg['wp_oscillation_per_force_m_per_n']:.3g} m/N and vd "
            f"{vd_hi['wp_oscillation_per_force_m_per_n']:.3g} m/N")}
    return out


@dataclass(frozen=True)
class Table3:
    """Rows (in trial order), the linear references and the remarks of a Table 3 run.

    Parameters
    ----------
    axis : str
        The axis' name.
    rows : tuple of dict
        Rows of :func:`run_trial`, in trial order.
    references : dict
        From :func:`linear_references`.
    remarks : dict
        From :func:`check_remarks`.
    settings : SweepSettings
        The sweep.
    """

    axis: str
    rows: tuple
    references: dict
    remarks: dict
    settings: SweepSettings

    def to_dict(self) -> dict:
        """Return the run as JSON-ready data.

        Returns
        -------
        dict
            ``axis``, ``rows`` (each with the paper's values under ``paper`` when the trial is
            one of :data:`PAPER_TABLE3` and the sweep is the paper's), ``linear_references``,
            ``remarks`` and ``sweep``.
        """
        paper = {(m, float(f), float(v)): (ef, em, res, osc) for m, f, v, ef, em, res, osc in
                 PAPER_TABLE3}
        rows = []
        for r in self.rows:
            row = dict(r)
            ref = paper.get((r["model"], r["force_pp_n"], r["speed_m_per_s"]))
            if ref is not None and self.settings == SweepSettings(
                    step=self.settings.step, tolerance=self.settings.tolerance):
                row["paper"] = {"energy_friction_j": ref[0], "energy_motor_j": ref[1],
                                "resonance_hz": ref[2],
                                "wp_oscillation_per_force_m_per_n": ref[3]}
            rows.append(row)
        s = self.settings
        return {"axis": self.axis, "rows": rows, "linear_references": self.references,
                "remarks": self.remarks,
                "sweep": {"f_start_hz": s.f_start_hz, "f_end_hz": s.f_end_hz,
                          "duration": s.duration, "window": list(s.window), "step": s.step,
                          "tolerance": s.tolerance}}


def table3(setup: AxisSetup, executor=None, trials=TRIALS,
           settings: SweepSettings | None = None, progress=None) -> Table3:
    """Run the trials of Table 3 (in parallel through ``executor``) and check the remarks.

    Parameters
    ----------
    setup : AxisSetup
        From :func:`servotune.simulate.setup.axis_setup`.
    executor : optional
        Anything with ``submit(fn, *args) -> future`` and ``future.result()``
        (``concurrent.futures.ProcessPoolExecutor``, ``dask.distributed.Client``, ...). None
        runs the trials one after the other in this process.
    trials : sequence of Trial
        Default: the paper's 15.
    settings : SweepSettings, optional
        Default: the paper's sweep and window.
    progress : callable, optional
        Called with ``(done, total)`` as trials finish.

    Returns
    -------
    Table3
        The rows in trial order, the linear references and the remarks.

    Raises
    ------
    SimulationError
        If a trial's integration stops before the end.
    """
    settings = SweepSettings() if settings is None else settings
    trials = tuple(trials)
    rows = [None] * len(trials)
    if executor is None:
        for i, trial in enumerate(trials):
            rows[i] = run_trial(setup, trial, settings)
            if progress:
                progress(i + 1, len(trials))
    else:
        futures = [executor.submit(run_trial, setup, trial, settings) for trial in trials]
        for i, fut in enumerate(futures):
            rows[i] = fut.result()
            if progress:
                progress(i + 1, len(trials))
    refs = linear_references(setup, settings)
    return Table3(axis=setup.name, rows=tuple(rows), references=refs,
                  remarks=check_remarks(rows, refs, setup, settings), settings=settings)
