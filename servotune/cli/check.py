"""``servotune check``: read FE or reduced matrices, check them and print the report."""

from __future__ import annotations

from pathlib import Path

from ..axis import load_axis
from ..structure import io
from ..structure.reduction import cb_check, craig_bampton
from ._common import add_output_options, print_json

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
    p.add_argument("--n-modes", type=int, help="fixed-interface modes to keep (default 20)")
    p.add_argument("--f-max-hz", type=float, help="keep fixed-interface modes up to this "
                                                  "frequency instead")
    p.add_argument("--coordinates", type=Path,
                   help="CSV node,x,y,z [m] for geometric rigid-body mass and centre of "
                        "gravity (DOFs named <node>.<x|y|z|rx|ry|rz>)")
    add_output_options(p, default_out=None)
    p.set_defaults(func=run)


def run(args) -> int:
    coords = io.read_coordinates(args.coordinates) if args.coordinates else None
    if len(args.matrices) == 1 and args.matrices[0].is_dir():
        model = load_axis(args.matrices[0]).structure
        check = cb_check(model, coordinates=coords)
        source = str(args.matrices[0])
    else:
        if len(args.matrices) > 2:
            raise ValueError("give MASS [STIFFNESS]: at most two matrix files")
        stiffness = args.matrices[1] if len(args.matrices) == 2 else None
        data = io.read_structure(args.matrices[0], stiffness, args.dof_map)
        source = data.source
        if args.boundary:
            n_modes = args.n_modes if args.n_modes is not None or args.f_max_hz else 20
            model = craig_bampton(data.mass, data.stiffness, data.index(args.boundary),
                                  n_modes=n_modes, f_max_hz=args.f_max_hz,
                                  boundary_names=args.boundary)
            check = cb_check(model, coordinates=coords)
        elif data.n <= DENSE_LIMIT:
            check = cb_check(data.mass, data.stiffness, data.dofs, coordinates=coords)
        else:
            raise ValueError(f"{source}: {data.n} DOFs; give --boundary DOF ... (and "
                             "--n-modes or --f-max-hz) to reduce before the check")
    if args.json:
        print_json({"source": source, **check.to_dict()})
    else:
        print(f"{source}:")
        print(check)
    return 0 if check.passed else 1
