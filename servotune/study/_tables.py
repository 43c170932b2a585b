"""What a study's description and its checks share: the error of a study file and the
varied axis tables (:func:`apply_values`), below both :mod:`servotune.study.spec` and
:mod:`servotune.study.validate` so that neither imports the other's module for them."""

from __future__ import annotations

import copy

__all__ = ["StudyFormatError", "apply_values", "study_error"]


class StudyFormatError(ValueError):
    """A study file that cannot be used: names the file, the field and the fix."""


def study_error(file, where: str, problem: str, fix: str) -> StudyFormatError:
    """Return the error of a study file: ``"<file>: <where>: <problem>; <fix>"``.

    Parameters
    ----------
    file : path-like
        The study file.
    where : str
        The field or section.
    problem, fix : str
        What is wrong and how to fix it.

    Returns
    -------
    StudyFormatError
    """
    return StudyFormatError(f"{file}: {where}: {problem}; {fix}")


def apply_values(tables: dict, values, relative=lambda path: False,
                 applied: dict | None = None) -> dict:
    """Return a copy of an axis description's tables with the varied fields set.

    A named LuGre set (``[friction] lugre = "bianchi2014"``) is expanded into its table when a
    field below it varies. With ``relative(path)`` true the value multiplies the field's own.

    Parameters
    ----------
    tables : dict
        The axis description as read from its TOML (not changed).
    values : iterable of (str, object)
        (dotted path, value) of each varied field.
    relative : callable, optional
        ``relative(path) -> bool``: whether the value multiplies the field's own (default
        never).
    applied : dict, optional
        When given, receives each path's value as set (the product for a relative one).

    Returns
    -------
    dict
        The modified deep copy of ``tables``.

    Raises
    ------
    KeyError
        For a path whose section or key the description does not have (relative values) or
        that runs through a value that is not a table; the message names the path.
    """
    from ..friction.lugre import LuGreParameters

    out = copy.deepcopy(tables)
    for path, value in values:
        parts = path.split(".")
        node = out
        for i, part in enumerate(parts[:-1]):
            child = node.get(part)
            if child is None:
                child = node[part] = {}
            elif isinstance(child, str) and ".".join(parts[:i + 1]) == "friction.lugre":
                try:
                    child = node[part] = LuGreParameters.named(child).to_dict()
                except (KeyError, ValueError):
                    raise KeyError(f"{path}: the LuGre set {child!r} is not known") from None
                child = {k: v for k, v in child.items() if v is not None}
                node[part] = child
            elif not isinstance(child, dict):
                raise KeyError(f"{path}: {'.'.join(parts[:i + 1])} is {child!r}, not a table")
            node = child
        last = parts[-1]
        if relative(path):
            if not isinstance(node.get(last), int | float) or isinstance(node.get(last), bool):
                raise KeyError(f"{path}: a relative variation needs a number there in the axis "
                               f"description (it has {node.get(last)!r})")
            node[last] = float(node[last]) * float(value)
        else:
            node[last] = value
        if applied is not None:
            applied[path] = node[last]
    return out
