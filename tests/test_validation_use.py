"""The value types and functions check their parameters with servotune.validation: each refusal
names the owner and the field, the accepted range with its unit, and the value given."""

import re

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from servotune.chatter.forces import cutting_force
from servotune.chatter.frf import Mode, compliance_matrix, modal_compliance
from servotune.chatter.setup import MillingSetup
from servotune.friction.equivalent import (
    describing_function,
    equivalent_damping_stiction,
    stiction_peak_damping,
)
from servotune.friction.lugre import BIANCHI2014, LuGreParameters, lugre_cycle, stribeck_curve
from servotune.regimes import Operation, RegimeModel
from servotune.requirements import Requirements
from servotune.simulate.scenario import Scenario, point_to_point, sine_sweep, sinusoid
from servotune.validation import finite_array, positive_array

PARAMS = BIANCHI2014.to_dict()
MODE = dict(natural_frequency=5793.0, damping_ratio=0.011, stiffness=1.34e6)


def _motion(t):
    return 0.0 * t, 0.0 * t, 0.0 * t


CASES = {
    "Operation.feed_speeds": (lambda: Operation(feed_speeds=(0.01, -0.02)),
                              r"Operation\.feed_speeds must be finite and > 0 m/s, got -0\.02"),
    "Operation.acceleration": (lambda: Operation(acceleration=float("nan")),
                               r"Operation\.acceleration must be finite and > 0 m/s\^2, got nan"),
    "Operation.feed_force": (lambda: Operation(feed_force=-3.0),
                             r"Operation\.feed_force must be finite and >= 0 N, got -3\.0"),
    "RegimeModel.speed": (lambda: RegimeModel("feed", "sliding", BIANCHI2014, speed=0.0),
                          r"RegimeModel\.speed must be finite and > 0 m/s, got 0\.0"),
    "RegimeModel.amplitude": (
        lambda: RegimeModel("standing", "describing", BIANCHI2014, frequency=100.0),
        r"RegimeModel\.amplitude must be a number in m, got None; a describing-function"),
    "LuGreParameters.fc": (lambda: LuGreParameters(**{**PARAMS, "fc": -1.0}),
                           r"LuGreParameters\.fc \(Coulomb friction\) must be finite and > 0 N, "
                           r"got -1\.0"),
    "LuGreParameters.sigma1": (lambda: LuGreParameters(**{**PARAMS, "sigma1": -1.6e7}),
                               r"sigma1 \(bristle damping\) must be finite and >= 0 N s/m, got "
                               r"-16000000\.0; a negative sigma1 .*\(non-passive\)"),
    "LuGreParameters.sigma1_decay_speed": (
        lambda: LuGreParameters(**{**PARAMS, "sigma1_decay_speed": True}),
        r"sigma1_decay_speed \(micro-damping decay speed v_d\) must be a number in m/s, got "
        r"True; leave it out \(None\)"),
    "LuGreParameters.scaled": (lambda: BIANCHI2014.scaled(-2.0),
                               r"LuGreParameters\.scale: factor must be finite and > 0, got "
                               r"-2\.0"),
    "stribeck_curve": (lambda: stribeck_curve(BIANCHI2014, [0.0, 1.0, np.inf]),
                       r"stribeck_curve: v must be finite m/s, got inf \(at index 2\)"),
    "lugre_cycle": (lambda: lugre_cycle(BIANCHI2014, 1e-6, [10.0, -10.0]),
                    r"lugre_cycle: omega must be finite and > 0 rad/s, got -10\.0 \(at index 1\)"),
    "equivalent_damping_stiction": (
        lambda: equivalent_damping_stiction(6013.0, 5.9e9, [1e-6, 0.0], 100.0),
        r"equivalent_damping_stiction: amplitude must be finite and > 0 m, got 0\.0 "
        r"\(at index 1\)"),
    "stiction_peak_damping": (lambda: stiction_peak_damping(6013.0, -5.9e9, 100.0),
                              r"stiction_peak_damping: sigma0 must be finite and > 0 N/m, got "
                              r"-5900000000\.0"),
    "describing_function": (lambda: describing_function(BIANCHI2014, 1e-6, np.nan),
                            r"describing_function: omega must be finite and > 0 rad/s, got nan"),
    "Scenario.duration": (lambda: Scenario(duration=-1.0, motion=_motion),
                          r"Scenario\.duration must be finite and > 0 s, got -1\.0"),
    "Scenario.speed": (lambda: Scenario(duration=1.0, motion=_motion, speed=np.inf),
                       r"Scenario\.speed must be finite m/s, got inf"),
    "sine_sweep": (lambda: sine_sweep(100.0, f_end_hz=-5.0),
                   r"sine_sweep: f_end_hz must be finite and > 0 Hz, got -5\.0"),
    "point_to_point": (lambda: point_to_point([0.0, 0.1], speed=0.1, acceleration=1.0,
                                              dwell=-0.5),
                       r"point_to_point: dwell must be finite and >= 0 s, got -0\.5"),
    "sinusoid": (lambda: sinusoid(1e-5, period=0.0),
                 r"sinusoid: period must be finite and > 0 s, got 0\.0"),
    "Requirements.thrust_margin": (lambda: Requirements(thrust_margin=-0.1),
                                   r"Requirements\.thrust_margin must be finite and >= 0, got "
                                   r"-0\.1"),
    "Requirements.depth_required": (lambda: Requirements(depth_required=-1e-3),
                                    r"Requirements\.depth_required must be finite and > 0 m, "
                                    r"got -0\.001"),
    "Requirements.kv_min": (lambda: Requirements(kv_min=-1.0),
                            r"Requirements\.kv_min must be finite and >= 0 1/s, got -1\.0"),
    "cutting_force": (lambda: cutting_force(MillingSetup(teeth=2, kt=6e8, kn=2e8), depth=-2e-3,
                                            feed_per_tooth=1e-4),
                      r"cutting_force: depth must be finite and > 0 m, got -0\.002"),
    "Mode.stiffness": (lambda: Mode(**{**MODE, "stiffness": 0.0}),
                       r"Mode\.stiffness must be finite and > 0 N/m, got 0\.0"),
    "Mode.damping_ratio": (lambda: Mode(**{**MODE, "damping_ratio": 1.5}),
                           r"Mode\.damping_ratio must lie in \(0, 1\), got 1\.5"),
    "compliance_matrix omega": (
        lambda: compliance_matrix(modal_compliance([Mode(**MODE)]), [10.0, 0.0, 30.0]),
        r"omega must be finite and > 0 rad/s, got 0\.0 \(at index 1\)"),
    "compliance_matrix order": (
        lambda: compliance_matrix(modal_compliance([Mode(**MODE)]), [10.0, 30.0, 20.0]),
        r"omega must be strictly increasing \[rad/s\], got 30\.0 then 20\.0 \(at index 2\)"),
}


@pytest.mark.parametrize("make, message", CASES.values(), ids=CASES.keys())
def test_a_refusal_names_the_field_its_range_and_the_value(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_valid_values_pass_unchanged():
    # the checks return the value given, as float
    op = Operation(feed_speeds=(0.02, 0.01, 0.02), rapid_speed=0.5, acceleration=2,
                   feed_force=0)
    assert op.feed_speeds == (0.01, 0.02) and op.acceleration == 2.0
    assert type(op.acceleration) is float and op.feed_force == 0.0
    assert LuGreParameters(**PARAMS) == BIANCHI2014
    assert Requirements(kv_min=5, depth_required=2e-3).kv_min == 5.0
    assert Mode(**{**MODE, "stiffness": int(2e6)}).stiffness == 2e6


def test_array_checks_return_the_values_and_show_the_first_bad_element():
    values = [[1.0, 2.0], [3.0, 4.0]]
    assert_array_equal(positive_array("f:", "x", values), np.array(values))
    assert_array_equal(finite_array("f:", "x", [-1.0, 0.0]), [-1.0, 0.0])
    assert positive_array("f:", "x", [0.0, 1.0], allow_zero=True)[0] == 0.0
    with pytest.raises(ValueError, match=re.escape("f: x must be finite and > 0 m, got -3.0 "
                                                   "(at index (1, 0))")):
        positive_array("f:", "x", [[1.0, 2.0], [-3.0, -4.0]], "m")
    with pytest.raises(ValueError, match=r"^T\.x must be an array of numbers in m, got 'a'"):
        finite_array("T", "x", "a", "m")
