"""The design job on an axis description: set up the tuning, run it, verify, summarise.

:func:`tune_axis` turns an :class:`~servotune.axis.Axis` into a
:class:`~servotune.tuning.TuningProblem`: the guide-way damping C (the total viscous part of the
friction), the drive's Kv and velocity PI, one linear model per operating regime (standing:
LuGre presliding and the describing function at the process amplitude; feeding: LuGre
linearised about each feed speed; :mod:`servotune.regimes`), the drive's thrust budget
(:mod:`servotune.thrust`), the axis' requirements and milling set-up. It solves it, verifies the
design in every model and, with ``simulate=True``, on the nonlinear axis
(:mod:`servotune.verdict`), and gathers what a designer reads: the design before and after, the
thrust needed against the thrust available, what could realise C, loops, compliance and lobes
of both, the several-modes trade-off in C (paper sec 5.2) and, for a two-mass axis, the check of
C against the closed-form fixed-point optimum (paper sec 4.1).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from . import analysis, twomass
from . import progress as _progress
from .axis import Axis
from .blas import one_thread
from .digital import SampledAxis
from .drive import PIController
from .plant import Contact
from .regimes import RegimeModel, axis_regimes, process_amplitude
from .thrust import CRealisation, c_realisations, thrust_budget
from .tuning import (
    LOWPASS_VARIABLES,
    NOTCH_VARIABLES,
    ChatterTarget,
    Design,
    NoStableStartError,
    RequirementsNotMetError,
    TuningDidNotConvergeError,
    TuningProblem,
    TuningResult,
    TuningStatistics,
    expand_free,
    tune,
)
from .units import HZ_PER_RAD_S

if TYPE_CHECKING:   # types of the results only (the modules are imported where they run)
    from .chatter import StabilityLobes
    from .verdict import Verdict

__all__ = [
    "DEFAULT_BOUNDS",
    "TwoMassCheck",
    "AxisTuning",
    "TuningRound",
    "MAX_ROUNDS",
    "spread_screen",
    "refuted_models",
    "stabilising_damping",
    "baseline_comparison",
    "ModePeaks",
    "tuning_problem",
    "two_mass_check",
    "mode_peaks_vs_damping",
    "tune_axis",
    "fig5_check",
    "nonlinear_check",
    "axis_regimes",
    "process_amplitude",
    "check_design",
    "start_notch",
    "tuned_lowpass",
    "with_drive_fixed",
]

#: A notch starts only where the velocity loop's sensitivity peaks at least this high above
#: NOTCH_ABOVE times its bandwidth (below, the loop's own crossover sets Ms: no resonance to
#: notch).
NOTCH_MS_MIN = 1.1
NOTCH_ABOVE = 3.0
#: The tuned notch's start: width (2 zeta_p) and depth (1: no notch yet, the start design is
#: the one given; the optimiser deepens it where that pays).
NOTCH_START_WIDTH = 0.3
NOTCH_START_DEPTH = 1.0


#: Default search bounds (SI); ``kp`` is relative to the initial value. Ti stays at or below
#: 0.2 s so that the velocity loop keeps its integral action (the compliance peak barely depends
#: on Ti above that, which would leave Ti undetermined).
DEFAULT_BOUNDS = {"c": (1e3, 1e8), "kv": (1.0, 300.0), "kp_factor": (0.01, 100.0),
                  "ti": (1e-3, 0.2)}


def tuning_problem(axis: Axis, free=("c", "kv", "kp", "ti"), chatter_weight: float = 0.0,
                   bounds: dict | None = None, c0: float | None = None,
                   regimes=None, notch=None, lowpass=None) -> TuningProblem:
    """Return the tuning problem of an axis.

    The axis' requirements are kept, except the objective band of a two-mass axis without a
    drive (layout B), which starts at the first fixed point and reaches at least 4 times the
    second (the closed-form optimum's band). With a drive, and unless ``bounds`` gives ``c``,
    the lower bound of C is raised to the guide ways' own viscous friction sigma2.

    Parameters
    ----------
    axis : Axis
        The axis description (needs ``[friction]``).
    free : sequence of str
        Free variables among c, kv, kp, ti, notch and lowpass (those needing a drive are
        dropped when the axis has none; the notch's when there is no ``notch`` to tune, the
        low-pass' when there is no ``lowpass``).
    chatter_weight : float in [0, 1]
        Weight of the chatter limit (initial b_crit / b_crit) against the compliance peak
        (peak / initial peak); needs ``[cutting]``.
    bounds : dict, optional
        ``{name: (low, high)}`` overriding :data:`DEFAULT_BOUNDS`.
    c0 : float, optional
        Initial C [N s/m]; default the axis' viscous guide-way damping, moved into the bounds
        when outside them.
    regimes : sequence of RegimeModel, optional
        Default :func:`axis_regimes` at ``c0``.
    notch : NotchFilter, optional
        The tuned current set-point notch (its start, e.g. :func:`start_notch`), after the
        drive's own set-point filters.
    lowpass : LowPassFilter, optional
        The tuned current set-point low-pass (its start, e.g. the drive's own): it replaces
        the drive's own low-pass.

    Returns
    -------
    TuningProblem
        Structure, pads, initial C, drive, free variables, bounds (``kp`` as
        ``kp_factor`` times the drive's velocity-loop Kp unless ``bounds`` gives ``kp``),
        requirements, chatter target (with ``[cutting]``), weights
        ``(1 - chatter_weight, chatter_weight)``, regime models and thrust budget.

    Raises
    ------
    ValueError
        If ``chatter_weight`` lies outside [0, 1].
    AxisFormatError
        If the axis has no ``[friction]``, or ``chatter_weight > 0`` without ``[cutting]``.
    """
    if not 0.0 <= chatter_weight <= 1.0:
        raise ValueError(f"chatter_weight must lie in [0, 1], got {chatter_weight!r}")
    if axis.friction is None:
        axis.pads  # the clear error naming [friction]  # noqa: B018
    drive = axis.drive
    notch = notch if drive is not None else None
    lowpass = lowpass if drive is not None else None
    if lowpass is not None:
        drive = dataclasses.replace(drive, lowpass=None)   # the tuned one replaces it
    free = tuple(v for v in expand_free(free) if (drive is not None or v == "c")
                 and (notch is not None or v not in NOTCH_VARIABLES)
                 and (lowpass is not None or v not in LOWPASS_VARIABLES))
    c0 = axis.friction.viscous if c0 is None else c0
    chatter = None
    if axis.cutting is not None:
        chatter = ChatterTarget.from_setup(axis.cutting.setup, axis.cutting.direction,
                                           axis.requirements.depth_required)
    elif chatter_weight > 0:
        axis.require_cutting()
    b = dict(DEFAULT_BOUNDS, **(bounds or {}))
    if drive is not None and "c" not in (bounds or {}):
        # the guide ways' own viscous friction is the floor: a design may add damping, not
        # take away what the guide ways have (give [tuning] c = [low, high] to allow it)
        b["c"] = (max(b["c"][0], axis.friction.law.viscous_part), b["c"][1])
    problem_bounds = {"c": b["c"]}
    if "c" in free:  # start inside the bounds (the axis' value is the "before" design only)
        c0 = min(max(c0, b["c"][0]), b["c"][1])
    if drive is not None:
        kp0 = drive.velocity_loop.kp
        problem_bounds.update(
            kv=b["kv"], ti=b["ti"],
            kp=b.get("kp", (kp0 * b["kp_factor"][0], kp0 * b["kp_factor"][1])))
        # the tuned filters' bounds when given (else TuningProblem's defaults around the start)
        problem_bounds.update({k: b[k] for k in (*NOTCH_VARIABLES, *LOWPASS_VARIABLES)
                               if k in b})
        if lowpass is not None and "lowpass_frequency" in b:
            # the low-pass starts inside its bounds, as C does
            lo, hi = b["lowpass_frequency"]
            w0 = min(max(2.0 * math.pi * lowpass.f_hz, lo), hi)
            lowpass = dataclasses.replace(lowpass, f_hz=w0 * HZ_PER_RAD_S)
    band = axis.requirements.band
    if drive is None and len(axis.pads) == 1 and axis.structure.n == 2:
        # a two-mass axis (layout B): the peak is sought above the first fixed point, as the
        # closed-form optimum assumes (|H| ~ 1/(w C) as w -> 0)
        system = _two_mass_system(axis)
        if system is not None:
            w_f1, w_f2 = twomass.fixed_points(system)
            band = (float(w_f1), max(band[1], 4.0 * float(w_f2)))
    from dataclasses import replace

    requirements = replace(axis.requirements, band=band)
    models = axis_regimes(axis, c0) if regimes is None else tuple(regimes)
    budget = thrust_budget(drive, None if axis.friction is None else axis.friction.law,
                           axis.operation, axis.structure, axis.pads,
                           axis.requirements.thrust_margin)
    return TuningProblem(axis.structure, axis.pads, c=c0, drive=drive, free=free,
                         bounds=problem_bounds, requirements=requirements, chatter=chatter,
                         weights=(1.0 - chatter_weight, chatter_weight), regimes=models,
                         thrust=budget, notch=notch, lowpass=lowpass)


def start_notch(problem: TuningProblem, n_points: int = 3000):
    """Return where the tuned current set-point notch starts, and why.

    The velocity loop of the problem's initial design, in every model in which the axis moves
    (the port model; a digital drive as its sampled-data loop): its bandwidth w_b (the first
    frequency where |T_v| falls below 1/sqrt 2) and its sensitivity |S_v| = 1/|1 + L_v| above
    :data:`NOTCH_ABOVE` w_b, up to 0.45 times the current controller's sample rate. Where the
    largest of these peaks is at least :data:`NOTCH_MS_MIN`, a resonance of the velocity-loop
    plant lifts the loop there (what a drive engineer notches: Ellis 2012, ch. 16); the notch
    starts on it (the largest |L_v| within 30 % of the sensitivity's peak), width
    :data:`NOTCH_START_WIDTH` and depth :data:`NOTCH_START_DEPTH` (no notch yet: the start is
    the design given).

    Parameters
    ----------
    problem : TuningProblem
        A problem with a drive.
    n_points : int
        Frequencies of the log-spaced loop grid.

    Returns
    -------
    (NotchFilter or None, str)
        The start notch (None: nothing to notch) and a sentence saying why.
    """
    from .drive import NotchFilter
    from .tuning.ports import ResponseModel, grid

    drive = problem.drive
    if drive is None:
        return None, "no drive"
    lo, hi = problem.requirements.loop_band
    if not drive.digital.is_continuous:
        hi = min(hi, 0.45 * 2.0 * math.pi / drive.digital.current_period)
    omega = grid(lo, hi, n_points)
    x0 = problem.initial_design()
    lv = ResponseModel(problem, omega, x0)(x0)["loop_velocity"]
    models = problem.moving_models or tuple(range(len(problem.regimes)))
    best = None
    for m in models:
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.abs(lv[m] / (1.0 + lv[m]))
            sens = 1.0 / np.abs(1.0 + lv[m])
        below = np.nonzero(t < math.sqrt(0.5))[0]
        if not below.size or not np.all(np.isfinite(sens)):
            continue
        w_b = omega[below[0]]
        above = omega > NOTCH_ABOVE * w_b
        if not above.any():
            continue
        i = int(np.argmax(np.where(above, sens, 0.0)))
        # the resonance that lifts the loop there: the largest |L_v| within 30 % of it
        near = above & (omega > omega[i] / 1.3) & (omega < omega[i] * 1.3)
        j = int(np.argmax(np.where(near, np.abs(lv[m]), 0.0)))
        if best is None or sens[i] > best[0]:
            best = (float(sens[i]), float(omega[j]), float(w_b), problem.regimes[m].name)
    if best is None:
        return None, "no velocity-loop bandwidth found in the loop band: no notch tuned"
    ms, w, w_b, name = best
    if ms < NOTCH_MS_MIN:
        return None, (f"the velocity loop's sensitivity stays below {NOTCH_MS_MIN:g} above "
                      f"{NOTCH_ABOVE:g} x its bandwidth ({ms:.3g} at most): no resonance to "
                      "notch, no notch tuned")
    f_hz = w * HZ_PER_RAD_S
    return NotchFilter(f_hz, NOTCH_START_WIDTH, NOTCH_START_DEPTH), (
        f"the tuned current set-point notch starts at {f_hz:.1f} Hz, the resonance that lifts "
        f"the velocity loop's sensitivity to {ms:.3g} ({name}; bandwidth "
        f"{w_b * HZ_PER_RAD_S:.1f} Hz), "
        f"width {NOTCH_START_WIDTH:g}, depth {NOTCH_START_DEPTH:g} (not yet a notch: the "
        "tuning deepens it where that pays)")


def with_drive_fixed(axis: Axis, fixed: dict | None, where="results.json") -> Axis:
    """Return the axis with the drive parts a tuning kept (``drive_fixed`` of its results):
    the current loop and the set-point filters it was tuned with (the commissioning design's,
    when the tuning started there).

    Parameters
    ----------
    axis : Axis
        The axis the results were tuned on.
    fixed : dict or None
        ``current_kp`` [V/A], ``current_ti`` [s], ``lowpass`` ({f_hz, damping_ratio} or None)
        and ``notches`` (list of {f_hz, width, depth}); None leaves the axis as it is.
    where : str
        Where ``fixed`` comes from (for the error message).

    Returns
    -------
    Axis

    Raises
    ------
    ValueError
        A part that is missing or not valid (the message names it).
    """
    from .drive import LowPassFilter, NotchFilter

    if fixed is None or axis.drive is None:
        return axis
    try:
        lowpass = None if fixed.get("lowpass") is None else LowPassFilter(**fixed["lowpass"])
        notches = tuple(NotchFilter(**n) for n in fixed.get("notches") or ())
        current = PIController(float(fixed["current_kp"]), float(fixed["current_ti"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{where}: drive_fixed is not valid ({exc}); it must hold "
                         "current_kp [V/A], current_ti [s], lowpass and notches as servotune "
                         "tune writes them") from None
    drive = dataclasses.replace(axis.drive, current_loop=current, lowpass=lowpass,
                                notches=notches)
    return dataclasses.replace(axis, drive=drive)


def _two_mass_system(axis: Axis) -> twomass.TwoMassSystem | None:
    """Layout B read off a 2-DOF axis (pad = slide M1 on the damper, wp = M2), if it is one."""
    s = axis.structure
    if s.n != 2 or axis.friction is None or "wp.x" not in s.dofs:
        return None
    i, j = int(s.index(axis.pads[0])), int(s.index("wp.x"))
    m, k = s.mass, s.stiffness
    if abs(m[i, j]) > 1e-12 * m.max() or not np.allclose(
            k, k[j, j] * np.array([[1, -1], [-1, 1]]), rtol=1e-9, atol=0):
        return None
    return twomass.TwoMassSystem(m1=m[i, i], k=k[j, j], alpha=m[j, j] / m[i, i])


@dataclass(frozen=True)
class TwoMassCheck:
    """The tuned C of a two-mass axis against the closed forms of sec 4.1 (Eq 4, 7).

    Parameters
    ----------
    system : servotune.twomass.TwoMassSystem
        The two-mass system (M1, K, alpha).
    c_opt_analytic : float
        Closed-form optimal damping Copt [N s/m] (paper, Eq 4).
    c_opt_tuned : float
        C [N s/m] the tuning found.
    peak_analytic : float
        Peak compliance with Copt [m/N] (paper, Eq 7).
    peak_tuned : float
        Peak compliance of the tuned design [m/N].
    """

    system: twomass.TwoMassSystem
    c_opt_analytic: float
    c_opt_tuned: float
    peak_analytic: float
    peak_tuned: float

    @property
    def c_relative_difference(self) -> float:
        return self.c_opt_tuned / self.c_opt_analytic - 1.0

    @property
    def peak_relative_difference(self) -> float:
        return self.peak_tuned / self.peak_analytic - 1.0

    def to_dict(self) -> dict:
        """Return the check as JSON-ready data.

        Returns
        -------
        dict
            ``m1`` [kg], ``k`` [N/m], ``alpha``, both C [N s/m] and peaks [m/N] and their
            relative differences (tuned / analytic - 1).
        """
        return {"m1": self.system.m1, "k": self.system.k, "alpha": self.system.alpha,
                "c_opt_analytic": self.c_opt_analytic, "c_opt_tuned": self.c_opt_tuned,
                "c_relative_difference": self.c_relative_difference,
                "peak_compliance_analytic": self.peak_analytic,
                "peak_compliance_tuned": self.peak_tuned,
                "peak_relative_difference": self.peak_relative_difference}


def two_mass_check(axis: Axis, result: TuningResult | None) -> TwoMassCheck | None:
    """Compare a tuned C with Copt and g(alpha)/K when the axis is a two-mass layout B.

    Parameters
    ----------
    axis : Axis
        The axis description.
    result : TuningResult or None
        The tuning result.

    Returns
    -------
    TwoMassCheck or None
        None when the axis is no two-mass layout B (two DOFs, one pad, ``wp.x``, a single
        spring between them and no mass coupling), or when the result has no check of the
        tuned design (``result.after`` is None).
    """
    system = _two_mass_system(axis)
    if system is None or result is None or result.after is None:
        return None
    return TwoMassCheck(system, twomass.optimal_damping(system), result.design.c,
                        twomass.optimal_peak(system), result.after.peak_compliance)


@dataclass(frozen=True)
class ModePeaks:
    """Compliance peak of each work-piece mode against the guide-way damping C (sec 5.2).

    Attributes
    ----------
    c_values : numpy.ndarray
        C [N s/m].
    frequencies : numpy.ndarray
        (modes, len(c)) natural frequency [rad/s] of each tracked closed-loop mode.
    peaks : numpy.ndarray
        (modes, len(c)) peak of the mode's own term of the compliance, |R|/|Re lambda|
        [m/N]; NaN where the mode's track has ended.
    c_best : numpy.ndarray
        The C [N s/m] that minimises each mode's peak on the grid.
    c_chosen : float
        The C of the design.
    """

    c_values: np.ndarray
    frequencies: np.ndarray
    peaks: np.ndarray
    c_best: np.ndarray
    c_chosen: float

    def to_dict(self) -> dict:
        """Return the peaks at the design's C and at each mode's best C as JSON-ready data.

        Returns
        -------
        dict
            ``c_chosen`` [N s/m] and ``modes``: per mode, its frequency [Hz] and peak [m/N] at
            the grid point nearest ``c_chosen`` (in log C), its best C and the peak there.
        """
        i = int(np.argmin(np.abs(np.log(self.c_values / self.c_chosen))))
        return {"c_chosen": self.c_chosen, "modes": [
            {"frequency_at_chosen_c_hz": float(self.frequencies[m, i] * HZ_PER_RAD_S),
             "peak_at_chosen_c": float(self.peaks[m, i]),
             "c_best": float(self.c_best[m]),
             "peak_at_best_c": float(np.nanmin(self.peaks[m]))}
            for m in range(self.peaks.shape[0])]}

    def plot(self):
        """Plot each mode's peak against C (:func:`servotune.plots.plot_mode_peaks`).

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        from .plots import plot_mode_peaks

        return plot_mode_peaks(self)


def mode_peaks_vs_damping(axis: Axis, c_values, drive=None, c_chosen: float | None = None,
                          f_max_hz: float = 300.0, keep: int = 4,
                          significance: float = 0.01) -> ModePeaks:
    """Track the closed-loop modes that move the work piece as C varies.

    For each C the closed-loop plant (``viscous`` pads, the drive) is put in modal form,
    ``H(s) = sum_i R_i / (s - lambda_i)``; a mode's own peak is ``|R_i| / |Re lambda_i|``
    (its pair's term at resonance). A digital drive's loop is a sampled-data system without
    poles in s: there the local maxima of its compliance (800 log-spaced points from 1 Hz to
    1.5 ``f_max_hz``) are the modes' peaks, at their frequencies. The modes are chosen at the
    design's C (the ``keep`` largest peaks below ``f_max_hz`` that reach ``significance`` times
    the largest) and followed outwards in C by the nearest pole; a mode that turns over-damped
    or jumps by more
    than half its frequency ends its track (NaN). The design's C is added to the grid.

    Parameters
    ----------
    axis : Axis
        The axis description.
    c_values : array_like
        Grid of C [N s/m], > 0.
    drive : Drive, optional
        The drive; default the axis' (the loop is open when neither exists).
    c_chosen : float, optional
        The design's C [N s/m]; default the axis' ``[friction] viscous``.
    f_max_hz : float
        Highest natural frequency [Hz] of a tracked mode.
    keep : int
        Largest number of tracked modes.
    significance : float
        Smallest peak, as a fraction of the largest at ``c_chosen``, of a tracked mode.

    Returns
    -------
    ModePeaks
        The tracks on the sorted grid (``c_values`` with ``c_chosen`` added).

    Raises
    ------
    ValueError
        If the closed loop has no oscillating mode below ``f_max_hz`` at ``c_chosen``.
    """
    chosen = float(c_chosen if c_chosen is not None else axis.friction.viscous)
    c_values = np.unique(np.append(np.asarray(c_values, dtype=float), chosen))
    controlled = (drive or axis.drive) is not None
    the_drive = (drive or axis.drive) if controlled else None
    sampled = the_drive is not None and not the_drive.digital.is_continuous
    poles, peaks = [], []
    for c in c_values:
        if sampled:
            # a sampled-data loop has no poles in s: the local maxima of its compliance (the
            # fundamental) stand for the modes, at j times their frequency
            omega = 2 * math.pi * np.geomspace(1.0, 1.5 * f_max_hz, 800)
            h = np.abs(analysis.axis_loop(axis, Contact.viscous(c), the_drive).compliance(
                omega)[0])
            top = np.nonzero((h[1:-1] > h[:-2]) & (h[1:-1] >= h[2:]))[0] + 1
            top = top[omega[top] * HZ_PER_RAD_S < f_max_hz]
            poles.append(1j * omega[top])
            peaks.append(h[top])
            continue
        plant = analysis.axis_plant(axis, Contact.viscous(c), drive, controlled=controlled)
        sub = plant[plant.output_labels.index("wp_x"), plant.input_labels.index("f_wp_x")]
        lam, v = np.linalg.eig(sub.A)
        res = (sub.C @ v).ravel() * np.linalg.solve(v, sub.B).ravel()
        sel = (lam.imag > 0) & (lam.imag * HZ_PER_RAD_S < f_max_hz)
        poles.append(lam[sel])
        # at s = j Im(lambda) the mode's own term R / (s - lambda) is R / (-Re lambda); its
        # conjugate's term is small when the mode is lightly damped
        peaks.append(np.abs(res[sel]) / np.maximum(np.abs(lam[sel].real), 1e-300))
    start = int(np.argmin(np.abs(np.log(c_values / chosen))))
    p0 = peaks[start]
    order = [i for i in np.argsort(-p0)[:keep] if p0[i] >= significance * p0.max()]
    tracks_f = np.full((len(order), c_values.size), np.nan)
    tracks_p = np.full((len(order), c_values.size), np.nan)
    for m, i0 in enumerate(order):
        tracks_f[m, start], tracks_p[m, start] = abs(poles[start][i0]), p0[i0]
        for direction in (1, -1):
            current = poles[start][i0]
            j = start + direction
            while 0 <= j < c_values.size and poles[j].size:
                dist = np.abs(poles[j] - current)
                i = int(np.argmin(dist))
                if dist[i] > 0.5 * abs(current):
                    break
                current = poles[j][i]
                tracks_f[m, j], tracks_p[m, j] = abs(current), peaks[j][i]
                j += direction
    best = np.array([c_values[np.nanargmin(row)] for row in tracks_p])
    return ModePeaks(c_values, tracks_f, tracks_p, best, chosen)


@dataclass(frozen=True)
class AxisTuning:
    """Everything the design job produces for an axis (see :func:`tune_axis`).

    ``verdict`` is the nonlinear verdict (None when the simulation was skipped: then the design
    is not verified, only linearly checked; without a drive, the linear verdict of the viscous
    pads, which are the system itself); ``thrust_before``/``thrust_after`` the thrust budget of
    both designs (None without torque limits); ``c_realisation`` the hardware options for the
    tuned C; ``compliance_before``/``compliance_after`` one curve per stable cutting regime
    model of the nominal friction; ``process`` the process force, pad amplitude and frequency
    of :func:`process_amplitude` for the tuned design; ``notes`` the defaults the axis loader
    filled in.
    """

    axis: Axis
    result: TuningResult
    loops_before: analysis.LoopReport | None = None
    loops_after: analysis.LoopReport | None = None
    compliance_before: tuple = ()
    compliance_after: tuple = ()
    lobes_before: StabilityLobes | None = None
    lobes_after: StabilityLobes | None = None
    two_mass: TwoMassCheck | None = None
    mode_peaks: ModePeaks | None = None
    verdict: Verdict | None = None
    thrust_before: dict | None = None
    thrust_after: dict | None = None
    c_realisation: tuple[CRealisation, ...] = ()
    process: dict | None = None
    notes: tuple[str, ...] = field(default=())
    as_given: dict | None = None
    """When the tuning started from the commissioning design: the axis as given (its design,
    current loop, the nominal models it is unstable in, the largest stable Kp)."""
    baseline: dict | None = None
    """The designs a commissioning engineer and the textbook would make
    (:func:`baseline_comparison`), each with its claim per regime (linear, and by harmonic
    balance with the verification)."""
    rounds: tuple = ()
    """The rounds of tuning and verification (:class:`TuningRound`): a refuted operating point
    (a corner of the friction's spread) becomes a model of the next round's tuning."""
    kp_limit: dict | None = None
    """With a digital drive whose initial design is unstable: the largest velocity-loop Kp
    that keeps the reference model's velocity loop stable at the initial Ti (position loop
    open), as the sampled-data system (:meth:`servotune.digital.SampledAxis.largest_stable_kp`):
    ``{"kp_max", "ti", "model", "kp_initial"}`` (SI)."""

    @property
    def design(self) -> Design:
        return self.result.design

    @property
    def verified(self) -> bool:
        """True only when the linear check holds in every regime model AND the nonlinear axis
        holds the claim in every regime (a skipped simulation is not a pass)."""
        return bool(self.verdict is not None and self.verdict.verified)

    @property
    def status(self) -> str:
        """``verified``, ``not verified`` or ``linear only`` (simulation skipped, the linear
        check held)."""
        if self.verified:
            return "verified"
        if self.verdict is None and self.result.success:
            return "linear only"
        return "not verified"

    def to_dict(self) -> dict:
        """Return the results file: SI values, the usual engineering units under suffixed keys.

        Returns
        -------
        dict
            JSON-ready data: status and reasons, the designs before and after, peaks,
            margins, loops, regimes, checks, thrust, the options realising C, the verdict,
            solver statistics and the two-mass and mode-peak checks (None where absent).
        """
        r = self.result
        before, after = r.before, r.after
        d = r.design
        regimes = None
        if self.verdict is not None:
            regimes = [v.to_dict() for v in self.verdict.regimes]
        elif after is not None:
            regimes = _linear_regimes(r)
        reasons = list(self.verdict.reasons) if self.verdict is not None else list(r.reasons)
        if self.verdict is None and r.success:
            reasons.append("the nonlinear verification was skipped (--no-simulation): the "
                           "design is checked on the linear models only")
        out = {
            "axis": self.axis.name if not self.axis.path else str(self.axis.path),
            "axis_name": self.axis.name,
            "status": self.status,
            "success": r.success,
            "verified": self.verified,
            "reasons": reasons,
            "free": list(r.problem.free),
            "design": d.to_dict(),
            "initial_design": r.initial.to_dict(),
            "start_design": None if r.start is None else r.start.to_dict(),
            "kv_m_per_min_per_mm": None if d.kv is None else d.kv * 60.0 / 1000.0,
            "kv_m_per_min_per_mm_before": None if r.initial.kv is None
            else r.initial.kv * 60.0 / 1000.0,
            "peak_compliance_before": _finite(before.peak_compliance),
            "peak_compliance_after": None if after is None else _finite(after.peak_compliance),
            "peak_frequency_before_hz": _finite(before.peak_frequency * HZ_PER_RAD_S),
            "peak_frequency_after_hz": (None if after is None
                                        else after.peak_frequency * HZ_PER_RAD_S),
            "worst_regime_model_before": None if before.worst_model is None
            else before.worst_model.model.name,
            "worst_regime_model_after": None if after is None or after.worst_model is None
            else after.worst_model.model.name,
            "b_crit_before_m": before.b_crit,
            "b_crit_after_m": None if after is None else after.b_crit,
            "stable_before": before.stable,
            "ms_velocity": None if after is None or after.velocity is None else after.velocity.ms,
            "ms_position": None if after is None or after.position is None else after.position.ms,
            "ms_velocity_before": None if before.velocity is None else before.velocity.ms,
            "ms_position_before": None if before.position is None else before.position.ms,
            "loops_before": None if self.loops_before is None else self.loops_before.to_dict(),
            "loops_after": None if self.loops_after is None else self.loops_after.to_dict(),
            "regimes": regimes,
            "regime_models": [m.to_dict() for m in r.problem.regimes],
            "excluded_models": [{"model": m.name, "reason": why} for m, why in r.excluded],
            "performance_before": before.to_dict(),
            "performance_after": None if after is None else after.to_dict(),
            "checks": [c.to_dict() for c in r.checks],
            "thrust": self.thrust_after,
            "thrust_before": self.thrust_before,
            "c_realisation": [x.to_dict() for x in self.c_realisation],
            "drive_sampling": (None if r.problem.drive is None
                               else r.problem.drive.digital.to_dict()),
            "drive_fixed": None if r.problem.drive is None else _fixed_parts(r.problem.drive),
            "process": self.process,
            "verdict": None if self.verdict is None else self.verdict.to_dict(),
            "active_constraints": list(r.active),
            "solver": r.stats.to_dict(),
            "predicted": None if r.predicted is None else r.predicted.to_dict(),
            "c_opt_analytic": (self.two_mass.c_opt_analytic
                               if self.two_mass is not None and self.result.problem.drive is None
                               else None),
            "two_mass_check": None if self.two_mass is None else self.two_mass.to_dict(),
            "mode_peaks": None if self.mode_peaks is None else self.mode_peaks.to_dict(),
            "kp_limit": self.kp_limit,
            "rounds": [x.to_dict() for x in self.rounds],
            "baseline": self.baseline,
            "as_given": self.as_given,
            "notes": list(self.notes),
        }
        return out


def _finite(value):
    return value if value is not None and math.isfinite(value) else None


def _linear_regimes(result) -> list[dict]:
    """The regimes with their linear claims only (no simulation)."""
    out = {}
    for mp in result.after.models:
        if not mp.model.cutting:
            continue
        entry = out.setdefault(mp.model.regime, {
            "name": mp.model.regime, "speed_m_per_s": mp.model.speed,
            "claimed_peak_m_per_n": 0.0, "nonlinear_peak_before_m_per_n": None,
            "nonlinear_peak_after_m_per_n": None, "band_hz": None, "holds": None,
            "reason": "not simulated (--no-simulation)"})
        peak = mp.peak_compliance if mp.stable else math.inf
        entry["claimed_peak_m_per_n"] = max(entry["claimed_peak_m_per_n"], peak)
    for entry in out.values():
        entry["claimed_peak_m_per_n"] = _finite(entry["claimed_peak_m_per_n"])
    return list(out.values())


def fig5_check(starts: int = 2) -> TwoMassCheck:
    """Tune C alone on the paper's Fig 5 system and compare with the closed-form optimum.

    The system is the two-mass layout B of Fig 5 (M1 = 5000 kg, K = 16e6 N/m, alpha = 0.3),
    undamped structure, no drive; C is tuned within [1e3, 1e8] N s/m, from 1e5 N s/m, on the
    band from the first fixed point to 4 times the second, with tolerance 1e-10: the
    optimiser's check on sec 4.1 (Eq 4 and 7).

    Parameters
    ----------
    starts : int
        Number of starting points of the tuning.

    Returns
    -------
    TwoMassCheck
        The tuned C and peak against Copt and g(alpha)/K.
    """
    from .requirements import Requirements
    from .structure.model import ModalModel

    system = twomass.TwoMassSystem(m1=5000.0, k=16e6, alpha=0.3)
    k, m1, m2 = system.k, system.m1, system.m2
    structure = ModalModel(np.diag([m1, m2]), [[k, -k], [-k, k]], ["pad1.x", "wp.x"],
                           damping_ratio=0.0)
    w_f1, w_f2 = twomass.fixed_points(system)
    problem = TuningProblem(structure, ["pad1.x"], c=1e5, free=("c",),
                            bounds={"c": (1e3, 1e8)},
                            requirements=Requirements(band=(float(w_f1), 4.0 * float(w_f2))))
    result = tune(problem, starts=starts, tolerance=1e-10)
    return TwoMassCheck(system, twomass.optimal_damping(system), result.design.c,
                        twomass.optimal_peak(system), result.after.peak_compliance)


def nonlinear_check(axis: Axis, design: Design, forces=(50.0, 600.0, 2000.0),
                    duration: float = 20.0, executor=None) -> dict:
    """Return sine sweeps of the axis with a design, compared with the linear predictions.

    The axis with LuGre pads and the design (its C as the viscous part sigma2 of the
    friction), standing still, is swept from 10 to 100 Hz and compared with the linear
    predictions (locked, presliding, viscous, describing function at the simulated pad
    amplitude); see :func:`servotune.simulate.verify.verify_design`.

    Parameters
    ----------
    axis : Axis
        The axis description (needs ``[friction]`` and ``[drive]``).
    design : Design
        The design; its Kv, Kp and Ti left None keep the axis' values.
    forces : sequence of float
        Peak-to-peak work-piece forces [N], one sweep each.
    duration : float
        Duration of each sweep [s].
    executor : concurrent.futures.Executor, optional
        Runs the sweeps in parallel.

    Returns
    -------
    dict
        As :func:`servotune.simulate.verify.verify_design`.

    Raises
    ------
    AxisFormatError
        If the axis has no ``[friction]`` or no ``[drive]``.
    ValueError
        If a design value is not a positive number.
    """
    from .simulate.setup import axis_setup
    from .simulate.verify import design_setup, verify_design

    setup = design_setup(axis_setup(axis), c=design.c, kv=design.kv, kp=design.kp,
                         ti=design.ti, notch=design.notch, lowpass=tuned_lowpass(axis, design))
    return verify_design(setup, forces=forces, duration=duration, executor=executor)


@one_thread
def check_design(axis: Axis, design: Design, feed_speeds=None) -> TuningResult:
    """Return the checks of a given design without tuning.

    The axis' regime models, the dense linear check of the design and of the axis' own one
    (``initial``) in every model, and every requirement judged (as
    :func:`servotune.tuning.solve.tune` ends).

    Parameters
    ----------
    axis : Axis
        The axis description.
    design : Design
        The design to check.
    feed_speeds : sequence of float, optional
        Feed speeds [m/s] at which the axis is judged feeding instead of its own
        ``[operation] feed_speeds`` (each gets its linear regime model, its claim and its
        share of the thrust budget).

    Returns
    -------
    TuningResult
        ``success`` when every requirement check holds; no prediction, no active constraints,
        statistics with zero starts and iterations.

    Raises
    ------
    ValueError
        If ``feed_speeds`` is given and the axis has no ``[operation]`` (no ``[drive]`` or no
        ``[friction]``).
    AxisFormatError
        If the axis has no ``[friction]``.
    """
    import dataclasses
    import time

    from .drive import current_loop_bandwidth
    from .tuning import requirement_checks, verify

    if feed_speeds is not None:
        if axis.operation is None:
            raise ValueError(f"{axis.file}: feed speeds need [drive] and [friction] (the "
                             "feeding regimes are models of the sliding guide ways)")
        axis = dataclasses.replace(axis, operation=dataclasses.replace(
            axis.operation, feed_speeds=tuple(float(v) for v in feed_speeds)))
    t0 = time.perf_counter()
    lowpass = tuned_lowpass(axis, design)
    problem = tuning_problem(axis, free=("c", "kv", "kp", "ti") if axis.drive else ("c",),
                             notch=design.notch, lowpass=lowpass)
    own = axis.drive.lowpass if axis.drive is not None else None
    x0 = dataclasses.replace(problem.initial_design(), **(
        {} if design.notch is None else {"notch_depth": 1.0}))  # the axis' own: no notch
    if lowpass is not None:    # the axis' own low-pass (or none)
        x0 = dataclasses.replace(x0, lowpass_frequency=None if own is None else
                                 2.0 * math.pi * own.f_hz)
    before = verify(problem, x0)
    after = verify(problem, design)
    current_bw = (current_loop_bandwidth(problem.drive) if problem.drive is not None else None)
    checks = requirement_checks(problem, design, after, current_bw)
    reasons = tuple(f"verification: {c.text}" for c in checks if not c.holds)
    return TuningResult(problem=problem, initial=x0, design=design, before=before, after=after,
                        predicted=None, success=not reasons, reasons=reasons, active=(),
                        stats=TuningStatistics(
                            starts=0, polished=0, iterations=0, exchange_rounds=0,
                            grid_points=0, models=len(problem.regimes), return_status=None,
                            current_loop_bandwidth_hz=(None if current_bw is None
                                                       else current_bw * HZ_PER_RAD_S),
                            time_s=time.perf_counter() - t0),
                        checks=checks)


def tuned_lowpass(axis: Axis, design: Design):
    """Return a design's tuned current set-point low-pass on an axis (its corner, the damping
    ratio of the axis' own low-pass or 1/sqrt 2), or None when the design has none.

    Parameters
    ----------
    axis : Axis
        The axis description.
    design : Design
        The design.

    Returns
    -------
    LowPassFilter or None
    """
    from .drive import LowPassFilter

    if design.lowpass_frequency is None or axis.drive is None:
        return None
    own = axis.drive.lowpass
    return LowPassFilter(design.lowpass_frequency * HZ_PER_RAD_S,
                         *(() if own is None else (own.damping_ratio,)))


def _fixed_parts(drive) -> dict:
    """The drive's parts the tuning keeps (the current loop and the set-point filters), SI."""
    return {"current_kp": drive.current_loop.kp, "current_ti": drive.current_loop.ti,
            "notches": [dataclasses.asdict(n) for n in drive.notches],
            "lowpass": None if drive.lowpass is None else dataclasses.asdict(drive.lowpass)}


def _reference_contact(problem, design):
    """The contact of the problem's reference model (the first moving one) for a design."""
    moving = problem.moving_models
    model = problem.regimes[moving[0] if moving else 0]
    return model.contact(design.c)


@one_thread
def tune_axis(axis: Axis, free=None, chatter_weight: float | None = None,
              starts: int = 4, bounds: dict | None = None, seed: int = 0,
              tolerance: float | None = None, simulate: bool = False,
              executor=None, c0: float | None = None, callback=None,
              progress=None, commission: bool = True) -> AxisTuning:
    """Tune an axis, verify it, and gather the before/after analyses.

    A Craig-Bampton structure is tuned, checked and simulated without its fixed-interface
    modes far above the band and the drive's sampling
    (:func:`servotune.verdict.simulated_structure`: their static flexibility kept, the port
    receptances within 1 % of the whole model's); the tuned design is then checked once on
    the whole structure (stable in every regime model, the worst compliance peak within 1 %),
    else it is not verified. The notes and the verdict say which structure was used.

    The tuning starts where a commissioning engineer ends
    (:func:`servotune.baseline.commissioning_design`): with a drive, friction and an
    operation, the current loop and the set-point filters of the commissioning design replace
    the axis' own (said in the notes; ``commission=False`` keeps them) and its design is the
    first start. A friction spread's corners that the first stable start leaves unstable join
    the tuning, with the least damping that holds them as the floor of C; a round whose design
    the verdict refutes at an operating point (a corner of the spread) is tuned again with it,
    up to :data:`MAX_ROUNDS` rounds.

    Parameters
    ----------
    axis : Axis
        The axis description.
    free : sequence of str, optional
        Free variables among c, kv, kp, ti; default ``[tuning] free``.
    chatter_weight : float, optional
        Weight in [0, 1] of the chatter limit; default ``[tuning] chatter_weight``.
    starts : int
        Number of starting points of the tuning.
    bounds : dict, optional
        ``{name: (low, high)}`` merged over ``[tuning] bounds`` (see :func:`tuning_problem`).
    seed : int
        Seed of the starting points.
    tolerance : float, optional
        Relative tolerance of the grid exchange; default 1e-10 for a two-mass axis, else 1e-6.
    simulate : bool
        Also run the nonlinear verdict (:func:`servotune.verdict.nonlinear_verdict`); without
        it the design is checked on the linear models only and not called verified.
    executor : concurrent.futures.Executor, optional
        Runs the nonlinear simulations in parallel.
    c0 : float, optional
        Initial guide-way damping [N s/m]; default the axis' viscous value.
    callback : casadi.Callback, optional
        IPOPT's iteration callback (e.g. to honour an interruption).
    progress : callable, optional
        ``progress(done, total)`` of the nonlinear simulations.
    commission : bool
        Start from the commissioning engineer's design, with its current loop and filters.

    Returns
    -------
    AxisTuning
        The tuning result and the analyses before and after.

    Raises
    ------
    NoStableStartError, RequirementsNotMetError, TuningDidNotConvergeError
        As :func:`servotune.tuning.solve.tune`.
    ValueError
        If ``chatter_weight`` lies outside [0, 1].
    AxisFormatError
        If the axis has no ``[friction]``, or a chatter weight is asked without
        ``[cutting]``.

    See Also
    --------
    servotune.axis.load_axis : reads the axis description.
    servotune.tuning.solve.tune : the optimisation this runs.
    servotune.tuning.verify.verify : the dense linear check of a design.
    """
    from .verdict import simulated_structure

    full = axis
    truncation = simulated_structure(axis) if axis.friction is not None else None
    if truncation is not None and truncation.truncated:
        # the modes far above the band and the drive's sampling cost every check of the
        # tuning O(n^3) and move nothing it judges: tuned without them, checked once with them
        axis = dataclasses.replace(axis, structure=truncation.structure)
    job = _tune_axis(axis, free, chatter_weight, starts, bounds, seed, tolerance, simulate,
                     executor, c0, callback, progress, commission)
    if truncation is None or not truncation.truncated:
        return job
    return _checked_on_whole_model(job, full, truncation)


def _checked_on_whole_model(job: AxisTuning, full: Axis, truncation) -> AxisTuning:
    """The tuned design checked once on the whole structure: stable in every regime model and
    its worst compliance peak within the truncation's tolerance of the reduced one's, else not
    verified; said in the notes and the verdict's checked lines."""
    from .simulate.truncation import TRUNCATION_TOLERANCE
    from .tuning.verify import verify

    result = job.result
    whole = dataclasses.replace(result.problem, structure=full.structure)
    with _progress.task(f"checking the design on the whole model ({full.structure.n} DOFs)"):
        perf = verify(whole, result.design)
    reduced = result.after
    dev = (abs(perf.peak_compliance / reduced.peak_compliance - 1.0)
           if perf.stable and reduced.stable and reduced.peak_compliance > 0 else math.inf)
    # (a design unstable on the reduced model has failed already: the line only reports)
    holds = bool(not reduced.stable or (perf.stable and dev <= TRUNCATION_TOLERANCE))
    line = (f"the structure: {truncation.describe()}, for the tuning, its linear checks and the "
            f"simulations; the tuned design checked once on the whole model "
            f"({truncation.total} fixed-interface modes): "
            + (f"stable in every regime model, worst compliance peak {perf.peak_compliance:.4g} "
               f"m/N ({100 * dev:.2g} % from the reduced model's)"
               if perf.stable and reduced.stable else
               "stable in every regime model" if perf.stable else "unstable in a regime model"))
    notes = (*job.notes, line)
    if holds:
        verdict = (None if job.verdict is None else dataclasses.replace(
            job.verdict, checked=(*job.verdict.checked, line)))
        return dataclasses.replace(job, axis=full, notes=notes, verdict=verdict)
    reason = ("on the whole model the design is unstable in a regime model" if not perf.stable
              else f"on the whole model the worst compliance peak differs by {100 * dev:.2g} % "
                   f"from the reduced model's (more than {100 * TRUNCATION_TOLERANCE:g} %)")
    result = dataclasses.replace(result, success=False, reasons=(*result.reasons, reason))
    verdict = (None if job.verdict is None else dataclasses.replace(
        job.verdict, verified=False, linear_holds=False,
        reasons=(*job.verdict.reasons, reason), checked=(*job.verdict.checked, line)))
    return dataclasses.replace(job, axis=full, result=result, notes=notes, verdict=verdict)


def _tune_axis(axis: Axis, free, chatter_weight, starts, bounds, seed, tolerance, simulate,
               executor, c0, callback, progress, commission) -> AxisTuning:
    """:func:`tune_axis` on the structure it tunes with."""
    settings = axis.tuning
    free = expand_free(settings.free if free is None else free)
    chatter_weight = settings.chatter_weight if chatter_weight is None else chatter_weight
    bounds = {**settings.bounds, **(bounds or {})}
    given = axis
    commissioned, commission_notes = None, ()
    if (commission and axis.drive is not None and axis.friction is not None
            and axis.operation is not None and ("kp" in free or "ti" in free)):
        from .baseline import commissioning_design

        try:
            with _progress.task("commissioning the axis (technical and symmetric optimum)"):
                commissioned = commissioning_design(axis)
        except ValueError as exc:
            commission_notes = (f"no commissioning start ({str(exc).splitlines()[0][:200]}): "
                                "the tuning starts from the axis' own drive",)
            axis = dataclasses.replace(axis, defaults=tuple(axis.defaults) + commission_notes)
    if commissioned is not None:
        d, own = commissioned.drive, axis.drive
        # the variables kept fixed keep the axis' own values
        d = dataclasses.replace(
            d, kv=d.kv if "kv" in free else own.kv,
            velocity_loop=PIController(d.velocity_loop.kp if "kp" in free else
                                       own.velocity_loop.kp,
                                       d.velocity_loop.ti if "ti" in free else
                                       own.velocity_loop.ti))
        commission_notes = (
            "the tuning starts from the commissioning design (servotune.baseline): its current "
            f"loop {d.current_loop.kp:.4g} V/A, {d.current_loop.ti * 1e3:.4g} ms (technical "
            f"optimum; the axis gives {own.current_loop.kp:.4g} V/A, "
            f"{own.current_loop.ti * 1e3:.4g} ms)"
            + "".join(f", its notch at {n.f_hz:.4g} Hz" for n in d.notches)
            + (f", its low-pass at {d.lowpass.f_hz:.4g} Hz" if d.lowpass is not None else "")
            + f" and its gains (Kv {d.kv:.4g} 1/s, Kp {d.velocity_loop.kp:.4g} N m s/rad, "
            f"Ti {d.velocity_loop.ti * 1e3:.4g} ms) as its start: the 'before' of the tables "
            "(commission=False, --no-commission: the axis' own)",)
        axis = dataclasses.replace(axis, drive=d, defaults=tuple(axis.defaults)
                                   + commission_notes)
    base = tuning_problem(axis, free, chatter_weight, bounds, c0)
    notch = lowpass = None
    if base.drive is not None and set(free) & set(NOTCH_VARIABLES):
        # the tuned notch starts on the resonance that lifts the start's velocity loop
        notch, why = start_notch(base)
        axis = dataclasses.replace(axis, defaults=(*axis.defaults, why))
    if base.drive is not None and set(free) & set(LOWPASS_VARIABLES):
        # the tuned low-pass starts at the drive's own (the start is the design given)
        lowpass = base.drive.lowpass
        why = ("no low-pass tuned: the drive has none ([drive.filters] lowpass_hz gives the "
               "tuning one to move)" if lowpass is None else
               f"the tuned current set-point low-pass starts at the drive's own "
               f"({lowpass.f_hz:.4g} Hz)")
        axis = dataclasses.replace(axis, defaults=(*axis.defaults, why))
    if notch is not None or lowpass is not None:
        base = tuning_problem(axis, free, chatter_weight, bounds, c0, notch=notch,
                              lowpass=lowpass)
    two_mass = _two_mass_system(axis) is not None
    if tolerance is None:
        tolerance = 1e-10 if two_mass else 1e-6
    rounds, added, c_floor, last = [], (), None, None
    # the baseline designs, on another worker while the tuning runs
    comparison = None
    if axis.drive is not None and axis.friction is not None and axis.operation is not None:
        nominal = tuple(m for m in base.regimes if m.sample == "nominal")
        comparison = (executor.submit(baseline_comparison, given, nominal, simulate,
                                      commissioned)
                      if executor is not None else (given, nominal, simulate, commissioned))

    def attach(job):
        if comparison is None:
            return job
        value = (comparison.result() if hasattr(comparison, "result")
                 else baseline_comparison(*comparison))
        return dataclasses.replace(job, baseline=value)

    if "c" in free:
        # the verdict's linear screen of the friction spread, before the first round: the
        # corners unstable at the first stable start join the tuning (the worst of each
        # regime), with the least damping that holds them as the floor of C
        added, c_floor, note = _prescreen(axis, base)
        if note:
            rounds.append(TuningRound(0, None, note, tuple(m.name for m in added)))
    hopeless = set()      # corners no damping the drive can carry holds
    for number in range(1, MAX_ROUNDS + 1):
        screen_note = ""
        problem = base
        if c_floor is not None:
            hi = base.bounds["c"][1]
            problem = tuning_problem(axis, free, chatter_weight,
                                     {**bounds, "c": (c_floor, hi)}, max(c_floor, base.c),
                                     notch=notch, lowpass=lowpass)
        if added:
            problem = dataclasses.replace(problem, regimes=problem.regimes + added)
        try:
            # a later round starts from the last design (C raised to its new floor) and
            # needs fewer starts
            first = () if last is None else (dataclasses.replace(
                last.design, c=max(last.design.c, c_floor or 0.0)),)
            n_starts = starts if last is None else min(starts, 2)
            with _progress.task(f"tuning, round {number} ({n_starts} starts)"):
                result = tune(problem, starts=n_starts, seed=seed, tolerance=tolerance,
                              callback=callback, first=first)
        except (RequirementsNotMetError, NoStableStartError, TuningDidNotConvergeError) as exc:
            if number == 1:
                raise
            # a later round found no design: the last one stands, with the reason
            rounds.append(TuningRound(number, None, f"no design: {exc}", ()))
            job = _finish(axis, last, simulate, executor, progress, two_mass,
                          given if commissioned is not None else None)
            return attach(dataclasses.replace(job, rounds=tuple(rounds)))
        last = result
        # the linear screen of the friction's spread: a corner whose model is unstable with
        # the design is refuted before anything is simulated; one whose instability no gain
        # reaches (a pad mode the friction's falling slope destabilises) needs damping: the
        # least C that holds it becomes the lower bound of C in the next round
        with _progress.task("screening the friction spread (linear)"):
            new = spread_screen(axis, result.problem, result.design)
        new = tuple(m for m in new if m.name not in {a.name for a in added})
        if new and number < MAX_ROUNDS:
            needs = []
            if "c" in problem.free:
                hi = problem.bounds["c"][1]
                for m in new:
                    c_min = stabilising_damping(result.problem, result.design, m, hi)
                    if c_min is not None and c_min > result.design.c:
                        needs.append((m, c_min))
            text = "; ".join(f"{m.name} is unstable" for m in new)
            c_max = (result.problem.thrust.c_max() if result.problem.thrust is not None
                     else math.inf)
            c_need = max((c for _, c in needs), default=None)
            if c_need is None or C_FLOOR_MARGIN * c_need > c_max:
                # no damping the drive can carry holds it: no further round; the verdict
                # names the corner
                limit = ("no C within the bounds holds it" if c_need is None else
                         f"it needs C >= {c_need:.4g} N s/m, the thrust budget allows "
                         f"{c_max:.4g} N s/m")
                screen_note = (f"the linear screen of the friction spread: {text} ({limit}): "
                               "no further round")
                hopeless |= {m.name for m in new}
            else:
                c_floor = max(c_floor or 0.0, C_FLOOR_MARGIN * c_need)
                text += (f" (with these gains it needs C >= {c_need:.4g} N s/m: the next "
                         f"round keeps C >= {c_floor:.4g} N s/m)")
                rounds.append(TuningRound(
                    number, result.design, "not verified by the linear screen of the "
                    f"friction spread: {text}", tuple(m.name for m in new)))
                added += new
                continue
        job = _finish(axis, result, simulate, executor, progress, two_mass,
                      given if commissioned is not None else None)
        new = refuted_models(job) if simulate else ()
        new = tuple(m for m in new if m.name not in {a.name for a in added} | hopeless)
        if job.verified or not new or number == MAX_ROUNDS:
            verdict = _round_verdict(job) + (f"; {screen_note}" if screen_note else "")
            rounds.append(TuningRound(number, result.design, verdict, ()))
            return attach(dataclasses.replace(job, rounds=tuple(rounds)))
        rounds.append(TuningRound(number, result.design, _round_verdict(job),
                                  tuple(m.name for m in new)))
        added += new
    raise AssertionError("unreachable")  # pragma: no cover


def baseline_comparison(axis: Axis, regimes, simulate: bool = True,
                        commissioned=None) -> dict:
    """Return the baseline designs of an axis and their claims, regime by regime.

    The commissioning engineer's design (:func:`servotune.baseline.commissioning_design`) and
    the textbook one (:func:`servotune.baseline.textbook_design`), each judged as the tuned
    design is: per regime its linear claim (the worst compliance peak of the regime's models
    on 1500 log-spaced points over the band, on the sampled-data model of a digital drive)
    and, with ``simulate``, its nonlinear peak (the largest periodic response by harmonic
    balance at the process force and three times it, the nominal friction; inf when the
    regime's loop is unstable).

    Parameters
    ----------
    axis : Axis
        The axis.
    regimes : sequence of RegimeModel
        The regime models of the nominal friction (as the tuning has them).
    simulate : bool
        Also the nonlinear peaks.
    commissioned : BaselineDesign, optional
        The commissioning design when it is known already.

    Returns
    -------
    dict
        ``commissioning`` and ``textbook``: ``design`` (the baseline's ``to_dict()``),
        ``regimes`` (``name``, ``speed_m_per_s``, ``claimed_peak_m_per_n``,
        ``nonlinear_peak_m_per_n``) and ``spread_unstable`` (the models of the friction
        spread's corners unstable with the baseline; None without a spread); SI. A baseline
        that cannot be made for the axis has ``design`` None and a ``note`` saying why.
    """
    from .baseline import commissioning_design, textbook_design
    from .closed_loop import closed_loop
    from .frequency import peak
    from .harmonic import ConvergenceError
    from .plant import UnstableLoopError
    from .simulate.simulator import NonlinearAxis
    from .verdict import FEEDING_LEVELS, harmonic_scan, verdict_spread

    omega = np.geomspace(*axis.requirements.band, 1500)
    band_hz = tuple(np.array(axis.requirements.band) * HZ_PER_RAD_S)
    process = (axis.operation.process_force_pp if axis.operation is not None
               and axis.operation.process_force_pp else 600.0)
    out = {}
    for key, make in (("commissioning", commissioning_design), ("textbook", textbook_design)):
        try:
            b = (commissioned if key == "commissioning" and commissioned is not None
                 else make(axis))
        except ValueError as exc:
            # no such design for this axis (e.g. no gain keeps a regime's loop stable): said,
            # not a failure of the tuning
            out[key] = {"design": None, "regimes": [], "spread_unstable": None,
                        "note": f"no {key} design: {str(exc).splitlines()[0][:300]}"}
            continue
        rows = []
        names = list(dict.fromkeys(m.regime for m in regimes if m.cutting))
        for name in names:
            models = [m for m in regimes if m.regime == name and m.cutting]
            claim = 0.0
            for m in models:
                loop = closed_loop(axis.structure, b.drive, m.contact(b.c), axis.pads)
                if not loop.is_stable():
                    claim = math.inf
                    break
                claim = max(claim, peak(omega, np.abs(loop.compliance(omega)[0]))[0])
            speed = models[0].speed or 0.0
            nonlinear = None
            if simulate and math.isfinite(claim):
                drive = dataclasses.replace(b.drive, velocity_feedforward=1.0)
                nl = NonlinearAxis(axis.structure, drive, axis.pads,
                                   axis.friction.law.with_viscous(float(b.c)))
                try:
                    scan = harmonic_scan(nl, speed, [process * k for k in FEEDING_LEVELS],
                                         band_hz)
                    nonlinear = max(h.peak for h in scan)
                except (ConvergenceError, UnstableLoopError):
                    nonlinear = None    # a branch harmonic balance cannot follow
            elif simulate:
                nonlinear = math.inf
            rows.append({"name": name, "speed_m_per_s": speed,
                         "claimed_peak_m_per_n": claim, "nonlinear_peak_m_per_n": nonlinear})
        # the friction spread's corners the verdict checks a design over: their stability
        spread_unstable = None
        box = verdict_spread(axis)
        if box is not None:
            spread_unstable = []
            for label, params in box.corners():
                for m in regimes:
                    corner = dataclasses.replace(m, friction=params, sample=label)
                    if not closed_loop(axis.structure, b.drive, corner.contact(b.c),
                                       axis.pads).is_stable():
                        spread_unstable.append(corner.name)
        out[key] = {"design": b.to_dict(), "regimes": rows, "spread_unstable": spread_unstable}
    return out


#: Rounds of tuning and verification at most: a refuted operating point becomes a model.
MAX_ROUNDS = 3
#: The lower bound of C after a round whose spread corner needed damping: this times the least
#: C that holds the corner with the round's gains.
C_FLOOR_MARGIN = 1.1


def stabilising_damping(problem: TuningProblem, design: Design, model: RegimeModel,
                        c_max: float, rtol: float = 1e-3) -> float | None:
    """Return the least guide-way damping C that makes a regime model stable with a design's
    gains, or None when even ``c_max`` does not.

    Bisection in log C on the closed loop's stability (the sampled-data multipliers of a
    digital drive) between the design's C and ``c_max``.

    Parameters
    ----------
    problem : TuningProblem
        The problem (structure, pads, drive).
    design : Design
        The design whose gains are kept.
    model : RegimeModel
        The model.
    c_max : float
        The largest C allowed [N s/m].
    rtol : float
        Relative width of the final bracket.

    Returns
    -------
    float or None
        The least stable C [N s/m] (the design's own C when it is stable already).
    """
    from .closed_loop import closed_loop

    def stable(c):
        d = dataclasses.replace(design, c=c)
        return closed_loop(problem.structure, problem.drive_for(d), model.contact(c),
                           problem.pads).is_stable()

    lo = max(design.c, 1e-9)
    if stable(lo):
        return lo
    if not stable(c_max):
        return None
    hi = c_max
    while hi / lo > 1.0 + rtol:
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if stable(mid) else (mid, hi)
    return hi


@dataclass(frozen=True)
class TuningRound:
    """One round of tuning and verification.

    Attributes
    ----------
    number : int
        1, 2, ...
    design : Design
        The round's design.
    verdict : str
        What the round's check said (the verdict's headline, or the linear screen).
    added : tuple of str
        The models added to the tuning for the next round (the refuted operating points).
    """

    number: int
    design: Design | None
    verdict: str
    added: tuple[str, ...]

    def to_dict(self) -> dict:
        """Return the round JSON-ready.

        Returns
        -------
        dict
            ``number``, ``design`` (None: the round found none), ``verdict``,
            ``added_models``.
        """
        return {"number": self.number,
                "design": None if self.design is None else self.design.to_dict(),
                "verdict": self.verdict, "added_models": list(self.added)}


def _round_verdict(job) -> str:
    if job.verdict is not None:
        return job.verdict.headline
    return "linear only" if job.result.success else "; ".join(job.result.reasons)


def _prescreen(axis: Axis, problem: TuningProblem):
    """The spread corners unstable at the problem's first stable start, the worst (most
    damping needed) of each regime, the floor of C they need, and what to say of it."""
    from .tuning.solve import stable_starts

    try:
        start = stable_starts(problem, 1).designs[0]
    except IndexError:
        return (), None, ""
    unstable = spread_screen(axis, problem, start)
    if not unstable:
        return (), None, ""
    hi = problem.bounds["c"][1]
    worst = {}
    for m in unstable:
        c_min = stabilising_damping(problem, start, m, hi)
        key = m.regime
        if key not in worst or (c_min or math.inf) > (worst[key][1] or math.inf):
            worst[key] = (m, c_min)
    models = tuple(m for m, _ in worst.values())
    needs = [c for _, c in worst.values() if c is not None]
    c_floor = C_FLOOR_MARGIN * max(needs) if needs else None
    head = ("the linear screen of the friction spread at the first stable start: "
            + "; ".join(f"{m.name} is unstable" for m in models))
    c_max = problem.thrust.c_max() if problem.thrust is not None else math.inf
    if not needs or c_floor > c_max:
        # no damping the drive can carry holds the corner: tuned for the others, the verdict
        # then names it, and what would change it
        need = (f"it needs C >= {max(needs):.4g} N s/m" if needs else
                f"no C up to {hi:.4g} N s/m holds it")
        limit = (f", but the thrust budget allows at most {c_max:.4g} N s/m "
                 f"({problem.thrust.c_max_case()})" if math.isfinite(c_max) else "")
        return (), None, (f"{head} ({need}{limit}): no design holds these corners; the levers: "
                          "a stronger motor or a lower rapid speed (more damping the thrust "
                          "carries), a damper that acts only while feeding, a feed above the "
                          "Stribeck speed, or a friction known to a narrower spread")
    text = (f"{head} (it needs C >= {max(needs):.4g} N s/m: the tuning keeps C >= "
            f"{c_floor:.4g} N s/m and includes these models)")
    if c_floor <= problem.bounds["c"][0]:
        c_floor = None
    return models, c_floor, text


def spread_screen(axis: Axis, problem: TuningProblem, design: Design) -> tuple:
    """Return the regime models of the friction spread's corners that are unstable with a
    design.

    The corners are the verdict's (:func:`servotune.verdict.verdict_spread`: ``[tuning]
    friction_spread``, else the identified set's own variation); each regime model of the
    nominal friction is taken with each corner's friction and its closed loop checked for
    stability (the sampled-data multipliers of a digital drive). Cheap, so it runs before the
    nonlinear verdict.

    Parameters
    ----------
    axis : Axis
        The axis.
    problem : TuningProblem
        The tuning problem (its nominal regime models).
    design : Design
        The design.

    Returns
    -------
    tuple of RegimeModel
        The unstable corner models (labelled by their corner), in order.
    """
    from .closed_loop import closed_loop
    from .verdict import verdict_spread

    if axis.friction is None or axis.drive is None:
        return ()
    box = verdict_spread(axis)
    if box is None:
        return ()
    drive = problem.drive_for(design)
    out = []
    for label, params in box.corners():
        for m in problem.regimes:
            if m.sample != "nominal" or m.friction is None:
                continue
            corner = dataclasses.replace(m, friction=params, sample=label)
            loop = closed_loop(problem.structure, drive, corner.contact(design.c), problem.pads)
            if not loop.is_stable():
                out.append(corner)
    return tuple(out)


def refuted_models(job) -> tuple:
    """Return the corner models a verdict refuted (unstable, or a periodic response above the
    claim), as regime models to tune for.

    Parameters
    ----------
    job : AxisTuning
        A job with its verdict.

    Returns
    -------
    tuple of RegimeModel
        For each regime that does not hold, the regime's nominal models with the friction of
        each of its corners that does not hold.
    """
    if job.verdict is None:
        return ()
    problem = job.result.problem
    out = []
    for regime in job.verdict.regimes:
        for corner in getattr(regime, "corners", ()):
            if corner.holds:
                continue
            for m in problem.regimes:
                if m.regime == regime.name and m.sample == "nominal":
                    out.append(dataclasses.replace(m, friction=corner.friction,
                                                   sample=corner.label))
    return tuple(out)


def _as_given(axis: Axis, problem: TuningProblem) -> dict:
    """The axis as given (its own drive and C) in the tuning's nominal models: stable or not,
    and with a digital drive that is not, the largest stable velocity Kp at its Ti."""
    from .closed_loop import closed_loop

    drive, c = axis.drive, axis.friction.viscous
    unstable = [m.name for m in problem.regimes if m.sample == "nominal"
                and not closed_loop(axis.structure, drive, m.contact(c), axis.pads).is_stable()]
    out = {"design": {"c": c, "kv": drive.kv, "kp": drive.velocity_loop.kp,
                      "ti": drive.velocity_loop.ti},
           "current_loop": {"kp": drive.current_loop.kp, "ti": drive.current_loop.ti},
           "unstable_in": unstable, "kp_limit": None}
    if unstable and not drive.digital.is_continuous:
        moving = problem.moving_models
        model = problem.regimes[moving[0] if moving else 0]
        kp_max = SampledAxis(axis.structure, drive, model.contact(c),
                             problem.pads).largest_stable_kp(rtol=1e-3)
        out["kp_limit"] = {"kp_max": kp_max, "ti": drive.velocity_loop.ti,
                           "model": model.name, "kp_initial": drive.velocity_loop.kp}
    return out


def _finish(axis: Axis, result: TuningResult, simulate: bool, executor, progress,
            two_mass: bool, given: Axis | None = None) -> AxisTuning:
    """The analyses and the verdict of a tuned design (``given``: the axis as given, when the
    tuning started from another drive)."""
    problem = result.problem
    out = {"axis": axis, "result": result, "notes": tuple(axis.defaults)}
    if given is not None and given.drive is not None and given.friction is not None:
        out["as_given"] = _as_given(given, problem)
    out["two_mass"] = two_mass_check(axis, result) if two_mass else None
    if problem.thrust is not None:
        out["thrust_before"] = problem.thrust.to_dict(result.initial.c)
        out["thrust_after"] = problem.thrust.to_dict(result.design.c)
    if axis.friction is not None and axis.drive is not None:
        amp = freq = None
        if axis.drive is not None and axis.operation is not None:
            force = axis.operation.process_force_pp or 600.0
            amp, freq = process_amplitude(axis, problem.drive_for(result.design),
                                          result.design.c, force)
            out["process"] = {"force_pp_n": force, "pad_amplitude_m": amp,
                              "frequency_hz": freq * HZ_PER_RAD_S,
                              "feed_force_n": axis.operation.feed_force}
        law = axis.friction.law
        out["c_realisation"] = c_realisations(problem.thrust, result.design.c,
                                              law.viscous_part, amp, freq,
                                              law.presliding()[0], axis.operation)
    if (axis.drive is not None and not result.before.stable
            and not axis.drive.digital.is_continuous and given is None):
        moving = problem.moving_models
        model = problem.regimes[moving[0] if moving else 0]
        initial = problem.drive_for(result.initial)
        kp_max = SampledAxis(axis.structure, initial, model.contact(result.initial.c),
                             problem.pads).largest_stable_kp(rtol=1e-3)
        out["kp_limit"] = {"kp_max": kp_max, "ti": initial.velocity_loop.ti,
                           "model": model.name, "kp_initial": initial.velocity_loop.kp}
    with _progress.task("the analyses: loops, compliance curves, lobes, modes against C"):
        if axis.drive is not None and result.after is not None:
            before_drive = problem.drive_for(result.initial)
            after_drive = problem.drive_for(result.design)
            c_before = _reference_contact(problem, result.initial)
            c_after = _reference_contact(problem, result.design)
            if result.before.stable:
                out["loops_before"] = analysis.loop_report(axis, c_before, before_drive)
            if result.after.stable:
                out["loops_after"] = analysis.loop_report(axis, c_after, after_drive)
            omega = analysis.default_omega(1.0, 1000.0, 3000)
            curves_before, curves_after = [], []
            for mp0, mp1 in zip(result.before.models, result.after.models, strict=True):
                if not mp1.model.cutting or mp1.model.sample != "nominal":
                    continue
                if mp0.stable:
                    curves_before.append(analysis.compliance_curve(
                        axis, mp0.model.contact(result.initial.c), before_drive, omega,
                        f"before, {mp0.model.name}"))
                if mp1.stable:
                    curves_after.append(analysis.compliance_curve(
                        axis, mp1.model.contact(result.design.c), after_drive, omega,
                        f"after, {mp1.model.name}"))
            out["compliance_before"] = tuple(curves_before)
            out["compliance_after"] = tuple(curves_after)
            if axis.cutting is not None:
                worst0, worst1 = result.before.worst_model, result.after.worst_model
                if worst0 is not None:
                    out["lobes_before"] = analysis.axis_lobes(
                        axis, worst0.model.contact(result.initial.c), before_drive)
                if worst1 is not None:
                    out["lobes_after"] = analysis.axis_lobes(
                        axis, worst1.model.contact(result.design.c), after_drive)
            if "c" in problem.free and result.after.stable:
                lo, hi = problem.bounds["c"]
                try:
                    # a sampled-data loop's peaks are found on its compliance: a coarser C grid
                    n_c = 61 if after_drive.digital.is_continuous else 13
                    out["mode_peaks"] = mode_peaks_vs_damping(
                        axis, np.geomspace(lo, hi, n_c), after_drive, result.design.c)
                except (ValueError, np.linalg.LinAlgError):
                    out["mode_peaks"] = None
    if axis.drive is not None and result.after is not None:
        if simulate and axis.friction is not None:
            from .verdict import nonlinear_verdict

            # one named stage with its count (and so an ETA): simulations and harmonic balance
            with _progress.task("the verdict: simulations and harmonic balance",
                                unit="run") as stage:
                def report(done, total):
                    stage.report(done, total)
                    if progress is not None:
                        progress(done, total)

                out["verdict"] = nonlinear_verdict(axis, result, executor=executor,
                                                   progress=report)
    if axis.drive is None and result.after is not None:
        omega = analysis.default_omega(1.0, 1000.0, 3000)
        out["compliance_before"] = (analysis.compliance_curve(
            axis, Contact.viscous(result.initial.c), None, omega, "before, viscous",
            controlled=False),)
        out["compliance_after"] = (analysis.compliance_curve(
            axis, Contact.viscous(result.design.c), None, omega, "after, viscous",
            controlled=False),)
    if axis.drive is None:
        from .verdict import Verdict

        # no drive, no friction law: the viscous model is the system itself, and the dense
        # check of it is the whole verification
        out["verdict"] = Verdict(
            verified=result.success, linear_holds=result.success, nonlinear_holds=None,
            regimes=(), tolerance=0.0, reasons=tuple(result.reasons),
            checked=("linear: the viscous pads without a drive are the system itself (the "
                     "paper's sec 4.1 analysis); the dense check of the compliance is the whole "
                     "verification",),
            not_checked=())
    verdict = out.get("verdict")
    if verdict is not None and verdict.verified:
        # a claim is verified only where the structure model holds: a reduced model whose
        # kept fixed-interface modes do not reach the band (with its margin) cannot verify it
        from .model_checks import band_coverage

        coverage = band_coverage(axis.structure, axis.requirements)
        if not coverage.covered:
            out["verdict"] = dataclasses.replace(
                verdict, verified=False,
                reasons=(*verdict.reasons, f"the structure model does not cover the band: "
                         f"{coverage.message}"),
                not_checked=(*verdict.not_checked, "the band beyond the reduced model's "
                             "fixed-interface modes"))
    return AxisTuning(**out)
