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

__all__ = ["spread_from_study", "LUGRE_PREFIX"]

LUGRE_PREFIX = INPUT_PREFIX + "friction.lugre."


def spread_from_study(path, count: int = 4) -> tuple[tuple[str, dict], ...]:
    """Return the worst samples of a study as friction samples.

    The samples with the highest compliance peak (the nonlinear one where computed) are
    returned as ``(label, {parameter: value})`` (see
    :func:`servotune.regimes.friction_samples`).

    Parameters
    ----------
    path : path-like
        The study's ``results.parquet`` or its folder.
    count : int
        How many samples (the worst first), 1 to 100.

    Returns
    -------
    tuple of (str, dict)
        ``("study sample <id>", {LuGre parameter: value})``, the worst first; at most
        ``count``.

    Raises
    ------
    ValueError
        A file that is not a study's table, a study that varied no LuGre parameter, one
        without a finished sample (the message says which), or a ``count`` outside 1..100.
    """
    import pyarrow.parquet as pq

    from ..friction.lugre import LuGreParameters

    p = Path(path)
    file = p / "results.parquet" if p.is_dir() else p
    if not file.is_file():
        raise ValueError(f"{file}: no study table here; give the results.parquet (or the "
                         "folder) that servotune study wrote")
    try:
        rows = pq.read_table(file).to_pylist()
    except Exception as exc:  # pyarrow raises several types for a file that is not Parquet
        raise ValueError(f"{file}: not a Parquet table ({exc}); give the results.parquet that "
                         "servotune study wrote") from None
    fields = {f.name for f in dataclasses.fields(LuGreParameters)}
    columns = sorted({k for r in rows for k in r if k.startswith(LUGRE_PREFIX)
                      and k[len(LUGRE_PREFIX):] in fields})
    if not columns:
        raise ValueError(f"{file}: the study varied no LuGre parameter (no "
                         f"'{LUGRE_PREFIX}*' column); a friction-spread study varies "
                         "friction.lugre.fc, fs, sigma0 or sigma1")
    if not isinstance(count, int) or not 1 <= count <= 100:
        raise ValueError(f"count must be a whole number 1..100, got {count!r}")

    def peak(r):
        for key in ("nonlinear_peak_m_per_n", "peak_compliance_m_per_n"):
            v = r.get(key)
            if isinstance(v, float) and math.isfinite(v):
                return v
        return None

    done = [r for r in rows if r.get("status") == "done" and peak(r) is not None]
    if not done:
        raise ValueError(f"{file}: no finished sample with a compliance peak; run the study "
                         "with compute = tune (or verify, compliance) first")
    worst = sorted(done, key=peak, reverse=True)[:count]
    return tuple((f"study sample {r['sample_id']}",
                  {c[len(LUGRE_PREFIX):]: float(r[c]) for c in columns if r.get(c) is not None})
                 for r in worst)
