"""LuGre describing function: servotune's exponential integrator against scipy's stiff solvers.

Task: the energy dissipated per cycle (and so Ceq = E / (pi w A^2)) of the paper's LuGre contact
(Bianchi et al. 2014, table after Fig 8) in periodic steady state under x = A sin(w t), for 20
amplitudes from 0.2 to 50 um at 20 Hz.

* servotune: :func:`servotune.friction.describing_function` (exponential integrator in the
  bristle time, all amplitudes at once, periodic state closed in one period).
* baselines: ``scipy.integrate.solve_ivp`` with Radau (analytic Jacobian) and with LSODA, one
  amplitude at a time, given the same advantages: the integration is split at the velocity
  reversals, and the periodic state is found by shooting (one period carrying the bristle time
  as an extra state, z0 = B / (1 - P)), then one period more accumulates the energy and Keq.

Accuracy is made equal first: a reference is computed with Radau at rtol = 1e-11, and each
method's cheapest setting (steps per period; rtol) whose energies are all within 1e-4 relative
of it is the one timed. Run: ``python benchmarks/friction_describing_function.py [--json]``.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import time

import numpy as np
from _timing import best_time
from scipy.integrate import solve_ivp

from servotune.friction import BIANCHI2014, describing_function

__all__ = ["main"]

TOLERANCE = 1e-4


def scipy_energy(p, amplitude, omega, method, rtol):
    """Energy per cycle and Keq of the periodic LuGre state by solve_ivp (shooting)."""
    period = 2 * math.pi / omega
    knots = (-period / 4, period / 4, 3 * period / 4)
    s0, s1, s2, fc, dfs, vs, delta = (p.sigma0, p.sigma1, p.sigma2, p.fc, p.fs - p.fc, p.vs,
                                      p.delta)

    def vel(t):
        return amplitude * omega * math.cos(omega * t)

    def rate(v):
        return s0 * abs(v) / (fc + dfs * math.exp(-abs(v / vs) ** delta))

    def rhs1(t, y):
        v = vel(t)
        a = rate(v)
        return [v - a * y[0], a]

    def jac1(t, y):
        return [[-rate(vel(t)), 0.0], [0.0, 0.0]]

    def rhs2(t, y):
        v = vel(t)
        zd = v - rate(v) * y[0]
        f = s0 * y[0] + s1 * zd + s2 * v
        return [zd, f * v, f * math.sin(omega * t)]

    def jac2(t, y):
        v = vel(t)
        a = rate(v)
        df = s0 - s1 * a
        return [[-a, 0.0, 0.0], [df * v, 0.0, 0.0], [df * math.sin(omega * t), 0.0, 0.0]]

    zs = p.fs / p.sigma0
    options = {"method": method, "rtol": rtol}
    y = [0.0, 0.0]
    for a, b in itertools.pairwise(knots):
        extra = {"jac": jac1} if method == "Radau" else {}
        y = solve_ivp(rhs1, (a, b), y, atol=[rtol * zs * 1e-2, rtol * 1e-2], **options,
                      **extra).y[:, -1]
    y = [y[0] / -math.expm1(-y[1]), 0.0, 0.0]
    for a, b in itertools.pairwise(knots):
        extra = {"jac": jac2} if method == "Radau" else {}
        y = solve_ivp(rhs2, (a, b), y, atol=[rtol * zs * 1e-2, rtol * 1e-2 * p.fs * amplitude,
                                             rtol * 1e-2 * p.fs * period],
                      **options, **extra).y[:, -1]
    return y[1], y[2] * omega / (math.pi * amplitude)


def scipy_all(p, amplitudes, omega, method, rtol):
    return np.array([scipy_energy(p, a, omega, method, rtol)[0] for a in amplitudes])


def servotune_all(p, amplitudes, omega, n_steps):
    ceq, _ = describing_function(p, amplitudes, omega, n_steps=n_steps)
    return ceq * math.pi * omega * amplitudes**2



def calibrate(fun, settings, reference):
    """The first setting (cheapest first) whose energies are within TOLERANCE of reference."""
    for s in settings:
        err = float(np.max(np.abs(fun(s) / reference - 1.0)))
        if err <= TOLERANCE:
            return s, err
    raise RuntimeError("no setting reached the tolerance")


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--repeats", type=int, default=3, help="timing repeats (best taken)")
    args = parser.parse_args(argv)

    p = BIANCHI2014
    omega = 2 * math.pi * 20.0
    amplitudes = np.geomspace(0.2e-6, 50e-6, 20)
    t0 = time.perf_counter()
    reference = scipy_all(p, amplitudes, omega, "Radau", 1e-11)
    t_reference = time.perf_counter() - t0
    fine = servotune_all(p, amplitudes, omega, 8192)

    n_steps, err_st = calibrate(lambda n: servotune_all(p, amplitudes, omega, n),
                                [16, 32, 64, 128, 256, 512, 1024], reference)
    rtols = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9]
    rtol_radau, err_radau = calibrate(lambda r: scipy_all(p, amplitudes, omega, "Radau", r),
                                      rtols, reference)
    rtol_lsoda, err_lsoda = calibrate(lambda r: scipy_all(p, amplitudes, omega, "LSODA", r),
                                      rtols, reference)

    t_st = best_time(lambda: servotune_all(p, amplitudes, omega, n_steps), 10 * args.repeats)[0]
    t_radau = best_time(lambda: scipy_all(p, amplitudes, omega, "Radau", rtol_radau),
                        args.repeats)[0]
    t_lsoda = best_time(lambda: scipy_all(p, amplitudes, omega, "LSODA", rtol_lsoda),
                        args.repeats)[0]
    t_default = best_time(lambda: servotune_all(p, amplitudes, omega, 1024), 10 * args.repeats)[0]
    baseline = min(t_radau, t_lsoda)
    result = {
        "task": "LuGre energy per cycle, Bianchi 2014 parameters, 20 amplitudes 0.2-50 um, 20 Hz",
        "tolerance_relative": TOLERANCE,
        "reference": "solve_ivp Radau rtol 1e-11",
        "reference_time_s": t_reference,
        "servotune_8192_steps_vs_reference_max_relative": float(
            np.max(np.abs(fine / reference - 1.0))),
        "servotune_steps_per_period": n_steps,
        "servotune_max_relative_error": err_st,
        "servotune_time_s": t_st,
        "servotune_default_1024_steps_time_s": t_default,
        "radau_rtol": rtol_radau,
        "radau_max_relative_error": err_radau,
        "radau_time_s": t_radau,
        "lsoda_rtol": rtol_lsoda,
        "lsoda_max_relative_error": err_lsoda,
        "lsoda_time_s": t_lsoda,
        "baseline": "radau" if t_radau <= t_lsoda else "lsoda",
        "speedup": baseline / t_st,
        "speedup_default_steps": baseline / t_default,
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for key, value in result.items():
            print(f"{key:>48}: {value}")
    return result


if __name__ == "__main__":
    main()
