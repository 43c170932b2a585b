"""``servotune tune``: tune guide-way damping and servo gains of an axis, verify, report."""

from __future__ import annotations

import math

from .. import report
from ..axis import load_axis
from ..design import tune_axis
from ._common import add_output_options, print_json, to_jsonable

__all__ = ["add_parser", "run"]

VARIABLES = ("c", "kv", "kp", "ti")


def _free(text: str) -> tuple[str, ...]:
    names = tuple(v.strip().lower() for v in text.split(",") if v.strip())
    unknown = [v for v in names if v not in VARIABLES]
    if unknown or not names:
        raise ValueError(f"--free takes a comma-separated subset of {','.join(VARIABLES)}, "
                         f"got {text!r}")
    return names


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "tune", help="tune guide-way damping C, Kv and the velocity PI (casadi), verify",
        description="Tune the guide-way damping C and the position/velocity loop gains of an "
                    "axis against its work-piece compliance peak (and, with --chatter-weight, "
                    "its chatter limit b_crit) under the Ms and margin requirements of "
                    "[requirements]; verify the design with python-control on grids the "
                    "optimiser never saw; print a before/after table and write results.json "
                    "and figures. On a two-mass axis (models/two_mass_fig5) the tuned C is "
                    "checked against the closed-form fixed-point optimum Copt.")
    p.add_argument("axis", help="axis folder with axis.toml (e.g. models/paper_x_axis)")
    p.add_argument("--free", type=_free, default=None,
                   help="design variables the optimiser may change (default: [tuning] free "
                        "of the axis, else c,kv,kp,ti)")
    p.add_argument("--chatter-weight", type=float, default=None,
                   help="weight in [0, 1] of the chatter limit against the compliance peak "
                        "(default: [tuning] chatter_weight of the axis, else 0)")
    p.add_argument("--starts", type=int, default=4, help="starting points (default 4)")
    p.add_argument("--no-simulation", action="store_true",
                   help="skip the nonlinear LuGre verification sweeps")
    p.add_argument("--sweep-duration", type=float, default=20.0,
                   help="duration of each nonlinear sweep 10 -> 100 Hz [s] (default 20, as the "
                        "paper's Table 3)")
    p.add_argument("--workers", type=int, default=None,
                   help="processes for the nonlinear sweeps (default: as many as CPUs, "
                        "1 = serial)")
    add_output_options(p, default_out="out/tune_AXISNAME")
    p.set_defaults(func=run)


def _row(name, before, after, fmt="{:.4g}"):
    def f(v):
        return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else \
            fmt.format(v)
    return f"  {name:34} {f(before):>14} {f(after):>14}"


def run(args) -> int:
    axis = load_axis(args.axis)
    out = (report.default_folder(f"tune_{axis.name}") if str(args.out) == "out/tune_AXISNAME"
           else args.out)
    names = ["report.html", "results.json", "compliance.png", "bode_before.png",
             "bode_after.png", "lobes.png", "modes.png"]
    report.check_writable([out / n for n in names], args.force)
    simulate = (not args.no_simulation and axis.drive is not None
                and axis.friction is not None)
    executor = None
    if simulate and args.workers != 1:
        from concurrent.futures import ProcessPoolExecutor

        executor = ProcessPoolExecutor(max_workers=args.workers)
    try:
        job = tune_axis(axis, free=args.free, chatter_weight=args.chatter_weight,
                        starts=args.starts, simulate=simulate, executor=executor,
                        sweep_duration=args.sweep_duration)
    finally:
        if executor is not None:
            executor.shutdown()
    results = job.to_dict()
    files = report.write_tuning_files(job, out, args.force)
    files.append(report.write_html_report(job, out, args.force))
    results["files"] = [str(f) for f in files]
    results["report"] = str(out / "report.html")
    report.write_json(out / "results.json", to_jsonable(results), force=args.force)
    if args.json:
        print_json(results)
        return 0 if job.result.success else 1
    r = job.result
    print(f"{axis.name}: tuned {', '.join(r.problem.free)} "
          f"({r.stats['starts']} starts, {r.stats['iterations']} IPOPT iterations, "
          f"{r.stats['time_s']:.1f} s)")
    print(f"  {'':34} {'before':>14} {'after':>14}")
    d0, d1 = r.initial, r.design
    print(_row("C guide ways [N s/m]", d0.c, d1.c))
    if d0.kv is not None:
        print(_row("Kv [1/s]", d0.kv, d1.kv))
        print(_row("Kv [(m/min)/mm]", results["kv_m_per_min_per_mm_before"],
                   results["kv_m_per_min_per_mm"]))
        print(_row("Kp velocity [N m s/rad]", d0.kp, d1.kp))
        print(_row("Ti velocity [s]", d0.ti, d1.ti))
    print(_row("peak compliance [m/N]", r.before.peak_compliance,
               None if r.after is None else r.after.peak_compliance))
    print(_row("  at [Hz]", results["peak_frequency_before_hz"],
               results["peak_frequency_after_hz"], "{:.2f}"))
    if r.before.b_crit is not None:
        print(_row("b_crit [mm]", r.before.b_crit * 1e3,
                   None if r.after is None else r.after.b_crit * 1e3, "{:.3g}"))
    for loop in ("velocity", "position"):
        a0 = getattr(r.before, loop)
        a1 = None if r.after is None else getattr(r.after, loop)
        if a0 is None:
            continue
        print(_row(f"Ms {loop} loop", a0.ms, a1 and a1.ms, "{:.3f}"))
        print(_row(f"  phase margin [deg]", a0.phase_margin_deg, a1 and a1.phase_margin_deg,
                   "{:.1f}"))
        print(_row(f"  gain margin [dB]", a0.gain_margin_db, a1 and a1.gain_margin_db, "{:.1f}"))
        print(_row(f"  bandwidth [Hz]", a0.bandwidth_hz, a1 and a1.bandwidth_hz, "{:.2f}"))
    if job.two_mass is not None:
        t = job.two_mass
        print(f"  two-mass check (sec 4.1): Copt closed form {t.c_opt_analytic:.6e} N s/m, "
              f"tuned {t.c_opt_tuned:.6e} N s/m (relative difference "
              f"{t.c_relative_difference:+.1e})")
        print(f"                            peak g(alpha)/K {t.peak_analytic:.6e} m/N, tuned "
              f"{t.peak_tuned:.6e} m/N ({t.peak_relative_difference:+.1e})")
    if r.active:
        print("  active: " + "; ".join(r.active))
    if job.mode_peaks is not None:
        for m in job.mode_peaks.to_dict()["modes"]:
            print(f"  mode at {m['frequency_at_chosen_c_hz']:.1f} Hz: peak "
                  f"{m['peak_at_chosen_c']:.3g} m/N at the chosen C, best C for it alone "
                  f"{m['c_best']:.3g} N s/m")
    print(("  VERIFIED: " if r.success else "  NOT VERIFIED: ")
          + ("constraints hold on dense grids the optimiser never saw" if r.success
             else "; ".join(r.reasons)))
    if job.nonlinear is not None:
        for row in job.nonlinear["sweeps"]:
            agree = [k for k in ("locked", "presliding", "viscous", "describing")
                     if row[f"agrees_{k}"]]
            print(f"  nonlinear sweep {row['force_pp_n']:6.0f} N p-p: resonance "
                  f"{row['resonance_hz']:.1f} Hz, peak {row['peak_m_per_n']:.3g} m/N; agrees "
                  f"with: {', '.join(agree) or 'none of the linear models'}")
    print(f"  wrote {out / 'results.json'} and {len(files) - 1} figures")
    print(f"  report: {out / 'report.html'}")
    return 0 if r.success else 1
