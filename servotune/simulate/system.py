"""The axis as a linear system with one (or a few) nonlinear inputs per guide-way pad.

:func:`axis_system` interconnects (``control.interconnect``) the structure, the linear part of
the friction law at each pad (:mod:`servotune.simulate.contact`) and the drive cascade exactly as
:func:`servotune.plant.build_plant` does (same structure block, same drive blocks, same motor
port), but leaves open, per pad, the nonlinear remainder ``r_<pad>`` of the friction law (and
``q_<pad>`` for a law with two remainders, LuGre with velocity-dependent micro-damping)::

    dX/dt = A X + B_u u(t) + B_r r,        r_p = r(v_p, z_p)   (per pad p)

u are the known inputs (``x_ref``, ``v_ref``, ``a_ref``, the work-piece forces ``f_wp_*``,
``t_dist`` and the constant ``one``). With ``r = 0`` the system is the plant linearised about the
operating point (at rest: :class:`servotune.plant.Contact` ``stiction``).

The result also carries what the energy balance needs: the rows that give the structure's
velocities and displacements from X, so that kinetic and potential energy, the power of the
distributed damping ``v^T D v``, of the motor torque and of the work-piece force can be formed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import control
import numpy as np
import scipy.linalg

from ..digital import MEASURED, DigitalController, digital_controller
from ..drive import Drive, drive_blocks, winding_block
from ..plant import WP_DOFS, motor_port
from ..structure.model import ModalModel, signal_name
from .contact import PadFriction

__all__ = ["AxisSystem", "axis_system", "KNOWN_INPUTS"]

KNOWN_INPUTS = ("x_ref", "v_ref", "a_ref", "f_wp_x", "f_wp_y", "f_wp_z", "t_dist", "one",
                "voltage")


@dataclass(frozen=True, eq=False)
class AxisSystem:
    """The linear part of the axis and the maps to what is recorded (SI).

    Attributes
    ----------
    system : control.StateSpace
        Inputs: the known inputs present (subset of :data:`KNOWN_INPUTS`) then ``r_<pad>`` for
        each pad with a nonlinear law (then ``q_<pad>`` for each pad, when the law has a second
        remainder: remainder input k belongs to pad ``k % n_pads``). Outputs: :attr:`outputs`.
    inputs : tuple of str
        Known input names (columns of B_u).
    outputs : tuple of str
        Recorded output names.
    pads : tuple of str
    nonlinear : bool
        Whether the pads carry a nonlinear remainder.
    pad_velocity, pad_state : (n_pads, n) arrays
        Rows giving v_p and the state of remainder component 0 z_p from X (no feed-through).
    remainder_velocity, remainder_state : (n_r, n) arrays
        Per remainder input k, the rows of the velocity and of the state it reads (pad
        ``k % n_pads``, state :meth:`~servotune.friction.law.FrictionLaw.remainder_states` of
        component ``k // n_pads``).
    spring_rows : (k, n) array
        ``sum k_j z_j^2 = |spring_rows X|^2`` over the law's elastic states at all pads
        (:meth:`~servotune.friction.law.FrictionLaw.spring_states`), for the stored energy.
    force_rows : (n_pads, n) arrays, force_du, force_dr
        F_p = force_rows X + force_du u + force_dr r (friction force, per pad; force_dr has a
        column per remainder input).
    wp_velocity : (n_forces, n) array
        Velocities of the DOFs the ``f_wp_*`` inputs act on, in input order.
    wp_force_inputs : tuple of int
        Indices in :attr:`inputs` of the work-piece forces.
    motor_rows : (2, n) array
        Torque [N m] and rotor-minus-stator speed [rad/s] from X (zero without a drive).
    damping_rows : (k, n) array
        ``v^T D v = |damping_rows X|^2``.
    energy_rows : (2 n_dof, n) array
        ``1/2 v^T M v + 1/2 x^T K x = 1/2 |energy_rows X|^2``.
    controller : DigitalController or None
        The digital drive's controllers (None for a continuous drive or none): the linear
        part is then the axis driven by its motor voltage (the known input ``voltage``, held
        between the controller's samples), and the controllers are computed at their sample
        instants by the integrator.
    measured_rows : (3, n) array
        The sampled outputs (:data:`servotune.digital.MEASURED`: current, rotor angle,
        position feedback) from X (no feed-through), for the controller.
    """

    system: control.StateSpace
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    pads: tuple[str, ...]
    nonlinear: bool
    pad_velocity: np.ndarray
    pad_state: np.ndarray
    remainder_velocity: np.ndarray
    remainder_state: np.ndarray
    spring_rows: np.ndarray
    force_rows: np.ndarray
    force_du: np.ndarray
    force_dr: np.ndarray
    wp_velocity: np.ndarray
    wp_force_inputs: tuple[int, ...]
    motor_rows: np.ndarray
    damping_rows: np.ndarray
    energy_rows: np.ndarray
    structure: ModalModel = field(repr=False)
    controller: DigitalController | None = None
    measured_rows: np.ndarray | None = None

    @property
    def n_states(self) -> int:
        """Number of states n of :attr:`system`."""
        return self.system.nstates


def _factor_psd(a: np.ndarray) -> np.ndarray:
    """L with L^T L = a for a symmetric positive semi-definite a (rows for non-zero
    eigenvalues only)."""
    lam, q = scipy.linalg.eigh(a)
    keep = lam > 1e-12 * max(lam.max(), 1e-300)
    return (np.sqrt(lam[keep])[:, None] * q[:, keep].T)


def axis_system(structure: ModalModel, drive: Drive | None, friction: PadFriction | None,
                pads=(), speed: float = 0.0, inputs=None) -> AxisSystem:
    """Interconnect structure, pad friction (linear part) and drive.

    Parameters
    ----------
    structure : ModalModel
        The reduced structure.
    drive : Drive, optional
        The cascade (None: no control, the motor DOFs are free).
    friction : PadFriction, optional
        The friction law at the pads (None: no friction).
    pads : sequence of str
        The pad DOFs (relative X at the guide-way pads).
    speed : float
        Operating speed [m/s] about which a nonlinear law is linearised (0: at rest).
    inputs : sequence of str, optional
        The known inputs to keep (default: all of :data:`KNOWN_INPUTS` the axis has). Leaving out
        the ones that stay zero makes the simulation faster.

    Returns
    -------
    AxisSystem
        The linear system with its known and remainder inputs, and the rows of the energy
        balance.

    Raises
    ------
    ValueError
        A friction law without pads, or an input in ``inputs`` the axis does not have.
    UnknownDofError
        A pad, motor or encoder DOF the structure does not have.
    """
    pads = tuple(pads)
    structure.index(list(pads))
    if friction is not None and not pads:
        raise ValueError("a friction law needs the pad DOFs (pads=...)")
    if friction is None:
        pads = ()
    nonlinear = bool(friction is not None and friction.nonlinear)
    have = set(structure.dofs)
    wp = [d for d in WP_DOFS if d in have]
    motor, extra = [], []
    if drive is not None:
        motor = [d for d in (drive.motor.rotor, drive.motor.stator) if d is not None]
        structure.index(motor)
        if drive.feedback == "linear" and drive.encoder not in wp + list(pads) + motor:
            structure.index(drive.encoder)
            extra = [drive.encoder]
    ports = list(dict.fromkeys(wp + list(pads) + motor))
    mech = structure.to_state_space(inputs=ports, outputs=ports + extra,
                                    velocity_outputs=ports, name="structure")
    blocks = [mech] + [friction.pad_block(p, len(pads), speed) for p in pads]
    sampled = drive is not None and not drive.digital.is_continuous
    controller = None
    if sampled:
        # the axis driven by its held motor voltage; the controllers run at their samples
        controller = digital_controller(drive)
        rel = [1.0] if drive.motor.stator is None else [1.0, -1.0]
        angles = [signal_name(d) for d in motor]
        blocks += [winding_block(drive.motor), *motor_port(drive),
                   control.ss([], [], [], [rel], inputs=angles, outputs=["motor_angle"],
                              name="motor_angle"),
                   control.ss([], [], [], [[1.0, -1.0]], inputs=["x_ref", "x_fb"],
                              outputs=["following_error"], name="following_error"),
                   # the velocity and acceleration references reach only the controllers
                   control.ss([], [], [], [[0.0, 0.0]], inputs=["v_ref", "a_ref"],
                              outputs=["references_read_by_the_controllers"],
                              name="references")]
    elif drive is not None:
        blocks += drive_blocks(drive) + motor_port(drive)
    available = (["x_ref", "v_ref", "a_ref"] if drive is not None else []) + [
        signal_name(d, "f_") for d in wp] + (["t_dist"] if drive is not None else []) + (
        ["one"] if nonlinear else []) + (["voltage"] if sampled else [])
    if inputs is None:
        inputs = available
    else:
        inputs = list(dict.fromkeys(inputs))
        if sampled:   # the controllers read the references and drive the voltage
            inputs = list(dict.fromkeys([*inputs, "x_ref", "v_ref", "a_ref", "voltage"]))
        unknown = [s for s in inputs if s not in available]
        if unknown:
            raise ValueError(f"inputs {unknown} are not inputs of this axis; it has {available}")
    remainders = ([friction.remainder_signals(p)[k] for k in range(friction.n_remainders)
                   for p in pads] if nonlinear else [])
    outputs = [signal_name(d) for d in wp]
    if drive is not None:
        outputs += ["slide_x", "omega_motor", "following_error", "torque", "current"]
    if sampled:
        outputs += ["motor_angle", "x_fb"]
    pad_blocks = blocks[1:1 + len(pads)]
    for p, block in zip(pads, pad_blocks, strict=True):
        # the pad, then the friction block's outputs but the force on the DOF (F_, states)
        outputs += [signal_name(p), signal_name(p, "v_")] + [
            o for o in block.output_labels if o != signal_name(p, "f_")]
    inplist = list(inputs) + remainders
    # control.interconnect needs every listed input to reach a block; 'one' and r_ exist only
    # with a nonlinear law
    sys = control.interconnect(blocks, inplist=inplist, outlist=outputs, inputs=inplist,
                               outputs=outputs, name="axis", check_unused=False)
    n = sys.nstates
    labels = sys.state_labels
    index = {s: i for i, s in enumerate(labels)}

    def state_row(name):
        row = np.zeros(n)
        row[index[name]] = 1.0
        return row

    def out_row(name):
        i = sys.output_labels.index(name)
        return sys.C[i], sys.D[i, :len(inputs)], sys.D[i, len(inputs):]

    dof_x = np.array([index[f"structure_x_{signal_name(d)}"] for d in structure.dofs])
    dof_v = np.array([index[f"structure_v_{signal_name(d)}"] for d in structure.dofs])
    n_pad = len(pads)
    pad_v = np.array([state_row(f"structure_v_{signal_name(p)}") for p in pads]).reshape(
        n_pad, n)
    pad_z = np.zeros((n_pad, n))
    force_rows = np.zeros((n_pad, n))
    force_du = np.zeros((n_pad, len(inputs)))
    force_dr = np.zeros((n_pad, len(remainders)))
    def law_state(p, name):
        return state_row(f"friction_{signal_name(p)}_{name}")

    rem_v = np.zeros((len(remainders), n))
    rem_z = np.zeros((len(remainders), n))
    springs = []
    for k, p in enumerate(pads):
        force_rows[k], force_du[k], dr = out_row(signal_name(p, "F_"))
        if nonlinear:
            states = friction.remainder_states(p)
            pad_z[k] = law_state(p, states[0])
            force_dr[k] = dr
            for comp, name in enumerate(states):
                rem_v[comp * n_pad + k] = pad_v[k]
                rem_z[comp * n_pad + k] = law_state(p, name)
            springs += [math.sqrt(stiff) * law_state(p, name)
                        for name, stiff in friction.spring_states(p, n_pad)]
    spring_rows = np.array(springs).reshape(len(springs), n)
    force_inputs = tuple(i for i, s in enumerate(inputs) if s.startswith("f_wp_"))
    wp_v = np.array([state_row(f"structure_v_{inputs[i][2:]}") for i in force_inputs]).reshape(
        len(force_inputs), n)
    motor_rows = np.zeros((2, n))
    if drive is not None:
        motor_rows[0] = out_row("torque")[0]
        motor_rows[1] = state_row(f"structure_v_{signal_name(drive.motor.rotor)}")
        if drive.motor.stator is not None:
            motor_rows[1] -= state_row(f"structure_v_{signal_name(drive.motor.stator)}")
    sel_v = np.zeros((structure.n, n))
    sel_v[np.arange(structure.n), dof_v] = 1.0
    sel_x = np.zeros((structure.n, n))
    sel_x[np.arange(structure.n), dof_x] = 1.0
    damping_rows = _factor_psd(structure.damping) @ sel_v
    energy_rows = np.vstack([np.linalg.cholesky(structure.mass).T @ sel_v,
                             _factor_psd(structure.stiffness) @ sel_x])
    measured = None
    if sampled:
        measured = np.array([out_row(name)[0] for name in MEASURED])
        feed = np.array([np.concatenate(out_row(name)[1:]) for name in MEASURED])
        if np.abs(feed).max(initial=0.0) > 0.0:
            raise ValueError("the sampled outputs of the axis have a feed-through")
    return AxisSystem(
        system=sys, inputs=tuple(inputs), outputs=tuple(outputs), pads=pads, nonlinear=nonlinear,
        pad_velocity=pad_v, pad_state=pad_z, remainder_velocity=rem_v,
        remainder_state=rem_z, spring_rows=spring_rows, force_rows=force_rows, force_du=force_du,
        force_dr=force_dr, wp_velocity=wp_v, wp_force_inputs=force_inputs,
        motor_rows=motor_rows, damping_rows=damping_rows, energy_rows=energy_rows,
        structure=structure, controller=controller, measured_rows=measured)
