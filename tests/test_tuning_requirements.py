"""Requirements as plug-ins: one class, and the NLP, the dense check and the report follow."""

from __future__ import annotations

import math

import numpy as np
import pytest
from axis_fixtures import PADS, small_axis, small_drive

from servotune.plant import Contact, loop_transfer
from servotune.tuning import Requirements, TuningProblem, constraint, tune
from servotune.tuning.constraint import Requirement, RequirementCheck, requirements
from servotune.tuning.gates import GATE_SAFETY, gate_switch


def _problem():
    req = Requirements(ms_velocity_max=1.6, ms_position_max=1.3, kv_min=10.0)
    return TuningProblem(small_axis(), PADS, c=5e4, drive=small_drive(),
                         free=("c", "kv", "kp", "ti"), requirements=req)


def _velocity_bandwidth(problem, design) -> float:
    """-3 dB bandwidth of the closed velocity loop, from python-control's own response."""
    lt = loop_transfer(problem.structure, problem.drive_for(design),
                       Contact.viscous(design.c), PADS, "velocity")
    omega = np.geomspace(2 * np.pi * 1.0, 2 * np.pi * 3000.0, 20001)
    loop = np.array([complex(lt(1j * w)) for w in omega])
    t = np.abs(loop / (1 + loop))
    below = np.nonzero(t < t[0] / math.sqrt(2))[0]
    return float(omega[below[0]])


def test_the_registered_requirements_are_the_shipped_ones_in_order():
    names = [c.name for c in requirements()]
    assert names[:6] == ["loop robustness", "loop hierarchy", "Ti and velocity bandwidth",
                         "current loop above", "thrust", "kv_min"]


def test_a_requirement_added_as_one_class_is_imposed_checked_and_reported():
    problem = _problem()
    free_run = tune(problem, starts=2)
    assert free_run.success, free_run.reasons
    bw_free = _velocity_bandwidth(problem, free_run.design)
    target = 1.1 * bw_free          # binding: the design tuned without it falls short

    class VelocityBandwidthMin(Requirement):
        """The closed velocity loop passes every frequency up to ``minimum`` [rad/s]."""

        name = "velocity bandwidth min"
        order = 45.0
        minimum = target

        @classmethod
        def applies(cls, problem):
            return problem.drive is not None

        @classmethod
        def row_names(cls, problem):
            return (cls.name,)

        @classmethod
        def loop_rows(cls, problem, q, gate):
            edge = math.log(GATE_SAFETY * cls.minimum)
            return [(q.tv2 - 0.5) / (q.tv2 + 0.5) + gate_switch(q.log_omega - edge)]

        @classmethod
        def model_checks(cls, problem, design, performance, moving, current_bandwidth):
            bw = performance.velocity.bandwidth
            return [RequirementCheck(cls.name, performance.model.name, bw, cls.minimum,
                                     bw >= 0.98 * cls.minimum,
                                     f"velocity-loop bandwidth {bw:.4g} rad/s "
                                     f"(at least {cls.minimum:.4g})")]

    try:
        result = tune(problem, starts=2)
        assert result.success, result.reasons
        # the dense check of the design lists it, and it holds
        mine = [c for c in result.checks if c.requirement == "velocity bandwidth min"]
        assert mine and all(c.holds for c in mine)
        # the reference: python-control's own closed velocity loop of the tuned design, wider
        # than the design tuned without the requirement had (0.98 x 1.1 > 1)
        assert _velocity_bandwidth(problem, result.design) >= 0.98 * target > bw_free
        # and the report shows it (the checks' text is what the reports print)
        assert any("velocity-loop bandwidth" in c.text for c in mine)
    finally:
        constraint._REGISTRY.pop("velocity bandwidth min", None)
    assert "velocity bandwidth min" not in [c.name for c in requirements()]


def test_two_requirements_of_one_name_are_refused():
    requirements()          # the shipped ones loaded from their entry points
    with pytest.raises(TypeError, match="registered already"):
        class Again(Requirement):
            name = "kv_min"
