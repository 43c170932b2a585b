"""Compliance curve of the nonlinear axis: harmonic balance against the time simulation.

Task: the work-piece compliance of the bundled axis (``models/paper_x_axis``, the paper's
continuous drive, LuGre at the four pads) over 10-100 Hz at one force level (default 600 N peak
to peak, standing still).

* servotune: :func:`servotune.harmonic.nonlinear_compliance` (9 harmonics, 64 AFT samples,
  arc-length continuation with the peak refined), the best of ``--repeat`` (5) calls after one
  warm-up call (numba's kernels loaded from its cache).
* baseline: the same curve by the time simulation (:func:`servotune.simulate.simulate`) as a
  stepped sine (:func:`servotune.harmonic.stepped.stepped_sine`): at each frequency of the
  harmonic-balance curve, from rest, until the fundamental of the work-piece displacement over
  the last two 10-cycle windows agrees within 1e-3 (runs doubled in length until it does),
  each run recording only the work-piece displacement it reads (``simulate(record=("wp_x",))``);
  timed as servotune: the best of ``--repeat`` (5) calls after one warm-up call.

Accuracy: the two curves are compared point by point (largest relative difference) and by their
peaks; the harmonic balance's own truncation is given by the same curve with 21 harmonics.
``speedup`` is the baseline's time over servotune's, both measured in this run.

``--table3`` adds the validation behind the documentation: at 50, 600 and 2000 N peak to peak,
at rest and feeding at 30 mm/s (the paper's Table 3 forces), the harmonic balance's peak
beside the stepped sine's at five frequencies around it (+-0.5, +-1 Hz, parabola through them).

BLAS and OpenMP are held to one thread (before numpy is imported) for both methods.
Run: ``python benchmarks/harmonic_balance.py [--json] [--force-pp N] [--speed V] [--table3]``.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from _timing import best_time  # noqa: E402

from servotune.axis import load_axis  # noqa: E402
from servotune.harmonic import HarmonicSettings, curve_peak, nonlinear_compliance  # noqa: E402
from servotune.harmonic.stepped import stepped_sine  # noqa: E402
from servotune.simulate.setup import axis_setup  # noqa: E402
from servotune.units import HZ_PER_RAD_S  # noqa: E402

AXIS = Path(__file__).resolve().parents[1] / "models" / "paper_x_axis"


def main(argv=None) -> dict:
    """Run the comparison and return its figures (also printed).

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments.

    Returns
    -------
    dict
    """
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--force-pp", type=float, default=600.0)
    parser.add_argument("--speed", type=float, default=0.0)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--table3", action="store_true")
    args = parser.parse_args(argv)
    setup = axis_setup(load_axis(AXIS).with_continuous_drive())

    def hb(harmonics=9):
        return nonlinear_compliance(setup, [args.force_pp], speed=args.speed, references=False,
                                    describing=False, settings=HarmonicSettings(harmonics))

    t0 = time.perf_counter()
    hb()
    first = time.perf_counter() - t0
    t_hb, result = best_time(hb, args.repeat)
    curve = result.curves[0]
    fine = hb(21).curves[0]

    def stepped():
        return stepped_sine(setup, args.force_pp, curve.omega, args.speed, tolerance=1e-3)

    # the same timing on both sides: one warm-up call, then the best of --repeat calls
    t0 = time.perf_counter()
    stepped()
    sim_first = time.perf_counter() - t0
    t_sim, sim = best_time(stepped, args.repeat)
    rel = np.abs(sim.compliance / curve.compliance - 1.0)
    w_sim, p_sim, _ = curve_peak(sim.omega, sim.compliance)
    out = {
        "task": f"compliance curve 10-100 Hz, {args.force_pp:g} N p-p, "
                f"{args.speed * 1e3:g} mm/s, models/paper_x_axis (continuous drive)",
        "points": int(curve.omega.size),
        "harmonic_balance_s": t_hb, "harmonic_balance_first_call_s": first,
        "newton_iterations": curve.newton_iterations,
        "time_simulation_s": t_sim, "time_simulation_first_call_s": sim_first,
        "repeat": args.repeat,
        "simulated_time_s": float(sim.durations.sum()),
        "speedup": t_sim / t_hb,
        "max_relative_difference": float(rel.max()),
        "median_relative_difference": float(np.median(rel)),
        "harmonic_balance": {"resonance_hz": curve.resonance * HZ_PER_RAD_S,
                             "peak_m_per_n": curve.peak},
        "harmonic_balance_21_harmonics": {"resonance_hz": fine.resonance * HZ_PER_RAD_S,
                                          "peak_m_per_n": fine.peak},
        "time_simulation": {"resonance_hz": w_sim * HZ_PER_RAD_S, "peak_m_per_n": p_sim},
        "load_average": os.getloadavg(),
    }
    if args.table3:
        out["table3"] = table3_cases(setup)
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print(f"{out['task']}: {out['points']} frequencies")
        print(f"harmonic balance  {t_hb:8.3f} s  (first call {first:.3f} s)  peak "
              f"{curve.peak:.5g} m/N at {curve.resonance * HZ_PER_RAD_S:.3f} Hz")
        print(f"stepped sine      {t_sim:8.3f} s  ({out['simulated_time_s']:.1f} s "
              f"simulated)  peak {p_sim:.5g} m/N at {w_sim * HZ_PER_RAD_S:.3f} Hz")
        print(f"speedup {out['speedup']:.1f}x; curves differ by at most {rel.max():.2e} "
              f"(median {np.median(rel):.2e})")
        for row in out.get("table3", []):
            print(f"{row['force_pp_n']:>6g} N {row['speed_m_per_s'] * 1e3:>3g} mm/s: HB "
                  f"{row['hb_resonance_hz']:.2f} Hz {row['hb_peak_m_per_n']:.4g} m/N (pad "
                  f"{row['hb_pad_amplitude_m']:.3g} m) | stepped sine "
                  f"{row['sim_resonance_hz']:.2f} Hz {row['sim_peak_m_per_n']:.4g} m/N")
    return out


def table3_cases(setup) -> list:
    """Return HB and stepped-sine peaks at the paper's Table 3 forces and speeds.

    Parameters
    ----------
    setup : servotune.simulate.setup.AxisSetup
        The axis.

    Returns
    -------
    list of dict
    """
    rows = []
    for speed in (0.0, 0.03):
        result = nonlinear_compliance(setup, [50.0, 600.0, 2000.0], speed=speed,
                                      references=False, describing=False)
        for curve in result.curves:
            grid = curve.resonance + 2 * np.pi * np.array([-1.0, -0.5, 0.0, 0.5, 1.0])
            sim = stepped_sine(setup, curve.force_pp, grid, speed, tolerance=1e-3)
            w_sim, p_sim, _ = curve_peak(grid, sim.compliance)
            rows.append({"force_pp_n": curve.force_pp, "speed_m_per_s": speed,
                         "hb_resonance_hz": curve.resonance * HZ_PER_RAD_S,
                         "hb_peak_m_per_n": curve.peak,
                         "hb_pad_amplitude_m": curve.pad_amplitude_at_peak,
                         "hb_time_s": curve.wall_time,
                         "sim_resonance_hz": w_sim * HZ_PER_RAD_S, "sim_peak_m_per_n": p_sim,
                         "sim_time_s": sim.wall_time})
    return rows


if __name__ == "__main__":
    main()
