"""A study's samples as the friction spread of a robust (multi-model) tuning.

A study of the friction spread shows which friction the axis is worst with. The samples whose
realised compliance peak was worst (the nonlinear one when the study verified, else the linear
claim) become further friction samples of ``servotune tune --spread-from``: every regime gets a
model per sample, and the tuning minimises the worst over all of them.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from .tasks import INPUT_PREFIX

__all__ = ["spread_from_study", "FrictionSpreadSamples", "LUGRE_PREFIX"]

LUGRE_PREFIX = INPUT_PREFIX + "friction.lugre."


class FrictionSpreadSamples(tuple):
    """The friction samples taken from a study (a tuple of ``(label, {parameter: value})``)
    with what they were taken from: ``source`` (the folder or table read), ``rows`` (the
    samples run), ``samples`` (in the study; None when the table alone was given) and
    ``note``, the sentence that says it."""

    source: str
    rows: int
    samples: int | None
    note: str

    def __new__(cls, items=(), source: str = "", rows: int = 0, samples: int | None = None,
                note: str = ""):
        self = super().__new__(cls, items)
        self.source, self.rows, self.samples, self.note = source, rows, samples, note
        return self


def _total(folder: Path) -> tuple[int | None, set | None]:
    """The number of samples and their keys from a study folder's study.json (None, None
    when there is none)."""
    import json

    try:
        marker = json.loads((folder / "study.json").read_text())
        return int(marker["samples"]), set(marker["keys"])
    except (OSError, ValueError, KeyError, TypeError):
        return None, None


def _read_table(file: Path) -> list[dict]:
    import pyarrow.parquet as pq

    try:
        return pq.read_table(file).to_pylist()
    except Exception as exc:  # pyarrow raises several types for a file that is not Parquet
        raise ValueError(f"{file}: not a Parquet table ({exc}); give the results.parquet (or "
                         "the folder) that servotune study wrote") from None


def _rows(p: Path) -> tuple[list[dict], str, int | None]:
    """The rows a study folder or table holds, what was read, and the study's sample count.

    A folder's ``rows/`` are read when it has them (they are there as soon as each sample
    finishes: an interrupted or running study has them without its ``results.parquet``)."""
    from .runner import read_rows

    if p.is_dir():
        total, keys = _total(p)
        if (p / "rows").is_dir() and total is not None:
            return read_rows(p, keys), f"{p}/rows", total
        if (p / "results.parquet").is_file():
            return _read_table(p / "results.parquet"), str(p / "results.parquet"), total
        raise ValueError(f"{p}: no study here (no rows/ with study.json, no results.parquet); "
                         "give the folder (or results.parquet) that servotune study wrote")
    if not p.is_file():
        raise ValueError(f"{p}: no study table here; give the results.parquet (or the "
                         "folder) that servotune study wrote")
    return _read_table(p), str(p), _total(p.parent)[0]


def spread_from_study(path, count: int = 4) -> FrictionSpreadSamples:
    """Return the worst samples of a study as friction samples.

    The samples with the highest compliance peak (the nonlinear one where computed) are
    returned as ``(label, {parameter: value})`` (see
    :func:`servotune.regimes.friction_samples`). A study folder is read from its rows, so a
    study that was interrupted (or is still running) gives the samples it has finished.

    Parameters
    ----------
    path : path-like
        The study's folder (``out/study_<name>``) or its ``results.parquet``.
    count : int
        How many samples (the worst first), 1 to 100.

    Returns
    -------
    FrictionSpreadSamples
        ``("study sample <id>", {LuGre parameter: value})``, the worst first; at most
        ``count``; its ``note`` says how many of the study's samples were read.

    Raises
    ------
    ValueError
        A path that holds no study, a file that is not a study's table, a study that varied
        no LuGre parameter, one without a finished sample (the message says which and how
        many samples it has), or a ``count`` outside 1..100.
    """
    from ..friction.lugre import LuGreParameters

    if not isinstance(count, int) or not 1 <= count <= 100:
        raise ValueError(f"count must be a whole number 1..100, got {count!r}")
    rows, source, total = _rows(Path(path))
    of = "" if total is None else f" of {total}"
    if not rows:
        raise ValueError(f"{source}: none{of} of the study's samples has finished; run "
                         "servotune study (again: it goes on from the finished ones)")
    fields = {f.name for f in dataclasses.fields(LuGreParameters)}
    columns = sorted({k for r in rows for k in r if k.startswith(LUGRE_PREFIX)
                      and k[len(LUGRE_PREFIX):] in fields})
    if not columns:
        raise ValueError(f"{source}: the study varied no LuGre parameter (no "
                         f"'{LUGRE_PREFIX}*' column); a friction-spread study varies "
                         "friction.lugre.fc, fs, sigma0 or sigma1")

    def peak(r):
        for key in ("nonlinear_peak_m_per_n", "peak_compliance_m_per_n"):
            v = r.get(key)
            if isinstance(v, float) and math.isfinite(v):
                return v
        return None

    done = [r for r in rows if r.get("status") == "done" and peak(r) is not None]
    run = f"{len(rows)}{of} samples run"
    if total is not None and len(rows) < total:
        run += " (the study was interrupted or is still running)"
    if not done:
        raise ValueError(f"{source}: {run}, none with a compliance peak; run the study with "
                         "compute = tune (or verify, compliance)")
    worst = sorted(done, key=peak, reverse=True)[:count]
    items = tuple((f"study sample {r['sample_id']}",
                   {c[len(LUGRE_PREFIX):]: float(r[c]) for c in columns if r.get(c) is not None})
                  for r in worst)
    note = (f"friction spread from {source}: {run}, {len(done)} with a compliance peak; "
            f"the {len(worst)} worst taken")
    return FrictionSpreadSamples(items, source, len(rows), total, note)
