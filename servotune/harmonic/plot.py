"""Figure of the amplitude-dependent compliance: the family of curves over the linear models.

One picture of the paper's remarks A-C (Bianchi et al. 2014, sec 5.3): at small force the axis
follows the presliding (locked) contact, at large force standing still the friction damps it
below every linear model, and while feeding it follows the sliding linearisation.
"""

from __future__ import annotations

from ..units import HZ_PER_RAD_S

__all__ = ["nonlinear_compliance_plot"]

_STYLES = {"presliding": ("k", "--", "linear: presliding (pads locked)"),
           "viscous": ("0.5", ":", "linear: viscous-only pads"),
           "sliding": ("tab:green", "-.", "linear: sliding at the feed speed")}


def nonlinear_compliance_plot(result):
    """Plot the compliance [m/N] over frequency [Hz] of a harmonic-balance result.

    The harmonic balance per force level (solid, its peak marked by a dot), the
    describing-function curve of the same level (thin dashed, same colour) and the linear
    references (presliding black dashed, viscous-only grey dotted, sliding green dash-dotted),
    on a logarithmic compliance axis.

    Parameters
    ----------
    result : NonlinearCompliance
        The curves and references (:func:`~servotune.harmonic.compliance.nonlinear_compliance`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (one axes); closing it is the caller's.
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    for name, (omega, comp) in result.references.items():
        color, style, label = _STYLES.get(name, ("k", "-", name))
        ax.semilogy(omega * HZ_PER_RAD_S, comp, color=color, ls=style, lw=1.2, label=label)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, curve in enumerate(result.curves):
        c = colors[i % len(colors)]
        ax.semilogy(curve.omega * HZ_PER_RAD_S, curve.compliance, color=c, lw=2.0,
                    label=f"{curve.force_pp:g} N p-p, harmonic balance (H = {curve.harmonics})")
        ax.plot(curve.resonance * HZ_PER_RAD_S, curve.peak, "o", color=c, ms=5)
    for i, curve in enumerate(result.describing):
        ax.semilogy(curve.omega * HZ_PER_RAD_S, curve.compliance, color=colors[i % len(colors)],
                    ls="--", lw=0.8, alpha=0.8,
                    label="describing function (H = 1)" if i == 0 else None)
    where = "at rest" if result.speed == 0.0 else f"feeding at {result.speed * 1e3:g} mm/s"
    ax.set_title(f"{result.axis}: work-piece compliance with LuGre pads, {where}")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("compliance x_wp / F [m/N]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return fig
