"""The largest following error while feeding, as a servotune requirement of its own package.

A position loop of gain Kv follows a ramp at speed v with the steady error e = v / Kv (a type-1
loop; Ellis, Control System Design Guide, 4th ed., 2012, ch 17): a contour cut at the highest
feed speed v_max is off by v_max / Kv. The requirement asks ``v_max / Kv <= e_max``, that is
``Kv >= v_max / e_max``, for the setting ``following_error_max_m`` of ``[requirements]``::

    [requirements]
    following_error_max_m = 2e-4     # m: 0.2 mm at the highest feed speed

Without the setting (its default is None) the requirement is off. (Velocity feed-forward
removes most of the steady error; the requirement is the conservative one without it.)

What a requirement of another package writes: the class below (name, order, the setting it
declares, when it applies, its row in the design variables and its check) and the entry point
in its ``pyproject.toml``.
"""

from __future__ import annotations

from servotune.requirements import Setting
from servotune.tuning.constraint import Requirement, RequirementCheck

__all__ = ["FollowingError"]


class FollowingError(Requirement):
    """v_max / Kv <= ``following_error_max_m`` at the highest feed speed."""

    name = "following_error"
    order = 61.0
    settings = (Setting("following_error_max_m", "m", None, 1e-7, 1e-2,
                        "largest steady following error v/Kv at the highest feed speed"),)

    @staticmethod
    def _speed(problem) -> float:
        return max((m.speed for m in problem.regimes if m.cutting and m.speed > 0),
                   default=0.0)

    @classmethod
    def applies(cls, problem) -> bool:
        """Return whether the setting is given and the axis feeds while cutting."""
        return (problem.drive is not None and cls._speed(problem) > 0
                and cls.setting(problem, "following_error_max_m") is not None)

    @classmethod
    def design_rows(cls, problem, value) -> list:
        """Return ``Kv e_max / v_max >= 1`` when Kv is free."""
        if "kv" not in problem.free:
            return []
        ratio = cls.setting(problem, "following_error_max_m") / cls._speed(problem)
        return [(cls.name, value("kv") * ratio, 1.0, float("inf"))]

    @classmethod
    def design_checks(cls, problem, design) -> list:
        """Return the following error at the highest feed speed against the setting."""
        if design.kv is None:
            return []
        limit = cls.setting(problem, "following_error_max_m")
        speed = cls._speed(problem)
        error = speed / design.kv
        return [RequirementCheck(cls.name, None, error, limit, error <= limit * (1 + 1e-9),
                                 f"following error {error * 1e3:.4g} mm at "
                                 f"{speed * 1e3:.4g} mm/s (at most {limit * 1e3:.4g} mm)")]
