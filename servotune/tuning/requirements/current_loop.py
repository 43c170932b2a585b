"""The current loop clearly faster than the velocity loop.

The current loop's bandwidth w_i (fixed: the drive's current PI is not tuned) at least
``current_bandwidth_ratio_min`` times the velocity loop's: in the NLP, in the moving models,
``|T_v| <= 1/sqrt 2`` for ``w`` in ``[w_i / N_i, 1.25 w_i / N_i]`` with the gates of
:mod:`servotune.tuning.gates` (defaults and sources: :mod:`servotune.requirements`).
"""

from __future__ import annotations

import math

from ..constraint import CHECK_TOLERANCE, Requirement, RequirementCheck
from ..gates import GATE_OFF, GATE_SAFETY, gate_switch

__all__ = ["CurrentLoopAbove"]


class CurrentLoopAbove(Requirement):
    """Current-loop bandwidth >= ``current_bandwidth_ratio_min`` x the velocity loop's."""

    name = "current loop above"
    order = 40.0
    gate_size = 2
    moving_only = True

    @classmethod
    def applies(cls, problem) -> bool:
        """Return whether a drive and a ratio > 0 are given."""
        return (problem.drive is not None
                and problem.requirements.current_bandwidth_ratio_min > 0)

    @classmethod
    def gate(cls, problem, model, gamma, current_bandwidth) -> tuple[float, ...]:
        """Return (on, log of the window's edge w_i / N_i / safety)."""
        req = problem.requirements
        on = float(model in set(problem.moving_models))
        wx = (current_bandwidth / req.current_bandwidth_ratio_min
              if current_bandwidth and req.current_bandwidth_ratio_min else 1.0)
        return on * (current_bandwidth is not None), math.log(wx / GATE_SAFETY)

    @classmethod
    def row_names(cls, problem) -> tuple[str, ...]:
        """Return ``("current loop above",)``."""
        return (cls.name,)

    @classmethod
    def loop_rows(cls, problem, q, gate) -> list:
        """Return the gated row ``|T_v| <= 1/sqrt 2`` in the window."""
        on, edge = gate
        return [(0.5 - q.tv2) / (0.5 + q.tv2) + gate_switch(edge - q.log_omega)
                + gate_switch(q.log_omega - edge - math.log(1.25)) + GATE_OFF * (1 - on)]

    @classmethod
    def model_checks(cls, problem, design, performance, moving, current_bandwidth) -> list:
        """Return the current over velocity bandwidth ratio in a moving model (2 % slack)."""
        if not moving or performance.velocity is None or current_bandwidth is None:
            return []
        from ...units import HZ_PER_RAD_S

        req = problem.requirements
        name = performance.model.name
        bw_v = performance.velocity.bandwidth
        ratio = current_bandwidth / bw_v if bw_v > 0 else math.inf
        return [RequirementCheck(
            cls.name, name, ratio, req.current_bandwidth_ratio_min,
            bool(ratio >= req.current_bandwidth_ratio_min * (1 - CHECK_TOLERANCE["ratio"])),
            f"{name}: current-loop bandwidth {current_bandwidth * HZ_PER_RAD_S:.3g} Hz "
            f"is {ratio:.3g} times the velocity loop's (at least "
            f"{req.current_bandwidth_ratio_min:g})")]
