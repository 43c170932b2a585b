"""Plug-ins: the friction laws and requirements of servotune and of any other installed package.

A plug-in is found through its **entry point** (:func:`importlib.metadata.entry_points`, as
pytest and Sphinx find theirs), in the group :data:`FRICTION_LAWS_GROUP` or
:data:`REQUIREMENTS_GROUP`. Another package declares its law in its own ``pyproject.toml``, and
servotune finds it once that package is installed, with no edit of servotune::

    [project.entry-points."servotune.friction_laws"]
    dahl = "dahl_friction:DahlFriction"

servotune's own laws and requirements are declared the same way in its ``pyproject.toml``: one
mechanism. Importing every module of the package (:func:`import_modules`, ``pkgutil``) is only
the fallback for a source tree that is not installed, whose entry points are unknown (when the
``servotune`` distribution declares none in the group).

A plug-in is loaded on first use (:func:`load_plugin`) and checked then, before anything uses
it: a friction law when an axis file or a call names it, the requirements all together when a
tuning problem is built. Why lazy: the names come from the installed metadata alone, so a
plug-in that fails to import breaks only what names it (its error said with its entry point and
distribution), never an axis on another law. Two plug-ins of one name are refused as soon as
the names are read (:func:`entry_point_plugins`), naming both.

Examples
--------
>>> laws = entry_point_plugins(FRICTION_LAWS_GROUP)
>>> laws["lugre"].value, laws["lugre"].from_servotune
('servotune.friction.laws.lugre:LuGreFriction', True)
"""

from __future__ import annotations

import importlib
import importlib.metadata
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass, field

__all__ = ["PluginError", "Plugin", "entry_point_plugins", "discover", "load_plugin",
           "missing_methods", "import_modules", "FRICTION_LAWS_GROUP", "REQUIREMENTS_GROUP",
           "OWN_DISTRIBUTION"]

#: Entry-point group of the friction laws (the entry point's name is the law's ``name``).
FRICTION_LAWS_GROUP = "servotune.friction_laws"
#: Entry-point group of the tuning requirements.
REQUIREMENTS_GROUP = "servotune.requirements"
#: The distribution whose entry points are servotune's own plug-ins.
OWN_DISTRIBUTION = "servotune"

#: What the plug-ins of a group are, for messages.
_KINDS = {FRICTION_LAWS_GROUP: "friction law", REQUIREMENTS_GROUP: "requirement"}


class PluginError(RuntimeError):
    """A plug-in that cannot be used: it fails to import, lacks what its interface requires,
    or shares its name with another (the message names its entry point and distribution)."""


@dataclass(frozen=True)
class Plugin:
    """One plug-in as its distribution declares it (an entry point), not yet loaded.

    Parameters
    ----------
    name : str
        The entry point's name (a friction law's ``name``).
    value : str
        What it loads, ``"module:attribute"``.
    group : str
        The entry-point group.
    distribution : str
        The distribution that declares it, ``"<name> <version>"``.
    entry_point : importlib.metadata.EntryPoint or None
        The entry point (None: a plug-in made by hand, loaded from ``value``).
    """

    name: str
    value: str
    group: str
    distribution: str
    entry_point: importlib.metadata.EntryPoint | None = field(default=None, compare=False,
                                                               repr=False)

    @property
    def kind(self) -> str:
        """What the plug-in is (``"friction law"``, ``"requirement"``)."""
        return _KINDS.get(self.group, "plug-in")

    def describe(self) -> str:
        """Return the plug-in as messages name it.

        Returns
        -------
        str
            Its entry point (group, name and value) and its distribution.
        """
        return (f"entry point {self.name!r} ({self.name} = {self.value} in group "
                f"{self.group}) of the distribution {self.distribution}")

    @property
    def from_servotune(self) -> bool:
        """Whether servotune itself declares the plug-in."""
        return self.distribution.split(" ")[0] == OWN_DISTRIBUTION


def _distribution(ep: importlib.metadata.EntryPoint) -> str:
    dist = getattr(ep, "dist", None)
    if dist is None:
        return "(unknown)"
    meta = dist.metadata
    return f"{meta['Name']} {meta['Version']}"


def entry_point_plugins(group: str) -> dict[str, Plugin]:
    """Return the plug-ins the installed distributions declare in a group, by name (none loaded).

    Parameters
    ----------
    group : str
        The entry-point group, e.g. :data:`FRICTION_LAWS_GROUP`.

    Returns
    -------
    dict of str to Plugin
        Entry-point name -> plug-in. A distribution found twice on the path, declaring the same
        ``module:attribute``, counts once.

    Raises
    ------
    PluginError
        Two plug-ins of one name that load different things (the message names both entry
        points and their distributions).
    """
    found: dict[str, Plugin] = {}
    for ep in importlib.metadata.entry_points(group=group):
        plugin = Plugin(ep.name, ep.value, group, _distribution(ep), ep)
        other = found.get(ep.name)
        if other is None:
            found[ep.name] = plugin
        elif other.value != plugin.value:
            raise PluginError(f"two {plugin.kind} plug-ins are named {ep.name!r}: the "
                              f"{other.describe()} and the {plugin.describe()}; uninstall "
                              "one of the distributions or rename one entry point")
    return found


def discover(group: str, package: str) -> dict[str, Plugin]:
    """Return the plug-ins of a group; in an uninstalled source tree, import the package's own.

    Parameters
    ----------
    group : str
        The entry-point group.
    package : str
        servotune's package of plug-in modules for the group, imported (:func:`import_modules`)
        only when the ``servotune`` distribution declares no entry point in it: a source tree
        that is not installed, or installed before its entry points were declared. Its classes
        then register themselves by being defined.

    Returns
    -------
    dict of str to Plugin
        The entry points, by name (:func:`entry_point_plugins`).

    Raises
    ------
    PluginError
        Two plug-ins of one name.
    """
    found = entry_point_plugins(group)
    if not any(p.from_servotune for p in found.values()):
        import_modules(package)
    return found


def missing_methods(plugin_class: type, base: type, names) -> list[str]:
    """Return the methods of an interface a class leaves to the base class.

    Parameters
    ----------
    plugin_class : type
        The class of the plug-in.
    base : type
        The interface's base class (whose methods only raise).
    names : iterable of str
        The methods the interface requires.

    Returns
    -------
    list of str
        Those of ``names`` that no class between ``plugin_class`` and ``base`` defines, in
        order.
    """
    missing = []
    for name in names:
        owner = next((k for k in plugin_class.__mro__ if name in vars(k)), None)
        if owner is None or owner is base:
            missing.append(name)
    return missing


def load_plugin(plugin: Plugin, check: Callable[[object], list[str]]):
    """Load a plug-in and check it provides what its interface requires.

    Parameters
    ----------
    plugin : Plugin
        The plug-in.
    check : callable
        ``check(obj) -> list of str``: what the loaded object lacks (empty: usable).

    Returns
    -------
    object
        The loaded object (a class).

    Raises
    ------
    PluginError
        It fails to import (the message gives the error) or ``check`` finds something missing;
        either way the message names the entry point and the distribution.
    """
    try:
        if plugin.entry_point is not None:
            obj = plugin.entry_point.load()
        else:
            module, _, attribute = plugin.value.partition(":")
            obj = importlib.import_module(module)
            for part in filter(None, attribute.split(".")):
                obj = getattr(obj, part)
    except Exception as exc:
        raise PluginError(f"the {plugin.kind} plug-in of the {plugin.describe()} cannot be "
                          f"loaded: {type(exc).__name__}: {exc}") from exc
    problems = check(obj)
    if problems:
        raise PluginError(f"the {plugin.kind} plug-in of the {plugin.describe()} is refused: "
                          + "; ".join(problems))
    return obj


def import_modules(package: str) -> list[str]:
    """Import every public module of a package (those not imported yet, and any added to its
    folders since): the fallback discovery of an uninstalled source tree.

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

    Examples
    --------
    >>> sorted(import_modules("servotune.friction.laws"))[:2]
    ['servotune.friction.laws.gms', 'servotune.friction.laws.lugre']
    """
    pkg = importlib.import_module(package)
    names = sorted(f"{package}.{info.name}" for info in pkgutil.iter_modules(pkg.__path__)
                   if not info.name.startswith("_"))
    for name in names:
        importlib.import_module(name)
    return names
