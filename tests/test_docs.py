"""The API documentation, checked mechanically: numpydoc validation and a Sphinx build.

The public API is every name ``servotune/__init__.py`` exports and every name in the
``__all__`` of a public module under ``servotune/`` (a module whose dotted name has no component
starting with ``_``, subpackages included): its functions, its classes and the public methods
of those classes (functions, static and class methods defined in the class body; properties
and inherited methods are left out). Each object is checked once, under its defining module.

The numpydoc checks (``numpydoc.validate.validate``; the codes are numpydoc's) and why:

- ``GL08``: every public function, class and method has a docstring.
- ``SS01`` to ``SS05``: a summary line that starts with a capital, ends with a period, has no
  leading whitespace and starts with an infinitive ("Return", not "Returns"), which is what
  the one-line tables of the API reference show. ``SS06`` (the summary fits on one line) is
  not checked: many summaries are one sentence that wraps at 100 characters.
- ``PR02``, ``PR03``, ``PR07`` on every object: a documented parameter exists in the
  signature, in the signature's order, and has a description (a wrong Parameters section is
  worse than none).
- ``PR01`` and ``RT01`` on every function and method: each parameter documented (``self``
  and ``cls`` aside), and a Returns section when the function returns a value (numpydoc finds
  a ``return`` with a value in its source). A class documents its fields in its own words
  (most are dataclasses, whose constructor is the list of fields), so ``PR01`` is not asked
  of classes.
- ``SA01`` on the main entry points (``MAIN_ENTRY_POINTS``, the functions the README and the
  index of the API reference lead with), and their See Also sections name at least one other
  main entry point, so a reader can go from one to the next (reported as ``SA-main``).

``EX01`` (Examples), ``ES01`` (extended summary), ``SA01`` elsewhere, ``RT02``/``RT03`` and the
``YD`` codes are not asked: the examples the docstrings have run as doctests
(``pytest --doctest-modules``), and the others are style.

The Sphinx build of ``docs/api`` (``sphinx-build -b dummy -n --keep-going``, into a temporary
folder) fails on any warning: a docutils error in a docstring, a cross-reference to a name that
does not exist (``-n``), an autodoc import error. The dummy builder reads, resolves and checks
every page as the HTML builder does but writes nothing, which halves the time;
``sphinx-build -b html docs/api out/api`` writes the pages.

``NOT_YET_CHECKED`` names the modules whose docstrings do not pass yet; their offenders and
warnings are tolerated (``python tests/test_docs.py`` lists them). It is empty: every public
module passes.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

numpydoc_validate = pytest.importorskip("numpydoc.validate")
docscrape = pytest.importorskip("numpydoc.docscrape")

import servotune  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent

# modules (and the modules below them) whose docstrings are not yet complete: none; a module
# named here has its offenders and Sphinx warnings tolerated
NOT_YET_CHECKED: tuple[str, ...] = ()

#: The entry points a reader starts from: See Also required, linking to one another.
MAIN_ENTRY_POINTS = (
    "servotune.axis.load_axis",
    "servotune.design.tune_axis",
    "servotune.tuning.solve.tune",
    "servotune.tuning.verify.verify",
    "servotune.analysis.loop_report",
    "servotune.analysis.compliance_curve",
    "servotune.frequency.compliance",
    "servotune.friction.equivalent.describing_function",
    "servotune.chatter.zoa.stability_lobes",
    "servotune.chatter.sdm.sdm_lobes",
    "servotune.simulate.simulator.simulate",
    "servotune.structure.reduction.craig_bampton",
    "servotune.twomass.optimal_damping",
)

#: Codes checked on every public object.
CODES_ALL = ("GL08", "SS01", "SS02", "SS03", "SS04", "SS05", "PR02", "PR03", "PR07")
#: Codes checked on functions and methods (not on classes).
CODES_CALLABLE = ("PR01", "RT01")


def public_modules() -> list[str]:
    """Return the public modules: ``servotune`` and those below it without a ``_`` component.

    Returns
    -------
    list of str
        Dotted module names, the package first.
    """
    names = [
        info.name
        for info in pkgutil.walk_packages(servotune.__path__, "servotune.")
        if not any(part.startswith("_") for part in info.name.split("."))
    ]
    return ["servotune", *sorted(names)]


def public_objects() -> dict[str, object]:
    """Return the public functions, classes and methods by their canonical dotted name.

    Returns
    -------
    dict
        ``"module.qualname"`` -> object, for the names of every public ``__all__`` defined in
        servotune, and the public methods of those classes.
    """
    objects = {}
    for module_name in public_modules():
        module = importlib.import_module(module_name)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if not (inspect.isfunction(inspect.unwrap(obj)) or inspect.isclass(obj)):
                continue
            if not str(getattr(obj, "__module__", "")).startswith("servotune"):
                continue
            key = f"{obj.__module__}.{obj.__qualname__}"
            objects[key] = obj
            if inspect.isclass(obj):
                for attr, value in vars(obj).items():
                    if attr.startswith("_"):
                        continue
                    if isinstance(value, staticmethod | classmethod):
                        value = value.__func__
                    if inspect.isfunction(value):
                        objects[f"{key}.{attr}"] = value
    return dict(sorted(objects.items()))


def see_also_names(obj) -> set[str]:
    """Return the last components of the names a docstring's See Also section lists.

    Parameters
    ----------
    obj : object
        Function or class with a numpydoc docstring.

    Returns
    -------
    set of str
        ``{"stability_lobes", ...}`` for ``servotune.chatter.stability_lobes`` and the like.
    """
    doc = docscrape.NumpyDocString(inspect.getdoc(obj) or "")
    return {name.split(".")[-1].lstrip("~") for names, _ in doc["See Also"] for name, _ in names}


def offenders() -> dict[str, list[str]]:
    """Return the docstring errors of the public API.

    Returns
    -------
    dict
        Canonical name -> the sorted error codes found (only names with errors), for every
        public object, including those in ``NOT_YET_CHECKED``.
    """
    found = {}
    main_names = {name.rsplit(".", 1)[-1] for name in MAIN_ENTRY_POINTS}
    for key, obj in public_objects().items():
        result = numpydoc_validate.validate(key)
        codes = {code for code, _ in result["errors"]}
        wanted = set(CODES_ALL)
        if not inspect.isclass(obj):
            wanted |= set(CODES_CALLABLE)
        if key in MAIN_ENTRY_POINTS:
            wanted.add("SA01")
            if "SA01" not in codes and not (see_also_names(obj) & (main_names - {obj.__name__})):
                codes.add("SA-main (See Also names no other main entry point)")
        codes = sorted(code for code in codes if code in wanted or code.startswith("SA-main"))
        if codes:
            found[key] = codes
    return found


def not_yet_checked(name: str) -> bool:
    """Return whether a dotted name lies in a module of ``NOT_YET_CHECKED``.

    Parameters
    ----------
    name : str
        Dotted name of a module or of an object in one.

    Returns
    -------
    bool
        True when the name is a listed module or lies below one.
    """
    return any(name == m or name.startswith(m + ".") for m in NOT_YET_CHECKED)


def test_main_entry_points_exist():
    """Each main entry point is a public function of its module."""
    objects = public_objects()
    assert [name for name in MAIN_ENTRY_POINTS if name not in objects] == []


def test_numpydoc_validation():
    """The public API passes the numpydoc checks listed in this module's docstring."""
    failing = {key: codes for key, codes in offenders().items() if not not_yet_checked(key)}
    listing = "\n".join(f"{key}: {', '.join(codes)}" for key, codes in failing.items())
    assert not failing, f"docstrings failing numpydoc validation:\n{listing}"


def sphinx_warnings(out: Path) -> list[str]:
    """Build the API reference and return its warnings.

    Parameters
    ----------
    out : pathlib.Path
        Empty folder; the sources are copied to ``out/src`` and built into ``out/build``.

    Returns
    -------
    list of str
        The lines of Sphinx's warning stream that report a warning or an error.
    """
    src = out / "src"
    shutil.copytree(ROOT / "docs" / "api", src, ignore=shutil.ignore_patterns("generated"))
    warning_file = out / "warnings.txt"
    run = subprocess.run(
        [sys.executable, "-m", "sphinx", "-b", "dummy", "-n", "--keep-going", "-q",
         "-w", str(warning_file), "-d", str(out / "doctrees"), str(src), str(out / "build")],
        capture_output=True, text=True, cwd=ROOT, timeout=600,
    )
    text = warning_file.read_text() if warning_file.exists() else ""
    lines = [line for line in text.splitlines() if re.search(r"(WARNING|ERROR|CRITICAL)", line)]
    if run.returncode not in (0, 1):
        lines.append(f"sphinx-build exited with {run.returncode}: {run.stderr[-2000:]}")
    return lines


def warning_module(line: str) -> str | None:
    """Return the servotune module a Sphinx warning is located in.

    Parameters
    ----------
    line : str
        One warning line, ``/path/servotune/x/y.py:docstring of ...: WARNING: ...``.

    Returns
    -------
    str or None
        Dotted module name (``servotune.x.y``), None when the warning is not in a source file
        of servotune.
    """
    match = re.search(r"(servotune/[\w/]+)\.py:", line)
    if not match:
        return None
    return match.group(1).replace("/", ".").removesuffix(".__init__")


def test_sphinx_build(tmp_path):
    """The API reference builds without warnings (``-n``: every cross-reference resolves)."""
    lines = sphinx_warnings(tmp_path)
    failing = [line for line in lines if not not_yet_checked(warning_module(line) or "")]
    assert failing == [], "Sphinx warnings:\n" + "\n".join(failing)
    pages = {p.stem for p in (tmp_path / "src" / "generated").glob("*.rst")}
    assert set(public_modules()) <= pages


if __name__ == "__main__":
    # the offenders still tolerated in the modules of NOT_YET_CHECKED
    for key, codes in offenders().items():
        if not_yet_checked(key):
            print(f"{key}: {', '.join(codes)}")
    if "--sphinx" in sys.argv:
        import tempfile

        with tempfile.TemporaryDirectory() as folder:
            for line in sphinx_warnings(Path(folder)):
                if not_yet_checked(warning_module(line) or ""):
                    print(line)
