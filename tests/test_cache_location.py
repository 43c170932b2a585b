"""Compiled and generated code goes to the user's cache, never into the package
(servotune/cache.py; the reference is the file system itself: a listing with sizes and
modification times of the package before and after a run)."""

from __future__ import annotations

import os
import re
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest

import servotune
from servotune.cache import CacheFolderError, cache_folder, cache_root, cached_njit
from servotune.simulate.integrator import _kernel_directory
from servotune.tuning import _clib

PACKAGE = Path(servotune.__file__).resolve().parent
TESTS = Path(__file__).resolve().parent
MODELS = TESTS.parent / "models"

# a short time simulation of a small axis with LuGre pads: it generates the LuGre kernel module
# and compiles the integrator's numba functions (all of them, in a fresh cache)
SIMULATION = """
import servotune
from axis_fixtures import PADS, small_axis, small_drive
from servotune.friction import LuGreParameters
from servotune.simulate import LuGreFriction, NonlinearAxis, simulate, sine_sweep

axis = NonlinearAxis(small_axis(), small_drive(velocity_feedforward=1.0), PADS,
                     LuGreFriction(LuGreParameters.named("bianchi2014")))
result = simulate(axis, sine_sweep(50.0, 50.0, 60.0, 0.05))
print(servotune.__file__)
print(result.complete)
"""


def _installed_copy(tmp_path) -> Path:
    """The package as an installation lays it out (sources only), in a folder of its own:
    what the run does to it is not mixed up with edits made to the working tree meanwhile."""
    site = tmp_path / "site"
    shutil.copytree(PACKAGE, site / "servotune",
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return site


def _listing(folder: Path) -> dict:
    """Every file and folder under ``folder`` with its size and modification time (a folder's
    time changes when a file is created in it or removed from it)."""
    out = {}
    for path in [folder, *folder.rglob("*")]:
        st = path.lstat()
        out[str(path.relative_to(folder))] = (st.st_size, st.st_mtime_ns)
    return out


def _simulate(site: Path, cache: Path) -> None:
    env = {**os.environ, "SERVOTUNE_CACHE": str(cache),
           "PYTHONPATH": os.pathsep.join([str(site), str(TESTS)]),
           # bytecode is the interpreter's business (an installer compiles it), not servotune's
           "PYTHONDONTWRITEBYTECODE": "1"}
    for name in ("SERVOTUNE_KERNEL_DIR", "NUMBA_CACHE_DIR", "NUMBA_DISABLE_JIT"):
        env.pop(name, None)
    # run outside the working tree: "-c" puts the current folder first on the path
    done = subprocess.run([sys.executable, "-c", SIMULATION], env=env, cwd=site.parent,
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    imported, complete = done.stdout.split()[-2:]
    assert Path(imported).resolve().parent == (site / "servotune").resolve()  # the copy ran
    assert complete == "True"


def _assert_cache_filled(cache: Path) -> None:
    kernels = cache / "kernels"
    assert list(kernels.glob("_kernel_lugre_*.py")), "no generated kernel module in the cache"
    assert list((kernels / "__pycache__").glob("_kernel_lugre_*.nbi")), \
        "numba did not cache the generated kernel next to it"
    assert list((cache / "numba").rglob("integrator._u_into-*.nbi")), \
        "numba did not cache the package's functions in the cache"


def test_a_simulation_writes_its_kernels_into_the_cache_and_nothing_into_the_package(tmp_path):
    site = _installed_copy(tmp_path)
    before = _listing(site / "servotune")
    cache = tmp_path / "cache"
    _simulate(site, cache)
    _assert_cache_filled(cache)
    assert _listing(site / "servotune") == before


def test_a_read_only_package_simulates_with_everything_in_the_cache(tmp_path):
    """The package folder made read-only (as site-packages of another user or of the system
    is). chmod does not stop root (or a process with CAP_DAC_OVERRIDE) from writing; then the
    test is skipped and the test above, which compares the package's listing before and after,
    is the check."""
    site = _installed_copy(tmp_path)
    package = site / "servotune"
    folders = [package, *(p for p in package.rglob("*") if p.is_dir())]
    for path in [*package.rglob("*"), package]:
        mode = path.stat().st_mode
        path.chmod(mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
    try:
        probe = package / "probe"
        try:
            probe.write_text("x")
        except OSError:
            pass
        else:
            probe.unlink()
            pytest.skip("chmod does not stop this user from writing (root): see the test above")
        before = _listing(package)
        cache = tmp_path / "cache"
        _simulate(site, cache)
        _assert_cache_filled(cache)
        assert _listing(package) == before
    finally:
        for path in folders:
            path.chmod(path.stat().st_mode | stat.S_IWUSR)


def test_the_cache_root_is_servotune_cache_then_xdg_then_home(tmp_path, monkeypatch):
    monkeypatch.setenv("SERVOTUNE_CACHE", str(tmp_path / "mine"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_root() == tmp_path / "mine"
    monkeypatch.delenv("SERVOTUNE_CACHE")
    assert cache_root() == tmp_path / "xdg" / "servotune"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/xdg")  # ignored, as the XDG spec says
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cache_root() == tmp_path / "home" / ".cache" / "servotune"
    monkeypatch.setenv("SERVOTUNE_CACHE", "")
    assert cache_root() is None
    kept_nowhere = cache_folder("kernels")        # in a temporary folder of the process
    assert kept_nowhere.is_dir() and kept_nowhere.name == "kernels"
    assert cache_folder("kernels") == kept_nowhere


def test_a_cache_folder_that_cannot_be_made_is_a_clear_error(tmp_path, monkeypatch):
    # a regular file where a folder should be: mkdir fails for root too
    (tmp_path / "file").write_text("")
    bad = tmp_path / "file" / "cache"
    monkeypatch.setenv("SERVOTUNE_CACHE", str(bad))
    for make in (lambda: cache_folder("numba"), _kernel_directory, _clib.cache_folder,
                 lambda: cached_njit(lambda x: x)):
        with pytest.raises(CacheFolderError, match="SERVOTUNE_CACHE") as err:
            make()
        assert str(bad) in str(err.value)


def test_the_command_reports_an_unwritable_cache_in_one_line(tmp_path):
    (tmp_path / "file").write_text("")
    env = {**os.environ, "SERVOTUNE_CACHE": str(tmp_path / "file" / "cache")}
    done = subprocess.run(
        [sys.executable, "-c", "import sys; from servotune.cli import main; sys.exit(main())",
         "nlcompliance", str(MODELS / "paper_x_axis"), "--force-pp", "100"],
        env=env, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 1
    assert "Traceback" not in done.stderr
    (line,) = [x for x in done.stderr.splitlines() if "error" in x]
    assert "cannot write its cache folder" in line and "set SERVOTUNE_CACHE" in line


def test_no_module_of_the_package_asks_numba_to_cache_beside_its_source():
    # numba.njit(cache=True) in a module writes a __pycache__ next to it: cached_njit instead
    decorator = re.compile(r"^\s*@numba\.(n)?jit\([^)]*cache\s*=\s*True", re.MULTILINE)
    found = [str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py")
             if "__pycache__" not in p.parts and decorator.search(p.read_text())]
    assert found == []
