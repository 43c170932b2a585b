"""Time simulation of the nonlinear axis: structure, drive and LuGre friction at every pad.

:func:`simulate` assembles the linear part (:func:`servotune.simulate.system.axis_system`),
diagonalises it once, and integrates with the exponential collocation scheme of
:mod:`servotune.simulate.integrator` in chunks (between which it reports progress and keeps
checkpoints of the energies). See those modules for the equations.

Why this integrator: the axis is stiff in two unrelated ways. Its linear part has modes from
the rigid-body travel to the bristle damper sigma1 on the pad masses (time constants ~1e-5 s)
and the structure's high modes; its nonlinear part, the sliding bristles, relaxes in ~1e-5 s
too. An exponential integrator makes the first exact for any step; Radau collocation makes the
second L-stable; and because the nonlinearity enters through one input per pad (two with a
velocity-dependent micro-damping), the implicit equations are of size 2 n_pads (4 n_pads)
whatever the size of the model. Compiled with numba, a step of
the paper's 41-DOF axis takes microseconds, and the step is chosen for the excitation (tens of
steps per cycle at 100 Hz), not for the stiffness; an error estimate (the curvature of the
friction remainder over the step, propagated to the pad motion) halves it where the friction
needs it. (casadi's CVODES was considered but not measured: a BDF solver would work with a dense
n x n Newton matrix and could not use the rank-n_pads structure of the nonlinearity.)
``benchmarks/simulate_sweep.py`` compares it with scipy's ``solve_ivp`` (LSODA; Radau with the
analytic Jacobian) at equal accuracy on the whole 20 s sweep of the bundled axis.
"""

from __future__ import annotations

import itertools
import math
import sys
import time
from dataclasses import dataclass

import numpy as np

from ..drive import Drive
from ..structure.model import ModalModel, signal_name
from . import integrator
from .contact import PadFriction
from .result import SimulationError, SimulationResult
from .scenario import Scenario
from .system import AxisSystem, axis_system

__all__ = ["NonlinearAxis", "simulate", "DEFAULT_STEP", "DEFAULT_RECORD_STEP"]

DEFAULT_STEP = 2.5e-4        # [s]: 40 steps per cycle at 100 Hz (shorter where friction asks)
DEFAULT_RECORD_STEP = 5e-4   # [s]
DEFAULT_TOLERANCE = 1e-4     # local error of the pad motion per step, relative to vs and Fs/sigma0
CHECKPOINT = 0.05            # [s] between energy checkpoints (and progress reports)
#: Base steps whose known inputs are held at a time (3 samples per step): a long run's inputs
#: take the memory of this window, not of the run.
INPUT_WINDOW = 1 << 15


@dataclass(frozen=True, eq=False)
class NonlinearAxis:
    """The axis to simulate: structure, drive, guide-way pads and their friction law.

    Parameters
    ----------
    structure : ModalModel
        The reduced structure (mass, damping, stiffness over named DOFs).
    drive : Drive, optional
        The cascade (None: the structure alone, motor DOFs free).
    pads : sequence of str
        The guide-way pad DOFs (relative X); the friction law's totals are shared equally.
    friction : PadFriction, optional
        :class:`~servotune.simulate.LuGreFriction`, :class:`~servotune.simulate.ViscousFriction`
        or another law, with axis-total parameters; None for frictionless pads.

    Raises
    ------
    ValueError
        A structure that is not a :class:`ModalModel`, a drive that is not a :class:`Drive`, a
        friction that is not a :class:`PadFriction`, or a friction law without pads.
    UnknownDofError
        A pad the structure does not have.
    """

    structure: ModalModel
    drive: Drive | None
    pads: tuple
    friction: PadFriction | None

    def __post_init__(self) -> None:
        if not isinstance(self.structure, ModalModel):
            raise ValueError("NonlinearAxis.structure must be a ModalModel")
        if self.drive is not None and not isinstance(self.drive, Drive):
            raise ValueError("NonlinearAxis.drive must be a Drive or None")
        if self.friction is not None and not isinstance(self.friction, PadFriction):
            raise ValueError("NonlinearAxis.friction must be a PadFriction (e.g. LuGreFriction) "
                             "or None")
        object.__setattr__(self, "pads", tuple(self.pads))
        self.structure.index(list(self.pads))
        if self.friction is not None and not self.pads:
            raise ValueError("a friction law needs pads=(...)")


def _progress_printer(stream):
    state = {"last": -1}

    def report(t, total):
        pct = int(100 * t / total)
        if pct == state["last"]:
            return
        state["last"] = pct
        bar = "#" * (pct // 4) + "-" * (25 - pct // 4)
        stream.write(f"\r  [{bar}] {pct:3d} %  t = {t:6.2f} / {total:g} s")
        if pct >= 100:
            stream.write("\n")
        stream.flush()

    return report


def _steps(value: float, h: float, what: str) -> int:
    k = round(value / h)
    if k < 1 or abs(k * h - value) > 1e-9 * value:
        raise ValueError(f"{what} ({value:g} s) must be a whole multiple of the step {h:g} s")
    return int(k)


def simulate(axis: NonlinearAxis, scenario: Scenario, *, step: float = DEFAULT_STEP,
             record_step: float = DEFAULT_RECORD_STEP, tolerance: float = DEFAULT_TOLERANCE,
             window=(), progress=False, record=None) -> SimulationResult:
    """Integrate the nonlinear axis through a scenario, from rest.

    The linear part (:func:`~servotune.simulate.system.axis_system`) is diagonalised once and
    integrated exactly; the friction remainders at the pads are collocated implicitly (Radau)
    within each step (:mod:`servotune.simulate.integrator`).

    Parameters
    ----------
    axis : NonlinearAxis
        Structure, drive, pads and friction law.
    scenario : Scenario
        See :mod:`servotune.simulate.scenario` (sine sweeps, moves, sinusoids, circles, custom);
        its duration must be a whole multiple of ``step``.
    step : float
        Base integration step [s] (default 2.5e-4 s, 40 steps per cycle at 100 Hz). The linear
        dynamics are exact for any step; the step resolves the excitation. Where the friction
        needs it (break-away, reversals, stick-slip) steps are halved, down to step/256. With a
        digital drive the step is the largest whole fraction of the current controller's
        period not above ``step`` (125 us for the default drive), so that every step starts
        on a sample: the controllers are computed at their sample instants, their outputs held
        in between (the motor voltage over each step).
    record_step : float
        Interval of the recorded histories [s], a whole multiple of ``step``.
    tolerance : float
        Local error allowed per step in the pad motion, relative to the Stribeck velocity vs
        and the presliding deflection Fs/sigma0 (default 1e-4: window energies within 0.1 %
        of a tight reference in the tests).
    window : sequence of float
        Extra times [s] where the energies are checkpointed (they are every 0.05 s anyway),
        e.g. the ends of an energy window.
    progress : bool or callable
        True: a progress bar on standard error; a callable gets ``(t, duration)``.
    record : sequence of str, optional
        The signals to record (names of the result's signals, outputs or inputs, e.g.
        ``("wp_x", "torque")``); None records all. The histories are the memory of a long run
        (a row per record step and signal); its inputs are held :data:`INPUT_WINDOW` steps at
        a time.

    Returns
    -------
    SimulationResult
        The histories every ``record_step`` (plant outputs, pad signals, the scenario's
        inputs), the cumulative works and the energies at the checkpoints, and statistics
        (steps, Newton iterations, wall time).

    Raises
    ------
    SimulationError
        When a step cannot be completed even at 1/256 of its length (or the state becomes
        non-finite); the exception carries the partial result (``.result``) and the time
        reached (``.time``).
    ValueError
        Bad arguments: ``axis`` not a :class:`NonlinearAxis` or ``scenario`` not a
        :class:`~servotune.simulate.scenario.Scenario`, a step or tolerance not positive, a
        duration, record step or window time not a whole multiple of the step, a scenario
        force on a DOF the structure does not have, a move of an axis without drive, or a
        name in ``record`` that is neither an output nor an input of the run.

    See Also
    --------
    servotune.frequency.compliance : The linearised axis' compliance, which a sweep checks.
    servotune.friction.equivalent.describing_function : The linear equivalent of the friction.
    servotune.analysis.loop_report : The loops' margins of the linearised axis.
    """
    if not isinstance(axis, NonlinearAxis):
        raise ValueError("simulate() needs a NonlinearAxis")
    if not isinstance(scenario, Scenario):
        raise ValueError("simulate() needs a Scenario (see servotune.simulate.scenario)")
    h = float(step)
    if not (math.isfinite(h) and h > 0):
        raise ValueError(f"step must be a positive number of seconds, got {step!r}")
    sps = 0
    if axis.drive is not None and not axis.drive.digital.is_continuous:
        # a digital drive: the steps land on the current controller's samples
        period = axis.drive.sampling.current_period
        sps = max(1, math.ceil(period / h - 1e-9))
        h = period / sps
    tolerance = float(tolerance)
    if not (math.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"tolerance must be a positive number, got {tolerance!r}")
    n_total = _steps(scenario.duration, h, "the scenario duration")
    record_every = _steps(record_step, h, "record_step")
    wall0 = time.perf_counter()
    # known inputs, sampled every h/3 (three spare samples for the cubic at the end), held a
    # window at a time; which of them the scenario has is found over the whole run first
    n_samples = 3 * n_total + 4

    def sampled(k0, k1):
        return scenario.signals(np.arange(k0, k1) * (h / 3.0))

    sig_names = {}
    for k0 in range(0, n_samples, 3 * INPUT_WINDOW):
        sig_names.update(dict.fromkeys(sampled(k0, min(n_samples, k0 + 3 * INPUT_WINDOW))))
    for name in sig_names:
        if name.startswith("f_") and name[2:] not in {signal_name(d) for d in
                                                      axis.structure.dofs}:
            raise ValueError(f"the scenario's force {name!r} acts on a DOF the structure does "
                             f"not have")
    if axis.drive is None and any(s in sig_names for s in ("x_ref", "v_ref", "a_ref")):
        raise ValueError("the scenario moves the axis but the axis has no drive")
    nonlinear = axis.friction is not None and axis.friction.nonlinear
    inputs = list(sig_names) + (["one"] if nonlinear else [])
    sysm = axis_system(axis.structure, axis.drive, axis.friction, axis.pads, scenario.speed,
                       inputs=inputs)
    kept = list(range(len(sysm.outputs)))
    if record is not None:
        names = [str(r) for r in ([record] if isinstance(record, str) else record)]
        unknown = [r for r in names if r not in sysm.outputs and r not in sig_names]
        if unknown:
            raise ValueError(f"record: {unknown} are not signals of this run; it has the "
                             f"outputs {', '.join(sysm.outputs)} and the inputs "
                             f"{', '.join(sig_names) or '(none)'}")
        kept = [i for i, o in enumerate(sysm.outputs) if o in names]
        recorded_inputs = [s for s in sig_names if s in names]
    else:
        recorded_inputs = list(sig_names)

    def window_of(n0, n1):
        # the samples that steps n0..n1-1 read: one before 3 n0 to three after 3 n1
        k0, k1 = max(0, 3 * n0 - 1), min(n_samples, 3 * n1 + 4)
        sig = sampled(k0, k1)
        cols = [sig[s] if s in sig else np.full(k1 - k0, 1.0 if s == "one" else 0.0)
                for s in sysm.inputs]
        rows = np.column_stack(cols) if cols else np.zeros((k1 - k0, 0))
        return k0, np.ascontiguousarray(rows, dtype=float)

    data = _prepare(sysm, h, axis, scenario)
    for key in ("cot_re", "cot_im"):
        data[key] = np.ascontiguousarray(data[key][:, kept])
    for key in ("dou", "dor"):
        data[key] = np.ascontiguousarray(data[key][kept])
    w_end = min(n_total, INPUT_WINDOW)
    s_base, samples = window_of(0, w_end)
    nr = data["br"].shape[1]
    m = data["lam"].size
    xr = np.zeros(m)
    xm = np.zeros(m)
    rparams = data["rparams"]
    n_pads_power = len(sysm.pads)
    # the remainders at rest (v = z = 0); remainder input k is component k // n_pads
    r_last = np.zeros(2 * nr)
    for k in range(nr):
        r_last[k] = r_last[nr + k] = data["remainder"](k // n_pads_power, 0.0, 0.0,
                                                       rparams)[0]
    energy = np.zeros(integrator.N_POWERS)
    power = np.zeros(integrator.N_POWERS)
    integrator._powers(xr, xm, samples[0], r_last[nr:], data["cpt_re"], data["cpt_im"],
                       data["dpu"], data["dpr"], data["n_force"], data["force_idx"],
                       n_pads_power, np.empty(data["cpt_re"].shape[1]), power)
    # checkpoints: a regular grid plus the requested window ends
    cp_every = max(1, round(CHECKPOINT / h))
    bounds = set(range(0, n_total, cp_every)) | {n_total}
    for tw in window:
        k = round(float(tw) / h)
        if not 0 <= k <= n_total or abs(k * h - float(tw)) > 1e-9 * max(1.0, abs(tw)):
            raise ValueError(f"window time {tw} s must be a multiple of the step within "
                             f"[0, {scenario.duration}] s")
        bounds.add(k)
    bounds = sorted(bounds)
    n_rec = n_total // record_every
    # by columns: each recorded signal is a contiguous column, handed out without a copy
    rec = np.zeros((n_rec + 1, data["cot_re"].shape[1]), order="F")
    rec_work = np.zeros((n_rec + 1, integrator.N_POWERS))
    rec[0] = data["dou"] @ samples[0] + (data["dor"] @ r_last[nr:] if nr else 0.0)
    cps_t, cps_work, cps_struct, cps_bristle = [], [], [], []
    stats = np.zeros(4, dtype=np.int64)
    report = None
    if progress is True:
        report = _progress_printer(sys.stderr)
    elif callable(progress):
        report = progress

    def checkpoint(n):
        cps_t.append(n * h)
        cps_work.append(energy.copy())
        # (no BLAS here: waking its threads between kernel calls costs milliseconds)
        cps_struct.append(0.5 * integrator.sum_of_squares(*data["energy_rows"], xr, xm))
        cps_bristle.append(0.5 * integrator.sum_of_squares(*data["bristle_rows"], xr, xm))

    checkpoint(0)
    failed_at = None
    level = 0
    w = data["w"]
    data["split"] = tuple(np.ascontiguousarray(part) for a in (
        data["bu"].T, data["br"].T, data["cy"].T, w.prop, w.alpha, w.beta)
        for part in (a.real, a.imag))
    kernel_time = 0.0
    kernel = integrator.chunk_kernel(data["remainder"])
    ctl = integrator.controller_arrays(sysm.controller, data, sysm.inputs, sps)
    for n0, n1 in itertools.pairwise(bounds):
        if n1 > w_end:
            w_end = min(n_total, max(n1, n0 + INPUT_WINDOW))
            s_base, samples = window_of(n0, w_end)
        tk = time.perf_counter()
        out = rec[1 + n0 // record_every:1 + n1 // record_every]
        out_w = rec_work[1 + n0 // record_every:1 + n1 // record_every]
        done, level = kernel(
            h, n0, n1, record_every, level, xr, xm, r_last, energy, power, samples, s_base,
            *data["split"], w.kmat, w.kerr, rparams,
            data["r_tol"], data["err_scale"], tolerance, data["cpt_re"], data["cpt_im"],
            data["dpu"], data["dpr"], data["n_force"], data["force_idx"], n_pads_power,
            data["cot_re"], data["cot_im"], data["dou"], data["dor"], out, out_w, stats, *ctl)
        kernel_time += time.perf_counter() - tk
        if done < n1 - n0 or not (np.all(np.isfinite(xr)) and np.all(np.isfinite(xm))):
            failed_at = n0 + done
            break
        checkpoint(n1)
        if report is not None:
            report(n1 * h, scenario.duration)
    wall = time.perf_counter() - wall0
    n_end = n_total if failed_at is None else failed_at
    n_keep = 1 + n_end // record_every
    t_rec = np.arange(n_keep) * (record_every * h)
    signals = {sysm.outputs[i]: rec[:n_keep, j] for j, i in enumerate(kept)}
    at_records = scenario.signals(t_rec) if recorded_inputs else {}
    for name in recorded_inputs:
        signals[name] = (np.array(at_records[name], dtype=float) if name in at_records
                         else np.zeros(n_keep))
    stat = {"step": h, "base_steps": int(n_end), "steps": int(stats[0]),
            "newton_iterations": int(stats[1]), "rejected_steps": int(stats[2]),
            "deepest_level": int(stats[3]), "tolerance": tolerance,
            "modes": int(m), "states": int(sysm.n_states),
            "eigenvector_condition": float(data["condition"]), "wall_time_s": wall,
            "integration_time_s": kernel_time,
            "real_time_factor": (n_end * h) / wall if wall > 0 else math.inf,
            "n_pads": n_pads_power,
            "controller_samples_per_step": 0 if not sps else 1.0 / sps}
    result = SimulationResult(
        t=t_rec, signals=signals, work=rec_work[:n_keep].copy(),
        checkpoints=np.array(cps_t), checkpoint_work=np.array(cps_work),
        structure_energy=np.array(cps_struct), bristle_energy=np.array(cps_bristle),
        pads=sysm.pads, friction=axis.friction.name if axis.friction else "none",
        scenario=scenario.name, sweep=scenario.sweep, stats=stat,
        complete=failed_at is None)
    if failed_at is not None:
        t_fail = failed_at * h
        raise SimulationError(
            f"the integration failed at t = {t_fail:.6g} s: the friction could not be resolved "
            f"even with the step halved {integrator.MAX_LEVEL} times (from {h:g} s to "
            f"{h / 2**integrator.MAX_LEVEL:.3g} s); the partial result up to there is in "
            f".result. Check the model and the scenario (a violent break-away, an unstable "
            f"loop), or try a smaller step or a larger tolerance",
            result=result, time=t_fail)
    return result


def _prepare(sysm: AxisSystem, h: float, axis: NonlinearAxis, scenario: Scenario) -> dict:
    """Modal form, weights and the projected matrices for the kernel."""
    a = sysm.system.A
    b = sysm.system.B
    nu = len(sysm.inputs)
    form = integrator.modal_form(a, times=(h / 3.0, h, 100.0 * h))
    vec, left = form.vectors, form.left
    bu = np.ascontiguousarray(left @ b[:, :nu])
    br = np.ascontiguousarray(left @ b[:, nu:])
    nr = br.shape[1]
    # the velocity and state each remainder input reads (remainder k: pad k % n_pads)
    cy = np.ascontiguousarray(np.vstack([sysm.remainder_velocity, sysm.remainder_state])
                              @ vec) if nr else np.zeros((0, vec.shape[1]), dtype=complex)
    weights = integrator.step_weights(form.lam, h, (cy, br) if nr else None)
    n_pads = len(sysm.pads)
    n_force = len(sysm.wp_force_inputs)
    n = sysm.n_states
    rows = np.vstack([sysm.wp_velocity.reshape(n_force, n), sysm.motor_rows,
                      sysm.force_rows.reshape(n_pads, n),
                      sysm.pad_velocity.reshape(n_pads, n), sysm.damping_rows])
    cp = rows @ vec
    dpu = np.zeros((rows.shape[0], nu))
    dpr = np.zeros((rows.shape[0], nr))
    dpu[n_force + 2:n_force + 2 + n_pads] = sysm.force_du
    if nr:
        dpr[n_force + 2:n_force + 2 + n_pads] = sysm.force_dr
    c, d = sysm.system.C, sysm.system.D
    friction = axis.friction
    if nr:
        rparams = np.ascontiguousarray(friction.remainder_parameters(scenario.speed),
                                       dtype=float)
        remainder = friction.remainder()
        r_tol = friction.newton_tolerance(h)
        # error scales of the remainders' velocities and states (by component)
        v_scale, z_scales = friction.error_scales()
        err_scale = np.concatenate([np.full(nr, v_scale),
                                    np.repeat(np.asarray(z_scales, dtype=float), n_pads)])
    else:
        rparams, remainder, r_tol = np.zeros(1), None, 0.0
        err_scale = np.zeros(0)
    meas = (sysm.measured_rows @ vec if sysm.measured_rows is not None
            else np.zeros((0, vec.shape[1]), dtype=complex))
    return {"meas_re": np.ascontiguousarray(meas.T.real),
            "meas_im": np.ascontiguousarray(meas.T.imag),
            "lam": form.lam, "vectors": vec, "condition": form.condition, "bu": bu, "br": br,
            "cy": cy, "w": weights, "cpt_re": np.ascontiguousarray(cp.T.real),
            "cpt_im": np.ascontiguousarray(cp.T.imag), "dpu": dpu, "dpr": dpr,
            "n_force": n_force, "force_idx": np.array(sysm.wp_force_inputs, dtype=np.int64),
            "cot_re": np.ascontiguousarray((c @ vec).T.real),
            "cot_im": np.ascontiguousarray((c @ vec).T.imag),
            "dou": np.ascontiguousarray(d[:, :nu]),
            "dor": np.ascontiguousarray(d[:, nu:]), "rparams": rparams,
            "remainder": remainder, "r_tol": r_tol, "err_scale": err_scale,
            "energy_rows": _split(sysm.energy_rows @ vec),
            "bristle_rows": _split(sysm.spring_rows @ vec)}


def _split(a):
    return np.ascontiguousarray(a.real), np.ascontiguousarray(a.imag)
