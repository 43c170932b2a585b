"""The verdict on a tuned design: does the nonlinear axis do what the design claims?

A design is tuned on linear models of the guide ways (:mod:`servotune.regimes`); its claim is,
for each operating regime, the worst work-piece compliance peak of that regime's models. The
verdict holds a design ``verified`` only when

(a) the linear check holds on dense grids in every regime model (stability, Ms, the loop
    hierarchy, the integral time, the thrust budget: :mod:`servotune.tuning.verify`), and
(b) in every cutting regime the time simulation of the axis with its friction law at every pad
    (LuGre in the paper, or any law of :mod:`servotune.friction.law`; the design's C as the
    law's viscous part, for LuGre sigma2; the digital drive's delays as in the linear model)
    peaks at or below the claim within ``nonlinear_tolerance`` (default 30 %), at the
    process force (the cutting-force amplitude at the required depth), at a larger force (3
    times) and, standing, at a smaller one (a quarter); stays stable (the response decays once
    the force stops); shows no stick-slip limit cycle while feeding (a run at the feed speed
    without force settles); keeps the motor torque within its peak; and has no peak at an edge
    of the swept band; and
(c) in every cutting regime the steady periodic response by harmonic balance
    (:func:`harmonic_scan`, :data:`SCAN_LEVELS` of the process force and the simulated levels)
    peaks at or below the claim within the same tolerance. A sweep passes a resonance before
    the response has built up and reads its peak low; the periodic response is the steady
    state (checked against a stepped sine of the time simulation in the tests); and
(d) over the friction spread (:func:`verdict_spread`: ``[tuning] friction_spread``, else the
    identified set's own variation, ``[friction] variation``), at every corner of its box: the
    regime's linear models are stable with the design, the thrust budget fits, and the
    periodic responses at the simulated levels stay within the tolerance of the claim; the
    corner that peaks highest in each regime is simulated in time as in (b), around its
    peak. Over a spread a regime's claim is the worst linear peak over the nominal friction
    and every corner (the tuner's own claim is kept beside it).

The sweep band is the requirements band widened to hold every mode that carries work-piece
motion and every predicted peak before and after. The sweep is slow where the linear models
predict resonances (a steady-state peak, see :func:`servotune.simulate.scenario.sweep_plan`);
a peak found elsewhere is swept again slowly there. The initial design is simulated the same
way (when it is stable), so that the realised improvement, nonlinear before over nonlinear
after, stands beside the linear one.

What it covered is :attr:`Verdict.coverage` (and one line of it, :attr:`Verdict.coverage_text`,
in :attr:`Verdict.headline`); what it does not cover is listed in :attr:`Verdict.not_checked`
(the inside of the spread's box, forces outside the levels simulated and scanned, the
stability of the periodic responses, the regimes of the axis file only, the start of a move
and the motor's heating).
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass, field

import numpy as np

from .closed_loop import axis_compliance
from .friction.law import FrictionLaw
from .friction.lugre import LuGreParameters
from .regimes import FrictionSpread, as_law, friction_spread
from .simulate.result import SimulationError
from .simulate.scenario import constant_speed, planned_sweep, sweep_plan
from .simulate.simulator import NonlinearAxis, simulate
from .simulate.truncation import Truncation
from .units import HZ_PER_RAD_S

__all__ = ["Simulation", "CornerVerdict", "RegimeVerdict", "Verdict", "Evidence",
           "nonlinear_verdict",
           "verdict_spread", "sweep_band",
           "predicted_resonances", "simulate_sweep", "DEFAULT_PROCESS_FORCE", "HarmonicPeak",
           "harmonic_scan", "harmonic_scans", "SCAN_LEVELS"]

#: Force [N peak to peak] of the standing regime when the process force is unknown.
DEFAULT_PROCESS_FORCE = 600.0
#: Force levels relative to the process force: smaller, process, larger.
FORCE_LEVELS = (0.25, 1.0, 3.0)
FEEDING_LEVELS = (1.0, 3.0)
#: Force levels (times the process force) of the harmonic-balance scan of every regime, besides
#: the simulated levels: the steady periodic response is judged at each.
SCAN_LEVELS = (0.1, 0.25, 0.5, 1.0, 1.7, 3.0)
SETTLE = 0.6       # [s] of motion before a feeding sweep (smooth start 0.2 s, then settling)
RING_DOWN = 0.3    # [s] without force after a sweep
EDGE = 0.03        # a peak within 3 % (in frequency) of a band edge is at the edge


@dataclass(frozen=True)
class Simulation:
    """One nonlinear run of the verdict (SI; frequencies in Hz under ``_hz`` names)."""

    regime: str
    design: str                 # "before" or "after"
    kind: str                   # "sweep" or "stick-slip"
    force_pp: float
    speed: float
    band_hz: tuple[float, float]
    friction: str = "nominal"   # or the corner of the friction spread
    peak: float | None = None               # [m/N]
    resonance_hz: float | None = None
    pad_amplitude: float | None = None      # [m] at the resonance
    max_torque: float | None = None         # [N m]
    decays: bool | None = None
    at_edge: bool | None = None
    stick_slip: bool | None = None
    speed_ripple: float | None = None       # (max - min)/mean of the slide speed
    error: str | None = None
    duration: float | None = None           # simulated [s]
    wall_time: float | None = None          # [s]
    envelope: tuple = field(default=(), repr=False)   # (f_hz, m_per_n) arrays, for figures

    def to_dict(self) -> dict:
        """Return the run as JSON-ready data (without the envelope).

        Returns
        -------
        dict
            The fields under names with their units (``force_pp_n``, ``peak_m_per_n``,
            ``simulated_s``, ...).
        """
        return {"regime": self.regime, "design": self.design, "kind": self.kind,
                "friction": self.friction,
                "force_pp_n": self.force_pp, "speed_m_per_s": self.speed,
                "band_hz": list(self.band_hz), "peak_m_per_n": self.peak,
                "resonance_hz": self.resonance_hz, "pad_amplitude_m": self.pad_amplitude,
                "max_torque": self.max_torque, "decays": self.decays, "at_edge": self.at_edge,
                "stick_slip": self.stick_slip, "speed_ripple": self.speed_ripple,
                "error": self.error, "simulated_s": self.duration, "wall_time_s": self.wall_time}


@dataclass(frozen=True)
class HarmonicPeak:
    """The peak of the periodic response at one force level, by harmonic balance.

    Parameters
    ----------
    force_pp : float
        Work-piece force, peak to peak [N].
    peak : float
        Largest compliance over the regime's band [m/N].
    resonance_hz : float
        Where [Hz].
    pad_amplitude : float
        Mean pad vibration amplitude there [m].
    """

    force_pp: float
    peak: float
    resonance_hz: float
    pad_amplitude: float

    def to_dict(self) -> dict:
        """Return the peak as JSON-ready data.

        Returns
        -------
        dict
            The fields with their units in the names.
        """
        return {"force_pp_n": self.force_pp, "peak_m_per_n": self.peak,
                "resonance_hz": self.resonance_hz, "pad_amplitude_m": self.pad_amplitude}


def harmonic_scan(nl_axis: NonlinearAxis, speed: float, forces_pp, band_hz):
    """Return the peaks of the periodic responses at force levels, by harmonic balance.

    The axis' steady periodic response to a harmonic work-piece force at each level, continued
    over the band (:func:`servotune.harmonic.nonlinear_compliance`: 9 harmonics, LuGre by the
    alternating frequency-time scheme; against the stepped-sine time simulation within 6e-4 on
    the bundled axis, docs/harmonic_balance.md). A tenth of a second per level.

    Parameters
    ----------
    nl_axis : NonlinearAxis
        The design's nonlinear axis (LuGre pads).
    speed : float
        Feed speed [m/s] (0: standing).
    forces_pp : sequence of float
        Force levels, peak to peak [N].
    band_hz : (float, float)
        The band [Hz].

    Returns
    -------
    tuple of HarmonicPeak
        One per level, in the order given.

    Raises
    ------
    servotune.harmonic.ConvergenceError
        When a branch cannot be followed.
    servotune.plant.UnstableLoopError
        When the regime's linear part is unstable.
    """
    from .harmonic import nonlinear_compliance
    from .simulate.setup import AxisSetup

    law = nl_axis.friction
    setup = AxisSetup("design", nl_axis.structure, nl_axis.drive, tuple(nl_axis.pads), None,
                      float(law.viscous_part), law=law)
    band = (2 * math.pi * band_hz[0], 2 * math.pi * band_hz[1])
    result = nonlinear_compliance(setup, list(forces_pp), speed=speed, band=band,
                                  references=False, describing=False)
    return tuple(HarmonicPeak(c.force_pp, c.peak, c.resonance * HZ_PER_RAD_S,
                              c.pad_amplitude_at_peak) for c in result.curves)


def _harmonic_or_why(nl_axis, speed, forces, band):
    """The harmonic scan, or () and why it could not be made."""
    from .harmonic import ConvergenceError
    from .plant import UnstableLoopError

    try:
        return harmonic_scan(nl_axis, speed, forces, band), ""
    except (ConvergenceError, UnstableLoopError, ValueError) as exc:
        return (), f"harmonic balance not available: {str(exc).splitlines()[0]}"


def harmonic_scans(nl_axes, speed: float, forces_pp, band_hz) -> list:
    """Return the harmonic scans of several axes, each with why it is missing.

    A picklable top-level function for executors: one job scans every corner of a friction
    spread, so that the tabulated receptance of the drive is made once per job.

    Parameters
    ----------
    nl_axes : sequence of NonlinearAxis
        The axes (one design, the friction of each corner).
    speed : float
        Feed speed [m/s] (0: standing).
    forces_pp : sequence of float
        Force levels, peak to peak [N].
    band_hz : (float, float)
        The band [Hz].

    Returns
    -------
    list of (tuple of HarmonicPeak, str)
        Per axis its peaks (:func:`harmonic_scan`; empty when harmonic balance could not
        follow a branch or the linear part is unstable) and why they are missing.
    """
    return [_harmonic_or_why(a, speed, forces_pp, band_hz) for a in nl_axes]


@dataclass(frozen=True)
class CornerVerdict:
    """One corner of the friction spread in one regime: its linear claim, its periodic
    responses by harmonic balance and, for the regime's worst corner, its time simulations.

    Parameters
    ----------
    label : str
        The corner (``"fs +258 N, sigma0 -1.17e9 N/m, sigma1 +1.3e6 N s/m"``).
    friction : LuGreParameters or FrictionLaw
        Its friction (axis totals; the viscous part as identified, the design's C replaces
        it).
    claimed_peak : float or None
        Its own linear claim: the worst compliance peak of the regime's models with this
        friction [m/N] (inf: a model is unstable with the design).
    harmonic : tuple of HarmonicPeak
        The periodic responses at the regime's force levels.
    harmonic_note : str
        Why harmonic balance is missing, if it is.
    simulations : tuple of Simulation
        The time simulations of this corner (the regime's worst corner only).
    holds : bool
        Whether the regime's claim holds at this corner.
    reason : str
        ``"holds"`` or why not.
    """

    label: str
    friction: LuGreParameters | FrictionLaw
    claimed_peak: float | None
    harmonic: tuple[HarmonicPeak, ...] = ()
    harmonic_note: str = ""
    simulations: tuple[Simulation, ...] = ()
    holds: bool = True
    reason: str = "holds"

    @property
    def harmonic_peak(self) -> HarmonicPeak | None:
        """The largest periodic response over the force levels (None without any)."""
        return max(self.harmonic, key=lambda h: h.peak) if self.harmonic else None

    @property
    def simulated_peak(self) -> float | None:
        """The largest simulated sweep peak [m/N] (None when not simulated)."""
        worst = _worst(self.simulations)
        return None if worst is None else worst[0]

    def to_dict(self) -> dict:
        """Return the corner as JSON-ready data.

        Returns
        -------
        dict
            ``label``, ``friction`` (its LuGre parameters, SI), ``claimed_peak_m_per_n``,
            ``harmonic_peak_m_per_n``, ``simulated_peak_m_per_n``, ``holds``, ``reason``, the
            periodic responses and the simulations.
        """
        worst = self.harmonic_peak
        return {"label": self.label, "friction": self.friction.to_dict(),
                "claimed_peak_m_per_n": self.claimed_peak,
                "harmonic_peak_m_per_n": None if worst is None else worst.peak,
                "simulated_peak_m_per_n": self.simulated_peak, "holds": self.holds,
                "reason": self.reason,
                "harmonic_balance": [h.to_dict() for h in self.harmonic],
                "harmonic_balance_note": self.harmonic_note,
                "simulations": [s.to_dict() for s in self.simulations]}


@dataclass(frozen=True)
class Evidence:
    """A point of the nonlinear axis that breaks a regime's claim (what a figure marks).

    Parameters
    ----------
    method : str
        ``"harmonic balance"`` (a steady periodic response) or ``"simulated sweep"``.
    friction : str
        ``"nominal"`` or the corner of the friction spread.
    force_pp : float
        Work-piece force, peak to peak [N].
    resonance_hz : float
        Where the response peaks [Hz].
    peak : float
        The peak compliance [m/N].
    why : str
        What is wrong there: ``"above the claim"``, ``"at the band edge"`` or ``"does not
        decay"``.
    """

    method: str
    friction: str
    force_pp: float
    resonance_hz: float
    peak: float
    why: str


@dataclass(frozen=True)
class RegimeVerdict:
    """The claim of one regime against the nonlinear axis, before and after.

    ``claimed_peak`` is the claim judged: the worst linear compliance peak over the regime's
    models with the nominal friction and with every corner of the friction spread (the tuner's
    own claim is ``claimed_peak_tuned``). ``nonlinear_peak_after`` is the worst simulated peak
    over the nominal friction and the corners simulated; ``nonlinear_peak_after_nominal`` and
    ``nonlinear_peak_before`` are of the nominal friction (the realised improvement compares
    them). ``simulations`` and ``harmonic`` are of the nominal friction; ``corners`` holds the
    spread's.
    """

    name: str
    speed: float
    models: tuple[str, ...]
    claimed_peak: float | None
    claimed_peak_before: float | None
    nonlinear_peak_before: float | None
    nonlinear_peak_after: float | None
    band_hz: tuple[float, float]
    holds: bool
    reason: str
    explanation: str = ""
    simulations: tuple[Simulation, ...] = ()
    harmonic: tuple[HarmonicPeak, ...] = ()
    harmonic_note: str = ""
    claimed_peak_tuned: float | None = None
    nonlinear_peak_after_nominal: float | None = None
    corners: tuple[CornerVerdict, ...] = ()

    @property
    def worst_corner(self) -> CornerVerdict | None:
        """The corner whose periodic response peaks highest (None without a spread)."""
        scanned = [c for c in self.corners if c.harmonic]
        return max(scanned, key=lambda c: c.harmonic_peak.peak) if scanned else None

    def evidence_against(self, tolerance: float) -> tuple[Evidence, ...]:
        """Return the peaks of the nonlinear axis that break this regime's claim.

        The same tests as the verdict's: a periodic response (harmonic balance) or a simulated
        sweep of the tuned design above ``claimed_peak`` (1 + ``tolerance``), at the nominal
        friction or at a corner of the spread, and a simulated sweep whose peak lies at an
        edge of its band or whose oscillation does not decay. Reasons without a peak (an
        unstable corner, stick-slip while feeding) have no point here; ``reason`` names them.

        Parameters
        ----------
        tolerance : float
            The verdict's tolerance on the claim (:attr:`Verdict.tolerance`).

        Returns
        -------
        tuple of Evidence
            Largest peak first; empty when the regime holds.
        """
        claim = self.claimed_peak
        limit = (claim * (1 + tolerance) if claim is not None and math.isfinite(claim)
                 else math.inf)
        sources = [("nominal", self.harmonic,
                    [s for s in self.simulations if s.design == "after"])]
        sources += [(c.label, c.harmonic, c.simulations) for c in self.corners]
        out = []
        for friction, harmonic, sims in sources:
            out += [Evidence("harmonic balance", friction, h.force_pp, h.resonance_hz, h.peak,
                             "above the claim") for h in harmonic if h.peak > limit]
            for s in sims:
                if s.kind != "sweep" or s.peak is None or s.resonance_hz is None:
                    continue
                why = ("above the claim" if s.peak > limit else "at the band edge"
                       if s.at_edge else "does not decay" if s.decays is False else None)
                if why is not None:
                    out.append(Evidence("simulated sweep", friction, s.force_pp,
                                        s.resonance_hz, s.peak, why))
        return tuple(sorted(out, key=lambda e: -e.peak))

    @property
    def realised_improvement(self) -> float | None:
        after = (self.nonlinear_peak_after_nominal if self.nonlinear_peak_after_nominal
                 is not None else self.nonlinear_peak_after)
        if self.nonlinear_peak_before is None or not after:
            return None
        return self.nonlinear_peak_before / after

    @property
    def linear_improvement(self) -> float | None:
        claim = self.claimed_peak_tuned if self.claimed_peak_tuned is not None else \
            self.claimed_peak
        if self.claimed_peak_before is None or not claim:
            return None
        if not math.isfinite(self.claimed_peak_before):
            return None
        return self.claimed_peak_before / claim

    def to_dict(self) -> dict:
        """Return the regime's verdict as JSON-ready data.

        Returns
        -------
        dict
            The fields under names with their units, the realised (nonlinear before over
            after, nominal friction) and linear (claim before over the tuner's claim after)
            improvements, the simulations and the corners of the friction spread.
        """
        worst = self.worst_corner
        return {"name": self.name, "speed_m_per_s": self.speed, "models": list(self.models),
                "claimed_peak_m_per_n": self.claimed_peak,
                "claimed_peak_tuned_m_per_n": self.claimed_peak_tuned,
                "claimed_peak_before_m_per_n": self.claimed_peak_before,
                "nonlinear_peak_before_m_per_n": self.nonlinear_peak_before,
                "nonlinear_peak_after_m_per_n": self.nonlinear_peak_after,
                "nonlinear_peak_after_nominal_m_per_n": self.nonlinear_peak_after_nominal,
                "realised_improvement": self.realised_improvement,
                "linear_improvement": self.linear_improvement,
                "band_hz": list(self.band_hz), "holds": self.holds, "reason": self.reason,
                "explanation": self.explanation,
                "simulations": [s.to_dict() for s in self.simulations],
                "harmonic_balance": [h.to_dict() for h in self.harmonic],
                "harmonic_balance_note": self.harmonic_note,
                "worst_corner": None if worst is None else worst.label,
                "corners": [c.to_dict() for c in self.corners]}


@dataclass(frozen=True, kw_only=True)
class Verdict:
    """Whether a design is verified, and what the verification covered.

    ``coverage`` says what the nonlinear checks ran over (the friction spread, the forces,
    the feeds, the duty of the thrust budget; see :func:`nonlinear_verdict`) and
    ``coverage_text`` says it in one line; :attr:`headline` is the verdict line.
    """

    verified: bool
    linear_holds: bool
    nonlinear_holds: bool | None
    regimes: tuple[RegimeVerdict, ...]
    tolerance: float
    reasons: tuple[str, ...]
    checked: tuple[str, ...] = ()
    not_checked: tuple[str, ...] = field(default=())
    coverage: dict = field(default_factory=dict)
    coverage_text: str = ""

    @property
    def label(self) -> str:
        return "VERIFIED" if self.verified else "NOT VERIFIED"

    @property
    def headline(self) -> str:
        """The verdict line: the label, what holds or why not, and what it covers.

        Returns
        -------
        str
            ``"VERIFIED over ...: <what holds>"`` or ``"NOT VERIFIED over ...: <reasons>"``
            (``over ...`` is :attr:`coverage_text`).
        """
        over = f" {self.coverage_text}" if self.coverage_text else ""
        if self.verified:
            what = ("the linear checks hold in every regime model and the nonlinear axis holds "
                    "the claim in every regime" if self.nonlinear_holds is not None
                    else (self.checked[0] if self.checked else "the linear checks hold"))
            return f"VERIFIED{over}: {what}"
        reasons = "; ".join(self.reasons) if self.reasons else "see the checks"
        return f"NOT VERIFIED{over}: {reasons}"

    def to_dict(self) -> dict:
        """Return the verdict as JSON-ready data.

        Returns
        -------
        dict
            ``verified``, ``label``, ``headline``, what held, the tolerance, the reasons,
            what was checked and what not, the ``coverage`` and ``coverage_text``, and each
            regime's verdict.
        """
        return {"verified": self.verified, "label": self.label, "headline": self.headline,
                "linear_holds": self.linear_holds, "nonlinear_holds": self.nonlinear_holds,
                "tolerance": self.tolerance, "reasons": list(self.reasons),
                "checked": list(self.checked), "not_checked": list(self.not_checked),
                "coverage": self.coverage, "coverage_text": self.coverage_text,
                "regimes": [r.to_dict() for r in self.regimes]}


# ----------------------------------------------------------------------------------- band
def _local_maxima(omega, mag, significance=0.1, count=6):
    inner = np.nonzero((mag[1:-1] >= mag[:-2]) & (mag[1:-1] > mag[2:]))[0] + 1
    inner = inner[mag[inner] >= significance * mag.max()] if inner.size else inner
    return inner[np.argsort(-mag[inner])][:count]


def predicted_resonances(omega, h) -> list[tuple[float, float]]:
    """Return the frequency and damping ratio of the peaks of a compliance curve.

    The peaks are the local maxima of ``|h|`` that reach 10 % of the largest, at most 6,
    largest first. The damping ratio comes from the half-power width,
    ``zeta = (w_hi - w_lo) / (2 w_peak)`` with ``|h(w_lo)|, |h(w_hi)| <= |h(w_peak)|/sqrt(2)``
    the nearest such points on either side, at least 0.003; 0.02 when the width cannot be
    read within the grid; at most 0.3.

    Parameters
    ----------
    omega : numpy.ndarray
        Angular frequencies [rad/s], increasing.
    h : numpy.ndarray
        Complex (or magnitude) compliance on ``omega`` [m/N].

    Returns
    -------
    list of (float, float)
        ``(frequency [Hz], damping ratio)`` of each peak.
    """
    mag = np.abs(h)
    out = []
    for i in _local_maxima(omega, mag):
        half = mag[i] / math.sqrt(2.0)
        lo = i
        while lo > 0 and mag[lo] > half:
            lo -= 1
        hi = i
        while hi < mag.size - 1 and mag[hi] > half:
            hi += 1
        zeta = 0.02
        if mag[lo] <= half and mag[hi] <= half and lo < i < hi:
            zeta = max(0.5 * (omega[hi] - omega[lo]) / omega[i], 0.003)
        out.append((float(omega[i] * HZ_PER_RAD_S), float(min(zeta, 0.3))))
    return out


def sweep_band(requirement_band, resonances_hz, modes_hz=()) -> tuple[float, float]:
    """Return the requirements band widened to hold the predicted peaks and work-piece modes.

    Each frequency f widens the band to ``[f / 1.25, 1.25 f]`` at least (25 % to spare); the
    result is clipped to 1 Hz .. 2 kHz.

    Parameters
    ----------
    requirement_band : (float, float)
        The requirements band [Hz].
    resonances_hz : sequence of float
        Predicted peak frequencies [Hz].
    modes_hz : sequence of float
        Frequencies [Hz] of the modes carrying work-piece motion.

    Returns
    -------
    (float, float)
        The sweep band [Hz].
    """
    lo, hi = requirement_band
    for f in list(resonances_hz) + list(modes_hz):
        lo, hi = min(lo, f / 1.25), max(hi, f * 1.25)
    return max(lo, 1.0), min(hi, 2000.0)


def _wp_modes_hz(axis, band) -> list[float]:
    """Frequencies [Hz] of the modes carrying work-piece X motion (5 % or more of its static
    compliance), with the pads locked and free, below 2.5 times the band's top."""
    out = []
    for pads in ("locked", "free"):
        try:
            model = axis.configuration(pads=pads, motor="free")
            share = model.participation("wp.x")
            f = model.natural_frequencies() * HZ_PER_RAD_S
        except (ValueError, KeyError):
            continue
        out += [float(x) for x, s in zip(f, share, strict=True)
                if s >= 0.05 and 0.5 < x < 2.5 * band[1]]
    return out


# ----------------------------------------------------------------------------- simulations
def simulate_sweep(axis: NonlinearAxis, force_pp: float, band_hz, resonances, speed: float,
                   torque_limit: float | None, tags: dict, max_passes: int = 2) -> Simulation:
    """Run one sweep of the verdict, slow where peaks are predicted or found.

    A picklable top-level function for executors. The sweep
    (:func:`servotune.simulate.scenario.sweep_plan`) is slow where ``resonances`` predict
    peaks; when the envelope's peak lies outside the slow windows, the sweep is run again
    with a slow window there (at most ``max_passes`` runs). The time step is at most 0.25 ms
    and 1/16 of the period at the band's top, a divisor of 0.25 ms. A moving axis first runs
    0.6 s at ``speed``; every sweep ends with 0.3 s without force. The response decays when
    the peak-to-peak work-piece motion over the last 0.1 s is at most 1.05 times that over
    the first 0.1 s without force; the peak is at an edge within 3 % of either end of the band.

    Parameters
    ----------
    axis : NonlinearAxis
        The axis with the design and LuGre pads.
    force_pp : float
        Peak-to-peak work-piece force [N].
    band_hz : (float, float)
        Swept band [Hz].
    resonances : sequence of (float, float)
        Predicted peaks ``(frequency [Hz], damping ratio)`` (see
        :func:`predicted_resonances`).
    speed : float
        Feed speed [m/s] during the sweep (0: standing).
    torque_limit : float or None
        Peak motor torque [N m]; a run exceeding it reports an error.
    tags : dict
        ``regime`` and ``design`` of the :class:`Simulation`.
    max_passes : int
        Largest number of runs, >= 1.

    Returns
    -------
    Simulation
        The sweep's peak [m/N], resonance [Hz], pad amplitude [m], largest motor torque,
        decay and band-edge flags and the envelope; a failed integration gives ``error`` set
        and ``decays=False``.
    """
    import time

    if max_passes < 1:
        raise ValueError(f"simulate_sweep: max_passes must be >= 1, got {max_passes!r}")
    wall = time.perf_counter()
    step = min(2.5e-4, 1.0 / (16.0 * band_hz[1]))
    step = 2.5e-4 / math.ceil(2.5e-4 / step)
    resonances = list(resonances)
    # what the sweep is judged by (a long sweep's memory is its histories)
    recorded = ["wp_x", *(p.replace(".", "_") for p in axis.pads)] + (
        ["torque"] if axis.drive is not None else [])
    for _ in range(max_passes):
        plan = sweep_plan(band_hz[0], band_hz[1], 0.5 * force_pp, resonances)
        settle = SETTLE if speed else 0.0
        scenario = planned_sweep(force_pp, plan, speed=speed, settle=settle,
                                 ring_down=RING_DOWN)
        n = round(scenario.duration / step)
        scenario = dataclasses.replace(scenario, duration=n * step)
        try:
            result = simulate(axis, scenario, step=step, record_step=step, record=recorded)
        except SimulationError as exc:
            return Simulation(**tags, kind="sweep", force_pp=force_pp, speed=speed,
                              band_hz=tuple(band_hz), error=str(exc).split(";")[0],
                              decays=False, duration=scenario.duration,
                              wall_time=time.perf_counter() - wall)
        env = result.sweep_envelope(t_min=settle + 0.02 * plan.duration)
        f_peak = env.resonance_hz
        if plan.in_slow_window(f_peak) or not math.isfinite(f_peak):
            break
        resonances.append((f_peak, 0.02))
    # the pads' amplitude in the cycle of the work piece's resonance (same window, same cycle)
    t_min = settle + 0.02 * plan.duration
    pads = [result.sweep_envelope(p.replace(".", "_"), t_min=t_min) for p in axis.pads]
    pad_amp = float(np.mean([p.amplitude[int(np.argmin(np.abs(p.frequency - env.resonance)))]
                             for p in pads]))
    t = result.t
    y = result["wp_x"]
    t_end = scenario.duration - RING_DOWN
    late = t > scenario.duration - 0.1
    early = (t > t_end) & (t <= t_end + 0.1)
    decays = bool(np.ptp(y[late]) <= 1.05 * np.ptp(y[early]) + 1e-15)
    torque = float(np.abs(result["torque"]).max()) if "torque" in result.signals else None
    at_edge = bool(f_peak <= band_hz[0] * (1 + EDGE) or f_peak >= band_hz[1] / (1 + EDGE))
    keep = np.unique(np.linspace(0, env.frequency.size - 1, min(env.frequency.size, 600))
                     .astype(int))
    envelope = (env.frequency[keep] * HZ_PER_RAD_S, env.amplitude[keep])
    return Simulation(**tags, kind="sweep", force_pp=force_pp, speed=speed,
                      band_hz=tuple(band_hz), peak=float(env.peak), resonance_hz=float(f_peak),
                      envelope=envelope,
                      pad_amplitude=pad_amp * 0.5 * force_pp, max_torque=torque,
                      decays=decays, at_edge=at_edge, duration=scenario.duration,
                      wall_time=time.perf_counter() - wall,
                      error=(None if torque_limit is None or torque is None
                             or torque <= torque_limit else
                             f"the motor torque reaches {torque:.3g} N m, above its peak "
                             f"{torque_limit:.3g} N m"))


def simulate_feeding(axis: NonlinearAxis, speed: float, tags: dict,
                     duration: float = 1.6) -> Simulation:
    """The axis fed at ``speed`` without force: does the slide settle to a steady speed, or do
    the pads stick and slip?"""
    import time

    wall = time.perf_counter()
    try:
        result = simulate(axis, constant_speed(speed, duration),
                          record=[f"v_{p.replace('.', '_')}" for p in axis.pads])
    except SimulationError as exc:
        return Simulation(**tags, kind="stick-slip", force_pp=0.0, speed=speed,
                          band_hz=(0.0, 0.0), stick_slip=True, error=str(exc).split(";")[0],
                          duration=duration, wall_time=time.perf_counter() - wall)
    late = result.t > duration - 0.5
    v = np.mean([result[f"v_{p.replace('.', '_')}"][late] for p in axis.pads], axis=0)
    ripple = float(np.ptp(v) / max(abs(np.mean(v)), 1e-12))
    stick = bool(v.min() <= 0.1 * speed or ripple > 0.2)
    return Simulation(**tags, kind="stick-slip", force_pp=0.0, speed=speed, band_hz=(0.0, 0.0),
                      stick_slip=stick, speed_ripple=ripple, duration=duration,
                      wall_time=time.perf_counter() - wall)


def simulated_structure(axis, problem=None) -> Truncation:
    """The structure the verdict simulates: the axis' own without the fixed-interface modes far
    above the band the verdict sweeps (up to 2.5 times the requirements band's top, at most
    2 kHz) and the drive's sampling
    (:func:`servotune.simulate.truncation.simulation_structure`)."""
    from .plant import WP_DOFS
    from .simulate.truncation import simulation_structure

    source = axis if problem is None else problem
    drive = source.drive
    ports = [d for d in WP_DOFS if d in axis.structure.dofs] + list(axis.pads)
    rate = 0.0
    if drive is not None:
        ports += [d for d in (drive.motor.rotor, drive.motor.stator, drive.encoder) if d]
        if not drive.digital.is_continuous:
            rate = 1.0 / drive.sampling.current_period
    lo, hi = (b * HZ_PER_RAD_S for b in source.requirements.band)
    return simulation_structure(axis.structure, ports, min(2.5 * hi, 2000.0), rate,
                                max(min(lo, 1.0), 0.1))


def design_axis(axis, problem, design, friction=None) -> NonlinearAxis:
    """The nonlinear axis of a design: the pads with the axis' friction law (or ``friction``,
    a law or LuGre parameters) with its viscous part the design's C, the design's drive with
    full velocity feed-forward (the axis follows its feed without lag), the structure without
    the modes far above what the verdict excites (:func:`simulated_structure`)."""
    drive = dataclasses.replace(problem.drive_for(design), velocity_feedforward=1.0)
    law = as_law(axis.friction.law if friction is None else friction)
    return NonlinearAxis(simulated_structure(axis, problem).structure, drive, axis.pads,
                         law.with_viscous(float(design.c)))


# --------------------------------------------------------------------------------- verdict
def _claims(problem, performance, regime) -> tuple[float | None, tuple[str, ...]]:
    if performance is None:
        return None, ()
    models = [m for m in performance.models if m.model.regime == regime and m.model.cutting]
    if not models:
        return None, ()
    if any(not m.stable for m in models):
        return math.inf, tuple(m.model.name for m in models)
    return max(m.peak_compliance for m in models), tuple(m.model.name for m in models)


def _regime_resonances(problem, designs, regime, omega):
    out = []
    for design in designs:
        if design is None:
            continue
        drive = problem.drive_for(design)
        for m in problem.regimes:
            if m.regime != regime:
                continue
            h = axis_compliance(problem.structure, omega, drive, m.contact(design.c),
                                problem.pads)[0]
            out += predicted_resonances(omega, h)
    return out


def _explain(regime, kind, improvement, active) -> str:
    if improvement is None or improvement >= 1.1:
        return ""
    if kind == "standing":
        return ("standing still the guide ways stick at these forces: the pads act as the stiff "
                "presliding contact (sigma0), so the viscous C in parallel moves little and the "
                "drive gains barely reach the work-piece mode; levers: a friction level that "
                "lets the pads slip at the process amplitude (see the friction damper of the "
                "realisation of C), or the structure itself (fixture stiffness, a damper on the "
                "work-piece mode)")
    binding = [a for a in active if a.startswith(("thrust", "loop hierarchy", "Ms", "Ti",
                                                  "current"))]
    return ("while feeding the sliding contact is damped by C and the velocity loop"
            + (f"; what binds: {', '.join(binding)}" if binding else "")
            + "; levers: more C (a stronger motor or a lower rapid speed or acceleration "
              "relaxes the thrust budget) or a faster velocity loop (shorter sample times)")


# ------------------------------------------------------------------------ friction spread
def verdict_spread(axis) -> FrictionSpread | None:
    """Return the friction spread the verdict checks an axis over, or None.

    ``[tuning] friction_spread`` when given (the spread the tuning covers too), else the
    identified set's own variation (``[friction] variation``, or a named set's measured one);
    see :func:`servotune.regimes.friction_spread`.

    Parameters
    ----------
    axis : Axis
        The axis description.

    Returns
    -------
    FrictionSpread or None
        None without LuGre friction or without either.
    """
    if axis.friction is None:
        return None
    t = axis.tuning
    return friction_spread(axis.friction.lugre, dict(t.friction_spread),
                           dict(t.friction_variation))


def _receptance_compliance(receptance, model, c, omega) -> np.ndarray:
    """|x_wp / F| with the model's linear pad contact (total impedance Z_0 + jwC shared by the
    pads) closed over the closed-loop receptance with the pads free:
    ``x_p = (I + G_pp z)^-1 G_pF F``, ``x_wp = G_wF F - G_wp z x_p`` (as the linear start of
    harmonic balance, :func:`servotune.harmonic.compliance.presliding_guess`)."""
    g = receptance(omega)
    n = g.shape[0] - 1
    z = (model.impedance(omega) + 1j * omega * c) / n
    a = np.eye(n) + np.moveaxis(g[:n, :n], -1, 0) * z[:, None, None]
    x = np.linalg.solve(a, np.moveaxis(g[:n, n], -1, 0)[..., None])[..., 0]
    return np.abs(g[n, n] - z * np.einsum("jk,kj->k", g[n, :n], x))


def _corner_levels(levels) -> list[float]:
    """The force level harmonic balance scans at a spread corner: the largest of the
    regime's simulated levels (three times the process force), where the friction is the most
    nonlinear; at and below the process force the pads stay near their linearisation, which
    the corner's linear claim checks (on the bundled axis' tuned design, scanned at both
    levels: at the process force the periodic response lay between 5.4 % below and 0.6 %
    above each corner's linear claim, against the tolerance of 30 %)."""
    return sorted(levels)[-1:]


def _corner_claim(problem, drive, receptance, models, c, omega) -> tuple[float, str]:
    """The worst compliance peak of a regime's models with one friction, and why there is
    none (a model unstable with the design: inf)."""
    from .closed_loop import closed_loop
    from .frequency import peak
    from .plant import UnstableLoopError

    worst = 0.0
    for model in models:
        loop = closed_loop(problem.structure, drive, model.contact(c), problem.pads)
        try:
            loop.require_stable(what=f"closed loop ({model.name})")
        except UnstableLoopError as exc:
            text = str(exc).splitlines()[0]
            grows = re.search(r"grows at [^,;)]*", text)
            kind = dataclasses.replace(model, sample="nominal").name.split(": ", 1)[-1]
            return math.inf, f"{kind}: {grows.group(0) if grows else text}"
        if receptance is not None:
            h = _receptance_compliance(receptance, model, c, omega)
        else:
            h = np.abs(loop.compliance(omega, problem.force, [problem.force])[0])
        worst = max(worst, peak(omega, h)[0])
    return worst, ""


def _run_checks(sims, band, speed, claim, tol) -> list[str]:
    """What the runs of one friction find wrong: errors, growth, band edges, stick-slip, and a
    peak above the claim beyond the tolerance."""
    why = []
    for s in sims:
        what = f"{s.kind} at {s.force_pp:g} N p-p" if s.kind == "sweep" else "feeding"
        if s.error:
            why.append(f"{what}: {s.error}")
        if s.kind == "sweep" and s.decays is False:
            why.append(f"{what}: the oscillation does not decay after the force stops")
        if s.at_edge:
            why.append(f"{what}: the peak at {s.resonance_hz:.1f} Hz lies at the edge of the "
                       f"swept band {s.band_hz[0]:.3g}-{s.band_hz[1]:.3g} Hz")
        if s.stick_slip:
            ripple = "" if s.speed_ripple is None else f" (speed ripple {s.speed_ripple:.0%})"
            why.append(f"stick-slip while feeding at {speed * 1e3:.3g} mm/s{ripple}")
    worst = _worst(sims)
    if claim is not None and math.isfinite(claim) and worst is not None:
        if worst[0] > claim * (1 + tol):
            s = worst[1]
            why.append(f"the nonlinear axis peaks at {s.peak:.3g} m/N ({s.resonance_hz:.1f} "
                       f"Hz, {s.force_pp:.4g} N p-p), {s.peak / claim - 1:.0%} above the "
                       f"claim {claim:.3g} m/N (tolerance {tol:.0%})")
    return why


def _corner_jobs(row, name, speed, levels, band, nominal_res, nominal_peak,
                 torque_limit) -> list:
    """The time simulations of a corner: its worst periodic response swept again in time
    around its peak ([f/1.25, 1.25 f]; slow there for the damping of the nearest predicted
    nominal resonance, scaled by the nominal periodic peak over the corner's, as a single
    mode's peak 1/(2 zeta k) scales) and, feeding, a run at the feed speed; without harmonic
    balance, a sweep at every level over the regime's band."""
    tags = {"regime": name, "design": "after", "friction": row["label"]}
    jobs = []
    if row["scan"]:
        worst = max(row["scan"], key=lambda h: h.peak)
        f = worst.resonance_hz
        narrow = sweep_band((f, f), [f])
        near = [r for r in nominal_res if narrow[0] <= r[0] <= narrow[1]]
        zeta = min(near, key=lambda r: abs(r[0] - f))[1] if near else 0.02
        if nominal_peak:
            zeta = min(max(zeta * min(nominal_peak / worst.peak, 1.0), 0.003), 0.3)
        jobs.append((simulate_sweep, (row["axis"], float(worst.force_pp), narrow,
                                      [(f, zeta), *near], speed, torque_limit, tags)))
    else:
        for force in levels:
            jobs.append((simulate_sweep, (row["axis"], float(force), band, nominal_res, speed,
                                          torque_limit, tags)))
    if speed > 0:
        jobs.append((simulate_feeding, (row["axis"], speed, tags)))
    return jobs


def _spread_thrust(problem, box, design) -> list[str]:
    """The thrust budget's cases at each corner of the spread that do not fit."""
    if problem.thrust is None or box is None:
        return []
    out = []
    for label, params in box.corners():
        budget = dataclasses.replace(problem.thrust, friction=params)
        for case in budget.cases(design.c):
            if not case.fits:
                out.append(f"thrust budget, {label}: {case.name} needs {case.needed / 1e3:.3g} "
                           f"kN of {case.usable / 1e3:.3g} kN usable")
    return out


def _coverage(box, regimes_judged, process, levels_of, corner_levels_of, band_of, problem,
              simulated, default_process) -> tuple[dict, str]:
    """What the nonlinear checks ran over, as data and in one line."""
    speeds = sorted(v for _, v in regimes_judged if v > 0)
    standing = any(v == 0 for _, v in regimes_judged)
    forces = sorted({f for fs in levels_of.values() for f in fs})
    corner_forces = sorted({f for fs in corner_levels_of.values() for f in fs})
    multiples = [min(forces) / process, max(forces) / process] if forces else []
    duty = ([c.name for c in problem.thrust.cases(0.0)] if problem.thrust is not None else [])
    coverage = {
        "friction_spread": None if box is None else box.to_dict(),
        "regimes": [name for name, _ in regimes_judged],
        "process_force_pp_n": process, "process_force_defaulted": default_process,
        "forces_pp_n": forces, "corner_forces_pp_n": corner_forces,
        "force_multiples_of_process": multiples,
        "feeds_m_per_s": speeds, "standing": standing,
        "band_hz": {name: list(b) for name, b in band_of.items()},
        "duty": duty, "simulated": simulated, "friction_law": _law_name(problem)}
    if box is None:
        text = "at the nominal friction only (no friction spread given)"
    else:
        n = len(box.corners())
        text = f"over the friction spread ({n} corners: {box.describe()})"
    if multiples:
        lo, hi = multiples
        text += (f", forces {lo:.3g}-{hi:.3g} x the process force ({process:.4g} N p-p)"
                 if hi > lo else f", forces {lo:.3g} x the process force ({process:.4g} N p-p)")
    feeds = " and ".join(f"{v * 1e3:.3g}" for v in speeds)
    if speeds:
        text += f", feeds {feeds} mm/s" + (" and standing" if standing else "")
    elif standing:
        text += ", standing"
    return coverage, text


# --------------------------------------------------------------------------------- verdict
def nonlinear_verdict(axis, result, executor=None, forces=None, band_hz=None,
                      speeds=None, simulate_before: bool = True, progress=None,
                      spread="axis") -> Verdict:
    """Return the verdict on a tuning result (see the module docstring).

    Parameters
    ----------
    axis : Axis
        The axis description (needs ``[friction]`` and ``[drive]``).
    result : TuningResult
        The tuning result with its linear checks before and after.
    executor : concurrent.futures.Executor, optional
        Runs the simulations in parallel.
    forces : sequence of float, optional
        Peak-to-peak forces [N] for every regime instead of the process force and its smaller
        and larger ones.
    band_hz : (float, float), optional
        The sweep band instead of the one from the axis.
    speeds : sequence of float, optional
        Judge only the standing regime and the feeding regimes at these speeds [m/s]; each
        must have its regime model in ``result`` (:func:`servotune.design.check_design` with
        ``feed_speeds`` builds them), so that every regime judged has a linear claim.
    simulate_before : bool
        Also simulate the initial design (for the realised improvement), when its linear
        models are stable.
    progress : callable, optional
        ``progress(done, total)`` after each simulation.
    spread : FrictionSpread, None or "axis"
        The friction spread to check over: ``"axis"`` (default) the axis' own
        (:func:`verdict_spread`), None the nominal friction only.

    Returns
    -------
    Verdict
        ``verified`` when the linear check holds (``result.success``, and the thrust budget
        at every corner of the spread) and every regime holds on the nonlinear axis at the
        nominal friction and at every corner.

    Raises
    ------
    ValueError
        If a speed of ``speeds`` has no feeding regime model in ``result``.

    Notes
    -----
    Over a friction spread (:class:`servotune.regimes.FrictionSpread`), a regime's claim is
    the worst linear compliance peak of its models over the nominal friction (the tuner's
    claim, with any friction samples it tuned for) and every corner of the box (each corner's
    models closed over the closed-loop receptance, as harmonic balance uses it, after a
    stability check of the closed loop). Every corner's periodic response is found by
    harmonic balance at the regime's simulated force levels; the corner that peaks highest is
    simulated in time (a sweep around its peak at its worst level, and a feeding run), as is
    any corner harmonic balance cannot follow (at every level, over the regime's band). A
    corner holds when its linear models are stable, its periodic responses and runs stay
    within the tolerance of the regime's claim and its runs decay, stay off the band's edges,
    keep the torque and do not stick and slip.
    """
    from .harmonic.linear import pad_receptance

    problem = result.problem
    req = problem.requirements
    reasons = list(result.reasons)
    op = axis.operation
    default_process = not (op is not None and op.process_force_pp)
    process = DEFAULT_PROCESS_FORCE if default_process else op.process_force_pp
    speed_of = {m.regime: m.speed for m in problem.regimes}
    regimes = list(dict.fromkeys(m.regime for m in problem.regimes if m.cutting))
    for model, _ in result.excluded:
        if model.cutting and model.regime not in regimes:
            regimes.append(model.regime)
            speed_of[model.regime] = model.speed
    if speeds is not None:
        chosen = [name for name in regimes if speed_of[name] == 0.0]
        for v in speeds:
            match = [name for name in regimes if speed_of[name] > 0.0
                     and math.isclose(speed_of[name], float(v), rel_tol=1e-9)]
            if not match:
                raise ValueError(f"no regime model feeds at {v * 1e3:.4g} mm/s: build the "
                                 "result with check_design(..., feed_speeds=...) so that the "
                                 "regime has a linear claim")
            chosen += [name for name in match if name not in chosen]
        regimes = chosen
    box = verdict_spread(axis) if isinstance(spread, str) else spread
    corners = box.corners() if box is not None else ()
    before_ok = result.before.stable and simulate_before
    omega = 2 * math.pi * np.geomspace(0.5, 2500.0, 6000)
    modes = _wp_modes_hz(axis, np.array(req.band) * HZ_PER_RAD_S)
    torque_limit = None
    if problem.drive is not None and problem.drive.limits is not None:
        torque_limit = problem.drive.limits.torque_peak
    jobs, scans = [], []
    regime_info = {}
    for name in regimes:
        speed = speed_of.get(name, 0.0)
        claim, models = _claims(problem, result.after, name)
        claim_before, _ = _claims(problem, result.before, name)
        res = _regime_resonances(problem, [result.initial if result.before.stable else None,
                                           result.design], name, omega)
        band = tuple(band_hz) if band_hz is not None else sweep_band(
            np.array(req.band) * HZ_PER_RAD_S, [f for f, _ in res], modes)
        levels = (forces if forces is not None else
                  [process * k for k in (FORCE_LEVELS if speed == 0 else FEEDING_LEVELS)])
        levels = [float(f) for f in levels]
        # the periodic responses at and between the simulated levels (harmonic balance),
        # computed while the simulations run: they widen the check over the forces
        scan_forces = sorted(set(levels)
                             | ({process * k for k in SCAN_LEVELS} if forces is None else set()))
        scans.append((name, design_axis(axis, problem, result.design), speed, scan_forces,
                      band))
        regime_info[name] = (speed, claim, claim_before, models, band, res, levels,
                             scan_forces)
        designs = [("after", result.design)] + ([("before", result.initial)] if before_ok
                                                else [])
        for label, design in designs:
            nl_axis = design_axis(axis, problem, design)
            tags = {"regime": name, "design": label}
            for f in levels:
                jobs.append((simulate_sweep, (nl_axis, float(f), band, res, speed, torque_limit,
                                              tags)))
            if speed > 0:
                jobs.append((simulate_feeding, (nl_axis, speed, tags)))
    spread_regimes = [name for name in regimes if corners and any(
        m.regime == name and m.cutting and m.sample == "nominal" for m in problem.regimes)]
    total = len(jobs) + sum(1 + (speed_of[name] > 0) for name in spread_regimes)
    done = [0]

    def tick():
        done[0] += 1
        if progress is not None:
            progress(done[0], max(total, done[0]))

    futures = None if executor is None else [executor.submit(fn, *args) for fn, args in jobs]
    # the friction spread: every corner's linear claim here while the simulations run, then
    # the periodic responses of its stable corners by harmonic balance, one job per regime (in
    # a worker when there is an executor); the worst corners' simulations follow them
    rows_of, corner_jobs = {}, []
    if spread_regimes:
        nl_design = design_axis(axis, problem, result.design)
        try:
            receptance = pad_receptance(nl_design.structure, nl_design.drive, nl_design.pads,
                                        problem.force)
        except ValueError:
            receptance = None   # coupled damping: the closed loop's own compliance
        claim_omega = np.geomspace(req.band[0], req.band[1], 6001)
    hb_jobs = {}
    for name in spread_regimes:
        speed, band, levels = regime_info[name][0], regime_info[name][4], regime_info[name][6]
        models = [m for m in problem.regimes
                  if m.regime == name and m.cutting and m.sample == "nominal"]
        rows = []
        for label, params in corners:
            corner_models = [dataclasses.replace(m, friction=params, sample=label)
                             for m in models]
            claim_c, unstable = _corner_claim(problem, nl_design.drive, receptance,
                                              corner_models, result.design.c, claim_omega)
            rows.append({"label": label, "friction": params, "claim": claim_c,
                         "unstable": unstable, "scan": (), "note": "",
                         "axis": design_axis(axis, problem, result.design, friction=params)})
        rows_of[name] = rows
        # an unstable corner has no periodic response to speak of (its claim fails); the
        # corners are scanned at three times the process force (see _corner_levels)
        args = ([r["axis"] for r in rows if not r["unstable"]], speed, _corner_levels(levels),
                band)
        hb_jobs[name] = args if executor is None else executor.submit(harmonic_scans, *args)
    scanned = {name: _harmonic_or_why(nl, speed, f, band) for name, nl, speed, f, band in scans}
    if executor is not None:
        from concurrent.futures import as_completed

        pending = {fut: name for name, fut in hb_jobs.items()}
        arrived = ((pending[fut], fut.result()) for fut in as_completed(list(pending)))
    else:
        arrived = ((name, harmonic_scans(*args)) for name, args in hb_jobs.items())
    for name, found in arrived:
        speed, _, _, _, band, res, levels, _ = regime_info[name]
        stable = [r for r in rows_of[name] if not r["unstable"]]
        for row, (scan, note) in zip(stable, found, strict=True):
            row["scan"], row["note"] = scan, note
        chosen = [r for r in stable if not r["scan"]]
        scanned_rows = [r for r in stable if r["scan"]]
        if scanned_rows:
            chosen.append(max(scanned_rows, key=lambda r: max(h.peak for h in r["scan"])))
        for row in chosen:
            nominal = max((h.peak for h in scanned[name][0]), default=None)
            for fn, args in _corner_jobs(row, name, speed, levels, band, res, nominal,
                                         torque_limit):
                corner_jobs.append((name, row["label"], fn, args,
                                    None if executor is None else executor.submit(fn, *args)))
    total += len(corner_jobs) - sum(1 + (speed_of[name] > 0) for name in spread_regimes)
    if executor is None:
        sims = []
        for fn, args in jobs:
            sims.append(fn(*args))
            tick()
    else:
        sims = []
        for fut in futures:
            sims.append(fut.result())
            tick()
    corner_sims = {}
    for name, label, fn, args, fut in corner_jobs:
        corner_sims.setdefault((name, label), []).append(fn(*args) if fut is None
                                                         else fut.result())
        tick()
    tol = req.nonlinear_tolerance
    spread_thrust = _spread_thrust(problem, box, result.design)
    linear_holds = bool(result.success) and not spread_thrust
    reasons += spread_thrust
    verdicts, failures = [], []
    excluded: dict = {}
    for m, r in result.excluded:
        excluded.setdefault(m.regime, []).append(f"{m.name}: {r}")
    for name in regimes:
        speed, claim_tuned, claim_before, models, band, _, levels, _ = regime_info[name]
        scan, scan_note = scanned[name]
        rows = rows_of.get(name, [])
        claim = claim_tuned
        if claim is not None and rows:
            # an unstable corner fails on its own; the others are judged against the rest
            claim = max([claim] + [r["claim"] for r in rows if not r["unstable"]])
        mine = tuple(s for s in sims if s.regime == name)
        after = [s for s in mine if s.design == "after"]
        before = [s for s in mine if s.design == "before"]
        nl_after = _worst(after)
        nl_before = _worst(before)
        why = []
        if name in excluded:
            why += [f"left out of the tuning: {e}" for e in excluded[name]]
        if claim is None and name not in excluded:
            why.append("no linear claim for this regime")
        elif claim_tuned is not None and not math.isfinite(claim_tuned):
            why.append("the linear model of this regime is unstable with the design")
        why += _run_checks(after, band, speed, None, tol)
        if claim is not None and math.isfinite(claim) and scan:
            # the steady periodic response: a sweep passes a resonance before it has built up
            # and reads its peak low, so the scan judges every level, simulated or not
            worst_scan = max(scan, key=lambda h: h.peak)
            simulated = {s.force_pp for s in after if s.kind == "sweep"}
            if worst_scan.peak > claim * (1 + tol):
                which = ("a level also simulated" if worst_scan.force_pp in simulated
                         else "a level not simulated")
                why.append(f"harmonic balance finds the axis peaking at {worst_scan.peak:.3g} "
                           f"m/N ({worst_scan.resonance_hz:.1f} Hz) at "
                           f"{worst_scan.force_pp:.4g} N p-p ({which}), "
                           f"{worst_scan.peak / claim - 1:.0%} above the claim {claim:.3g} m/N")
        if claim is not None and math.isfinite(claim) and nl_after is not None:
            if nl_after[0] > claim * (1 + tol):
                s = nl_after[1]
                why.append(f"the nonlinear axis peaks at {s.peak:.3g} m/N ({s.resonance_hz:.1f} "
                           f"Hz, {s.force_pp:.4g} N p-p), {s.peak / claim - 1:.0%} above the "
                           f"claim {claim:.3g} m/N (tolerance {tol:.0%})")
        failures += [f"{name}: {w}" for w in why]
        corner_verdicts, corner_why = [], []
        for row in rows:
            runs = tuple(corner_sims.get((name, row["label"]), ()))
            found = []
            if row["unstable"]:
                found.append(f"the linear model is unstable with the design "
                             f"({row['unstable']})")
            if row["scan"] and claim is not None and math.isfinite(claim):
                h = max(row["scan"], key=lambda x: x.peak)
                if h.peak > claim * (1 + tol):
                    found.append(f"harmonic balance peak {h.peak:.3g} m/N ({h.resonance_hz:.1f} "
                                 f"Hz, {h.force_pp:.4g} N p-p) is {h.peak / claim - 1:.0%} above "
                                 f"the claim {claim:.3g} m/N")
            found += _run_checks(runs, band, speed, claim, tol)
            corner_why += [f"{row['label']}: {w}" for w in found]
            failures += [f"{name}, {row['label']}: {w}" for w in found]
            corner_verdicts.append(CornerVerdict(
                row["label"], row["friction"], row["claim"], row["scan"], row["note"], runs,
                not found, "; ".join(found) or "holds"))
        all_why = why + corner_why
        holds = not all_why
        spread_after = [s for c in corner_verdicts for s in c.simulations]
        worst_spread = _worst(after + spread_after)
        worst_after = None if nl_after is None else nl_after[0]
        worst_before = None if nl_before is None else nl_before[0]
        improvement = (None if worst_before is None or not worst_after
                       else worst_before / worst_after)
        explanation = (_explain(name, "standing" if speed == 0 else "feeding", improvement,
                                result.active) if holds else "")
        if (claim is not None and claim_tuned is not None and math.isfinite(claim)
                and claim > claim_tuned * 1.005):   # shown when it reads 1 % or more
            top = max(rows, key=lambda r: r["claim"])
            explanation = "; ".join(x for x in (
                f"over the friction spread the claim is {claim:.3g} m/N (at {top['label']}), "
                f"{claim / claim_tuned - 1:.0%} above the tuned {claim_tuned:.3g} m/N of the "
                "tuning's friction models ([tuning] friction_spread tunes over the spread)",
                explanation) if x)
        verdicts.append(RegimeVerdict(
            name=name, speed=speed, models=models, claimed_peak=claim,
            claimed_peak_before=claim_before, nonlinear_peak_before=worst_before,
            nonlinear_peak_after=None if worst_spread is None else worst_spread[0],
            band_hz=tuple(band), holds=holds,
            reason="holds" if holds else "; ".join(all_why),
            explanation=explanation, simulations=mine, harmonic=scan, harmonic_note=scan_note,
            claimed_peak_tuned=claim_tuned, nonlinear_peak_after_nominal=worst_after,
            corners=tuple(corner_verdicts)))
    nonlinear_holds = all(v.holds for v in verdicts)
    reasons += failures
    levels_of = {name: regime_info[name][7] for name in regimes}
    corner_levels_of = {name: _corner_levels(regime_info[name][6]) for name in spread_regimes}
    simulated = {v.name: {"nominal": sorted({s.force_pp for s in v.simulations
                                            if s.kind == "sweep" and s.design == "after"}),
                          "corners": {c.label: sorted({s.force_pp for s in c.simulations
                                                       if s.kind == "sweep"})
                                      for c in v.corners if c.simulations}}
                 for v in verdicts}
    coverage, coverage_text = _coverage(
        box if spread_regimes else None, [(v.name, v.speed) for v in verdicts], process,
        levels_of, corner_levels_of, {v.name: v.band_hz for v in verdicts}, problem, simulated,
        default_process)
    checked, not_checked = _checked_lines(problem, verdicts, box if spread_regimes else None,
                                          result, simulated=simulated_structure(axis, problem))
    return Verdict(verified=linear_holds and nonlinear_holds, linear_holds=linear_holds,
                   nonlinear_holds=nonlinear_holds, regimes=tuple(verdicts), tolerance=tol,
                   reasons=tuple(reasons), checked=checked, not_checked=not_checked,
                   coverage=coverage, coverage_text=coverage_text)


def _law_name(problem) -> str:
    """The friction law of the problem's regime models (``"viscous"`` without one)."""
    names = sorted({m.friction.name for m in problem.regimes if m.friction is not None})
    return "/".join(names) if names else "viscous"


def _checked_lines(problem, verdicts, box, result, simulated: Truncation | None = None
                   ) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """What the verdict checked and what not, each a line that is true of this run."""
    thrust = problem.thrust
    budget = ("the thrust budget on the motor's torque-speed curve ("
              + ", ".join(f"{c.name}: {c.thrust_kind} thrust" for c in thrust.cases(0.0))
              + ")" if thrust is not None else "")
    samples = sorted({m.sample for m in problem.regimes if m.sample != "nominal"})
    checked = [
        "linear: stability, Ms of both loops, loop hierarchy, Ti vs velocity bandwidth"
        + (f", {budget}" if budget else "")
        + " and the compliance peak in every regime model (nominal friction"
        + (f" and the tuning's friction samples {', '.join(samples)}" if samples else "")
        + "), on dense grids with python-control",
        f"nonlinear: the {_law_name(problem)} friction law at every pad, sine sweeps "
        + "; ".join(f"{v.name} over {v.band_hz[0]:.3g}-{v.band_hz[1]:.3g} Hz at "
                    + ", ".join(f"{f:.3g}" for f in sorted({s.force_pp for s in v.simulations
                                                            if s.kind == "sweep"
                                                            and s.design == "after"}))
                    + " N p-p" for v in verdicts)
        + ("; stick-slip runs at each feed speed" if any(v.speed > 0 for v in verdicts)
           else "")
        + (f"; the structure simulated: {simulated.describe()}"
           if simulated is not None and simulated.truncated else ""),
        *(["nonlinear, between the simulated levels: the periodic response by harmonic "
           "balance (9 harmonics) at " + "; ".join(
               f"{v.name} " + ", ".join(f"{h.force_pp:.3g}" for h in v.harmonic) + " N p-p"
               for v in verdicts if v.harmonic)] if any(v.harmonic for v in verdicts) else [])]
    if box is not None:
        n = len(box.corners())
        worst = []
        for v in verdicts:
            c = v.worst_corner
            if c is None:
                continue
            sim = c.simulated_peak
            worst.append(f"{v.name} worst at {c.label}: {c.harmonic_peak.peak:.3g} m/N by "
                         f"harmonic balance" + ("" if sim is None else
                                                f", {sim:.3g} m/N simulated")
                         + f" (claim {v.claimed_peak:.3g})")
        checked.append(
            f"the friction spread ({box.source}: {box.describe()}), at each of its {n} "
            "corners: the stability and the compliance peak of every regime's linear models"
            + (", the thrust budget" if thrust is not None else "")
            + " and the periodic response by harmonic balance at the simulated levels; the "
              "worst corner of each regime simulated in time (a sweep around its peak, and "
              "feeding a stick-slip run)" + ("; " + "; ".join(worst) if worst else ""))
    not_checked = []
    if box is None:
        not_checked.append("the friction spread: only the nominal friction is checked (give "
                           "[tuning] friction_spread or the identified set's [friction] "
                           "variation)")
    else:
        not_checked.append("inside the friction spread's box, only its corners (a response "
                           "that peaks inside the box is missed); at the corners, Ms, the loop "
                           "hierarchy and Ti (the linear checks cover the tuning's regime "
                           "models)")
    not_checked.append(
        "forces outside the levels simulated and scanned by harmonic balance, and operating "
        "points other than the regimes; the stability of the periodic responses found by "
        "harmonic balance (the time simulation confirms the simulated levels"
        + (" and the worst corners)" if box is not None else ")"))
    if thrust is not None:
        not_checked.append(
            "the start of a move against the static friction Fs (the budget takes the sliding "
            "friction at the rapid speed) and the motor's heating over a duty cycle (each case "
            "is judged alone); in the time simulation the motor torque only against its "
            "largest peak torque, not the torque-speed curve at the simulated speed")
    else:
        not_checked.append("the thrust budget (the drive has no torque limits)")
    return tuple(checked), tuple(not_checked)


def _worst(sims):
    peaks = [(s.peak, s) for s in sims if s.kind == "sweep" and s.peak is not None]
    return max(peaks, key=lambda p: p[0]) if peaks else None
