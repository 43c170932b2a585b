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
    "tuning_report_html",
    "write_html_report",
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
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; results are ordinary files
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


def _figure_png(fig) -> str:
    import base64
    import io

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def _fmt(value, fmt="{:.4g}"):
    import math

    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "&ndash;"
    return fmt.format(value)


def tuning_report_html(job) -> str:
    """A single self-contained HTML page of a tuning job (figures embedded as PNG data)."""
    import datetime
    import html

    from . import plots
    from .drive import kv_to_m_per_min_per_mm

    r, axis = job.result, job.axis
    d0, d1 = r.initial, r.design
    rows = [("Guide-way damping C [N s/m] (axis total)", d0.c, d1.c, "{:.4g}")]
    if d0.kv is not None:
        rows += [("Kv [1/s]", d0.kv, d1.kv, "{:.4g}"),
                 ("Kv [(m/min)/mm]", kv_to_m_per_min_per_mm(d0.kv),
                  kv_to_m_per_min_per_mm(d1.kv), "{:.3g}"),
                 ("Velocity loop Kp [N m s/rad]", d0.kp, d1.kp, "{:.4g}"),
                 ("Velocity loop Ti [s]", d0.ti, d1.ti, "{:.4g}")]
    after = r.after
    rows += [("Peak work-piece compliance [m/N]", r.before.peak_compliance,
              after and after.peak_compliance, "{:.4g}"),
             ("&nbsp;&nbsp;at [Hz]", r.before.peak_frequency / 6.283185307179586,
              after and after.peak_frequency / 6.283185307179586, "{:.2f}")]
    if r.before.b_crit is not None:
        rows.append(("Chatter limit b_crit [mm]", r.before.b_crit * 1e3,
                     after and after.b_crit * 1e3, "{:.3g}"))
    for loop in ("velocity", "position"):
        a0 = getattr(r.before, loop)
        a1 = after and getattr(after, loop)
        if a0 is None:
            continue
        rows += [(f"{loop.capitalize()} loop Ms", a0.ms, a1 and a1.ms, "{:.3f}"),
                 ("&nbsp;&nbsp;phase margin [deg]", a0.phase_margin_deg,
                  a1 and a1.phase_margin_deg, "{:.1f}"),
                 ("&nbsp;&nbsp;gain margin [dB]", a0.gain_margin_db, a1 and a1.gain_margin_db,
                  "{:.1f}"),
                 ("&nbsp;&nbsp;bandwidth [Hz]", a0.bandwidth_hz, a1 and a1.bandwidth_hz,
                  "{:.2f}")]
    table = "".join(f"<tr><td>{n}</td><td>{_fmt(b, f)}</td><td>{_fmt(a, f)}</td></tr>"
                    for n, b, a, f in rows)
    status = ("<p class='ok'>VERIFIED: the constraints hold on dense frequency grids the "
              "optimiser never saw (python-control, interconnected state space), and the "
              "closed loop is stable.</p>" if r.success else
              "<p class='bad'>NOT VERIFIED: " + html.escape("; ".join(r.reasons)) + "</p>")
    figures = []
    if job.compliance_before is not None:
        figures.append(("Work-piece compliance before and after", plots.plot_compliance(
            [("before", job.compliance_before.omega, job.compliance_before.values),
             ("after", job.compliance_after.omega, job.compliance_after.values)],
            title=f"{axis.name}: work-piece X compliance (closed loop, viscous pads)")))
    if job.loops_before is not None:
        figures.append(("Loops before (Bode, margins)", job.loops_before.plot(
            f"{axis.name}: loops before")))
        figures.append(("Loops after (Bode, margins)", job.loops_after.plot(
            f"{axis.name}: loops after")))
    if job.lobes_before is not None:
        figures.append(("Stability lobes before and after", plots.plot_stability_lobes(
            [job.lobes_before, job.lobes_after], labels=["before", "after"],
            required_depth=axis.requirements.depth_required,
            depth_max=4 * job.lobes_after.b_crit,
            title=f"{axis.name}: stability lobes (work-piece compliance, zero-order)")))
    if job.mode_peaks is not None:
        figures.append(("Several modes, one C (paper sec 5.2)", job.mode_peaks.plot()))
    two = ""
    if job.two_mass is not None:
        t = job.two_mass
        analysis = __import__("servotune.twomass", fromlist=["x"]).analyse_two_mass(t.system)
        figures.append(("Two-mass check: the paper's Fig 5 with the fixed points",
                        plots.plot_two_mass_compliance(analysis)))
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
    nonlinear = ""
    if job.nonlinear is not None:
        nl = job.nonlinear
        body = "".join(
            f"<tr><td>{s['force_pp_n']:g}</td><td>{s['resonance_hz']:.1f}</td>"
            f"<td>{s['peak_m_per_n']:.3g}</td><td>{s['pad_amplitude_m'] * 1e6:.3g}</td>"
            + "".join(f"<td>{s[k]['resonance_hz'] if k == 'describing' else nl['linear'][k]['resonance_hz']:.1f} Hz, "  # noqa: E501
                      f"{(s[k] if k == 'describing' else nl['linear'][k])['peak_m_per_n']:.3g}"
                      f" {'&#10003;' if s['agrees_' + k] else '&#10007;'}</td>"
                      for k in ("locked", "presliding", "viscous", "describing"))
            + "</tr>" for s in nl["sweeps"])
        nonlinear = (
            "<h2>Nonlinear verification (LuGre pads, standing still)</h2>"
            "<p>Sine sweeps 10&ndash;100 Hz of the work-piece force with the full nonlinear "
            "axis (LuGre friction at every pad, the design's C as the viscous part sigma2, the "
            "tuned loops), against the linear predictions; &#10003; = resonance within "
            f"{nl['freq_tol'] * 100:.0f}% and peak within {nl['peak_tol'] * 100:.0f}%.</p>"
            "<table><tr><th>force p-p [N]</th><th>resonance [Hz]</th><th>peak [m/N]</th>"
            "<th>pad amplitude [&mu;m]</th><th>locked pads</th><th>presliding (stiction)</th>"
            "<th>viscous (tuning model)</th><th>describing function</th></tr>"
            f"{body}</table>"
            "<p>Standing still, stiction holds the pads: the guide-way C of the tuning acts "
            "once the axis slides; at rest the presliding and describing-function models are "
            "the ones to trust.</p>")
    figs = "".join(f"<h3>{html.escape(title)}</h3><img alt='{html.escape(title)}' "
                   f"src='data:image/png;base64,{_figure_png(fig)}'/>" for title, fig in figures)
    active = html.escape("; ".join(r.active)) or "none"
    stamp = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>servotune: {html.escape(axis.name)}</title>
<style>
body {{ font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
td, th {{ border: 1px solid #bbb; padding: 4px 10px; text-align: right; }}
td:first-child {{ text-align: left; }}
img {{ max-width: 100%; border: 1px solid #ddd; margin-bottom: 1em; }}
.ok {{ color: #075; font-weight: bold; }} .bad {{ color: #a00; font-weight: bold; }}
</style></head><body>
<h1>Feed-axis tuning: {html.escape(axis.name)}</h1>
<p>{html.escape(axis.description)}<br>Axis description: <code>{html.escape(str(axis.file))}</code>;
written {stamp} by servotune. Method: Bianchi et al., "Analysis of vibration damping in machine
tools", Procedia CIRP 21 (2014). SI units; frequencies in Hz.</p>
{status}
<h2>Design</h2>
<p>Free variables: {", ".join(r.problem.free)}; objective: work-piece compliance peak over
{r.problem.requirements.band[0] / 6.283185307179586:.3g}&ndash;{r.problem.requirements.band[1] / 6.283185307179586:.3g} Hz
(weight {r.problem.weights[0]:g}) and chatter limit (weight {r.problem.weights[1]:g});
Ms limits: velocity {r.problem.requirements.ms_limit("velocity"):.3f}, position
{r.problem.requirements.ms_limit("position"):.3f}. Active at the optimum: {active}.
Solver: {r.stats["starts"]} starts, {r.stats["iterations"]} IPOPT iterations,
{r.stats["exchange_rounds"]} grid-exchange rounds, {r.stats["time_s"]:.1f} s.</p>
<table><tr><th></th><th>before</th><th>after</th></tr>{table}</table>
{two}
{nonlinear}
<h2>Figures</h2>
{figs}
</body></html>
"""


def write_html_report(job, folder, force: bool = False) -> Path:
    """Write ``report.html`` of a tuning job into ``folder`` (atomically)."""
    return write_atomically(Path(folder) / "report.html", tuning_report_html(job), force)
