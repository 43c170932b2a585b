"""Amplitude-dependent compliance of the closed-loop axis with LuGre pads, by harmonic balance.

:func:`nonlinear_compliance` gives, per peak-to-peak work-piece force, the periodic response to
``F(t) = F_pp/2 cos(w t)`` over a band, followed by continuation
(:mod:`servotune.harmonic.continuation`) of the multi-harmonic balance
(:mod:`servotune.harmonic.balance`), standing still or feeding at a constant speed. The
compliance is the fundamental of the work-piece displacement per force amplitude, as the
paper's Table 3 (and :meth:`servotune.simulate.SimulationResult.sweep_envelope`) measure it.

Beside it, the linear predictions that bracket it (the paper's remarks A-C in one picture):
the presliding contact (pads locked by the bristle spring sigma0 and the dampers sigma1 and
sigma2), the viscous-only pads (the paper's "vd"), the LuGre linearisation about steady sliding
at the feed speed (when feeding), and the describing-function prediction (the same balance with
the fundamental only, H = 1).

References
----------
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 4.2, 5.3 (Table 3, remarks A-C).
M. Krack, J. Gross, "Harmonic Balance for Nonlinear Vibration Problems", Springer (2019).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..blas import one_thread
from ..closed_loop import axis_compliance
from ..peaks import BandPeak, band_peak, parabola_peak
from ..plant import Contact
from ..regimes import as_law
from ..units import HZ_PER_RAD_S
from .aft import samples_from_harmonics
from .balance import HarmonicSettings, PadBalance
from .continuation import Branch, ContinuationSettings, continue_in_frequency
from .linear import pad_receptance

__all__ = ["ComplianceCurve", "NonlinearCompliance", "nonlinear_compliance", "curve_peak",
           "presliding_guess", "refine_peak", "require_stable_regime", "DEFAULT_BAND"]

DEFAULT_BAND = (2.0 * math.pi * 10.0, 2.0 * math.pi * 100.0)   # the paper's sweep [rad/s]


def curve_peak(omega, compliance) -> tuple[float, float, int]:
    """Return the peak of a sampled curve: its frequency, its value and the largest sample.

    A parabola through the largest sample and its two neighbours places the peak between
    them, when the three frequencies increase, the parabola opens downwards and its vertex
    lies between the neighbours; otherwise the largest sample is the peak
    (:func:`servotune.peaks.parabola_peak`). Whether that is a resonance or the value at an
    edge of the band, :func:`servotune.peaks.band_peak` says.

    Parameters
    ----------
    omega : array_like, shape (K,)
        Frequencies [rad/s].
    compliance : array_like, shape (K,)
        Values [m/N].

    Returns
    -------
    omega_peak : float
        Frequency of the peak [rad/s].
    peak : float
        The peak [m/N] (the parabola's vertex value, or the largest sample).
    index : int
        Index of the largest sample.
    """
    return parabola_peak(omega, compliance)


@dataclass(frozen=True, eq=False)
class ComplianceCurve:
    """The periodic response at one force level along the band (SI).

    Attributes
    ----------
    force_pp : float
        Work-piece force, peak to peak [N].
    omega : numpy.ndarray
        Frequencies of the continuation points [rad/s].
    compliance : numpy.ndarray
        Fundamental work-piece displacement per force amplitude [m/N].
    pad_amplitude : numpy.ndarray
        Half the peak-to-peak pad displacement (largest pad, all harmonics) [m].
    resonance : float
        Frequency of the largest compliance [rad/s] (:func:`curve_peak`); a resonance only
        when it lies inside the band (:attr:`band_peak`).
    peak : float
        The largest compliance [m/N] (:func:`curve_peak`).
    pad_amplitude_at_peak : float
        Pad amplitude at the largest point of the curve [m].
    harmonics : int
        H, the harmonics of the balance.
    newton_iterations : int
        Newton iterations of the continuation and the peak refinement.
    wall_time : float
        Seconds spent on the curve.
    """

    force_pp: float
    omega: np.ndarray
    compliance: np.ndarray
    pad_amplitude: np.ndarray
    resonance: float
    peak: float
    pad_amplitude_at_peak: float
    harmonics: int
    newton_iterations: int
    wall_time: float

    @property
    def band_peak(self) -> BandPeak:
        """The largest compliance over the curve's band and whether it is a resonance
        (:func:`servotune.peaks.band_peak`: at the first or last frequency it is not)."""
        return band_peak(self.omega, self.compliance, unit="m/N")

    def to_dict(self) -> dict:
        """Return the curve as JSON-ready values (SI, Hz in ``_hz`` names).

        Returns
        -------
        dict
            The scalars (``force_pp_n``; ``resonance_hz`` and ``peak_compliance_m_per_n``,
            None when the largest value is at an edge of the band; ``peak_at_band_edge``,
            ``largest_compliance_m_per_n``, ``largest_at_hz`` and the other keys of
            :meth:`servotune.peaks.BandPeak.to_dict`; ``pad_amplitude_at_peak_m`` (at the
            largest value), ``harmonics``, ``points``, ``newton_iterations``,
            ``wall_time_s``) and the lists ``frequency_hz``, ``compliance_m_per_n`` and
            ``pad_amplitude_m``.
        """
        return {"force_pp_n": self.force_pp, **self.band_peak.to_dict("compliance_m_per_n"),
                "pad_amplitude_at_peak_m": self.pad_amplitude_at_peak,
                "harmonics": self.harmonics, "points": int(self.omega.size),
                "newton_iterations": self.newton_iterations, "wall_time_s": self.wall_time,
                "frequency_hz": (self.omega * HZ_PER_RAD_S).tolist(),
                "compliance_m_per_n": self.compliance.tolist(),
                "pad_amplitude_m": self.pad_amplitude.tolist()}


@dataclass(frozen=True, eq=False)
class NonlinearCompliance:
    """Compliance curves at several force levels with their linear references.

    Attributes
    ----------
    speed : float
        Feed speed [m/s] (0 at rest).
    curves : tuple of ComplianceCurve
        Multi-harmonic balance, one per force level.
    describing : tuple of ComplianceCurve
        The describing-function prediction (H = 1), one per force level (empty when not
        asked for).
    references : dict
        ``{name: (omega [rad/s], compliance [m/N])}`` of the linear models: ``"presliding"``,
        ``"viscous"`` and, when feeding, ``"sliding"`` (empty when not asked for).
    settings : HarmonicSettings
        Harmonics, AFT samples and tolerance of ``curves``.
    axis : str
        The axis' name.
    notes : tuple of str
        Remarks for the reports (none from :func:`nonlinear_compliance` itself).
    band : (float, float), optional
        The band [rad/s] the curves were continued over.
    """

    speed: float
    curves: tuple
    describing: tuple
    references: dict
    settings: HarmonicSettings
    axis: str = ""
    notes: tuple = field(default=())
    band: tuple | None = None

    def reference_peaks(self) -> dict:
        """Return the largest values of the linear references (resonances or not).

        Returns
        -------
        dict
            ``{name: (frequency [rad/s], largest compliance [m/N])}``; whether each is a
            resonance, :meth:`reference_band_peaks` says.
        """
        return {k: curve_peak(w, c)[:2] for k, (w, c) in self.references.items()}

    def reference_band_peaks(self) -> dict:
        """Return the peaks of the linear references by the rule of :mod:`servotune.peaks`.

        Returns
        -------
        dict
            ``{name: BandPeak}``: a largest value at an edge of the band is no resonance.
        """
        return {k: band_peak(w, c, unit="m/N") for k, (w, c) in self.references.items()}

    def to_dict(self) -> dict:
        """Return the result as JSON-ready values (SI, Hz in ``_hz`` names).

        Returns
        -------
        dict
            ``axis``, ``speed_m_per_s``, the settings (``harmonics``, ``aft_samples``,
            ``tolerance``), ``band_hz``, ``curves`` (:meth:`ComplianceCurve.to_dict`), the
            peaks of ``describing_function`` and ``linear_references`` (each with the keys of
            :meth:`servotune.peaks.BandPeak.to_dict`: ``resonance_hz`` is None when the
            largest value is at an edge of the band), and ``notes``.
        """
        name = "compliance_m_per_n"
        return {
            "axis": self.axis, "speed_m_per_s": self.speed,
            "band_hz": (None if self.band is None
                        else [self.band[0] * HZ_PER_RAD_S, self.band[1] * HZ_PER_RAD_S]),
            "harmonics": self.settings.harmonics, "aft_samples": self.settings.samples,
            "tolerance": self.settings.tolerance,
            "curves": [c.to_dict() for c in self.curves],
            "describing_function": [
                {"force_pp_n": c.force_pp, **c.band_peak.to_dict(name)}
                for c in self.describing],
            "linear_references": {
                k: p.to_dict(name) for k, p in self.reference_band_peaks().items()},
            "notes": list(self.notes)}

    def plot(self):
        """Plot the family of curves over the linear predictions.

        Returns
        -------
        matplotlib.figure.Figure
            The figure of :func:`~servotune.harmonic.plot.nonlinear_compliance_plot`.
        """
        from .plot import nonlinear_compliance_plot

        return nonlinear_compliance_plot(self)


def _pad_amplitudes(balance: PadBalance, branch) -> np.ndarray:
    out = np.empty(branch.omega.size)
    for i, y in enumerate(branch.y):
        x = samples_from_harmonics(balance.complex_of(y), balance.samples)
        out[i] = 0.5 * float(np.max(x.max(axis=1) - x.min(axis=1)))
    return out


def _compliance(balance: PadBalance, omega, y) -> float:
    return abs(balance.work_piece(y, omega)[0]) / balance.force_amplitude


def refine_peak(balance: PadBalance, branch: Branch, rounds: int = 3) -> Branch:
    """Return the branch with more points at the compliance peak.

    Each round adds a point at the vertex of the parabola through the compliance's largest
    point and its neighbours (:func:`curve_peak`), solved at that fixed frequency from the
    linear interpolation of the two points around it, so that the peak is resolved finer than
    the continuation steps. The rounds stop early when the largest point is at an end of the
    branch or the vertex lies within 1e-5 of its frequency (relative).

    Parameters
    ----------
    balance : PadBalance
        The balance equations of the branch.
    branch : Branch
        The continued branch.
    rounds : int
        Most points added (default 3).

    Returns
    -------
    Branch
        The branch with the points inserted in frequency order; ``iterations`` counts their
        Newton iterations too.

    Raises
    ------
    ConvergenceError
        If a fixed-frequency solve does not converge.
    """
    w, ys = list(branch.omega), list(branch.y)
    comp = [_compliance(balance, a, b) for a, b in zip(w, ys, strict=True)]
    iterations = branch.iterations
    for _ in range(rounds):
        vertex, _, i = curve_peak(w, comp)
        if not 0 < i < len(w) - 1 or abs(vertex - w[i]) <= 1e-5 * w[i]:
            break
        j = i + 1 if vertex > w[i] else i - 1
        lam = (vertex - w[i]) / (w[j] - w[i])
        y, n_it = balance.solve(vertex, (1 - lam) * ys[i] + lam * ys[j])
        iterations += n_it
        k = max(i, j)
        w.insert(k, vertex)
        ys.insert(k, y)
        comp.insert(k, _compliance(balance, vertex, y))
    return Branch(omega=np.array(w), y=np.array(ys), iterations=iterations,
                  rejected=branch.rejected)


def _curve(balance: PadBalance, band, continuation, y0=None) -> ComplianceCurve:
    t0 = time.perf_counter()
    branch = continue_in_frequency(balance, band[0], band[1], continuation, y0=y0)
    branch = refine_peak(balance, branch)
    comp = np.array([_compliance(balance, w, y) for w, y in zip(branch.omega, branch.y,
                                                                  strict=True)])
    pads = _pad_amplitudes(balance, branch)
    res, peak, i = curve_peak(branch.omega, comp)
    return ComplianceCurve(force_pp=2.0 * balance.force_amplitude, omega=branch.omega,
                           compliance=comp, pad_amplitude=pads, resonance=res, peak=peak,
                           pad_amplitude_at_peak=float(pads[i]),
                           harmonics=balance.harmonics, newton_iterations=branch.iterations,
                           wall_time=time.perf_counter() - t0)


def presliding_guess(balance: PadBalance, omega: float, params) -> np.ndarray:
    """Return a start of the balance at rest: the pads on the linear presliding contact.

    The friction of each pad is taken as the linear impedance of the law's presliding contact
    ``z = (k + j w d) / n`` (the axis totals shared by the n pads; LuGre: k = sigma0,
    d = sigma1 + sigma2), so that
    (1) with the fundamental only becomes ``(I + G_pp(j w) z) X_1 = G_pF(j w) F_a``.

    Parameters
    ----------
    balance : PadBalance
        The balance equations.
    omega : float
        Angular frequency [rad/s].
    params : FrictionLaw or LuGreParameters
        Axis-total friction law (its presliding spring [N/m] and damper [N s/m]).

    Returns
    -------
    numpy.ndarray, shape (n 2H,)
        The real unknowns of ``balance`` [m]: X_1 of each pad, the higher harmonics zero.
    """
    n = balance.n_pads
    g = balance.receptance(np.array([omega]))[:, :, 0]
    k, d = as_law(params).presliding()
    z = (k + 1j * omega * d) / n
    x = np.linalg.solve(np.eye(n) + g[:n, :n] * z, g[:n, n] * balance.force_amplitude)
    h = np.zeros((n, balance.harmonics), dtype=complex)
    h[:, 0] = x
    return balance.real_of(h)


def require_stable_regime(setup, speed: float = 0.0) -> None:
    """Refuse an axis whose linearised closed loop is unstable in the regime.

    Harmonic balance would return periodic solutions about an unstable state, which nobody can
    observe.

    Parameters
    ----------
    setup : servotune.simulate.setup.AxisSetup
        Structure, drive, pads and friction of the axis.
    speed : float
        Feed speed [m/s]: > 0 checks the law's linearisation about sliding at that speed,
        otherwise its presliding contact (at rest).

    Raises
    ------
    servotune.plant.UnstableLoopError
        (a ValueError) If the closed loop has a pole in the right half-plane (a digital
        drive: a growing multiplier of the sampled-data loop); the message names them.
    """
    from ..closed_loop import closed_loop

    law = setup.law
    if speed > 0.0:
        contact = Contact.sliding(law.sliding_system(speed), speed)
        what = (f"closed loop feeding at {speed * 1e3:g} mm/s ({law.name} linearised about "
                f"sliding)")
    else:
        contact = Contact.stiction(*law.presliding(), 0.0)
        what = f"closed loop at rest ({law.name} presliding contact)"
    # a digital drive is checked as the sampled-data loop it is (the balance models it so)
    closed_loop(setup.structure, setup.drive, contact, setup.pads).require_stable(what)


@one_thread
def nonlinear_compliance(setup, forces_pp, speed: float = 0.0, band=DEFAULT_BAND,
                         settings: HarmonicSettings | None = None,
                         continuation: ContinuationSettings | None = None, law=None,
                         references: bool = True, describing: bool = True,
                         progress=None) -> NonlinearCompliance:
    """Compliance curves of the axis with nonlinear guide-way friction at force levels.

    Parameters
    ----------
    setup : servotune.simulate.setup.AxisSetup
        Structure, drive, pads and friction of the axis
        (:func:`~servotune.simulate.setup.axis_setup`).
    forces_pp : sequence of float
        Work-piece force levels, peak to peak [N].
    speed : float
        Feed speed [m/s] (0: at rest; the pads slide on average at this speed).
    band : (float, float)
        Frequency band [rad/s], ``0 < start < end`` (default 10-100 Hz, the paper's sweep;
        :func:`servotune.analysis.default_band` gives an axis' band that holds its work-piece
        modes). A curve whose largest value lies at the band's first or last frequency has no
        resonance in it (:attr:`ComplianceCurve.band_peak`).
    settings : HarmonicSettings, optional
        Harmonics, AFT samples, tolerance (default 9 harmonics, 64 samples); the
        describing-function curves take H = 1 with the default samples for it (32).
    continuation : ContinuationSettings, optional
        Step control of the continuation.
    law : object, optional
        The pad friction law (axis totals): any law with ``periodic_force`` (see
        :func:`~servotune.harmonic.aft.periodic_friction_force`); default the friction law of
        ``setup`` (LuGre by :func:`~servotune.friction.periodic.lugre_periodic_force` with
        its exact Jacobian).
    references : bool
        Also the linear references (presliding, viscous-only and, when ``speed > 0``, sliding
        at ``speed``), by :func:`servotune.closed_loop.axis_compliance` on 901 frequencies.
    describing : bool
        Also the describing-function curves (H = 1).
    progress : callable, optional
        Called with the number of force levels done (after each level's curves).

    Returns
    -------
    NonlinearCompliance
        One curve per force level (and its describing-function curve), the linear references,
        the settings and the axis' name.

    Raises
    ------
    ValueError
        If a force level is not finite and > 0, the speed is not finite and >= 0, the band is
        not ``0 < start < end``, or the structure's damping is not modal
        (:func:`~servotune.harmonic.linear.pad_receptance`).
    ConvergenceError
        If a branch cannot be followed.

    Notes
    -----
    The work-piece force is ``F(t) = F_pp/2 cos(w t)``; the compliance at w is
    ``|X_wp,1| / (F_pp / 2)``, the fundamental of the work-piece displacement by equation (2)
    of :mod:`servotune.harmonic.balance`. Each curve is continued from ``band[0]`` (at rest
    started from :func:`presliding_guess`) and its peak refined (:func:`refine_peak`). The
    stability of the regime is not checked here (:func:`require_stable_regime` does).

    See Also
    --------
    servotune.simulate.simulate : the time simulation that checks it.
    """
    forces = [float(f) for f in np.atleast_1d(forces_pp)]
    if not forces or not all(math.isfinite(f) and f > 0 for f in forces):
        raise ValueError(f"force levels must be finite and > 0 N peak to peak, got {forces_pp!r}")
    speed = float(speed)
    if not (math.isfinite(speed) and speed >= 0.0):
        raise ValueError(f"the feed speed must be finite and >= 0 m/s, got {speed!r}")
    settings = settings or HarmonicSettings()
    law = setup.law if law is None else law
    rec = pad_receptance(setup.structure, setup.drive, setup.pads)
    curves, df = [], []
    for j, fpp in enumerate(forces):
        for h, out in ((settings.harmonics, curves), (1, df)):
            if h == 1 and not describing:
                continue
            s = dataclasses.replace(settings, harmonics=h, samples=None) if h == 1 else settings
            bal = PadBalance(rec, law, 0.5 * fpp, speed, s)
            y0 = presliding_guess(bal, band[0], setup.law) if speed == 0.0 else None
            out.append(_curve(bal, band, continuation, y0))
        if progress is not None:
            progress(j + 1)
    refs = {}
    if references:
        omega = np.linspace(band[0], band[1], 901)
        models = {"presliding": Contact.stiction(*setup.law.presliding(), 0.0),
                  "viscous": Contact.viscous(setup.viscous)}
        if speed > 0.0:
            models["sliding"] = Contact.sliding(setup.law.sliding_system(speed), speed)
        for name, contact in models.items():
            refs[name] = (omega, np.abs(axis_compliance(setup.structure, omega, setup.drive,
                                                        contact, setup.pads)[0]))
    return NonlinearCompliance(speed=speed, curves=tuple(curves), describing=tuple(df),
                               references=refs, settings=settings, axis=setup.name,
                               band=(float(band[0]), float(band[1])))
