"""servotune's own guide-way friction laws, one module each (LuGre, GMS, viscous).

Each is declared as an entry point of the group ``servotune.friction_laws`` in servotune's
``pyproject.toml`` and imported when first asked for (:func:`servotune.friction.law.friction_law`);
a law of another package is declared the same way in that package. Only in a source tree that is
not installed are the modules of this package imported to find them
(:func:`servotune.plugins.discover`). See README.md, "Extending", and
:mod:`servotune.friction.law` for the interface.
"""

from __future__ import annotations

__all__: list[str] = []
