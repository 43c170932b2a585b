"""Loop hierarchy: the velocity loop at least N times as wide as the position loop.

The closed velocity loop must pass (``|T_v| >= 1/sqrt 2``) every frequency up to N times the
position loop's bandwidth ``gamma Kv`` (gamma, the ratio of that bandwidth to Kv, is updated by
the solve between exchange rounds). In the NLP, with the smooth gate of
:mod:`servotune.tuning.nlp`::

    (|T_v|^2 - 1/2) / (|T_v|^2 + 1/2) + sigma(kappa (log w - log(S N gamma Kv))) >= 0

in the moving models (sliding or viscous pads), S = ``GATE_SAFETY``. Defaults and sources:
:mod:`servotune.requirements`.
"""

from __future__ import annotations

import math

from ..constraint import CHECK_TOLERANCE, Requirement, RequirementCheck
from ..gates import GATE_OFF, GATE_SAFETY, gate_switch

__all__ = ["LoopHierarchy"]


class LoopHierarchy(Requirement):
    """Velocity-loop bandwidth >= ``bandwidth_ratio_min`` x the position loop's."""

    name = "loop hierarchy"
    order = 20.0
    gate_size = 2
    moving_only = True

    @classmethod
    def applies(cls, problem) -> bool:
        """Return whether a drive and a ratio > 0 are given."""
        return problem.drive is not None and problem.requirements.bandwidth_ratio_min > 0

    @classmethod
    def gate(cls, problem, model, gamma, current_bandwidth) -> tuple[float, ...]:
        """Return (on, log of the edge over Kv): on in the moving models."""
        n_ratio = problem.requirements.bandwidth_ratio_min
        on = float(model in set(problem.moving_models))
        return on, math.log(GATE_SAFETY * max(n_ratio, 1.0) * gamma)

    @classmethod
    def row_names(cls, problem) -> tuple[str, ...]:
        """Return ``("loop hierarchy",)``."""
        return (cls.name,)

    @classmethod
    def loop_rows(cls, problem, q, gate) -> list:
        """Return the gated row ``|T_v| >= 1/sqrt 2`` below the edge."""
        on, edge = gate
        edge = edge + _log(q.kv)
        return [(q.tv2 - 0.5) / (q.tv2 + 0.5) + gate_switch(q.log_omega - edge)
                + GATE_OFF * (1 - on)]

    @classmethod
    def model_checks(cls, problem, design, performance, moving, current_bandwidth) -> list:
        """Return the bandwidth ratio of the loops in a moving model (2 % slack)."""
        if not moving or performance.velocity is None:
            return []
        from ...units import HZ_PER_RAD_S

        req = problem.requirements
        name = performance.model.name
        bw_v, bw_p = performance.velocity.bandwidth, performance.position.bandwidth
        ratio = bw_v / bw_p if bw_p > 0 else math.inf
        return [RequirementCheck(
            cls.name, name, ratio, req.bandwidth_ratio_min,
            bool(ratio >= req.bandwidth_ratio_min * (1 - CHECK_TOLERANCE["ratio"])),
            f"{name}: velocity-loop bandwidth {bw_v * HZ_PER_RAD_S:.3g} Hz is {ratio:.3g} "
            f"times the position loop's {bw_p * HZ_PER_RAD_S:.3g} Hz "
            f"(at least {req.bandwidth_ratio_min:g})")]


def _log(x):
    import casadi as ca

    return ca.log(x)
