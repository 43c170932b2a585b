"""``servotune friction``: LuGre friction, equivalent damping (sec 4.2, Eq 8-10), fits (sec 5.1).

``servotune friction`` evaluates the equivalent viscous damping of the guide-way friction at one
amplitude and frequency (closed-form stiction cycle and LuGre describing function) and writes the
Stribeck curve, hysteresis loops and Ceq-against-amplitude figures. ``servotune friction fit
DATA.csv`` identifies LuGre parameters from measurements.
"""

from __future__ import annotations

import dataclasses
import math

from .. import plots, report
from ..friction import equivalent, identify, lugre
from ._common import add_output_options, print_json

__all__ = ["add_parser", "run", "run_fit"]

HZ = 1.0 / (2.0 * math.pi)
TABLE_AMPLITUDES = (1e-6, 2e-6, 5e-6)  # the amplitudes the paper's discussion is about [m]


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "friction", help="LuGre friction: equivalent damping (Eq 8-10), figures, fits",
        description="Equivalent viscous damping of guide-way friction at amplitude A and "
                    "frequency F: the paper's stiction cycle in closed form (Eq 8-10, with the "
                    "area corrected) and the LuGre describing function; writes the Stribeck "
                    "curve (Fig 7), hysteresis loops (Fig 2/6) and Ceq against amplitude. "
                    "'servotune friction fit DATA.csv' identifies parameters from measurements.")
    names = lugre.LuGreParameters.names()
    p.add_argument("--params", choices=names, default="bianchi2014",
                   help="named LuGre parameter set (default: the paper's, bianchi2014)")
    p.add_argument("--amplitude", type=float, default=2e-6,
                   help="displacement amplitude A [m] (default 2e-6)")
    p.add_argument("--frequency-hz", type=float, default=20.0,
                   help="vibration frequency [Hz] (default 20)")
    p.add_argument("--sigma1-decay-speed", type=float, default=None, metavar="V_D",
                   help="velocity-dependent micro-damping sigma1 exp(-(v/V_D)^2), V_D [m/s] "
                        "(default: the constant sigma1 of the set)")
    p.add_argument("--no-plots", action="store_true", help="do not write figures")
    add_output_options(p)
    p.set_defaults(func=run)

    sub = p.add_subparsers(dest="friction_command", metavar="fit")
    f = sub.add_parser(
        "fit", help="identify LuGre parameters from a CSV file",
        description="Fit (Fc, Fs, vs, delta, sigma2) to steady-state data with columns "
                    "v_m_per_s,f_n, or (sigma0, sigma1) to a presliding history with columns "
                    "t_s,x_m,f_n (the sliding parameters then come from --params). One header "
                    "row; SI units (v_mm_per_s, x_mm, x_um and f_kn are also accepted).")
    f.add_argument("data", help="CSV file with a header row")
    f.add_argument("--params", choices=names, default="bianchi2014",
                   help="parameter set supplying what the data do not determine")
    f.add_argument("--fix", action="append", default=[], metavar="NAME=VALUE",
                   help="hold a steady-state parameter (fc, fs, vs, delta, sigma2) at VALUE "
                        "(SI); repeatable, e.g. --fix delta=1")
    f.add_argument("--no-plots", action="store_true", help="do not write figures")
    add_output_options(f)
    f.set_defaults(func=run_fit)


def run(args) -> int:
    params = lugre.LuGreParameters.named(args.params)
    if args.sigma1_decay_speed is not None:
        params = dataclasses.replace(params, sigma1_decay_speed=args.sigma1_decay_speed)
    if not math.isfinite(args.frequency_hz) or args.frequency_hz <= 0.0:
        raise ValueError(f"--frequency-hz must be a positive number, got {args.frequency_hz}")
    if not math.isfinite(args.amplitude) or args.amplitude <= 0.0:
        raise ValueError(f"--amplitude must be a positive number of metres, got {args.amplitude}")
    omega = 2.0 * math.pi * args.frequency_hz
    files = [] if args.no_plots else [args.out / "friction_stribeck.png",
                                      args.out / "friction_hysteresis.png",
                                      args.out / "friction_equivalent_damping.png"]
    report.check_writable(files, args.force)
    ceq_s, keq_s = equivalent.stiction_describing_function(params.fs, params.sigma0,
                                                           args.amplitude, omega)
    ceq_l, keq_l = equivalent.describing_function(params, args.amplitude, omega)
    a_peak, c_peak = equivalent.stiction_peak_damping(params.fs, params.sigma0, omega)
    table_s = equivalent.equivalent_damping_stiction(params.fs, params.sigma0,
                                                     TABLE_AMPLITUDES, omega)
    table_c, table_k = equivalent.describing_function(params, TABLE_AMPLITUDES, omega)
    if files:
        a0 = params.presliding_displacement
        loops = lugre.lugre_cycle(params, [0.5 * a0, a0, 2.0 * a0, 5.0 * a0], omega)
        report.save_figure(plots.plot_stribeck(params), files[0], args.force)
        report.save_figure(plots.plot_hysteresis(loops, params), files[1], args.force)
        report.save_figure(plots.plot_equivalent_damping(params, omega), files[2], args.force)
    result = {
        "parameter_set": args.params,
        "parameters": params.to_dict(),
        "amplitude": args.amplitude,
        "omega": omega,
        "frequency_hz": args.frequency_hz,
        "ceq_stiction": float(ceq_s),
        "keq_stiction": float(keq_s),
        "ceq_lugre": float(ceq_l),
        "keq_lugre": float(keq_l),
        "presliding_displacement": params.presliding_displacement,
        "ceq_stiction_max": float(c_peak),
        "amplitude_at_ceq_stiction_max": float(a_peak),
        "table": [{"amplitude": a, "ceq_stiction": float(cs), "ceq_lugre": float(cl),
                   "keq_lugre": float(kl)}
                  for a, cs, cl, kl in zip(TABLE_AMPLITUDES, table_s, table_c, table_k,
                                           strict=True)],
        "figures": [str(f) for f in files],
    }
    if args.json:
        print_json(result)
        return 0
    print(f"LuGre friction ({args.params}): Fc = {params.fc:g} N, Fs = {params.fs:g} N, "
          f"vs = {params.vs:g} m/s, delta = {params.delta:g}, sigma0 = {params.sigma0:g} N/m, "
          f"sigma1 = {params.sigma1:g} N s/m, sigma2 = {params.sigma2:g} N s/m"
          + ("" if params.sigma1_decay_speed is None else
             f", sigma1 decay speed = {params.sigma1_decay_speed:g} m/s"))
    print(f"  Fs/sigma0 = {params.presliding_displacement:.4g} m; stiction Ceq max "
          f"{float(c_peak):.4g} N s/m at A = {float(a_peak):.4g} m")
    print(f"  at A = {args.amplitude:g} m, {args.frequency_hz:g} Hz:")
    print(f"    stiction cycle : Ceq = {float(ceq_s):.4g} N s/m, Keq = {float(keq_s):.4g} N/m")
    print(f"    LuGre          : Ceq = {float(ceq_l):.4g} N s/m, Keq = {float(keq_l):.4g} N/m")
    print(f"  {'A [m]':>10} {'Ceq stiction':>14} {'Ceq LuGre':>12} {'Keq LuGre':>12}")
    for row in result["table"]:
        print(f"  {row['amplitude']:10.3g} {row['ceq_stiction']:14.4g} {row['ceq_lugre']:12.4g} "
              f"{row['keq_lugre']:12.4g}")
    for f in files:
        print(f"  wrote {f}")
    return 0


def _fixed(items) -> dict[str, float]:
    fixed = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"--fix expects NAME=VALUE, got {item!r}")
        try:
            fixed[name.strip()] = float(value)
        except ValueError as exc:
            raise ValueError(f"--fix {item!r}: {value!r} is not a number") from exc
    return fixed


def run_fit(args) -> int:
    base = lugre.LuGreParameters.named(args.params)
    data = identify.read_friction_csv(args.data)
    fixed = _fixed(args.fix)
    name = "fit_stribeck.png" if data.kind == "steady_state" else "fit_presliding.png"
    files = [] if args.no_plots else [args.out / name]
    report.check_writable(files, args.force)
    if data.kind == "steady_state":
        fit = identify.fit_steady_state(data.velocity, data.force, fixed=fixed, base=base)
        if files:
            fig = plots.plot_stribeck(fit.parameters, data.velocity, data.force,
                                      title="Measured and fitted sliding friction (Fig 7)")
            report.save_figure(fig, files[0], args.force)
    else:
        if fixed:
            raise ValueError("--fix applies to steady-state (v, F) data only")
        fit = identify.fit_presliding(data.t, data.displacement, data.force, base)
        if files:
            response = lugre.simulate_lugre(fit.parameters, data.t,
                                            displacement=data.displacement,
                                            z0=fit.estimate("f0")[0] / fit.parameters.sigma0)
            title = (f"Measured and fitted presliding friction (Fig 2 / Fig 8)\n"
                     f"sigma0 = {fit.parameters.sigma0:.4g} N/m, "
                     f"sigma1 = {fit.parameters.sigma1:.4g} N s/m")
            report.save_figure(plots.plot_response_hysteresis(response, data.force, title),
                               files[0], args.force)
    result = fit.to_dict()
    result["data"] = str(args.data)
    result["figures"] = [str(f) for f in files]
    if args.json:
        print_json(result)
        return 0
    print(f"{fit.kind.replace('_', '-')} fit of {args.data} ({fit.residuals.size} points, "
          f"rms residual {fit.rms:.4g} N):")
    for n, v, s in zip(fit.names, fit.values, fit.standard_errors, strict=True):
        print(f"  {n:>7} = {v:.6g} +- {s:.2g}")
    for n, v in fit.fixed.items():
        print(f"  {n:>7} = {v:.6g} (fixed)")
    for f in files:
        print(f"  wrote {f}")
    return 0
