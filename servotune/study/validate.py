"""A study checked against its axes before any sample runs.

Every axis file is parsed (a syntax error names the file and the line), every varied path is
resolved in each axis description (an unknown one is named with its close matches), every
value's type is compared with the field it replaces, and the axis loader itself
(:func:`servotune.axis.axis_from_tables`) judges each listed value and the random draws: a
value the loader refuses in every sample that has it ends the study before it starts, with
the loader's reason. A sample the loader refuses only in combination (Coulomb above static
friction in one random draw) stays a failed row of the study, as the samples of a spread
should.
"""

from __future__ import annotations

import difflib
import re
import tomllib
from pathlib import Path

from ._tables import StudyFormatError, apply_values
from ._tables import study_error as _err

__all__ = ["read_axis_tables", "check_study", "MAX_BUILDS"]

#: at most this many samples' axes are built to check a study (a few ms each)
MAX_BUILDS = 500

_MISSING = object()


def _kind(value) -> str:
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int | float):
        return "number"
    if isinstance(value, str):
        return "text"
    if isinstance(value, dict):
        return "table"
    if isinstance(value, list):
        return "list"
    return type(value).__name__


def read_axis_tables(folder, study_file) -> dict:
    """Return the tables of an axis description a study names.

    Parameters
    ----------
    folder : path-like
        The axis folder (holding ``axis.toml``).
    study_file : path-like
        The study file that names it (for the messages).

    Returns
    -------
    dict
        The tables as :mod:`tomllib` reads them.

    Raises
    ------
    StudyFormatError
        An axis file that cannot be read or is not valid TOML: names the file, the line and
        column, and the study that uses it.
    """

    file = Path(folder) / "axis.toml"
    try:
        with open(file, "rb") as handle:
            return tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        raise StudyFormatError(
            f"{file}: not valid TOML: {exc}; fix the syntax there or just before (the axis of "
            f"[study] axes in {study_file})") from None
    except UnicodeDecodeError as exc:
        raise StudyFormatError(f"{file}: not UTF-8 text ({exc}); save it as UTF-8 (the axis of "
                               f"[study] axes in {study_file})") from None
    except OSError as exc:
        raise StudyFormatError(f"{file}: cannot be read ({exc.strerror or exc}); check it "
                               f"(the axis of [study] axes in {study_file})") from None


def _known_keys(walked: list[str], node) -> list[str]:
    """The keys a level of an axis description may have that a study can know of here."""
    from ..axis import SECTIONS
    from ..friction.law import friction_law_names

    keys = list(node) if isinstance(node, dict) else []
    if not walked:
        keys += list(SECTIONS)
    elif walked == ["friction"]:
        keys += ["pads", "viscous", "measurements", "variation", *friction_law_names()]
    elif walked == ["friction", "lugre"]:
        import dataclasses

        from ..friction.lugre import LuGreParameters

        keys += [f.name for f in dataclasses.fields(LuGreParameters)]
    return list(dict.fromkeys(keys))


def _resolve(tables: dict, path: str):
    """Walk a dotted path through an axis description.

    Returns ``(value, None)`` for a field that is there, ``(_MISSING, (walked, candidates))``
    for one that is not, or raises ValueError for a path through a value that is not a
    table.
    """
    from ..friction.lugre import LuGreParameters

    node = tables
    walked: list[str] = []
    for part in path.split("."):
        if isinstance(node, str) and walked == ["friction", "lugre"]:
            try:  # a named set: its fields are there
                node = LuGreParameters.named(node).to_dict()
            except (KeyError, ValueError):
                raise ValueError(f"the LuGre set {node!r} of [friction] lugre is not "
                                 "known") from None
        if not isinstance(node, dict):
            raise ValueError(f"{'.'.join(walked)} is {node!r} there, not a table")
        if part not in node:
            return _MISSING, (walked, _known_keys(walked, node))
        node = node[part]
        walked.append(part)
    return node, None


def _close(tables: dict, path: str, walked: list[str], candidates, message: str = "") -> str:
    """'did you mean ...' for the unknown part of a path (also among the names a loader's
    message quotes); the paths that are in the description first, and only those if any."""
    part = path.split(".")[len(walked)]
    quoted = re.findall(r"'([A-Za-z_][A-Za-z0-9_]*)'", message)
    names = [n for n in dict.fromkeys([*candidates, *quoted]) if n != part]
    matches = difflib.get_close_matches(part, names, n=3, cutoff=0.6)
    parts = path.split(".")
    full = [".".join([*walked, m, *parts[len(walked) + 1:]]) for m in matches]
    there = [f for f in full if _there(tables, f)]
    full = [f'"{f}"' for f in (there or full)]
    if full:
        return f"did you mean {' or '.join(full)}?"
    shown = ", ".join(sorted(str(c) for c in candidates)[:12])
    return (f"the fields there are {shown}" if shown else
            "check the path against the axis description")


def _there(tables: dict, path: str) -> bool:
    try:
        return _resolve(tables, path)[1] is None
    except ValueError:
        return False


def _build(tables: dict, file: Path, values, relative) -> str | None:
    """The loader's reason for refusing a sample's axis, or None when it builds."""
    from ..axis import axis_from_tables

    try:
        axis_from_tables(apply_values(tables, values, relative), file)
    except Exception as exc:  # the loader's and apply_values' refusals, whatever their type
        text = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
        return str(text)
    return None


def _check_paths(study, folder: str, tables: dict) -> None:

    file = Path(folder) / "axis.toml"
    for v in study.variations:
        where = f'[vary."{v.path}"]'
        try:
            leaf, missing = _resolve(tables, v.path)
        except ValueError as exc:
            raise _err(study.file, where, f"{exc} in {file}",
                       "vary a field below a table (check the path)") from None
        if missing is not None:
            walked, candidates = missing
            section = f"[{'.'.join(walked)}]" if walked else "its sections"
            if v.relative:
                raise _err(study.file, where,
                           f"{file} has no field {v.path.split('.')[len(walked)]!r} in "
                           f"{section}, and a relative variation multiplies the number there",
                           _close(tables, v.path, walked, candidates))
            # an absolute value may set a field the description leaves to its default: the
            # loader says whether the field exists
            value = v.values[0] if v.values else v.draw(_rng(study))
            reason = _build(tables, file, [(v.path, value)], lambda p: False)
            if reason is not None:
                raise _err(study.file, where,
                           f"{file} has no field {v.path.split('.')[len(walked)]!r} in "
                           f"{section} and the axis loader refuses it ({reason})",
                           _close(tables, v.path, walked, candidates, reason))
            continue
        kind = _kind(leaf)
        if v.relative:
            if kind != "number":
                raise _err(study.file, f"{where} relative",
                           f"{v.path} is {leaf!r} in {file}, not a number to multiply",
                           "give absolute values (leave relative out)")
            continue
        if v.random and kind != "number":
            raise _err(study.file, f"{where} distribution",
                       f"draws numbers, but {v.path} is {_article(kind)} in {file} ({leaf!r})",
                       f"list the {kind} values instead (values = [...])")
        for x in v.values:
            given = _kind(x)
            fits = (given == kind or (kind in ("text", "table") and given in ("text", "table")))
            if not fits:
                raise _err(study.file, f"{where} values",
                           f"{x!r} is {_article(given)}, but {v.path} is {_article(kind)} "
                           f"in {file} ({leaf!r})",
                           f"give {kind} values" + (" (without quotes)" if kind == "number"
                                                    else ""))


def _article(kind: str) -> str:
    return f"{'an' if kind[0] in 'aeiou' else 'a'} {kind}"


def _rng(study):
    import numpy as np

    return np.random.default_rng([study.seed, 0])


def check_study(study, tables: dict) -> None:
    """Check a study against the descriptions of its axes; returns when it can run.

    Parameters
    ----------
    study : Study
        The parsed study.
    tables : dict
        ``{axis folder: tables}`` of every axis of the study (:func:`read_axis_tables`).

    Raises
    ------
    StudyFormatError
        A path the axis does not have (with the close matches), a value of another type than
        the field's, or a value the axis loader refuses in every sample that has it (with the
        loader's reason); names the study file, the field and the fix.

    Notes
    -----
    The loader is run on the samples in their order until each listed (or grid) value has
    built in at least one sample and one sample has built at all, so a study whose values
    are all good costs a few axis builds (milliseconds each for a reduced model); at most
    :data:`MAX_BUILDS` (a value not yet judged then is judged by its sample's run).
    """

    for folder in study.axes:
        _check_paths(study, folder, tables[folder])
    fixed = {(v.path, x) for v in study.variations if not v.random for x in v.values}
    built = set()
    refused: dict = {}           # (path, value) -> first reason, while no sample built it
    first_reason = None
    any_built = False
    builds = 0
    for sample in study.sample_list():
        if any_built and fixed <= built:
            return
        if builds >= MAX_BUILDS:
            break
        pairs = [(p, x) for p, x in sample.values if (p, x) in fixed]
        if any_built and all(pair in built for pair in pairs):
            continue
        file = Path(sample.axis) / "axis.toml"
        reason = _build(tables[sample.axis], file, sample.values, study.relative)
        builds += 1
        if reason is None:
            any_built = True
            built.update(pairs)
            continue
        first_reason = first_reason or (sample, reason)
        for pair in pairs:
            refused.setdefault(pair, (sample, reason))
    for (path, value), (_, reason) in refused.items():
        if (path, value) not in built and builds < MAX_BUILDS:
            how = "factor" if study.relative(path) else "value"
            raise _err(study.file, f'[vary."{path}"] values', f"{how} {value!r}: the axis "
                       f"loader refuses every sample with it ({reason})",
                       "give values the axis accepts")
    if not any_built and first_reason is not None:
        sample, reason = first_reason
        varied = ", ".join(f"{p} = {x!r}" for p, x in sample.values) or "nothing varied"
        every = "every sample" if builds < MAX_BUILDS else f"the first {builds} samples"
        raise _err(study.file, "[vary]", f"the axis loader refuses {every} (sample "
                   f"{sample.sample_id}, {varied}: {reason})",
                   "give variations the axis accepts (their ranges, the relations between "
                   "fields such as fs >= fc)")
