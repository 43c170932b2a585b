"""Loop robustness: the sensitivity peak Ms of the velocity and of the position loop.

A Nyquist curve outside the circle of radius 1/Ms about -1 keeps ``|1 + L| >= 1/Ms`` at every
frequency, so the NLP imposes ``Ms^2 |1 + L(jw)|^2 >= 1`` at the loop frequencies of every
regime model; the limits include what the gain and phase margin requirements imply
(:meth:`servotune.requirements.Requirements.ms_limit`; Astrom and Murray, Feedback Systems,
2nd ed., sec 13.3).
"""

from __future__ import annotations

from ..constraint import CHECK_TOLERANCE, Requirement, RequirementCheck

__all__ = ["LoopRobustness"]

_LOOPS = ("velocity", "position")


class LoopRobustness(Requirement):
    """Ms of the velocity loop (position loop open) and of the position loop, every model."""

    name = "loop robustness"
    order = 10.0
    lower = 1.0

    @classmethod
    def applies(cls, problem) -> bool:
        """Return whether the problem has a drive (loops to judge)."""
        return problem.drive is not None

    @classmethod
    def row_names(cls, problem) -> tuple[str, ...]:
        """Return ``("Ms velocity loop", "Ms position loop")``."""
        return tuple(f"Ms {loop} loop" for loop in _LOOPS)

    @classmethod
    def loop_rows(cls, problem, q, gate) -> list:
        """Return ``Ms^2 |1 + L|^2`` of each loop (>= 1 when the loop keeps its Ms)."""
        req = problem.requirements
        return [(1.0 + q.lv).abs2() * req.ms_limit("velocity") ** 2,
                (1.0 + q.lp).abs2() * req.ms_limit("position") ** 2]

    @classmethod
    def model_checks(cls, problem, design, performance, moving, current_bandwidth) -> list:
        """Return the Ms of each loop against its limit (0.5 % slack)."""
        out = []
        name = performance.model.name
        for loop, analysis in zip(_LOOPS, (performance.velocity, performance.position),
                                  strict=True):
            if analysis is None:
                continue
            limit = problem.requirements.ms_limit(loop)
            out.append(RequirementCheck(
                f"Ms {loop} loop", name, analysis.ms, limit,
                analysis.ms <= limit * (1 + CHECK_TOLERANCE["ms"]),
                f"{name}: Ms of the {loop} loop {analysis.ms:.3f} (limit {limit:.3f})"))
        return out
