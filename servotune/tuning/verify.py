"""The independent check of a design: python-control state space, dense grids, every model.

The optimiser works on port-coupled frequency responses on grids it refines itself; the check
builds each regime model's closed loop (:func:`servotune.closed_loop.closed_loop`: the
python-control state space of a continuous drive, the exact sampled-data model of a digital
one, :class:`servotune.digital.SampledAxis`), tests its stability, and evaluates compliance,
chatter limit and both loops on grids offset from any the optimiser builds. Each requirement
is then judged by :func:`requirement_checks`, one :class:`RequirementCheck` per requirement and
model, so that the verdict, the JSON and the report all read the same list.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import frequency
from ..closed_loop import closed_loop
from ..plant import UnstableLoopError
from ..regimes import RegimeModel
from ..units import HZ_PER_RAD_S
from .constraint import CHECK_TOLERANCE, RequirementCheck, requirements
from .problem import Design, TuningProblem

__all__ = ["ModelPerformance", "Performance", "RequirementCheck", "verify",
           "requirement_checks", "CHECK_TOLERANCE"]



@dataclass(frozen=True)
class ModelPerformance:
    """What a design achieves with one regime model (SI; None where it does not apply).

    Parameters
    ----------
    model : RegimeModel
        The regime model.
    stable : bool
        Whether the closed loop (and, with a drive, both loops) is stable.
    peak_compliance : float, optional
        Peak work-piece compliance [m/N] over the requirements band (cutting models).
    peak_frequency : float, optional
        Its angular frequency [rad/s].
    b_crit : float, optional
        Critical depth of cut [m] (with a chatter target).
    velocity, position : servotune.frequency.LoopAnalysis, optional
        The velocity loop (position loop open) and the position loop (velocity loop closed).
    reason : str
        Why the model is unstable.
    """

    model: RegimeModel
    stable: bool
    peak_compliance: float | None = None
    peak_frequency: float | None = None
    b_crit: float | None = None
    velocity: frequency.LoopAnalysis | None = None
    position: frequency.LoopAnalysis | None = None
    reason: str = ""

    def to_dict(self) -> dict:
        """Return the model's performance as JSON-ready data.

        Returns
        -------
        dict
            The model's own data (:meth:`RegimeModel.to_dict`), stability and reason, peak
            [m/N] and its frequency [Hz], ``b_crit_m`` and both loops.
        """
        return {**self.model.to_dict(), "stable": self.stable, "reason": self.reason or None,
                "peak_compliance": self.peak_compliance,
                "peak_frequency_hz": None if self.peak_frequency is None
                else self.peak_frequency * HZ_PER_RAD_S,
                "b_crit_m": self.b_crit,
                "velocity_loop": self.velocity.to_dict() if self.velocity else None,
                "position_loop": self.position.to_dict() if self.position else None}


@dataclass(frozen=True)
class Performance:
    """What a design achieves over every regime model.

    ``peak_compliance`` is the worst over the cutting models (inf when one is unstable),
    ``b_crit`` the smallest (0 when a cutting model is unstable); ``velocity`` and
    ``position`` are the loops of the reference model (the first moving one, where loop
    bandwidths mean something, else the first).

    Parameters
    ----------
    models : tuple of ModelPerformance
        One per regime model, in the order of ``problem.regimes``.
    reference : int
        Index of the reference model.
    notes : tuple of str
        Remarks shown with the results.
    """

    models: tuple[ModelPerformance, ...]
    reference: int = 0
    notes: tuple[str, ...] = field(default=())

    @property
    def stable(self) -> bool:
        return all(m.stable for m in self.models)

    def _cutting(self):
        return [m for m in self.models if m.model.cutting]

    @property
    def peak_compliance(self) -> float:
        cut = self._cutting()
        if any(not m.stable for m in cut):
            return math.inf
        return max(m.peak_compliance for m in cut)

    @property
    def peak_frequency(self) -> float:
        cut = [m for m in self._cutting() if m.stable]
        if not cut:
            return math.nan
        return max(cut, key=lambda m: m.peak_compliance).peak_frequency

    @property
    def worst_model(self) -> ModelPerformance | None:
        cut = [m for m in self._cutting() if m.stable]
        return max(cut, key=lambda m: m.peak_compliance) if cut else None

    @property
    def b_crit(self) -> float | None:
        values = [m.b_crit for m in self._cutting() if m.b_crit is not None]
        if any(not m.stable for m in self._cutting()):
            return 0.0 if values else None
        return min(values) if values else None

    @property
    def velocity(self) -> frequency.LoopAnalysis | None:
        return self.models[self.reference].velocity

    @property
    def position(self) -> frequency.LoopAnalysis | None:
        return self.models[self.reference].position

    def to_dict(self) -> dict:
        """Return the performance as JSON-ready data.

        Returns
        -------
        dict
            The worst peak [m/N] and its frequency [Hz], ``b_crit_m``, stability, the
            reference model's name and loops, and every model's performance.
        """
        return {"peak_compliance": self.peak_compliance,
                "peak_frequency_hz": self.peak_frequency * HZ_PER_RAD_S,
                "b_crit_m": self.b_crit, "stable": self.stable,
                "reference_model": self.models[self.reference].model.name,
                "velocity_loop": self.velocity.to_dict() if self.velocity else None,
                "position_loop": self.position.to_dict() if self.position else None,
                "models": [m.to_dict() for m in self.models]}


def _offset_grid(lo: float, hi: float, n: int) -> np.ndarray:
    """A log grid offset by a third of a step from any grid the optimiser builds."""
    ratio = (hi / lo) ** (1.0 / (n - 1))
    omega = lo * ratio ** (np.arange(n) + 1.0 / 3.0)
    return omega[omega <= hi]


def verify(problem: TuningProblem, design: Design) -> Performance:
    """Return the performance of a design in every regime model, on dense grids.

    For each regime model the closed loop is built (:func:`servotune.closed_loop.closed_loop`:
    the python-control state space of a continuous drive, the sampled-data system of a digital
    one) and its stability tested (poles, or the multipliers over the slowest sample period);
    a stable cutting model gets its compliance peak on 6001 log-spaced points over the
    requirements band and, with a chatter target, its critical depth; with a drive, both loops
    are analysed on 8001 points over the loop band (up to each loop's Nyquist frequency when
    sampled). The grids are offset by a third of a step from any grid the optimiser builds. An
    unstable model is reported, not raised.

    Parameters
    ----------
    problem : TuningProblem
        Structure, pads, drive, regime models, requirements and chatter target.
    design : Design
        The design to check.

    Returns
    -------
    Performance
        One :class:`ModelPerformance` per regime model; the reference model is the first
        moving one (else the first).

    See Also
    --------
    servotune.tuning.solve.tune : the optimisation whose result this checks.
    servotune.design.tune_axis : the design job that runs both on an axis.
    """
    req = problem.requirements
    drive = problem.drive_for(design)
    band = _offset_grid(*req.band, 6001)
    loop_omega = _offset_grid(*req.loop_band, 8001)
    out = []
    for model in problem.regimes:
        contact = model.contact(design.c) if problem.pads else None
        pads = problem.pads
        axis = closed_loop(problem.structure, drive, contact, pads)
        try:
            axis.require_stable(what=f"closed loop ({model.name})")
        except UnstableLoopError as exc:
            out.append(ModelPerformance(model, False, reason=str(exc)))
            continue
        peak = w_peak = b_crit = None
        if model.cutting:
            h = axis.compliance(band, problem.force, [problem.force])[0]
            peak, w_peak = frequency.peak(band, h)
            if problem.chatter is not None:
                from ..chatter import critical_depth

                b_crit = critical_depth(problem.chatter.mu * h.real, problem.chatter.kt, band)
        velocity = position = None
        if drive is not None:
            try:
                velocity = axis.analyse_loop("velocity", loop_omega)
                position = axis.analyse_loop("position", loop_omega)
            except UnstableLoopError as exc:
                out.append(ModelPerformance(model, False, peak, w_peak, b_crit,
                                            reason=f"{model.name}: {exc}"))
                continue
        out.append(ModelPerformance(model, True, peak, w_peak, b_crit, velocity, position))
    moving = problem.moving_models
    return Performance(tuple(out), moving[0] if moving else 0)


def requirement_checks(problem: TuningProblem, design: Design, performance: Performance,
                       current_bandwidth: float | None) -> tuple[RequirementCheck, ...]:
    """Return every requirement of the problem judged on a verified performance.

    Per model: stability, then each requirement's checks in that model
    (:meth:`Requirement.model_checks` of :mod:`servotune.tuning.requirements`: the Ms of each
    loop against :meth:`Requirements.ms_limit` with 0.5 % slack; in the moving models the
    loop hierarchy, Ti times the velocity bandwidth and the current loop above, each with 2 %
    slack, :data:`CHECK_TOLERANCE`). Then the checks of the design itself
    (:meth:`Requirement.design_checks`: each thrust case at the design's C, Kv against
    ``kv_min``).

    Parameters
    ----------
    problem : TuningProblem
        Requirements, regime models and thrust budget.
    design : Design
        The design judged.
    performance : Performance
        Its dense check (:func:`verify`).
    current_bandwidth : float or None
        Closed-loop bandwidth of the current loop [rad/s] (None: not judged).

    Returns
    -------
    tuple of RequirementCheck
        The checks, model by model, then thrust and Kv.
    """
    out = []
    moving = set(problem.moving_models)
    active = requirements(problem)
    for i, mp in enumerate(performance.models):
        name = mp.model.name
        if not mp.stable:
            out.append(RequirementCheck("stability", name, None, None, False,
                                        f"{name}: unstable ({mp.reason})"))
            continue
        out.append(RequirementCheck("stability", name, None, None, True, f"{name}: stable"))
        for requirement in active:
            out += requirement.model_checks(problem, design, mp, i in moving, current_bandwidth)
    for requirement in active:
        out += requirement.design_checks(problem, design)
    return tuple(out)
