"""``servotune friction``: LuGre friction, equivalent damping (sec 4.2, Eq 8-10), fits (sec 5.1).

``servotune friction`` evaluates the equivalent viscous damping of the guide-way friction at one
amplitude and frequency (closed-form stiction cycle and LuGre describing function) and writes the
Stribeck curve, hysteresis loops and Ceq-against-amplitude figures. ``servotune friction fit
DATA.csv`` identifies LuGre parameters from measurements.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ._common import (
    RunOutput,
    UsageError,
    add_common_options,
    number,
    print_json,
    save_figure,
    write_results,
)

__all__ = ["add_parser", "run", "run_fit", "PARAMETER_SETS"]

TABLE_AMPLITUDES = (1e-6, 2e-6, 5e-6)  # the amplitudes the paper's discussion is about [m]
# LuGreParameters.names(), listed here so that the parser needs no numerics (tests check it)
PARAMETER_SETS = ("bianchi2014", "canudas1995")
FIGURES = ("stribeck.png", "hysteresis.png", "equivalent_damping.png")

_AMPLITUDE = number(0.0, 0.1, low_open=True, example="2e-6", unit="m")
_FREQUENCY = number(0.0, 1e5, low_open=True, example=20, unit="Hz")
_DECAY_SPEED = number(0.0, 10.0, low_open=True, example="1e-3", unit="m/s")


def add_parser(subparsers) -> None:
    """Add the ``servotune friction`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "friction", help="LuGre friction: equivalent damping (Eq 8-10), figures, fits",
        description="Equivalent viscous damping of guide-way friction at amplitude A and "
                    "frequency F: the paper's stiction cycle in closed form (Eq 8-10, with the "
                    "area corrected) and the LuGre describing function; writes the Stribeck "
                    "curve (Fig 7), hysteresis loops (Fig 2/6) and Ceq against amplitude. "
                    "'servotune friction fit DATA.csv' identifies parameters from measurements.")
    names = PARAMETER_SETS
    p.add_argument("--params", choices=names, default="bianchi2014",
                   help="named LuGre parameter set (default: the paper's, bianchi2014)")
    p.add_argument("--amplitude", type=_AMPLITUDE, default=None,
                   help=f"displacement amplitude A [m] (default {AMPLITUDE:g})")
    p.add_argument("--frequency-hz", type=_FREQUENCY, default=None,
                   help=f"vibration frequency [Hz] (default {FREQUENCY_HZ:g})")
    p.add_argument("--sigma1-decay-speed", type=_DECAY_SPEED, default=None, metavar="V_D",
                   help="velocity-dependent micro-damping sigma1 exp(-(v/V_D)^2), V_D [m/s] "
                        "(default: the constant sigma1 of the set)")
    add_common_options(p, plots=True)
    p.set_defaults(func=run)

    sub = p.add_subparsers(dest="friction_command", metavar="fit")
    f = sub.add_parser(
        "fit", help="identify LuGre parameters from a CSV file",
        description="Fit (Fc, Fs, vs, delta, sigma2) to steady-state data with columns "
                    "v_m_per_s,f_n, or (sigma0, sigma1) to a presliding history with columns "
                    "t_s,x_m,f_n (the sliding parameters then come from --params). One header "
                    "row; SI units (v_mm_per_s, x_mm, x_um and f_kn are also accepted).")
    f.add_argument("data", help="CSV file with a header row")
    f.add_argument("--params", choices=names, default=argparse.SUPPRESS,
                   help="parameter set supplying what the data do not determine (default "
                        "bianchi2014)")
    f.add_argument("--fix", action="append", default=[], metavar="NAME=VALUE",
                   help="hold a steady-state parameter (fc, fs, vs, delta, sigma2) at VALUE "
                        "(SI); repeatable, e.g. --fix delta=1")
    add_common_options(f, plots=True, nested=True)
    f.set_defaults(func=run_fit)


def run(args) -> int:
    """Run ``servotune friction``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        The exit status: 0. Errors are raised, and reported by
        :func:`servotune.cli.main` with status 1.
    """
    import dataclasses

    from .. import progress

    with progress.task("loading the friction models"):
        from ..friction import equivalent, lugre

    params = lugre.LuGreParameters.named(args.params)
    args.amplitude = AMPLITUDE if args.amplitude is None else args.amplitude
    args.frequency_hz = FREQUENCY_HZ if args.frequency_hz is None else args.frequency_hz
    if args.sigma1_decay_speed is not None:
        params = dataclasses.replace(params, sigma1_decay_speed=args.sigma1_decay_speed)
    omega = 2.0 * math.pi * args.frequency_hz
    names = [] if args.no_plots else list(FIGURES)
    run_out = RunOutput.for_args(args, "friction", args.params, ["results.json", *names])
    ceq_s, keq_s = equivalent.stiction_describing_function(params.fs, params.sigma0,
                                                           args.amplitude, omega)
    ceq_l, keq_l = equivalent.describing_function(params, args.amplitude, omega)
    a_peak, c_peak = equivalent.stiction_peak_damping(params.fs, params.sigma0, omega)
    table_s = equivalent.equivalent_damping_stiction(params.fs, params.sigma0,
                                                     TABLE_AMPLITUDES, omega)
    table_c, table_k = equivalent.describing_function(params, TABLE_AMPLITUDES, omega)
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
        "folder": str(run_out.path),
        "figures": [str(run_out.file(n)) for n in names],
    }
    with progress.task(f"writing {run_out.path}"), run_out.writing() as folder:
        if names:
            from .. import plots

            a0 = params.presliding_displacement
            loops = lugre.lugre_cycle(params, [0.5 * a0, a0, 2.0 * a0, 5.0 * a0], omega)
            save_figure(plots.plot_stribeck(params), folder / names[0])
            save_figure(plots.plot_hysteresis(loops, params), folder / names[1])
            save_figure(plots.plot_equivalent_damping(params, omega), folder / names[2])
        write_results(folder, result)
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
    print(f"  wrote {run_out.path}")
    return 0


#: the vibration the equivalent damping is computed at when not given: A [m], f [Hz]
AMPLITUDE, FREQUENCY_HZ = 2e-6, 20.0
FIXABLE = ("fc", "fs", "vs", "delta", "sigma2")  # the steady-state parameters
#: the values a fixed parameter may take: (low, high, unit, whether low itself is allowed);
#: the ranges of an axis file's [friction.lugre] (servotune.axis.LUGRE_RANGES)
FIX_RANGES = {"fc": (0.0, 1e7, "N", False), "fs": (0.0, 1e7, "N", False),
              "vs": (1e-7, 1.0, "m/s", True), "delta": (0.0, 10.0, "", False),
              "sigma2": (0.0, 1e10, "N s/m", True)}
#: the fastest sliding speed a guide-way measurement can hold [m/s]
SPEED_MAX = 10.0


def _fixed(items) -> dict[str, float]:
    fixed = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep:
            raise ValueError(f"--fix expects NAME=VALUE, got {item!r}; e.g. --fix delta=1")
        if name not in FIXABLE:
            raise ValueError(f"--fix {item!r}: {name!r} is not a steady-state parameter; use "
                             f"one of {', '.join(FIXABLE)}")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not math.isfinite(number):
            raise ValueError(f"--fix {item!r}: {value!r} is not a finite number; give the value "
                             "in SI units, e.g. --fix delta=1")
        low, high, unit, closed = FIX_RANGES[name]
        if not ((number >= low if closed else number > low) and number <= high):
            span = f"{'[' if closed else '('}{low:g}, {high:g}]" + (f" {unit}" if unit else "")
            raise ValueError(f"--fix {item!r}: {name} must be in {span}; give the value in SI "
                             "units, e.g. --fix vs=0.01")
        fixed[name] = number
    return fixed


def run_fit(args) -> int:
    """Run ``servotune friction fit``: identify LuGre parameters from a measurement CSV.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        The exit status, 0. Errors are raised, and reported by :func:`servotune.cli.main`
        with status 1.
    """
    from .. import progress

    with progress.task("loading the friction models"):
        from ..friction import identify, lugre

    unused = [flag for flag, value in (("--amplitude", args.amplitude),
                                       ("--frequency-hz", args.frequency_hz),
                                       ("--sigma1-decay-speed", args.sigma1_decay_speed))
              if value is not None]
    if unused:
        raise UsageError(f"{', '.join(unused)} {'set' if len(unused) > 1 else 'sets'} the "
                         "equivalent damping of 'servotune friction', not the fit: drop "
                         f"{'them' if len(unused) > 1 else 'it'} (or run 'servotune friction' "
                         "without fit)")
    base = lugre.LuGreParameters.named(getattr(args, "params", "bianchi2014"))
    data = identify.read_friction_csv(args.data)
    fixed = _fixed(args.fix)
    if fixed and data.kind != "steady_state":
        raise ValueError("--fix applies to steady-state (v, F) data only")
    if data.kind == "steady_state":
        fastest = float(abs(data.velocity).max())
        if fastest > SPEED_MAX:
            raise ValueError(f"{args.data}: column v_m_per_s reaches {fastest:g} m/s, past any "
                             f"guide way ({SPEED_MAX:g} m/s); give the speeds in m/s (a value "
                             "in mm/s divided by 1000)")
    name = "fit_stribeck.png" if data.kind == "steady_state" else "fit_presliding.png"
    names = [] if args.no_plots else [name]
    run_out = RunOutput.for_args(args, "friction_fit", Path(args.data).stem,
                                 ["results.json", *names])
    with progress.task(f"fitting {args.data}"):
        if data.kind == "steady_state":
            fit = identify.fit_steady_state(data.velocity, data.force, fixed=fixed, base=base)
        else:
            fit = identify.fit_presliding(data.t, data.displacement, data.force, base)
    result = fit.to_dict()
    result["data"] = str(args.data)
    result["folder"] = str(run_out.path)
    result["figures"] = [str(run_out.file(n)) for n in names]
    with progress.task(f"writing {run_out.path}"), run_out.writing() as folder:
        if names and data.kind == "steady_state":
            from .. import plots

            save_figure(plots.plot_stribeck(fit.parameters, data.velocity, data.force,
                                            title="Measured and fitted sliding friction (Fig 7)"),
                        folder / names[0])
        elif names:
            from .. import plots

            response = lugre.simulate_lugre(fit.parameters, data.t,
                                            displacement=data.displacement,
                                            z0=fit.estimate("f0")[0] / fit.parameters.sigma0)
            title = (f"Measured and fitted presliding friction (Fig 2 / Fig 8)\n"
                     f"sigma0 = {fit.parameters.sigma0:.4g} N/m, "
                     f"sigma1 = {fit.parameters.sigma1:.4g} N s/m")
            save_figure(plots.plot_response_hysteresis(response, data.force, title),
                        folder / names[0])
        write_results(folder, result)
    if args.json:
        print_json(result)
        return 0
    print(f"{fit.kind.replace('_', '-')} fit of {args.data} ({fit.residuals.size} points, "
          f"rms residual {fit.rms:.4g} N):")
    for n, v, s in zip(fit.names, fit.values, fit.standard_errors, strict=True):
        print(f"  {n:>7} = {v:.6g} +- {s:.2g}")
    for n, v in fit.fixed.items():
        print(f"  {n:>7} = {v:.6g} (fixed)")
    print(f"  wrote {run_out.path}")
    return 0
