"""What a person reads of a study: a summary, figures against each varied field, one page.

The summary counts the samples (run, failed, verified; shares over the samples run), gives
the spread (min, median, max) of every result column, and lists the failures with their
reasons. The figures put the realised compliance peak (the nonlinear one when the study
verified, else the linear claim) and the chatter limit against each varied field, and the
spread of the tuned gains.
"""

from __future__ import annotations

import html
import math
from dataclasses import dataclass, field

import numpy as np

from .tasks import INPUT_PREFIX

__all__ = ["StudySummary", "summarise", "summary_figures", "summary_html"]

#: result columns summarised, with their labels (SI)
RESULTS = (("nonlinear_peak_m_per_n", "nonlinear compliance peak [m/N]"),
           ("peak_compliance_m_per_n", "claimed compliance peak [m/N]"),
           ("b_crit_m", "chatter limit b_crit [m]"),
           ("c", "C [N s/m]"), ("kv", "Kv [1/s]"), ("kp", "Kp [N m s/rad]"), ("ti", "Ti [s]"))


@dataclass(frozen=True)
class StudySummary:
    """Counts and spreads of a study's rows."""

    samples: int
    done: int
    failed: int
    verified: int | None            # None when the study did not verify
    spreads: dict = field(default_factory=dict)   # column -> {min, median, max, count}
    failures: tuple = ()            # (sample_id, error) of the failed samples
    inputs: tuple = ()              # the varied fields (dotted paths)
    unchecked: int = 0              # done samples whose design fails its linear checks

    @property
    def finished(self) -> int:
        """Samples run to their end, done or failed (fewer than ``samples`` while the study is
        interrupted or still running)."""
        return self.done + self.failed

    @property
    def verified_share(self) -> float | None:
        """Verified over the samples run (done or failed) [-]; None when the study did not
        verify or none has run."""
        if self.verified is None or not self.finished:
            return None
        return self.verified / self.finished

    def counts(self) -> str:
        """Return the counts in words, e.g. ``"2 of 2 samples run: 1 of 2 verified (50 %),
        1 failed"``; shares are over the samples run, failures counted beside.

        Returns
        -------
        str
            The line the command prints and the page shows.

        Examples
        --------
        >>> StudySummary(samples=3, done=1, failed=1, verified=1).counts()
        '2 of 3 samples run (1 not run): 1 of 2 verified (50 %), 1 failed'
        >>> StudySummary(samples=2, done=2, failed=0, verified=None).counts()
        '2 of 2 samples run: 2 done, 0 failed'
        >>> StudySummary(samples=2, done=2, failed=0, verified=None, unchecked=2).counts()
        '2 of 2 samples run: 2 done (2 with a design that fails its linear checks), 0 failed'
        """
        n = self.finished
        text = f"{n} of {self.samples} samples run"
        if n < self.samples:
            text += f" ({self.samples - n} not run)"
        if self.verified is None:
            bad = (f" ({self.unchecked} with a design that fails its linear checks)"
                   if self.unchecked else "")
            return text + f": {self.done} done{bad}, {self.failed} failed"
        text += f": {self.verified} of {n} verified"
        if n:
            text += f" ({100.0 * self.verified / n:.0f} %)"
        if self.done > self.verified:
            text += f", {self.done - self.verified} not verified"
        return text + f", {self.failed} failed"

    def to_dict(self) -> dict:
        """Return the summary as a JSON-ready dictionary.

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        return {"samples": self.samples, "finished": self.finished, "done": self.done,
                "failed": self.failed, "linear_checks_failed": self.unchecked,
                "verified": self.verified,
                "verified_share": self.verified_share, "counts": self.counts(),
                "spreads": self.spreads,
                "failures": [{"sample_id": i, "error": e} for i, e in self.failures],
                "inputs": list(self.inputs)}


def _numbers(rows, key):
    out = []
    for r in rows:
        v = r.get(key)
        if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v):
            out.append(float(v))
    return np.array(out)


def summarise(rows: list[dict], samples: int) -> StudySummary:
    """Return the summary of a study's rows.

    Parameters
    ----------
    rows : list of dict
        The rows (:func:`~servotune.study.runner.read_rows`).
    samples : int
        How many samples the study has (finished or not).

    Returns
    -------
    StudySummary
        Counts of done, failed and verified rows, the min, median and max of each result
        column over the done rows, the failures and the varied fields.
    """
    ok = [r for r in rows if r.get("status") == "done"]
    failed = [r for r in rows if r.get("status") == "failed"]
    verified = None
    if any("verified" in r and r["verified"] is not None for r in ok):
        verified = sum(1 for r in ok if r.get("verified"))
    spreads = {}
    for key, _ in RESULTS:
        x = _numbers(ok, key)
        if x.size:
            spreads[key] = {"min": float(x.min()), "median": float(np.median(x)),
                            "max": float(x.max()), "count": int(x.size)}
    inputs = tuple(dict.fromkeys(k[len(INPUT_PREFIX):] for r in rows for k in r
                                 if k.startswith(INPUT_PREFIX)))
    unchecked = sum(1 for r in ok if r.get("linear_ok") is False)
    return StudySummary(samples, len(ok), len(failed), verified, spreads,
                        tuple((r["sample_id"], r.get("error")) for r in failed), inputs,
                        unchecked)


def _primary(rows):
    if any(r.get("nonlinear_peak_m_per_n") is not None for r in rows):
        return "nonlinear_peak_m_per_n", "realised (nonlinear) compliance peak [m/N]"
    return "peak_compliance_m_per_n", "claimed compliance peak [m/N]"


def summary_figures(rows: list[dict], name: str, tuned: bool = True):
    """Return the figures of a study.

    The realised peak and b_crit against each varied numeric field (verified samples in
    green, others in red), and the spread of the tuned design.

    Parameters
    ----------
    rows : list of dict
        The rows (:func:`~servotune.study.runner.read_rows`); only the done ones are drawn.
    name : str
        The study's name, in the titles.
    tuned : bool, optional
        Whether the study tuned (then the histograms of C, Kv, Kp, Ti are drawn).

    Returns
    -------
    list of (str, str, matplotlib.figure.Figure)
        (file name, title, figure), pyplot figures the caller closes; empty when there is
        nothing to draw.
    """
    import matplotlib.pyplot as plt

    ok = [r for r in rows if r.get("status") == "done"]
    out = []
    primary, label = _primary(ok)
    inputs = [k for k in dict.fromkeys(k for r in ok for k in r if k.startswith(INPUT_PREFIX))
              if _numbers(ok, k).size == len(ok) and ok]
    shown = [(primary, label)] + ([("b_crit_m", "chatter limit b_crit [m]")]
                                  if _numbers(ok, "b_crit_m").size else [])
    if inputs and _numbers(ok, primary).size:
        fig, axes = plt.subplots(len(shown), len(inputs), squeeze=False,
                                 figsize=(4.2 * len(inputs), 3.4 * len(shown)))
        colour = ["#075" if r.get("verified", True) else "#a00" for r in ok]
        for j, key in enumerate(inputs):
            x = np.array([r[key] for r in ok], float)
            for i, (col, lab) in enumerate(shown):
                y = np.array([np.nan if r.get(col) is None else r[col] for r in ok], float)
                ax = axes[i][j]
                ax.scatter(x, y, s=14, c=colour)
                ax.set_xlabel(key[len(INPUT_PREFIX):])
                ax.set_ylabel(lab)
                ax.grid(True, alpha=0.3)
        fig.suptitle(f"{name}: results against the varied fields"
                     + (" (green verified, red not)" if any("verified" in r for r in ok)
                        else ""))
        fig.tight_layout()
        out.append(("study_results.png", "Results against each varied field", fig))
    gains = [(k, lab) for k, lab in RESULTS[3:] if _numbers(ok, k).size > 1]
    if tuned and gains:
        fig, axes = plt.subplots(1, len(gains), squeeze=False, figsize=(3.6 * len(gains), 3.2))
        for ax, (k, lab) in zip(axes[0], gains, strict=True):
            ax.hist(_numbers(ok, k), bins=min(30, max(5, len(ok) // 5)), color="#357")
            ax.set_xlabel(lab)
            ax.set_ylabel("samples")
        fig.suptitle(f"{name}: spread of the design")
        fig.tight_layout()
        out.append(("study_design.png", "Spread of the design", fig))
    return out


def summary_html(study, run, summary: StudySummary, figures) -> str:
    """Return one self-contained page of a study.

    The study, the counts, the spreads, the first 50 failures and the figures.

    Parameters
    ----------
    study : Study
        The study.
    run : StudyRun
        The run (counts, scheduler, wall time).
    summary : StudySummary
        The summary (:func:`summarise`).
    figures : sequence of (bytes, str)
        (PNG bytes, title) of the figures, embedded.

    Returns
    -------
    str
        The HTML page.
    """
    import base64

    esc = html.escape
    head = summary.counts()
    varied = "".join(
        f"<tr><td>{esc(v.path)}</td><td>"
        + esc(f"{v.distribution} {dict(v.parameters)}" if v.random else str(list(v.values)))
        + f"</td><td>{'factor on the axis&#39; own value' if v.relative else 'value'}"
        "</td></tr>"
        for v in study.variations)
    labels = dict(RESULTS)
    spreads = "".join(
        f"<tr><td>{esc(labels[k])}</td><td>{s['min']:.4g}</td><td>{s['median']:.4g}</td>"
        f"<td>{s['max']:.4g}</td><td>{s['count']}</td></tr>"
        for k, s in summary.spreads.items())
    def short(text, n=240):
        text = str(text)
        return text if len(text) <= n else text[:n] + " ..."

    failures = "".join(f"<tr><td>{i}</td><td style='text-align: left'>{esc(short(e))}</td></tr>"
                       for i, e in summary.failures[:50])
    figs = "".join(
        f"<h3>{esc(title)}</h3><img alt='{esc(title)}' "
        f"src='data:image/png;base64,{base64.b64encode(png).decode('ascii')}'/>"
        for png, title in figures)
    from ..report import html_page

    return html_page(f"servotune study: {study.name}", f"""
<h1>Study: {esc(study.name)}</h1>
<p>{esc(head)}. Axes: {esc(", ".join(a.rsplit("/", 1)[-1] for a in study.axes))};
computed per sample: {esc(", ".join(study.compute))}; {len(study.sample_list())} samples
(seed {study.seed}). This run: {run.computed} computed, {run.skipped} already done, on
{esc(run.scheduler)}, {run.wall_time:.1f} s ({run.throughput:.3g} samples/s). SI units.</p>
<h2>What varies</h2>
<table><tr><th>field</th><th>how</th><th>meaning</th></tr>{varied}</table>
<h2>Results</h2>
<table><tr><th></th><th>min</th><th>median</th><th>max</th><th>samples</th></tr>{spreads}</table>
<h2>Figures</h2>
{figs}
{"<h2>Failed samples</h2><p>The first 50; the whole reasons are in results.parquet (column "
 "error).</p><table><tr><th>sample</th><th>reason</th></tr>" + failures + "</table>"
 if failures else ""}
""")


def write_summary(study, run, plots: bool = True) -> tuple[StudySummary, list]:
    """Write ``summary.html`` and the figures into the run's folder, each file atomically.

    Parameters
    ----------
    study : Study
        The study.
    run : StudyRun
        The run; its folder receives the files.
    plots : bool, optional
        Write the figures as PNG too (default True).

    Returns
    -------
    summary : StudySummary
        The summary of the study's finished rows.
    files : list of pathlib.Path
        The files written, ``summary.html`` last.
    """
    import io

    from .runner import _write_atomically, read_rows

    keys = {s.key for s in study.sample_list()}
    rows = read_rows(run.folder, keys)
    summary = summarise(rows, run.samples)
    files, figures = [], []
    if plots and rows:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        for name, title, fig in summary_figures(rows, study.name, "tune" in study.compute):
            buffer = io.BytesIO()
            fig.savefig(buffer, format="png", dpi=110)
            plt.close(fig)
            png = buffer.getvalue()
            path = run.folder / name
            _write_atomically(path, lambda p, png=png: p.write_bytes(png))
            files.append(path)
            figures.append((png, title))
    page = summary_html(study, run, summary, figures)
    path = run.folder / "summary.html"
    _write_atomically(path, lambda p: p.write_text(page))
    files.append(path)
    return summary, files
