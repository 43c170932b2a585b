"""The ``servotune`` command: thin argument parsing over the library, no numerics here.

Each subcommand lives in its own module of this package and exposes ``add_parser(subparsers)``
(which registers it and sets ``func``) and a ``run(args) -> int``. With ``--json`` a subcommand
prints exactly one JSON object of its results on standard output.

:func:`main` loads only the module of the subcommand given (``servotune --help`` lists the
others from :data:`SUMMARIES`), so that help and argument errors come back at once; it runs the
subcommand with progress bars on standard error when wanted (:mod:`servotune.progress`) and with
Ctrl-C turned into exit status 130 and one line saying what was interrupted
(:mod:`servotune.interrupt`). Errors of the user's input end in one line ``servotune CMD: error:
...`` and exit status 1; argument errors in argparse's usage message and exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import os
import re
import sys

__all__ = ["main", "build_parser", "COMMANDS", "SUMMARIES"]

# subcommand modules, in the order ``servotune --help`` lists them
COMMANDS = ("init", "twomass", "modes", "identify", "check", "friction", "bode", "compliance",
            "nlcompliance", "lobes", "tune", "table3", "verify", "study")

# one line per subcommand for ``servotune --help`` without importing every module (a command
# missing here is imported to list it); tests/test_cli.py checks them against the modules
SUMMARIES = {
    "init": "write a commented starter axis description (axis.toml + structure.npz)",
    "twomass": "fixed points, Copt and g(alpha) of the two-mass layouts (Fig 4, 5)",
    "modes": "natural frequencies and each mode's share of work-piece X motion",
    "identify": "modes from measured FRFs (LSCF/LSFD); with --axis, the axis model updated to "
                "them",
    "check": "check mass/stiffness matrices (symmetry, definiteness, rigid-body mass, "
             "fixed-base frequencies, modal effective mass) and a reduction against the full "
             "model",
    "friction": "LuGre friction: equivalent damping (Eq 8-10), figures, fits",
    "bode": "loop transfer functions of the velocity and position loops, with margins",
    "compliance": "work-piece X compliance with a guide-way contact model (Fig 9)",
    "nlcompliance": "amplitude-dependent compliance with LuGre pads by harmonic balance "
                    "(Table 3, A-C)",
    "lobes": "chatter stability lobes, b_crit and the chatter margin (sec 2)",
    "tune": "tune guide-way damping C, Kv and the velocity PI (casadi), verify",
    "table3": "simulate the paper's Table 3 (sine sweeps with LuGre friction)",
    "verify": "does the nonlinear axis (LuGre) do what a tuned design claims?",
    "study": "an axis sampled over what varies, tuned/verified per sample on dask.distributed",
}

EXIT_INTERRUPTED = 130  # 128 + SIGINT, as shells report it


def _module(name: str):
    return importlib.import_module(f"{__name__}.{name}")


class _Parser(argparse.ArgumentParser):
    """argparse's parser whose usage error keeps its message on the exit (``usage_message``),
    so that under ``--json`` it becomes the command's one JSON object too. Flags are not
    abbreviated: a mistyped ``--freq`` is refused, not taken for ``--frequency-hz``."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)
        self.given: list[str] = []

    def parse_known_args(self, args=None, namespace=None):
        self.given = list(sys.argv[1:] if args is None else args)
        return super().parse_known_args(args, namespace)

    def error(self, message):
        # argparse takes a negative number with an exponent (-1e-6) for a flag: say how to
        # give it, instead of only "expected one argument"
        found = re.match(r"argument (\S+?)(?:/\S+)?: expected one argument$", message)
        if found and found.group(1) in self.given:
            i = self.given.index(found.group(1))
            value = self.given[i + 1] if i + 1 < len(self.given) else ""
            if re.match(r"^-\.?\d", value):
                message += (f" ({value} reads as a flag: write {found.group(1)}={value} for a "
                            "negative number)")
        try:
            super().error(message)
        except SystemExit as exc:
            exc.usage_message = message
            raise


def build_parser(command: str | None = "*") -> argparse.ArgumentParser:
    """Return the argument parser.

    Parameters
    ----------
    command : str or None
        ``"*"`` (default) registers every subcommand in full; a subcommand name registers that
        one in full and lists the others by name and summary only (fast); None lists all.

    Returns
    -------
    argparse.ArgumentParser
        The ``servotune`` parser with its sub-commands.
    """
    from .. import __version__

    parser = _Parser(
        prog="servotune",
        description="Design machine-tool feed axes where servo drive, guide-way friction and "
                    "structure interact (Bianchi et al., Procedia CIRP 21, 2014).",
        epilog="Every command takes --json (one JSON object on standard output) and --quiet; "
               "commands that write results put them in --out DIR/<command>_<subject> "
               "(default out/). 'servotune COMMAND --help' for its flags.")
    parser.add_argument("--version", action="version", version=f"servotune {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        if command == "*" or name == command or name not in SUMMARIES:
            _module(name).add_parser(subparsers)
        else:
            subparsers.add_parser(name, help=SUMMARIES[name], add_help=False)
    return parser


def _chosen(argv: list[str]) -> str | None:
    """The subcommand named on the command line (the first word that is not an option)."""
    for word in argv:
        if word == "--":
            return None
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def _label(args) -> str:
    words = ["servotune", args.command]
    sub = getattr(args, "friction_command", None)
    if sub:
        words.append(sub)
    return " ".join(words)


def _text(exc: Exception) -> str:
    """The message of an error; a KeyError's own repr quotes are dropped."""
    if isinstance(exc, KeyError) and len(exc.args) == 1 and isinstance(exc.args[0], str):
        return exc.args[0]
    return str(exc)


def _os_message(exc: OSError) -> str:
    if exc.filename is not None and exc.strerror:
        return f"{exc.filename}: {exc.strerror.lower()}"
    return str(exc)


def _interrupted(label: str, args, what: str | None) -> int:
    """Print the one line of an interrupted command; the exit status for it."""
    from .. import interrupt

    interrupt.restore_stderr()
    try:  # a progress bar's line may still stand (its clearing went to the silenced stderr)
        if sys.stderr.isatty():
            sys.stderr.write("\r\x1b[K")
    except (AttributeError, ValueError, OSError):
        pass
    run = getattr(args, "run_output", None)
    done = (f"the results in {run.path} were written before" if run is not None
            and run.committed else "nothing was written")
    line = f"{label}: interrupted" + (f" during {what}" if what else "") + f"; {done}"
    print(line, file=sys.stderr)
    return _json_error(args, label, "interrupted", line, status=EXIT_INTERRUPTED)


#: BLAS/OpenMP thread counts the command sets when the user has not (see :func:`main`)
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def _one_blas_thread() -> None:
    """One BLAS thread per process unless the environment says otherwise: the command's
    matrices are small (tens to hundreds of states), where threaded BLAS only costs (on two
    loaded cores a tuning took 80 s instead of 18 s), and its worker processes bring their own
    parallelism. Set before numpy is loaded; worker processes inherit it."""
    if "numpy" in sys.modules:
        return
    for name in THREAD_VARIABLES:
        os.environ.setdefault(name, "1")


def main(argv: list[str] | None = None) -> int:
    """Run the ``servotune`` command and return the process exit status.

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        0 done, 1 an error of the input or a design that failed its checks, 2 a usage error,
        3 a design whose nonlinear verification was skipped (``tune --no-simulation``), 130
        interrupted.
    """
    _one_blas_thread()
    from .. import interrupt, progress
    from ._common import CliError, UsageError, show_progress

    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(_chosen(argv))
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a usage error (already printed)
        message = getattr(exc, "usage_message", None)
        if message is not None and "--json" in argv:
            command = _chosen(argv)
            label = "servotune" + (f" {command}" if command else "")
            _json_error(argparse.Namespace(json=True), label, "usage", message, status=2)
        return exc.code if isinstance(exc.code, int) else 2
    if not getattr(args, "func", None):
        parser.print_usage(sys.stderr)
        print("servotune: error: give a COMMAND ('servotune --help' lists them)",
              file=sys.stderr)
        return 2
    label = _label(args)
    try:
        with interrupt.handling(silence_native_stderr=True), \
                progress.reporting(show_progress(args)):
            try:
                return int(args.func(args) or 0)
            except KeyboardInterrupt:
                return _interrupted(label, args, progress.current())
    except KeyboardInterrupt:  # pressed while the handling was being set up or taken down
        return _interrupted(label, args, None)
    except UsageError as exc:
        print(f"{label}: error: {_text(exc)} ('{label} --help' lists the arguments)",
              file=sys.stderr)
        _json_error(args, label, "usage", _text(exc), status=2)
        return 2
    except (CliError, ValueError, RuntimeError, LookupError) as exc:
        print(f"{label}: error: {_text(exc)}", file=sys.stderr)
        return _json_error(args, label, "input", _text(exc))
    except OSError as exc:
        if isinstance(exc, BrokenPipeError):  # output piped into e.g. head: stop quietly
            sys.stderr.close()
            return 0
        print(f"{label}: error: {_os_message(exc)}", file=sys.stderr)
        return _json_error(args, label, "file", _os_message(exc))
    except Exception as exc:
        if os.environ.get("SERVOTUNE_TRACEBACK"):
            raise
        text = (f"internal error ({type(exc).__name__}: {exc}); please report it with the "
                "command line (SERVOTUNE_TRACEBACK=1 shows the traceback)")
        print(f"{label}: {text}", file=sys.stderr)
        return _json_error(args, label, "internal", text)


def _json_error(args, label: str, kind: str, text: str, status: int = 1) -> int:
    """Under ``--json``, print the error as the command's one JSON object too (``status``
    "error", ``error_kind`` usage/input/file/internal, ``error``, ``exit_status``); return
    ``status``."""
    if getattr(args, "json", False):
        import json

        print(json.dumps({"command": label, "status": "error", "error_kind": kind,
                          "error": text, "exit_status": status}))
    return status


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
