"""``servotune init``: write a commented starter axis description."""

from __future__ import annotations

from pathlib import Path

from ..template import write_template
from ._common import print_json

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "init", help="write a commented starter axis description (axis.toml + structure.npz)",
        description="Write a complete, loadable axis description into DIR: a commented "
                    "axis.toml (every field with its unit and meaning) and a small lumped "
                    "ball-screw axis in structure.npz. Replace them with your axis' data.")
    p.add_argument("folder", type=Path, help="folder to write into (created if needed)")
    p.add_argument("--force", action="store_true", help="overwrite existing files")
    p.add_argument("--json", action="store_true", help="print one JSON object of the result")
    p.set_defaults(func=run)


def run(args) -> int:
    files = write_template(args.folder, args.force)
    if args.json:
        print_json({"files": [str(f) for f in files]})
        return 0
    for f in files:
        print(f"wrote {f}")
    print(f"next: servotune modes {args.folder}   and   servotune tune {args.folder}")
    return 0
