"""The figures of servotune.plots: the curves' data read back from the matplotlib Line2D
objects against closed forms written out here, axis labels with units, log axes where the
quantity spans decades."""

import math

import control
import numpy as np
import pytest
import two_mass_reference as ref
from matplotlib.lines import Line2D
from numpy.testing import assert_allclose

from servotune import plots, twomass
from servotune.design import ModePeaks
from servotune.frequency import analyse_loop
from servotune.friction.lugre import BIANCHI2014

HZ_PER_RAD_S = 1.0 / (2.0 * math.pi)


def _curves(ax):
    """The data lines of an axes (markers and guide lines of fewer than 3 points left out)."""
    return [line for line in ax.get_lines() if isinstance(line, Line2D)
            and np.asarray(line.get_xdata()).size > 2]


def test_bode_of_an_integrator_is_its_closed_form():
    # L = wc / s: |L| = wc / w (20 log10), phase -90 deg, crossover at wc, Ms = 1
    wc = 2 * math.pi * 30.0
    omega = np.geomspace(1.0, 1e4, 500)
    values = wc / (1j * omega)
    analysis = analyse_loop(control.ss(control.tf([wc], [1.0, 0.0])))
    fig = plots.plot_bode({"velocity": (omega, values)}, {"velocity": analysis}, title="t")
    ax_mag, ax_ph = fig.axes
    (mag,), (phase,) = _curves(ax_mag), _curves(ax_ph)
    assert_allclose(mag.get_xdata(), omega * HZ_PER_RAD_S, rtol=1e-15)
    assert_allclose(mag.get_ydata(), 20 * np.log10(wc / omega), rtol=1e-12, atol=1e-12)
    assert_allclose(phase.get_ydata(), -90.0, rtol=1e-12)
    assert ax_mag.get_xscale() == "log" and ax_ph.get_xscale() == "log"
    assert ax_mag.get_ylabel() == "|L| [dB]" and ax_ph.get_ylabel() == "phase of L [deg]"
    assert ax_ph.get_xlabel() == "frequency [Hz]"
    # the crossover marker sits at 0 dB and wc
    markers = [ln for ln in ax_mag.get_lines() if ln.get_marker() == "o"]
    assert len(markers) == 1
    assert_allclose(markers[0].get_xdata(), [wc * HZ_PER_RAD_S], rtol=1e-3)
    assert_allclose(markers[0].get_ydata(), [0.0])
    assert "PM 90.0 deg" in markers[0].get_label()


def test_compliance_plot_of_one_mode_is_its_receptance():
    # x/F = 1 / (k - m w^2 + j c w), drawn on log-log axes in Hz and m/N
    m, k, c = 200.0, 8e7, 4e3
    omega = np.geomspace(2 * math.pi, 2 * math.pi * 1e3, 800)
    h = 1.0 / (k - m * omega**2 + 1j * c * omega)
    wn = math.sqrt(k / m)
    fig = plots.plot_compliance([("one mode", omega, h)],
                                marks=[("peak", wn, 1.0 / (c * wn))])
    ax_mag, ax_ph = fig.axes
    (mag,), (phase,) = _curves(ax_mag), _curves(ax_ph)
    assert_allclose(mag.get_xdata(), omega * HZ_PER_RAD_S, rtol=1e-15)
    assert_allclose(mag.get_ydata(), 1.0 / np.hypot(k - m * omega**2, c * omega), rtol=1e-12)
    assert_allclose(phase.get_ydata(), np.degrees(np.arctan2(-c * omega, k - m * omega**2)),
                    atol=1e-9)
    assert (ax_mag.get_xscale(), ax_mag.get_yscale()) == ("log", "log")
    assert ax_mag.get_ylabel() == "|x/F| [m/N]" and ax_ph.get_ylabel() == "phase [deg]"
    assert ax_ph.get_xlabel() == "frequency [Hz]"
    assert mag.get_label() == "one mode"
    (mark,) = [ln for ln in ax_mag.get_lines() if ln.get_marker() == "v"]
    assert_allclose(mark.get_xdata(), [wn * HZ_PER_RAD_S])
    assert_allclose(mark.get_ydata(), [1 / (c * wn)])


def test_g_alpha_figure_is_the_closed_form():
    fig = plots.plot_g_alpha(mark=0.3)
    (ax,) = fig.axes
    (curve,) = _curves(ax)
    a = np.asarray(curve.get_xdata())
    assert a.min() > 0 and a.max() == pytest.approx(1.0)
    assert_allclose(curve.get_ydata(), [ref.g(x) for x in a], rtol=1e-12)
    (mark,) = [ln for ln in ax.get_lines() if ln.get_marker() == "o"]
    assert_allclose(mark.get_ydata(), [ref.g(0.3)], rtol=1e-12)
    assert ax.get_xlabel().endswith("[-]") and ax.get_ylabel().endswith("[-]")


def test_two_mass_figure_draws_the_closed_form_compliance_for_each_c():
    # x2/f2 of ground --C-- M1 --K-- M2 (paper sec 4.1); five curves C = Copt 10^k
    system = twomass.TwoMassSystem(m1=ref.M1, k=ref.K, alpha=ref.ALPHA)
    fig = plots.plot_two_mass_compliance(twomass.analyse_two_mass(system), f_max_hz=25.0)
    ax_mag, ax_ph = fig.axes[:2]
    curves = _curves(ax_mag)
    assert len(curves) == 5 and ax_mag.get_yscale() == "log"
    for i, line in enumerate(curves):
        c = ref.c_opt() * 10.0 ** (i - 2)
        w = 2 * math.pi * np.asarray(line.get_xdata())
        assert_allclose(line.get_ydata(), np.abs(ref.h(w, c)), rtol=1e-9)
        assert f"C = {c:.3e} N s/m" in line.get_label()
    # the fixed points, where every curve passes
    fixed = [ln for ln in ax_mag.get_lines() if ln.get_marker() == "s"]
    assert_allclose([ln.get_xdata()[0] for ln in fixed],
                    np.array(ref.fixed_points()) * HZ_PER_RAD_S, rtol=1e-12)
    assert_allclose([ln.get_ydata()[0] for ln in fixed],
                    np.abs(ref.h(ref.fixed_points(), 10 * ref.c_opt())), rtol=1e-9)
    assert ax_mag.get_ylabel().endswith("[m/N]") and ax_ph.get_ylabel().endswith("[deg]")
    assert ax_ph.get_xlabel() == "frequency [Hz]"


def test_stribeck_figure_is_the_steady_state_curve():
    # F_ss(v) = sgn(v) (Fc + (Fs - Fc) exp(-|v/vs|^delta)) + sigma2 v (Canudas de Wit 1995)
    p = BIANCHI2014
    v_meas = np.array([-0.3, -0.01, 0.02, 0.4])
    f_meas = np.array([-4000.0, -3900.0, 4100.0, 4300.0])
    fig = plots.plot_stribeck(p, v_meas, f_meas)
    (ax,) = fig.axes
    measured, model = [ln for ln in ax.get_lines() if ln.get_label() in (
        "measured", "LuGre steady state (fitted)")]
    assert_allclose(measured.get_xdata(), v_meas)
    assert_allclose(measured.get_ydata(), f_meas)
    v = np.asarray(model.get_xdata())
    expected = np.sign(v) * (p.fc + (p.fs - p.fc) * np.exp(-np.abs(v / p.vs) ** p.delta)) \
        + p.sigma2 * v
    assert_allclose(model.get_ydata(), expected, rtol=1e-12)
    assert ax.get_xlim() == pytest.approx((-0.4, 0.4))  # the data's largest |v|
    assert ax.get_xlabel() == "sliding velocity v [m/s]"
    assert ax.get_ylabel() == "friction force F [N]"


def test_mode_peaks_figure_draws_each_track_on_log_axes():
    c = np.geomspace(1e3, 1e7, 9)
    peaks = np.vstack([1e-7 * (c / 1e5 + 1e5 / c), 3e-8 * (c / 1e4 + 1e4 / c)])
    omega = 2 * math.pi * np.vstack([np.full(9, 300.0), np.full(9, 600.0)])  # [rad/s]
    tracks = ModePeaks(c_values=c, frequencies=omega, peaks=peaks, c_best=np.array([1e5, 1e4]),
                       c_chosen=1e5)
    fig = plots.plot_mode_peaks(tracks)
    (ax,) = fig.axes
    curves = _curves(ax)
    assert len(curves) == 2
    for line, row in zip(curves, peaks, strict=True):
        assert_allclose(line.get_xdata(), c)
        assert_allclose(line.get_ydata(), row)
    # each track's minimum is marked at its best C: x + 1/x is smallest at x = 1
    dots = [ln for ln in ax.get_lines() if ln.get_marker() == "o"]
    assert_allclose([d.get_xdata()[0] for d in dots], [1e5, 1e4])
    assert "mode at 300 Hz" in curves[0].get_label()  # labelled in Hz
    assert "mode at 600 Hz" in curves[1].get_label()
    assert (ax.get_xscale(), ax.get_yscale()) == ("log", "log")
    assert ax.get_xlabel() == "guide-way damping C [N s/m]" and ax.get_ylabel().endswith("[m/N]")
