"""The one-degree-of-freedom milling benchmark of Insperger and Stepan by both lobe methods.

Goal: for the tool of Insperger and Stepan (2 teeth, Kt = 6e8 N/m^2, Kn = 2e8 N/m^2,
f_n = 922 Hz, zeta = 0.011, modal mass 0.03993 kg, flexible in the feed direction x;
down-milling), compare the zero-order approximation (Altintas and Budak 1995) with the
semi-discretisation (Insperger and Stepan 2004) at radial immersions a/D = 1, 0.5, 0.1, 0.05
over 5,000-25,000 rpm: the smallest stable depth b_crit, where it occurs, and the kind of
instability there. In a full slot the two agree closely; at low immersion period-doubling
(flip) lobes reach far below the zero-order limit.

Data source: T. Insperger, G. Stepan, "Updated semi-discretization method for periodic
delay-differential equations with discrete delay", Int J Numer Meth Engng 61 (2004) 117-141.
"""

import math

import numpy as np

import servotune as st
from servotune import chatter, plots


def main(immersions=(1.0, 0.5, 0.1, 0.05), speed_range_rpm=(5000.0, 25000.0), speeds=201,
         intervals=40, depth_max=10e-3, figure=None):
    """Table rows (SI, speeds in rpm) and, if ``figure`` is a path, a 2 x 2 panel figure."""
    wn = 2 * math.pi * 922.0
    system = st.modal_compliance([st.Mode(wn, 0.011, 0.03993 * wn**2)])
    grid = np.linspace(*speed_range_rpm, speeds)
    rows, panels = [], []
    for ae in immersions:
        setup = st.MillingSetup(teeth=2, kt=6e8, kn=2e8, radial_immersion=ae, milling="down")
        zoa = st.stability_lobes(system, setup, np.linspace(*speed_range_rpm, 4001))
        sdm = st.sdm_lobes(system, setup, grid, depth_max, intervals=intervals, tol=1e-5)
        model = chatter.cutting_state_space(system)
        _, mu = chatter.monodromy_spectral_radius(
            model, chatter.periodic_directional_matrix(setup, intervals),
            60.0 / (setup.teeth * sdm.critical_speed_rpm), 1.01 * sdm.b_crit,
            return_multiplier=True)
        kind = "flip" if abs(mu.imag) < 1e-9 * abs(mu) and mu.real < 0 else (
            "Hopf" if abs(mu.imag) > 1e-9 * abs(mu) else "fold")
        rows.append({
            "radial_immersion": ae,
            "directional_factor": chatter.directional_factor(setup, "x"),
            "zoa_b_crit_m": zoa.b_crit,
            "zoa_critical_speed_rpm": zoa.critical_speed_rpm,
            "zoa_chatter_frequency_hz": zoa.critical_frequency / (2 * math.pi),
            "sdm_b_crit_m": sdm.b_crit,
            "sdm_critical_speed_rpm": sdm.critical_speed_rpm,
            "sdm_instability": kind,
            "sdm_over_zoa": sdm.b_crit / zoa.b_crit,
        })
        panels.append((setup, zoa, sdm))
    if figure is not None:
        from matplotlib.figure import Figure

        from servotune import report

        fig = Figure(figsize=(12.0, 8.0), layout="constrained")
        axes = fig.subplots(2, 2).ravel()
        for ax, (setup, zoa, sdm) in zip(axes, panels, strict=False):
            plots.plot_stability_lobes(
                [zoa, sdm], depth_max=min(depth_max, 4 * max(zoa.b_crit, sdm.b_crit)), ax=ax,
                title=f"a/D = {setup.radial_immersion:g}, down-milling")
        fig.suptitle("Insperger-Stepan milling benchmark: zero-order approximation vs "
                     f"semi-discretisation (m = {intervals})")
        report.save_figure(fig, figure, force=True)
    return rows


if __name__ == "__main__":
    print(f"{'a/D':>5} {'mu_x':>8} {'ZOA b_crit':>11} {'at rpm':>8} {'f_c Hz':>7} "
          f"{'SDM b_crit':>11} {'at rpm':>8} {'kind':>5} {'SDM/ZOA':>8}")
    for r in main(figure="milling_stability_benchmark.png"):
        print(f"{r['radial_immersion']:5.2f} {r['directional_factor']:8.4f} "
              f"{1e3 * r['zoa_b_crit_m']:8.4f} mm {r['zoa_critical_speed_rpm']:8.0f} "
              f"{r['zoa_chatter_frequency_hz']:7.1f} {1e3 * r['sdm_b_crit_m']:8.4f} mm "
              f"{r['sdm_critical_speed_rpm']:8.0f} {r['sdm_instability']:>5} "
              f"{r['sdm_over_zoa']:8.3f}")
