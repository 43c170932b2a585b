"""Figures. SI values come in; Hz and degrees appear only on the axes.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot, so that
figures can be made in threads, in tests and on machines with no screen.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from . import twomass
from .captions import drawn_labels, figure_caption, ls_name, set_caption, style_key
from .regime_plots import (
    EVIDENCE_IN_LEGEND,
    SPIKE_FACTOR,
    plot_mode_peaks,
    plot_regime_compliance,
    plot_regime_verification,
)
from .units import HZ_PER_RAD_S

__all__ = [
    "BODE_PHASE_RANGE_DEG",
    "EVIDENCE_IN_LEGEND",
    "SPIKE_FACTOR",
    "wrapped_phase_deg",
    "drawn_labels",
    "figure_caption",
    "ls_name",
    "set_caption",
    "style_key",
    "plot_bode",
    "plot_compliance",
    "plot_energies",
    "plot_equivalent_damping",
    "plot_g_alpha",
    "plot_hysteresis",
    "plot_mode_peaks",
    "plot_pad_hysteresis",
    "plot_response_hysteresis",
    "plot_stability_lobes",
    "plot_stability_map",
    "plot_stribeck",
    "plot_sweep_envelope",
    "plot_regime_verification",
    "plot_regime_compliance",
    "plot_two_mass_compliance",
]



def plot_g_alpha(alpha_max: float = 1.0, mark: float | None = None) -> Figure:
    """The paper's Fig 4: dynamic amplification g(alpha) at the work piece with Copt (Eq 7).

    Parameters
    ----------
    alpha_max : float
        Upper end of the alpha axis (the paper plots (0, 1]).
    mark : float, optional
        An alpha to mark on the curve (e.g. the system being analysed).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
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
        From :func:`servotune.twomass.analyse_two_mass`: the system, Copt, the fixed points.
    f_max_hz : float
        Upper end of the frequency axis [Hz].
    decades : int
        How many decades of C either side of Copt.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
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
    set_caption(fig, f"Two-mass layout {system.layout} (M1 = {system.m1:g} kg, K = "
                     f"{system.k:g} N/m, alpha = {system.alpha:g}): magnitude and phase of "
                     f"the work-piece compliance x2/f2 for C = Copt x 10^k, k = "
                     f"{-decades}..{decades}, Copt = {analysis.c_opt:.4g} N s/m (the thick "
                     f"black curve), as in the paper's Fig 5; solid lines: "
                     f"{', '.join(drawn_labels(ax_mag)[:2 * decades + 1])}".replace(
                         "($C_{opt}$)", "(Copt)") + ". Green squares: "
                     "the fixed points every curve passes through.")
    return fig


# ---------------------------------------------------------------- friction (servotune.friction)


UM_PER_M = 1e6


def plot_stribeck(params, v=None, force=None, v_max: float | None = None,
                  title: str = "Sliding friction against velocity (Fig 7)") -> Figure:
    """Steady-state friction F_ss(v) of a LuGre contact, with measured points if given (Fig 7).

    Parameters
    ----------
    params : servotune.friction.LuGreParameters
        The LuGre parameters whose steady-state curve is drawn.
    v, force : array_like, optional
        Measured velocities [m/s] and friction forces [N].
    v_max : float, optional
        Half-width of the velocity axis [m/s]; default the data's, or 0.5 m/s (Fig 7).
    title : str, optional
        First line of the title (the parameters follow on the second).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    from .friction import lugre

    if v_max is None:
        v_max = float(np.max(np.abs(v))) if v is not None else 0.5
    grid = np.concatenate([-np.geomspace(v_max, 1e-6 * v_max, 400),
                           np.geomspace(1e-6 * v_max, v_max, 400)])
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    if v is not None and force is not None:
        ax.plot(v, force, "o", ms=4, mfc="none", color="tab:blue", label="measured")
    ax.plot(grid, lugre.steady_state_friction(params, grid), color="tab:red", lw=1.8,
            label="LuGre steady state" + (" (fitted)" if v is not None else ""))
    for sign in (-1, 1):
        ax.axvline(sign * params.vs, color="0.5", lw=0.8, ls=":")
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.axvline(0.0, color="0.3", lw=0.6)
    ax.text(params.vs, 0.0, r" $v_s$", color="0.4", va="bottom")
    ax.set_xlim(-v_max, v_max)
    ax.set_xlabel("sliding velocity v [m/s]")
    ax.set_ylabel("friction force F [N]")
    ax.set_title(f"{title}\nFc = {params.fc:.4g} N, Fs = {params.fs:.4g} N, "
                 f"vs = {params.vs:.3g} m/s, delta = {params.delta:.3g}, "
                 f"sigma2 = {params.sigma2:.4g} N s/m", fontsize=10)
    ax.grid(True, alpha=0.4)
    ax.legend(loc="lower right")
    return fig


def _stiction_loop(fs: float, sigma0: float, amplitude: float, n: int = 721):
    """The idealised elasto-plastic cycle of Fig 6 over one period (for drawing)."""
    theta = np.linspace(-0.5 * math.pi, 1.5 * math.pi, n)
    x = amplitude * np.sin(theta)
    f = np.empty_like(x)
    f[0] = -min(fs, sigma0 * amplitude)
    for i in range(1, x.size):
        f[i] = min(max(f[i - 1] + sigma0 * (x[i] - x[i - 1]), -fs), fs)
    return x, f


def plot_hysteresis(cycle, params=None) -> Figure:
    """Friction force against displacement over one period, one loop per amplitude (Fig 2/6).

    Parameters
    ----------
    cycle : servotune.friction.HysteresisCycle
        From :func:`servotune.friction.lugre_cycle` with a 1-D batch of amplitudes at one
        frequency (or a single amplitude).
    params : servotune.friction.LuGreParameters, optional
        If given, the paper's idealised stiction cycle (Fig 6: spring sigma0 up to +-Fs, then
        sliding) is drawn dashed for the same amplitudes.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    amplitude = np.atleast_1d(cycle.amplitude)
    x = np.atleast_2d(cycle.displacement)
    force = np.atleast_2d(cycle.force)
    ceq = np.atleast_1d(cycle.ceq)
    fig = Figure(figsize=(7.5, 5.0), layout="constrained")
    ax = fig.add_subplot()
    for i, a in enumerate(amplitude):
        ax.plot(x[i] * UM_PER_M, force[i], color=f"C{i % 10}", lw=1.6,
                label=f"A = {a * UM_PER_M:.3g} um: Ceq = {ceq[i]:.3g} N s/m")
        if params is not None:
            xs, fs_ = _stiction_loop(params.fs, params.sigma0, float(a))
            ax.plot(xs * UM_PER_M, fs_, color=f"C{i % 10}", lw=1.0, ls="--",
                    label="idealised stiction cycle (Fig 6)" if i == amplitude.size - 1
                    else None)
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.axvline(0.0, color="0.3", lw=0.6)
    ax.set_xlabel("displacement x [um]")
    ax.set_ylabel("friction force F [N]")
    f_hz = float(np.atleast_1d(cycle.omega)[0]) * HZ_PER_RAD_S
    ax.set_title(f"LuGre hysteresis loops under x = A sin(wt), {f_hz:.3g} Hz (Fig 2 / Fig 6)",
                 fontsize=11)
    ax.grid(True, alpha=0.4)
    ax.legend(fontsize=8, loc="upper left")
    return fig


def plot_equivalent_damping(params, omega: float, amplitude=None,
                            show_printed: bool = True) -> Figure:
    """Equivalent viscous damping against amplitude: closed form and LuGre (Eq 8-10).

    Parameters
    ----------
    params : servotune.friction.LuGreParameters
        The LuGre parameters (Fs, sigma0 for the closed form; all for the describing function).
    omega : float
        Angular frequency [rad/s].
    amplitude : array_like, optional
        Amplitudes [m]; default 0.05 to 50 times Fs/sigma0.
    show_printed : bool
        Also draw the paper's printed Eq 9 (half the cycle's area), dotted.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    from .friction import equivalent

    a0 = params.fs / params.sigma0
    if amplitude is None:
        amplitude = np.geomspace(0.05 * a0, 50.0 * a0, 120)
    amplitude = np.asarray(amplitude, dtype=float)
    closed = equivalent.equivalent_damping_stiction(params.fs, params.sigma0, amplitude, omega)
    ceq, _ = equivalent.describing_function(params, amplitude, omega, n_steps=512)
    fig = Figure(figsize=(7.0, 5.2), layout="constrained")
    ax = fig.add_subplot()
    ax.loglog(amplitude * UM_PER_M, ceq, color="tab:red", lw=1.8,
              label="LuGre describing function (numerical)")
    pos = closed > 0
    ax.loglog(amplitude[pos] * UM_PER_M, closed[pos], color="tab:blue", lw=1.8,
              label=r"stiction cycle: $4F_s(A - F_s/\sigma_0)/(\pi\omega A^2)$")
    if show_printed:
        ax.loglog(amplitude[pos] * UM_PER_M, 0.5 * closed[pos], color="tab:blue", lw=1.0,
                  ls=":", label="as printed in the paper (Eq 9, half the area)")
    a_peak, c_peak = equivalent.stiction_peak_damping(params.fs, params.sigma0, omega)
    ax.plot([float(a_peak) * UM_PER_M], [float(c_peak)], "o", color="tab:blue",
            label=rf"max $\sigma_0/(\pi\omega)$ = {float(c_peak):.3g} N s/m")
    ax.axhline(params.sigma1 + params.sigma2, color="0.5", lw=0.8, ls="--",
               label=r"$\sigma_1 + \sigma_2$ (presliding)")
    ax.axvline(a0 * UM_PER_M, color="0.5", lw=0.8, ls=":")
    ax.text(a0 * UM_PER_M, 0.03, r" $F_s/\sigma_0$", color="0.4", va="bottom",
            transform=ax.get_xaxis_transform())
    ax.set_xlabel("amplitude A [um]")
    ax.set_ylabel(r"equivalent damping $C_{eq}$ [N s/m]")
    ax.set_title(f"Equivalent viscous damping at {omega * HZ_PER_RAD_S:.3g} Hz (Eq 8-10)",
                 fontsize=11)
    ax.grid(True, which="both", alpha=0.4)
    fig.legend(fontsize=8, loc="outside lower center", ncol=2)
    return fig


def plot_response_hysteresis(response, measured_force=None,
                             title: str = "Friction force against displacement") -> Figure:
    """Draw the force against displacement of a simulated LuGre response.

    Parameters
    ----------
    response : servotune.friction.LuGreResponse
        From :func:`servotune.friction.simulate_lugre`: displacement [m] and force [N].
    measured_force : array_like, optional
        Measured forces [N] at the same samples, drawn as dots.
    title : str, optional
        The title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    if measured_force is not None:
        ax.plot(response.displacement * UM_PER_M, measured_force, ".", ms=2, color="0.55",
                label="measured")
    ax.plot(response.displacement * UM_PER_M, response.force, color="tab:red", lw=1.4,
            label="LuGre")
    ax.set_xlabel("displacement x [um]")
    ax.set_ylabel("friction force F [N]")
    ax.set_title(title, fontsize=11)
    ax.grid(True, alpha=0.4)
    ax.legend(loc="center", markerscale=4)
    return fig


# ------------------------------------------------------------------ chatter (servotune.chatter)



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
        The title (default: the set-up).
    ax : matplotlib.axes.Axes, optional
        Draw into these axes (e.g. one panel of a larger figure) and return their figure.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (that of ``ax`` when given).

    Raises
    ------
    ValueError
        When ``results`` is empty.
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
    text = [f"Stability lobes: the axial depth of cut b_lim [mm] at which the cut starts to "
            f"chatter, over the spindle speed ({setup.teeth} teeth, radial immersion a/D = "
            f"{setup.radial_immersion:g}, {setup.milling}-milling); "
            + "; ".join(style_key(ax)) + "."]
    if any(res.method == "zoa" and res.lobe_speed_rpm.size for res in results):
        text.append("Thin lines: the individual lobes of the zero-order approximation.")
    text.append("Dots: each limit's smallest depth b_crit; shaded: unstable (chatter) above "
                "the first limit.")
    if required_depth is not None:
        text.append(f"Orange: the required depth {1e3 * required_depth:.3g} mm.")
    set_caption(fig, " ".join(text))
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
        The title (default: the set-up).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
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


def wrapped_phase_deg(values) -> np.ndarray:
    """The phase of L [deg] wrapped into (-360, 0], with NaN where it wraps (so that a line
    drawn through it breaks there instead of jumping by a turn).

    In (-360, 0] every phase crossover of the loop is a crossing of the -180 deg line and
    the phase at the gain crossover is the phase margin less 180 deg.

    Parameters
    ----------
    values : array_like
        L(j omega), complex.

    Returns
    -------
    numpy.ndarray
        The wrapped phase [deg] (float; NaN at the first point after each wrap).
    """
    phase = np.degrees(np.unwrap(np.angle(np.asarray(values).reshape(-1))))
    wrapped = phase - 360.0 * np.ceil(phase / 360.0)
    jumps = np.nonzero(np.abs(np.diff(wrapped)) > 180.0)[0] + 1
    wrapped[jumps] = np.nan
    return wrapped


#: the phase range a Bode figure shows [deg]: the wrapped phase, where the margins are read
BODE_PHASE_RANGE_DEG = (-360.0, 0.0)


def plot_bode(loops, analyses=None, title: str = "Loop transfer functions",
              styles=None, regime: str | None = None) -> Figure:
    """Bode diagram of loop transfer functions with their margins marked.

    The phase is wrapped into (-360, 0] (:func:`wrapped_phase_deg`; the line breaks where it
    wraps), so that every phase crossover is a crossing of -180 deg and the phase at the gain
    crossover is the phase margin less 180 deg. Marked for each loop with an
    analysis: the gain crossover (dot at 0 dB) and, on the phase, the phase margin as a bar
    up from -180 deg; the phase crossover (square at -180 deg) and, on the magnitude, the gain
    margin as a bar from |L| to 0 dB; where the sensitivity peaks (Ms, diamond on |L|). The
    figure's caption (:func:`figure_caption`) lists what was drawn.

    Parameters
    ----------
    loops : dict
        ``{name: (omega [rad/s], L(j omega) complex array)}``.
    analyses : dict, optional
        ``{name: LoopAnalysis}``; crossover, phase margin and gain margin are marked.
    title : str, optional
        The title.
    styles : dict, optional
        ``{name: (colour, line style)}`` (default: a colour per loop, solid lines).
    regime : str, optional
        The regime model the loops are of, named in the title and the caption.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig = Figure(figsize=(8.5, 6.5), layout="constrained")
    ax_mag, ax_ph = fig.subplots(2, 1, sharex=True)
    colors = ["tab:blue", "tab:red", "tab:green", "tab:purple"]
    lo, hi = BODE_PHASE_RANGE_DEG
    marked = []
    for i, (name, (omega, values)) in enumerate(loops.items()):
        omega = np.asarray(omega, dtype=float)
        f_hz = omega * HZ_PER_RAD_S
        values = np.asarray(values).reshape(-1)
        color, ls = (styles or {}).get(name, (colors[i % len(colors)], "-"))
        a = (analyses or {}).get(name)
        phase = wrapped_phase_deg(values)
        mag_db = 20 * np.log10(np.abs(values))
        ax_mag.semilogx(f_hz, mag_db, color=color, lw=1.5, ls=ls, label=f"{name} loop")
        ax_ph.semilogx(f_hz, phase, color=color, lw=1.5, ls=ls, label=f"{name} loop")
        if a is None:
            continue
        parts = []
        solid = ls in ("-", "solid")
        if math.isfinite(a.crossover):
            fc = a.crossover * HZ_PER_RAD_S
            at = a.phase_margin_deg - 180.0   # the wrapped phase at the crossover
            parts.append(f"PM {a.phase_margin_deg:.1f} deg at {fc:.3g} Hz")
            ax_mag.plot([fc], [0.0], "o", color=color, ms=6,
                        label=f"{name}: " + ", ".join(
                            [parts[0]]
                            + ([f"GM {a.gain_margin_db:.1f} dB"]
                               if math.isfinite(a.gain_margin) else [])
                            + [f"Ms {a.ms:.2f}"]))
            ax_ph.plot([fc, fc], [-180.0, at], color=color, lw=3.0, alpha=0.6,
                       solid_capstyle="butt", label=f"_{name}: phase margin")
            if solid:
                ax_ph.annotate(f"PM {a.phase_margin_deg:.0f}\N{DEGREE SIGN}", (fc, at),
                               textcoords="offset points", xytext=(4, 4), fontsize=7,
                               color=color)
        else:
            ax_mag.plot([], [], "o", color=color, label=f"{name}: no gain crossover, "
                                                        f"Ms {a.ms:.2f}")
            parts.append("no gain crossover")
        if math.isfinite(a.phase_crossover):
            fp = a.phase_crossover * HZ_PER_RAD_S
            level = float(np.interp(np.log(a.phase_crossover), np.log(omega), mag_db))
            ax_ph.plot([fp], [-180.0], "s", color=color, ms=5, mfc="none",
                       label=f"_{name}: phase crossover")
            if math.isfinite(a.gain_margin):
                ax_mag.plot([fp, fp], [level, 0.0], color=color, lw=3.0, alpha=0.6,
                            solid_capstyle="butt", label=f"_{name}: gain margin")
                parts.append(f"GM {a.gain_margin_db:.1f} dB at {fp:.3g} Hz")
                if solid:
                    ax_mag.annotate(f"GM {a.gain_margin_db:.0f} dB", (fp, level),
                                    textcoords="offset points", xytext=(4, -10), fontsize=7,
                                    color=color)
        if math.isfinite(a.ms_frequency):
            fm = a.ms_frequency * HZ_PER_RAD_S
            level = float(np.interp(np.log(a.ms_frequency), np.log(omega), mag_db))
            ax_mag.plot([fm], [level], "D", color=color, ms=5, mfc="white",
                        label=f"_{name}: Ms")
            parts.append(f"Ms {a.ms:.2f} at {fm:.3g} Hz")
        marked.append(f"{name} ({ls_name(ls)}): " + ", ".join(parts))
    ax_mag.axhline(0.0, color="k", lw=0.8)
    ax_mag.set_ylabel("|L| [dB]")
    ax_mag.set_title(title if regime is None else f"{title}\nregime model {regime}",
                     fontsize=10)
    ax_mag.grid(True, which="both", alpha=0.4)
    ax_mag.legend(fontsize=7)
    ax_ph.axhline(-180.0, color="k", lw=0.8)
    ax_ph.set_ylim(lo - 10.0, hi + 10.0)
    ax_ph.set_yticks(np.arange(lo, hi + 1, 90.0))
    ax_ph.set_ylabel("phase of L [deg]")
    ax_ph.set_xlabel("frequency [Hz]")
    ax_ph.grid(True, which="both", alpha=0.4)
    sentences = ["Bode diagram of the loop transfer functions L"
                 + (f" in the regime model {regime}" if regime else "") + ": "
                 + ("; ".join(style_key(ax_mag)) or "no loop drawn") + "."]
    if marked:
        sentences += ["Margins: " + "; ".join(marked) + ".",
                      "Dots: gain crossover (0 dB); bars: the phase margin (up from -180 deg) "
                      "and the gain margin (from |L| up to 0 dB); squares: phase crossover; "
                      "diamonds: where the sensitivity peaks (Ms)."]
    sentences.append(f"The phase is wrapped into ({lo:g}, {hi:g}] deg (the line breaks where "
                     "it wraps): every crossing of -180 deg is a phase crossover.")
    set_caption(fig, " ".join(sentences))
    return fig


def plot_compliance(curves, title: str = "Work-piece compliance",
                    marks=None) -> Figure:
    """Magnitude and phase of compliances x/F.

    Parameters
    ----------
    curves : list of (label, omega [rad/s], H [m/N] complex array)
        The compliances, one line each.
    title : str, optional
        The title.
    marks : list of (label, omega [rad/s], value [m/N]), optional
        Points to mark (e.g. peaks).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig = Figure(figsize=(8.5, 6.5), layout="constrained")
    ax_mag, ax_ph = fig.subplots(2, 1, sharex=True)
    for label, omega, values in curves:
        f_hz = np.asarray(omega) * HZ_PER_RAD_S
        values = np.asarray(values).reshape(-1)
        (line,) = ax_mag.loglog(f_hz, np.abs(values), lw=1.4, label=label)
        ax_ph.semilogx(f_hz, np.degrees(np.angle(values)), lw=1.2, color=line.get_color())
    for label, omega, value in marks or ():
        ax_mag.plot([omega * HZ_PER_RAD_S], [value], "v", color="k", ms=7)
        ax_mag.annotate(label, (omega * HZ_PER_RAD_S, value), textcoords="offset points",
                        xytext=(6, 6), fontsize=8)
    ax_mag.set_ylabel("|x/F| [m/N]")
    ax_mag.set_title(title)
    ax_mag.grid(True, which="both", alpha=0.4)
    ax_mag.legend(fontsize=8)
    ax_ph.set_ylabel("phase [deg]")
    ax_ph.set_xlabel("frequency [Hz]")
    ax_ph.set_yticks(np.arange(-180, 181, 90))
    ax_ph.grid(True, which="both", alpha=0.4)
    return fig


# ------------------------------------------------------------------------------------------
# time simulation (servotune.simulate): sweep envelopes, energies, pad hysteresis


def plot_sweep_envelope(envelopes, labels=None, reference=None, title=None) -> Figure:
    """Work-piece oscillation per unit force along sine sweeps (the paper's Table 3 trials).

    Parameters
    ----------
    envelopes : sequence of SweepEnvelope
        From :meth:`servotune.simulate.SimulationResult.sweep_envelope`.
    labels : sequence of str, optional
        Legend entries, one per envelope.
    reference : dict, optional
        ``{label: (omega [rad/s], |compliance| [m/N])}`` linear curves to draw dashed.
    title : str, optional
        The title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    ax = fig.add_subplot()
    labels = labels or [None] * len(envelopes)
    for env, label in zip(envelopes, labels, strict=True):
        line, = ax.plot(env.frequency * HZ_PER_RAD_S, env.amplitude, lw=1.6, label=label)
        ax.plot([env.resonance_hz], [env.peak], "o", color=line.get_color(), ms=5)
    for label, (omega, mag) in (reference or {}).items():
        ax.plot(np.asarray(omega) * HZ_PER_RAD_S, np.abs(mag), "--", lw=1.0, label=label)
    ax.set_xlabel("excitation frequency [Hz]")
    ax.set_ylabel("work-piece oscillation / force [m/N]")
    ax.set_title(title or "Sine sweep: first-harmonic envelope per cycle (dots: resonance)",
                 fontsize=10)
    ax.grid(True, alpha=0.4)
    if any(labels) or reference:
        ax.legend(fontsize=8)
    return fig


def plot_energies(result, title=None) -> Figure:
    """Draw the cumulative works done on the structure over time.

    The works of the external force, the motor, the guide-way friction and the structural
    damping, with the structure's kinetic plus potential energy at the checkpoints.

    Parameters
    ----------
    result : servotune.simulate.SimulationResult
        A simulation with its work channels.
    title : str, optional
        The title (default: the scenario).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    names = ("external force", "motor", "guide-way friction", "structural damping")
    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    ax = fig.add_subplot()
    for k, name in enumerate(names):
        ax.plot(result.t, result.work[:, k], lw=1.5, label=name)
    ax.plot(result.checkpoints, result.structure_energy, "k:", lw=1.2,
            label="kinetic + potential energy")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("work done on the structure [J]")
    ax.set_title(title or f"Energies: {result.scenario}", fontsize=10)
    ax.grid(True, alpha=0.4)
    ax.legend(fontsize=8)
    return fig


def plot_pad_hysteresis(result, pad: str, t_start: float = 0.0, t_end: float | None = None,
                        title=None) -> Figure:
    """Draw the friction force against displacement of one guide-way pad (Fig 2/8).

    Parameters
    ----------
    result : servotune.simulate.SimulationResult
        A simulation with the pad's displacement and friction force.
    pad : str
        The pad DOF, e.g. ``"pad1.x"``.
    t_start : float, optional
        Start of the window [s] (default 0); the displacement is drawn from its value there.
    t_end : float, optional
        End of the window [s] (default the end of the simulation).
    title : str, optional
        The title (default: the scenario).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.

    Raises
    ------
    KeyError
        When the result has no signal of that pad.
    """
    key = pad.replace(".", "_")
    t_end = result.t[-1] if t_end is None else t_end
    sel = (result.t >= t_start) & (result.t <= t_end)
    x = result[key][sel]
    force = result["F_" + key][sel]
    fig = Figure(figsize=(6.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(1e6 * (x - x[0]), force, lw=0.9, color="tab:blue")
    ax.set_xlabel(f"{pad} displacement from t = {t_start:g} s [um]")
    ax.set_ylabel(f"friction force at {pad} [N]")
    ax.set_title(title or f"Pad hysteresis, {result.scenario}", fontsize=10)
    ax.grid(True, alpha=0.4)
    return fig
