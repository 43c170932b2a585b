"""Figures of a tuning job's regimes: the compliance per regime model, the nonlinear
verification per regime with the evidence that breaks a claim, and each mode's peak against
the guide-way damping C (sec 5.2). Each figure carries its caption (:mod:`servotune.captions`).
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from .captions import set_caption, style_key
from .units import HZ_PER_RAD_S

__all__ = ["EVIDENCE_IN_LEGEND", "SPIKE_FACTOR", "plot_mode_peaks", "plot_regime_compliance",
           "plot_regime_verification"]


#: a point of a mode's track this many times both its neighbours is drawn on its own
SPIKE_FACTOR = 2.0


def plot_mode_peaks(mode_peaks, bounds=None, axis_name: str | None = None) -> Figure:
    """Draw the compliance peak of each work-piece mode against the guide-way damping C.

    Different modes ask for different optimal C (sec 5.2); the chosen C is marked. Each
    track's smallest peak is marked as its best C only where it lies inside the grid; at an
    end of the grid (a bound of C) or where the track ends (the mode turns over-damped or
    jumps) it is said so instead. A point more than :data:`SPIKE_FACTOR` times both its
    neighbours is drawn as a cross, not joined to them: the grid of C does not resolve it
    (near-coincident poles, whose terms grow and cancel in the sum, or a track stepping onto
    another pole for one point). Where two tracks follow the same pole (the nearest pole is
    followed, so one mode is lost there) the later one is drawn once.

    Parameters
    ----------
    mode_peaks : servotune.design.ModePeaks
        From :func:`servotune.design.mode_peaks_vs_damping`.
    bounds : (float, float), optional
        The bounds of C [N s/m] the grid spans (default: the grid's ends), named in the
        labels.
    axis_name : str, optional
        The axis, named in the title and the caption.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (its caption: :func:`figure_caption`).
    """
    fig = Figure(figsize=(8.0, 5.0), layout="constrained")
    ax = fig.add_subplot()
    c = np.asarray(mode_peaks.c_values, dtype=float)
    peaks = np.asarray(mode_peaks.peaks, dtype=float)
    lo, hi = (c[0], c[-1]) if bounds is None else (float(bounds[0]), float(bounds[1]))
    bound_word = "bound" if bounds is not None else "end of the grid"
    i = int(np.argmin(np.abs(np.log(c / mode_peaks.c_chosen))))
    notes, spikes_total = [], 0
    for m in range(peaks.shape[0]):
        f = mode_peaks.frequencies[m, i] * HZ_PER_RAD_S
        row = peaks[m].copy()
        finite = np.isfinite(row)
        # a track that follows the same pole as an earlier one: drawn once, said so
        same = np.zeros_like(finite)       # on an earlier track's pole: drawn there
        shared = np.zeros_like(finite)     # on any other track's pole
        merged_with = None
        for k in range(peaks.shape[0]):
            if k == m:
                continue
            eq = finite & np.isfinite(peaks[k]) & np.isclose(row, peaks[k], rtol=1e-9, atol=0.0)
            if eq.any():
                shared |= eq
                merged_with = mode_peaks.frequencies[k, i] * HZ_PER_RAD_S
                if k < m:
                    same |= eq
        spike = np.zeros_like(finite)
        for j in range(1, len(row) - 1):
            if finite[j - 1] and finite[j] and finite[j + 1]:
                spike[j] = row[j] > SPIKE_FACTOR * max(row[j - 1], row[j + 1])
        spikes_total += int(spike.sum())
        track = np.where(spike | ~finite, np.nan, row)
        shown = np.where(same, np.nan, track)
        if same.any():   # keep the joining point so that the track reaches the merge
            first = int(np.argmax(same))
            shown[first] = track[first]
        ok = np.isfinite(track)
        if not ok.any():
            continue
        j = int(np.nanargmin(track))
        cb = c[j]
        last = int(np.nonzero(ok)[0][-1])
        first_ok = int(np.nonzero(ok)[0][0])
        if j == len(c) - 1 or (np.isclose(cb, hi, rtol=1e-9, atol=0.0) and j == last):
            where = f"falls up to the upper {bound_word} C = {hi:.3g} N s/m (no minimum inside)"
            marker = ">"
        elif j == 0 or (np.isclose(cb, lo, rtol=1e-9, atol=0.0) and j == first_ok):
            where = f"rises from the lower {bound_word} C = {lo:.3g} N s/m (no minimum inside)"
            marker = "<"
        elif shared[j] and not shared[j - 1]:
            where = (f"smallest where its track meets the {merged_with:.0f} Hz one, "
                     f"C = {cb:.2g} N s/m")
            marker = "s"
        elif j == last:
            where = f"smallest where its track ends (the mode is lost beyond), C = {cb:.2g} N s/m"
            marker = "s"
        else:
            where = f"best C = {cb:.2g} N s/m"
            marker = "o"
        (line,) = ax.loglog(c, shown, lw=1.6, label=f"mode at {f:.0f} Hz (at the chosen C): "
                                                      f"{where}")
        ax.plot([cb], [track[j]], marker, color=line.get_color(), ms=7,
                label=f"_{f:.0f} Hz: {where}")
        if spike.any():
            ax.plot(c[spike], row[spike], "x", color=line.get_color(), ms=7, mew=1.6,
                    label=f"{f:.0f} Hz mode: near-coincident poles ({int(spike.sum())} point"
                          f"{'s' if spike.sum() > 1 else ''})")
        notes.append(f"the {f:.0f} Hz mode: {where}")
        if same.any():
            notes.append(f"from C = {c[np.argmax(same)]:.2g} N s/m the {f:.0f} Hz track "
                         f"follows the same pole as the {merged_with:.0f} Hz one (the nearest "
                         "pole is followed, so one of the two modes is lost there; drawn once)")
    chosen = mode_peaks.c_chosen
    at_bound = (" (at the lower bound)" if np.isclose(chosen, lo, rtol=1e-6, atol=0.0) else
                " (at the upper bound)" if np.isclose(chosen, hi, rtol=1e-6, atol=0.0) else "")
    if bounds is None:
        at_bound = ""
    ax.axvline(chosen, color="k", ls="--", lw=1.0,
               label=f"chosen C = {chosen:.3g} N s/m{at_bound}")
    ax.set_xlabel("guide-way damping C [N s/m]")
    ax.set_ylabel("peak of the mode's compliance term [m/N]")
    head = "Several modes, one C: each mode's compliance peak against C (sec 5.2)"
    ax.set_title(head if axis_name is None else f"{axis_name}: {head}", fontsize=10)
    ax.grid(True, which="both", alpha=0.4)
    ax.legend(fontsize=7)
    text = [f"{'The axis ' + axis_name + ': e' if axis_name else 'E'}ach closed-loop mode's "
            f"own compliance peak |R|/|Re lambda| against the guide-way damping C, on "
            f"{len(c)} values of C from {c[0]:.3g} to {c[-1]:.3g} N s/m (the pads as viscous "
            f"dampers C, the tuned design's gains); solid: the tracks; dashed vertical: the "
            f"chosen C {chosen:.3g} N s/m{at_bound}; dots: a minimum inside the grid, squares: the "
            "smallest value where a track ends or meets another, triangles: the smallest value at "
            "a bound."]
    text += [n[0].upper() + n[1:] + "." for n in notes]
    if spikes_total:
        text.append(f"Crosses ({spikes_total}): single points more than {SPIKE_FACTOR:g} "
                    "times both neighbours, not joined to their track: this grid of C does not "
                    "resolve them (near-coincident poles, whose modal terms grow and cancel in "
                    "the sum, or a track stepping onto another pole for one point); read the "
                    "track between them.")
    set_caption(fig, " ".join(text))
    return fig


def plot_regime_compliance(before, after, band=None, title: str | None = None,
                           not_drawn=()) -> Figure:
    """Work-piece compliance of every regime model, before (dashed) and after (solid) tuning.

    The title (by default) and the caption (:func:`figure_caption`) say which designs have
    curves: a design with none (unstable in every regime model) is named as not drawn.

    Parameters
    ----------
    before, after : sequence of ComplianceCurve
        One per regime model (labels ``"before, <model>"``, ``"after, <model>"``).
    band : (float, float), optional
        The requirement band [rad/s], shaded.
    title : str, optional
        The title; default what is drawn and in which style.
    not_drawn : sequence of str, optional
        Curves the caller has no data for and why (``"before, standing: presliding
        (unstable)"``), named in the caption.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig = Figure(figsize=(8.5, 5.0), layout="constrained")
    ax = fig.add_subplot()
    colors = {}
    palette = ["tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange", "tab:brown"]
    drawn = {}
    for tag, style, curves in (("before", "--", before), ("after", "-", after)):
        for c in curves:
            model = c.label.split(", ", 1)[-1]
            color = colors.setdefault(model, palette[len(colors) % len(palette)])
            ax.loglog(np.asarray(c.omega) * HZ_PER_RAD_S, np.abs(c.values), style, lw=1.4,
                      color=color, label=c.label)
            ax.plot([c.peak_frequency * HZ_PER_RAD_S], [c.peak_compliance],
                    "o" if style == "-" else "s", color=color, ms=4, mfc="none"
                    if style == "--" else color, label=f"_peak of {c.label}")
            drawn.setdefault(tag, []).append(model)
    if band is not None:
        ax.axvspan(band[0] * HZ_PER_RAD_S, band[1] * HZ_PER_RAD_S, color="0.9", zorder=0,
                   label="requirement band")
    styles = " and ".join(f"{tag} ({'dashed' if tag == 'before' else 'solid'})"
                          for tag in ("before", "after") if tag in drawn)
    missing = [tag for tag in ("before", "after") if tag not in drawn]
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("|x/F| at the work piece [m/N]")
    ax.set_title(title or "Work-piece compliance per regime model: " + (styles or "no curve")
                 + "".join(f"; {tag}: no stable model, not drawn" for tag in missing),
                 fontsize=10)
    ax.grid(True, which="both", alpha=0.4)
    if drawn or band is not None:
        ax.legend(fontsize=7, ncol=2)
    text = ["Closed-loop compliance |x/F| at the work piece of each cutting regime model "
            "(nominal friction), one colour per model: "
            + ("; ".join(style_key(ax)) or "no curve drawn") + "."]
    if drawn:
        text.append("Markers: each curve's peak (hollow squares before, dots after).")
    text += [f"No {tag} curve: the {tag} design is unstable in every regime model."
             for tag in missing if not any(n.startswith(tag) for n in not_drawn)]
    if not_drawn:
        text.append("Not drawn: " + "; ".join(not_drawn) + ".")
    if band is not None:
        text.append(f"Shaded: the requirement band {band[0] * HZ_PER_RAD_S:.3g}-"
                    f"{band[1] * HZ_PER_RAD_S:.3g} Hz.")
    set_caption(fig, " ".join(text))
    return fig


def _short(text: str, n: int = 110) -> str:
    return text if len(text) <= n else text[:n - 3].rstrip() + "..."


def _evidence_label(e, claim) -> str:
    where = "" if e.friction == "nominal" else f", {e.friction}"
    over = e.peak / claim - 1 if claim and math.isfinite(claim) else None
    why = (f"{over:.1%} above the claim" if e.why == "above the claim" and over is not None
           and over < 0.095 else f"{over:.0%} above the claim" if e.why == "above the claim"
           and over is not None else e.why)
    return (f"{e.method} at {e.force_pp:.4g} N p-p{where}: {e.peak:.3g} m/N at "
            f"{e.resonance_hz:.1f} Hz, {why}")


def _failure_without_a_point(r) -> str:
    """Why a regime fails when no drawn point shows it: its unstable corners of the friction
    spread (which have no response to draw), else the first of its reasons."""
    unstable = [c.label for c in r.corners
                if c.claimed_peak is not None and not math.isfinite(c.claimed_peak)]
    if unstable:
        return (f"the design is unstable at {len(unstable)} corner(s) of the friction spread "
                f"({'; '.join(unstable)}), which have no response to draw")
    return r.reason.split("; ")[0]


#: how many points that break a claim the legend names one by one (the caption names all)
EVIDENCE_IN_LEGEND = 3


def plot_regime_verification(regimes, linear=None, title: str | None = None,
                             tolerance: float = 0.3) -> Figure:
    """The nonlinear verification: simulated sweep envelopes per regime over the linear claims.

    One panel per regime: the claim (black line) and its tolerance (green band), the simulated
    sweeps of the tuned design (solid; at the corners of the friction spread dash-dotted) and
    of the design before (thin grey), the linear models (dashed), the periodic responses by
    harmonic balance (hollow dots; at the corners small pluses) and, red and labelled, every
    point that breaks the claim (:meth:`servotune.verdict.RegimeVerdict.evidence_against`).
    A panel's title says whether the claim holds and, when not, which evidence fails it.

    Parameters
    ----------
    regimes : sequence of RegimeVerdict
        From :func:`servotune.verdict.nonlinear_verdict`.
    linear : dict, optional
        ``{regime: [(label, omega [rad/s], H complex), ...]}`` linear curves (dashed).
    title : str, optional
        A title over the panels.
    tolerance : float, optional
        The verdict's tolerance on the claim (:attr:`servotune.verdict.Verdict.tolerance`;
        default 30 %, that of the requirements).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (its caption: :func:`figure_caption`).
    """
    regimes = [r for r in regimes if not r.holds or any(s.envelope for s in r.simulations)
               or r.harmonic] or list(regimes)
    n = max(len(regimes), 1)
    fig = Figure(figsize=(8.5, 3.4 * n), layout="constrained")
    axes = np.atleast_1d(fig.subplots(n, 1, squeeze=False)[:, 0])
    text = []
    for ax, r in zip(axes, regimes, strict=False):
        counts = {"after": 0, "before": 0, "corner": 0}
        for s in r.simulations:
            if not s.envelope:
                continue
            f_hz, amp = s.envelope
            if s.design == "after":
                ax.loglog(f_hz, amp, lw=1.4, label=f"after, {s.force_pp:.3g} N p-p")
                counts["after"] += 1
            else:
                ax.loglog(f_hz, amp, lw=0.8, color="0.55",
                          label=f"before, {s.force_pp:.3g} N p-p")
                counts["before"] += 1
        for corner in r.corners:
            for s in corner.simulations:
                if s.envelope and s.kind == "sweep":
                    f_hz, amp = s.envelope
                    ax.loglog(f_hz, amp, "-.", lw=1.2,
                              label=f"after, {corner.label}, {s.force_pp:.3g} N p-p")
                    counts["corner"] += 1
        for label, omega, values in (linear or {}).get(r.name, []):
            ax.loglog(np.asarray(omega) * HZ_PER_RAD_S, np.abs(values), "--", lw=1.0,
                      label=label)
        if r.harmonic:
            ax.plot([h.resonance_hz for h in r.harmonic], [h.peak for h in r.harmonic], "o",
                    color="k", mfc="none", ms=5,
                    label=f"harmonic balance, after ({len(r.harmonic)} levels)")
        corner_points = [h for c in r.corners for h in c.harmonic]
        if corner_points:
            ax.plot([h.resonance_hz for h in corner_points], [h.peak for h in corner_points],
                    "+", color="0.35", ms=5,
                    label=f"harmonic balance at the spread's corners ({len(corner_points)})")
        claim = r.claimed_peak
        if claim is not None and math.isfinite(claim):
            ax.axhline(claim, color="k", lw=0.8, label=f"claim {claim:.3g} m/N")
            ax.axhspan(claim, claim * (1 + tolerance), color="tab:green", alpha=0.08)
        evidence = r.evidence_against(tolerance)
        for k, e in enumerate(evidence):
            label = (_short(_evidence_label(e, claim), 120) if k < EVIDENCE_IN_LEGEND else
                     f"{len(evidence) - k} more point(s) that break the claim (in the caption)"
                     if k == EVIDENCE_IN_LEGEND else "_more evidence")
            ax.plot([e.resonance_hz], [e.peak], "X", color="tab:red", ms=9, mec="k", mew=0.6,
                    label=label, zorder=5)
        if evidence:
            worst = evidence[0]
            bottom, top = ax.get_ylim()
            ax.set_ylim(bottom, max(top, 2.0 * worst.peak))   # room for the label
            ax.annotate(f"{worst.method}, {worst.force_pp:.4g} N p-p"
                        + ("" if worst.friction == "nominal" else f"\n{worst.friction}"),
                        (worst.resonance_hz, worst.peak), textcoords="offset points",
                        xytext=(8, 8), fontsize=7, color="tab:red",
                        bbox=dict(boxstyle="round", fc="white", ec="tab:red", alpha=0.85))
        ax.axvline(r.band_hz[0], color="k", ls=":", lw=0.8)
        ax.axvline(r.band_hz[1], color="k", ls=":", lw=0.8)
        if r.holds:
            verdict = f"holds: every peak within the claim + {tolerance:.0%}"
        elif evidence:
            verdict = "does NOT hold: " + _evidence_label(evidence[0], claim)
        else:
            verdict = "does NOT hold: " + _failure_without_a_point(r)
        ax.set_title(_short(f"{r.name}: {verdict}", 120), fontsize=9,
                     color="k" if r.holds else "tab:red")
        ax.set_ylabel("|x/F| [m/N]")
        ax.grid(True, which="both", alpha=0.4)
        ax.legend(fontsize=6, ncol=2)
        drawn = [f"{counts['after']} simulated sweep(s) of the tuned design (nominal friction)",
                 f"{counts['corner']} at corners of the friction spread" if counts["corner"]
                 else "", f"{counts['before']} of the design before" if counts["before"]
                 else "", f"{len(r.harmonic)} periodic responses by harmonic balance"
                 if r.harmonic else "", f"{len(corner_points)} at the spread's corners"
                 if corner_points else ""]
        sentence = (f"{r.name}: " + ", ".join(x for x in drawn if x) + "; line styles: "
                    + ("; ".join(style_key(ax)) or "none") + ". ")
        if r.holds:
            sentence += f"The claim holds (within {tolerance:.0%})."
        else:
            sentence += (f"The claim does NOT hold: {r.reason}."
                         + (" Red crosses: " + "; ".join(_evidence_label(e, claim)
                                                          for e in evidence) + "."
                            if evidence else " No drawn point carries the failure: "
                            + _failure_without_a_point(r) + "."))
        text.append(sentence)
    axes[-1].set_xlabel("excitation frequency [Hz] (dotted: the swept band)")
    if title:
        fig.suptitle(title, fontsize=10)
    set_caption(fig, f"The tuned design's claim per regime (black line; green: the tolerance "
                     f"of {tolerance:.0%} above it) against the nonlinear axis with LuGre "
                     "friction at every pad. " + " ".join(text))
    return fig
