"""The current set-point notch as a design variable of the tuner.

A motor drives a slide through a belt and screw spring (a drive-train resonance near 400 Hz,
the bundled axis' motor, transmission and digital drive), the work piece rides stiffly on the
slide. The resonance lifts the sampled velocity loop's sensitivity and caps Kp; a notch on it
lets Kp rise. References: the undamped natural frequencies of the structure (scipy's
generalised eigenproblem on M and K built here), the velocity loop measured again on a freshly
built sampled-data axis (not the tuner's port model), and the same tuning without the notch and
with the notch held at the resonance (a second method for "the placement pays").
"""

import dataclasses
import math

import numpy as np
import pytest
import scipy.linalg

from servotune.design import start_notch
from servotune.digital import SampledAxis
from servotune.drive import Drive, Motor, NotchFilter, PIController, Sampling
from servotune.plant import Contact
from servotune.requirements import Requirements
from servotune.structure import ModalModel
from servotune.tuning import Design, TuningProblem, tune

R = 1.5915e-3                    # [m/rad] slide travel per motor radian
JM, MASS, M_WP = 0.01, 4000.0, 20.0
F_RES, F_WP = 400.0, 2500.0      # [Hz] the drive train's design resonance, the work piece's
C = 2000.0                       # [N s/m] viscous guide ways


def matrices():
    jl = MASS * R**2
    k = (2 * math.pi * F_RES) ** 2 / (1 / JM + 1 / jl) / R**2       # [N/m] at the slide
    k_wp = (2 * math.pi * F_WP) ** 2 * M_WP
    coupling = np.array([R, -1.0, 0.0])
    stiffness = k * np.outer(coupling, coupling)
    stiffness[1:, 1:] += k_wp * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return np.diag([JM, MASS, M_WP]), stiffness


def resonance_hz() -> float:
    """The drive train's natural frequency (the free structure's second mode)."""
    mass, stiffness = matrices()
    w2 = scipy.linalg.eigh(stiffness, mass, eigvals_only=True)
    return float(np.sqrt(np.sort(np.abs(w2))[1]) / (2 * math.pi))


@pytest.fixture(scope="module")
def problem():
    mass, stiffness = matrices()
    structure = ModalModel(mass, stiffness, ["motor.rotor", "pad1.x", "wp.x"],
                           damping_ratio=0.02)
    drive = Drive(Motor(1.5, 1.5, 0.25, 4e-3, stator=None), ratio=R,
                  current_loop=PIController(20.0, 0.016), velocity_loop=PIController(1.0, 0.01),
                  kv=10.0, encoder="pad1.x", sampling=Sampling())
    return TuningProblem(structure, ("pad1.x",), c=C, drive=drive, free=("kv", "kp", "ti"),
                         requirements=Requirements(ms_velocity_max=1.6, ms_position_max=1.5))


@pytest.fixture(scope="module")
def tuned(problem):
    notch, why = start_notch(problem)
    with_notch = dataclasses.replace(problem, notch=notch, free=("kv", "kp", "ti", "notch"))
    return notch, why, tune(problem, starts=2), tune(with_notch, starts=2)


def velocity_loop(problem, design):
    drive = dataclasses.replace(problem, notch=design.notch).drive_for(design)
    axis = SampledAxis(problem.structure, drive, Contact.viscous(C), problem.pads)
    return axis.is_stable(), axis.analyse_loop("velocity")


def test_the_notch_starts_on_the_drive_train_resonance(tuned):
    """The start is read off the velocity loop (the peak of |L_v| next to its sensitivity's);
    reference: the structure's natural frequency from M and K (399.5 Hz)."""
    notch, why, _, _ = tuned
    assert notch is not None and notch.depth == 1.0          # not yet a notch
    assert abs(notch.f_hz / resonance_hz() - 1) < 0.02
    assert f"{notch.f_hz:.1f} Hz" in why


def test_the_tuned_notch_sits_on_the_resonance_and_the_loop_holds_its_ms(problem, tuned):
    """The tuner deepens the notch on the resonance (within 10 % of the plant's natural
    frequency: a notch's phase lag below its centre costs the loop's phase, so the Ms-best
    centre lies a little above it; within 5 % of the frequency where the resonance lifts the
    sampled loop's sensitivity, the resonance as the loop sees it), the
    sampled velocity loop built anew holds Ms <= 1.6 and Kp rises well above the tuned design
    without a notch (measured: 12.9 against 4.33 N m s/rad)."""
    _, _, plain, notched = tuned
    assert notched.success
    assert "Ms velocity loop" in plain.active     # without the notch Ms caps the loop
    d = notched.design
    f_res = resonance_hz()
    assert d.notch_depth < 0.5                                  # a real notch
    assert 1.0 <= d.notch.f_hz / f_res < 1.10
    # and within 5 % of where the resonance lifts the loop's sensitivity (the tuned loop
    # without a notch, measured on a fresh sampled-data axis: 439.6 Hz)
    _, plain_loop = velocity_loop(problem, plain.design)
    assert abs(d.notch.f_hz / (plain_loop.ms_frequency / (2 * math.pi)) - 1) < 0.05
    stable, loop = velocity_loop(problem, d)
    assert stable and loop.ms <= 1.6 * (1 + 1e-3)
    assert d.kp > 2.0 * plain.design.kp
    # without the notch the same loop at the tuned gains is far beyond its Ms limit
    bare = dataclasses.replace(d, notch_depth=1.0)
    stable_bare, loop_bare = velocity_loop(problem, bare)
    assert not stable_bare or loop_bare.ms > 2.0


def test_the_tuned_placement_beats_the_notch_held_at_the_resonance(problem, tuned):
    """Second method: the same tuning with the notch's centre held at the structure's natural
    frequency (width and depth free) ends with a higher compliance peak than the tuner's own
    placement."""
    _, _, _, notched = tuned
    d = notched.design
    held = dataclasses.replace(
        problem, notch=NotchFilter(resonance_hz(), d.notch_width, d.notch_depth),
        free=("kv", "kp", "ti", "notch_width", "notch_depth"))
    at_resonance = tune(held, starts=1)
    assert at_resonance.success
    assert notched.after.peak_compliance < at_resonance.after.peak_compliance


def test_design_keeps_the_notch_whole():
    """A design takes the notch's three values together and its depth in (0, 1]."""
    with pytest.raises(ValueError, match="together"):
        Design(c=1.0, kv=1.0, kp=1.0, ti=1.0, notch_frequency=100.0)
    with pytest.raises(ValueError, match="depth"):
        Design(c=1.0, kv=1.0, kp=1.0, ti=1.0, notch_frequency=100.0, notch_width=0.3,
               notch_depth=1.5)
    d = Design(c=1.0, kv=1.0, kp=1.0, ti=1.0, notch_frequency=2 * math.pi * 400.0,
               notch_width=0.3, notch_depth=0.2)
    assert d.notch == NotchFilter(400.0, 0.3, 0.2)
    assert Design(**d.to_dict()) == d
