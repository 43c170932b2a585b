"""Nonlinear sweep simulation: servotune's integrator against scipy's solve_ivp on the whole sweep.

Task: the bundled paper axis (41 DOFs, four LuGre pads) with its drive in continuous time
(``Axis.with_continuous_drive()``: the paper's continuous cascade, as its Table 3) under the
paper's sine-sweep force at the work piece, 10 -> 100 Hz in 20 s, standing still, 2000 N peak
to peak (the pads slip around the resonance): Table 3, trial 13. The continuous drive because
the baseline's ODE (:mod:`servotune.simulate.reference`) integrates the continuous linear part
only: it has no digital controllers, so with the axis' own digital drive it would not be the
system servotune simulates.

* servotune: :func:`servotune.simulate.simulate` (exponential collocation, numba), default
  settings (step 2.5e-4 s, tolerance 1e-4). Its time is the wall time of the call, set-up
  included (the interconnection of the linear part, its modal form, the step weights) and
  reported apart.
* baselines: ``scipy.integrate.solve_ivp`` with LSODA, Radau and BDF, each given the analytic
  Jacobian, on the same ODE (:func:`servotune.simulate.reference.ode_model`, works as extra
  states) with the sweep force written in closed form in its right-hand side: the ODE's inputs
  function (which evaluates ``Scenario.signals(t)`` at every call: a dict, broadcasts, finite
  checks) replaced by ``u[k] = (F_pp / 2) sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T)))`` and the
  constant 1, the phase as :func:`servotune.simulate.sweep_phase` writes it (asserted equal to
  ``scenario.signals(t)["f_wp_x"]`` to 1e-12 of the amplitude on 4001 times, and the
  right-hand sides equal, before any timing). Set-up (building that ODE) included.

Equal accuracy, decided on a 0.1 s segment around the resonance (45 -> 45.45 Hz at the sweep's
rate), where LSODA at rtol 1e-10 is affordable as the reference: each scipy method runs at the
loosest rtol (from 1e-1 down) whose four works are within the error servotune reaches there (at
least 1e-3 relative). Then every method runs the whole 20 s sweep at that setting; the full-sweep
errors are measured against servotune at tolerance 1e-7 and a quarter of the step (itself
checked against the LSODA reference on the segment). ``speedup`` is the best scipy method's
time over servotune's on the whole sweep, both with their set-up.

Reported beside it, not in the speedup (scipy has no counterpart): the real-time factor of
servotune's simulation of the same sweep with the axis' digital drive (``[drive.sampling]``:
the controllers computed at their sample instants inside the integrator, the motor voltage held
over each current period; the step is then the largest whole fraction of the current period
not above the given one, 125 us here), ``real_time_factor_digital_drive``. The axis' own
velocity-loop gain is unstable as a sampled-data loop, so the digital run softens it by the
tuner's factors (``servotune.tuning.solve.SOFTENING``) until the loop is stable with the
standing (stiction) and the viscous-only contact (:class:`servotune.digital.SampledAxis`),
as the tuner's first start does.

BLAS and OpenMP are held to one thread for every method (before numpy is imported): the
matrices are small, and on a shared machine threaded BLAS mostly waits for its threads.

Run: ``python benchmarks/simulate_sweep.py [--json] [--baselines LSODA,Radau,BDF] [--repeat N]
[--duration S]`` (the scipy runs of the whole sweep take minutes; ``--duration`` shortens the
sweep, at the same rate, for a quick check).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

from servotune import analysis  # noqa: E402
from servotune.axis import load_axis  # noqa: E402
from servotune.digital import SampledAxis  # noqa: E402
from servotune.simulate import (  # noqa: E402
    LuGreFriction,
    NonlinearAxis,
    simulate,
    sine_sweep,
)
from servotune.simulate.reference import ode_model  # noqa: E402
from servotune.simulate.setup import axis_setup  # noqa: E402
from servotune.tuning.solve import SOFTENING  # noqa: E402

__all__ = ["main"]

AXIS = Path(__file__).resolve().parents[1] / "models" / "paper_x_axis"
FORCE_PP = 2000.0
DURATION = 20.0
RATE = 90.0 / DURATION   # Hz/s of the paper's sweep
RTOLS = (1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)


def _works_error(works, ref):
    return float(np.abs(works - ref).max() / np.abs(ref).max())


def _inputs_cell(ode):
    """The closure cell of the inputs function that ``ode.rhs``, ``ode.jac`` and ``ode.outputs``
    call, and the names of the inputs in its order."""
    rhs = ode.rhs
    cell = dict(zip(rhs.__code__.co_freevars, rhs.__closure__, strict=True))["inputs"]
    inputs = cell.cell_contents
    sysm = dict(zip(inputs.__code__.co_freevars, inputs.__closure__, strict=True))["sysm"]
    sysm = sysm.cell_contents
    return cell, list(sysm.inputs)


def _closed_form(ode, scenario):
    """The ODE with the sweep force in closed form in its right-hand side (returned).

    :func:`servotune.simulate.reference.ode_model` evaluates the inputs through the scenario's
    signals (:meth:`servotune.simulate.Scenario.signals`: a dict, broadcasts and finite checks)
    at every call; a user writing the right-hand side for this sweep writes the force itself.
    The inputs function is replaced by ``u = u0.copy(); u[k] = (F_pp / 2) sin(phase(t))``, the
    phase as :func:`servotune.simulate.sweep_phase` writes it. Standing still, the inputs are
    the force and the constant 1 only.
    """
    cell, names = _inputs_cell(ode)
    if not set(names) <= {"f_wp_x", "one"} or scenario.motion is not None:
        raise RuntimeError(f"closed form written for the standing sweep force only: {names}")
    f0, f1, _, duration, amplitude = scenario.sweep
    k = names.index("f_wp_x")
    u0 = np.array([1.0 if name == "one" else 0.0 for name in names])
    two_pi, df, sin = 2.0 * math.pi, f1 - f0, math.sin

    def inputs(t):
        u = u0.copy()
        u[k] = amplitude * sin(two_pi * (f0 * t + 0.5 * df * t * t / duration))
        return u

    cell.cell_contents = inputs
    return ode


def _check_closed_form(axis, scenario, n=4001):
    """Assert that the closed-form force equals ``scenario.signals(t)["f_wp_x"]`` (and the
    whole input vector the scenario's inputs) on n times to 1e-12 of the amplitude, and the
    right-hand sides agree; returns the largest difference over the amplitude."""
    ode = ode_model(axis, scenario)
    cell, names = _inputs_cell(ode)
    original = cell.cell_contents
    _closed_form(ode, scenario)
    closed = cell.cell_contents
    t = np.linspace(0.0, scenario.duration, n)
    force = scenario.signals(t)["f_wp_x"]
    u_closed = np.array([closed(float(ti)) for ti in t])
    u_orig = np.array([original(float(ti)) for ti in t])
    scale = float(np.abs(force).max())
    err = float(np.abs(u_closed[:, names.index("f_wp_x")] - force).max() / scale)
    assert err <= 1e-12, f"the closed-form force differs from the scenario's by {err:.2e}"
    assert np.abs(u_closed - u_orig).max() <= 1e-12 * scale, "closed-form inputs differ"
    y = np.linspace(-1e-6, 1e-6, ode.n)
    for ti in t[:: max(1, n // 50)]:
        cell.cell_contents = original
        ref = ode.rhs(float(ti), y)
        cell.cell_contents = closed
        assert np.allclose(ode.rhs(float(ti), y), ref, rtol=1e-12, atol=1e-300)
    return err


def _scipy_run(axis, scenario, method, rtol):
    """solve_ivp over the scenario, set-up (the ODE, the closed-form force) included;
    (time, works, success, nfev)."""
    t0 = time.perf_counter()
    ode = _closed_form(ode_model(axis, scenario), scenario)
    sol = solve_ivp(ode.rhs, (0.0, scenario.duration), np.zeros(ode.n), method=method,
                    jac=ode.jac, rtol=rtol, atol=rtol * 1e-6, t_eval=[scenario.duration])
    return time.perf_counter() - t0, sol.y[-4:, -1], bool(sol.success), int(sol.nfev)


def _ours(axis, scenario, **kwargs):
    t0 = time.perf_counter()
    run = simulate(axis, scenario, **kwargs)
    wall = time.perf_counter() - t0
    return wall, run


def _digital_axis(axis):
    """The axis with its digital drive, the velocity-loop Kp softened (``SOFTENING``) until the
    sampled-data loop is stable with the stiction and the viscous-only contact; (axis, factor)."""
    drive = axis.require_drive()
    contacts = [analysis.axis_contact(axis, kind) for kind in ("stiction", "viscous")]
    for factor in (1.0, *SOFTENING):
        d = dataclasses.replace(drive, velocity_loop=dataclasses.replace(
            drive.velocity_loop, kp=drive.velocity_loop.kp * factor))
        if all(SampledAxis(axis.structure, d, c, axis.pads).is_stable() for c in contacts):
            return dataclasses.replace(axis, drive=d), factor
    raise RuntimeError("no softened velocity loop is stable with the digital drive")


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--segment", type=float, default=0.1,
                        help="length [s] of the calibration segment (default 0.1)")
    parser.add_argument("--baselines", default="LSODA,Radau,BDF",
                        help="scipy methods, comma-separated (default LSODA,Radau,BDF)")
    parser.add_argument("--repeat", type=int, default=3,
                        help="repeats of servotune's full sweep (best taken)")
    parser.add_argument("--duration", type=float, default=DURATION,
                        help=f"sweep length [s] at the paper's rate (default {DURATION:g}: "
                             "10 -> 100 Hz; shorter for a quick check)")
    args = parser.parse_args(argv)
    methods = [m.strip() for m in args.baselines.split(",") if m.strip()]
    own = load_axis(AXIS)
    # the paper's continuous drive, as its Table 3: the baseline's ODE has no digital
    # controllers, so both methods integrate the continuous model
    setup = axis_setup(own.with_continuous_drive())
    axis = NonlinearAxis(setup.structure, setup.drive, setup.pads, LuGreFriction(setup.lugre))
    duration = args.duration
    full = sine_sweep(FORCE_PP, 10.0, 10.0 + RATE * duration, duration)

    # first call in this process: loads (or compiles) the kernels
    first_wall, _ = _ours(axis, sine_sweep(FORCE_PP, 45.0, 45.5, 0.01))

    # calibration on the segment
    seg = sine_sweep(FORCE_PP, 45.0, 45.0 + RATE * args.segment, args.segment)
    closed_form_error = max(_check_closed_form(axis, seg), _check_closed_form(axis, full))
    ode = ode_model(axis, seg)
    t0 = time.perf_counter()
    ref = solve_ivp(ode.rhs, (0, args.segment), np.zeros(ode.n), method="LSODA", jac=ode.jac,
                    rtol=1e-10, atol=1e-16)
    t_ref = time.perf_counter() - t0
    ref_works = ref.y[-4:, -1]
    _, seg_ours = _ours(axis, seg)
    err_ours = _works_error(seg_ours.work[-1], ref_works)
    _, seg_tight = _ours(axis, seg, tolerance=1e-7, step=2.5e-4 / 4, record_step=5e-4)
    err_tight = _works_error(seg_tight.work[-1], ref_works)
    target = max(err_ours, 1e-3)
    calibrated = {}
    for method in methods:
        for rtol in RTOLS:
            elapsed, works, ok, nfev = _scipy_run(axis, seg, method, rtol)
            err = _works_error(works, ref_works)
            if ok and err <= target:
                calibrated[method] = {"rtol": rtol, "segment_time_s": elapsed,
                                      "segment_works_error": err, "segment_nfev": nfev}
                break

    # the whole sweep
    runs = [_ours(axis, full) for _ in range(max(1, args.repeat))]
    wall, run = min(runs, key=lambda r: r[0])
    kernel = run.stats["integration_time_s"]
    _, tight = _ours(axis, full, tolerance=1e-7, step=2.5e-4 / 4, record_step=5e-4)
    tight_works = tight.work[-1]
    err_full = _works_error(run.work[-1], tight_works)
    scipy_full = {}
    for method, cal in calibrated.items():
        elapsed, works, ok, nfev = _scipy_run(axis, full, method, cal["rtol"])
        scipy_full[method] = {"rtol": cal["rtol"], "time_s": elapsed, "success": ok,
                              "nfev": nfev, "works_error": _works_error(works, tight_works),
                              "calibration": cal}
    # the same sweep with the digital drive (servotune only: the real-time factor)
    digital, factor = _digital_axis(own)
    dsetup = axis_setup(digital)
    daxis = NonlinearAxis(dsetup.structure, dsetup.drive, dsetup.pads,
                          LuGreFriction(dsetup.lugre))
    d_first, _ = _ours(daxis, sine_sweep(FORCE_PP, 45.0, 45.5, 0.01))
    d_runs = [_ours(daxis, full) for _ in range(max(1, args.repeat))]
    d_wall, d_run = min(d_runs, key=lambda r: r[0])
    d_kernel = d_run.stats["integration_time_s"]
    finished = {m: v for m, v in scipy_full.items() if v["success"]}
    best_method = min(finished, key=lambda m: finished[m]["time_s"]) if finished else None
    best = finished[best_method]["time_s"] if best_method else float("nan")
    result = {
        "axis": str(AXIS), "drive": "continuous (Axis.with_continuous_drive())",
        "force_pp_n": FORCE_PP,
        "sweep": f"10 -> {10.0 + RATE * duration:g} Hz in {duration:g} s",
        "baseline": f"scipy solve_ivp, best of {', '.join(methods)} at equal accuracy, "
                    "analytic Jacobian, the sweep force in closed form in the right-hand side",
        "closed_form_force_max_relative_difference": closed_form_error,
        "speedup": best / wall,
        "speedup_integration_only": best / kernel,
        "speedups_by_method": {m: v["time_s"] / wall for m, v in finished.items()},
        "real_time_factor": duration / wall,
        "real_time_factor_integration_only": duration / kernel,
        "real_time_factor_digital_drive": duration / d_wall,
        "servotune": {
            "time_s": wall, "setup_and_checkpoints_s": wall - kernel,
            "integration_time_s": kernel, "first_call_in_process_s": first_wall,
            "steps": run.stats["steps"], "newton_iterations": run.stats["newton_iterations"],
            "rejected_steps": run.stats["rejected_steps"],
            "works": run.work[-1].tolist(),
            "works_error_vs_tight": err_full,
        },
        "servotune_digital_drive": {
            "drive": "the axis' digital drive (sample-and-hold controllers), velocity-loop Kp "
                     f"x {factor:g} = {daxis.drive.velocity_loop.kp:g} (softened until stable)",
            "periods_s": {"current": daxis.drive.sampling.current_period,
                          "velocity": daxis.drive.sampling.velocity_period,
                          "position": daxis.drive.sampling.position_period},
            "time_s": d_wall, "setup_and_checkpoints_s": d_wall - d_kernel,
            "integration_time_s": d_kernel, "first_call_in_process_s": d_first,
            "real_time_factor": duration / d_wall,
            "real_time_factor_integration_only": duration / d_kernel,
            "step_s": d_run.stats["step"], "steps": d_run.stats["steps"],
            "newton_iterations": d_run.stats["newton_iterations"],
            "rejected_steps": d_run.stats["rejected_steps"],
            "controller_samples_per_step": d_run.stats.get("controller_samples_per_step"),
            "works": d_run.work[-1].tolist(),
        },
        "servotune_tight_reference": {"tolerance": 1e-7, "step_s": 2.5e-4 / 4,
                                      "segment_works_error_vs_lsoda_1e-10": err_tight,
                                      "works": tight_works.tolist()},
        "scipy": scipy_full,
        "best_scipy_method": best_method,
        "calibration": {"segment_s": args.segment, "reference": "LSODA rtol 1e-10",
                        "reference_time_s": t_ref, "servotune_works_error": err_ours,
                        "accuracy_target": target},
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(f"sweep {result['sweep']}, {FORCE_PP:g} N p-p, standing still, continuous "
              "drive:")
        print(f"  servotune   {wall:8.3f} s (set-up and checkpoints {wall - kernel:.3f} s), "
              f"real-time factor {duration / wall:.1f}, works error {err_full:.2g}")
        for m, v in scipy_full.items():
            print(f"  scipy {m:6} {v['time_s']:8.1f} s (rtol {v['rtol']:g}), works error "
                  f"{v['works_error']:.2g}, speedup {v['time_s'] / wall:.1f}")
        print(f"  speedup over the best scipy method: {best / wall:.1f}")
        print(f"the same sweep with the digital drive (velocity Kp x {factor:g}): servotune "
              f"{d_wall:.3f} s, real-time factor {duration / d_wall:.1f}")
    return result


if __name__ == "__main__":
    main()
