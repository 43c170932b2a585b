"""LuGre describing function: servotune's exponential integrator against scipy's stiff solvers.

Task: the energy dissipated per cycle (and so Ceq = E / (pi w A^2)) of the paper's LuGre contact
(Bianchi et al. 2014, table after Fig 8) in periodic steady state under x = A sin(w t), for 20
amplitudes from 0.2 to 50 um at 20 Hz.

* servotune: :func:`servotune.friction.describing_function` at its default steps per period
  (exponential integrator in the bristle time, all amplitudes at once, half a period by
  antisymmetry, phase steps graded towards the reversals).
* baselines: ``scipy.integrate.solve_ivp`` with LSODA and with Radau, both given the analytic
  Jacobian (``jac=``), one amplitude at a time, given the same advantages: the integration is
  split at the velocity reversals, and the periodic state is found by shooting (one period
  carrying the bristle time as an extra state, z0 = B / (1 - P)), then one period more
  accumulates the energy and Keq.

Accuracy is made equal first: a reference is computed with Radau at rtol = 1e-11; servotune's
default reaches some error against it, and each scipy method runs at the loosest rtol of the
1-2-5 ladder 1e-1, 5e-2, 2e-2, 1e-2, ..., 2e-10, 1e-10 (tried loosest first) whose energies
are all within that error (at least 1e-9, as the ladder ends at 1e-10); atol follows rtol.
``speedup`` is the faster scipy method's time over servotune's at these settings. A second
comparison gives each method its cheapest setting within 1e-4 (servotune's steps per period
16, 32, ..., 1024; scipy the same rtol ladder). All timings, servotune's and scipy's, are the
best of the same number of repeats (``--repeats``, default 10), each repeat computing all 20
amplitudes.

``--convergence`` adds the convergence study behind the default steps per period: the error
of N = Keq + j w Ceq against 65,536 steps for three parameter sets, 21 amplitudes (0.01 to 1000
Fs/sigma0) and 7 frequencies (1 Hz to 1 kHz), for the graded steps of ``describing_function``
and for the uniform steps of ``lugre_cycle``.

BLAS and OpenMP are held to one thread (before numpy is imported) for all methods.
Run: ``python benchmarks/friction_describing_function.py [--json] [--convergence]``.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import itertools  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from _timing import best_time  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

from servotune.friction import (  # noqa: E402
    BIANCHI2014,
    LuGreParameters,
    describing_function,
    lugre_cycle,
)
from servotune.friction.equivalent import DESCRIBING_FUNCTION_STEPS  # noqa: E402

__all__ = ["main"]

TOLERANCE = 1e-4
# scipy's rtol ladder, loosest first: 1e-1, 5e-2, 2e-2, 1e-2, ..., 2e-10, 1e-10
RTOLS = [0.1] + [float(f"{m}e{e}") for e in range(-2, -11, -1) for m in (5, 2, 1)]


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
        y = solve_ivp(rhs1, (a, b), y, atol=[rtol * zs * 1e-2, rtol * 1e-2], jac=jac1,
                      **options).y[:, -1]
    y = [y[0] / -math.expm1(-y[1]), 0.0, 0.0]
    for a, b in itertools.pairwise(knots):
        y = solve_ivp(rhs2, (a, b), y, atol=[rtol * zs * 1e-2, rtol * 1e-2 * p.fs * amplitude,
                                             rtol * 1e-2 * p.fs * period],
                      jac=jac2, **options).y[:, -1]
    return y[1], y[2] * omega / (math.pi * amplitude)


def scipy_all(p, amplitudes, omega, method, rtol):
    return np.array([scipy_energy(p, a, omega, method, rtol)[0] for a in amplitudes])


def servotune_all(p, amplitudes, omega, n_steps):
    ceq, _ = describing_function(p, amplitudes, omega, n_steps=n_steps)
    return ceq * math.pi * omega * amplitudes**2



def calibrate(fun, settings, reference, tolerance):
    """The first setting (cheapest first) whose energies are within tolerance of reference."""
    for setting in settings:
        err = float(np.max(np.abs(fun(setting) / reference - 1.0)))
        if err <= tolerance:
            return setting, err
    return None, math.nan


def convergence_study(steps=(128, 256, 512, 1024, 2048, 4096)):
    """Largest error of N = Keq + j w Ceq (and of Ceq) against 65,536 steps, per parameter set
    and steps per period, for the graded and the uniform phase steps."""
    sets = {"bianchi2014": BIANCHI2014, "canudas1995": LuGreParameters.named("canudas1995"),
            "bianchi2014_vd_1mm_s": dataclasses.replace(BIANCHI2014, sigma1_decay_speed=1e-3)}
    ratios = np.geomspace(0.01, 1000.0, 21)
    freqs = np.array([1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0])
    out = {}
    for name, p in sets.items():
        a = (ratios * p.fs / p.sigma0)[:, None] * np.ones((1, freqs.size))
        w = 2 * math.pi * freqs[None, :] * np.ones((ratios.size, 1))
        c0, k0 = describing_function(p, a, w, n_steps=65536)
        n0 = k0 + 1j * w * c0
        rows = {}
        for n in steps:
            c, k = describing_function(p, a, w, n_steps=n)
            cyc = lugre_cycle(p, a, w, n_steps=n)
            err = np.abs(k + 1j * w * c - n0) / np.abs(n0)
            err_u = np.abs(cyc.keq + 1j * w * cyc.ceq - n0) / np.abs(n0)
            i = np.unravel_index(np.argmax(err), err.shape)
            rows[n] = {"graded_n_error": float(err.max()),
                       "graded_ceq_error": float(np.abs(c / c0 - 1.0).max()),
                       "graded_worst_at": {"amplitude_m": float(a[i]),
                                           "frequency_hz": float(freqs[i[1]]),
                                           "peak_speed_over_vs": float(a[i] * w[i] / p.vs)},
                       "uniform_n_error": float(err_u.max()),
                       "uniform_ceq_error": float(np.abs(cyc.ceq / c0 - 1.0).max())}
        out[name] = {"peak_speed_over_vs_max": float((a * w).max() / p.vs), "steps": rows}
    return out


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--repeats", type=int, default=10,
                        help="timing repeats of every method (best taken)")
    parser.add_argument("--convergence", action="store_true",
                        help="add the convergence study of the default steps per period")
    args = parser.parse_args(argv)

    p = BIANCHI2014
    omega = 2 * math.pi * 20.0
    amplitudes = np.geomspace(0.2e-6, 50e-6, 20)
    t0 = time.perf_counter()
    reference = scipy_all(p, amplitudes, omega, "Radau", 1e-11)
    t_reference = time.perf_counter() - t0
    n_default = DESCRIBING_FUNCTION_STEPS
    err_default = float(np.max(np.abs(
        servotune_all(p, amplitudes, omega, n_default) / reference - 1.0)))
    target = max(err_default, 1e-9)
    rtols = RTOLS
    t_default = best_time(lambda: servotune_all(p, amplitudes, omega, n_default),
                          args.repeats)[0]
    methods = {}
    for method in ("LSODA", "Radau"):
        rtol, err = calibrate(lambda r, m=method: scipy_all(p, amplitudes, omega, m, r), rtols,
                              reference, target)
        row = {"rtol": rtol, "max_relative_error": err, "time_s": math.nan}
        if rtol is not None:
            row["time_s"] = best_time(
                lambda m=method, r=rtol: scipy_all(p, amplitudes, omega, m, r), args.repeats)[0]
        methods[method] = row
    timed = {m: v["time_s"] for m, v in methods.items() if v["rtol"] is not None}
    baseline = min(timed, key=timed.get)

    # the cheapest settings within 1e-4
    loose = 1e-4
    n_loose, err_loose = calibrate(lambda n: servotune_all(p, amplitudes, omega, n),
                                   [16, 32, 64, 128, 256, 512, 1024], reference, loose)
    t_loose = best_time(lambda: servotune_all(p, amplitudes, omega, n_loose),
                        args.repeats)[0]
    loose_methods = {}
    for method in ("LSODA", "Radau"):
        rtol, err = calibrate(lambda r, m=method: scipy_all(p, amplitudes, omega, m, r), rtols,
                              reference, loose)
        loose_methods[method] = {"rtol": rtol, "max_relative_error": err,
                                 "time_s": best_time(lambda m=method, r=rtol: scipy_all(
                                     p, amplitudes, omega, m, r), args.repeats)[0]}
    loose_best = min(v["time_s"] for v in loose_methods.values())
    result = {
        "task": "LuGre energy per cycle, Bianchi 2014 parameters, 20 amplitudes 0.2-50 um, 20 Hz",
        "baseline": f"scipy solve_ivp {baseline} (the faster of LSODA and Radau) at equal "
                    f"accuracy",
        "speedup": timed[baseline] / t_default,
        "reference": "solve_ivp Radau rtol 1e-11",
        "reference_time_s": t_reference,
        "rtol_ladder": rtols,
        "timing": f"best of {args.repeats} repeats for every method (all 20 amplitudes each)",
        "servotune_default_steps_per_period": n_default,
        "servotune_default_max_relative_error": err_default,
        "servotune_default_time_s": t_default,
        "accuracy_target": target,
        "scipy": methods,
        "speedup_by_method": {m: t / t_default for m, t in timed.items()},
        "at_1e-4": {
            "servotune_steps_per_period": n_loose, "servotune_max_relative_error": err_loose,
            "servotune_time_s": t_loose, "scipy": loose_methods,
            "speedup": loose_best / t_loose,
        },
    }
    if args.convergence:
        result["convergence"] = convergence_study()
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main()
