"""``servotune study STUDY.toml``: an axis sampled over what varies, on dask.distributed."""

from __future__ import annotations

import re

from ._common import (
    WORKERS,
    CliError,
    add_common_options,
    default_workers,
    print_json,
)

__all__ = ["add_parser", "run"]

_ADDRESS = re.compile(r"^(tcp|tls|inproc|ucx|ws|wss)://[^\s]+$")


def _scheduler(text: str) -> str:
    import argparse

    if not _ADDRESS.match(text):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a scheduler address: give e.g. tcp://10.0.0.5:8786 (as "
            "'dask scheduler' prints it)")
    return text


def add_parser(subparsers) -> None:
    """Add the ``servotune study`` sub-command and its options.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The sub-commands of the ``servotune`` parser.
    """
    p = subparsers.add_parser(
        "study", help="an axis sampled over what varies, tuned/verified per sample on "
                      "dask.distributed",
        description="Run a study file (TOML: [study] name, axes, compute = tune, verify, "
                    "lobes, compliance, samples, seed; [vary.\"section.key\"] a list, a grid "
                    "or a distribution per varied axis.toml field; see servotune.study.spec). "
                    "Every finished sample is written at once to OUT/study_<name>/rows/ "
                    "(Parquet); a re-run skips what is done; results.parquet and summary.html "
                    "hold the whole study. Without --scheduler the samples run on a local "
                    "cluster of --workers processes. The study is checked against its axes "
                    "before any sample runs (every varied path, each value's type, the values "
                    "the axis loader refuses). Exit status 0 when every sample ran (failed "
                    "samples are rows with their reason), 1 for a bad study file, 130 "
                    "interrupted (the rows written stay, and the line says where); 1 too when "
                    "every sample failed.")
    p.add_argument("study", help="study file (TOML)")
    p.add_argument("--scheduler", type=_scheduler, default=None, metavar="ADDRESS",
                   help="address of a running dask scheduler (tcp://host:8786); default a "
                        "local cluster on this machine")
    p.add_argument("--workers", type=WORKERS, default=None, metavar="N",
                   help="worker processes of the local cluster (default: the CPUs this "
                        "process may use)")
    add_common_options(p, plots=True)
    p.set_defaults(func=run)


def _state(folder, keys) -> tuple[bool, int]:
    """Whether the folder has its study.json, and how many of the study's rows it holds."""
    rows = {p.stem for p in (folder / "rows").glob("*.parquet")} if (folder / "rows").is_dir() \
        else set()
    return (folder / "study.json").is_file(), len(rows & keys)


def _interrupted(what: str | None, folder, keys, before: tuple[bool, int],
                 json: bool = False) -> int:
    """Print the one line of an interrupted study: what is in its folder now, truthfully."""
    import sys

    from .. import interrupt
    from . import EXIT_INTERRUPTED

    interrupt.restore_stderr()
    try:  # a progress bar's line may still stand (its clearing went to the silenced stderr)
        if sys.stderr.isatty():
            sys.stderr.write("\r\x1b[K")
    except (AttributeError, ValueError, OSError):
        pass
    marker, rows = _state(folder, keys)
    new = rows - before[1]
    if not marker:
        kept = "nothing was written"
    elif not rows:
        kept = (f"{folder} holds study.json and an empty rows/ (no sample had finished); the "
                "same command starts the study again")
    else:
        kept = (f"{folder} keeps study.json and the rows of {rows} of {len(keys)} samples "
                f"in rows/ ({new} finished in this run); the same command goes on from them, "
                "'servotune tune --spread-from' reads them")
    line = "servotune study: interrupted" + (f" during {what}" if what else "") + f"; {kept}"
    print(line, file=sys.stderr)
    if json:  # the one JSON object, as for any other end of the command
        print_json({"command": "servotune study", "status": "error",
                    "error_kind": "interrupted", "error": line,
                    "exit_status": EXIT_INTERRUPTED})
    return EXIT_INTERRUPTED


def run(args) -> int:
    """Run ``servotune study``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        The exit status: 0 the study ran (failed samples are rows with their reason), 1
        every sample failed (nothing to summarise: the line says why and where the rows are),
        130 interrupted (with one line saying what the folder keeps). Errors are raised, and
        reported by :func:`servotune.cli.main` with status 1.
    """
    from .. import progress
    from ..study import (
        StudyFolderError,
        StudyFormatError,
        load_study,
        run_study,
        study_folder,
        write_summary,
    )

    try:
        with progress.task(f"checking {args.study}"):
            study = load_study(args.study)
    except StudyFormatError as exc:
        raise CliError(str(exc)) from None
    if args.scheduler and args.workers:
        raise CliError("--workers sizes the local cluster; a cluster at --scheduler has its own "
                       "workers: give one of them")
    workers = args.workers or default_workers()
    folder = study_folder(study, args.out)
    samples = study.sample_list()
    n = len(samples)
    keys = {s.key for s in samples}
    before = _state(folder, keys)
    what = None
    try:
        with progress.task(f"study {study.name}: {n} samples", total=n, unit="sample") as task:
            try:
                result = run_study(study, args.out, scheduler=args.scheduler, workers=workers,
                                   progress=task.report)
            except StudyFolderError as exc:
                raise CliError(str(exc)) from None
            except KeyboardInterrupt:
                what = progress.current()
                raise
        summary, files = write_summary(study, result, plots=not args.no_plots)
    except KeyboardInterrupt:
        return _interrupted(what, folder, keys, before, json=args.json)
    all_failed = summary.finished > 0 and summary.failed == summary.finished
    status = 1 if all_failed else 0
    out = {"study": study.name, "folder": str(result.folder),
           "status": "failed" if all_failed else "done", "exit_status": status,
           "run": result.to_dict(), "summary": summary.to_dict(),
           "files": [str(p.relative_to(result.folder)) for p in files]
           + ["results.parquet", "rows/"]}
    if all_failed:
        import sys

        first_id, first = summary.failures[0]
        print(f"servotune study: error: all {summary.failed} samples failed, so the study has "
              f"no result (sample {first_id}: {first}); the reasons are in "
              f"{result.folder}/results.parquet", file=sys.stderr)
    if args.json:
        print_json(out)
        return status
    print(f"study {study.name}: {summary.counts()}")
    print(f"  this run: {result.computed} computed, {result.skipped} already done, "
          f"{result.wall_time:.1f} s on {result.scheduler} "
          f"({result.throughput:.3g} samples/s)")
    for key, s in summary.spreads.items():
        print(f"  {key:28} min {s['min']:.4g}  median {s['median']:.4g}  max {s['max']:.4g}")
    for sample_id, error in summary.failures[:5]:
        print(f"  failed: sample {sample_id}: {error}")
    if len(summary.failures) > 5:
        print(f"  ... {len(summary.failures) - 5} more failures in summary.html")
    print(f"  wrote {result.folder} (results.parquet, summary.html, rows/)")
    return status
