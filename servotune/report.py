"""Results files: written atomically, never overwritten without being asked to.

A result is written to a temporary file in the target folder and moved into place only when it
is complete, so a crash never leaves a half-written file behind.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

__all__ = [
    "OutputExistsError",
    "check_writable",
    "default_folder",
    "save_figure",
    "write_atomically",
    "write_json",
    "write_tuning_files",
]


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


def default_folder(name: str) -> Path:
    """``out/<name>`` under the current folder."""
    return Path("out") / name


def write_tuning_files(job, folder, force: bool = False) -> list[Path]:
    """The figures of a tuning job (see :func:`servotune.design.tune_axis`): compliance, Bode
    and lobes before and after, and the several-modes trade-off."""
    from . import plots

    folder = Path(folder)
    written = []
    if job.compliance_before is not None:
        curves = [(label, c.omega, c.values)
                  for label, c in (("before", job.compliance_before),
                                   ("after", job.compliance_after))]
        marks = [(f"{c.peak_compliance:.3g} m/N", c.peak_frequency, c.peak_compliance)
                 for c in (job.compliance_before, job.compliance_after)]
        written.append(save_figure(plots.plot_compliance(
            curves, title=f"{job.axis.name}: work-piece X compliance before and after tuning",
            marks=marks), folder / "compliance.png", force))
    if job.loops_before is not None:
        written.append(save_figure(job.loops_before.plot(f"{job.axis.name}: loops before"),
                                   folder / "bode_before.png", force))
        written.append(save_figure(job.loops_after.plot(f"{job.axis.name}: loops after"),
                                   folder / "bode_after.png", force))
    if job.lobes_before is not None:
        depth = job.axis.requirements.depth_required
        written.append(save_figure(plots.plot_stability_lobes(
            [job.lobes_before, job.lobes_after], required_depth=depth,
            labels=["before", "after"], depth_max=4 * job.lobes_after.b_crit,
            title=f"{job.axis.name}: stability lobes before and after tuning"),
            folder / "lobes.png", force))
    if job.mode_peaks is not None:
        written.append(save_figure(job.mode_peaks.plot(), folder / "modes.png", force))
    return written
