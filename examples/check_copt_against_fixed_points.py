"""Check the closed-form optimal guide-way damping against a numeric minimax search and the tuner.

Goal: for the paper's Fig 5 system (M1 = 5000 kg, K = 16e6 N/m, alpha = 0.3; Bianchi et al.
2014, sec 4.1) and a sweep of mass ratios, compare Copt from the fixed-point theory (Eq 4) with
the damping that numerically minimises the true compliance peak, and the optimal peak g(alpha)/K
(Eq 7) with the peak found on the frequency response. Then run the design job
(:func:`servotune.design.tune_axis`, casadi/IPOPT with python-control verification) on the
bundled axis ``models/two_mass_fig5``, started from guide-way dampings well away from Copt, and
compare the tuned C and peak with the same closed forms.

Data source: the paper's Fig 5 values; ``models/two_mass_fig5`` (see its README).
"""

import dataclasses
from pathlib import Path

import servotune as st
from servotune.design import tune_axis

TWO_MASS_AXIS = Path(__file__).resolve().parents[1] / "models" / "two_mass_fig5"


def tune_two_mass(c_start: float, axis_path=TWO_MASS_AXIS) -> dict:
    """Tune C of the two-mass axis from the guide-way damping ``c_start`` [N s/m]."""
    axis = st.load_axis(axis_path)
    axis = dataclasses.replace(axis, friction=dataclasses.replace(axis.friction,
                                                                  viscous=c_start))
    job = tune_axis(axis, starts=1)
    check = job.two_mass.to_dict()
    return {"c_start": c_start, "verified": job.result.success,
            "peak_compliance_start": job.result.before.peak_compliance, **check}


def main(alphas=(0.1, 0.3, 0.6, 1.0), tuner_starts=(1e5, 1e7)):
    """Minimax rows per mass ratio and tuner rows per starting C, as a dict."""
    rows = []
    for alpha in alphas:
        system = st.TwoMassSystem(m1=5000.0, k=16e6, alpha=alpha)
        c_closed = st.optimal_damping(system)
        c_numeric, peak_numeric = st.minimax_damping(system)
        rows.append({
            "alpha": alpha,
            "c_opt_closed_form": c_closed,
            "c_opt_minimax": c_numeric,
            "c_relative_difference": c_numeric / c_closed - 1.0,
            "peak_closed_form": st.optimal_peak(system),
            "peak_minimax": peak_numeric,
        })
    return {"minimax": rows, "tuned": [tune_two_mass(c) for c in tuner_starts]}


if __name__ == "__main__":
    result = main()
    print(f"{'alpha':>6} {'Copt (Eq 4) [N s/m]':>20} {'minimax [N s/m]':>16} {'rel. diff':>10} "
          f"{'g/K [m/N]':>11} {'peak [m/N]':>11}")
    for r in result["minimax"]:
        print(f"{r['alpha']:6.2f} {r['c_opt_closed_form']:20.6e} {r['c_opt_minimax']:16.6e} "
              f"{r['c_relative_difference']:10.1e} {r['peak_closed_form']:11.4e} "
              f"{r['peak_minimax']:11.4e}")
    print("\nservotune.design.tune_axis on models/two_mass_fig5 (alpha = 0.3):")
    print(f"{'C start [N s/m]':>16} {'peak start [m/N]':>17} {'C tuned [N s/m]':>16} "
          f"{'rel. diff':>10} {'peak tuned':>11} {'rel. diff':>10} verified")
    for r in result["tuned"]:
        print(f"{r['c_start']:16.3e} {r['peak_compliance_start']:17.4e} {r['c_opt_tuned']:16.6e} "
              f"{r['c_relative_difference']:10.1e} {r['peak_compliance_tuned']:11.4e} "
              f"{r['peak_relative_difference']:10.1e} {r['verified']}")
