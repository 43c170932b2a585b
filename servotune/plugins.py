"""Discovery of plug-in modules: every module of a package imported, so that the classes they
define register themselves (friction laws, tuning requirements).

Examples
--------
>>> import servotune.friction.laws as laws
>>> sorted(import_modules("servotune.friction.laws"))[:2]
['servotune.friction.laws.gms', 'servotune.friction.laws.lugre']
"""

from __future__ import annotations

import importlib
import pkgutil

__all__ = ["import_modules"]


def import_modules(package: str) -> list[str]:
    """Import every public module of a package (those not imported yet, and any added to its
    folders since).

    Parameters
    ----------
    package : str
        Dotted name of the package, e.g. ``"servotune.friction.laws"``.

    Returns
    -------
    list of str
        The dotted names of its public modules (whose names do not start with ``_``), sorted.

    Raises
    ------
    ImportError
        When the package or one of its modules cannot be imported.
    """
    pkg = importlib.import_module(package)
    names = sorted(f"{package}.{info.name}" for info in pkgutil.iter_modules(pkg.__path__)
                   if not info.name.startswith("_"))
    for name in names:
        importlib.import_module(name)
    return names
