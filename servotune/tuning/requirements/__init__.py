"""The requirements of the tuning problem, one module each, imported (and registered) on import.

Every module of this package is imported here (:func:`servotune.plugins.import_modules`), and
defining a class on :class:`servotune.tuning.constraint.Requirement` registers it: adding a
requirement is adding a module, no list to edit. See :mod:`servotune.tuning.constraint` for the
interface.
"""

from __future__ import annotations

from ...plugins import import_modules

__all__: list[str] = []

import_modules(__name__)
