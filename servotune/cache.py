"""Where servotune keeps the code it generates and compiles: the user's cache, never the package.

Three kinds of files are made at run time and kept for the next run, each in a folder of
:func:`cache_root`:

* ``casadi``: the tuning kernels compiled to C as shared libraries
  (:mod:`servotune.tuning._clib`);
* ``kernels``: the time simulation's kernel modules, generated per friction law
  (:func:`servotune.simulate.integrator.chunk_kernel`), with numba's cache of them in its
  ``__pycache__``;
* ``numba``: numba's machine code of every function compiled with :func:`cached_njit`.

The cache root is ``$SERVOTUNE_CACHE`` if set, else ``$XDG_CACHE_HOME/servotune`` (when that is
an absolute path, as the XDG base directory specification asks), else ``~/.cache/servotune``.
``SERVOTUNE_CACHE=`` (empty) keeps nothing between runs: generated files go to a temporary
folder of the process, removed when it ends, and numba compiles in memory. Nothing is ever
written into the package's own folder: installed, it is site-packages, which may be read-only
and is shared between users. A cache folder that cannot be created or written is an error
(:class:`CacheFolderError`) that names the folder and the remedy, never a silent fall-back
into the package.

Why :func:`cached_njit` and not ``numba.njit(cache=True)``: numba keeps the cache of a function
in a ``__pycache__`` next to its source file (here, inside the package) and falls back to a
user-wide folder only when that one is not writable. Its own setting ``NUMBA_CACHE_DIR``
(``numba.config.CACHE_DIR``) moves the caches of every function of the process, and numba reads
it once per function, when the function is decorated. :func:`cached_njit` sets it only while
it decorates a servotune function and restores it at once, so servotune's functions are cached
here whatever the environment says, while other packages' functions keep the place their users
chose. This uses numba's documented setting, not its internal list of cache locators (whose
classes were renamed in numba 0.68), and changes no environment variable that other code or
child processes would see.

Examples
--------
>>> from servotune.cache import cache_folder, cache_root
>>> folder = cache_folder("kernels")
>>> folder.name, folder.is_dir(), cache_root() in folder.parents
('kernels', True, True)
"""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
from pathlib import Path

__all__ = ["CacheFolderError", "cache_root", "cache_folder", "writable_folder", "cached_njit"]


class CacheFolderError(OSError):
    """The cache folder cannot be created or written; the message names it and the remedy.

    Parameters
    ----------
    folder : str or pathlib.Path
        The folder.
    reason : str
        What went wrong (the operating system's words).
    """

    def __init__(self, folder, reason: str):
        self.folder = str(folder)
        super().__init__(f"servotune cannot write its cache folder {self.folder} ({reason}); "
                         "set SERVOTUNE_CACHE to a writable folder (or to an empty value to "
                         "keep nothing between runs)")


def cache_root() -> Path | None:
    """Return the root of servotune's cache (not created here).

    Returns
    -------
    pathlib.Path or None
        ``$SERVOTUNE_CACHE`` (made absolute), else ``$XDG_CACHE_HOME/servotune`` when that is
        an absolute path, else ``~/.cache/servotune``; None when ``SERVOTUNE_CACHE`` is empty
        (nothing is kept between runs).

    Raises
    ------
    CacheFolderError
        If neither variable is set and the home folder is unknown.
    """
    env = os.environ.get("SERVOTUNE_CACHE")
    if env is not None:
        return Path(env).expanduser().absolute() if env else None
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    if os.path.isabs(xdg):
        return Path(xdg) / "servotune"
    home = os.path.expanduser("~")
    if not os.path.isabs(home):
        raise CacheFolderError("~/.cache/servotune", "the home folder is unknown")
    return Path(home) / ".cache" / "servotune"


_PROCESS_FOLDER: list[Path] = []


def _process_folder() -> Path:
    """A temporary folder of this process (``SERVOTUNE_CACHE`` empty), removed when it ends."""
    if not _PROCESS_FOLDER:
        folder = Path(tempfile.mkdtemp(prefix="servotune-cache-"))
        atexit.register(shutil.rmtree, folder, True)
        _PROCESS_FOLDER.append(folder)
    return _PROCESS_FOLDER[0]


def writable_folder(folder) -> Path:
    """Return ``folder``, created if missing, after checking that a file can be written there.

    Parameters
    ----------
    folder : str or pathlib.Path
        The folder.

    Returns
    -------
    pathlib.Path
        The folder, absolute.

    Raises
    ------
    CacheFolderError
        If it cannot be created or a file cannot be written into it.
    """
    folder = Path(folder).expanduser().absolute()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        # a real write: access() says yes to root on a read-only file system
        tempfile.TemporaryFile(dir=folder).close()
    except OSError as err:
        raise CacheFolderError(folder, err.strerror or str(err)) from err
    return folder


def cache_folder(name: str) -> Path:
    """Return the folder ``name`` of servotune's cache, created if missing.

    Parameters
    ----------
    name : str
        The folder's name under :func:`cache_root` (``"casadi"``, ``"kernels"``, ``"numba"``).

    Returns
    -------
    pathlib.Path
        ``cache_root() / name``, or a folder in a temporary folder of the process (removed when
        it ends) when ``SERVOTUNE_CACHE`` is empty.

    Raises
    ------
    CacheFolderError
        If the folder cannot be created or written.
    """
    root = cache_root()
    return writable_folder((root if root is not None else _process_folder()) / name)


def cached_njit(function=None, **options):
    """Compile with numba, cached in servotune's cache instead of beside the source.

    ``numba.njit(cache=True, **options)`` with numba's cache in ``cache_folder("numba")``
    instead of a ``__pycache__`` in the package.

    Parameters
    ----------
    function : callable, optional
        The function to compile; without it, a decorator is returned
        (``@cached_njit(fastmath=False)`` as well as ``@cached_njit``).
    **options
        numba's ``njit`` options (``cache`` is set here).

    Returns
    -------
    numba dispatcher, or a decorator making one
        Compiled lazily on first call, as ``numba.njit`` does; cached on disk unless
        ``SERVOTUNE_CACHE`` is empty.

    Raises
    ------
    CacheFolderError
        If the cache folder cannot be created or written.
    TypeError
        If ``cache`` is among the options.

    Notes
    -----
    numba picks the cache folder of a function when it is decorated (the user-provided
    folder ``numba.config.CACHE_DIR`` first, then the source's ``__pycache__``, then a
    user-wide folder) and keeps it; so the setting is changed only around the decoration
    (see the module docstring for why this way).
    """
    if function is None:
        return lambda f: cached_njit(f, **options)
    import numba

    if "cache" in options:
        raise TypeError("cached_njit sets numba's cache option itself")
    if cache_root() is None:  # SERVOTUNE_CACHE empty: nothing kept between runs
        return numba.njit(cache=False, **options)(function)
    folder = cache_folder("numba")
    previous = numba.config.CACHE_DIR
    numba.config.CACHE_DIR = str(folder)
    try:
        return numba.njit(cache=True, **options)(function)
    finally:
        numba.config.CACHE_DIR = previous
