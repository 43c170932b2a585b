"""servotune's own requirements of the tuning problem, one module each.

Each is declared as an entry point of the group ``servotune.requirements`` in servotune's
``pyproject.toml`` and loaded by :func:`servotune.tuning.constraint.requirements`; a requirement
of another package is declared the same way in that package. Only in a source tree that is not
installed are the modules of this package imported to find them
(:func:`servotune.plugins.discover`). See :mod:`servotune.tuning.constraint` for the interface.
"""

from __future__ import annotations

__all__: list[str] = []
