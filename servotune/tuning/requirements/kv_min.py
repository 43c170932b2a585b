"""The smallest position-loop gain Kv the machine accepts (following error per feed speed)."""

from __future__ import annotations

from ..constraint import Requirement, RequirementCheck

__all__ = ["KvMin"]


class KvMin(Requirement):
    """Kv >= ``kv_min`` [1/s]."""

    name = "kv_min"
    order = 60.0

    @classmethod
    def applies(cls, problem) -> bool:
        """Return whether ``kv_min`` > 0 is given."""
        return problem.requirements.kv_min > 0

    @classmethod
    def design_rows(cls, problem, value) -> list:
        """Return ``Kv / kv_min >= 1`` when Kv is free."""
        if "kv" not in problem.free:
            return []
        return [(cls.name, value("kv") / problem.requirements.kv_min, 1.0, float("inf"))]

    @classmethod
    def design_checks(cls, problem, design) -> list:
        """Return Kv against ``kv_min``."""
        kv_min = problem.requirements.kv_min
        if design.kv is None:
            return []
        return [RequirementCheck(cls.name, None, design.kv, kv_min,
                                 design.kv >= kv_min * (1 - 1e-9),
                                 f"Kv {design.kv:.4g} 1/s (at least {kv_min:.4g})")]
