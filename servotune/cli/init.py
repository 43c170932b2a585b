"""``servotune init``: write a commented starter axis description.

The one command whose output is not a run folder under ``--out``: it writes the axis folder
DIR itself (``axis.toml`` and ``structure.npz``), names the axis after DIR, and refuses to
replace files there unless ``--force`` is given (they may hold the user's own data).
"""

from __future__ import annotations

import os
from pathlib import Path

from ._common import CliError, add_common_options, print_json

__all__ = ["add_parser", "run"]

FILES = ("axis.toml", "structure.npz")


def add_parser(subparsers) -> None:
    """Add the ``servotune init`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "init", help="write a commented starter axis description (axis.toml + structure.npz)",
        description="Write a complete, loadable axis description into DIR: a commented "
                    "axis.toml (every field with its unit and meaning; the axis is named after "
                    "DIR) and a small lumped ball-screw axis in structure.npz. Replace them "
                    "with your axis' data.")
    p.add_argument("folder", type=Path, metavar="DIR",
                   help="folder to write into (created if needed)")
    p.add_argument("--force", action="store_true",
                   help="replace axis.toml and structure.npz if DIR has them")
    add_common_options(p, out=False)
    p.set_defaults(func=run)


def _check_folder(folder: Path, force: bool) -> None:
    """Refuse, before writing, a folder that cannot take the starter axis."""
    if folder.exists() and not folder.is_dir():
        raise CliError(f"{folder} is a file, not a folder; give a new or existing folder")
    existing = folder
    while not existing.exists() and existing.parent != existing:
        existing = existing.parent
    if not existing.is_dir():
        raise CliError(f"{folder}: {existing} is a file, so no folder can be made under it; "
                       "give another folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise CliError(f"{folder}: no permission to write into {existing}; give a folder you "
                       "can write to")
    present = [name for name in FILES if (folder / name).exists()]
    if present and not force:
        raise CliError(f"{folder} already has {' and '.join(present)}; give --force to replace "
                       f"{'it' if len(present) == 1 else 'them'} with the starter, or choose "
                       "another folder")
    for name in present:
        if (folder / name).is_dir():
            raise CliError(f"{folder / name} is a folder; move it away first")


def run(args) -> int:
    """Run ``servotune init``.

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
    folder = args.folder
    _check_folder(folder, args.force)
    from ..template import axis_name_for, write_template

    name = axis_name_for(folder)
    try:
        files = write_template(folder, force=True, name=name)
    except OSError as exc:
        raise CliError(f"{folder}: cannot write there ({exc.strerror or exc}); give a folder "
                       "you can write to") from None
    if args.json:
        print_json({"axis": name, "folder": str(folder), "files": [str(f) for f in files]})
        return 0
    for f in files:
        print(f"wrote {f}")
    print(f"axis name: {name} (in axis.toml, [axis] name)")
    print(f"next: servotune modes {folder}   and   servotune tune {folder}")
    return 0
