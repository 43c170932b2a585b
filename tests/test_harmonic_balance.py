"""Harmonic balance of the closed-loop axis (servotune.harmonic) against independent references:

* the linear closed loop of servotune.frequency.port_compliance (a second implementation of the
  coupling) for the pad receptance and for a balance whose law is linear (viscous pads);
* the time simulation (servotune.simulate, LuGre at every pad), stepped sine to steady state,
  at 50, 600 and 2000 N peak to peak, at rest and feeding at 30 mm/s, on the bundled axis;
* the describing-function response of a single-DOF oscillator with a Jenkins (elasto-plastic)
  element in closed form (Caughey 1960; Krack and Gross 2019, sec 2.4);
* convergence in the number of harmonics;
* the paper's Table 3 regimes (Bianchi et al. 2014): locked near 57 Hz at small force, 32 Hz
  while feeding, reduced oscillation at 2000 N standing.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.optimize import brentq

from servotune.axis import load_axis
from servotune.closed_loop import axis_compliance
from servotune.frequency import port_compliance
from servotune.harmonic import (
    ContinuationSettings,
    HarmonicSettings,
    PadBalance,
    curve_peak,
    harmonics_from_samples,
    nonlinear_compliance,
    pad_receptance,
    periodic_friction_force,
    presliding_guess,
)
from servotune.harmonic.stepped import stepped_sine
from servotune.plant import Contact
from servotune.simulate import LuGreFriction, ViscousFriction
from servotune.simulate.setup import axis_setup
from servotune.structure.model import ModalModel
from servotune.units import HZ_PER_RAD_S, RAD_S_PER_HZ

PAPER_AXIS = load_axis("models/paper_x_axis")


@pytest.fixture(scope="module")
def setup():
    """The bundled axis with the paper's continuous drive (its Table 3 model)."""
    return axis_setup(PAPER_AXIS.with_continuous_drive())


@pytest.mark.parametrize("continuous", [True, False])
def test_pad_receptance_closed_by_a_viscous_contact_is_port_compliance(continuous):
    axis = PAPER_AXIS.with_continuous_drive() if continuous else PAPER_AXIS
    s = axis_setup(axis)
    rec = pad_receptance(s.structure, s.drive, s.pads)
    omega = RAD_S_PER_HZ * np.linspace(5.0, 300.0, 40)
    c, n = 5e4, len(s.pads)
    g = rec(omega)
    ours = []
    for k, w in enumerate(omega):
        z = 1j * w * c / n                      # f_p = -z x_p per pad
        xp = np.linalg.solve(np.eye(n) + g[:n, :n, k] * z, g[:n, n, k])
        ours.append(g[n, n, k] - g[n, :n, k] @ (z * xp))
    ref = axis_compliance(s.structure, omega, s.drive, Contact.viscous(c), s.pads)[0]
    # continuous: the same coupling, to rounding; sampled: the fundamental of the free-pad
    # receptance closed by a continuous contact leaves out what the holds' aliases feed back
    # through the contact (below 1e-6 of the fundamental here) and the receptance is
    # interpolated from its table (1e-6)
    tol = 1e-9 if continuous else 1e-5
    assert_allclose(ours, ref, rtol=tol, atol=tol * np.abs(ref).max())


def test_a_linear_law_balances_to_the_linear_compliance(setup):
    # viscous pads are linear: the balance must give the linear closed loop at every harmonic
    law = ViscousFriction(2e5)
    rec = pad_receptance(setup.structure, setup.drive, setup.pads)
    bal = PadBalance(rec, law, 300.0, 0.0, HarmonicSettings(3))
    omega = RAD_S_PER_HZ * np.array([20.0, 32.0, 57.0])
    ref = port_compliance(setup.structure, omega, setup.drive, Contact.viscous(2e5),
                          setup.pads)[0]
    for w, r in zip(omega, ref, strict=True):
        y, _ = bal.solve(w)
        x = bal.work_piece(y, w)
        assert abs(x[0] / 300.0 - r) <= 1e-7 * abs(r)
        assert np.abs(x[1:]).max() <= 1e-9 * abs(x[0])        # no higher harmonics


def test_a_law_object_gives_the_balance_of_its_parameters(setup):
    # the simulation's LuGre law class (through its own periodic_force, when it has one, and
    # finite-difference Jacobians) against the LuGre parameters (lugre_periodic_force and its
    # exact Jacobian): two routes to the same periodic solution
    rec = pad_receptance(setup.structure, setup.drive, setup.pads)
    w = RAD_S_PER_HZ * 55.0
    out = []
    for law in (LuGreFriction(setup.lugre), setup.lugre):
        bal = PadBalance(rec, law, 300.0, 0.0, HarmonicSettings(5))
        y, _ = bal.solve(w, presliding_guess(bal, w, setup.lugre))
        out.append(bal.work_piece(y, w))
    assert_allclose(out[0], out[1], rtol=1e-6, atol=1e-6 * abs(out[1][0]))


# --- against the time simulation --------------------------------------------------------------

CASES = [(50.0, 0.0), (600.0, 0.0), (2000.0, 0.0), (50.0, 0.03), (600.0, 0.03), (2000.0, 0.03)]


@pytest.mark.parametrize("force_pp, speed", CASES)
def test_peak_and_resonance_agree_with_the_time_simulation(setup, force_pp, speed):
    """HB (9 harmonics, continuation) against a stepped sine of the LuGre time simulation at
    five frequencies around the HB resonance (+-0.5, +-1 Hz), each to a steady state within
    1e-3. Tolerances: pointwise 0.5 % (the stepped sine's steady-state tolerance 1e-3, the
    simulation's friction tolerance 1e-4 and the HB truncation < 1e-4, see the harmonics
    test, with margin); the peak of the same five-point parabola 0.5 % and 0.1 Hz; the
    stepped parabola against the continuation's refined peak 1 % and 0.25 Hz (a parabola over
    +-1 Hz of a resonance whose half-power band is ~3 Hz)."""
    result = nonlinear_compliance(setup, [force_pp], speed=speed, references=False,
                                  describing=False)
    curve = result.curves[0]
    grid = curve.resonance + RAD_S_PER_HZ * np.array([-1.0, -0.5, 0.0, 0.5, 1.0])
    sim = stepped_sine(setup, force_pp, grid, speed, tolerance=1e-3)
    rec = pad_receptance(setup.structure, setup.drive, setup.pads)
    bal = PadBalance(rec, setup.lugre, 0.5 * force_pp, speed,
                     HarmonicSettings(9))
    hb = []
    y = presliding_guess(bal, grid[0], setup.lugre) if speed == 0 else None
    for w in grid:
        y, _ = bal.solve(w, y)
        hb.append(abs(bal.work_piece(y, w)[0]) / bal.force_amplitude)
    assert_allclose(hb, sim.compliance, rtol=5e-3)
    w_hb, p_hb, _ = curve_peak(grid, hb)
    w_sim, p_sim, _ = curve_peak(grid, sim.compliance)
    assert abs(w_hb - w_sim) * HZ_PER_RAD_S <= 0.1
    assert abs(p_hb - p_sim) <= 5e-3 * p_sim
    assert abs(curve.resonance - w_sim) * HZ_PER_RAD_S <= 0.25
    assert abs(curve.peak - p_sim) <= 1e-2 * p_sim


# --- the paper's Table 3 regimes ----------------------------------------------------------------

def test_the_regimes_of_table3(setup):
    """Bianchi et al. (2014), Table 3 and remarks A-C: standing at 50 N the pads stay locked
    (resonance 57 Hz, the model's presliding peak); feeding at 30 mm/s the 32 Hz resonance at
    every force; at 2000 N standing the oscillation falls well below the 50 N one (the paper:
    1.9e-8 against 5.96e-8 m/N)."""
    rest = nonlinear_compliance(setup, [50.0, 2000.0], describing=False)
    feed = nonlinear_compliance(setup, [50.0, 2000.0], speed=0.03, describing=False,
                                references=False)
    locked_w, locked_peak = rest.reference_peaks()["presliding"]
    small, large = rest.curves
    assert abs(small.resonance * HZ_PER_RAD_S - 57.0) <= 1.5
    assert abs(small.resonance - locked_w) * HZ_PER_RAD_S <= 0.2
    assert small.peak == pytest.approx(locked_peak, rel=0.02)
    assert large.peak < 0.7 * small.peak
    for c in feed.curves:
        assert abs(c.resonance * HZ_PER_RAD_S - 32.0) <= 1.0


# --- harmonics ------------------------------------------------------------------------------------

def test_convergence_in_the_number_of_harmonics(setup):
    """At 2000 N standing near resonance (the most nonlinear case: the pads stick and slip each
    cycle) the compliance settles as harmonics are added: the change from H to the reference
    H = 21 falls below 1e-4 by H = 9 (the default) and is far smaller than the describing
    function's (H = 1) error."""
    rec = pad_receptance(setup.structure, setup.drive, setup.pads)
    w = RAD_S_PER_HZ * 56.0
    values = {}
    for h in (1, 3, 5, 9, 21):
        bal = PadBalance(rec, setup.lugre, 1000.0, 0.0, HarmonicSettings(h))
        y, _ = bal.solve(w, presliding_guess(bal, w, setup.lugre))
        values[h] = abs(bal.work_piece(y, w)[0])
    err = {h: abs(values[h] / values[21] - 1) for h in (1, 3, 5, 9)}
    assert err[9] < 1e-4
    assert err[9] < 0.05 * err[1]
    assert err[5] < err[1]


# --- Jenkins oscillator: the describing function in closed form ------------------------------

class JenkinsElement:
    """Elasto-plastic (Jenkins) element: a spring k in series with a Coulomb slider of limit
    force fs, as a law with ``periodic_force`` (the interface harmonic balance calls)."""

    nonlinear = True

    def __init__(self, k: float, fs: float) -> None:
        self.k, self.fs = k, fs

    def periodic_force(self, velocity, period, share=1.0):
        v = np.asarray(velocity, dtype=float)
        n = v.size
        dx = 0.5 * (v + np.roll(v, -1)) * period / n       # displacement increments
        k, fs = self.k * share, self.fs * share
        f, out = 0.0, np.empty(n)
        for _ in range(2):                                  # the second period is periodic
            for i in range(n):
                out[i] = f
                f = min(max(f + k * dx[i], -fs), fs)
        return out


def _jenkins_describing_amplitude(m, c, kl, k, fs, force, w):
    """Amplitude A of ``m x'' + c x' + kl x + F_J = force cos(w t)`` by the describing function
    of the Jenkins element (Caughey 1960): with cos(b) = 1 - 2 fs/(k A) for A > fs/k,
    ``N(A) = k/pi (b - sin(2b)/2) + j k/pi sin(b)^2``, else N = k; A solves
    ``A |kl - m w^2 + j w c + N(A)| = force``."""
    def n_of(a):
        if a <= fs / k:
            return k + 0j
        b = math.acos(1 - 2 * fs / (k * a))
        return k / math.pi * (b - 0.5 * math.sin(2 * b)) + 1j * k / math.pi * math.sin(b) ** 2

    def g(a):
        return a * abs(kl - m * w * w + 1j * w * c + n_of(a)) - force

    return brentq(g, 1e-12, 10 * force / (c * w) + force / kl, xtol=1e-16, rtol=1e-13)


def test_a_jenkins_oscillator_follows_its_describing_function():
    m, kl, k, fs, zeta = 10.0, 4e5, 1.2e6, 30.0, 0.01
    structure = ModalModel([[m]], [[kl]], ["mass.x"], damping_ratio=zeta)
    c = 2 * zeta * math.sqrt(kl * m)
    rec = pad_receptance(structure, None, ["mass.x"], force_dof="mass.x")
    law = JenkinsElement(k, fs)
    force = 40.0
    bal = PadBalance(rec, law, force, 0.0, HarmonicSettings(1, samples=1024))
    omega = np.linspace(math.sqrt(kl / m) * 0.8, math.sqrt((kl + k) / m) * 1.2, 25)
    ours, y = [], None
    for w in omega:
        y, _ = bal.solve(w, y)
        ours.append(abs(bal.complex_of(y)[0, 0]))
    ref = [_jenkins_describing_amplitude(m, c, kl, k, fs, force, w) for w in omega]
    assert_allclose(ours, ref, rtol=2e-3)
    # the peak lies between the slipping (kl) and the stuck (kl + k) linear resonances
    i = int(np.argmax(ours))
    assert math.sqrt(kl / m) < omega[i] < math.sqrt((kl + k) / m)
    # the law was reached through the duck-typed interface
    assert periodic_friction_force(law, np.zeros(4), 0.1).shape == (4,)


@pytest.mark.parametrize("make, message", [
    (lambda: HarmonicSettings(max_iterations=2.5), "max_iterations"),
    (lambda: ContinuationSettings(arc_max=-1.0), "arc_max"),
    (lambda: ContinuationSettings(max_iterations=0), "max_iterations"),
    (lambda: harmonics_from_samples(np.ones(8), 4), "harmonics 1 to 3"),
])
def test_settings_and_sample_counts_that_cannot_work_are_refused(make, message):
    # 8 samples resolve the harmonics up to 3 (Nyquist): the 4th would come back doubled
    with pytest.raises(ValueError, match=message):
        make()
