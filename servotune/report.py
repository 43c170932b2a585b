"""Results files: written atomically, never overwritten without being asked to.

A result is written to a temporary file in the target folder and moved into place only when it
is complete, so a crash never leaves a half-written file behind.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

__all__ = [
    "OutputExistsError",
    "check_writable",
    "default_folder",
    "figure_metadata",
    "png_caption",
    "render_figures",
    "save_figure",
    "write_atomically",
    "write_json",
    "tuning_figures",
    "tuning_report_html",
    "write_html_report",
    "write_tuning_files",
    "html_page",
]


class OutputExistsError(FileExistsError):
    """An output file exists and overwriting it was not asked for."""


def check_writable(paths, force: bool = False) -> None:
    """Refuse, before any work is done, to overwrite existing files unless ``force``.

    Parameters
    ----------
    paths : iterable of str or os.PathLike
        The files about to be written.
    force : bool, optional
        Overwrite an existing file (default False).

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
    """Write ``data`` to ``path`` through a temporary file and an atomic rename.

    Missing parent folders are created; the file gets the permissions of an ordinary file
    (0666 less the umask).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    data : bytes or str
        The contents (str is written as text in the locale's encoding).
    force : bool, optional
        Overwrite an existing file (default False).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    OutputExistsError
        When the file exists and ``force`` is False.
    OSError
        When the folder or the file cannot be written.
    """
    path = Path(path)
    check_writable([path], force)
    path.parent.mkdir(parents=True, exist_ok=True)
    mode = "w" if isinstance(data, str) else "wb"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, mode) as handle:
            handle.write(data)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; results are ordinary files
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def save_figure(fig, path, force: bool = False, dpi: int = 150) -> Path:
    """Save a matplotlib figure atomically (format from the file suffix).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or os.PathLike
        The file; its suffix gives the format (PNG when it has none).
    force : bool, optional
        Overwrite an existing file (default False).
    dpi : int, optional
        Resolution of raster formats [dots per inch] (default 150).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    OutputExistsError
        When the file exists and ``force`` is False.
    OSError
        When the folder or the file cannot be written.
    """
    import io

    path = Path(path)
    buffer = io.BytesIO()
    fmt = path.suffix.lstrip(".") or "png"
    fig.savefig(buffer, format=fmt, dpi=dpi, metadata=figure_metadata(fig, fmt))
    return write_atomically(path, buffer.getvalue(), force)


def render_figures(figures, fmt: str = "png", dpi: int = 150, workers: int = 1) -> list[bytes]:
    """Render matplotlib figures to file bytes, in up to ``workers`` processes.

    Rendering (text layout, constrained layout, rasterising) takes a few tenths of a second per
    figure; with ``workers`` > 1 on a system with ``os.fork`` the figures are shared out
    between this process and forked children (which see the figures in their memory, render
    their share into a temporary file each and end without running any exit handler). A child
    that fails has its figures rendered here instead, so the bytes never depend on how they
    were made.

    Parameters
    ----------
    figures : sequence of matplotlib.figure.Figure
        The figures.
    fmt : str, optional
        File format (default ``"png"``).
    dpi : int, optional
        Resolution of raster formats [dots per inch] (default 150).
    workers : int, optional
        Largest number of processes (this one included; default 1: render here, in turn).

    Returns
    -------
    list of bytes
        The rendered files, in the order of ``figures``.
    """
    import io

    figures = list(figures)

    def render(fig) -> bytes:
        buffer = io.BytesIO()
        fig.savefig(buffer, format=fmt, dpi=dpi, metadata=figure_metadata(fig, fmt))
        return buffer.getvalue()

    n = min(int(workers), len(figures))
    if n < 2 or not hasattr(os, "fork"):
        return [render(f) for f in figures]
    # share out by size (axes x plotted points), the largest first, each to the lightest share
    def size(fig) -> int:
        return sum(1 + sum(len(line.get_xdata()) for line in ax.get_lines())
                   for ax in fig.axes)

    shares, load = [[] for _ in range(n)], [0] * n
    for i in sorted(range(len(figures)), key=lambda i: -size(figures[i])):
        k = load.index(min(load))
        shares[k].append(i)
        load[k] += size(figures[i]) + 5000  # a figure's fixed cost (layout, text)
    out: list[bytes | None] = [None] * len(figures)
    children = []
    with tempfile.TemporaryDirectory(prefix="servotune-figures-") as tmp:
        try:
            for k, share in enumerate(shares[1:], start=1):
                path = os.path.join(tmp, f"share{k}")
                try:
                    pid = os.fork()
                except OSError:  # no process to be had: this share is rendered here
                    continue
                if pid == 0:  # the child: render, write, leave at once
                    status = 1
                    try:
                        # own streams: a progress thread of the parent may have held the
                        # locks of the inherited ones at the fork (its output is not needed:
                        # a failed share is rendered again in the parent, errors and all)
                        sys.stdout = sys.stderr = open(os.devnull, "w")
                        with open(path, "wb") as f:
                            for i in share:
                                data = render(figures[i])
                                f.write(len(data).to_bytes(8, "little") + data)
                        status = 0
                    finally:
                        os._exit(status)
                children.append((pid, share, path))
            for i in shares[0]:
                out[i] = render(figures[i])
        finally:
            for pid, share, path in children:
                _, status = os.waitpid(pid, 0)
                if status == 0:
                    with open(path, "rb") as f:
                        for i in share:
                            length = int.from_bytes(f.read(8), "little")
                            out[i] = f.read(length)
    for i, data in enumerate(out):
        if data is None:  # a child that failed (or was interrupted): rendered here
            out[i] = render(figures[i])
    return out


def write_json(path, obj, force: bool = False) -> Path:
    """Write a JSON results file atomically.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    obj : object
        JSON-serialisable results (indented by 2; NaN and infinity written as JavaScript
        literals, as :func:`json.dumps` does by default).
    force : bool, optional
        Overwrite an existing file (default False).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    OutputExistsError
        When the file exists and ``force`` is False.
    OSError
        When the folder or the file cannot be written.
    TypeError
        When ``obj`` is not JSON-serialisable.
    """
    return write_atomically(path, json.dumps(obj, indent=2, sort_keys=False) + "\n", force)


def default_folder(name: str) -> Path:
    """Return ``out/<name>`` under the current folder.

    Parameters
    ----------
    name : str
        The folder's name.

    Returns
    -------
    pathlib.Path
        ``out/<name>`` (relative).
    """
    return Path("out") / name


def _regime_names(job) -> tuple[str | None, str | None]:
    """The regime models the loops (the reference model) and the lobes (the worst model) of
    the tuned design are of."""
    after = job.result.after
    if after is None:
        return None, None
    ref = after.models[after.reference].model.name if after.models else None
    worst = after.worst_model
    return ref, None if worst is None else worst.model.name


def tuning_figures(job) -> list[tuple[str, str, object]]:
    """Return the figures of a tuning job as (file name, title, matplotlib figure).

    Each figure carries its caption (:func:`servotune.plots.figure_caption`), made by the
    function that drew it from what it drew; :func:`render_figures` and :func:`save_figure`
    store it in the PNG (``Description``), and the report shows it under the figure.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).

    Returns
    -------
    list of (str, str, matplotlib.figure.Figure)
        (file name, title, figure) of each figure the job has data for.
    """
    from . import plots

    name = job.axis.name
    r = job.result
    reference, worst = _regime_names(job)
    out = []
    if job.compliance_after or job.compliance_before:
        not_drawn = []
        if r.after is not None:
            for mp0, mp1 in zip(r.before.models, r.after.models, strict=True):
                if not mp1.model.cutting or mp1.model.sample != "nominal":
                    continue
                not_drawn += [f"{tag}, {mp.model.name} (unstable)"
                              for tag, mp in (("before", mp0), ("after", mp1)) if not mp.stable]
        fig = plots.plot_regime_compliance(job.compliance_before, job.compliance_after,
                                           band=r.problem.requirements.band,
                                           not_drawn=not_drawn)
        _prefix_title(fig, name)
        out.append(("compliance.png", "Work-piece compliance per regime model", fig))
    if job.verdict is not None and job.verdict.regimes:
        linear = {}
        for c in list(job.compliance_before) + list(job.compliance_after):
            regime = c.label.split(", ", 1)[-1].split(":")[0]
            linear.setdefault(regime, []).append((f"linear {c.label}", c.omega, c.values))
        failing = [v.name for v in job.verdict.regimes if not v.holds]
        out.append(("nonlinear.png", "Nonlinear verification: the claim per regime against "
                    "the nonlinear axis" + (f" (does NOT hold: {', '.join(failing)})"
                                             if failing else ""),
                    plots.plot_regime_verification(
                        job.verdict.regimes, linear, tolerance=job.verdict.tolerance,
                        title=f"{name}: LuGre time simulation (sweep envelopes) and harmonic "
                              "balance against the linear claims")))
    loops, analyses, styles = {}, {}, {}
    for tag, ls, report in (("before", "--", job.loops_before), ("after", "-", job.loops_after)):
        if report is None:
            continue
        for loop, colour in (("velocity", "tab:blue"), ("position", "tab:red")):
            key = f"{loop}, {tag}"
            loops[key] = (report.omega, getattr(report, f"l_{loop}"))
            analyses[key] = getattr(report, loop)
            styles[key] = (colour, ls)
    if loops:
        shown = " and ".join(t for t, x in (("before (dashed)", job.loops_before),
                                            ("after (solid)", job.loops_after)) if x is not None)
        out.append(("bode.png", "Velocity and position loops (Bode, margins)"
                    + (f" in {reference}" if reference else ""), plots.plot_bode(
                        loops, analyses, title=f"{name}: loops {shown}", styles=styles,
                        regime=reference)))
    # the tuned design first: drawn solid with its unstable region shaded, as elsewhere
    lobes = [x for x in (job.lobes_after, job.lobes_before) if x is not None]
    if lobes:
        labels = [lab for lab, x in (("after", job.lobes_after), ("before", job.lobes_before))
                  if x is not None]
        depth = job.axis.requirements.depth_required
        fig = plots.plot_stability_lobes(
            lobes, required_depth=depth, labels=labels, depth_max=4 * lobes[0].b_crit,
            title=f"{name}: stability lobes (zero-order) of the worst regime model"
                  + (f" after: {worst}" if worst else ""))
        worst_before = (r.before.worst_model.model.name if job.lobes_before is not None
                        and r.before.worst_model is not None else None)
        which = [f"{tag}: {model}" for tag, model in (("after", worst if job.lobes_after
                                                               is not None else None),
                                                      ("before", worst_before)) if model]
        if which:
            plots.set_caption(fig, plots.figure_caption(fig) + " Each design's lobes are of "
                              "its worst regime model (largest compliance peak): "
                              + "; ".join(which) + ".")
        out.append(("lobes.png", "Stability lobes, " + " and ".join(labels), fig))
    if job.mode_peaks is not None:
        bounds = getattr(r.problem, "bounds", {}).get("c")
        out.append(("modes.png", "Several modes, one C (paper sec 5.2)",
                    plots.plot_mode_peaks(job.mode_peaks, bounds=bounds, axis_name=name)))
    if job.two_mass is not None:
        from .twomass import analyse_two_mass

        out.append(("two_mass.png", "Two-mass check: the paper's Fig 5 with the fixed points",
                    plots.plot_two_mass_compliance(analyse_two_mass(job.two_mass.system))))
    return out


def _prefix_title(fig, name: str) -> None:
    """Put the axis' name in front of the title of a one-axes figure."""
    ax = fig.axes[0]
    ax.set_title(f"{name}: {ax.get_title()}", fontsize=10)


def figure_metadata(fig, fmt: str = "png") -> dict | None:
    """Return the metadata a figure file carries: its caption, in a PNG as ``Description``.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    fmt : str, optional
        The file format (default ``"png"``).

    Returns
    -------
    dict or None
        ``{"Description": caption}`` for a PNG with a caption, else None.
    """
    from .captions import figure_caption

    text = figure_caption(fig)
    return {"Description": text} if text and fmt == "png" else None


def png_caption(data: bytes) -> str:
    """Return the caption stored in a PNG (its ``Description`` text; "" without one).

    Parameters
    ----------
    data : bytes
        The PNG file.

    Returns
    -------
    str
        The caption.
    """
    import io

    from PIL import Image

    try:
        with Image.open(io.BytesIO(data)) as image:
            return str(getattr(image, "text", {}).get("Description", ""))
    except (OSError, ValueError):
        return ""


def write_tuning_files(job, folder, force: bool = False) -> list[Path]:
    """Write the figures of a tuning job (PNG) into a folder.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).
    folder : str or os.PathLike
        The output folder (created when missing).
    force : bool, optional
        Overwrite an existing file (default False).

    Returns
    -------
    list of pathlib.Path
        The files written, in the order of :func:`tuning_figures`.

    Raises
    ------
    OutputExistsError
        When a file exists and ``force`` is False.
    OSError
        When the folder or the file cannot be written.
    """
    folder = Path(folder)
    written = []
    for file, _, fig in tuning_figures(job):
        written.append(save_figure(fig, folder / file, force))
    return written


def _fmt(value, fmt="{:.4g}"):
    import math

    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "&ndash;"
    return fmt.format(value)


def tuning_report_html(job, figures=None, base: Path | None = None) -> str:
    """Return a single self-contained HTML page of a tuning job.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).
    figures : sequence of (path, str), optional
        (PNG path, title) of figures already written (their bytes are embedded, their
        captions read from the PNGs' ``Description``, :func:`png_caption`); without them the
        figures are drawn here.
    base : pathlib.Path, optional
        Folder the paths shown are relative to.

    Returns
    -------
    str
        The HTML page (figures embedded as base64 PNG, each a ``<figure>`` with its title and
        its caption in a ``<figcaption>``).
    """
    import base64
    import datetime
    import html

    from . import summary

    r, axis = job.result, job.axis
    if figures is None:
        import io

        from .captions import figure_caption

        drawn = []
        for _, title, fig in tuning_figures(job):
            buffer = io.BytesIO()
            fig.savefig(buffer, format="png", dpi=110, metadata=figure_metadata(fig))
            drawn.append((buffer.getvalue(), title, figure_caption(fig)))
        figures = drawn
    else:
        figures = [(data, title, png_caption(data))
                   for data, title in ((Path(p).read_bytes(), t) for p, t in figures)]
    head, lines = summary.verdict_lines(job)
    status = (f"<p class='{'ok' if job.verified else 'bad'}'>{html.escape(head)}</p>"
              + ("<ul>" + "".join(f"<li>{html.escape(x)}</li>" for x in lines) + "</ul>"
                 if lines else ""))
    tables = "".join(summary.html_table(t) for t in (
        summary.inputs_table(job), summary.regimes_table(job), summary.baseline_table(job),
        summary.rounds_table(job),
        summary.design_table(job),
        summary.thrust_table(job), summary.realisation_table(job), summary.loops_table(job)))
    two = ""
    if job.two_mass is not None:
        t = job.two_mass
        two = (f"<h2>Optimiser against the fixed-point theory (sec 4.1)</h2>"
               f"<p>Two-mass layout B, M1 = {t.system.m1:g} kg, K = {t.system.k:g} N/m, "
               f"alpha = {t.system.alpha:g}: C tuned alone by the same optimiser.</p>"
               "<table><tr><th></th><th>closed form (Eq 4, 7)</th><th>optimiser</th>"
               "<th>relative difference</th></tr>"
               f"<tr><td>Copt [N s/m]</td><td>{t.c_opt_analytic:.6e}</td>"
               f"<td>{t.c_opt_tuned:.6e}</td><td>{t.c_relative_difference:+.1e}</td></tr>"
               f"<tr><td>peak g(alpha)/K [m/N]</td><td>{t.peak_analytic:.6e}</td>"
               f"<td>{t.peak_tuned:.6e}</td><td>{t.peak_relative_difference:+.1e}</td></tr>"
               "</table>")
    figs = "".join(
        f"<figure id='figure-{k}'><h3>Figure {k}: {html.escape(title)}</h3>"
        f"<img alt='{html.escape(title)}' "
        f"src='data:image/png;base64,{base64.b64encode(png).decode('ascii')}'/>"
        f"<figcaption><b>Figure {k}.</b> {html.escape(caption or title)}</figcaption></figure>"
        for k, (png, title, caption) in enumerate(figures, start=1))
    source = axis.path.name if base is None else _relative(axis.file, base)
    stamp = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    return html_page(f"servotune: {axis.name}", f"""
<h1>Feed-axis tuning: {html.escape(axis.name)}</h1>
<p>{html.escape(axis.description)}<br>Axis description: <code>{html.escape(str(source))}</code>;
written {stamp} by servotune. Method: Bianchi et al., "Analysis of vibration damping in machine
tools", Procedia CIRP 21 (2014), extended to operating regimes, a digital drive, the thrust
budget and a nonlinear verdict. SI units; frequencies in Hz.</p>
{status}
{tables}
{two}
<h2>Figures</h2>
{figs}
<p>Solver: {r.stats.starts} starts, {r.stats.iterations} IPOPT iterations,
{r.stats.exchange_rounds} grid-exchange rounds, {r.stats.models} regime models,
{r.stats.time_s:.1f} s.</p>
""")


#: the style of every page servotune writes
PAGE_CSS = """
body { font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222; }
table { border-collapse: collapse; margin: 0.5em 0; }
td, th { border: 1px solid #bbb; padding: 3px 9px; text-align: right; }
td:first-child { text-align: left; }
table { display: block; max-width: 100%; overflow-x: auto; }
img { max-width: 100%; height: auto; border: 1px solid #ddd; box-sizing: border-box; }
figure { margin: 1.5em 0; max-width: 100%; }
figcaption { font-size: 90%; color: #333; line-height: 1.35; margin-top: 0.3em; }
p, li, figcaption { overflow-wrap: anywhere; }
code { overflow-wrap: anywhere; }
.ok { color: #075; font-weight: bold; } .bad { color: #a00; font-weight: bold; }
ul.notes { font-size: 90%; color: #444; }
"""


def html_page(title: str, body: str) -> str:
    """Return a self-contained HTML page in servotune's style.

    Parameters
    ----------
    title : str
        The page title (escaped here).
    body : str
        The page body, HTML already (not escaped).

    Returns
    -------
    str
        The page, with its style sheet inline.
    """
    import html

    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>'
            f"{html.escape(title)}</title>\n<style>{PAGE_CSS}</style></head><body>{body}"
            "</body></html>\n")


def _relative(path: Path, base: Path) -> str:
    import os

    try:
        return os.path.relpath(Path(path).resolve(), Path(base).resolve())
    except ValueError:
        return Path(path).name


def write_html_report(job, folder, force: bool = False, figures=None) -> Path:
    """Write ``report.html`` of a tuning job into a folder (atomically).

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).
    folder : str or os.PathLike
        The output folder (created when missing).
    force : bool, optional
        Overwrite an existing file (default False).
    figures : sequence of (path, str), optional
        Figures already written, as for :func:`tuning_report_html`.

    Returns
    -------
    pathlib.Path
        The report's path.

    Raises
    ------
    OutputExistsError
        When the file exists and ``force`` is False.
    OSError
        When the folder or the file cannot be written.
    """
    folder = Path(folder)
    return write_atomically(folder / "report.html",
                            tuning_report_html(job, figures, base=folder), force)
