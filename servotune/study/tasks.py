"""The work of one study sample: a pure function of (study settings, sample) -> one flat row.

It runs in a worker process (a dask worker on this machine or on a cluster) and needs nothing
but the installed package and the axis files: it reads the axis description, sets the varied
fields, builds the axis, and computes what the study asks for. A failure (an axis the loader
refuses, an unstable loop, requirements no design meets) is a row with its reason, never an
exception, so one bad sample does not end a study.
"""

from __future__ import annotations

import math
import os
import socket
import time
import tomllib
from pathlib import Path

__all__ = ["run_sample", "INPUT_PREFIX", "FACTOR_PREFIX"]

#: column prefix of the varied fields in a row, as set in the axis (``in.friction.lugre.fc``)
INPUT_PREFIX = "in."
#: column prefix of the factor drawn for a relative variation (``factor.friction.lugre.fc``)
FACTOR_PREFIX = "factor."


def _finite(x):
    return None if x is None or not math.isfinite(x) else float(x)


def _axis(settings: dict, sample: dict, applied: dict):
    from ..axis import axis_from_tables
    from .spec import apply_values

    file = Path(sample["axis"]) / "axis.toml"
    try:
        with open(file, "rb") as handle:
            tables = tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:  # changed since the study was checked
        raise ValueError(f"{file}: not valid TOML: {exc}; fix the syntax there") from None
    relative = set(settings.get("relative", ()))
    values = list(sample["values"].items())
    return axis_from_tables(apply_values(tables, values, lambda p: p in relative, applied),
                            file)


def _performance_columns(prefix: str, perf) -> dict:
    if perf is None:
        return {}
    worst = perf.worst_model
    return {f"{prefix}peak_compliance_m_per_n": _finite(perf.peak_compliance),
            f"{prefix}peak_frequency_hz": _finite(perf.peak_frequency / (2 * math.pi)),
            f"{prefix}worst_model": None if worst is None else worst.model.name,
            f"{prefix}b_crit_m": _finite(perf.b_crit) if perf.b_crit is not None else None,
            f"{prefix}stable": bool(perf.stable)}


def run_sample(settings: dict, sample: dict) -> dict:
    """Compute one sample; returns its row (flat: numbers, strings, booleans, None).

    Parameters
    ----------
    settings : dict
        ``compute`` (list among tune, verify, lobes, compliance), ``starts``, ``design`` (a fixed
        design {c, kv, kp, ti} or None), ``chatter_weight`` (or None), ``relative`` (the
        dotted paths whose values multiply the axis' own).
    sample : dict
        :meth:`servotune.study.Sample.to_dict`.

    Returns
    -------
    dict
        ``sample_id``, ``key``, ``axis``, ``in.<path>`` per varied field (the value set;
        ``factor.<path>`` too for a relative one), ``status`` ("done" or
        "failed"), ``error``, ``time_s``, ``worker``, and the results: the design (``c``,
        ``kv``, ``kp``, ``ti`` [SI]), ``peak_compliance_m_per_n`` (the design's worst claim over
        the regime models), ``b_crit_m``, ``linear_ok``, and with verify ``verified``,
        ``nonlinear_peak_m_per_n`` (worst over the regimes), ``failed_regimes``.
    """
    t0 = time.perf_counter()
    row = {"sample_id": int(sample["sample_id"]), "key": sample["key"],
           "axis": Path(sample["axis"]).name, "status": "done", "error": None,
           "worker": f"{socket.gethostname()}:{os.getpid()}"}
    relative = set(settings.get("relative", ()))
    for path, value in sample["values"].items():
        row[(FACTOR_PREFIX if path in relative else INPUT_PREFIX) + path] = value
    compute = set(settings["compute"])
    try:
        from ..design import check_design, tuning_problem, with_drive_fixed
        from ..tuning import Design, tune

        applied: dict = {}
        try:
            axis = _axis(settings, sample, applied)
        finally:
            for path in relative & set(applied):
                row[INPUT_PREFIX + path] = applied[path]
        if "tune" in compute:
            t = axis.tuning
            weight = settings.get("chatter_weight")
            problem = tuning_problem(axis, t.free, t.chatter_weight if weight is None else weight,
                                     dict(t.bounds))
            result = tune(problem, starts=int(settings.get("starts", 2)), seed=0)
        else:
            fixed = dict(settings.get("design") or {})
            if not fixed:  # the axis' own design
                fixed = tuning_problem(axis).initial_design().to_dict()
            axis = with_drive_fixed(axis, fixed.pop("drive_fixed", None))
            result = check_design(axis, Design(**fixed))
        d = result.design
        row.update({"c": d.c, "kv": d.kv, "kp": d.kp, "ti": d.ti,
                    "linear_ok": bool(result.success),
                    "reasons": "; ".join(result.reasons) or None})
        perf = result.after if result.after is not None else result.before
        cols = _performance_columns("", perf)
        if "compliance" in compute or "tune" in compute or "verify" in compute:
            row.update({k: v for k, v in cols.items() if not k.startswith("b_crit")})
        if "lobes" in compute or "tune" in compute:
            row["b_crit_m"] = cols.get("b_crit_m")
        if "tune" in compute:
            row["peak_compliance_before_m_per_n"] = _finite(result.before.peak_compliance)
        if "verify" in compute:
            from ..verdict import nonlinear_verdict

            # a study samples the friction itself: each sample is judged at its own friction
            verdict = nonlinear_verdict(axis, result, simulate_before=False, spread=None)
            peaks = [r.nonlinear_peak_after for r in verdict.regimes
                     if r.nonlinear_peak_after is not None]
            row.update({"verified": bool(verdict.verified),
                        "nonlinear_peak_m_per_n": max(peaks) if peaks else None,
                        "failed_regimes": "; ".join(f"{r.name}: {r.reason}"
                                                    for r in verdict.regimes
                                                    if not r.holds) or None})
    except Exception as exc:  # a failed sample is a row with its reason
        row["status"] = "failed"
        row["error"] = f"{type(exc).__name__}: {exc}"
    row["time_s"] = time.perf_counter() - t0
    return row
