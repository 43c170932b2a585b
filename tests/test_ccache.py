"""The tuning kernels compiled to C as one cached shared library (servotune/tuning/_clib.py)."""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from axis_fixtures import PADS, small_axis, small_drive
from numpy.testing import assert_allclose

from servotune.tuning import Requirements, TuningProblem, _clib

TESTS = Path(__file__).parent


def _counting_cc(tmp_path):
    real = shutil.which("cc") or shutil.which("gcc")
    if real is None or shutil.which("sh") is None:
        pytest.skip("needs a C compiler and a POSIX shell")
    cc = tmp_path / "cc"
    cc.write_text('#!/bin/sh\n'
                  'echo c >> "$(dirname "$0")/compiles"\n'
                  f'exec "{real}" "$@"\n')
    cc.chmod(cc.stat().st_mode | stat.S_IEXEC)
    return cc


def _compiles(tmp_path) -> int:
    f = tmp_path / "compiles"
    return len(f.read_text().split()) if f.exists() else 0


def _problem():
    return TuningProblem(small_axis(), PADS, c=5e4, drive=small_drive(), free=("c", "kp"),
                         requirements=Requirements())


def test_the_tuning_kernels_compile_once_per_problem(tmp_path):
    # the same problem in two processes: the second compiles nothing (it loads the library
    # the first left in the cache) and evaluates the kernels to the same numbers
    cc = _counting_cc(tmp_path)
    code = ("import numpy as np\n"
            "from axis_fixtures import PADS, small_axis, small_drive\n"
            "from servotune.tuning import Requirements, TuningProblem\n"
            "from servotune.tuning.nlp import Kernels\n"
            "p = TuningProblem(small_axis(), PADS, c=5e4, drive=small_drive(),\n"
            "                  free=('c', 'kp'), requirements=Requirements())\n"
            "k = Kernels(p, 1e-7, 1e-7)\n"
            "print(k.band.class_name())\n"
            "print(repr(float(k.band(np.zeros(2), np.ones(k.band.size1_in(1)))[0])))\n")
    env = {**os.environ, "SERVOTUNE_CACHE": str(tmp_path / "c"), "CC": str(cc),
           "SERVOTUNE_JIT": "1", "PYTHONPATH": str(TESTS)}
    outputs = []
    for expected in (1, 0):
        before = _compiles(tmp_path)
        r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                           text=True, check=False)
        assert r.returncode == 0, r.stderr
        assert _compiles(tmp_path) - before == expected
        outputs.append(r.stdout)
    assert outputs[0] == outputs[1]
    assert outputs[0].startswith("External")
    assert len(list((tmp_path / "c" / "casadi").glob("kernels-*.so"))) == 1


def _kernel_values(kernels, problem):
    """The kernels, their Hessians and casadi's Jacobian of the mapped kernels (through the
    compiled derivative functions when compiled) at a few points."""
    rng = np.random.default_rng(3)
    nf = len(problem.free)
    out = []
    for name in ("band", "loop"):
        f, hess = getattr(kernels, name), getattr(kernels, f"{name}_hessian")
        data = rng.uniform(0.5, 1.5, (f.size1_in(1), 5))
        u = ca.MX.sym("u", nf)
        mapped = f.map(5)(u, data)
        jac = ca.Function("j", [u], [ca.jacobian(ca.vec(mapped), u)])
        for u0 in (np.zeros(nf), rng.normal(scale=0.3, size=nf)):
            out.append(np.array(f.map(5)(u0, data)))
            out.append(np.array(jac(u0)))
            lam = rng.normal(size=f.size1_out(0))
            out.append(np.array(hess(u0, data[:, 0], lam)))
    return out


def test_the_compiled_kernels_and_their_derivatives_equal_the_interpreted_ones(tmp_path,
                                                                              monkeypatch):
    from servotune.tuning.nlp import Kernels

    if _clib.compiler() is None:
        pytest.skip("needs a C compiler")
    monkeypatch.setenv("SERVOTUNE_CACHE", str(tmp_path / "c"))
    problem = _problem()
    compiled = Kernels(problem, 1e-7, 1e-7)
    assert compiled.band.class_name() == "External"
    monkeypatch.setenv("SERVOTUNE_JIT", "0")
    interpreted = Kernels(problem, 1e-7, 1e-7)
    assert interpreted.band.class_name() == "SXFunction"
    for got, want in zip(_kernel_values(compiled, problem), _kernel_values(interpreted, problem),
                         strict=True):
        assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


def test_a_failed_compilation_warns_and_leaves_the_kernels_interpreted(tmp_path, monkeypatch):
    false = shutil.which("false")
    if false is None:
        pytest.skip("needs /bin/false")
    monkeypatch.setenv("SERVOTUNE_CACHE", str(tmp_path / "c"))
    monkeypatch.setenv("CC", false)
    monkeypatch.setenv("SERVOTUNE_JIT", "1")
    x = ca.SX.sym("x")
    f = ca.Function("twice", [x], [2 * x])
    with pytest.warns(RuntimeWarning, match="interpreted"):
        (g,) = _clib.compile_functions([f], {})
    assert g is f
    assert not list((tmp_path / "c" / "casadi").iterdir())  # no half-written library


def test_the_cache_keeps_the_most_recently_used_libraries(tmp_path):
    for i in range(_clib.KEEP + 3):
        p = tmp_path / f"kernels-{i}.so"
        p.write_bytes(b"x")
        os.utime(p, (1000 + i, 1000 + i))
    _clib._prune(str(tmp_path))
    kept = sorted(int(p.stem.split("-")[1]) for p in tmp_path.glob("*.so"))
    assert kept == list(range(3, _clib.KEEP + 3))


def test_a_library_that_does_not_load_warns_and_leaves_the_kernels_interpreted(tmp_path):
    # a damaged (or foreign) file under the library's name in the cache, met by a new process
    if _clib.compiler() is None:
        pytest.skip("needs a C compiler")
    code = ("import warnings\n"
            "import casadi as ca\n"
            "from servotune.tuning import _clib\n"
            "x = ca.SX.sym('x')\n"
            "with warnings.catch_warnings(record=True) as caught:\n"
            "    warnings.simplefilter('always')\n"
            "    (g,) = _clib.compile_functions([ca.Function('twice', [x], [2 * x])], {})\n"
            "print(g.class_name(), float(g(3.0)))\n"
            "print([str(w.message) for w in caught])\n")
    env = {**os.environ, "SERVOTUNE_CACHE": str(tmp_path / "c"), "SERVOTUNE_JIT": "1"}

    def run():
        r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                           text=True, check=False)
        assert r.returncode == 0, r.stderr
        return r.stdout.splitlines()

    first = run()
    assert first[0] == "External 6.0" and first[1] == "[]"
    (library,) = (tmp_path / "c" / "casadi").glob("kernels-*.so")
    library.write_bytes(b"not a shared library")
    second = run()
    assert second[0] == "SXFunction 6.0" and "could not be loaded" in second[1]
