"""Sphinx configuration of the servotune API reference.

Build with ``sphinx-build -W --keep-going -n -b html docs/api out/api`` (tests/test_docs.py
builds it so, into a temporary folder). The page of each public module is written here, at
configuration time, into ``generated/`` (ignored by git): one page per module under
``servotune/`` whose name has no component starting with ``_``, documenting the public names
the module defines itself (a name a package re-exports is documented once, in the module that
defines it).
"""

import importlib
import inspect
import pkgutil
import re
from pathlib import Path

import servotune

project = "servotune"
author = "servotune developers"
release = servotune.__version__

extensions = ["sphinx.ext.autodoc", "numpydoc"]

# the signatures without annotations (the parameters' types are in the docstrings)
autodoc_typehints = "none"
autodoc_member_order = "bysource"
autodoc_default_options = {"show-inheritance": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
html_theme = "alabaster"
exclude_patterns = ["_build"]


def public_modules() -> list[str]:
    """Return the names of the public modules of servotune, the package first.

    Returns
    -------
    list of str
        ``"servotune"`` and every module below it whose name has no component starting with
        an underscore, sorted.
    """
    names = [
        info.name
        for info in pkgutil.walk_packages(servotune.__path__, "servotune.")
        if not any(part.startswith("_") for part in info.name.split("."))
    ]
    return ["servotune", *sorted(names)]


def own_members(module_name: str) -> list[str]:
    """Return the functions and classes of a module's ``__all__`` that the module defines.

    Parameters
    ----------
    module_name : str
        Dotted module name, e.g. ``"servotune.chatter.zoa"``.

    Returns
    -------
    list of str
        The names, in the order of ``__all__``; empty when the module has no ``__all__``.
    """
    module = importlib.import_module(module_name)
    names = []
    for name in getattr(module, "__all__", ()):
        obj = getattr(module, name)
        routine = inspect.isfunction(inspect.unwrap(obj)) or inspect.isclass(obj)
        if routine and obj.__module__ == module_name:
            names.append(name)
    return names


def write_pages(folder: Path) -> list[str]:
    """Write one page per public module into a folder.

    Parameters
    ----------
    folder : pathlib.Path
        Folder the pages are written to (created when missing).

    Returns
    -------
    list of str
        The page names (the module names), for the toctree of the index.
    """
    folder.mkdir(exist_ok=True)
    pages = []
    for name in public_modules():
        members = own_members(name)
        lines = [name, "=" * len(name), "", f".. automodule:: {name}"]
        if members:
            lines.append(f"   :members: {', '.join(members)}")
        text = "\n".join(lines) + "\n"
        path = folder / f"{name}.rst"
        if not path.exists() or path.read_text() != text:
            path.write_text(text)
        pages.append(name)
    return pages


_PAGES = write_pages(Path(__file__).parent / "generated")


def _resolve(target: str, module_name: str | None, class_name: str | None):
    """Return the servotune object a cross-reference names, or None.

    Parameters
    ----------
    target : str
        The reference's target as written (``craig_bampton``, ``servotune.structure.cb_check``,
        ``SimulationResult.sweep_envelope``); a leading ``~`` or ``.`` is dropped.
    module_name : str or None
        Module of the docstring the reference is written in.
    class_name : str or None
        Class of that docstring, when it belongs to a class.

    Returns
    -------
    object
        The object the name denotes, looked up as an absolute dotted path, then relative to the
        class and the module of the docstring; ``_MISSING`` when no servotune object has that
        name.
    """
    target = target.lstrip("~.")
    candidates = [target]
    if module_name:
        if class_name:
            candidates.append(f"{module_name}.{class_name}.{target}")
        candidates.append(f"{module_name}.{target}")
    for candidate in candidates:
        parts = candidate.split(".")
        owner = None
        for split in range(len(parts), 0, -1):
            try:
                obj = importlib.import_module(".".join(parts[:split]))
            except ImportError:
                continue
            try:
                for attr in parts[split:]:
                    owner, obj = obj, getattr(obj, attr)
            except AttributeError:
                # a dataclass field without a default is no class attribute
                fields = getattr(obj, "__dataclass_fields__", {})
                if attr == parts[-1] and attr in fields:
                    return fields[attr]
                break
            module = getattr(obj, "__module__", None) or getattr(obj, "__name__", "")
            if inspect.ismodule(obj) or str(module).startswith("servotune") or owner is not None:
                return obj
    # a name (or Class.attribute) whose first part is defined once in the public modules
    first, _, rest = target.partition(".")
    found = {id(obj): obj for obj in _public_objects().get(first, [])}
    if len(found) != 1:
        return _MISSING
    obj = next(iter(found.values()))
    for attr in rest.split(".") if rest else ():
        fields = getattr(obj, "__dataclass_fields__", {})
        if not hasattr(obj, attr):
            return fields.get(attr, _MISSING)
        obj = getattr(obj, attr)
    return obj


_MISSING = object()


def _public_objects() -> dict:
    """Return the functions and classes of the public modules by their bare name.

    Returns
    -------
    dict
        Bare name -> list of the objects of that name (several when a package re-exports it).
    """
    if not _INDEX:
        for module_name in public_modules():
            module = importlib.import_module(module_name)
            for name, obj in vars(module).items():
                routine = inspect.isfunction(inspect.unwrap(obj)) or inspect.isclass(obj)
                if routine and str(getattr(obj, "__module__", "")).startswith("servotune"):
                    _INDEX.setdefault(name, []).append(obj)
    return _INDEX


_INDEX: dict = {}


def _missing_reference(app, env, node, contnode):
    """Resolve a Python cross-reference to a servotune name that exists under another path.

    A name re-exported by a package (``servotune.structure.craig_bampton``) or imported into
    the module of the docstring (``ModalModel`` in ``servotune.structure.cbcheck``) is linked to
    its page under the defining module; a name that exists but has no page (a constant, an
    attribute) is printed as code without a link. A name that does not exist stays unresolved,
    so that ``sphinx-build -n`` reports it.

    Parameters
    ----------
    app : sphinx.application.Sphinx
        The application.
    env : sphinx.environment.BuildEnvironment
        The build environment.
    node : sphinx.addnodes.pending_xref
        The unresolved reference.
    contnode : docutils.nodes.Element
        The reference's content.

    Returns
    -------
    docutils.nodes.Element or None
        The resolved reference, the content alone, or None to leave the reference unresolved.
    """
    if node.get("refdomain") != "py":
        return None
    obj = _resolve(node["reftarget"], node.get("py:module"), node.get("py:class"))
    if obj is _MISSING:
        return None
    module = getattr(obj, "__module__", None)
    qualname = getattr(obj, "__qualname__", None)
    if inspect.ismodule(obj):
        canonical = obj.__name__
    elif module and qualname:
        canonical = f"{module}.{qualname}"
    else:
        return contnode
    domain = env.get_domain("py")
    node = node.deepcopy()
    node["reftarget"] = canonical
    for role in ("obj", "mod"):
        found = domain.resolve_xref(env, node["refdoc"], app.builder, role, canonical, node,
                                    contnode)
        if found is not None:
            return found
    return contnode


_SPANS = re.compile(r"(``.*?``|`[^`]*`)")


def _escape_bars(line: str) -> str:
    """Return a line with its ``|`` escaped outside inline literals and interpreted text.

    Parameters
    ----------
    line : str
        One line of a docstring.

    Returns
    -------
    str
        The line with every bare ``|`` written ``\\|``.
    """
    parts = _SPANS.split(line)
    for i in range(0, len(parts), 2):  # the even parts lie outside the spans
        parts[i] = re.sub(r"(?<!\\)\|", r"\\|", parts[i])
    return "".join(parts)


def _plain_bars(app, what, name, obj, options, lines):
    """Keep the absolute-value bars of the docstrings' plain-text equations as text.

    The docstrings write equations in plain text (``|X/F|``, ``|v| z / g(v)``), which
    reStructuredText would read as substitution references. The bars are escaped everywhere but
    in literal blocks (after ``::``), doctest blocks (``>>>``) and inline literals.

    Parameters
    ----------
    app : sphinx.application.Sphinx
        The application.
    what : str
        The kind of object.
    name : str
        Its name.
    obj : object
        The object.
    options : dict
        The autodoc options.
    lines : list of str
        The docstring's lines, changed in place.
    """
    literal_indent = None
    doctest = False
    for i, line in enumerate(lines):
        stripped = line.strip()
        indent = len(line) - len(line.lstrip())
        if literal_indent is not None:
            if not stripped or indent > literal_indent:
                continue
            literal_indent = None
        if doctest:
            if stripped:
                continue
            doctest = False
        if stripped.startswith(">>>"):
            doctest = True
            continue
        lines[i] = _escape_bars(line)
        if stripped.endswith("::"):
            literal_indent = indent


def setup(app):
    """Connect the resolver of re-exported names and the escaping of bars.

    Parameters
    ----------
    app : sphinx.application.Sphinx
        The application.

    Returns
    -------
    dict
        The extension's metadata.
    """
    app.connect("missing-reference", _missing_reference)
    app.connect("autodoc-process-docstring", _plain_bars, priority=600)
    return {"parallel_read_safe": True}
