"""Figures. SI values come in; Hz and degrees appear only on the axes.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot, so that
figures can be made in threads, in tests and on machines with no screen.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from . import twomass

__all__ = [
    "plot_g_alpha",
    "plot_two_mass_compliance",
    # chatter
    "plot_stability_lobes",
    "plot_stability_map",
]

HZ_PER_RAD_S = 1.0 / (2.0 * math.pi)


def plot_g_alpha(alpha_max: float = 1.0, mark: float | None = None) -> Figure:
    """The paper's Fig 4: dynamic amplification g(alpha) at the work piece with Copt (Eq 7).

    Parameters
    ----------
    alpha_max : float
        Upper end of the alpha axis (the paper plots (0, 1]).
    mark : float, optional
        An alpha to mark on the curve (e.g. the system being analysed).
    """
    alpha = np.linspace(alpha_max / 200.0, alpha_max, 400)
    fig = Figure(figsize=(6.0, 4.0), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(alpha, twomass.g_alpha(alpha), color="tab:blue", lw=1.8,
            label=r"$g(\alpha) = (1-\alpha+\sqrt{1+\alpha^2})/\alpha$")
    if mark is not None:
        g = float(twomass.g_alpha(mark))
        ax.plot([mark], [g], "o", color="tab:red", label=rf"$\alpha$ = {mark:g}: g = {g:.3f}")
    ax.set_xlim(0.0, alpha_max)
    ax.set_ylim(0.0, 30.0)
    ax.set_xlabel(r"$\alpha = M_{WP}/M_{GW}$ [-]")
    ax.set_ylabel(r"$g(\alpha)$ [-]")
    ax.set_title(r"Dynamic amplification at the work piece with $C_{opt}$ (Fig 4, Eq 7)")
    ax.grid(True, alpha=0.4)
    ax.legend()
    return fig


def plot_two_mass_compliance(analysis: twomass.TwoMassAnalysis, f_max_hz: float = 25.0,
                             decades: int = 2) -> Figure:
    """The paper's Fig 5: |x2/f2| and its phase for C = Copt x 10^k, k = -decades..decades.

    Parameters
    ----------
    analysis : TwoMassAnalysis
    f_max_hz : float
        Upper end of the frequency axis [Hz].
    decades : int
        How many decades of C either side of Copt.
    """
    system = analysis.system
    f_hz = np.linspace(0.05, f_max_hz, 2000)
    omega = 2.0 * math.pi * f_hz
    fig = Figure(figsize=(9.0, 6.0), layout="constrained")
    ax_mag, ax_ph = fig.subplots(2, 1, sharex=True)
    colors = ["tab:purple", "tab:blue", "black", "tab:orange", "tab:red"]
    for i, k in enumerate(range(-decades, decades + 1)):
        c = analysis.c_opt * 10.0 ** k
        h = twomass.two_mass_compliance(system, omega, c)
        style = dict(lw=2.2 if k == 0 else 1.2, color=colors[i % len(colors)])
        label = f"C = {c:.3e} N s/m" + (r" ($C_{opt}$)" if k == 0 else "")
        ax_mag.semilogy(f_hz, np.abs(h), label=label, **style)
        ax_ph.plot(f_hz, np.degrees(np.angle(h)), **style)
    for j, w in enumerate(analysis.fixed_points):
        h = abs(complex(twomass.two_mass_compliance(system, w, analysis.c_opt)))
        ax_mag.plot([w * HZ_PER_RAD_S], [h], "s", ms=8, mfc="none", mec="tab:green", mew=1.8,
                    label="fixed points" if j == 0 else None)
        ax_mag.annotate(f"fixed point {j + 1}\n{w * HZ_PER_RAD_S:.2f} Hz",
                        (w * HZ_PER_RAD_S, h), textcoords="offset points", xytext=(10, -38),
                        fontsize=8, color="tab:green",
                        bbox=dict(boxstyle="round", fc="white", ec="none", alpha=0.8))
    ax_mag.set_ylabel(r"$|x_2/f_2|$ [m/N]")
    ax_mag.set_title(f"Layout {system.layout}: dynamic compliance at the work piece (Fig 5)\n"
                     f"M1 = {system.m1:g} kg, K = {system.k:g} N/m, alpha = {system.alpha:g}")
    ax_mag.grid(True, which="both", alpha=0.4)
    fig.legend(fontsize=8, loc="outside right upper")
    ax_ph.set_ylabel(r"phase of $x_2/f_2$ [deg]")
    ax_ph.set_xlabel("frequency [Hz]")
    ax_ph.set_xlim(0.0, f_max_hz)
    ax_ph.set_yticks(np.arange(-180, 1, 45))
    ax_ph.grid(True, alpha=0.4)
    return fig


# --- chatter: stability lobe diagrams -------------------------------------------------------

def _finite_or_nan(values) -> np.ndarray:
    values = np.array(values, dtype=float)
    values[~np.isfinite(values)] = np.nan
    return values


def plot_stability_lobes(results, required_depth: float | None = None,
                         labels=None, depth_max: float | None = None,
                         title: str | None = None, ax=None) -> Figure:
    """Stability lobe diagram: axial depth limit [mm] over spindle speed [rpm].

    Parameters
    ----------
    results : StabilityLobes or sequence of StabilityLobes
        Zero-order and/or semi-discretisation results on comparable speed ranges. The first
        one is shaded: above its limit the cut chatters. Zero-order results also show their
        individual lobes (thin lines).
    required_depth : float, optional
        A required axial depth [m], drawn as a horizontal line with the margin in the legend.
    labels : sequence of str, optional
        Legend entries; default the method and the number of intervals.
    depth_max : float, optional
        Upper end of the depth axis [m]; default 4 b_crit of the first result.
    title : str, optional
    ax : matplotlib.axes.Axes, optional
        Draw into these axes (e.g. one panel of a larger figure) and return their figure.
    """
    if not isinstance(results, (list, tuple)):
        results = [results]
    if not results:
        raise ValueError("give at least one StabilityLobes result")
    first = results[0]
    setup = first.setup
    depth_max = 4.0 * first.b_crit if depth_max is None else float(depth_max)
    if ax is None:
        fig = Figure(figsize=(8.0, 4.8), layout="constrained")
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    colors = ["black", "tab:red", "tab:blue", "tab:green", "tab:purple"]
    lo, hi = first.speed_rpm[0], first.speed_rpm[-1]
    for i, res in enumerate(results):
        color = colors[i % len(colors)]
        if labels is not None:
            label = labels[i]
        elif res.method == "sdm":
            label = f"semi-discretisation, m = {res.intervals}"
        else:
            label = "zero-order approximation"
        if res.method == "zoa" and res.lobe_speed_rpm.size:
            for n, b in zip(res.lobe_speed_rpm, res.lobe_depth, strict=True):
                b = _finite_or_nan(b)
                inside = (n >= lo) & (n <= hi) & (b <= 1.5 * depth_max)
                if np.any(inside):
                    ax.plot(n, 1e3 * b, color=color, lw=0.5, alpha=0.35)
        limit = _finite_or_nan(res.depth_limit)
        style = "-" if i == 0 else "--"
        ax.plot(res.speed_rpm, 1e3 * limit, style, color=color, lw=1.8,
                label=f"{label}: b_crit = {1e3 * res.b_crit:.3f} mm "
                      f"at {res.critical_speed_rpm:.0f} rpm")
        ax.plot([res.critical_speed_rpm], [1e3 * res.b_crit], "o", color=color, ms=5)
        if i == 0:
            top = np.where(np.isfinite(res.depth_limit), res.depth_limit, 10.0 * depth_max)
            ax.fill_between(res.speed_rpm, 1e3 * top, 1e3 * 10.0 * depth_max,
                            color="tab:red", alpha=0.08, lw=0, label="unstable (chatter)")
            ax.axhline(1e3 * res.b_crit, color=color, lw=0.8, ls=":")
    if required_depth is not None:
        margin = first.min_depth_limit / required_depth
        ax.axhline(1e3 * required_depth, color="tab:orange", lw=1.4,
                   label=f"required depth {1e3 * required_depth:.3g} mm (margin {margin:.2f})")
    ax.set_xlim(lo, hi)
    ax.set_ylim(0.0, 1e3 * depth_max)
    ax.set_xlabel("spindle speed [rpm]")
    ax.set_ylabel("axial depth of cut $b_{lim}$ [mm]")
    if title is None:
        title = (f"Stability lobes: {setup.teeth} teeth, a/D = {setup.radial_immersion:g}, "
                 f"{setup.milling}-milling, $K_t$ = {setup.kt:.3g}, $K_n$ = {setup.kn:.3g} "
                 "N/m$^2$")
    ax.set_title(title, fontsize=10)
    ax.grid(True, alpha=0.4)
    ax.legend(fontsize=8, loc="upper left")
    return fig


def plot_stability_map(stability_map, zoa=None, title: str | None = None) -> Figure:
    """Spectral radius of the monodromy matrix over (speed, depth), with its |mu| = 1 contour.

    Parameters
    ----------
    stability_map : StabilityMap
        From :func:`servotune.chatter.stability_map`.
    zoa : StabilityLobes, optional
        Zero-order lobes drawn over the map for comparison.
    title : str, optional
    """
    from matplotlib.lines import Line2D

    res = stability_map
    setup = res.setup
    fig = Figure(figsize=(8.0, 4.8), layout="constrained")
    ax = fig.add_subplot()
    rho = np.minimum(res.spectral_radius.T, 2.0)
    levels = np.linspace(0.0, 2.0, 21)
    filled = ax.contourf(res.speed_rpm, 1e3 * res.depth, rho, levels=levels, cmap="RdYlBu_r")
    ax.contour(res.speed_rpm, 1e3 * res.depth, res.spectral_radius.T, levels=[1.0],
               colors="black", linewidths=1.6)
    handles = [Line2D([], [], color="black", lw=1.6,
                      label=f"semi-discretisation |mu| = 1, m = {res.intervals}")]
    if zoa is not None:
        ax.plot(zoa.speed_rpm, 1e3 * _finite_or_nan(zoa.depth_limit), "--", color="white",
                lw=1.4)
        handles.append(Line2D([], [], color="white", ls="--", lw=1.4,
                              label="zero-order approximation"))
    fig.colorbar(filled, ax=ax, label="spectral radius |mu| (clipped at 2)")
    ax.set_xlim(res.speed_rpm[0], res.speed_rpm[-1])
    ax.set_ylim(1e3 * res.depth[0], 1e3 * res.depth[-1])
    ax.set_xlabel("spindle speed [rpm]")
    ax.set_ylabel("axial depth of cut [mm]")
    if title is None:
        title = (f"Monodromy spectral radius: {setup.teeth} teeth, a/D = "
                 f"{setup.radial_immersion:g}, {setup.milling}-milling")
    ax.set_title(title, fontsize=10)
    legend = ax.legend(handles=handles, fontsize=8, loc="upper left", facecolor="0.6")
    legend.get_frame().set_alpha(0.8)
    return fig
