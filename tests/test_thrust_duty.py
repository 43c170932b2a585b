"""The whole duty in the thrust budget: accelerating to rapid speed against the peak thrust,
traversing at rapid speed and feeding against the continuous thrust, each at the thrust the
motor's torque-speed curve gives at the case's speed; each against a hand calculation written
out here (the budget's cases are affine in C: F_fix + C v <= (1 - margin) F(v))."""

import copy
import math
import tomllib
from pathlib import Path

import pytest

from servotune.axis import AxisFormatError, axis_from_tables, load_axis
from servotune.design import tuning_problem
from servotune.drive import DriveLimits, TorqueSpeedCurve
from servotune.friction import LuGreParameters
from servotune.regimes import Operation
from servotune.template import write_template
from servotune.thrust import ThrustBudget
from servotune.tuning.requirements.thrust import ThrustBudget as ThrustRequirement

MODELS = Path(__file__).resolve().parents[1] / "models"
RPM = 2 * math.pi / 60


def _friction():
    # Coulomb 300 N, static 600 N, Stribeck speed 10 mm/s: g(v) = 300 + 300 exp(-v / 0.01)
    return LuGreParameters(fc=300.0, fs=600.0, vs=0.01, delta=1.0, sigma0=1e9, sigma1=2e6,
                           sigma2=2e3)


def _g(v):
    return 300.0 + 300.0 * math.exp(-v / 0.01)


# ----------------------------------------------------------------- the budget's cases by hand
def test_the_traverse_at_rapid_speed_is_a_continuous_case_by_hand():
    # 40 kN peak, 12 kN continuous, 20 % kept; 1000 kg at 2 m/s^2; rapid 0.5 m/s; a feed of
    # 30 mm/s against 150 N of cutting force; C = 8000 N s/m
    op = Operation(feed_speeds=(0.03,), rapid_speed=0.5, acceleration=2.0, feed_force=150.0)
    budget = ThrustBudget(4e4, 1.2e4, 0.2, 1000.0, _friction(), op)
    cases = {case.name: case for case in budget.cases(8000.0)}
    assert list(cases) == ["accelerating to rapid", "rapid traverse", "feeding 30 mm/s"]
    traverse = cases["rapid traverse"]
    assert traverse.thrust_kind == "continuous" and traverse.speed == 0.5
    # g(0.5) = 300 + 300 exp(-50) = 300 N; 8000 x 0.5 = 4000 N; no acceleration, no cutting
    assert traverse.needed == pytest.approx(300.0 + 4000.0, rel=1e-12)
    assert traverse.usable == pytest.approx(0.8 * 12000.0, rel=1e-12)
    accelerating = cases["accelerating to rapid"]
    assert accelerating.thrust_kind == "peak"
    assert accelerating.needed == pytest.approx(300.0 + 4000.0 + 1000.0 * 2.0, rel=1e-12)
    assert accelerating.usable == pytest.approx(0.8 * 40000.0, rel=1e-12)
    feeding = cases["feeding 30 mm/s"]
    assert feeding.needed == pytest.approx(_g(0.03) + 8000.0 * 0.03 + 150.0, rel=1e-12)
    # the C each case allows, and the budget's: the least, set by the traverse
    hand = {"accelerating to rapid": (0.8 * 40000.0 - 300.0 - 2000.0) / 0.5,   # 59400
            "rapid traverse": (0.8 * 12000.0 - 300.0) / 0.5,                    # 18600
            "feeding 30 mm/s": (0.8 * 12000.0 - _g(0.03) - 150.0) / 0.03}
    assert budget.c_limits() == pytest.approx(hand, rel=1e-12)
    assert budget.c_max() == pytest.approx(18600.0, rel=1e-12)
    assert budget.c_max_case() == "rapid traverse"
    # at 20 kN s/m the traverse needs 300 + 10000 N > 9600 N: it does not fit, the rest do
    fits = {case.name: case.fits for case in budget.cases(2.0e4)}
    assert fits == {"accelerating to rapid": True, "rapid traverse": False,
                    "feeding 30 mm/s": True}


def test_a_heavy_slide_makes_the_acceleration_bind_by_hand():
    # 6000 kg at 2 m/s^2 takes 12 kN of the 32 kN usable peak: (32000 - 300 - 12000) / 0.5 =
    # 39400 N s/m; the traverse still allows (9600 - 300) / 0.5 = 18600: the least binds
    op = Operation(feed_speeds=(), rapid_speed=0.5, acceleration=2.0)
    budget = ThrustBudget(4e4, 1.2e4, 0.2, 6000.0, _friction(), op)
    assert budget.c_max() == pytest.approx(18600.0, rel=1e-12)
    heavy = ThrustBudget(4e4, 1.2e4, 0.2, 14000.0, _friction(), op)
    # 14000 kg: (32000 - 300 - 28000) / 0.5 = 7400 N s/m, below the traverse's 18600
    assert heavy.c_max() == pytest.approx(7400.0, rel=1e-12)
    assert heavy.c_max_case() == "accelerating to rapid"


def test_the_tuners_rows_bound_c_at_the_least_case():
    # the NLP rows (F_fix + C v) / F_usable(v) <= 1 of the thrust requirement: at the budget's
    # C_max the binding row is exactly 1, every other row below
    from axis_fixtures import PADS, small_axis, small_drive

    from servotune.tuning import TuningProblem

    op = Operation(feed_speeds=(0.03,), rapid_speed=0.5, acceleration=2.0, feed_force=150.0)
    budget = ThrustBudget(4e4, 1.2e4, 0.2, 1000.0, _friction(), op)
    problem = TuningProblem(small_axis(), PADS, c=5e3, drive=small_drive(), free=("c",),
                            thrust=budget)
    rows = ThrustRequirement.design_rows(problem, lambda name: 18600.0)
    values = {name: value for name, value, _, _ in rows}
    assert values["thrust: rapid traverse"] == pytest.approx(1.0, rel=1e-12)
    assert values["thrust: accelerating to rapid"] == pytest.approx(
        (300.0 + 18600.0 * 0.5 + 2000.0) / 32000.0, rel=1e-12)
    assert max(values.values()) == pytest.approx(1.0, rel=1e-12)


# --------------------------------------------------------------------------- the bundled axis
def _paper_tables():
    with open(MODELS / "paper_x_axis" / "axis.toml", "rb") as handle:
        return tomllib.load(handle)


def _paper_budget(change=None):
    data = _paper_tables()
    if change is not None:
        change(data["drive"]["motor"])
    axis = axis_from_tables(data, MODELS / "paper_x_axis" / "axis.toml")
    return axis, tuning_problem(axis).thrust


def test_the_bundled_axis_c_bound_is_the_least_over_the_whole_duty_by_hand():
    # models/paper_x_axis: 90 / 27 N m through r = 1.5915e-3 m/rad (README), rapid 3000 rpm x r
    # = 0.5 m/s, friction Fc = 2198 N at rapid speed (the Stribeck term is exp(-50) there),
    # 0.0362 kg m^2 at the motor over r^2 = 14,300 kg at the slide (calibration.json) at
    # 1 m/s^2, 20 % kept in reserve
    axis, budget = _paper_budget()
    r = axis.drive.ratio
    v_r = 3000 * RPM * r
    mass = 0.0362 / r**2
    traverse = (0.8 * 27.0 / r - 2198.0) / v_r
    accelerating = (0.8 * 90.0 / r - 2198.0 - mass * 1.0) / v_r
    feeds = [(0.8 * 27.0 / r - 2198.0 - 3815.0 * math.exp(-v / 0.01) - 67.3) / v
             for v in (1e-4 * 4 * 1000 / 60, 1e-4 * 4 * 6000 / 60)]
    assert traverse == pytest.approx(2.27e4, rel=0.01)       # the "about 2.3e4"
    assert accelerating == pytest.approx(5.75e4, rel=0.01)   # the bound of the peak alone
    assert budget.c_max() == pytest.approx(min(traverse, accelerating, *feeds), rel=1e-4)
    assert budget.c_max() == pytest.approx(traverse, rel=1e-4)
    assert budget.c_max_case() == "rapid traverse"
    # the tuning problem's cost of C spans up to the same bound
    problem = tuning_problem(axis)
    lo, span = problem.c_cost
    assert lo + span == pytest.approx(traverse, rel=1e-4)


def test_a_flat_curve_in_the_range_gives_the_same_bound_as_no_curve():
    _, plain = _paper_budget()

    def flat(motor):
        motor["torque_speed"] = {"speed_rpm": [0, 3000], "peak": [90, 90],
                                 "continuous": [27, 27]}

    axis, curved = _paper_budget(flat)
    assert axis.drive.limits.torque_speed is not None
    assert curved.c_limits() == pytest.approx(plain.c_limits(), rel=1e-12)
    assert curved.c_max() == pytest.approx(plain.c_max(), rel=1e-12)


def test_a_continuous_torque_falling_at_rapid_speed_lowers_the_bound_by_hand():
    # a data sheet's curve: flat to 2000 rpm, then down to 60 / 18 N m at 3000 rpm (the top
    # speed, where the axis traverses); the feeds (at most 40 mm/s / r = 240 rpm) keep 27 N m
    def falling(motor):
        motor["torque_speed"] = {"speed_rpm": [0, 2000, 3000], "peak": [90, 90, 60],
                                 "continuous": [27, 27, 18]}

    axis, budget = _paper_budget(falling)
    r = axis.drive.ratio
    v_r = 3000 * RPM * r
    mass = 0.0362 / r**2
    traverse = (0.8 * 18.0 / r - 2198.0) / v_r
    accelerating = (0.8 * 60.0 / r - 2198.0 - mass * 1.0) / v_r
    limits = budget.c_limits()
    assert limits["rapid traverse"] == pytest.approx(traverse, rel=1e-9)
    assert limits["accelerating to rapid"] == pytest.approx(accelerating, rel=1e-4)
    assert budget.c_max() == pytest.approx(traverse, rel=1e-9)   # about 1.37e4 N s/m
    v_f = 1e-4 * 4 * 6000 / 60
    feed = (0.8 * 27.0 / r - 2198.0 - 3815.0 * math.exp(-v_f / 0.01) - 67.3) / v_f
    assert limits["feeding 40 mm/s"] == pytest.approx(feed, rel=1e-3)
    # the same fall at constant power above a rated 2000 rpm: at 3000 rpm 2/3 of the torques,
    # 60 and 18 N m again, so the same bound at the top speed
    axis, rated = _paper_budget(lambda motor: motor.update(rated_speed_rpm=2000.0))
    assert rated.c_max() == pytest.approx(traverse, rel=1e-9)
    assert any("rated_speed_rpm = 2000" in d for d in axis.defaults)


def test_the_curve_is_interpolated_at_the_case_speed_by_hand():
    # r = 1 mm/rad; continuous torque 20 N m to 1000 rpm, 10 N m at 3000 rpm: at a rapid speed
    # of 2000 rpm (0.2094 m/s) 15 N m, 15 kN of thrust; (0.8 x 15000 - g(v)) / v
    curve = TorqueSpeedCurve.from_rpm([0, 1000, 3000], [60, 60, 30], [20, 20, 10])
    limits = DriveLimits.from_curve(curve)
    v = 2000 * RPM * 1e-3
    op = Operation(feed_speeds=(), rapid_speed=v, acceleration=2.0)
    budget = ThrustBudget(60e3, 20e3, 0.2, 1000.0, _friction(), op, limits=limits, ratio=1e-3)
    assert budget.thrust_continuous_at(v) == pytest.approx(15000.0, rel=1e-12)
    assert budget.thrust_peak_at(v) == pytest.approx(45000.0, rel=1e-12)
    assert budget.c_max() == pytest.approx((0.8 * 15000.0 - _g(v)) / v, rel=1e-12)
    # beyond the curve the drive cannot go: refused, not extrapolated
    with pytest.raises(ValueError, match="cannot go there"):
        limits.continuous(3001 * RPM)
    fast = Operation(feed_speeds=(), rapid_speed=3100 * RPM * 1e-3, acceleration=2.0)
    with pytest.raises(ValueError, match="cannot go there"):
        ThrustBudget(60e3, 20e3, 0.2, 1000.0, _friction(), fast, limits=limits, ratio=1e-3)


def test_without_a_curve_the_default_is_flat_to_the_top_speed_and_said():
    axis = load_axis(MODELS / "paper_x_axis")
    limits = axis.drive.limits
    assert limits.torque_speed is None and limits.rated_speed is None
    assert limits.continuous(0.0) == limits.continuous(3000 * RPM) == 27.0
    assert limits.peak(3000 * RPM) == 90.0
    said = [d for d in axis.defaults if d.startswith("[drive.motor] torque_speed absent")]
    assert len(said) == 1 and "up to speed_max_rpm = 3000" in said[0]


# ------------------------------------------------------------------------- every shipped axis
@pytest.mark.parametrize("path", [MODELS / "paper_x_axis", MODELS / "weak_motor_axis",
                                  Path(__file__).resolve().parents[1] / "examples" / "data"
                                  / "table_axis", "starter"])
def test_every_shipped_axis_can_traverse_at_rapid_speed_with_its_own_friction(path, tmp_path):
    # the guide ways' own viscous friction sigma2 (the least C the tuning may choose) fits the
    # traverse: g(v_r) + sigma2 v_r <= 0.8 T_cont / r
    if path == "starter":
        write_template(tmp_path / "starter")
        path = tmp_path / "starter"
    axis = load_axis(path)
    p, r = axis.friction.lugre, axis.drive.ratio
    v_r = axis.operation.rapid_speed
    g = p.fc + (p.fs - p.fc) * math.exp(-((v_r / p.vs) ** p.delta))
    assert g + p.sigma2 * v_r <= 0.8 * axis.drive.limits.torque_continuous / r
    assert tuning_problem(axis).thrust.c_max() > p.sigma2


def test_two_mass_fig5_has_no_budget():
    assert tuning_problem(load_axis(MODELS / "two_mass_fig5")).thrust is None


# ------------------------------------------------------------------ bad torque_speed tables
TABLE = {"speed_rpm": [0, 3000], "peak": [36, 36], "continuous": [12, 12]}


def _starter_tables(tmp_path):
    write_template(tmp_path / "ax")
    file = tmp_path / "ax" / "axis.toml"
    with open(file, "rb") as handle:
        return tomllib.load(handle), file


def _with(**table):
    return {**TABLE, **table}


BAD = [
    ("not a table", [0, 3000], "[drive.motor] torque_speed", "give a table of motor speeds"),
    ("a key missing", {"speed_rpm": [0, 3000], "peak": [36, 36]},
     "[drive.motor] torque_speed", "missing ['continuous']"),
    ("a key misspelt", {**TABLE, "contnuous": [12, 12]}, "[drive.motor] torque_speed",
     "unknown keys ['contnuous']"),
    ("a word for a number", _with(peak=[36, "high"]), "[drive.motor] torque_speed.peak",
     "give a list of finite numbers in N m"),
    ("lengths that differ", _with(peak=[36, 36, 24]), "[drive.motor] torque_speed",
     "give one peak and one continuous torque per speed"),
    ("one point", {"speed_rpm": [0], "peak": [36], "continuous": [12]},
     "[drive.motor] torque_speed.speed_rpm", "give at least two speeds"),
    ("not from standstill", _with(speed_rpm=[100, 3000]),
     "[drive.motor] torque_speed.speed_rpm", "start the table at 0 rpm"),
    ("speeds not increasing", _with(speed_rpm=[0, 3000, 3000], peak=[36, 36, 30],
                                    continuous=[12, 12, 10]),
     "[drive.motor] torque_speed.speed_rpm", "list the speeds in increasing order"),
    ("a zero torque", _with(continuous=[12, 0]), "[drive.motor] torque_speed.continuous",
     "give torques > 0 in N m"),
    ("continuous above peak", _with(continuous=[12, 40], peak=[36, 36]),
     "[drive.motor] torque_speed.continuous", "at most the peak torque at each speed"),
    ("ending below the top speed", _with(speed_rpm=[0, 2000]),
     "[drive.motor] torque_speed.speed_rpm", "extend the table to the motor's top speed"),
    ("a torque_peak the table does not have", _with(peak=[30, 30]),
     "[drive.motor] torque_peak", "make the two agree"),
]


@pytest.mark.parametrize("what, table, field, fix", BAD, ids=[b[0] for b in BAD])
def test_a_bad_torque_speed_table_names_file_field_and_fix(what, table, field, fix, tmp_path):
    data, file = _starter_tables(tmp_path)
    data["drive"]["motor"]["torque_speed"] = table
    with pytest.raises(AxisFormatError) as info:
        axis_from_tables(data, file)
    message = str(info.value)
    assert str(file) in message and field in message and fix in message


@pytest.mark.parametrize("change, field, fix", [
    ({"torque_speed": TABLE, "rated_speed_rpm": 2000.0}, "[drive.motor] rated_speed_rpm",
     "remove rated_speed_rpm"),
    ({"rated_speed_rpm": 4000.0}, "[drive.motor] rated_speed_rpm", "at most the top speed"),
])
def test_rated_speed_conflicts_name_file_field_and_fix(change, field, fix, tmp_path):
    data, file = _starter_tables(tmp_path)
    data["drive"]["motor"].update(copy.deepcopy(change))
    with pytest.raises(AxisFormatError) as info:
        axis_from_tables(data, file)
    message = str(info.value)
    assert str(file) in message and field in message and fix in message


def test_a_good_table_loads_with_the_torques_and_top_speed_it_gives(tmp_path):
    # without torque_peak, torque_continuous and speed_max_rpm: the table's largest torques
    # and its last speed (said in one line)
    data, file = _starter_tables(tmp_path)
    motor = data["drive"]["motor"]
    for key in ("torque_peak", "torque_continuous", "speed_max_rpm"):
        del motor[key]
    motor["torque_speed"] = {"speed_rpm": [0, 2000, 3000], "peak": [36, 36, 24],
                             "continuous": [12, 12, 8]}
    axis = axis_from_tables(data, file)
    limits = axis.drive.limits
    assert (limits.torque_peak, limits.torque_continuous) == (36.0, 12.0)
    assert limits.speed_max == pytest.approx(3000 * RPM, rel=1e-15)
    assert limits.continuous(2500 * RPM) == pytest.approx(10.0, rel=1e-12)   # half-way
    assert any("speed_max_rpm from torque_speed" in d for d in axis.defaults)
    assert axis.operation.rapid_speed == pytest.approx(3000 * RPM * axis.drive.ratio, rel=1e-12)
