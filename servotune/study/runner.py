"""Running a study on dask.distributed: samples as tasks, each finished row written at once.

The folder of a study (``<out>/study_<name>``) holds::

    study.json        the study as run (what varied, what was computed) and its progress
    rows/<key>.parquet  one file per finished sample (written atomically as it completes)
    results.parquet   every row of this study, one per sample, in sample order
    summary.html      the table and figures a person reads (see :mod:`servotune.study.summary`)

A re-run with the same study and folder skips every sample whose row is there (the ``key`` is a
hash of the axis file, the values and the settings, so a changed study recomputes what changed).
A worker that dies mid-task loses nothing already written: dask's scheduler runs its tasks
again on the other workers (the nanny restarts the dead one). Ctrl-C cancels what is left and
closes the cluster; the rows already written stay and the next run resumes from them. The
workers of the local cluster never see Ctrl-C (the terminal sends it to every process of its
group): this process alone handles it, and closes them.

Without a scheduler address the study runs on a :class:`distributed.LocalCluster` of processes
on this machine (one thread each, BLAS on one thread); with one (``tcp://host:8786``) it runs
unchanged on that cluster, whose workers need only servotune installed and the axis files at
the same paths.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import signal
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from .spec import Study
from .tasks import run_sample

__all__ = ["StudyRun", "run_study", "study_folder", "read_rows", "StudyFolderError"]

_MARKER = "study.json"


class StudyFolderError(ValueError):
    """The output folder of a study cannot be used (names it and the fix)."""


@dataclass(frozen=True)
class StudyRun:
    """What a run of a study did (SI; times in s)."""

    folder: Path
    samples: int              # in the study
    skipped: int              # already done before this run
    computed: int             # finished in this run
    failed: int               # rows with status "failed" (over the whole study)
    wall_time: float
    workers: int
    scheduler: str

    @property
    def throughput(self) -> float:
        """Samples finished per second of wall time in this run."""
        return self.computed / self.wall_time if self.wall_time > 0 else 0.0

    def to_dict(self) -> dict:
        """Return the run as a JSON-ready dictionary (the folder as a string, times in s).

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        d = dataclasses.asdict(self)
        d["folder"] = str(self.folder)
        d["wall_time_s"] = d.pop("wall_time")
        d["throughput_per_s"] = self.throughput
        return d


def study_folder(study: Study, out) -> Path:
    """Return the folder a study writes into: ``<out>/study_<name>``.

    Parameters
    ----------
    study : Study
        The study; its name, made safe for a file name, names the folder.
    out : str or os.PathLike
        The parent folder.

    Returns
    -------
    pathlib.Path
        The study's folder (not created here).
    """
    from ..names import safe_name

    return Path(out) / f"study_{safe_name(study.name)}"


def _check_folder(folder: Path) -> None:
    out = folder.parent
    if out.exists() and not out.is_dir():
        raise StudyFolderError(f"--out {out}: is a file, not a folder; give a folder")
    if folder.exists():
        if not folder.is_dir():
            raise StudyFolderError(f"{folder} is a file; give another --out or move it")
        if any(folder.iterdir()) and not (folder / _MARKER).is_file():
            raise StudyFolderError(
                f"{folder} holds files that are not a study's (no {_MARKER}); they would be "
                "mixed with the study's rows: give another --out or move them")
    probe = folder if folder.exists() else out
    while not probe.exists():
        probe = probe.parent
    if not os.access(probe, os.W_OK):
        raise StudyFolderError(f"{probe}: no permission to write; give another --out")


def _write_atomically(path: Path, write) -> None:
    """``write(tmp_path)`` then move the file into place."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        write(Path(tmp))
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _write_row(rows: Path, row: dict) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pylist([row])
    _write_atomically(rows / f"{row['key']}.parquet", lambda p: pq.write_table(table, p))


def read_rows(folder, keys=None) -> list[dict]:
    """Return the finished rows in a study folder, in sample order.

    Parameters
    ----------
    folder : str or os.PathLike
        The study's folder (its rows are ``rows/<key>.parquet``).
    keys : collection of str, optional
        Only the rows of these sample keys (default all).

    Returns
    -------
    list of dict
        One dictionary per row, sorted by ``sample_id``; empty when there is none.
    """
    import pyarrow.parquet as pq

    rows = []
    for p in sorted((Path(folder) / "rows").glob("*.parquet")):
        if keys is not None and p.stem not in keys:
            continue
        rows += pq.read_table(p).to_pylist()
    return sorted(rows, key=lambda r: r["sample_id"])


def _settings(study: Study) -> dict:
    return {"compute": list(study.compute), "starts": study.starts, "design": study.design,
            "chatter_weight": study.chatter_weight,
            "relative": sorted({v.path for v in study.variations if v.relative})}


@contextlib.contextmanager
def _sigint_blocked() -> Iterator[None]:
    """SIGINT held back from this thread, and from the threads and processes it starts.

    The worker processes of a LocalCluster are started by threads the cluster starts; started
    inside this block they inherit the blocked signal (through ``exec`` too), so Ctrl-C at the
    terminal, which goes to every process of its group, reaches only this process: the
    workers print no tracebacks and are closed by it. A Ctrl-C pressed inside the block is
    delivered at its end. Outside the main thread, or without ``pthread_sigmask``, nothing
    changes.
    """
    block = (hasattr(signal, "pthread_sigmask")
             and threading.current_thread() is threading.main_thread())
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT}) if block else None
    try:
        yield
    finally:
        if block:
            signal.pthread_sigmask(signal.SIG_SETMASK, previous)


#: run first in every local worker (restarted ones too): Ctrl-C is this process' to handle;
#: the blocked signal alone does not last, as multiprocessing's resource tracker unblocks it
#: in the thread that starts it
_IGNORE_CTRL_C = "from servotune.interrupt import ignore_in_worker; ignore_in_worker()"


def _client(scheduler: str | None, workers: int):
    from distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler, timeout="20s"), None
    env = {name: "1" for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                  "MKL_NUM_THREADS")}
    cluster = client = None
    try:
        with _sigint_blocked():
            # on this machine only (loopback); the scheduler's HTTP server on a free port, so
            # that two studies at once do not compete for dask's default 8787
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address="127.0.0.1:0", env=env, silence_logs=40,
                                   preload=[_IGNORE_CTRL_C])
            client = Client(cluster)
    except BaseException:  # Ctrl-C delivered as the block ends: close what was started
        _close(client, cluster)
        raise
    return client, cluster


def _close(client, cluster) -> None:
    """Close the client and the local cluster; a second Ctrl-C waits until they are closed."""
    with _sigint_blocked():
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()


def run_study(study: Study, out, scheduler: str | None = None, workers: int = 2,
              progress=None, task=run_sample, on_row=None) -> StudyRun:
    """Run (or resume) a study; every finished row is written as it completes.

    Parameters
    ----------
    study : Study
        The study: its samples and what to compute for each.
    out : path-like
        Parent folder; the study writes ``<out>/study_<name>``.
    scheduler : str, optional
        Address of a running dask scheduler; default a LocalCluster on this machine.
    workers : int
        Worker processes of the LocalCluster.
    progress : callable, optional
        ``progress(done, total)`` after each row.
    task : callable
        ``task(settings, sample_dict) -> row`` (default :func:`run_sample`; tests inject
        faults through it).
    on_row : callable, optional
        Called with each row once it is written.

    Returns
    -------
    StudyRun
        Samples in the study, skipped (done before), computed in this run and failed, the wall
        time, the workers and the scheduler.

    Raises
    ------
    StudyFolderError
        The folder cannot be used (before any work).
    KeyboardInterrupt
        After cancelling the rest; the rows written stay.
    """
    from distributed import as_completed

    folder = study_folder(study, out)
    _check_folder(folder)
    rows_dir = folder / "rows"
    rows_dir.mkdir(parents=True, exist_ok=True)
    samples = study.sample_list()
    keys = {s.key for s in samples}
    done = {p.stem for p in rows_dir.glob("*.parquet")} & keys
    todo = [s for s in samples if s.key not in done]
    marker = {"study": study.to_dict(), "samples": len(samples), "keys": sorted(keys)}
    _write_atomically(folder / _MARKER,
                      lambda p: p.write_text(json.dumps(marker, indent=1, default=str)))
    t0 = time.perf_counter()
    computed = 0
    label = scheduler or f"LocalCluster({workers} processes)"
    if progress is not None:
        progress(len(done), len(samples))
    if todo:
        client, cluster = _client(scheduler, workers)
        futures = []
        try:
            settings = _settings(study)
            futures = client.map(task, [settings] * len(todo), [s.to_dict() for s in todo],
                                 key=[f"servotune-sample-{s.key}" for s in todo], pure=False)
            for fut in as_completed(futures):
                row = fut.result()
                _write_row(rows_dir, row)
                computed += 1
                if on_row is not None:
                    on_row(row)
                if progress is not None:
                    progress(len(done) + computed, len(samples))
        except BaseException:
            with _sigint_blocked():
                for f in futures:
                    f.cancel()
            raise
        finally:
            _close(client, cluster)
    wall = time.perf_counter() - t0
    rows = read_rows(folder, keys)
    _write_table(folder, rows)
    failed = sum(1 for r in rows if r.get("status") == "failed")
    return StudyRun(folder, len(samples), len(done), computed, failed, wall,
                    workers if scheduler is None else 0, label)


def _write_table(folder: Path, rows: list[dict]) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    if not rows:
        return
    names = list(dict.fromkeys(k for r in rows for k in r))  # rows differ (failed ones)
    table = pa.table({k: [r.get(k) for r in rows] for k in names})
    _write_atomically(folder / "results.parquet", lambda p: pq.write_table(table, p))
