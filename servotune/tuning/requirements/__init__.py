"""The requirements of the tuning problem, one module each, imported (and registered) on import.

Every module of this package is imported here (``pkgutil.iter_modules``), and defining a class on
:class:`servotune.tuning.constraint.Requirement` registers it: adding a requirement is adding a
module, no list to edit. See :mod:`servotune.tuning.constraint` for the interface.
"""

from __future__ import annotations

import importlib
import pkgutil

__all__: list[str] = []

for _info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
    if not _info.name.startswith("_"):
        importlib.import_module(f"{__name__}.{_info.name}")
