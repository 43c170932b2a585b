"""``servotune check``: read FE or reduced matrices, check them and print the report.

With ``--boundary`` the matrices are reduced by Craig-Bampton first and the reduced model is
checked against the full one over the band (``--band-hz``): frequencies, port compliance and
the coverage of the band by the kept fixed-interface modes. Given an axis folder, its structure
is checked, against its FE matrices when it reduces them on loading, and its transmission
against the drive.
"""

from __future__ import annotations

import math
from pathlib import Path

from ._common import (
    RunOutput,
    UsageError,
    add_common_options,
    number,
    print_json,
    write_results,
)

__all__ = ["add_parser", "run"]

DENSE_LIMIT = 5000
TWO_PI = 2.0 * math.pi
DEFAULT_MARGIN = 1.5  # as servotune.structure.coverage.DEFAULT_MARGIN (kept here: lazy imports)


def add_parser(subparsers) -> None:
    """Add the ``servotune check`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "check", help="check mass/stiffness matrices (symmetry, definiteness, rigid-body "
                      "mass, fixed-base frequencies, modal effective mass) and a reduction "
                      "against the full model",
        description="Read mass and stiffness matrices (.npz, .mtx/.mmf MatrixMarket, "
                    "Harwell-Boeing .hb/.rsa/.rua/.hbmat, MATLAB .mat, Nastran .op4) or an "
                    "axis folder, check them, optionally reduce them by Craig-Bampton first "
                    "and check the reduced model against the full one over the band "
                    "(frequencies, port compliance, fixed-interface modes covering the band "
                    "with a margin). Exit status 1 when a check fails.")
    p.add_argument("matrices", nargs="+", type=Path,
                   help="MASS [STIFFNESS] files (one .npz/.mat/.op4 may hold both), or an axis "
                        "folder")
    p.add_argument("--dof-map", type=Path, help="CSV naming the DOFs (name, or node,dof)")
    p.add_argument("--mass-name", metavar="NAME",
                   help="the mass matrix' name inside an .npz/.mat/.op4 file (default: the "
                        "usual names, e.g. MAA, MGG, MHH, mass)")
    p.add_argument("--stiffness-name", metavar="NAME",
                   help="the stiffness matrix' name inside the file (default: KAA, KGG, KHH, "
                        "stiffness, ...)")
    p.add_argument("--ports", type=Path,
                   help="CSV naming ports from node numbers (port,node,direction) or positions "
                        "(port,x,y,z,direction; needs --coordinates)")
    p.add_argument("--boundary", nargs="+", metavar="DOF",
                   help="reduce by Craig-Bampton to these boundary DOFs first")
    p.add_argument("--n-modes", type=number(0, 100_000, integer=True, example=20),
                   help="fixed-interface modes to keep (default: every mode up to --margin "
                        "times the band's top; 0 is a static (Guyan) reduction)")
    p.add_argument("--f-max-hz", type=number(0.0, 1e6, low_open=True, example=500, unit="Hz"),
                   help="keep fixed-interface modes up to this frequency instead")
    p.add_argument("--band-hz", type=number(0.0, 1e6, low_open=True, example=300, unit="Hz"),
                   nargs=2, metavar=("LOW", "HIGH"),
                   help="band of interest [Hz] for the reduction check (default 5 300, or the "
                        "axis' [requirements] band_hz)")
    p.add_argument("--margin", type=number(1.0, 100.0, example=1.5), default=DEFAULT_MARGIN,
                   help="the kept fixed-interface modes must reach MARGIN times the band's top "
                        f"(default {DEFAULT_MARGIN:g})")
    p.add_argument("--coordinates", type=Path,
                   help="CSV node,x,y,z [m] for geometric rigid-body mass and centre of "
                        "gravity (DOFs named <node>.<x|y|z|rx|ry|rz>) and ports by position")
    add_common_options(p)
    p.set_defaults(func=run)


def _band(args, axis=None):
    if args.band_hz is not None:
        lo, hi = args.band_hz
        if not lo < hi:
            raise ValueError(f"--band-hz needs LOW < HIGH, got {lo:g} {hi:g}")
        return (TWO_PI * lo, TWO_PI * hi)
    if axis is not None:
        return axis.requirements.band
    return (TWO_PI * 5.0, TWO_PI * 300.0)


def _check_axis(args, coords, progress):
    from ..axis import load_axis, structure_matrices
    from ..model_checks import transmission_check
    from ..structure.cbcheck import cb_check
    from ..structure.coverage import mode_coverage
    from ..structure.reduction_check import reduction_check

    ignored = [flag for flag, value in (
        ("--dof-map", args.dof_map), ("--ports", args.ports), ("--mass-name", args.mass_name),
        ("--stiffness-name", args.stiffness_name), ("--boundary", args.boundary),
        ("--n-modes", args.n_modes), ("--f-max-hz", args.f_max_hz)) if value is not None]
    if ignored:
        verb = "set" if len(ignored) > 1 else "sets"
        raise UsageError(f"{', '.join(ignored)} {verb} how matrix files are read or reduced; "
                         f"{args.matrices[0]} is an axis folder, whose [structure] says that "
                         "(dof_map, ports, mass_name, stiffness_name, reduce): drop "
                         f"{'them' if len(ignored) > 1 else 'it'}, or give the matrix files")
    with progress.task(f"loading {args.matrices[0]}"):
        axis = load_axis(args.matrices[0])
    band = _band(args, axis)
    model = axis.structure
    with progress.task(f"checking {model.n} DOFs"):
        out = {"check": cb_check(model, coordinates=coords), "transmission": None,
               "reduction": None, "coverage": mode_coverage(model, band, args.margin)}
    if axis.drive is not None:
        out["transmission"] = transmission_check(model, axis.drive)
    table = axis.tables.get("structure", {})
    if "reduce" in table:  # FE matrices reduced on loading: check against them
        with progress.task("checking the reduction against the full model"):
            data = structure_matrices(axis)  # as read, ports named
            boundary = list(table["reduce"]["boundary"])
            zeta = model.damping_ratio
            zeta = (float(zeta[0]) if zeta is not None and len(set(zeta.tolist())) == 1
                    else 0.03)
            out["reduction"] = reduction_check(data.mass, data.stiffness,
                                               data.index(boundary), model, band,
                                               margin=args.margin, damping_ratio=zeta,
                                               coordinates=coords)
    return str(args.matrices[0]), axis.name, out


def run(args) -> int:
    """Run ``servotune check``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        The exit status: 0 when every check passes, 1 when one fails. Errors are raised, and
        reported by :func:`servotune.cli.main` with status 1.
    """
    from .. import progress

    with progress.task("loading the structure tools"):
        from ..structure import io
        from ..structure.cbcheck import cb_check
        from ..structure.reduction import craig_bampton
        from ..structure.reduction_check import reduction_check

    if len(args.matrices) > 2:
        raise UsageError("give MASS [STIFFNESS]: at most two matrix files")
    if args.n_modes is not None and args.f_max_hz is not None:
        raise UsageError("give --n-modes or --f-max-hz, not both")
    coords = io.read_coordinates(args.coordinates) if args.coordinates else None
    if len(args.matrices) == 1 and args.matrices[0].is_dir():
        source, subject, out = _check_axis(args, coords, progress)
    else:
        stiffness = args.matrices[1] if len(args.matrices) == 2 else None
        with progress.task(f"reading {args.matrices[0]}"):
            data = io.read_structure(args.matrices[0], stiffness, args.dof_map,
                                     ports=args.ports, coordinates=coords,
                                     mass_name=args.mass_name,
                                     stiffness_name=args.stiffness_name)
        source, subject = data.source, args.matrices[0].stem
        if not args.boundary and data.n > DENSE_LIMIT:
            raise ValueError(f"{source}: {data.n} DOFs; give --boundary DOF ... (and "
                             "--n-modes or --f-max-hz) to reduce before the check")
        out = {"check": None, "transmission": None, "reduction": None, "coverage": None}
        if args.boundary:
            band = _band(args)
            f_max = args.f_max_hz
            if args.n_modes is None and f_max is None:
                f_max = args.margin * band[1] / TWO_PI  # cover the band by default
            with progress.task(f"Craig-Bampton reduction of {data.n} DOFs"):
                model = craig_bampton(data.mass, data.stiffness, data.index(args.boundary),
                                      n_modes=args.n_modes, f_max_hz=f_max,
                                      boundary_names=args.boundary)
            with progress.task(f"checking the reduced model ({model.n} DOFs)"):
                out["check"] = cb_check(model, coordinates=coords)
                out["reduction"] = reduction_check(data.mass, data.stiffness,
                                                   data.index(args.boundary), model, band,
                                                   margin=args.margin, coordinates=coords)
        else:
            with progress.task(f"checking {data.n} DOFs"):
                out["check"] = cb_check(data.mass, data.stiffness, data.dofs,
                                        coordinates=coords)
    run_output = RunOutput.for_args(args, "check", subject, ["results.json"])
    parts = [out["check"], out["transmission"], out["reduction"]]
    passed = all(p.passed for p in parts if p is not None)
    if out["reduction"] is None and out["coverage"] is not None:
        passed = passed and out["coverage"].covered
    result = {"source": source, **out["check"].to_dict()}
    result["model_check_passed"] = out["check"].passed
    if out["reduction"] is not None:
        result["reduction_check"] = out["reduction"].to_dict()
    if out["coverage"] is not None:
        result["band_coverage"] = out["coverage"].to_dict()
    elif out["reduction"] is not None:
        result["band_coverage"] = out["reduction"].coverage.to_dict()
    if out["transmission"] is not None:
        result["transmission"] = out["transmission"].to_dict()
    result["passed"] = passed
    result["folder"] = str(run_output.path)
    with run_output.writing() as folder:
        write_results(folder, result)
    if args.json:
        print_json(result)
    else:
        print(f"{source}:")
        print(out["check"])
        if out["reduction"] is not None:
            print(out["reduction"])
        elif out["coverage"] is not None:
            print(f"band coverage: {out['coverage'].message}")
        if out["transmission"] is not None:
            t = out["transmission"]
            print(f"transmission: {'ok' if t.passed else 'FAILED'}: {t.message}")
        print(f"overall: {'passed' if passed else 'FAILED'}")
        print(f"  wrote {run_output.path}")
    return 0 if passed else 1
