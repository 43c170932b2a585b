"""The guide-way friction laws, one module each, imported (and so registered) on import.

Every module of this package is imported here (``pkgutil.iter_modules``), and defining a class on
:class:`servotune.friction.law.FrictionLaw` registers it: adding a law is adding a module, no list
to edit. See README.md, "Extending", and :mod:`servotune.friction.law` for the interface.
"""

from __future__ import annotations

import importlib
import pkgutil

__all__: list[str] = []

for _info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
    if not _info.name.startswith("_"):
        importlib.import_module(f"{__name__}.{_info.name}")
