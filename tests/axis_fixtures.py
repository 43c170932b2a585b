"""A small flexible feed axis, built by hand, for tests of the drive, plant and analyses.

DOFs: motor.rotor and motor.stator [rad], pad1.x and pad2.x (slide halves at the guide-way
pads) [m], encoder.x (linear-encoder head) [m], wp.x (work piece) [m]. The ball screw couples
r * rotor to the slide; the stator sits on a torsional bracket.
"""

import numpy as np

from servotune.drive import Drive, Motor, PIController, kv_from_m_per_min_per_mm
from servotune.structure import ModalModel

RATIO = 10e-3 / (2 * np.pi)  # 10 mm lead, direct drive [m/rad]


def small_axis(zeta=0.03) -> ModalModel:
    dofs = ["motor.rotor", "motor.stator", "pad1.x", "pad2.x", "encoder.x", "wp.x"]
    idx = {d: i for i, d in enumerate(dofs)}
    m = np.diag([0.012, 0.03, 400.0, 400.0, 2.0, 300.0])
    k = np.zeros((6, 6))

    def spring(a, b, value, ca=1.0, cb=1.0):
        # spring on the coordinate ca*q[a] - cb*q[b] (b may be None: grounded)
        vec = np.zeros(6)
        vec[idx[a]] += ca
        if b is not None:
            vec[idx[b]] -= cb
        k[:] += value * np.outer(vec, vec)

    spring("motor.rotor", "pad1.x", 3.0e8, ca=RATIO)      # screw, nut and bearings
    spring("motor.rotor", "motor.stator", 0.0)           # (torque acts between them)
    spring("motor.stator", None, 2.0e5)                  # motor bracket, torsional
    spring("pad1.x", "pad2.x", 2.0e9)                    # slide body
    spring("pad2.x", "encoder.x", 5.0e8)                 # encoder head bracket
    spring("pad2.x", "wp.x", 1.5e8)                      # table, fixture, work piece
    return ModalModel(m, k, dofs, damping_ratio=zeta)


def small_drive(**changes) -> Drive:
    j_ref = 0.012 + 1100.0 * RATIO**2  # rotor plus slide and work piece referred to the motor
    params = dict(
        motor=Motor(torque_constant=1.2, back_emf_constant=1.2, resistance=0.4,
                    inductance=3e-3),
        ratio=RATIO,
        current_loop=PIController(kp=15.0, ti=2e-3),
        velocity_loop=PIController(kp=2 * np.pi * 40.0 * j_ref, ti=12e-3),
        kv=kv_from_m_per_min_per_mm(1.0),
    )
    params.update(changes)
    return Drive(**params)


PADS = ["pad1.x", "pad2.x"]
