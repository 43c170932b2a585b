"""The independent check of a design: python-control state space, dense grids, every model.

The optimiser works on port-coupled frequency responses on grids it refines itself; the check
builds each regime model's closed loop as a state space (:func:`servotune.plant.build_plant`,
with the digital drive's delays as Pade blocks), tests its poles, and evaluates compliance,
chatter limit and both loops on grids offset from any the optimiser builds. Each requirement
is then judged by :func:`requirement_checks`, one :class:`RequirementCheck` per requirement and
model, so that the verdict, the JSON and the report all read the same list.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import frequency
from ..plant import UnstableLoopError, build_plant, loop_transfer
from ..regimes import RegimeModel
from ..structure.model import signal_name
from ..units import HZ_PER_RAD_S
from .problem import Design, TuningProblem

__all__ = ["ModelPerformance", "Performance", "RequirementCheck", "verify",
           "requirement_checks", "CHECK_TOLERANCE"]

#: Relative slack of the dense check on a requirement the optimiser imposed exactly (the grid
#: exchange converges to this order; the gates of the hierarchy constraints are soft by a few
#: percent, see :mod:`servotune.tuning.nlp`).
CHECK_TOLERANCE = {"ms": 0.005, "ratio": 0.02}


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

    For each regime model the closed loop is built as a python-control state space
    (:func:`servotune.plant.build_plant`, the digital drive's delays as Pade blocks) and its
    poles tested; a stable cutting model gets its compliance peak on 6001 log-spaced points
    over the requirements band and, with a chatter target, its critical depth; with a drive,
    both loops are analysed on 8001 points over the loop band. The grids are offset by a third
    of a step from any grid the optimiser builds. An unstable model is reported, not raised.

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
        plant = build_plant(problem.structure, drive, contact, pads)
        try:
            frequency.require_stable(plant, what=f"closed loop ({model.name})")
        except UnstableLoopError as exc:
            out.append(ModelPerformance(model, False, reason=str(exc)))
            continue
        peak = w_peak = b_crit = None
        if model.cutting:
            h = frequency.compliance(plant, band, force=signal_name(problem.force, "f_"),
                                     output=signal_name(problem.force))
            peak, w_peak = frequency.peak(band, h)
            if problem.chatter is not None:
                from ..chatter import critical_depth

                b_crit = critical_depth(problem.chatter.mu * h.real, problem.chatter.kt, band)
        velocity = position = None
        if drive is not None:
            try:
                velocity = frequency.analyse_loop(
                    loop_transfer(problem.structure, drive, contact, pads, "velocity"),
                    loop_omega)
                position = frequency.analyse_loop(
                    loop_transfer(problem.structure, drive, contact, pads, "position"),
                    loop_omega)
            except UnstableLoopError as exc:
                out.append(ModelPerformance(model, False, peak, w_peak, b_crit,
                                            reason=f"{model.name}: {exc}"))
                continue
        out.append(ModelPerformance(model, True, peak, w_peak, b_crit, velocity, position))
    moving = problem.moving_models
    return Performance(tuple(out), moving[0] if moving else 0)


@dataclass(frozen=True)
class RequirementCheck:
    """One requirement judged on the dense check of one model (or of the axis).

    Parameters
    ----------
    requirement : str
        The requirement (``"stability"``, ``"Ms velocity loop"``, ``"loop hierarchy"``,
        ``"thrust"``, ``"kv_min"``, ...).
    model : str or None
        The regime model's name (the thrust case for ``"thrust"``); None for the axis.
    value, limit : float or None
        The value reached and the limit it is judged against.
    holds : bool
        Whether the requirement holds.
    text : str
        One line for the reader.
    """

    requirement: str
    model: str | None
    value: float | None
    limit: float | None
    holds: bool
    text: str

    def to_dict(self) -> dict:
        """Return the check as JSON-ready data.

        Returns
        -------
        dict
            The fields by name.
        """
        return {"requirement": self.requirement, "model": self.model, "value": self.value,
                "limit": self.limit, "holds": self.holds, "text": self.text}


def requirement_checks(problem: TuningProblem, design: Design, performance: Performance,
                       current_bandwidth: float | None) -> tuple[RequirementCheck, ...]:
    """Return every requirement of the problem judged on a verified performance.

    Per model: stability, and the Ms of each loop against :meth:`Requirements.ms_limit`
    (0.5 % slack, :data:`CHECK_TOLERANCE`). Per moving model with a velocity loop: the
    velocity over position bandwidth ratio, Ti times the velocity bandwidth within its range,
    and the current over velocity bandwidth ratio, each with 2 % slack. Then each thrust case
    of the thrust budget at the design's C, and Kv against ``kv_min``.

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
    req = problem.requirements
    out = []
    moving = set(problem.moving_models)
    for i, mp in enumerate(performance.models):
        name = mp.model.name
        if not mp.stable:
            out.append(RequirementCheck("stability", name, None, None, False,
                                        f"{name}: unstable ({mp.reason})"))
            continue
        out.append(RequirementCheck("stability", name, None, None, True, f"{name}: stable"))
        for loop, la in (("velocity", mp.velocity), ("position", mp.position)):
            if la is None:
                continue
            limit = req.ms_limit(loop)
            out.append(RequirementCheck(
                f"Ms {loop} loop", name, la.ms, limit, la.ms <= limit * (1 + CHECK_TOLERANCE["ms"]),
                f"{name}: Ms of the {loop} loop {la.ms:.3f} (limit {limit:.3f})"))
        if i not in moving or mp.velocity is None:
            continue
        bw_v, bw_p = mp.velocity.bandwidth, mp.position.bandwidth
        slack = 1 - CHECK_TOLERANCE["ratio"]
        if req.bandwidth_ratio_min > 0:
            ratio = bw_v / bw_p if bw_p > 0 else math.inf
            out.append(RequirementCheck(
                "loop hierarchy", name, ratio, req.bandwidth_ratio_min,
                bool(ratio >= req.bandwidth_ratio_min * slack),
                f"{name}: velocity-loop bandwidth {bw_v * HZ_PER_RAD_S:.3g} Hz is {ratio:.3g} "
                f"times the "
                f"position loop's {bw_p * HZ_PER_RAD_S:.3g} Hz "
                f"(at least {req.bandwidth_ratio_min:g})"))
        ti = design.ti
        if ti is not None and math.isfinite(bw_v) and (req.ti_bandwidth_min
                                                       or req.ti_bandwidth_max):
            value = ti * bw_v
            lo_ok = value >= req.ti_bandwidth_min * slack
            hi_ok = not req.ti_bandwidth_max or value <= req.ti_bandwidth_max / slack
            out.append(RequirementCheck(
                "Ti and velocity bandwidth", name, value,
                req.ti_bandwidth_min if not lo_ok else (req.ti_bandwidth_max or None),
                bool(lo_ok and hi_ok),
                f"{name}: Ti times the velocity-loop bandwidth ({bw_v * HZ_PER_RAD_S:.3g} Hz) is "
                f"{value:.3g} (within [{req.ti_bandwidth_min:g}, "
                f"{req.ti_bandwidth_max or math.inf:g}])"))
        if req.current_bandwidth_ratio_min > 0 and current_bandwidth is not None:
            ratio = current_bandwidth / bw_v if bw_v > 0 else math.inf
            out.append(RequirementCheck(
                "current loop above", name, ratio, req.current_bandwidth_ratio_min,
                bool(ratio >= req.current_bandwidth_ratio_min * slack),
                f"{name}: current-loop bandwidth {current_bandwidth * HZ_PER_RAD_S:.3g} Hz "
                f"is {ratio:.3g} "
                f"times the velocity loop's (at least {req.current_bandwidth_ratio_min:g})"))
    if problem.thrust is not None:
        for case in problem.thrust.cases(design.c):
            out.append(RequirementCheck(
                "thrust", case.name, case.needed, case.usable, case.fits,
                f"thrust at {case.name}: needs {case.needed / 1e3:.3g} kN of "
                f"{case.usable / 1e3:.3g} kN usable ({case.thrust_kind}, "
                f"{problem.thrust.margin:.0%} kept in reserve)"))
    if design.kv is not None and req.kv_min > 0:
        out.append(RequirementCheck("kv_min", None, design.kv, req.kv_min,
                                    design.kv >= req.kv_min * (1 - 1e-9),
                                    f"Kv {design.kv:.4g} 1/s (at least {req.kv_min:.4g})"))
    return tuple(out)
