"""Validation of the value types on construction, and the read-only arrays of ModalModel.

Each bad value is refused with a message naming the type, the field and the accepted range;
good values are kept unchanged. The reference for the immutable model is the closed form of a
2-DOF spring-mass chain.
"""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from axis_fixtures import PADS, small_axis, small_drive
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from servotune.axis import Axis, Cutting, TuningSettings
from servotune.chatter.setup import MillingSetup
from servotune.drive import Drive, Motor, NotchFilter, PIController, Sampling
from servotune.friction.guideway import GuideWayFriction
from servotune.friction.lugre import BIANCHI2014
from servotune.structure.builder import StructureBuilder
from servotune.structure.model import ModalModel
from servotune.tuning.problem import Design
from servotune.twomass import TwoMassSystem
from servotune.validation import finite, fraction, number, positive

NAN, INF = math.nan, math.inf


# -- the shared checks ----------------------------------------------------------------------
@pytest.mark.parametrize("value", [-1.0, 0.0, NAN, INF, -INF])
def test_positive_refuses_with_owner_field_unit_and_value(value):
    with pytest.raises(ValueError) as info:
        positive("Design", "kv", value, "1/s")
    assert str(info.value) == f"Design.kv must be finite and > 0 1/s, got {value!r}"


@pytest.mark.parametrize("value", ["5", None, True, [1.0], 1 + 2j])
def test_number_refuses_what_is_not_a_real_number(value):
    with pytest.raises(ValueError, match=r"^Motor\.resistance must be a number in ohm, got "):
        number("Motor", "resistance", value, "ohm")


def test_options_of_the_checks():
    assert positive("PIController", "ti", INF, "s", allow_inf=True) == INF
    assert positive("Sampling", "speed_filter", 0, "s", allow_zero=True) == 0.0
    with pytest.raises(ValueError, match=r"PIController\.ti must be > 0 \(or inf\) s"):
        positive("PIController", "ti", NAN, "s", allow_inf=True)
    with pytest.raises(ValueError, match=r"must be finite and >= 0"):
        positive("Sampling", "speed_filter", -1e-3, allow_zero=True)
    assert fraction("TuningSettings", "chatter_weight", 1, closed=True) == 1.0
    with pytest.raises(ValueError, match=r"in \[0, 1\)"):
        fraction("NotchFilter", "depth", 1.0)
    with pytest.raises(ValueError, match=r"finite"):
        finite("x", "y", NAN)
    with pytest.raises(ValueError, match=r"^beam a-b: e must be .*; give a stiffer one$"):
        positive("beam a-b:", "e", 0.0, "Pa", "give a stiffer one")


@given(st.floats(allow_nan=True, allow_infinity=True))
def test_positive_accepts_exactly_the_positive_finite_floats(value):
    if value > 0 and math.isfinite(value):
        assert positive("T", "f", value) == value
    else:
        with pytest.raises(ValueError, match=r"^T\.f must be finite and > 0"):
            positive("T", "f", value)


def test_numpy_scalars_and_0d_arrays_are_numbers():
    assert positive("T", "f", np.float32(2.5)) == 2.5
    assert positive("T", "f", np.array(3.0)) == 3.0
    assert positive("T", "f", np.int64(4)) == 4.0


# -- Design ------------------------------------------------------------------------------
@pytest.mark.parametrize("changes, message", [
    ({"c": -1.0}, r"Design\.c must be finite and > 0 N s/m, got -1\.0"),
    ({"kv": -5}, r"Design\.kv must be finite and > 0 1/s, got -5\.0"),
    ({"kp": 0}, r"Design\.kp must be finite and > 0 N m s/rad, got 0\.0"),
    ({"ti": NAN}, r"Design\.ti must be > 0 \(or inf\) s, got nan"),
    ({"ti": -INF}, r"Design\.ti must be > 0 \(or inf\) s, got -inf"),
    ({"kv": INF}, r"Design\.kv must be finite and > 0 1/s, got inf"),
    ({"c": None}, r"Design\.c must be a number in N s/m, got None"),
    ({"kp": "30"}, r"Design\.kp must be a number in N m s/rad, got '30'"),
])
def test_design_refuses_bad_values(changes, message):
    values = dict(c=3e5, kv=16.7, kp=30.0, ti=0.01) | changes
    with pytest.raises(ValueError, match=f"^{message}$"):
        Design(**values)


def test_design_refuses_the_reported_combination():
    with pytest.raises(ValueError, match=r"Design\.c"):
        Design(c=-1, kv=-5, kp=0, ti=NAN)


@given(st.tuples(*[st.floats(min_value=1e-12, max_value=1e12)] * 3),
       st.one_of(st.floats(min_value=1e-9, max_value=1e3), st.just(INF)))
def test_design_keeps_every_good_value_unchanged(gains, ti):
    c, kv, kp = gains
    d = Design(c=c, kv=kv, kp=kp, ti=ti)
    assert (d.c, d.kv, d.kp, d.ti) == (c, kv, kp, ti)
    assert dataclasses.replace(d, kv=2 * kv).kv == 2 * kv  # varied by replace, validated again
    with pytest.raises(ValueError, match=r"^Design\.kv"):
        dataclasses.replace(d, kv=-kv)


def test_design_keeps_good_values():
    d = Design(c=3e5, kv=16, kp=30.0, ti=INF)
    assert (d.c, d.kv, d.kp, d.ti) == (3e5, 16.0, 30.0, INF)
    assert isinstance(d.kv, float)
    assert Design(c=1.0).kv is None


# -- drive, milling set-up, two-mass system, builder -------------------------------------
@pytest.mark.parametrize("build, message", [
    (lambda: Motor(1.2, 1.2, -0.4, 3e-3), r"Motor\.resistance must be finite and > 0 ohm"),
    (lambda: Motor(1.2, NAN, 0.4, 3e-3), r"Motor\.back_emf_constant .* V s/rad"),
    (lambda: PIController(kp=0.0), r"PIController\.kp must be finite and > 0"),
    (lambda: PIController(kp=1.0, ti=0.0), r"PIController\.ti must be > 0 \(or inf\) s"),
    (lambda: NotchFilter(100.0, depth=1.5), r"NotchFilter\.depth must be finite and in \[0, 1\]"),
    (lambda: Sampling(current_period=-1e-4), r"Sampling\.current_period .* >= 0 s"),
    (lambda: small_drive(kv=-5.0), r"Drive\.kv must be finite and > 0 1/s, got -5\.0"),
    (lambda: small_drive(ratio=0.0), r"Drive\.ratio must be finite and > 0 m/rad"),
    (lambda: MillingSetup(2, kt=-6e8, kn=2e8), r"MillingSetup\.kt .* N/m\^2.*cutting coeff"),
    (lambda: MillingSetup(2, kt=6e8, kn=NAN), r"MillingSetup\.kn must be finite and >= 0"),
    (lambda: MillingSetup.from_ratio(2, kt=6e8, kr=-0.3), r"MillingSetup\.from_ratio\.kr"),
    (lambda: TwoMassSystem(m1=0.0, k=16e6, alpha=0.3), r"TwoMassSystem\.m1 .* kg, got 0\.0"),
    (lambda: TwoMassSystem(m1=5e3, k=INF, alpha=0.3), r"TwoMassSystem\.k .* N/m, got inf"),
    (lambda: TwoMassSystem(m1=5e3, k=1e6, alpha=0.3, layout="C"), r"TwoMassSystem\.layout"),
    (lambda: MillingSetup(2.5, kt=6e8, kn=2e8), r"MillingSetup\.teeth must be a whole number"),
    (lambda: MillingSetup(2, kt=6e8, kn=2e8, milling="side"), r"MillingSetup\.milling"),
    (lambda: ModalModel(np.eye(2), np.eye(2), ["a", "a"]),
     r"ModalModel\.dofs has duplicate DOF names \['a'\]"),
    (lambda: ModalModel(np.eye(1), np.eye(1), ["a"]).with_added(damping={"a": -2.0}),
     r"ModalModel\.with_added\.damping\['a'\] must be finite and >= 0 N s/m, got -2\.0"),
])
def test_value_types_refuse_bad_values_by_name(build, message):
    with pytest.raises(ValueError, match=message):
        build()


def test_drive_parts_keep_good_values_as_floats():
    motor = Motor(1, 1.2, 0.4, 3e-3)
    assert (motor.torque_constant, motor.resistance) == (1.0, 0.4)
    assert isinstance(motor.torque_constant, float)
    assert PIController(kp=30, ti=INF).ti == INF
    notch = NotchFilter(410, width=0.5, depth=0)
    assert (notch.f_hz, notch.width, notch.depth) == (410.0, 0.5, 0.0)
    s = Sampling(current_period=62.5e-6, velocity_period=62.5e-6, speed_filter=0,
                 computation_delay=np.float64(1.0))
    assert (s.current_period, s.velocity_period, s.speed_filter) == (62.5e-6, 62.5e-6, 0.0)
    assert type(s.computation_delay) is int
    drive = small_drive(kv=np.float64(25.5), velocity_feedforward=1)
    assert (drive.kv, drive.velocity_feedforward) == (25.5, 1.0)
    assert type(drive.kv) is float


def test_builder_refuses_bad_elements_by_name():
    b = StructureBuilder()
    b.add_node("a", (0.0, 0.0, 0.0))
    b.add_node("b", (1.0, 0.0, 0.0))
    with pytest.raises(ValueError, match=r"^beam a-b: area must be finite and > 0 m\^2"):
        b.add_beam("a", "b", e=2.1e11, area=0.0, iy=1e-6, iz=1e-6, torsion=1e-6, rho=7850.0)
    with pytest.raises(ValueError, match=r"^beam a-b: iy must be finite and >= 0 m\^4"):
        b.add_beam("a", "b", e=2.1e11, area=1e-3, iy=-1e-6, iz=1e-6, torsion=1e-6, rho=7850.0)
    with pytest.raises(ValueError, match=r"mass must be finite and >= 0 kg"):
        b.add_mass("a.x", -1.0)
    with pytest.raises(ValueError, match=r"stiffness must be finite and >= 0 N/m"):
        b.add_spring({"a.x": 1.0}, NAN)


# -- Axis and its parts ---------------------------------------------------------------------
SETUP = MillingSetup(teeth=2, kt=6e8, kn=2e8)


@pytest.mark.parametrize("changes, message", [
    ({"speed_rpm": (12000.0, 1000.0)}, r"Cutting\.speed_rpm must be \(low, high\)"),
    ({"speed_rpm": (1000.0,)}, r"Cutting\.speed_rpm must be \(low, high\)"),
    ({"speed_rpm": (-1.0, 10.0)}, r"Cutting\.speed_rpm must be finite and > 0 rpm"),
    ({"direction": "z"}, r"Cutting\.direction must be 'x' \(feed\) or 'y', got 'z'"),
    ({"feed_per_tooth": 0.0}, r"Cutting\.feed_per_tooth must be finite and > 0 m"),
    ({"setup": "slot"}, r"Cutting\.setup must be a servotune\.chatter\.MillingSetup"),
])
def test_cutting_refuses_bad_values(changes, message):
    with pytest.raises(ValueError, match=message):
        Cutting(**({"setup": SETUP} | changes))


def test_cutting_keeps_good_values():
    cutting = Cutting(SETUP, [2000, 8000], "y", 5e-5)
    assert cutting.speed_rpm == (2000.0, 8000.0)
    assert (cutting.direction, cutting.feed_per_tooth) == ("y", 5e-5)
    # f_z N n / 60 with N = 2 teeth
    assert_allclose(cutting.feed_speeds(), (5e-5 * 2 * 2000 / 60, 5e-5 * 2 * 8000 / 60))


@pytest.mark.parametrize("changes, message", [
    ({"free": ("c", "c")}, r"TuningSettings\.free must be distinct names"),
    ({"free": ("c", "gain")}, r"TuningSettings\.free must be distinct names"),
    ({"free": ()}, r"TuningSettings\.free"),
    ({"bounds": {"kv": (10.0, 1.0)}}, r"TuningSettings\.bounds\['kv'\] must be \(low, high\)"),
    ({"bounds": {"kv": (-1.0, 1.0)}}, r"TuningSettings\.bounds\['kv'\] must be finite and > 0"),
    ({"bounds": {"zeta": (0.1, 1.0)}}, r"TuningSettings\.bounds has 'zeta'"),
    ({"chatter_weight": 1.5}, r"TuningSettings\.chatter_weight must be finite and in \[0, 1\]"),
    ({"friction_spread": {"fc": 2.0}}, r"TuningSettings\.friction_spread .*fraction in"),
    ({"friction_spread": {"vs": 0.1}}, r"TuningSettings\.friction_spread .*choose among"),
    ({"friction_spread": {"sigma0": NAN}}, r"friction_spread\['sigma0'\] must be finite"),
])
def test_tuning_settings_refuse_bad_values(changes, message):
    with pytest.raises(ValueError, match=message):
        TuningSettings(**changes)


def test_tuning_settings_keep_good_values_read_only():
    settings = TuningSettings(free=["c", "kv"], bounds={"c": (1e3, 1e6)}, chatter_weight=0.5,
                              friction_spread={"fc": 0.3, "sigma0": 3.0},
                              friction_samples=[("worst", {"fc": 2500.0})])
    assert settings.free == ("c", "kv")
    assert dict(settings.bounds) == {"c": (1e3, 1e6)}
    assert dict(settings.friction_spread) == {"fc": 0.3, "sigma0": 3.0}
    assert settings.friction_samples[0][0] == "worst"
    assert dict(settings.friction_samples[0][1]) == {"fc": 2500.0}
    with pytest.raises(TypeError):
        settings.bounds["kv"] = (1.0, 2.0)


def _axis(**changes):
    values = dict(name="small", description="", path=Path("."), structure=small_axis(),
                  friction=GuideWayFriction(tuple(PADS), BIANCHI2014), drive=small_drive())
    return Axis(**(values | changes))


@pytest.mark.parametrize("changes, message", [
    ({"name": ""}, r"Axis\.name must be a non-empty str"),
    ({"structure": np.eye(6)}, r"Axis\.structure must be a ModalModel, got ndarray"),
    ({"drive": "fast"}, r"Axis\.drive must be a Drive or None, got str"),
    ({"friction": GuideWayFriction(("pad9.x",), BIANCHI2014)},
     r"Axis\.friction\.pads names DOF 'pad9\.x', which the structure does not have"),
    ({"drive": small_drive(encoder="scale.x")}, r"Axis\.drive\.encoder names DOF 'scale\.x'"),
    ({"drive": small_drive(motor=Motor(1.2, 1.2, 0.4, 3e-3, rotor="spindle"))},
     r"Axis\.drive\.motor\.rotor names DOF 'spindle'"),
])
def test_axis_refuses_bad_parts(changes, message):
    with pytest.raises(ValueError, match=message):
        _axis(**changes)


def test_axis_built_in_python_keeps_its_parts():
    axis = _axis(path="models/somewhere")
    assert axis.path == Path("models/somewhere")
    assert axis.pads == tuple(PADS)
    # with the position measured at the motor the linear encoder need not exist
    drive = small_drive(feedback="motor", encoder="scale.x")
    assert isinstance(_axis(drive=drive).drive, Drive)


# -- ModalModel: read-only arrays, varied by dataclasses.replace -------------------------
def _chain(k1, k2, m1=2.0, m2=1.0):
    """ground --k1-- m1 --k2-- m2."""
    return ModalModel([[m1, 0.0], [0.0, m2]], [[k1 + k2, -k2], [-k2, k2]], ["a", "b"])


def _chain_frequencies(k1, k2, m1=2.0, m2=1.0):
    """The roots of det(K - w^2 M) = 0: m1 m2 w^4 - (m1 k2 + m2 (k1 + k2)) w^2 + k1 k2 = 0."""
    b = m1 * k2 + m2 * (k1 + k2)
    root = math.sqrt(b * b - 4.0 * m1 * m2 * k1 * k2)
    return np.sqrt([(b - root) / (2 * m1 * m2), (b + root) / (2 * m1 * m2)])


@pytest.mark.parametrize("attribute", ["mass", "stiffness", "damping", "damping_ratio"])
def test_model_arrays_refuse_in_place_changes(attribute):
    model = _chain(1e4, 2e4)
    before = model.natural_frequencies()
    with pytest.raises(ValueError, match="read-only"):
        getattr(model, attribute)[0, ...] = 1.0
    assert_allclose(model.natural_frequencies(), before, rtol=0)


def test_model_keeps_a_copy_of_the_given_arrays():
    k = np.array([[3e4, -2e4], [-2e4, 2e4]])
    model = ModalModel(np.diag([2.0, 1.0]), k, ["a", "b"])
    k[0, 0] = 1e9  # the caller's array stays writeable and the model does not see the change
    assert model.stiffness[0, 0] == 3e4
    assert_allclose(model.natural_frequencies(), _chain_frequencies(1e4, 2e4), rtol=1e-12)


def test_cached_modes_are_read_only_and_returned_as_copies():
    model = _chain(1e4, 2e4)
    omega = model.natural_frequencies()
    omega[:] = 0.0
    assert_allclose(model.natural_frequencies(), _chain_frequencies(1e4, 2e4), rtol=1e-12)
    phi = model.mode_shapes()
    assert_allclose(phi.T @ model.mass @ phi, np.eye(2), atol=1e-12)


@pytest.mark.parametrize("k1, k2", [(1e4, 2e4), (5e6, 1e5), (3.0, 3.0)])
def test_replace_gives_the_new_frequencies(k1, k2):
    model = _chain(1.0, 1.0)
    new_k = [[k1 + k2, -k2], [-k2, k2]]
    changed = dataclasses.replace(model, stiffness=new_k)
    assert_allclose(changed.natural_frequencies(), _chain_frequencies(k1, k2), rtol=1e-10)
    # the original model is unchanged
    assert_allclose(model.natural_frequencies(), _chain_frequencies(1.0, 1.0), rtol=1e-12)
    # with damping=None the modal damping ratio is re-assigned to the new modes
    redamped = dataclasses.replace(model, stiffness=new_k, damping=None)
    assert_allclose(redamped.modal_damping_ratios(), [0.03, 0.03], rtol=1e-10)


def test_model_refuses_bad_damping_and_reduction():
    with pytest.raises(ValueError, match=r"ModalModel\.damping_ratio must lie in \[0, 1\)"):
        ModalModel([[1.0]], [[1.0]], ["a"], damping_ratio=1.0)
    with pytest.raises(ValueError, match=r"ModalModel\.reduction must be a ReductionInfo"):
        ModalModel([[1.0]], [[1.0]], ["a"], reduction="craig-bampton")


def test_model_keeps_the_damping_ratios_it_was_given():
    zeta = ModalModel(np.diag([2.0, 1.0]), [[3e4, -2e4], [-2e4, 2e4]], ["a", "b"],
                      damping_ratio=[0.02, 0.05])
    assert_allclose(zeta.damping_ratio, [0.02, 0.05], rtol=0)
    assert_allclose(zeta.modal_damping_ratios(), [0.02, 0.05], rtol=1e-10)
    matrix = ModalModel([[1.0]], [[4.0]], ["a"], damping=[[0.4]])
    assert matrix.damping_ratio is None
    assert_allclose(matrix.modal_damping_ratios(), [0.4 / (2 * 2.0)], rtol=1e-12)  # c/(2 m w)


def test_a_loaded_axis_whose_default_stator_is_not_in_the_structure_names_the_file(tmp_path):
    from servotune.axis import AxisFormatError, load_axis
    from servotune.template import template_structure, template_toml

    m, k, dofs = template_structure()
    keep = [i for i, d in enumerate(dofs) if d != "motor.stator"]
    np.savez(tmp_path / "structure.npz", mass=m[np.ix_(keep, keep)],
             stiffness=k[np.ix_(keep, keep)], dofs=np.array([dofs[i] for i in keep]))
    (tmp_path / "axis.toml").write_text(
        template_toml("s").replace('stator = "motor.stator"\n', ""))  # the default stays
    with pytest.raises(AxisFormatError, match=r"axis\.toml: Axis\.drive\.motor\.stator names DOF "
                       r"'motor\.stator', which the structure does not have"):
        load_axis(tmp_path)
