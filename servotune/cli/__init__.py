"""The ``servotune`` command: thin argument parsing over the library, no numerics here.

Each subcommand lives in its own module of this package and exposes ``add_parser(subparsers)``
(which registers it and sets ``func``) and a ``run(args) -> int``. With ``--json`` a subcommand
prints exactly one JSON object of its results on standard output.
"""

from __future__ import annotations

import argparse
import importlib
import sys

__all__ = ["main", "build_parser"]

# subcommand modules, in the order ``servotune --help`` lists them
COMMANDS = ("init", "twomass", "modes", "check", "friction", "bode", "compliance", "lobes", "tune",
            "table3", "verify")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    from .. import __version__

    parser = argparse.ArgumentParser(
        prog="servotune",
        description="Design machine-tool feed axes where servo drive, guide-way friction and "
                    "structure interact (Bianchi et al., Procedia CIRP 21, 2014).")
    parser.add_argument("--version", action="version", version=f"servotune {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"{__name__}.{name}").add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the ``servotune`` command; returns the process exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except (ValueError, FileExistsError, FileNotFoundError, RuntimeError) as exc:
        print(f"servotune {args.command}: error: {exc}", file=sys.stderr)
        return 1
    except BrokenPipeError:  # output piped into e.g. head: stop quietly
        sys.stderr.close()
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
