"""A C compiler front end that keeps each compiled object, by the hash of its source.

casadi compiles the tuning kernels to C on every run (about a second and a half for the bundled
axis); the generated source depends only on the problem, so a second run of the same axis can
take the objects of the first. casadi's shell JIT calls this file as its compiler::

    python -S _ccache.py CACHE_FOLDER COMPILER [compiler arguments] SOURCE.c -o OBJECT.o

The key is the SHA-256 of the compiler, its arguments (paths apart) and the source's bytes. A
found object is copied to OBJECT.o; otherwise COMPILER runs and its object is stored (written
to a temporary name, then renamed, so a concurrent run never reads half a file). The folder
keeps the ``KEEP`` most recently used objects. Only the standard library is used (the file
runs with ``python -S``, without the package).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile

#: Objects kept in the cache folder (the least recently used beyond are removed).
KEEP = 64


def _key(compiler: str, args: list[str], source: str) -> str:
    digest = hashlib.sha256()
    digest.update(compiler.encode())
    for a in args:
        if not (a.endswith((".c", ".o")) or os.sep in a):
            digest.update(b"\0" + a.encode())
    with open(source, "rb") as f:
        digest.update(b"\0\0" + f.read())
    return digest.hexdigest()


def _prune(folder: str) -> None:
    try:
        objects = [os.path.join(folder, n) for n in os.listdir(folder) if n.endswith(".o")]
        objects.sort(key=lambda p: os.stat(p).st_mtime, reverse=True)
        for p in objects[KEEP:]:
            os.remove(p)
    except OSError:
        pass


def main(argv: list[str]) -> int:
    """Compile (or copy from the cache) as the arguments say; returns the exit status."""
    folder, compiler, args = argv[0], argv[1], argv[2:]
    sources = [a for a in args if a.endswith(".c")]
    out = args[args.index("-o") + 1] if "-o" in args[:-1] else None
    if len(sources) != 1 or out is None:
        return subprocess.call([compiler, *args])
    try:
        os.makedirs(folder, exist_ok=True)
        cached = os.path.join(folder, _key(compiler, args, sources[0]) + ".o")
        if os.path.isfile(cached):
            shutil.copyfile(cached, out)
            os.utime(cached)
            return 0
    except OSError:
        return subprocess.call([compiler, *args])
    status = subprocess.call([compiler, *args])
    if status == 0:
        try:
            fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
            os.close(fd)
            shutil.copyfile(out, tmp)
            os.replace(tmp, cached)
            _prune(folder)
        except OSError:
            pass
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
