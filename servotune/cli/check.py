"""``servotune check``: read FE or reduced matrices, check them and print the report."""

from __future__ import annotations

from pathlib import Path

from ._common import RunOutput, add_common_options, number, print_json, write_results

__all__ = ["add_parser", "run"]

DENSE_LIMIT = 5000


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "check", help="check mass/stiffness matrices (symmetry, definiteness, rigid-body "
                      "mass, fixed-base frequencies, modal effective mass)",
        description="Read mass and stiffness matrices (.npz, .mtx/.mmf MatrixMarket, "
                    "Harwell-Boeing .hb/.rsa/.rua/.hbmat, MATLAB .mat) or an axis folder, "
                    "check them, optionally reduce them by Craig-Bampton first, and print the "
                    "check report.")
    p.add_argument("matrices", nargs="+", type=Path,
                   help="MASS [STIFFNESS] files (one .npz/.mat may hold both), or an axis "
                        "folder")
    p.add_argument("--dof-map", type=Path, help="CSV naming the DOFs (name, or node,dof)")
    p.add_argument("--boundary", nargs="+", metavar="DOF",
                   help="reduce by Craig-Bampton to these boundary DOFs first")
    p.add_argument("--n-modes", type=number(0, 100_000, integer=True, example=20),
                   help="fixed-interface modes to keep (default 20; 0 is a static (Guyan) "
                        "reduction)")
    p.add_argument("--f-max-hz", type=number(0.0, 1e6, low_open=True, example=500, unit="Hz"),
                   help="keep fixed-interface modes up to this frequency instead")
    p.add_argument("--coordinates", type=Path,
                   help="CSV node,x,y,z [m] for geometric rigid-body mass and centre of "
                        "gravity (DOFs named <node>.<x|y|z|rx|ry|rz>)")
    add_common_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import progress

    with progress.task("loading the structure tools"):
        from ..axis import load_axis
        from ..structure import io
        from ..structure.reduction import cb_check, craig_bampton

    if len(args.matrices) > 2:
        raise ValueError("give MASS [STIFFNESS]: at most two matrix files")
    if args.n_modes is not None and args.f_max_hz is not None:
        raise ValueError("give --n-modes or --f-max-hz, not both")
    coords = io.read_coordinates(args.coordinates) if args.coordinates else None
    if len(args.matrices) == 1 and args.matrices[0].is_dir():
        with progress.task(f"loading {args.matrices[0]}"):
            axis = load_axis(args.matrices[0])
        out = RunOutput.for_args(args, "check", axis.name, ["results.json"])
        with progress.task(f"checking {axis.structure.n} DOFs"):
            check = cb_check(axis.structure, coordinates=coords)
        source = str(args.matrices[0])
    else:
        stiffness = args.matrices[1] if len(args.matrices) == 2 else None
        with progress.task(f"reading {args.matrices[0]}"):
            data = io.read_structure(args.matrices[0], stiffness, args.dof_map)
        source = data.source
        if not args.boundary and data.n > DENSE_LIMIT:
            raise ValueError(f"{source}: {data.n} DOFs; give --boundary DOF ... (and "
                             "--n-modes or --f-max-hz) to reduce before the check")
        out = RunOutput.for_args(args, "check", args.matrices[0].stem, ["results.json"])
        if args.boundary:
            n_modes = args.n_modes if args.n_modes is not None or args.f_max_hz else 20
            with progress.task(f"Craig-Bampton reduction of {data.n} DOFs"):
                model = craig_bampton(data.mass, data.stiffness, data.index(args.boundary),
                                      n_modes=n_modes, f_max_hz=args.f_max_hz,
                                      boundary_names=args.boundary)
            with progress.task(f"checking the reduced model ({model.n} DOFs)"):
                check = cb_check(model, coordinates=coords)
        else:
            with progress.task(f"checking {data.n} DOFs"):
                check = cb_check(data.mass, data.stiffness, data.dofs, coordinates=coords)
    result = {"source": source, **check.to_dict(), "folder": str(out.path)}
    with out.writing() as folder:
        write_results(folder, result)
    if args.json:
        print_json(result)
    else:
        print(f"{source}:")
        print(check)
        print(f"  wrote {out.path}")
    return 0 if check.passed else 1
