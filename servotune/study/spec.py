"""A study: what varies across samples of an axis, and what is computed for each.

A study file (TOML) names one or more axes, the fields that vary (any ``axis.toml`` field by
its dotted path), how they vary (a list, a grid, or random draws from a named distribution with
a seed) and what to compute per sample::

    [study]
    name = "friction_spread"
    axes = ["../models/paper_x_axis"]     # folders (or axis.toml files), relative to this file
    compute = ["tune", "verify"]          # among tune, verify, lobes, compliance
    samples = 200                         # random draws (with the lists and grids: per point)
    seed = 0
    starts = 2                            # tuning starts per sample (default 2)
    # design = "tuned/results.json"       # judge this design on every sample instead of tuning

    [vary."friction.lugre.fc"]            # a named LuGre set ("bianchi2014") is expanded first
    distribution = "uniform"              # uniform, loguniform, normal, lognormal, triangular
    low = 0.7
    high = 1.3
    relative = true                       # values multiply the axis' own value

    [vary."friction.lugre.sigma0"]
    values = [2e9, 5.9e9, 1.8e10]         # or grid = {low = ..., high = ..., count = 5, log = true}

Samples are the product of the lists and grids, times ``samples`` random draws (one draw when
nothing is random); each has a stable ``sample_id`` and a ``key`` (a hash of the axis and the
values), so a re-run skips what is done and a changed study recomputes what changed.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ._tables import StudyFormatError, apply_values
from ._tables import study_error as _err

__all__ = ["StudyFormatError", "Variation", "Sample", "Study", "load_study", "COMPUTE",
           "DISTRIBUTIONS", "apply_values"]

#: what a sample may compute, in the order it is done
COMPUTE = ("tune", "verify", "lobes", "compliance")
#: the named distributions of random variations and their parameters
DISTRIBUTIONS = {"uniform": ("low", "high"), "loguniform": ("low", "high"),
                 "normal": ("mean", "std"), "lognormal": ("median", "sigma"),
                 "triangular": ("low", "mode", "high")}
_STUDY_KEYS = {"name", "axes", "axis", "compute", "samples", "seed", "starts", "design",
               "chatter_weight"}


@dataclass(frozen=True)
class Variation:
    """How one axis field varies (``path`` is dotted, e.g. ``friction.lugre.fc``)."""

    path: str
    values: tuple = ()                       # a list or a grid (explicit values)
    distribution: str | None = None          # or random draws
    parameters: tuple[tuple[str, float], ...] = ()
    relative: bool = False                   # values multiply the axis' own value

    @property
    def random(self) -> bool:
        return self.distribution is not None

    def draw(self, rng: np.random.Generator) -> float:
        """Return one random value of this variation.

        Parameters
        ----------
        rng : numpy.random.Generator
            The generator of this draw.

        Returns
        -------
        float
            A value of the variation's distribution.
        """
        p = dict(self.parameters)
        d = self.distribution
        if d == "uniform":
            return float(rng.uniform(p["low"], p["high"]))
        if d == "loguniform":
            return float(math.exp(rng.uniform(math.log(p["low"]), math.log(p["high"]))))
        if d == "normal":
            return float(rng.normal(p["mean"], p["std"]))
        if d == "lognormal":
            return float(p["median"] * math.exp(rng.normal(0.0, p["sigma"])))
        if d == "triangular":
            return float(rng.triangular(p["low"], p["mode"], p["high"]))
        raise AssertionError(d)

    def to_dict(self) -> dict:
        """Return the variation as a JSON-ready dictionary.

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        return {"path": self.path, "values": list(self.values),
                "distribution": self.distribution, "parameters": dict(self.parameters),
                "relative": self.relative}


@dataclass(frozen=True)
class Sample:
    """One sample of a study: an axis and the values of the varied fields."""

    sample_id: int
    axis: str                                   # the axis folder (absolute)
    values: tuple[tuple[str, object], ...]      # (dotted path, value as given)
    key: str = ""

    def to_dict(self) -> dict:
        """Return the sample as a JSON-ready dictionary (the values keyed by path).

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        return {"sample_id": self.sample_id, "axis": self.axis, "values": dict(self.values),
                "key": self.key}


@dataclass(frozen=True)
class Study:
    """A parsed, validated study (see the module docstring)."""

    name: str
    file: Path
    axes: tuple[str, ...]
    variations: tuple[Variation, ...]
    compute: tuple[str, ...]
    samples: int = 1
    seed: int = 0
    starts: int = 2
    design: dict | None = None
    design_file: str | None = None
    chatter_weight: float | None = None
    tables: dict = field(default_factory=dict, compare=False, repr=False)

    def sample_list(self) -> list[Sample]:
        """Return every sample, in a stable order.

        Random values come from ``default_rng([seed, i])`` for the i-th draw, so a sample does not
        change when others are added.

        Returns
        -------
        list of Sample
            One sample per axis, grid point of the fixed variations and random draw.
        """
        fixed = [v for v in self.variations if not v.random]
        random = [v for v in self.variations if v.random]
        draws = self.samples if random else 1
        out = []
        grid = list(itertools.product(*[v.values for v in fixed])) or [()]
        for axis in self.axes:
            for point in grid:
                for d in range(draws):
                    rng = np.random.default_rng([self.seed, d])
                    values = [(v.path, x) for v, x in zip(fixed, point, strict=True)]
                    values += [(v.path, v.draw(rng)) for v in random]
                    out.append(Sample(len(out), axis, tuple(values),
                                      _key(self, axis, values)))
        return out

    def relative(self, path: str) -> bool:
        """Return whether a varied field's values multiply the axis's own value.

        Parameters
        ----------
        path : str
            Dotted path of the field, e.g. ``"friction.lugre.fs"``.

        Returns
        -------
        bool
            True when a variation of that path is relative.
        """
        return any(v.relative for v in self.variations if v.path == path)

    def to_dict(self) -> dict:
        """Return the study's settings as a JSON-ready dictionary (not its tables).

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        return {"name": self.name, "file": str(self.file), "axes": list(self.axes),
                "variations": [v.to_dict() for v in self.variations],
                "compute": list(self.compute), "samples": self.samples, "seed": self.seed,
                "starts": self.starts, "design": self.design, "design_file": self.design_file,
                "chatter_weight": self.chatter_weight}


def _key(study: Study, axis: str, values) -> str:
    """A hash of what a sample's results depend on: the axis file's bytes, the values, what is
    computed and how."""
    axis_file = Path(axis) / "axis.toml"
    try:
        axis_bytes = axis_file.read_bytes()
    except OSError:
        axis_bytes = b""
    what = json.dumps({"axis": axis, "values": [[p, v] for p, v in values],
                       "relative": [study.relative(p) for p, _ in values],
                       "compute": list(study.compute), "starts": study.starts,
                       "design": study.design, "chatter_weight": study.chatter_weight},
                      sort_keys=True, default=str)
    h = hashlib.sha256(axis_bytes)
    h.update(what.encode())
    return h.hexdigest()[:16]


def _number(value, file, where) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise _err(file, where, f"{value!r} is not a finite number", "give a number")
    return float(value)


def _value_kind(value) -> str:
    if isinstance(value, bool):
        return "booleans"
    if isinstance(value, int | float):
        return "numbers"
    return "texts" if isinstance(value, str) else f"{type(value).__name__}s"


def _variation(path: str, table, file) -> Variation:
    where = f'[vary."{path}"]'
    if not isinstance(table, dict):
        raise _err(file, where, "is not a table", 'write [vary."section.key"] with values = '
                   "[...], grid = {low, high, count} or distribution = ...")
    parts = path.split(".")
    if len(parts) < 2 or not all(parts):
        raise _err(file, where, "is not a dotted path to an axis.toml field",
                   'name the section and the key, e.g. "friction.lugre.fc"')
    kinds = [k for k in ("values", "grid", "distribution") if k in table]
    if len(kinds) != 1:
        raise _err(file, where, f"has {kinds or 'none'} of values, grid, distribution",
                   "give exactly one")
    relative = table.get("relative", False)
    if not isinstance(relative, bool):
        raise _err(file, f"{where} relative", f"{relative!r}", "write true or false")
    allowed = {"values", "grid", "distribution", "relative", *DISTRIBUTIONS.get(
        table.get("distribution"), ())}
    unknown = set(table) - allowed
    if unknown:
        raise _err(file, where, f"unknown keys {sorted(unknown)}",
                   f"use {sorted(allowed)} (check the spelling)")
    kind = kinds[0]
    if kind == "values":
        values = table["values"]
        if not isinstance(values, list) or not values:
            raise _err(file, f"{where} values", f"{values!r}", "give a non-empty list")
        if relative:
            values = [_number(v, file, f"{where} values") for v in values]
        kinds = sorted({_value_kind(v) for v in values})
        if len(kinds) > 1:
            raise _err(file, f"{where} values", f"{values!r} mixes {' and '.join(kinds)}",
                       "give values of one kind (the field's: numbers without quotes for a "
                       "number)")
        return Variation(path, tuple(values), relative=relative)
    if kind == "grid":
        grid = table["grid"]
        if not isinstance(grid, dict) or set(grid) - {"low", "high", "count", "log"} \
                or not {"low", "high", "count"} <= set(grid):
            raise _err(file, f"{where} grid", f"{grid!r}",
                       "write grid = {low = 1, high = 2, count = 5} (log = true for a "
                       "logarithmic grid)")
        low = _number(grid["low"], file, f"{where} grid low")
        high = _number(grid["high"], file, f"{where} grid high")
        count = grid["count"]
        if not isinstance(count, int) or isinstance(count, bool) or not 1 <= count <= 100_000:
            raise _err(file, f"{where} grid count", f"{count!r}", "give a whole number 1..100000")
        log = grid.get("log", False)
        if log and not (low > 0 and high > 0):
            raise _err(file, f"{where} grid", "a logarithmic grid needs low, high > 0",
                       "give positive limits or log = false")
        values = np.geomspace(low, high, count) if log else np.linspace(low, high, count)
        return Variation(path, tuple(float(v) for v in values), relative=relative)
    name = table["distribution"]
    if name not in DISTRIBUTIONS:
        raise _err(file, f"{where} distribution", f"{name!r}",
                   f"use one of {sorted(DISTRIBUTIONS)}")
    params = []
    for p in DISTRIBUTIONS[name]:
        if p not in table:
            raise _err(file, where, f"{name} needs {p}",
                       f"give {', '.join(DISTRIBUTIONS[name])}")
        params.append((p, _number(table[p], file, f"{where} {p}")))
    d = dict(params)
    if name in ("uniform", "loguniform", "triangular") and not d["low"] < d["high"]:
        raise _err(file, where, f"low {d['low']:g} is not below high {d['high']:g}",
                   "swap them")
    if name == "loguniform" and d["low"] <= 0:
        raise _err(file, where, "loguniform needs low > 0", "give a positive low")
    if name == "triangular" and not d["low"] <= d["mode"] <= d["high"]:
        raise _err(file, where, "mode outside [low, high]", "move the mode into the range")
    if (name == "normal" and d["std"] <= 0) or (name == "lognormal" and (
            d["sigma"] <= 0 or d["median"] <= 0)):
        raise _err(file, where, "a spread must be > 0 (and a median > 0)", "give positive ones")
    return Variation(path, (), name, tuple(params), relative)


def load_study(path, check_axes: bool = True) -> Study:
    """Read and check a study file.

    Parameters
    ----------
    path : str or os.PathLike
        The study's TOML file.
    check_axes : bool, optional
        Also check the study against its axes (default): every axis file parsed, every
        varied path resolved, every value's type and the values the axis loader refuses
        (:func:`servotune.study.validate.check_study`), so that a bad study ends before any
        sample runs.

    Returns
    -------
    Study
        The parsed, validated study.

    Raises
    ------
    StudyFormatError
        With the file, the field and the fix (an axis file's syntax error with its line).
    """
    file = Path(path)
    if not file.is_file():
        raise StudyFormatError(f"{file}: no study file here; give a STUDY.toml (see "
                               "'servotune study --help' for its form)")
    try:
        data = tomllib.loads(file.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise StudyFormatError(f"{file}: not valid TOML ({exc}); fix the syntax") from None
    unknown = set(data) - {"study", "vary"}
    if unknown:
        raise _err(file, "sections", f"unknown {sorted(unknown)}", "use [study] and [vary.*]")
    head = data.get("study")
    if not isinstance(head, dict):
        raise _err(file, "[study]", "missing", 'add [study] with name, axes and compute')
    unknown = set(head) - _STUDY_KEYS
    if unknown:
        raise _err(file, "[study]", f"unknown keys {sorted(unknown)}",
                   f"use {sorted(_STUDY_KEYS)} (check the spelling)")
    name = head.get("name", file.stem)
    if not isinstance(name, str) or not name:
        raise _err(file, "[study] name", f"{name!r}", 'give a name, e.g. name = "spread"')
    axes = head.get("axes", [head["axis"]] if "axis" in head else None)
    if not isinstance(axes, list) or not axes or not all(isinstance(a, str) for a in axes):
        raise _err(file, "[study] axes", f"{axes!r}",
                   'give a list of axis folders, e.g. axes = ["../models/paper_x_axis"]')
    folders = []
    for a in axes:
        p = (file.parent / a).resolve()
        p = p.parent if p.is_file() else p
        if not (p / "axis.toml").is_file():
            raise _err(file, "[study] axes", f"{a!r} holds no axis.toml ({p})",
                       "give an axis folder, relative to the study file")
        folders.append(str(p))
    compute = head.get("compute", ["tune"])
    if not isinstance(compute, list) or not compute or set(compute) - set(COMPUTE):
        raise _err(file, "[study] compute", f"{compute!r}", f"choose among {list(COMPUTE)}")
    samples = head.get("samples", 1)
    if not isinstance(samples, int) or isinstance(samples, bool) or not 1 <= samples <= 1_000_000:
        raise _err(file, "[study] samples", f"{samples!r}", "give a whole number 1..1000000")
    seed = head.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise _err(file, "[study] seed", f"{seed!r}", "give a whole number >= 0")
    starts = head.get("starts", 2)
    if not isinstance(starts, int) or isinstance(starts, bool) or not 1 <= starts <= 100:
        raise _err(file, "[study] starts", f"{starts!r}", "give a whole number 1..100")
    weight = head.get("chatter_weight")
    if weight is not None:
        weight = _number(weight, file, "[study] chatter_weight")
        if not 0.0 <= weight <= 1.0:
            raise _err(file, "[study] chatter_weight", f"{weight!r}", "give a number in [0, 1]")
    design = design_file = None
    if "design" in head:
        if not isinstance(head["design"], str):
            raise _err(file, "[study] design", f"got {head['design']!r}",
                       'name the results.json that servotune tune wrote, e.g. design = '
                       '"out/tune_myaxis/results.json" (the design is read from it, not '
                       "written here)")
        design_file = str((file.parent / head["design"]).resolve())
        design = _read_design(design_file, file)
        if "tune" in compute:
            raise _err(file, "[study] design", "given together with compute = tune",
                       "judge a fixed design (compute = [\"verify\"]) or tune each sample, "
                       "not both")
    elif "verify" in compute and "tune" not in compute:
        raise _err(file, "[study] compute", "verify needs a design",
                   'add tune to compute, or name a design = "results.json" of servotune tune')
    vary = data.get("vary", {})
    if not isinstance(vary, dict):
        raise _err(file, "[vary]", "is not a table", 'write [vary."section.key"] tables')
    variations = tuple(_variation(p, t, file) for p, t in vary.items())
    study = Study(name=name, file=file.resolve(), axes=tuple(folders), variations=variations,
                  compute=tuple(c for c in COMPUTE if c in compute), samples=samples,
                  seed=seed, starts=starts, design=design, design_file=design_file,
                  chatter_weight=weight, tables=data)
    if check_axes:
        from .validate import check_study, read_axis_tables

        check_study(study, {a: read_axis_tables(a, file) for a in study.axes})
    return study


def _read_design(path: str, file) -> dict:
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise _err(file, "[study] design", f"cannot read {path} ({exc})",
                   "name the results.json that servotune tune wrote") from None
    design = data.get("design") if isinstance(data, dict) else None
    if not isinstance(design, dict) or "c" not in design:
        raise _err(file, "[study] design", f"{path} has no 'design' with c, kv, kp, ti",
                   "name the results.json that servotune tune wrote")
    out = {k: design.get(k) for k in ("c", "kv", "kp", "ti")}
    for key, value in out.items():  # checked here, not in every sample (each would fail)
        if key == "ti" and value is None:
            continue  # no integral action: tune writes an infinite Ti as null
        if (isinstance(value, bool) or not isinstance(value, (int, float))
                or not math.isfinite(value) or value <= 0):
            raise _err(file, "[study] design", f"{path}: design.{key} is {value!r}",
                       "give a finite number > 0 (SI, as servotune tune writes it), or name "
                       "another results.json")
    out.update({k: design[k] for k in ("notch_frequency", "notch_width", "notch_depth",
                                       "lowpass_frequency")
                if design.get(k) is not None})
    # the current loop and filters it was tuned with (the commissioning's, by default)
    out["drive_fixed"] = data.get("drive_fixed")
    return out


