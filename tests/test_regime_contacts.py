"""The describing-function regime model adds no state of its own to the axis.

Reference: the presliding model of the same axis (a spring and a damper at the pads, no
state): the describing function's Keq x + Ceq v is the same kind of element, so the closed
loop has as many states, and no exponent near zero (an integrator of the pad velocity would
repeat the structure's displacement: a neutral mode, 0 but for rounding, whose sign decides a
stability check by chance).
"""

from pathlib import Path

import numpy as np

import servotune as st
from servotune.design import tuning_problem
from servotune.digital.sampled import SampledAxis

AXIS = Path(__file__).resolve().parents[1] / "models" / "paper_x_axis"


def test_describing_function_model_has_no_neutral_state():
    axis = st.load_axis(AXIS)
    problem = tuning_problem(axis)
    design = problem.initial_design()
    models = {m.kind: m for m in problem.regimes}
    assert {"presliding", "describing"} <= set(models)
    loops = {kind: SampledAxis(problem.structure, problem.drive_for(design),
                               models[kind].contact(design.c), problem.pads)
             for kind in ("presliding", "describing")}
    assert loops["describing"].plant.nstates == loops["presliding"].plant.nstates
    for loop in loops.values():
        _, p = loop._stability        # the closed loop's exponents [1/s] (stable or not)
        p = p[np.isfinite(p.real)]
        assert np.abs(p).min() > 1e-3     # no neutral mode (before: two at about 1e-8)
