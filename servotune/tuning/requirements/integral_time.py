"""Integral time of the velocity PI against the velocity loop's bandwidth.

``Ti w_b`` within ``[ti_bandwidth_min, ti_bandwidth_max]`` (defaults 3 and 30, sources in
:mod:`servotune.requirements`), w_b the velocity loop's bandwidth: the *first* frequency where
``|T_v|`` falls to 1/sqrt 2. In the NLP, in the moving models, with the gates of
:mod:`servotune.tuning.gates`: ``|T_v| >= 1/sqrt 2`` for ``w <= r_min / Ti`` (the first crossing
lies beyond ``r_min / Ti``: a condition at every frequency below the edge, exact).

The upper bound is judged on the design (:meth:`IntegralTime.model_checks`, on the dense
check's first crossing) but is not a row of the NLP: "the first crossing lies below
``r_max / Ti``" holds where ``|T_v|`` is *somewhere* below the edge, which no condition at every
frequency of a window can say; the windowed row ``|T_v| <= 1/sqrt 2`` on ``[r_max / Ti,
1.25 r_max / Ti]`` it replaced also forbade designs whose window met a drive-train resonance
where ``|T_v|`` climbs back above 1/sqrt 2 (on the bundled axis near 184 Hz), which split the
feasible Ti into islands and let the start decide the optimum. A design that breaks the upper
bound is reported by the check (the tuning then fails with that reason).
"""

from __future__ import annotations

import math

from ..constraint import CHECK_TOLERANCE, Requirement, RequirementCheck
from ..gates import GATE_OFF, GATE_SAFETY, gate_switch

__all__ = ["IntegralTime"]


class IntegralTime(Requirement):
    """Ti times the velocity-loop bandwidth within ``[ti_bandwidth_min, ti_bandwidth_max]``."""

    name = "Ti and velocity bandwidth"
    order = 30.0
    gate_size = 4
    moving_only = True

    @classmethod
    def applies(cls, problem) -> bool:
        """Return whether a drive and a bound of the range are given."""
        req = problem.requirements
        return problem.drive is not None and bool(req.ti_bandwidth_min or req.ti_bandwidth_max)

    @classmethod
    def gate(cls, problem, model, gamma, current_bandwidth) -> tuple[float, ...]:
        """Return (on, log edge) of the lower and of the upper bound."""
        req = problem.requirements
        on = float(model in set(problem.moving_models))
        return (on * (req.ti_bandwidth_min > 0),
                math.log(GATE_SAFETY * max(req.ti_bandwidth_min, 1e-9)),
                on * (req.ti_bandwidth_max > 0),
                math.log(max(req.ti_bandwidth_max, 1e-9) / GATE_SAFETY))

    @classmethod
    def row_names(cls, problem) -> tuple[str, ...]:
        """Return the NLP's row of the lower bound, "Ti bandwidth min" (the upper bound is
        checked on the design only: see the module docstring)."""
        req = problem.requirements
        return ("Ti bandwidth min",) if req.ti_bandwidth_min > 0 else ()

    @classmethod
    def loop_rows(cls, problem, q, gate) -> list:
        """Return the gated row of the lower bound."""
        import casadi as ca

        req = problem.requirements
        on_lo, edge_lo, _, _ = gate   # the upper edge: gate() keeps the layout
        rows = []
        if req.ti_bandwidth_min > 0:
            edge = edge_lo - ca.log(q.ti)
            rows.append((q.tv2 - 0.5) / (q.tv2 + 0.5) + gate_switch(q.log_omega - edge)
                        + GATE_OFF * (1 - on_lo))
        return rows

    @classmethod
    def model_checks(cls, problem, design, performance, moving, current_bandwidth) -> list:
        """Return Ti w_b against the range in a moving model (2 % slack)."""
        bw_v = performance.velocity.bandwidth if performance.velocity is not None else None
        if not moving or bw_v is None or design.ti is None or not math.isfinite(bw_v):
            return []
        from ...units import HZ_PER_RAD_S

        req = problem.requirements
        name = performance.model.name
        slack = 1 - CHECK_TOLERANCE["ratio"]
        value = design.ti * bw_v
        lo_ok = value >= req.ti_bandwidth_min * slack
        hi_ok = not req.ti_bandwidth_max or value <= req.ti_bandwidth_max / slack
        return [RequirementCheck(
            cls.name, name, value,
            req.ti_bandwidth_min if not lo_ok else (req.ti_bandwidth_max or None),
            bool(lo_ok and hi_ok),
            f"{name}: Ti times the velocity-loop bandwidth ({bw_v * HZ_PER_RAD_S:.3g} Hz) is "
            f"{value:.3g} (within [{req.ti_bandwidth_min:g}, "
            f"{req.ti_bandwidth_max or math.inf:g}])")]
