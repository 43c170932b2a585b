"""Linear analyses of an axis description: plants per contact model, loops, compliance, lobes.

These functions join an :class:`~servotune.axis.Axis` to the model and analysis layers
(:mod:`servotune.plant`, :mod:`servotune.frequency`, :mod:`servotune.chatter`) so that the
command line and the report only call them. Every result is a frozen dataclass in SI units with
a ``to_dict()`` for JSON (frequencies also in Hz under ``*_hz`` keys).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np

from . import frequency
from .axis import Axis
from .chatter import stability_lobes
from .drive import Drive
from .plant import (
    Contact,
    UnstableLoopError,
    build_plant,
    contact_kind,
    contact_kinds,
    loop_transfer,
)
from .units import HZ_PER_RAD_S, RAD_S_PER_HZ

__all__ = [
    "axis_contact",
    "axis_plant",
    "LoopReport",
    "loop_report",
    "ComplianceCurve",
    "compliance_curve",
    "uncontrolled_compliance",
    "axis_lobes",
    "feed_compliance",
    "default_omega",
]



def default_omega(f_min_hz: float = 1.0, f_max_hz: float = 1000.0, n: int = 3000) -> np.ndarray:
    """A log-spaced grid [rad/s]."""
    return 2 * math.pi * np.geomspace(f_min_hz, f_max_hz, n)


def axis_contact(axis: Axis, kind: str, amplitude: float | None = None,
                 frequency_hz: float | None = None, speed: float | None = None,
                 c: float | None = None) -> Contact:
    """The axis' guide-way contact model of a kind (:func:`servotune.plant.contact_kinds`).

    Parameters
    ----------
    axis : Axis
        The axis; its friction law builds the contact.
    kind : str
        A registered contact kind, e.g. ``"stiction"``, ``"viscous"``, ``"equivalent"``,
        ``"sliding"``; built from the axis' friction law.
    amplitude : float, optional
        Vibration amplitude [m] (``equivalent``).
    frequency_hz : float, optional
        Vibration frequency [Hz] (``equivalent``).
    speed : float, optional
        Sliding speed [m/s], non-zero (``sliding``).
    c : float, optional
        Viscous damping [N s/m] (``viscous``; default the axis' viscous-only value).

    Returns
    -------
    Contact

    Raises
    ------
    ValueError
        An unknown kind, a parameter the kind needs is missing, or one is given that the kind
        does not use (the message names the parameters of this function).
    """
    spec = contact_kind(kind)
    values = {"c": c, "amplitude": amplitude, "frequency_hz": frequency_hz, "speed": speed}
    for name, value in values.items():
        if value is not None and name not in spec.parameters:
            user = next(k for k in map(contact_kind, contact_kinds()) if name in k.parameters)
            raise ValueError(f"{name} is a parameter of the {user.name!r} contact; it has no "
                             f"meaning for the {kind!r} contact")
    if axis.friction is None:
        if not spec.needs_friction:
            return spec.build(None, **{p: values[p] for p in spec.parameters})
        axis.pads  # raises the clear error  # noqa: B018
    omega = None if frequency_hz is None else RAD_S_PER_HZ * frequency_hz
    return axis.friction.contact(kind, amplitude=amplitude, omega=omega, v0=speed, c=c)


def axis_plant(axis: Axis, contact: Contact, drive: Drive | None = None,
               controlled: bool = True) -> control.StateSpace:
    """The linearised axis (see :func:`servotune.plant.build_plant`) with the axis' drive (or
    ``drive``), or without control when ``controlled`` is False."""
    drive = (drive or axis.require_drive()) if controlled else None
    pads = axis.pads if axis.friction is not None else ()
    return build_plant(axis.structure, drive, contact, pads if contact.pads != "free" else ())


@dataclass(frozen=True)
class LoopReport:
    """The velocity and position loops of an axis: analyses and their frequency responses."""

    contact: Contact
    omega: np.ndarray
    velocity: frequency.LoopAnalysis
    position: frequency.LoopAnalysis
    l_velocity: np.ndarray
    l_position: np.ndarray

    def to_dict(self) -> dict:
        return {"contact": self.contact.kind, "contact_note": self.contact.note,
                "velocity_loop": self.velocity.to_dict(),
                "position_loop": self.position.to_dict()}

    def plot(self, title: str = "Loop transfer functions"):
        from .plots import plot_bode

        return plot_bode({"velocity": (self.omega, self.l_velocity),
                          "position": (self.omega, self.l_position)},
                         {"velocity": self.velocity, "position": self.position}, title=title)


def loop_report(axis: Axis, contact: Contact, drive: Drive | None = None,
                omega=None) -> LoopReport:
    """Margins, Ms and bandwidth of both loops (velocity with the position loop open,
    position with the velocity loop closed).

    Raises
    ------
    UnstableLoopError
        If a closed loop is unstable.
    """
    drive = drive or axis.require_drive()
    omega = default_omega(0.1, 3000.0, 8001) if omega is None else np.asarray(omega, float)
    pads = axis.pads if axis.friction is not None else ()
    out = {}
    for loop in ("velocity", "position"):
        lt = loop_transfer(axis.structure, drive, contact, pads, loop)
        try:
            analysed = frequency.analyse_loop(lt, omega)
        except UnstableLoopError as exc:
            if drive.sampling is not None and not drive.sampling.is_continuous:
                raise UnstableLoopError(
                    f"{exc}. The drive is sampled ([drive.sampling]): its delays cost phase "
                    "that a continuous model does not show; tune the gains (servotune tune) "
                    "or, for the paper's continuous model, pass --continuous") from None
            raise
        out[loop] = (analysed,
                     frequency.fast_frequency_response(lt, omega).complex.reshape(-1))
    return LoopReport(contact, omega, out["velocity"][0], out["position"][0],
                      out["velocity"][1], out["position"][1])


@dataclass(frozen=True)
class ComplianceCurve:
    """A work-piece compliance curve and its peak (SI)."""

    label: str
    omega: np.ndarray
    values: np.ndarray
    peak_compliance: float
    peak_frequency: float
    band: tuple[float, float] | None = None     # where the peak was sought [rad/s]

    @property
    def at_edge(self) -> bool:
        """The peak lies at an edge of its band (within 3 % in frequency): the largest value
        there, not a resonance; the true peak may lie outside the band."""
        if self.band is None or not np.isfinite(self.peak_frequency):
            return False
        lo, hi = self.band
        return bool(self.peak_frequency <= lo * 1.03 or self.peak_frequency >= hi / 1.03)

    def to_dict(self) -> dict:
        return {"label": self.label, "peak_compliance": self.peak_compliance,
                "peak_frequency_hz": self.peak_frequency * HZ_PER_RAD_S,
                "peak_at_edge": self.at_edge}


def _curve(label, plant, omega, band) -> ComplianceCurve:
    values = frequency.compliance(plant, omega)
    sel = (omega >= band[0]) & (omega <= band[1])
    value, where = frequency.peak(omega[sel], values[sel])
    return ComplianceCurve(label, omega, values, value, where, (float(band[0]), float(band[1])))


def compliance_curve(axis: Axis, contact: Contact, drive: Drive | None = None, omega=None,
                     label: str | None = None, controlled: bool | None = None
                     ) -> ComplianceCurve:
    """Work-piece X compliance with a contact model, closed loop when the axis has a drive
    (or ``controlled`` says so); the peak is taken over the axis' requirement band."""
    omega = default_omega() if omega is None else np.asarray(omega, float)
    if controlled is None:
        controlled = drive is not None or axis.drive is not None
    plant = axis_plant(axis, contact, drive, controlled=controlled)
    return _curve(label or contact.note or contact.kind, plant, omega, axis.requirements.band)


def uncontrolled_compliance(axis: Axis, c_values, omega=None) -> list[ComplianceCurve]:
    """The paper's Fig 9: work-piece compliance with viscous guide-way damping C and no
    motion control (the axis free to move), for each C [N s/m]."""
    omega = default_omega() if omega is None else np.asarray(omega, float)
    curves = []
    for c in c_values:
        plant = axis_plant(axis, Contact.viscous(c), controlled=False)
        curves.append(_curve(f"C = {c:.0e} N s/m", plant, omega, axis.requirements.band))
    return curves


def _lobes_omega() -> np.ndarray:
    return default_omega(1.0, 2000.0, 6000)


def feed_compliance(axis: Axis, contact: Contact, drive: Drive | None = None, omega=None):
    """Return the closed-loop work-piece compliance in the axis' feed direction, as data.

    This is the compliance every chatter analysis of an axis uses (the design job's lobes and
    ``servotune lobes AXIS``), on one frequency grid.

    Parameters
    ----------
    axis : Axis
        The axis (its ``[cutting]`` direction, else x).
    contact : Contact
        The guide-way contact model.
    drive : Drive, optional
        The drive (default: the axis' own; an axis without drive is taken uncontrolled).
    omega : array_like, optional
        Frequencies [rad/s] (default 1 to 2000 Hz, 6000 points, log-spaced).

    Returns
    -------
    control.FrequencyResponseData
        x/F at the work piece [m/N], input ``f_wp_<d>``, output ``wp_<d>``.

    Raises
    ------
    servotune.plant.UnstableLoopError
        When the closed loop is unstable (a compliance would mean nothing).

    See Also
    --------
    axis_lobes : the stability lobes from this compliance.
    """
    omega = _lobes_omega() if omega is None else np.asarray(omega, float)
    d = axis.cutting.direction if axis.cutting is not None else "x"
    plant = axis_plant(axis, contact, drive,
                       controlled=drive is not None or axis.drive is not None)
    frequency.require_stable(plant)
    return frequency.fast_frequency_response(plant, omega, inputs=[f"f_wp_{d}"],
                                             outputs=[f"wp_{d}"])


def axis_lobes(axis: Axis, contact: Contact, drive: Drive | None = None, omega=None,
               n_speeds: int = 2000):
    """Return the zero-order stability lobes of the closed-loop axis in its feed direction.

    Parameters
    ----------
    axis : Axis
        The axis, with its milling set-up (``[cutting]``): the speed range and direction.
    contact : Contact
        The guide-way contact model.
    drive : Drive, optional
        The drive (default: the axis' own).
    omega : array_like, optional
        Frequencies [rad/s] of the compliance (default: :func:`feed_compliance`'s).
    n_speeds : int
        Number of spindle speeds, equally spaced over the axis' speed range.

    Returns
    -------
    servotune.chatter.StabilityLobes
        The lobes, b_crit and the critical speed.

    Raises
    ------
    ValueError
        When the axis has no ``[cutting]`` section.

    See Also
    --------
    feed_compliance : the compliance the lobes are computed from.
    """
    cutting = axis.require_cutting()
    frd = feed_compliance(axis, contact, drive, omega)
    speeds = np.linspace(*cutting.speed_rpm, n_speeds)
    return stability_lobes(frd, cutting.setup, speeds, direction=cutting.direction)
