"""Names that become parts of file names: one rule for the command line and the studies."""

from __future__ import annotations

import re

__all__ = ["safe_name"]

_SAFE = re.compile(r"[^A-Za-z0-9_.+-]+")


def safe_name(name: str, fallback: str = "unnamed") -> str:
    """Return a folder-name part made of letters, digits and ``_ . + -`` only, never ``..`` or
    a leading dot, at most 80 characters; so that a name cannot point outside ``--out``.

    Parameters
    ----------
    name : str
        Any name (an axis', a study's).
    fallback : str
        What an empty result becomes.

    Returns
    -------
    str

    Examples
    --------
    >>> safe_name("../../x")
    'x'
    >>> safe_name("X axis (rev 2)")
    'X_axis_rev_2'
    """
    text = _SAFE.sub("_", str(name))
    text = re.sub(r"\.{2,}", "_", text)
    text = re.sub(r"_{2,}", "_", text).strip("._-")
    return text[:80] or fallback
