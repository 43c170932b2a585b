"""Nonlinear sweep simulation: servotune's integrator against scipy's solve_ivp at equal accuracy.

Task: the bundled paper axis (41 DOFs, drive, four LuGre pads; 89 states) under a sine-sweep
force at the work piece, standing still, 2000 N peak to peak (the pads slip near resonance).

* servotune: :func:`servotune.simulate.simulate` (exponential collocation, numba), default
  settings (step 2.5e-4 s, tolerance 1e-4).
* baselines: ``scipy.integrate.solve_ivp`` with LSODA and with Radau given the analytic
  Jacobian, on the same ODE (:mod:`servotune.simulate.reference`, works as extra states).

Equal accuracy: a reference is computed by LSODA at rtol 1e-10 on a segment of the sweep around
the resonance (``--segment`` seconds of a 45 -> 65 Hz sweep at the 20 s sweep's rate); each
scipy method is timed at the loosest rtol whose four works are within the error servotune
reaches (at least 1e-3 relative). scipy cannot afford the full 20 s (its time is extrapolated
from the segment, and said so); servotune's real-time factor is measured on the full
10 -> 100 Hz, 20 s sweep. Run: ``python benchmarks/simulate_sweep.py [--json]``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from servotune.axis import load_axis
from servotune.simulate import LuGreFriction, NonlinearAxis, simulate, sine_sweep
from servotune.simulate.reference import ode_model
from servotune.simulate.setup import axis_setup

__all__ = ["main"]

AXIS = Path(__file__).resolve().parents[1] / "models" / "paper_x_axis"
FORCE_PP = 2000.0
RATE = 90.0 / 20.0   # Hz/s of the paper's sweep


def _works_error(works, ref):
    return float(np.abs(works - ref).max() / np.abs(ref).max())


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--segment", type=float, default=0.1,
                        help="length [s] of the segment compared with scipy (default 0.1)")
    args = parser.parse_args(argv)
    setup = axis_setup(load_axis(AXIS))
    axis = NonlinearAxis(setup.structure, setup.drive, setup.pads, LuGreFriction(setup.lugre))
    seg = sine_sweep(FORCE_PP, 45.0, 45.0 + RATE * args.segment, args.segment)
    simulate(axis, seg)                                         # compile (numba cache)
    ode = ode_model(axis, seg)
    y0 = np.zeros(ode.n)
    t0 = time.perf_counter()
    ref = solve_ivp(ode.rhs, (0, args.segment), y0, method="LSODA", jac=ode.jac, rtol=1e-10,
                    atol=1e-16)
    t_ref = time.perf_counter() - t0
    ref_works = ref.y[-4:, -1]
    t0 = time.perf_counter()
    ours = simulate(axis, seg)
    t_ours = time.perf_counter() - t0
    err_ours = _works_error(ours.work[-1], ref_works)
    target = max(err_ours, 1e-3)
    baselines = {}
    for method in ("LSODA", "Radau"):
        for rtol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8):
            t0 = time.perf_counter()
            sol = solve_ivp(ode.rhs, (0, args.segment), y0, method=method, jac=ode.jac,
                            rtol=rtol, atol=rtol * 1e-6)
            elapsed = time.perf_counter() - t0
            err = _works_error(sol.y[-4:, -1], ref_works)
            if sol.success and err <= target:
                baselines[method] = {"rtol": rtol, "time_s": elapsed, "works_error": err,
                                     "nfev": int(sol.nfev)}
                break
    best = min(v["time_s"] for v in baselines.values()) if baselines else float("nan")
    full = sine_sweep(FORCE_PP, 10.0, 100.0, 20.0)
    t0 = time.perf_counter()
    run = simulate(axis, full)
    t_full = time.perf_counter() - t0
    result = {
        "axis": str(AXIS), "force_pp_n": FORCE_PP, "segment_s": args.segment,
        "reference": {"method": "LSODA rtol 1e-10", "time_s": t_ref},
        "servotune": {"time_s": t_ours, "works_error": err_ours,
                      "steps": ours.stats["steps"]},
        "scipy": baselines,
        "accuracy_target": target,
        "speedup": {m: v["time_s"] / t_ours for m, v in baselines.items()},
        "speedup_vs_best_scipy": best / t_ours,
        "full_sweep": {"duration_s": 20.0, "time_s": t_full,
                       "integration_time_s": run.stats["integration_time_s"],
                       "real_time_factor": 20.0 / t_full,
                       "scipy_best_extrapolated_s": best * 20.0 / args.segment},
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(f"segment of {args.segment:g} s around the resonance, {FORCE_PP:g} N p-p:")
        print(f"  servotune   {t_ours:8.3f} s  works error {err_ours:.2g}")
        for m, v in baselines.items():
            print(f"  scipy {m:6} {v['time_s']:8.3f} s  works error {v['works_error']:.2g} "
                  f"(rtol {v['rtol']:g}), speedup {v['time_s'] / t_ours:.1f}")
        print(f"  speedup over the best scipy method: {best / t_ours:.1f}")
        print(f"full 20 s sweep: {t_full:.2f} s wall, real-time factor {20.0 / t_full:.1f} "
              f"(scipy extrapolated: {best * 20.0 / args.segment:.0f} s)")
    return result


if __name__ == "__main__":
    main()
