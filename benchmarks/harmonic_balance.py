"""Compliance curve of the nonlinear axis: harmonic balance against the time simulation.

Task: the work-piece compliance of the bundled axis (``models/paper_x_axis``, the paper's
continuous drive, LuGre at the four pads) over 10-100 Hz at one force level (default 600 N peak
to peak, standing still).

* servotune: :func:`servotune.harmonic.nonlinear_compliance` (9 harmonics, 128 AFT samples,
  arc-length continuation with the peak refined), the best of ``--repeat`` calls after one
  warm-up call (numba's kernels loaded from its cache).
* baseline: the same curve by the time simulation (:func:`servotune.simulate.simulate`) as a
  stepped sine (:func:`servotune.harmonic.stepped.stepped_sine`): at each frequency of the
  harmonic-balance curve, from rest, until the fundamental of the work-piece displacement over
  the last two 10-cycle windows agrees within 1e-3 (runs doubled in length until it does).

Accuracy: the two curves are compared point by point (largest relative difference) and by their
peaks; the harmonic balance's own truncation is given by the same curve with 21 harmonics.
``speedup`` is the baseline's time over servotune's, both measured in this run.

BLAS and OpenMP are held to one thread (before numpy is imported) for both methods.
Run: ``python benchmarks/harmonic_balance.py [--json] [--force-pp N] [--speed V]``.
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
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", action="store_true")
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
    sim = stepped_sine(setup, args.force_pp, curve.omega, args.speed, tolerance=1e-3)
    rel = np.abs(sim.compliance / curve.compliance - 1.0)
    w_sim, p_sim, _ = curve_peak(sim.omega, sim.compliance)
    out = {
        "task": f"compliance curve 10-100 Hz, {args.force_pp:g} N p-p, "
                f"{args.speed * 1e3:g} mm/s, models/paper_x_axis (continuous drive)",
        "points": int(curve.omega.size),
        "harmonic_balance_s": t_hb, "harmonic_balance_first_call_s": first,
        "newton_iterations": curve.newton_iterations,
        "time_simulation_s": sim.wall_time,
        "simulated_time_s": float(sim.durations.sum()),
        "speedup": sim.wall_time / t_hb,
        "max_relative_difference": float(rel.max()),
        "median_relative_difference": float(np.median(rel)),
        "harmonic_balance": {"resonance_hz": curve.resonance * HZ_PER_RAD_S,
                             "peak_m_per_n": curve.peak},
        "harmonic_balance_21_harmonics": {"resonance_hz": fine.resonance * HZ_PER_RAD_S,
                                          "peak_m_per_n": fine.peak},
        "time_simulation": {"resonance_hz": w_sim * HZ_PER_RAD_S, "peak_m_per_n": p_sim},
        "load_average": os.getloadavg(),
    }
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print(f"{out['task']}: {out['points']} frequencies")
        print(f"harmonic balance  {t_hb:8.3f} s  (first call {first:.3f} s)  peak "
              f"{curve.peak:.5g} m/N at {curve.resonance * HZ_PER_RAD_S:.3f} Hz")
        print(f"stepped sine      {sim.wall_time:8.3f} s  ({out['simulated_time_s']:.1f} s "
              f"simulated)  peak {p_sim:.5g} m/N at {w_sim * HZ_PER_RAD_S:.3f} Hz")
        print(f"speedup {out['speedup']:.1f}x; curves differ by at most {rel.max():.2e} "
              f"(median {np.median(rel):.2e})")
    return out


if __name__ == "__main__":
    main()
