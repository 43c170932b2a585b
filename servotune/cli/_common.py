"""What every subcommand shares: the flags and their limits, the output policy, JSON printing.

Flags (one name and one default per notion, see the README's "Command-line flags"):

``--json``       print one JSON object of the results on standard output (and nothing else)
``--quiet``      no progress bars (they are also off under ``--json`` and when standard error
                 is not a terminal)
``--out DIR``    parent folder of the results (default ``out``); a run writes into
                 ``DIR/<command>_<subject>`` (see :class:`RunOutput`)
``--no-plots``   write no figures (commands that draw)
``--workers N``  processes for parallel work (default: the CPUs this process may use)
``--duration S`` length of each nonlinear sine sweep [s] (default 20, the paper's)

Numeric flags are parsed by the types below (:func:`number`, :data:`STARTS`, ...): a wrong
value stops the command before any work with a message that says what was given, the range
accepted and an example.

The library is imported inside functions only, so that ``servotune --help`` and argument
errors stay fast.

A command adopts all of it like this (``tune``, for example)::

    def add_parser(subparsers):
        p = subparsers.add_parser("tune", help=...)
        p.add_argument("axis")
        p.add_argument("--starts", type=STARTS, default=4)
        add_duration_option(p, aliases=("--sweep-duration",))
        add_workers_option(p)
        add_common_options(p, plots=True)
        p.set_defaults(func=run)

    def run(args):
        from .. import interrupt, progress
        with progress.task(f"loading {args.axis}"):
            from ..axis import load_axis
            axis = load_axis(args.axis)
        require_section(axis, "friction", "[friction]", "servotune tune")
        out = RunOutput.for_args(args, "tune", axis.name, ["report.html", "results.json"])
        with interrupt.process_pool(args.workers or default_workers()) as pool:
            job = ...                                  # the work, reporting progress
        with out.writing() as folder:                  # all or nothing, swapped in at the end
            report.write_html_report(job, folder)
            write_results(folder, results)
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import shutil
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ..names import safe_name

__all__ = [
    # errors
    "CliError",
    "UsageError",
    "friction_law_of",
    "OutputError",
    # numeric flag types
    "number",
    "finite_float",
    "STARTS",
    "WORKERS",
    "DURATION",
    "FRACTION",
    "COUNT",
    # flags
    "DEFAULT_OUT",
    "DEFAULT_DURATION",
    "add_common_options",
    "refuse_no_plots",
    "add_output_options",
    "out_folder",
    "add_workers_option",
    "add_duration_option",
    "add_contact_options",
    "contact_from_args",
    "check_contact_args",
    "default_workers",
    "show_progress",
    # output policy
    "RunOutput",
    "safe_name",
    "save_figure",
    "write_results",
    # JSON
    "to_jsonable",
    "print_json",
    # missing sections
    "require_section",
    "default_notes",
]

DEFAULT_OUT = "out"
DEFAULT_DURATION = 20.0  # [s] the paper's sweep (Table 3: 10 -> 100 Hz in 20 s)


def friction_law_of(axis) -> str | None:
    """The name of an axis' friction law (``friction_law`` of a command's JSON), or None.

    Parameters
    ----------
    axis : servotune.axis.Axis or None
        The axis (None: a command that works without one).

    Returns
    -------
    str or None
    """
    friction = getattr(axis, "friction", None)
    return None if friction is None else friction.law.name


class CliError(Exception):
    """A user error found by the command line itself; its text is the whole message."""


class OutputError(CliError):
    """The output folder cannot take the results (a file in the way, no permission, ...)."""


class UsageError(CliError):
    """A missing or conflicting argument the parser cannot see (e.g. one of several that are
    each optional): exit status 2, as argparse's own usage errors."""


# --- numeric flags -----------------------------------------------------------------------------

def _bound(value, integer: bool) -> str:
    if integer:
        return str(int(value))
    return f"{value:g}"


def number(low=None, high=None, *, integer: bool = False, low_open: bool = False,
           high_open: bool = False, example=None, unit: str = ""):
    """An argparse ``type`` for a finite number in an interval.

    Parameters
    ----------
    low, high : float or int, optional
        The limits (None: unbounded on that side).
    integer : bool
        Whole numbers only.
    low_open, high_open : bool
        Exclude the limit itself (``(0, 1]`` is ``low=0, low_open=True, high=1``).
    example : str, optional
        A good value to suggest in the message.
    unit : str
        Unit of the value, for the message ("s", "Hz", "N/m").

    Returns
    -------
    callable
        ``str -> int | float`` raising ``argparse.ArgumentTypeError`` with what was given,
        the accepted range and an example.

    Examples
    --------
    >>> STARTS("4")
    4
    >>> STARTS("0")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: '0' is not accepted: give a whole number from 1 to 100 (e.g. 4)
    """
    kind = "whole number" if integer else "number"
    suffix = f" {unit}" if unit else ""
    if low is not None and high is not None:
        left = "(" if low_open else "["
        right = ")" if high_open else "]"
        if integer:
            accepted = f"a {kind} from {_bound(low, True)} to {_bound(high, True)}{suffix}"
        else:
            accepted = (f"a {kind} in {left}{_bound(low, False)}, {_bound(high, False)}{right}"
                        f"{suffix}")
    elif low is not None:
        accepted = f"a {kind} {'>' if low_open else '>='} {_bound(low, integer)}{suffix}"
    elif high is not None:
        accepted = f"a {kind} {'<' if high_open else '<='} {_bound(high, integer)}{suffix}"
    else:
        accepted = f"a finite {kind}{suffix}"
    hint = f" (e.g. {example})" if example is not None else ""

    def parse(text: str):
        try:
            value = int(text) if integer else float(text)
        except (TypeError, ValueError):
            raise argparse.ArgumentTypeError(
                f"{text!r} is not a {kind}: give {accepted}{hint}") from None
        bad = not math.isfinite(value)
        if low is not None and not bad:
            bad = value <= low if low_open else value < low
        if high is not None and not bad:
            bad = value >= high if high_open else value > high
        if bad:
            raise argparse.ArgumentTypeError(f"{text!r} is not accepted: give {accepted}{hint}")
        return value

    parse.__name__ = "whole number" if integer else "number"  # argparse names it on errors
    parse.accepted = accepted
    return parse


finite_float = number()
STARTS = number(1, 100, integer=True, example=4)          # tune --starts
WORKERS = number(1, 256, integer=True, example=2)         # --workers
DURATION = number(0.0, 3600.0, low_open=True, example=20, unit="s")   # --duration
FRACTION = number(0.0, 1.0, example=0.5)                  # weights such as --chatter-weight
COUNT = number(1, 100_000, integer=True, example=10)      # how many items to show or keep


def default_workers() -> int:
    """The CPUs this process may run on (the default of ``--workers``)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


# --- flags -------------------------------------------------------------------------------------

def add_common_options(parser, *, out: bool = True, plots: bool = False,
                       nested: bool = False) -> None:
    """``--json`` and ``--quiet`` for every command; ``--out`` for those that write results,
    ``--no-plots`` for those that draw.

    Parameters
    ----------
    parser : argparse.ArgumentParser
    out : bool
        The command writes results into ``--out``.
    plots : bool
        The command writes figures (``--no-plots`` turns them off).
    nested : bool
        ``parser`` is a sub-subcommand (``friction fit``) whose parent has the same flags: the
        flags then default to "not given" so that a flag given before the sub-subcommand
        (``friction --json fit``) is kept.
    """
    keep = {"default": argparse.SUPPRESS} if nested else {}
    parser.add_argument("--json", action="store_true",
                        help="print one JSON object of the results (SI values) and nothing "
                             "else on standard output", **keep)
    parser.add_argument("--quiet", action="store_true",
                        help="no progress bars on standard error (also off under --json and "
                             "when standard error is not a terminal)", **keep)
    if out:
        parser.add_argument("--out", type=out_folder, metavar="DIR",
                            default=argparse.SUPPRESS if nested else Path(DEFAULT_OUT),
                            help=f"parent folder of the results (default {DEFAULT_OUT}); this "
                                 "run writes into DIR/<command>_<subject>, replacing its own "
                                 "earlier results")
        # older spelling: results used to be kept unless --force; now a run replaces its own
        parser.add_argument("--force", action="store_true", help=argparse.SUPPRESS, **keep)
    if plots:
        parser.add_argument("--no-plots", action="store_true",
                            help="write no figures (faster; matplotlib is not loaded)", **keep)
    elif not nested:
        command = parser.prog.split(" ", 1)[-1]
        refuse_no_plots(parser, command, "results.json" if out else "the axis files")


def refuse_no_plots(parser, command: str, writes: str = "results.json") -> None:
    """``--no-plots`` on a command that draws no figure: not listed, and refused as a usage
    error (exit status 2) that says why, rather than argparse's bare "unrecognized
    arguments"."""
    class _Refuse(argparse.Action):
        def __call__(self, parser, namespace, values, option_string=None):
            parser.error(f"{option_string}: servotune {command} writes no figures (only "
                         f"{writes}), so there are none to turn off; drop the flag")

    parser.add_argument("--no-plots", nargs=0, action=_Refuse, default=False,
                        help=argparse.SUPPRESS)


def out_folder(text: str) -> Path:
    """``--out DIR``: a folder name, not an empty text (an unset shell variable would put the
    results into the current folder unnoticed)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"{text!r} is empty: give the folder for the results, "
                                         f"e.g. --out {DEFAULT_OUT}")
    return Path(text)


def add_output_options(parser, default_out: str | None = DEFAULT_OUT) -> None:
    """The flags of earlier versions (``--json``, ``--out DIR``, ``--force``) for commands that
    have not moved to :func:`add_common_options` and :class:`RunOutput` yet; ``--quiet`` is
    added too."""
    parser.add_argument("--json", action="store_true",
                        help="print one JSON object of the results (SI values)")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress bars on standard error")
    if default_out is not None:
        parser.add_argument("--out", type=out_folder, default=Path(default_out),
                            help=f"folder for figures and results (default: {default_out})")
        parser.add_argument("--force", action="store_true",
                            help="overwrite existing output files")


def add_workers_option(parser) -> None:
    """``--workers N``: processes for parallel work (default: the CPUs available)."""
    parser.add_argument("--workers", type=WORKERS, default=None, metavar="N",
                        help="parallel processes (default: the CPUs this process may use; 1 "
                             "runs in this process)")


def add_duration_option(parser, aliases=()) -> None:
    """``--duration S``: length of each nonlinear sine sweep [s]; ``aliases`` are older
    spellings (such as ``--sweep-duration``), accepted but not listed."""
    parser.add_argument("--duration", type=DURATION, default=DEFAULT_DURATION, metavar="S",
                        help=f"length of each sine sweep [s] (default {DEFAULT_DURATION:g}, the "
                             "paper's)")
    for alias in aliases:
        parser.add_argument(alias, type=DURATION, dest="duration", help=argparse.SUPPRESS)


def show_progress(args) -> bool:
    """Progress bars for this run: not with ``--quiet`` or ``--json``, and only when standard
    error is a terminal."""
    if getattr(args, "quiet", False) or getattr(args, "json", False):
        return False
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


_DAMPING = number(0.0, 1e12, example="5e5", unit="N s/m")
_AMPLITUDE = number(0.0, 0.1, low_open=True, example="2e-6", unit="m")
_FREQUENCY = number(0.0, 1e5, low_open=True, example=50, unit="Hz")
_SPEED = number(-10.0, 10.0, example=0.03, unit="m/s")


def add_contact_options(parser, default: str = "viscous") -> None:
    """``--contact`` and its parameters, as the analysis subcommands spell them."""
    from ..contact_kinds import contact_kind, contact_kinds

    kinds = "; ".join(f"{k}: {contact_kind(k).summary}" for k in contact_kinds())
    parser.add_argument("--contact", choices=contact_kinds(), default=default,
                        help=f"guide-way model, built from the axis' friction law ({kinds}; "
                             f"default {default})")
    parser.add_argument("--c", type=_DAMPING, default=None,
                        help="viscous guide-way damping C [N s/m] (axis total), "
                             f"{_DAMPING.accepted}; only with --contact viscous")
    parser.add_argument("--amplitude", type=_AMPLITUDE, default=None,
                        help=f"vibration amplitude [m], {_AMPLITUDE.accepted}; needed by and "
                             "only with --contact equivalent")
    parser.add_argument("--frequency-hz", type=_FREQUENCY, default=None,
                        help=f"vibration frequency [Hz], {_FREQUENCY.accepted}; needed by and "
                             "only with --contact equivalent (not guessed: give it)")
    parser.add_argument("--speed", type=_SPEED, default=None,
                        help=f"sliding speed [m/s], {_SPEED.accepted} and not 0; needed by and "
                             "only with --contact sliding")
    parser.add_argument("--continuous", action="store_true",
                        help="the drive in continuous time, as the paper models it (no "
                             "sampling, no delays) instead of the digital drive of "
                             "[drive.sampling]")


def axis_from_args(axis, args):
    """The axis with the drive the options ask for (``--continuous``: the paper's model)."""
    return axis.with_continuous_drive() if getattr(args, "continuous", False) else axis


def check_contact_args(args) -> None:
    """Refuse a contact parameter given with a ``--contact`` that does not use it, and a
    ``--contact`` given without the parameters it needs, naming the flags.

    Raises
    ------
    CliError
    """
    from ..contact_kinds import CONTACT_PARAMETERS, contact_kind, contact_kinds

    kind = args.contact
    spec = contact_kind(kind)
    values = {name: getattr(args, name, None) for name in CONTACT_PARAMETERS}
    for name, value in values.items():
        if value is not None and name not in spec.parameters:
            param = CONTACT_PARAMETERS[name]
            user = next(k for k in contact_kinds() if name in contact_kind(k).parameters)
            raise CliError(f"{param.flag} sets {param.what} of --contact {user}; it has no "
                           f"meaning with --contact {kind}: drop it or use --contact {user}")
    missing = spec.missing(values)
    if missing:
        flags = " and ".join(("a non-zero " if CONTACT_PARAMETERS[n].nonzero else "")
                             + CONTACT_PARAMETERS[n].flag for n in missing)
        raise CliError(f"--contact {kind} needs {flags}: {spec.purpose}, e.g. {spec.example}")


def contact_from_args(axis, args):
    """The contact model the options ask for (the options checked by
    :func:`check_contact_args`)."""
    from ..analysis import axis_contact

    check_contact_args(args)
    return axis_contact(axis, args.contact, amplitude=args.amplitude,
                        frequency_hz=args.frequency_hz, speed=args.speed, c=args.c)


def require_section(axis, attribute: str, section: str, command: str, fix: str = "") -> None:
    """Stop with a clear error when ``axis`` lacks a section the command needs.

    Parameters
    ----------
    axis : servotune.axis.Axis
    attribute : str
        The attribute of the Axis that holds the section (``"drive"``, ``"cutting"``).
    section : str
        The TOML section, as the user writes it (``"[cutting]"``).
    command : str
        What needs it ("servotune lobes").
    fix : str
        How else to proceed, appended to the message.
    """
    if getattr(axis, attribute, None) is None:
        where = getattr(axis, "path", None)
        toml = f"{Path(where) / 'axis.toml'}" if where is not None else f"axis {axis.name!r}"
        raise CliError(f"{toml} has no {section} section, which {command} needs: add it "
                       f"(servotune init DIR writes a commented example){fix}")


def default_notes(axis) -> list[str]:
    """One line per default that stands in for what the axis description omits (an optional
    section or field), as the loader recorded them (for the text output and the ``notes`` of
    the JSON)."""
    return list(getattr(axis, "defaults", ()) or ())


# --- the output policy -------------------------------------------------------------------------
# (safe_name, the rule for names in file names, is servotune.names.safe_name)


class RunOutput:
    """The results folder of one run: ``<--out>/<command>_<subject>``.

    The policy, the same for every command:

    * a run writes only inside ``--out``, into the folder named after its command and subject
      (the axis, the data file, ...; made safe with :func:`safe_name`);
    * it writes everything into a fresh hidden folder next to it and swaps it into place when
      complete, so an interruption or an error leaves the earlier results untouched and no
      half-written file;
    * it replaces its own earlier results (the files listed by the earlier run of the same
      command, or files it would write again) and refuses, before any work, only when the
      folder holds something else that would be lost, saying what and what to do;
    * ``--out`` naming a file, a folder under a file or a folder without write permission is a
      clear error before any work.

    Parameters
    ----------
    out : path-like
        The ``--out`` folder (created when the results are written).
    command : str
        The command ("bode", "friction_fit").
    subject : str
        What the run is about: an axis name, a file stem.
    files : iterable of str
        Names of the files the run will write (for the check before any work).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> top = pathlib.Path(tempfile.mkdtemp())
    >>> run = RunOutput(top, "bode", "../../x", ["bode.png"])
    >>> run.path == top / "bode_x"
    True
    >>> with run.writing() as folder:
    ...     _ = (folder / "bode.png").write_bytes(b"png")
    >>> sorted(p.name for p in run.path.iterdir())
    ['.servotune-run.json', 'bode.png']
    """

    MANIFEST = ".servotune-run.json"

    def __init__(self, out, command: str, subject: str, files=(), source=None):
        self.out = Path(out)
        self.command = str(command)
        self.subject = str(subject)
        self.name = f"{safe_name(command)}_{safe_name(subject)}"
        self.path = self.out / self.name
        self.files = tuple(files)
        if source is not None:  # an axis given by its axis.toml is the same axis as its folder
            source = Path(source).resolve()
            source = source.parent if source.name == "axis.toml" and source.is_file() else source
        self.source = None if source is None else str(source)
        self.committed = False
        self.check()

    @classmethod
    def for_args(cls, args, command: str, subject: str, files=()) -> RunOutput:
        """The run folder of a parsed command line (``args.out``), checked now; remembered on
        ``args`` so that an interruption can say whether anything was written. The axis
        folder of the command line (``args.axis``), when there is one, is the run's source:
        the results of another axis of the same name are not replaced."""
        axis = getattr(args, "axis", None)
        source = axis if isinstance(axis, str | Path) and Path(axis).exists() else None
        run = cls(args.out, command, subject, files, source=source)
        args.run_output = run
        return run

    def file(self, name: str) -> Path:
        """Where ``name`` will be once the run is written."""
        return self.path / name

    def _flag(self) -> str:
        return f"--out {self.out}"

    def check(self) -> None:
        """Refuse now, before any work, what writing would fail on or lose.

        Raises
        ------
        OutputError
        """
        out = self.out
        if out.exists() and not out.is_dir():
            raise OutputError(f"{self._flag()}: {out} is a file, not a folder; give a folder "
                              "(it is created if needed)")
        existing = out
        while not existing.exists():
            if existing.parent == existing:
                break
            existing = existing.parent
        if existing.exists() and not existing.is_dir():
            raise OutputError(f"{self._flag()}: {existing} is a file, so no folder can be made "
                              "under it; give another folder")
        if existing.exists() and not os.access(existing, os.W_OK | os.X_OK):
            raise OutputError(f"{self._flag()}: no permission to write into {existing}; give a "
                              "folder you can write to")
        if self.path.resolve().parent != out.resolve():  # pragma: no cover - safe_name holds
            raise OutputError(f"{self.name!r} would be written outside {out}")
        other = self._other_source()
        if other:
            raise OutputError(
                f"{self.path} holds the results of 'servotune {self.command.replace('_', ' ')}' "
                f"on {other}, another axis of the same name; this run would replace them: give "
                "another --out or another [axis] name")
        lost = self.foreign()
        if lost:
            shown = ", ".join(lost[:5]) + (" ..." if len(lost) > 5 else "")
            raise OutputError(
                f"{self.path} holds {shown}, which no earlier 'servotune "
                f"{self.command.replace('_', ' ')}' run wrote; this run replaces that folder "
                f"and would delete {'it' if len(lost) == 1 else 'them'}: move "
                f"{'it' if len(lost) == 1 else 'them'} elsewhere or give another --out")

    def _other_source(self) -> str | None:
        """The source of the earlier results in the run folder when it is not this run's."""
        if self.source is None:
            return None
        with contextlib.suppress(OSError, ValueError, TypeError, AttributeError):
            data = json.loads((self.path / self.MANIFEST).read_text())
            earlier = data.get("source")
            if data.get("command") == self.command and earlier and earlier != self.source:
                return earlier
        return None

    def foreign(self) -> list[str]:
        """Entries of the run folder that this command did not write (they would be lost)."""
        path = self.path
        if not path.exists() and not path.is_symlink():
            return []
        if path.is_symlink() or not path.is_dir():
            return [f"{path} itself (a file, not a results folder)"]
        own = set(self.files) | {self.MANIFEST}
        manifest = path / self.MANIFEST
        with contextlib.suppress(OSError, ValueError, TypeError):
            data = json.loads(manifest.read_text())
            if data.get("command") == self.command:
                own |= {str(f) for f in data.get("files", [])}
        own_top = {Path(f).parts[0] for f in own if Path(f).parts}
        return sorted(p.name + ("/" if p.is_dir() else "") for p in path.iterdir()
                      if p.name not in own_top)

    def _missing_parents(self) -> list[Path]:
        missing, p = [], self.out
        while not p.exists() and p.parent != p:
            missing.append(p)
            p = p.parent
        return missing

    @contextlib.contextmanager
    def writing(self) -> Iterator[Path]:
        """Write the results: yields a fresh folder to write into; when the block ends
        normally, that folder replaces the run folder (with a list of its files); on an error
        or Ctrl-C it is removed and the earlier results stay as they were.

        Raises
        ------
        OutputError
            When the folders cannot be made or swapped (permission, disk full, ...).
        """
        self.check()
        created = self._missing_parents()
        try:
            self.out.mkdir(parents=True, exist_ok=True)
            stage = Path(tempfile.mkdtemp(prefix=f".{self.name}.", suffix=".tmp", dir=self.out))
        except OSError as exc:
            _remove_empty(created)
            raise OutputError(f"{self._flag()}: cannot write there ({exc.strerror or exc}); "
                              "give a folder you can write to") from None
        try:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(stage, 0o777 & ~umask)  # mkdtemp makes 0700; results are ordinary files
            yield stage
            files = sorted(str(p.relative_to(stage)) for p in stage.rglob("*") if p.is_file())
            (stage / self.MANIFEST).write_text(json.dumps(
                {"command": self.command, "subject": self.subject, "files": files,
                 "source": self.source},
                indent=1) + "\n")
            self._swap(stage)
        except BaseException as exc:
            shutil.rmtree(stage, ignore_errors=True)
            _remove_empty(created)
            if isinstance(exc, OSError):
                raise OutputError(f"{self._flag()}: writing the results failed "
                                  f"({exc.strerror or exc}); nothing was changed") from None
            raise
        self.committed = True

    def _swap(self, stage: Path) -> None:
        old = None
        if self.path.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{self.name}.", suffix=".old", dir=self.out))
            old.rmdir()
            os.rename(self.path, old)
        try:
            os.rename(stage, self.path)
        except BaseException:
            if old is not None:
                os.rename(old, self.path)
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)


def save_figure(fig, path, dpi: int = 150) -> Path:
    """Save a matplotlib figure (format from the suffix) into a run's folder."""
    path = Path(path)
    fig.savefig(path, format=path.suffix.lstrip(".") or "png", dpi=dpi)
    return path


def write_results(folder, result, name: str = "results.json") -> Path:
    """Write ``results.json`` of a run (the object ``--json`` prints) into its folder."""
    path = Path(folder) / name
    path.write_text(json.dumps(to_jsonable(result), indent=2, allow_nan=False) + "\n")
    return path


def _remove_empty(folders) -> None:
    for folder in folders:  # innermost first
        with contextlib.suppress(OSError):
            folder.rmdir()


# --- JSON --------------------------------------------------------------------------------------

# why a value is not finite, for keys where the reason is known (key -> text)
_REASONS = {
    "phase_margin": "no gain crossover: the loop gain never reaches 1 in the frequency range",
    "phase_margin_deg": "no gain crossover: the loop gain never reaches 1 in the frequency range",
    "crossover": "no gain crossover: the loop gain never reaches 1 in the frequency range",
    "crossover_hz": "no gain crossover: the loop gain never reaches 1 in the frequency range",
    "gain_margin": "no phase crossover: the phase never reaches -180 deg",
    "gain_margin_db": "no phase crossover: the phase never reaches -180 deg",
    "phase_crossover_hz": "no phase crossover: the phase never reaches -180 deg",
    "gain_margin_lower_db": "no lower gain margin: the loop tolerates any gain reduction",
    "bandwidth_hz": "the closed loop does not fall 3 dB below its static gain in the "
                    "frequency range, or the loop does nothing (see inert and note)",
    "margin": "no chatter limit in the depths examined",
}


def _reason(key: str, value: float) -> str:
    what = "not a number" if math.isnan(value) else ("+infinity" if value > 0 else "-infinity")
    known = _REASONS.get(key)
    return f"{what}: {known}" if known else f"{what}: not defined for this case"


def _is_bad(x) -> bool:
    return isinstance(x, float) and not math.isfinite(x)


def to_jsonable(obj):
    """Plain JSON values: numpy scalars and arrays to Python, paths to strings, and every
    non-finite number to null with a reason beside it.

    In a mapping, a non-finite ``key`` becomes ``null`` and ``key_reason`` says why
    ("+infinity: no gain crossover ..."); a list with non-finite entries gets nulls there and
    ``key_reason`` once.

    Examples
    --------
    >>> out = to_jsonable({"phase_margin_deg": float("inf"), "ms": 1.4})
    >>> out["phase_margin_deg"], out["ms"]
    (None, 1.4)
    >>> out["phase_margin_deg_reason"]
    '+infinity: no gain crossover: the loop gain never reaches 1 in the frequency range'
    """
    import numpy as np

    if isinstance(obj, dict):
        out, reasons = {}, {}
        for k, v in obj.items():
            k = str(k)
            v = _plain(v, np)
            if _is_bad(v):
                reasons[f"{k}_reason"] = _reason(k, v)
                out[k] = None
            elif isinstance(v, list) and any(_is_bad(x) for x in v):
                bad = next(x for x in v if _is_bad(x))
                reasons[f"{k}_reason"] = (f"null entries are {_reason(k, bad)}")
                out[k] = to_jsonable(v)
            else:
                out[k] = to_jsonable(v)
        for k, v in reasons.items():
            out.setdefault(k, v)
        return out
    obj = _plain(obj, np)
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if _is_bad(obj):
        return None
    return obj


def _plain(obj, np):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    return obj


def print_json(obj) -> None:
    """Print one JSON object on standard output (non-finite numbers as null with a reason)."""
    json.dump(to_jsonable(obj), sys.stdout, indent=2, allow_nan=False)
    sys.stdout.write("\n")
