"""The thrust budget: what the motor must push, C v included, within its usable thrust.

A viscous guide-way damper C resists feeding: its force C v adds to the process force,
friction and acceleration the motor must supply. Each case of the budget
(:class:`servotune.thrust.ThrustBudget`: accelerating to rapid speed against the peak thrust,
traversing at rapid speed and feeding at each feed speed against the continuous thrust) is a row
linear in C: ``(F_fix + C v) / F_usable(v) <= 1``, with the usable thrust of the motor's
torque-speed curve taken at the case's speed v (a constant for the given design variables, so
the row stays affine in C). Together the rows bound C by
:meth:`servotune.thrust.ThrustBudget.c_max`, the minimum over the cases.
"""

from __future__ import annotations

from ..constraint import Requirement, RequirementCheck

__all__ = ["ThrustBudget"]


class ThrustBudget(Requirement):
    """Every thrust case within the motor's usable thrust (the reserve kept)."""

    name = "thrust"
    order = 50.0

    @classmethod
    def applies(cls, problem) -> bool:
        """Return whether the problem has a thrust budget."""
        return problem.thrust is not None

    @classmethod
    def design_rows(cls, problem, value) -> list:
        """Return ``(F_fix + C v) / F_usable(v) <= 1`` for each case with a speed, C free
        (the cases of :meth:`servotune.thrust.ThrustBudget.linear_form`)."""
        if "c" not in problem.free:
            return []
        return [(f"thrust: {name}", (fixed + value("c") * speed) / usable, -float("inf"), 1.0)
                for fixed, speed, usable, name in problem.thrust.linear_form() if speed > 0]

    @classmethod
    def design_checks(cls, problem, design) -> list:
        """Return each thrust case at the design's C."""
        return [RequirementCheck(
            cls.name, case.name, case.needed, case.usable, case.fits,
            f"thrust at {case.name}: needs {case.needed / 1e3:.3g} kN of "
            f"{case.usable / 1e3:.3g} kN usable ({case.thrust_kind} at {case.speed:.3g} m/s, "
            f"{problem.thrust.margin:.0%} kept in reserve)")
            for case in problem.thrust.cases(design.c)]
