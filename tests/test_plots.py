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


def test_bode_phase_is_wrapped_into_the_range_where_the_margins_are_read():
    # L = wc/s / (1 + s/p)^8: the phase falls from -90 to -810 deg; drawn it is wrapped into
    # (-360, 0] (each point the unwrapped phase less whole turns; the line broken where it
    # wraps), so that at the crossover it is PM - 180 deg and every phase crossover crosses
    # -180 deg; the phase axis spans plots.BODE_PHASE_RANGE_DEG
    wc, p = 2 * math.pi * 10.0, 2 * math.pi * 200.0
    loop = control.tf([wc], [1.0, 0.0]) * control.tf([1.0], [1.0 / p, 1.0]) ** 8
    omega = np.geomspace(1.0, 1e5, 2000)
    values = np.asarray(loop(1j * omega)).reshape(-1)
    analysis = analyse_loop(control.ss(loop))
    fig = plots.plot_bode({"velocity": (omega, values)}, {"velocity": analysis}, title="t",
                          regime="feeding 20 mm/s: sliding")
    ax_mag, ax_ph = fig.axes
    (phase,) = _curves(ax_ph)
    y = np.asarray(phase.get_ydata())
    unwrapped = np.degrees(np.unwrap(np.angle(values)))
    assert unwrapped[-1] < -700   # what was unreadable
    ok = np.isfinite(y)
    assert (~ok).sum() == 2   # the two wraps, at -360 and -720 deg
    assert np.all((y[ok] > -360.0) & (y[ok] <= 0.0))
    turns = (y[ok] - unwrapped[ok]) / 360.0
    assert_allclose(turns, np.round(turns), atol=1e-9)   # whole turns only
    lo, hi = plots.BODE_PHASE_RANGE_DEG
    assert (lo, hi) == (-360.0, 0.0)
    assert ax_ph.get_ylim()[0] <= lo and ax_ph.get_ylim()[1] >= hi
    assert ax_ph.get_ylim()[1] - ax_ph.get_ylim()[0] <= 400.0
    at = np.interp(np.log(analysis.crossover), np.log(omega), y)
    assert at == pytest.approx(analysis.phase_margin_deg - 180.0, abs=0.5)
    # the phase margin is a bar from -180 deg to the phase at the crossover
    f_c = analysis.crossover * HZ_PER_RAD_S
    (bar,) = [ln for ln in ax_ph.get_lines() if len(ln.get_xdata()) == 2
              and np.allclose(ln.get_xdata(), f_c)]
    assert_allclose(bar.get_ydata(), [-180.0, at], atol=0.5)
    # the gain margin is a bar at the phase crossover from |L| up to 0 dB
    f_pc = analysis.phase_crossover * HZ_PER_RAD_S
    (gm,) = [ln for ln in ax_mag.get_lines() if len(ln.get_xdata()) == 2
             and np.allclose(ln.get_xdata(), f_pc)]
    assert_allclose(gm.get_ydata(), [-analysis.gain_margin_db, 0.0], atol=0.05)
    # Ms is marked where the sensitivity peaks; the regime is named in title and caption
    (ms,) = [ln for ln in ax_mag.get_lines() if ln.get_marker() == "D"]
    assert_allclose(ms.get_xdata(), [analysis.ms_frequency * HZ_PER_RAD_S])
    assert "feeding 20 mm/s: sliding" in ax_mag.get_title()
    caption = plots.figure_caption(fig)
    assert "feeding 20 mm/s: sliding" in caption and 'solid (1): "velocity loop"' in caption
    assert f"PM {analysis.phase_margin_deg:.1f} deg" in caption and "dashed" not in caption


def test_mode_peaks_at_a_bound_and_a_spike_are_said_so():
    # one track falls all the way to the upper bound (no minimum inside): no "best C" there;
    # another has one point raised 20 times (6 times its larger neighbour): drawn as a cross,
    # not joined to the track
    c = np.geomspace(1e3, 1e8, 11)
    falling = 1e-7 * (1e3 / c) ** 0.1
    bowl = 3e-8 * (c / 1e5 + 1e5 / c)
    bowl[7] *= 20.0
    omega = 2 * math.pi * np.vstack([np.full(11, 60.0), np.full(11, 150.0)])
    tracks = ModePeaks(c_values=c, frequencies=omega, peaks=np.vstack([falling, bowl]),
                       c_best=np.array([1e8, 1e5]), c_chosen=1e4)
    fig = plots.plot_mode_peaks(tracks, bounds=(1e3, 1e8), axis_name="ax")
    (ax,) = fig.axes
    first, second = _curves(ax)
    assert "upper bound C = 1e+08 N s/m" in first.get_label()
    assert "best C" not in first.get_label() and "best C = 1e+05" in second.get_label()
    (end,) = [ln for ln in ax.get_lines() if ln.get_marker() == ">"]
    assert_allclose(end.get_xdata(), [1e8])
    assert np.isnan(second.get_ydata()[7])
    (cross,) = [ln for ln in ax.get_lines() if ln.get_marker() == "x"]
    assert_allclose(cross.get_xdata(), [c[7]])
    assert_allclose(cross.get_ydata(), [bowl[7]])
    caption = plots.figure_caption(fig)
    assert "upper bound C = 1e+08 N s/m" in caption and "Crosses (1)" in caption
