"""Results files: written atomically, never overwritten without being asked to.

A result is written to a temporary file in the target folder and moved into place only when it
is complete, so a crash never leaves a half-written file behind.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

__all__ = ["OutputExistsError", "check_writable", "write_atomically", "save_figure", "write_json"]


class OutputExistsError(FileExistsError):
    """An output file exists and overwriting it was not asked for."""


def check_writable(paths, force: bool = False) -> None:
    """Refuse, before any work is done, to overwrite existing files unless ``force``.

    Raises
    ------
    OutputExistsError
        Naming the first existing file and how to proceed.
    """
    for path in paths:
        path = Path(path)
        if path.exists() and not force:
            raise OutputExistsError(
                f"{path} exists; pass --force (force=True) to overwrite it, "
                "or choose another output folder")


def write_atomically(path, data: bytes | str, force: bool = False) -> Path:
    """Write ``data`` to ``path`` through a temporary file and an atomic rename."""
    path = Path(path)
    check_writable([path], force)
    path.parent.mkdir(parents=True, exist_ok=True)
    mode = "w" if isinstance(data, str) else "wb"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, mode) as handle:
            handle.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def save_figure(fig, path, force: bool = False, dpi: int = 150) -> Path:
    """Save a matplotlib figure atomically (format from the file suffix)."""
    import io

    path = Path(path)
    buffer = io.BytesIO()
    fig.savefig(buffer, format=path.suffix.lstrip(".") or "png", dpi=dpi)
    return write_atomically(path, buffer.getvalue(), force)


def write_json(path, obj, force: bool = False) -> Path:
    """Write a JSON results file atomically."""
    return write_atomically(path, json.dumps(obj, indent=2, sort_keys=False) + "\n", force)
