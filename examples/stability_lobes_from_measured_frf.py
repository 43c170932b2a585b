"""Stability lobes of a milling operation from a measured tool/work-piece FRF (CSV).

Goal: read a compliance measured in the feed direction (an impact test: ``f_hz`` with the real
and imaginary parts of G_xx [m/N]) with :func:`servotune.read_frf_csv` and compute the
zero-order stability lobes (Altintas and Budak 1995) with :func:`servotune.stability_lobes`:
the absolute limit b_crit, the chatter frequency there, the lobe diagram over the spindle-speed
range and the margin against a required depth of cut. The measurement is used as it is (no
modal fit): the minimum of Re G between grid points comes from a parabola through the three
lowest points.

Data source: ``examples/data/frf_two_mode.csv``, synthetic: two modes in x, 620 Hz
(zeta = 0.035, k = 2e7 N/m) and 1350 Hz (zeta = 0.025, k = 6e7 N/m), every 1 Hz from 200 to
2000 Hz, with complex Gaussian noise of 1 % of the largest |G| (seeded;
``examples/data/generate.py``).
"""

import math
from pathlib import Path

import numpy as np

import servotune as st
from servotune.chatter import directional_factor

DATA = Path(__file__).resolve().parent / "data" / "frf_two_mode.csv"
#: Face milling of steel with a 4-tooth cutter, half immersion, down-milling.
SETUP = st.MillingSetup(teeth=4, kt=1.5e9, kn=0.45e9, radial_immersion=0.5, milling="down")
SPEED_RANGE_RPM = (3000.0, 15000.0)
REQUIRED_DEPTH = 1.0e-3


def main(path=DATA, setup=SETUP, speed_range_rpm=SPEED_RANGE_RPM, speeds=3001,
         required_depth=REQUIRED_DEPTH, figure=None):
    """The lobes' key numbers (SI, speeds in rpm) and, if ``figure`` is a path, the diagram."""
    frf = st.read_frf_csv(path)
    lobes = st.stability_lobes(frf, setup, np.linspace(*speed_range_rpm, speeds))
    if figure is not None:
        from servotune import report

        fig = lobes.plot(required_depth=required_depth,
                         title=f"Zero-order stability lobes from {Path(path).name}: "
                               f"{setup.teeth} teeth, a/D = {setup.radial_immersion:g}, "
                               f"{setup.milling}-milling")
        report.save_figure(fig, figure, force=True)
    stable = np.isfinite(lobes.depth_limit)
    best = int(np.argmax(np.where(stable, lobes.depth_limit, -np.inf)))
    return {
        "b_crit_m": lobes.b_crit,
        "chatter_frequency_hz": lobes.critical_frequency / (2 * math.pi),
        "critical_speed_rpm": lobes.critical_speed_rpm,
        "min_depth_limit_m": lobes.min_depth_limit,
        "margin": lobes.margin(required_depth),
        "best_speed_rpm": float(lobes.speed_rpm[best]),
        "best_depth_limit_m": float(lobes.depth_limit[best]),
        "directional_factor": directional_factor(setup, "x"),
        "frequency_range_hz": (float(frf.omega[0] / (2 * math.pi)),
                               float(frf.omega[-1] / (2 * math.pi))),
        "lobe_count": lobes.lobe_count,
    }


if __name__ == "__main__":
    r = main(figure="stability_lobes_from_measured_frf.png")
    print(f"b_crit = {1e3 * r['b_crit_m']:.3f} mm at a chatter frequency of "
          f"{r['chatter_frequency_hz']:.1f} Hz (directional factor mu_x = "
          f"{r['directional_factor']:.4f})")
    print(f"lowest limit in {SPEED_RANGE_RPM[0]:.0f}-{SPEED_RANGE_RPM[1]:.0f} rpm: "
          f"{1e3 * r['min_depth_limit_m']:.3f} mm; margin over {1e3 * REQUIRED_DEPTH:g} mm: "
          f"{r['margin']:.2f}")
    print(f"best speed in the range: {r['best_speed_rpm']:.0f} rpm, stable to "
          f"{1e3 * r['best_depth_limit_m']:.2f} mm")
