"""``servotune twomass``: the paper's two-mass analysis (sec 4.1, Fig 4 and Fig 5)."""

from __future__ import annotations

from ._common import (
    RunOutput,
    add_common_options,
    number,
    print_json,
    save_figure,
    write_results,
)

__all__ = ["add_parser", "run"]

FIGURES = ("fig5_compliance.png", "fig4_g_alpha.png")

_MASS = number(0.0, 1e9, low_open=True, example=5000, unit="kg")
_STIFFNESS = number(0.0, 1e13, low_open=True, example="16e6", unit="N/m")
_ALPHA = number(0.0, 100.0, low_open=True, example=0.3)


def add_parser(subparsers) -> None:
    """Add the ``servotune twomass`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "twomass", help="fixed points, Copt and g(alpha) of the two-mass layouts (Fig 4, 5)",
        description="Fixed points, optimal guide-way damping Copt, optimal peak and limit "
                    "resonances of the two-mass layouts of sec 4.1; writes Fig 4 and Fig 5 "
                    "into OUT/twomass_layout_<A|B>. Defaults are the paper's Fig 5 system.")
    p.add_argument("--m1", type=_MASS, default=5000.0, help="slide mass M1 [kg] (5000)")
    p.add_argument("--k", type=_STIFFNESS, default=16e6, help="stiffness K [N/m] (16e6)")
    p.add_argument("--alpha", type=_ALPHA, default=0.3, help="mass ratio M2/M1 [-] (0.3)")
    p.add_argument("--layout", choices=("A", "B"), default="B",
                   help="B: ground-C-M1-K-M2 (paper Eq 1-7); A: ground-K-M2-C-M1 "
                        "(an interpretation of the paper's unreadable figure)")
    add_common_options(p, plots=True)
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``servotune twomass``.

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
    import warnings

    from .. import twomass

    system = twomass.TwoMassSystem(m1=args.m1, k=args.k, alpha=args.alpha, layout=args.layout)
    names = [] if args.no_plots else list(FIGURES)
    out = RunOutput.for_args(args, "twomass", f"layout_{system.layout}", ["results.json", *names])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        analysis = twomass.analyse_two_mass(system)
    result = analysis.to_dict()
    result["warnings"] = [str(w.message) for w in caught]
    result["folder"] = str(out.path)
    result["figures"] = [str(out.file(n)) for n in names]
    with out.writing() as folder:
        if names:
            from .. import plots

            save_figure(plots.plot_two_mass_compliance(analysis), folder / names[0])
            save_figure(plots.plot_g_alpha(mark=system.alpha if system.layout == "B" else None),
                        folder / names[1])
        write_results(folder, result)
    if args.json:
        print_json(result)
        return 0
    print(f"two-mass layout {system.layout}: M1 = {system.m1:g} kg, M2 = {system.m2:g} kg, "
          f"K = {system.k:g} N/m, alpha = {system.alpha:g}")
    print("  fixed points        : " + ", ".join(f"{f:.3f} Hz" for f in result["fixed_points_hz"]))
    print(f"  Copt                : {analysis.c_opt:.4e} N s/m")
    print(f"  optimal peak        : {analysis.peak_compliance:.4e} m/N "
          f"at {result['peak_frequency_hz']:.3f} Hz")
    print(f"  resonance C -> 0    : {result['resonance_c0_hz']:.3f} Hz")
    print(f"  resonance C -> inf  : {result['resonance_cinf_hz']:.3f} Hz")
    for message in result["warnings"]:
        print(f"  warning: {message}")
    print(f"  wrote {out.path}")
    return 0

