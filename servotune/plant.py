"""The linearised feed axis: structure, guide-way contacts and the drive in one python-control
system.

:func:`build_plant` interconnects (``control.interconnect``) the reduced structure
(:class:`~servotune.structure.ModalModel`), one linear contact element per guide-way pad
(:class:`Contact`) and the cascade of :mod:`servotune.drive`::

      x_ref, v_ref, a_ref              f_wp_x/y/z            t_dist
            |                              |                    |
        [drive cascade] --torque--> [ motor port ] ---> [ structure ] ---> wp_x/y/z, slide_x
            ^      ^                                      |      ^
            |      +------ omega_fb (rotor - stator) -----+      |
            +------------- x_fb (linear or motor encoder) -------+
                                                   pad x, v  |   | -F_pad
                                                        [ contact per pad ]

Plant inputs: ``x_ref`` [m], ``v_ref`` [m/s], ``a_ref`` [m/s^2], ``f_wp_x``, ``f_wp_y``,
``f_wp_z`` [N] (those the structure has), ``t_dist`` [N m] (disturbance torque on the rotor).
Plant outputs: ``wp_x``, ``wp_y``, ``wp_z`` [m], ``slide_x`` [m] (the position feedback
signal), ``omega_motor`` [rad/s], ``following_error`` [m], ``torque`` [N m], ``current`` [A].

Guide-way friction is linearised per pad (all axis friction is lumped at the pads, paper sec 3;
the values of a :class:`Contact` are axis totals shared equally by the pads). The kinds of
contact are registered (:func:`register_contact_kind`, :func:`contact_kinds`) and built from the
axis' friction law (:class:`servotune.friction.law.FrictionLaw`), whatever law it is:

- ``locked``: the pads are held rigidly (the pad DOFs are removed);
- ``stiction``: the law's presliding contact (LuGre: a spring sigma0 with a damper
  sigma1 + sigma2);
- ``viscous``: a damper C;
- ``equivalent``: the law's describing function at a vibration amplitude, Ceq with Keq
  (Eq 8-10);
- ``sliding``: the law linearised about a sliding speed v0, a dynamic element;
- ``free``: no contact force.

References
----------
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 3, 4.2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import control
import numpy as np

from .contact_kinds import (
    CONTACT_PARAMETERS,
    ContactKind,
    ContactParameter,
    contact_kind,
    contact_kinds,
    register_contact_kind,
)
from .drive import Drive, drive_blocks, winding_block
from .friction.guideway import GuideWayFriction
from .interconnect import connect
from .structure.model import ModalModel, signal_name
from .units import HZ_PER_RAD_S, RAD_S_PER_HZ

__all__ = ["Contact", "ContactKind", "ContactParameter", "friction_contact", "build_contact",
           "build_plant",
           "build_open_plant",
           "loop_transfer", "CONTACT_KINDS", "CONTACT_PARAMETERS", "UnstableLoopError",
           "contact_kind", "contact_kinds", "register_contact_kind"]

WP_DOFS = ("wp.x", "wp.y", "wp.z")


class UnstableLoopError(ValueError):
    """A closed loop that is unstable where a stable one is required."""


@dataclass(frozen=True)
class Contact:
    """Linear model of the guide-way friction, as axis totals shared equally by the pads.

    Parameters
    ----------
    kind : str
        A registered kind (:func:`contact_kinds`).
    stiffness : float
        Total contact stiffness [N/m] (stiction: the presliding spring; equivalent: Keq).
    damping : float
        Total contact damping [N s/m] (stiction: the presliding damper; viscous: C;
        equivalent: Ceq).
    system : control.StateSpace, optional
        A dynamic contact (e.g. ``sliding``): the total contact as a SISO system from pad
        velocity [m/s] to friction force [N]; it replaces stiffness and damping.
    note : str
        Where the values came from (shown in reports).

    Raises
    ------
    ValueError
        Unknown kind, negative or non-finite stiffness or damping, a system that is not SISO.

    Examples
    --------
    >>> Contact.viscous(4.912e5).damping
    491200.0
    """

    kind: str
    stiffness: float = 0.0
    damping: float = 0.0
    system: control.StateSpace | None = field(default=None, compare=False)
    note: str = ""

    def __post_init__(self) -> None:
        contact_kind(self.kind)
        for name in ("stiffness", "damping"):
            value = float(getattr(self, name))
            if not math.isfinite(value) or value < 0.0:
                raise ValueError(f"Contact.{name} must be finite and >= 0, got {value!r}; a "
                                 "negative value would make the guide way generate energy")
            object.__setattr__(self, name, value)
        if self.system is not None:
            sys = control.ss(self.system)
            if sys.ninputs != 1 or sys.noutputs != 1:
                raise ValueError(f"the {self.kind} contact system must be SISO (velocity -> "
                                 "force)")
            object.__setattr__(self, "system", sys)

    @property
    def pads(self) -> str:
        """``"contact"``, ``"locked"`` or ``"free"`` (:attr:`ContactKind.pads`)."""
        return contact_kind(self.kind).pads

    @classmethod
    def locked(cls) -> Contact:
        """Pads held rigidly."""
        return cls("locked", note="pads locked")

    @classmethod
    def free(cls) -> Contact:
        """No friction at the pads."""
        return cls("free", note="no friction")

    @classmethod
    def viscous(cls, c: float) -> Contact:
        """Viscous damping C [N s/m] (axis total).

        Parameters
        ----------
        c : float
            Total viscous damping C [N s/m], finite and >= 0.

        Returns
        -------
        Contact
            Kind ``viscous``, ``damping = c``, no stiffness.
        """
        return cls("viscous", damping=c, note=f"viscous C = {c:.4g} N s/m")

    @classmethod
    def stiction(cls, sigma0: float, sigma1: float, sigma2: float) -> Contact:
        """LuGre presliding linearisation: spring sigma0, damper sigma1 + sigma2 (axis totals).

        About v = 0 the LuGre force ``F = sigma0 z + sigma1 dz/dt + sigma2 v`` (Bianchi et al.
        2014, Eq 3) with ``dz/dt = v`` to first order is a spring sigma0 in parallel with a
        damper sigma1 + sigma2.

        Parameters
        ----------
        sigma0 : float
            Total bristle stiffness [N/m].
        sigma1 : float
            Total bristle damping [N s/m].
        sigma2 : float
            Total viscous coefficient [N s/m].

        Returns
        -------
        Contact
            Kind ``stiction``, ``stiffness = sigma0``, ``damping = sigma1 + sigma2``.
        """
        return cls("stiction", stiffness=sigma0, damping=sigma1 + sigma2,
                   note=f"stiction: sigma0 = {sigma0:.3g} N/m, sigma1 + sigma2 = "
                        f"{sigma1 + sigma2:.3g} N s/m")

    @classmethod
    def equivalent(cls, ceq: float, keq: float = 0.0, amplitude: float | None = None) -> Contact:
        """Describing-function contact: Ceq [N s/m] and Keq [N/m] (axis totals).

        Parameters
        ----------
        ceq : float
            Total equivalent damping Ceq [N s/m] (Bianchi et al. 2014, Eq 8-10).
        keq : float
            Total equivalent stiffness Keq [N/m].
        amplitude : float, optional
            The vibration amplitude [m] the values belong to; only shown in ``note``.

        Returns
        -------
        Contact
            Kind ``equivalent``, ``stiffness = keq``, ``damping = ceq``.

        See Also
        --------
        servotune.friction.equivalent.describing_function : Ceq and Keq of a friction law.
        """
        at = f" at A = {amplitude:.3g} m" if amplitude is not None else ""
        return cls("equivalent", stiffness=keq, damping=ceq,
                   note=f"describing function{at}: Ceq = {ceq:.3g} N s/m, Keq = {keq:.3g} N/m")

    @classmethod
    def sliding(cls, system, v0: float | None = None) -> Contact:
        """Sliding linearisation: a SISO system from pad velocity to friction force (total).

        Parameters
        ----------
        system : control.StateSpace or control.TransferFunction
            Total contact, pad velocity [m/s] -> friction force [N], SISO (e.g. from
            :meth:`servotune.friction.law.FrictionLaw.sliding_system`).
        v0 : float, optional
            The sliding speed [m/s] it was linearised at; only shown in ``note``.

        Returns
        -------
        Contact
            Kind ``sliding`` with ``system`` as a state space.

        Raises
        ------
        ValueError
            If ``system`` is None or not SISO.
        """
        if system is None:
            raise ValueError("a sliding contact needs its linearised system (v -> F)")
        at = f" at v0 = {v0:.3g} m/s" if v0 is not None else ""
        return cls("sliding", system=system, note=f"sliding{at}")

    def pad_block(self, pad: str, n_pads: int) -> control.StateSpace:
        """Return one pad's share as a python-control block.

        Parameters
        ----------
        pad : str
            The pad DOF (its signal names follow :func:`servotune.structure.model.signal_name`).
        n_pads : int
            Number of pads sharing the contact (each gets ``1/n_pads`` of it).

        Returns
        -------
        control.StateSpace
            Inputs the pad displacement [m] and velocity [m/s] (only the velocity for a
            dynamic contact, ``system``), output the force on the pad DOF [N], minus the
            friction force: ``-(k x + c v)/n_pads`` or ``-system(v)/n_pads``.
        """
        x, v, f = signal_name(pad), signal_name(pad, "v_"), signal_name(pad, "f_")
        name = f"contact_{signal_name(pad)}"
        if self.system is not None:
            share = control.ss(self.system) * (-1.0 / n_pads)
            return control.ss(share.A, share.B, share.C, share.D, inputs=[v], outputs=[f],
                              name=name)
        gain = [[-self.stiffness / n_pads, -self.damping / n_pads]]
        return control.ss([], [], [], gain, inputs=[x, v], outputs=[f], name=name)


#: The contact kinds built in (:func:`contact_kinds` has those registered since).
CONTACT_KINDS = contact_kinds()


# ------------------------------------------------- the builders of servotune's contact kinds
def _presliding(friction, **_):
    k, c = friction.law.presliding()
    return Contact("stiction", stiffness=k, damping=c,
                   note=f"stiction ({friction.law.name} presliding): {k:.3g} N/m, {c:.3g} N s/m")


def _describing(friction, amplitude, frequency_hz, **_):
    ceq, keq = friction.law.describing_function(amplitude, RAD_S_PER_HZ * frequency_hz)
    return Contact.equivalent(float(ceq), max(float(keq), 0.0), amplitude)


def _viscous(friction, c=None, **_):
    return Contact.viscous(friction.viscous if c is None else c)


def _sliding(friction, speed, **_):
    return Contact.sliding(friction.law.sliding_system(speed), speed)


_BUILDERS = {"locked": lambda friction, **_: Contact.locked(),
             "free": lambda friction, **_: Contact.free(),
             "stiction": _presliding, "viscous": _viscous, "equivalent": _describing,
             "sliding": _sliding}


def build_contact(kind: str, friction, **parameters) -> Contact:
    """Return the contact of a registered kind built from the axis' friction.

    Parameters
    ----------
    kind : str
        A registered contact kind (:func:`contact_kinds`).
    friction : GuideWayFriction or None
        The axis' friction (None for a kind that needs none).
    **parameters
        The kind's parameters (:attr:`ContactKind.parameters`).

    Returns
    -------
    Contact
        Built by the kind's own ``build``, or by servotune's builder of its own kinds.
    """
    spec = contact_kind(kind)
    build = spec.build if spec.build is not None else _BUILDERS[spec.name]
    return build(friction, **parameters)


def friction_contact(friction: GuideWayFriction, kind: str, amplitude: float | None = None,
                     omega: float | None = None, v0: float | None = None,
                     c: float | None = None) -> Contact:
    """Return the linear contact model of a kind (see :func:`contact_kinds`), axis total.

    ``stiction`` is the law's presliding contact; ``viscous`` the viscous-only damping (or
    ``c``); ``equivalent`` the law's describing function (Ceq and Keq); ``sliding`` the law
    linearised at a speed.

    Parameters
    ----------
    friction : GuideWayFriction
        The axis' guide-way friction (its law builds the contact).
    kind : str
        A registered contact kind.
    amplitude : float, optional
        Vibration amplitude [m] (``equivalent``).
    omega : float, optional
        Vibration angular frequency [rad/s] (``equivalent``).
    v0 : float, optional
        Sliding speed [m/s], non-zero (``sliding``).
    c : float, optional
        Viscous damping [N s/m] (``viscous``; default ``friction.viscous``).

    Returns
    -------
    Contact

    Raises
    ------
    ValueError
        Unknown kind, or a parameter the kind needs is missing.
    """
    spec = contact_kind(kind)
    values = {"c": c, "amplitude": amplitude, "speed": v0,
              "frequency_hz": None if omega is None else HZ_PER_RAD_S * omega}
    missing = spec.missing(values)
    if missing:
        raise ValueError(f"the {kind!r} contact needs {_listing(spec.required)} "
                         f"({spec.purpose})")
    return build_contact(kind, friction, **{p: values[p] for p in spec.parameters})


def _listing(names) -> str:
    """'a non-zero speed [m/s]', 'amplitude [m] and frequency_hz [Hz]'."""
    words = []
    for name in names:
        p = CONTACT_PARAMETERS[name]
        words.append(f"{'a non-zero ' if p.nonzero else ''}{name} [{p.unit}]")
    return " and ".join(words)


def _blocks(structure: ModalModel, drive: Drive | None, contact: Contact | None, pads,
            motor_of: Drive | None = None, extra_ports=()):
    """The python-control blocks of the axis and the work-piece DOFs present (the structure
    with the motor ports of ``drive`` or ``motor_of``; the controllers of ``drive`` only)."""
    contact = Contact.free() if contact is None else contact
    pads = list(pads)
    structure.index(pads)  # clear error for unknown pad DOFs
    if contact.pads != "free" and not pads:
        raise ValueError(f"a {contact.kind!r} contact needs the pad DOFs (pads=...)")
    if contact.pads == "locked":
        structure = structure.locked(pads)
    if contact.pads != "contact":
        pads = []
    have = set(structure.dofs)
    wp = [d for d in WP_DOFS if d in have]
    motor, outputs_extra = [], []
    ported = drive if drive is not None else motor_of
    if ported is not None:
        motor = [d for d in (ported.motor.rotor, ported.motor.stator) if d is not None]
        structure.index(motor)  # clear error for unknown motor DOFs
        if ported.feedback == "linear" and ported.encoder not in wp + pads + motor:
            structure.index(ported.encoder)
            outputs_extra = [ported.encoder]
    extra = [p for p in extra_ports if p not in wp + pads + motor]
    ports = wp + pads + motor + extra
    mech = structure.to_state_space(inputs=ports, outputs=ports + outputs_extra,
                                    velocity_outputs=pads + motor, name="structure")
    blocks = [mech] + [contact.pad_block(p, len(pads)) for p in pads]
    if drive is not None:
        blocks += drive_blocks(drive) + motor_port(drive)
    return blocks, wp


def build_open_plant(structure: ModalModel, drive: Drive, contact: Contact | None = None,
                     pads=(), force_pads: bool = False,
                     name: str = "open_axis") -> control.StateSpace:
    """Return the axis driven by its motor voltage, without the controllers (continuous).

    Structure, guide-way contacts, the motor winding and its port: what a digital drive
    samples and drives through its zero-order hold (see :mod:`servotune.digital`).

    Parameters
    ----------
    structure : ModalModel
        The reduced structure.
    drive : Drive
        The drive (its motor, transmission and feedback; the controllers are not used).
    contact : Contact, optional
        Guide-way model (default: free).
    pads : sequence of str
        The pad DOFs where the contact acts.
    force_pads : bool
        With inputs ``f_<pad>`` [N] acting on the pad DOFs and outputs ``<pad>`` [m] (the
        free pads of harmonic balance; the contact must be ``free``).
    name : str
        Name of the system.

    Returns
    -------
    control.StateSpace
        Inputs ``voltage`` [V], the work-piece forces ``f_wp_*`` [N], ``t_dist`` [N m]
        (then the pad forces); outputs ``current`` [A], ``motor_angle`` (rotor minus stator)
        [rad], ``x_fb`` [m], the work-piece displacements ``wp_*`` [m], ``slide_x`` [m],
        ``omega_motor`` [rad/s], ``torque`` [N m], then the pad displacements ``<pad>`` [m]
        (with a contact acting at the pads, or ``force_pads``).

    Raises
    ------
    ValueError
        ``force_pads`` with a contact other than ``free``, or a contact without pads.
    UnknownDofError
        A pad, motor or encoder DOF the structure does not have.
    """
    contact = Contact.free() if contact is None else contact
    pads = list(pads)
    if force_pads:
        if contact.pads != "free":
            raise ValueError("force_pads needs a free contact (the pad forces are inputs)")
        structure.index(pads)
    blocks, wp = _blocks(structure, None, contact, pads, motor_of=drive,
                         extra_ports=pads if force_pads else ())
    rotor, stator = drive.motor.rotor, drive.motor.stator
    angle_in = [signal_name(rotor)] + ([] if stator is None else [signal_name(stator)])
    rel = [1.0] if stator is None else [1.0, -1.0]
    blocks += [winding_block(drive.motor), *motor_port(drive),
               control.ss([], [], [], [rel], inputs=angle_in, outputs=["motor_angle"],
                          name="motor_angle")]
    inputs = ["voltage", *[signal_name(d, "f_") for d in wp], "t_dist"]
    outputs = ["current", "motor_angle", "x_fb", *[signal_name(d) for d in wp], "slide_x",
               "omega_motor", "torque"]
    if force_pads:
        inputs += [signal_name(p, "f_") for p in pads]
    if force_pads or contact.pads == "contact":
        outputs += [signal_name(p) for p in pads]
    return connect(blocks, inputs, outputs, name=name)


def build_plant(structure: ModalModel, drive: Drive | None = None, contact: Contact | None = None,
                pads=(), name: str = "axis") -> control.StateSpace:
    """Interconnect structure, contacts and drive into the linearised axis.

    Parameters
    ----------
    structure : ModalModel
        The reduced structure (DOF names as in the module docstring).
    drive : Drive, optional
        The cascade. Without it the plant is the structure with its contacts (no control: the
        paper's Fig 9 set-up).
    contact : Contact, optional
        Guide-way model (default: free).
    pads : sequence of str
        The pad DOFs (relative X at the guide-way pads) where the contact acts; a ``locked``
        contact removes them from the structure, a ``free`` one ignores them.
    name : str
        Name of the interconnected system.

    Returns
    -------
    control.StateSpace
        With the named inputs and outputs of the module docstring (without a drive only the
        work-piece forces ``f_wp_*`` and displacements ``wp_*``).

    Raises
    ------
    UnknownDofError
        A pad, motor or encoder DOF the structure does not have.
    ValueError
        A contact other than ``free`` with no pads.
    """
    blocks, wp = _blocks(structure, drive, contact, pads)
    plant_inputs = [signal_name(d, "f_") for d in wp]
    plant_outputs = [signal_name(d) for d in wp]
    if drive is not None:
        plant_inputs = ["x_ref", "v_ref", "a_ref", *plant_inputs, "t_dist"]
        plant_outputs += ["slide_x", "omega_motor", "following_error", "torque", "current"]
    return connect(blocks, plant_inputs, plant_outputs, name=name)


def motor_port(drive: Drive) -> list[control.StateSpace]:
    """Torque onto the rotor/stator DOFs; encoder signals from them."""
    rotor, stator = drive.motor.rotor, drive.motor.stator
    grounded = stator is None
    torque_out = [signal_name(rotor, "f_")] + ([] if grounded else [signal_name(stator, "f_")])
    port = control.ss([], [], [], [[1.0, 1.0]] + ([] if grounded else [[-1.0, 0.0]]),
                      inputs=["torque", "t_dist"], outputs=torque_out, name="motor_port")
    speed_in = [signal_name(rotor, "v_")] + ([] if grounded else [signal_name(stator, "v_")])
    angle_in = [signal_name(rotor)] + ([] if grounded else [signal_name(stator)])
    rel = np.array([1.0] if grounded else [1.0, -1.0])
    speeds = control.ss([], [], [], np.vstack([rel, rel, rel]), inputs=speed_in,
                        outputs=["omega_fb", "omega_rel", "omega_motor"], name="motor_encoder")
    if drive.feedback == "linear":
        position = control.ss([], [], [], [[1.0], [1.0]], inputs=[signal_name(drive.encoder)],
                              outputs=["x_fb", "slide_x"], name="linear_encoder")
    else:
        position = control.ss([], [], [], np.vstack([rel * drive.ratio] * 2), inputs=angle_in,
                              outputs=["x_fb", "slide_x"], name="motor_position")
    return [port, speeds, position]


def loop_transfer(structure: ModalModel, drive: Drive, contact: Contact | None = None,
                  pads=(), loop: str = "velocity") -> control.StateSpace:
    """Loop transfer function L(s) of the velocity or position loop, opened at its feedback.

    The loop is broken at the feedback signal (``omega_fb`` or ``x_fb``); L is minus the
    response of the measured signal to an injection into the controller's feedback input, so
    the closed loop is ``L/(1 + L)`` and the sensitivity ``1/(1 + L)``. The velocity loop is
    opened with the position loop open too (as a drive commissioning tool measures it); the
    position loop is opened with the velocity loop closed.

    Parameters
    ----------
    structure : ModalModel
        The reduced structure.
    drive : Drive
        The cascade whose loop is opened.
    contact : Contact, optional
        Guide-way model (default: free).
    pads : sequence of str
        The pad DOFs where the contact acts.
    loop : {"velocity", "position"}
        The loop to open: at ``omega_fb`` [rad/s] or at ``x_fb`` [m].

    Returns
    -------
    control.StateSpace
        SISO, input ``u`` (injected feedback), output ``y`` (minus the measured signal).

    Raises
    ------
    ValueError
        ``loop`` not ``"velocity"`` or ``"position"``, or a contact other than ``free``
        with no pads.
    UnknownDofError
        A pad, motor or encoder DOF the structure does not have.

    See Also
    --------
    servotune.frequency.analyse_loop : Margins and sensitivity peak of L.
    servotune.analysis.loop_report : Both loops of an axis analysed.
    """
    if loop not in ("velocity", "position"):
        raise ValueError(f"loop must be 'velocity' or 'position', got {loop!r}")
    blocks, _ = _blocks(structure, drive, contact, pads)
    broken = {"velocity": ("omega_fb", "x_fb"), "position": ("x_fb",)}[loop]
    for i, b in enumerate(blocks):  # rename the measured signals: their inputs become free
        if any(s in broken for s in b.output_labels):
            labels = [f"{s}_measured" if s in broken else s for s in b.output_labels]
            blocks[i] = control.ss(b.A, b.B, b.C, b.D, inputs=b.input_labels, outputs=labels,
                                   states=b.state_labels, name=b.name)
    signal = broken[0]
    open_loop = connect(blocks, [signal], [f"{signal}_measured"], name=f"L_{loop}",
                        input_names=["u"], output_names=["y"])
    return control.ss(open_loop.A, open_loop.B, -open_loop.C, -open_loop.D, inputs=["u"],
                      outputs=["y"], name=f"L_{loop}")
