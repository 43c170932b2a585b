"""Figures. SI values come in; Hz and degrees appear only on the axes.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot, so that
figures can be made in threads, in tests and on machines with no screen.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from . import twomass

__all__ = ["plot_g_alpha", "plot_two_mass_compliance"]

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
