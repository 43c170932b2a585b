"""The drive cascade and the interconnected plant against closed forms and a second assembly."""

import math

import control
import numpy as np
import pytest
from axis_fixtures import PADS, RATIO, small_axis, small_drive
from numpy.testing import assert_allclose

from servotune.drive import (
    Drive,
    LowPassFilter,
    Motor,
    NotchFilter,
    PIController,
    kv_from_m_per_min_per_mm,
    kv_to_m_per_min_per_mm,
)
from servotune.frequency import compliance, following_error, modal_receptance, port_compliance
from servotune.plant import Contact, UnstableLoopError, build_plant, loop_transfer
from servotune.structure import ModalModel, UnknownDofError

OMEGA = 2 * np.pi * np.geomspace(0.5, 3000.0, 300)


def test_kv_factor_conversion():
    # 1 (m/min)/mm: 1 m/min = 1/60 m/s gives 1 mm = 1e-3 m of following error
    assert kv_from_m_per_min_per_mm(1.0) == pytest.approx((1.0 / 60.0) / 1e-3)
    assert kv_to_m_per_min_per_mm(kv_from_m_per_min_per_mm(2.5)) == pytest.approx(2.5)


def rigid_cascade_reference(drive: Drive, inertia: float, s: np.ndarray):
    """Closed-form loop transfer functions of the cascade on a rigid axis (derived by hand).

    Electrical: (L s + R) i = u - ke w,  u = Ci (T/kt - i),  w = kt i / (J s)
      =>  i (L s + R + Ci + kt ke/(J s)) = Ci T_set / kt
    Velocity loop: Lv = Cv * Gi / (J s) with Gi = T/T_set; position loop: Lp = Kv Tv / s.
    """
    m = drive.motor
    ci = drive.current_loop.kp * (1 + 1 / (drive.current_loop.ti * s))
    cv = drive.velocity_loop.kp * (1 + 1 / (drive.velocity_loop.ti * s))
    gi = ci / (m.inductance * s + m.resistance + ci + m.torque_constant * m.back_emf_constant
               / (inertia * s))
    lv = cv * gi / (inertia * s)
    tv = lv / (1 + lv)
    lp = drive.kv * tv / s
    return lv, lp, lp / (1 + lp)


@pytest.mark.parametrize("feedforward", [0.0, 1.0])
def test_rigid_axis_reproduces_the_analytic_cascade(feedforward):
    inertia = 0.012 + 1100.0 * RATIO**2
    rigid = ModalModel([[inertia]], [[0.0]], ["motor.rotor"], damping_ratio=0.0)
    drive = small_drive(motor=Motor(1.2, 1.2, 0.4, 3e-3, stator=None), feedback="motor",
                        velocity_feedforward=feedforward)
    s = 1j * OMEGA
    lv, lp, tp = rigid_cascade_reference(drive, inertia, s)
    plant = build_plant(rigid, drive)
    x_over_ref = np.array([plant(sk)[plant.output_labels.index("slide_x"), 0] for sk in s])
    assert_allclose(x_over_ref, tp, rtol=1e-9)
    for loop, ref in (("velocity", lv), ("position", lp)):
        got = loop_transfer(rigid, drive, loop=loop)(s)
        assert_allclose(np.asarray(got).ravel(), ref, rtol=1e-9)
    if feedforward:  # full velocity feed-forward: x/v_ref = (1/s) Tv-ish, check v_ref path
        tv = lv / (1 + lv)
        x_over_v = np.array([plant(sk)[plant.output_labels.index("slide_x"), 1] for sk in s])
        assert_allclose(x_over_v, (tv / s) / (1 + lp), rtol=1e-9)


@pytest.mark.parametrize("feedback", ["linear", "motor"])
@pytest.mark.parametrize("contact", [Contact.free(), Contact.viscous(5e4)])
def test_following_error_is_feed_over_kv(feedback, contact):
    plant = build_plant(small_axis(), small_drive(feedback=feedback), contact, PADS)
    feed = 5.0 / 60.0  # 5 m/min
    assert following_error(plant, feed) == pytest.approx(feed / plant_kv(), rel=1e-9)


def plant_kv():
    return small_drive().kv


def test_velocity_feedforward_removes_the_following_error():
    plant = build_plant(small_axis(), small_drive(velocity_feedforward=1.0), Contact.free(), PADS)
    assert abs(following_error(plant, 0.1)) < 1e-12


CONTACTS = [
    Contact.free(),
    Contact.viscous(2e5),
    Contact.stiction(sigma0=5.9e9, sigma1=1.6e7, sigma2=5578.0),
    Contact.equivalent(ceq=3e6, keq=1e8),
    Contact.locked(),
    Contact.sliding(control.tf([-2.0e4], [1e-4, 1.0]), v0=2e-3),
]


@pytest.mark.parametrize("feedback", ["linear", "motor"])
@pytest.mark.parametrize("contact", CONTACTS, ids=lambda c: c.kind)
def test_interconnected_plant_equals_port_coupling(contact, feedback):
    # two independent assemblies: control.interconnect of state spaces, and the modal-sum
    # receptance at the ports closed by hand at each frequency
    drive = small_drive(feedback=feedback, lowpass=LowPassFilter(800.0),
                        notches=(NotchFilter(410.0, width=0.4, depth=0.05),))
    structure = small_axis()
    plant = build_plant(structure, drive, contact, PADS)
    h_plant = compliance(plant, OMEGA)
    h_ports = port_compliance(structure, OMEGA, drive, contact, PADS)[0]
    assert_allclose(h_plant, h_ports, rtol=1e-9)


def test_uncontrolled_locked_axis_is_the_constrained_structure():
    structure = small_axis()
    plant = build_plant(structure, None, Contact.locked(), PADS)
    constrained = structure.locked(PADS)
    direct = constrained.receptance(OMEGA, ["wp.x"], ["wp.x"])[:, 0, 0]
    assert_allclose(compliance(plant, OMEGA), direct, rtol=1e-9)


def test_stiff_stiction_converges_to_locked_pads():
    structure, drive = small_axis(), small_drive(feedback="motor")
    locked = compliance(build_plant(structure, drive, Contact.locked(), PADS), OMEGA)
    errors = []
    for sigma0 in (1e11, 1e12, 1e13):
        stiff = compliance(build_plant(structure, drive, Contact.stiction(sigma0, 0.0, 0.0), PADS),
                           OMEGA)
        errors.append(np.abs(stiff / locked - 1).max())
    # the residual flexibility of the contact spring falls as 1/sigma0 (first order)
    assert_allclose(errors[0] / errors[1], 10.0, rtol=0.1)
    assert_allclose(errors[1] / errors[2], 10.0, rtol=0.1)
    assert errors[2] < 1e-3


def test_modal_receptance_equals_direct_solution():
    structure = small_axis()
    ports = ["wp.x", "pad1.x", "motor.rotor"]
    direct = np.moveaxis(structure.receptance(OMEGA, ports, ports), 0, -1)
    assert_allclose(modal_receptance(structure, OMEGA, ports, ports), direct, rtol=1e-9)


@pytest.mark.parametrize("field, value, message", [
    ("kv", -1.0, "kv"),
    ("ratio", 0.0, "ratio"),
    ("feedback", "tacho", "feedback"),
    ("velocity_feedforward", -0.5, "velocity_feedforward"),
])
def test_bad_drive_settings_are_refused(field, value, message):
    with pytest.raises(ValueError, match=message):
        small_drive(**{field: value})


@pytest.mark.parametrize("kwargs, message", [
    (dict(kp=-1.0, ti=0.01), "kp"), (dict(kp=1.0, ti=0.0), "ti"),
    (dict(kp=1.0, ti=-0.01), "ti"), (dict(kp=math.nan, ti=0.01), "kp")])
def test_bad_pi_settings_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        PIController(**kwargs)


def test_negative_contact_damping_is_refused():
    with pytest.raises(ValueError, match="generate energy"):
        Contact.viscous(-10.0)


def test_unknown_dofs_are_named():
    with pytest.raises(UnknownDofError, match=r"pad9\.x"):
        build_plant(small_axis(), small_drive(), Contact.viscous(1e4), ["pad9.x"])
    with pytest.raises(UnknownDofError, match=r"ruler\.x"):
        build_plant(small_axis(), small_drive(encoder="ruler.x"))


def test_unstable_loop_is_a_clear_error():
    # a velocity gain far beyond what the first torsional mode allows
    drive = small_drive(velocity_loop=PIController(kp=500.0, ti=1e-4), kv=300.0)
    plant = build_plant(small_axis(), drive, Contact.free(), PADS)
    with pytest.raises(UnstableLoopError, match="right half plane"):
        compliance(plant, OMEGA)
