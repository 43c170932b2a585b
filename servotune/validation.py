"""Checks of scalar parameters, shared by the value types' ``__post_init__``.

Each check converts a value to ``float`` and returns it, or raises a :class:`ValueError` whose
message names the owner and the field, states the accepted range with its unit and shows the
value given, e.g. ``Design.kv must be finite and > 0 1/s, got -5.0``. An optional ``hint``
adds how to fix it.

Examples
--------
>>> positive("Motor", "resistance", 0.25, "ohm")
0.25
>>> positive("Design", "kv", -5, "1/s")
Traceback (most recent call last):
...
ValueError: Design.kv must be finite and > 0 1/s, got -5.0
>>> fraction("NotchFilter", "depth", 1.0)
Traceback (most recent call last):
...
ValueError: NotchFilter.depth must be finite and in [0, 1), got 1.0

The array checks show the first offending element and where it stands:

>>> positive_array("lugre_cycle:", "omega", [10.0, 0.0], "rad/s")
Traceback (most recent call last):
...
ValueError: lugre_cycle: omega must be finite and > 0 rad/s, got 0.0 (at index 1)
"""

from __future__ import annotations

import math
import numbers

import numpy as np

__all__ = ["finite", "finite_array", "fraction", "number", "positive", "positive_array"]


def _label(owner: str, name: str) -> str:
    if not owner:
        return name
    return f"{owner} {name}" if owner.endswith(":") else f"{owner}.{name}"


def _fail(owner: str, name: str, need: str, unit: str, value, hint: str) -> ValueError:
    unit = f" {unit}" if unit else ""
    hint = f"; {hint}" if hint else ""
    return ValueError(f"{_label(owner, name)} must be {need}{unit}, got {value!r}{hint}")


def number(owner: str, name: str, value, unit: str = "", hint: str = "") -> float:
    """Return ``value`` as a float, refusing what is not a real number (bool, str, None).

    Parameters
    ----------
    owner : str
        Name of the type or function the value belongs to: ``"Design"`` and ``"kv"`` are shown
        as ``Design.kv``; an owner ending in ':' (``"beam a-b:"``) is followed by a space.
        May be empty.
    name : str
        Name of the field (``"kv"``).
    value : object
        The value given.
    unit : str, optional
        Its SI unit, shown in the message.
    hint : str, optional
        How to fix a wrong value, appended to the message.

    Returns
    -------
    float
        ``float(value)`` (may be NaN or infinite).

    Raises
    ------
    ValueError
        If the value is not a real number.
    """
    zero_d = isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf"
    if not zero_d and (isinstance(value, bool) or not isinstance(value, numbers.Real)):
        raise _fail(owner, name, "a number", f"in {unit}" if unit else "", value, hint)
    return float(value)


def finite(owner: str, name: str, value, unit: str = "", hint: str = "") -> float:
    """Return ``value`` as a float, refusing NaN and infinities.

    Parameters
    ----------
    owner, name : str
        Owner and field, as for :func:`number`.
    value : object
        The value given.
    unit : str, optional
        Its SI unit, shown in the message.
    hint : str, optional
        How to fix a wrong value, appended to the message.

    Returns
    -------
    float
        The finite value.

    Raises
    ------
    ValueError
        If the value is not a finite real number.
    """
    value = number(owner, name, value, unit, hint)
    if not math.isfinite(value):
        raise _fail(owner, name, "finite", unit, value, hint)
    return value


def positive(owner: str, name: str, value, unit: str = "", hint: str = "", *,
             allow_zero: bool = False, allow_inf: bool = False) -> float:
    """Return ``value`` as a float if it is > 0 (or >= 0) and finite (or +inf if allowed).

    Parameters
    ----------
    owner, name : str
        Owner and field, as for :func:`number`.
    value : object
        The value given.
    unit : str, optional
        Its SI unit, shown in the message.
    hint : str, optional
        How to fix a wrong value, appended to the message.
    allow_zero : bool, optional
        Accept 0 (the check is then ``>= 0``).
    allow_inf : bool, optional
        Accept ``+inf`` (e.g. an integral time meaning "no integral action").

    Returns
    -------
    float
        The value.

    Raises
    ------
    ValueError
        If the value is not a number, is NaN, negative, zero (unless ``allow_zero``) or
        infinite (unless ``allow_inf``).
    """
    value = number(owner, name, value, unit, hint)
    ok = (value >= 0.0 if allow_zero else value > 0.0) and (
        math.isfinite(value) or (allow_inf and value == math.inf))
    if not ok:
        need = ">= 0" if allow_zero else "> 0"
        need = f"{need} (or inf)" if allow_inf else f"finite and {need}"
        raise _fail(owner, name, need, unit, value, hint)
    return value


def fraction(owner: str, name: str, value, unit: str = "", hint: str = "", *,
             closed: bool = False) -> float:
    """Return ``value`` as a float if it lies in [0, 1) (or [0, 1] with ``closed``).

    Parameters
    ----------
    owner, name : str
        Owner and field, as for :func:`number`.
    value : object
        The value given.
    unit : str, optional
        Its unit, shown in the message (usually none).
    hint : str, optional
        How to fix a wrong value, appended to the message.
    closed : bool, optional
        Accept 1 as well.

    Returns
    -------
    float
        The value.

    Raises
    ------
    ValueError
        If the value is not a number or lies outside the interval.
    """
    value = number(owner, name, value, unit, hint)
    ok = math.isfinite(value) and 0.0 <= value and (value <= 1.0 if closed else value < 1.0)
    if not ok:
        raise _fail(owner, name, "finite and in [0, 1]" if closed else "finite and in [0, 1)",
                    unit, value, hint)
    return value


def _array_fail(owner, name, need, unit, value, bad, hint) -> ValueError:
    index = tuple(int(i) for i in np.argwhere(bad)[0])
    where = "" if value.ndim == 0 else f" (at index {index[0] if len(index) == 1 else index})"
    shown = float(value[index]) if value.ndim else float(value)
    unit = f" {unit}" if unit else ""
    hint = f"; {hint}" if hint else ""
    return ValueError(f"{_label(owner, name)} must be {need}{unit}, got {shown!r}{where}{hint}")


def _real_array(owner, name, value, unit, hint) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise _fail(owner, name, "an array of numbers", f"in {unit}" if unit else "", value,
                    hint) from None
    return array


def finite_array(owner: str, name: str, value, unit: str = "", hint: str = "") -> np.ndarray:
    """Return ``value`` as a float array, refusing NaN and infinities in any element.

    Parameters
    ----------
    owner, name : str
        Owner and field, as for :func:`number`.
    value : array_like
        The values given (a scalar gives a 0-d array).
    unit, hint : str, optional
        Unit and hint, as for :func:`finite`.

    Returns
    -------
    numpy.ndarray
        ``numpy.asarray(value, dtype=float)``.

    Raises
    ------
    ValueError
        If the values are not numbers, or one is not finite (the message shows the first such
        element and its index).
    """
    array = _real_array(owner, name, value, unit, hint)
    bad = ~np.isfinite(array)
    if np.any(bad):
        raise _array_fail(owner, name, "finite", unit, array, bad, hint)
    return array


def positive_array(owner: str, name: str, value, unit: str = "", hint: str = "", *,
                   allow_zero: bool = False) -> np.ndarray:
    """Return ``value`` as a float array if every element is finite and > 0 (or >= 0).

    Parameters
    ----------
    owner, name : str
        Owner and field, as for :func:`number`.
    value : array_like
        The values given (a scalar gives a 0-d array).
    unit, hint : str, optional
        Unit and hint, as for :func:`finite`.
    allow_zero : bool, optional
        Accept 0 (the check is then ``>= 0``).

    Returns
    -------
    numpy.ndarray
        ``numpy.asarray(value, dtype=float)``.

    Raises
    ------
    ValueError
        If the values are not numbers, or one is NaN, infinite, negative or zero (unless
        ``allow_zero``); the message shows the first such element and its index.
    """
    array = _real_array(owner, name, value, unit, hint)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(array) & ((array >= 0.0) if allow_zero else (array > 0.0))
    if not np.all(ok):
        need = "finite and >= 0" if allow_zero else "finite and > 0"
        raise _array_fail(owner, name, need, unit, array, ~ok, hint)
    return array
