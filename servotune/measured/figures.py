"""Figures of a modal identification (the FRF fit, the stabilisation diagram), of a model
update and of a measured speed plant with the velocity loop closed on it.

SI values come in; Hz and degrees appear only on the axes. Each function draws a
:class:`~servotune.measured.ema.ModalIdentification` or a
:class:`~servotune.measured.update.ModelUpdate` without computing anything, and returns a
:class:`matplotlib.figure.Figure` built without pyplot.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..plots import set_caption
from ..units import HZ_PER_RAD_S

__all__ = ["plot_frf_fit", "plot_model_update", "plot_speed_plant", "plot_stabilisation"]

#: how each status of the stabilisation diagram is drawn: marker, colour, label
_STATUS_STYLE = {
    -1: ("x", "0.75", "damping outside the range"),
    0: (".", "0.45", "new"),
    1: ("^", "tab:orange", "stable in frequency"),
    2: ("o", "tab:green", "stable in frequency and damping"),
}


def plot_frf_fit(result) -> Figure:
    """Plot the measured against the synthesised FRFs over the band (magnitude and phase).

    Parameters
    ----------
    result : servotune.measured.ema.ModalIdentification
        The identification.

    Returns
    -------
    matplotlib.figure.Figure
        Magnitude (log) above the phase; each FRF measured (solid) and synthesised (dashed),
        the identified natural frequencies as dotted vertical lines.
    """
    fig = Figure(figsize=(8, 6.5), layout="constrained")
    ax_mag, ax_ph = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    f = result.omega * HZ_PER_RAD_S
    unit = result.frfs[0].unit
    for k, frf in enumerate(result.frfs[:8]):
        colour = f"C{k % 10}"
        ax_mag.semilogy(f, np.abs(result.measured[k]), "-", color=colour, lw=2.5, alpha=0.45,
                        label=f"{frf.name} measured")
        ax_mag.semilogy(f, np.abs(result.synthesised[k]), "--", color=colour, lw=1.4,
                        label=f"synthesised ({100 * result.frf_errors[k]:.1f} % RMS)")
        ax_ph.plot(f, np.rad2deg(np.angle(result.measured[k])), "-", color=colour, lw=2.5,
                   alpha=0.45)
        ax_ph.plot(f, np.rad2deg(np.angle(result.synthesised[k])), "--", color=colour, lw=1.4)
    for mode in result.modes:
        for ax in (ax_mag, ax_ph):
            ax.axvline(mode.frequency * HZ_PER_RAD_S, color="0.5", ls=":", lw=0.8)
    ax_mag.set_ylabel(f"|H| [{unit}]")
    ax_ph.set_ylabel("phase [deg]")
    ax_ph.set_yticks([-180, -90, 0, 90, 180])
    ax_ph.set_xlabel("frequency [Hz]")
    ax_mag.set_title(f"{len(result.modes)} mode(s); relative RMS error "
                     f"{100 * result.frf_error:.2f} % over the band")
    ax_mag.legend(fontsize="small")
    for ax in (ax_mag, ax_ph):
        ax.grid(True, which="both", alpha=0.3)
    more = (f"; the first 8 of {len(result.frfs)} FRFs are drawn" if len(result.frfs) > 8
            else "")
    return set_caption(fig, "Measured FRFs (solid, light) and the FRFs of the identified "
                            "modes with the residual terms (dashed); natural frequencies "
                            "dotted" + more)


def plot_stabilisation(result) -> Figure:
    """Plot the stabilisation diagram: every pole of every model order, and the chosen ones.

    Parameters
    ----------
    result : servotune.measured.ema.ModalIdentification
        The identification.

    Returns
    -------
    matplotlib.figure.Figure
        Model order over natural frequency, one marker per pole by its status; the chosen
        poles circled in red; the sum of the measured magnitudes on a second axis.
    """
    diagram = result.diagram
    fig = Figure(figsize=(9, 5.5), layout="constrained")
    ax = fig.subplots()
    f = diagram.frequency * HZ_PER_RAD_S
    for status, (marker, colour, label) in _STATUS_STYLE.items():
        mask = diagram.status == status
        if mask.any():
            ax.plot(f[mask], diagram.order[mask], marker, color=colour, ms=4, ls="none",
                    label=label, mfc="none" if status == 1 else colour)
    for mode in result.modes:
        ax.plot(mode.frequency * HZ_PER_RAD_S, mode.order, "o", ms=10, mfc="none",
                color="tab:red", mew=1.5)
        ax.axvline(mode.frequency * HZ_PER_RAD_S, color="tab:red", ls=":", lw=0.8)
    ax.plot([], [], "o", ms=10, mfc="none", color="tab:red", mew=1.5, label="chosen")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    low, high = (b * HZ_PER_RAD_S for b in diagram.band)
    ax.set_xlim(low, high)
    twin = ax.twinx()
    twin.semilogy(result.omega * HZ_PER_RAD_S, np.sum(np.abs(result.measured), axis=0),
                  color="0.3", lw=0.8)
    twin.set_ylabel(f"sum of |H| measured [{result.frfs[0].unit}]")
    ax.legend(fontsize="small", loc="upper left")
    rule = diagram.rule
    ax.set_title(f"Stabilisation diagram (LSCF): stable = within "
                 f"{100 * rule.frequency_tolerance:g} % in frequency and "
                 f"{100 * rule.damping_tolerance:g} % in damping of the order below")
    return set_caption(fig, "Poles of every model order by their stability against the order "
                            "below; the chosen poles circled (" + rule.describe() + ")")


def plot_model_update(update) -> Figure:
    """Plot the measured FRF and the model's before and after updating (magnitude and phase).

    Parameters
    ----------
    update : servotune.measured.update.ModelUpdate
        The update.

    Returns
    -------
    matplotlib.figure.Figure
        Magnitude (log) above the phase over the band: the measurement (solid, light), the
        model before (dotted) and after (dashed); the updated poles' frequencies as vertical
        lines.
    """
    fig = Figure(figsize=(8, 6.5), layout="constrained")
    ax_mag, ax_ph = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    f = update.omega * HZ_PER_RAD_S
    curves = ((update.measured, "-", "0.2", 2.5, 0.45, "measured"),
              (update.before, ":", "tab:red", 1.6, 1.0,
               f"model before ({100 * update.frf_error_before:.1f} % RMS)"),
              (update.after, "--", "tab:blue", 1.4, 1.0,
               f"model after ({100 * update.frf_error_after:.1f} % RMS)"))
    for values, style, colour, width, alpha, label in curves:
        ax_mag.semilogy(f, np.abs(values), style, color=colour, lw=width, alpha=alpha,
                        label=label)
        ax_ph.plot(f, np.rad2deg(np.angle(values)), style, color=colour, lw=width, alpha=alpha)
    for p in update.parameters:
        for ax in (ax_mag, ax_ph):
            ax.axvline(abs(p.pole_after) * HZ_PER_RAD_S, color="0.5", ls=":", lw=0.8)
    unit = {"receptance": "m/N", "mobility": "m/s/N", "accelerance": "m/s^2/N"}[update.quantity]
    ax_mag.set_ylabel(f"|H| at {update.dof} [{unit}]")
    ax_ph.set_ylabel("phase [deg]")
    ax_ph.set_yticks([-180, -90, 0, 90, 180])
    ax_ph.set_xlabel("frequency [Hz]")
    changed = ", ".join(f"mode {p.mode + 1}: {p.frequency_before * HZ_PER_RAD_S:.1f} -> "
                        f"{p.frequency_after * HZ_PER_RAD_S:.1f} Hz" for p in update.parameters)
    ax_mag.set_title(f"Model updating: {changed}", fontsize="medium")
    ax_mag.legend(fontsize="small")
    for ax in (ax_mag, ax_ph):
        ax.grid(True, which="both", alpha=0.3)
    return set_caption(fig, f"The measured {update.quantity} at {update.dof} "
                            f"({update.configuration}) against the model before and after "
                            "updating the stored modes' frequencies and damping ratios; the "
                            "updated poles dotted")


def _margins_label(analysis) -> str:
    """'GM 8.5 dB, PM 75.0 deg, Ms 1.62' of a LoopAnalysis."""
    gm = analysis.gain_margin_db
    gm_text = f"GM {gm:.2f} dB" if np.isfinite(gm) else "GM inf"
    return f"{gm_text}, PM {analysis.phase_margin_deg:.1f} deg, Ms {analysis.ms:.3f}"


def plot_speed_plant(comparison, title: str = "Speed plant and velocity loop") -> Figure:
    """Plot a measured speed plant against the model's, and the velocity loops on both.

    Parameters
    ----------
    comparison : servotune.measured.speed_plant.SpeedPlantComparison
        The comparison.
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
        Left: |P| and its phase, measured (solid, light) and model (dashed). Right: |L| and
        its phase of the velocity loop on each, the gain and phase crossovers of the loop on
        the measured plant marked, the margins in the legend.
    """
    fig = Figure(figsize=(12, 6.5), layout="constrained")
    axes = fig.subplots(2, 2, sharex="col", height_ratios=(2, 1))
    f = comparison.omega * HZ_PER_RAD_S
    (p_mag, l_mag), (p_ph, l_ph) = axes
    for values, style, colour, width, alpha, label in (
            (comparison.measured, "-", "0.2", 2.5, 0.45, "measured"),
            (comparison.model, "--", "tab:blue", 1.3, 1.0,
             f"model ({100 * comparison.frf_error:.2f} % RMS apart)")):
        p_mag.loglog(f, np.abs(values), style, color=colour, lw=width, alpha=alpha, label=label)
        p_ph.semilogx(f, np.rad2deg(np.angle(values)), style, color=colour, lw=width,
                      alpha=alpha)
    p_mag.set_ylabel("|P| [rad/s/N m]")
    p_mag.set_title(f"Speed plant: motor speed / motor torque ({comparison.contact.kind} "
                    "guide ways)", fontsize="medium")
    poles = comparison.measured_unstable_poles
    verdict = (_margins_label(comparison.measured_loop) if not poles
               else f"unstable ({poles} closed-loop poles by the Nyquist criterion)")
    loops = [(comparison.l_measured, "-", "0.2", 2.5, 0.45, "on the measured plant: " + verdict)]
    if comparison.model_loop is not None:
        loops.append((comparison.l_model, "--", "tab:blue", 1.3, 1.0,
                      "on the model: " + _margins_label(comparison.model_loop)))
    else:
        loops.append((comparison.l_model, "--", "tab:red", 1.3, 1.0,
                      "on the model: its closed loop is unstable"))
    for values, style, colour, width, alpha, label in loops:
        l_mag.loglog(f, np.abs(values), style, color=colour, lw=width, alpha=alpha, label=label)
        l_ph.semilogx(f, np.rad2deg(np.unwrap(np.angle(values))), style, color=colour,
                      lw=width, alpha=alpha)
    l_mag.axhline(1.0, color="0.5", lw=0.8)
    l_ph.axhline(-180.0, color="0.5", lw=0.8)
    a = comparison.measured_loop
    for w, colour in ((a.crossover, "tab:green"), (a.phase_crossover, "tab:orange")):
        if np.isfinite(w):
            for ax in (l_mag, l_ph):
                ax.axvline(w * HZ_PER_RAD_S, color=colour, ls=":", lw=1.0)
    if np.isfinite(comparison.nyquist):
        for ax in (l_mag, l_ph):
            ax.axvline(comparison.nyquist * HZ_PER_RAD_S, color="0.3", ls="-.", lw=0.8)
    l_mag.set_ylabel("|L| [-]")
    l_mag.set_title(f"Velocity loop ({comparison.drive_kind} drive), position loop open",
                    fontsize="medium")
    p_ph.set_ylabel("phase [deg]")
    l_ph.set_ylabel("phase [deg]")
    for ax in (p_ph, l_ph):
        ax.set_xlabel("frequency [Hz]")
    for ax in (p_mag, l_mag):
        ax.legend(fontsize="small")
    for ax in axes.ravel():
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(title)
    nyquist = ("; the velocity controller's Nyquist frequency dash-dotted"
               if np.isfinite(comparison.nyquist) else "")
    return set_caption(fig, "The measured speed plant against the model's, and the velocity "
                            "loop closed on each by the drive's own controllers (gain "
                            "crossover green, phase crossover orange, of the loop on the "
                            f"measurement{nyquist})")
