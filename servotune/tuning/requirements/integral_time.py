"""Integral time of the velocity PI against the velocity loop's bandwidth.

``Ti w_b`` within ``[ti_bandwidth_min, ti_bandwidth_max]`` (defaults 3 and 30, sources in
:mod:`servotune.requirements`). In the NLP, in the moving models, with the gates of
:mod:`servotune.tuning.gates`: ``|T_v| >= 1/sqrt 2`` for ``w <= r_min / Ti`` (the bandwidth
reaches ``r_min / Ti``) and ``|T_v| <= 1/sqrt 2`` for ``w`` in ``[r_max / Ti, 1.25 r_max / Ti]``
(the bandwidth stays below ``r_max / Ti``).
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
        """Return the rows of the bounds given: "Ti bandwidth min", "Ti bandwidth max"."""
        req = problem.requirements
        return tuple(n for n, on in (("Ti bandwidth min", req.ti_bandwidth_min > 0),
                                     ("Ti bandwidth max", req.ti_bandwidth_max > 0)) if on)

    @classmethod
    def loop_rows(cls, problem, q, gate) -> list:
        """Return the gated rows of the bounds given."""
        import casadi as ca

        req = problem.requirements
        on_lo, edge_lo, on_hi, edge_hi = gate
        rows = []
        if req.ti_bandwidth_min > 0:
            edge = edge_lo - ca.log(q.ti)
            rows.append((q.tv2 - 0.5) / (q.tv2 + 0.5) + gate_switch(q.log_omega - edge)
                        + GATE_OFF * (1 - on_lo))
        if req.ti_bandwidth_max > 0:
            edge = edge_hi - ca.log(q.ti)
            rows.append((0.5 - q.tv2) / (0.5 + q.tv2) + gate_switch(edge - q.log_omega)
                        + gate_switch(q.log_omega - edge - math.log(1.25))
                        + GATE_OFF * (1 - on_hi))
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
