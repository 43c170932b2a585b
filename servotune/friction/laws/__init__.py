"""The guide-way friction laws, one module each, imported (and so registered) on import.

Every module of this package is imported here (:func:`servotune.plugins.import_modules`), and
defining a class on :class:`servotune.friction.law.FrictionLaw` registers it: adding a law is
adding a module, no list to edit. See README.md, "Extending", and :mod:`servotune.friction.law`
for the interface.
"""

from __future__ import annotations

from ...plugins import import_modules

__all__: list[str] = []

import_modules(__name__)
