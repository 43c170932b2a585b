"""The compiler front end that keeps compiled tuning kernels (servotune/tuning/_ccache.py)."""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "servotune" / "tuning" / "_ccache.py"


@pytest.fixture
def counting_compiler(tmp_path):
    """A 'compiler' that writes its source's bytes, reversed, as the object and counts calls."""
    if shutil.which("sh") is None:
        pytest.skip("needs a POSIX shell")
    script = tmp_path / "fakecc"
    script.write_text('#!/bin/sh\n'
                      'echo x >> "$(dirname "$0")/calls"\n'
                      'while [ $# -gt 0 ]; do case "$1" in\n'
                      '  -o) out="$2"; shift 2;;\n'
                      '  *.c) src="$1"; shift;;\n'
                      '  *) shift;;\n'
                      'esac; done\n'
                      'rev "$src" > "$out"\n')
    script.chmod(script.stat().st_mode | stat.S_IEXEC)
    return script


def _compile(cache, compiler, source, out, *flags):
    return subprocess.run([sys.executable, "-S", str(SCRIPT), str(cache), str(compiler),
                           *flags, "-fPIC", "-c", str(source), "-o", str(out)],
                          capture_output=True, text=True, check=False)


def _calls(compiler):
    calls = compiler.parent / "calls"
    return len(calls.read_text().split()) if calls.exists() else 0


def test_the_second_compilation_of_the_same_source_is_a_copy(tmp_path, counting_compiler):
    cache = tmp_path / "cache"
    src = tmp_path / "a" / "jit_tmp1.c"
    src.parent.mkdir()
    src.write_text("int f(void) { return 1; }\n")
    first = _compile(cache, counting_compiler, src, tmp_path / "one.o", "-O1")
    assert first.returncode == 0, first.stderr
    # another temporary name, same bytes: taken from the cache, the compiler is not called
    other = tmp_path / "b" / "jit_tmp2.c"
    other.parent.mkdir()
    other.write_text(src.read_text())
    second = _compile(cache, counting_compiler, other, tmp_path / "two.o", "-O1")
    assert second.returncode == 0, second.stderr
    assert _calls(counting_compiler) == 1
    assert (tmp_path / "two.o").read_bytes() == (tmp_path / "one.o").read_bytes()
    # other flags or other source bytes compile anew
    _compile(cache, counting_compiler, other, tmp_path / "three.o", "-O2")
    other.write_text("int f(void) { return 2; }\n")
    _compile(cache, counting_compiler, other, tmp_path / "four.o", "-O1")
    assert _calls(counting_compiler) == 3
    assert len(list(cache.glob("*.o"))) == 3 and not list(cache.glob("*.tmp"))


def test_a_failed_compilation_is_not_kept(tmp_path):
    cache = tmp_path / "cache"
    src = tmp_path / "bad.c"
    src.write_text("int f(void) { return 1; }\n")
    result = _compile(cache, shutil.which("false") or "/bin/false", src, tmp_path / "bad.o")
    assert result.returncode != 0
    assert not cache.exists() or not list(cache.iterdir())


def test_the_tuning_kernels_compile_once_per_problem(tmp_path):
    # the same problem in two processes: the second compiles nothing (it only links the
    # objects the first left in the cache) and evaluates the kernels to the same numbers
    real = shutil.which("cc") or shutil.which("gcc")
    if real is None:
        pytest.skip("needs a C compiler")
    cc = tmp_path / "cc"
    cc.write_text('#!/bin/sh\n'
                  'case " $* " in *" -c "*) echo c >> "$(dirname "$0")/compiles";; esac\n'
                  f'exec "{real}" "$@"\n')
    cc.chmod(cc.stat().st_mode | stat.S_IEXEC)
    code = ("import numpy as np\n"
            "from axis_fixtures import PADS, small_axis, small_drive\n"
            "from servotune.tuning import Requirements, TuningProblem\n"
            "from servotune.tuning.nlp import Kernels\n"
            "p = TuningProblem(small_axis(), PADS, c=5e4, drive=small_drive(),\n"
            "                  free=('c', 'kp'), requirements=Requirements())\n"
            "k = Kernels(p, 1e-7, 1e-7)\n"
            "print(repr(float(k.band(np.zeros(2), np.ones(k.band.size1_in(1)))[0])))\n")
    env = {**os.environ, "SERVOTUNE_CACHE": str(tmp_path / "c"), "CC": str(cc),
           "SERVOTUNE_JIT": "1", "PYTHONPATH": str(Path(__file__).parent)}
    compiles = tmp_path / "compiles"
    outputs = []
    for expected in (True, False):
        before = len(compiles.read_text().split()) if compiles.exists() else 0
        r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                           text=True, check=False)
        assert r.returncode == 0, r.stderr
        after = len(compiles.read_text().split()) if compiles.exists() else 0
        assert (after > before) == expected
        outputs.append(r.stdout)
    assert outputs[0] == outputs[1]
    assert list((tmp_path / "c" / "casadi").glob("*.o"))
