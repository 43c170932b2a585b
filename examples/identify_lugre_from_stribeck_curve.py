"""Identify the steady-state LuGre parameters of a guide way from a measured Stribeck curve.

Goal: from sliding friction measured at constant velocities in both directions (the test of the
paper's sec 5.1 and Fig 7), estimate Fc, Fs, vs, delta and sigma2 with their standard errors by
:func:`servotune.fit_steady_state` (nonlinear least squares; Gauss-Newton covariance), once with
all five free and once with the Stribeck exponent fixed at the paper's delta = 1. The rms
residual estimates the force noise of the measurement.

Data source: ``examples/data/stribeck_paper_axis.csv`` (columns ``v_m_per_s,f_n``), synthetic:
the steady-state friction of the set identified by Bianchi et al. (2014) (Fc = 2198 N,
Fs = 6013 N, vs = 0.01 m/s, delta = 1, sigma2 = 5578 N s/m) at 20 speeds per direction from
0.1 mm/s to 0.5 m/s, plus Gaussian force noise of 60 N (seeded; ``examples/data/generate.py``).
"""

from pathlib import Path

import servotune as st
from servotune.friction import read_friction_csv

DATA = Path(__file__).resolve().parent / "data" / "stribeck_paper_axis.csv"


def _summary(fit) -> dict:
    return {"estimates": {n: fit.estimate(n)[0] for n in fit.names},
            "standard_errors": {n: fit.estimate(n)[1] for n in fit.names},
            "rms_residual": fit.rms, "n_points": int(fit.residuals.size),
            "n_parameters": len(fit.names)}


def main(path=DATA, figure=None):
    """Both fits as dicts of estimates and standard errors (SI); optionally the Fig 7-like
    figure of the data and the fitted curve written to ``figure``."""
    data = read_friction_csv(path)
    free = st.fit_steady_state(data.velocity, data.force)
    fixed = st.fit_steady_state(data.velocity, data.force, fixed={"delta": 1.0})
    if figure is not None:
        from servotune import plots, report

        fig = plots.plot_stribeck(free.parameters, data.velocity, data.force,
                                  title="Sliding friction measured at constant velocities")
        report.save_figure(fig, figure, force=True)
    return {"free": _summary(free), "delta_fixed": _summary(fixed),
            "parameters": free.parameters.to_dict()}


if __name__ == "__main__":
    result = main(figure="identify_lugre_from_stribeck_curve.png")
    for label, key in (("all five free", "free"), ("delta fixed at 1", "delta_fixed")):
        r = result[key]
        print(f"{label} ({r['n_points']} points, rms residual {r['rms_residual']:.1f} N):")
        for name, value in r["estimates"].items():
            print(f"  {name:7} {value:12.5g} +- {r['standard_errors'][name]:.2g}")
