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
from .closed_loop import closed_loop
from .drive import Drive
from .plant import (
    Contact,
    UnstableLoopError,
    build_plant,
    contact_kind,
    contact_kinds,
    friction_contact,
)
from .units import HZ_PER_RAD_S, RAD_S_PER_HZ

__all__ = [
    "axis_contact",
    "axis_plant",
    "axis_loop",
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
    """Return a log-spaced grid of angular frequencies [rad/s].

    Parameters
    ----------
    f_min_hz, f_max_hz : float
        First and last frequency [Hz], > 0.
    n : int
        Number of points.

    Returns
    -------
    numpy.ndarray
        ``2 pi geomspace(f_min_hz, f_max_hz, n)`` [rad/s], shape (n,).
    """
    return 2 * math.pi * np.geomspace(f_min_hz, f_max_hz, n)


def axis_contact(axis: Axis, kind: str, amplitude: float | None = None,
                 frequency_hz: float | None = None, speed: float | None = None,
                 c: float | None = None) -> Contact:
    """Return the axis' guide-way contact model of a kind (:func:`servotune.plant.contact_kinds`).

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
    return friction_contact(axis.friction, kind, amplitude=amplitude, omega=omega, v0=speed,
                            c=c)


def axis_plant(axis: Axis, contact: Contact, drive: Drive | None = None,
               controlled: bool = True) -> control.StateSpace:
    """Return the linearised axis with the axis' drive (or ``drive``), or without control.

    Parameters
    ----------
    axis : Axis
        The axis: its structure and, when it has ``[friction]``, its pads.
    contact : Contact
        The guide-way contact model (a ``free`` contact gets no pads).
    drive : Drive, optional
        The drive (default: the axis' own); ignored when ``controlled`` is False.
    controlled : bool
        With the drive's cascade (True) or without motion control (False: the structure and
        its contacts only, the paper's Fig 9 set-up).

    Returns
    -------
    control.StateSpace
        The plant of :func:`servotune.plant.build_plant`, with its named signals.

    Raises
    ------
    AxisFormatError
        Controlled, with no ``drive`` given and no ``[drive]`` in the axis.
    ValueError
        A contact acting at the pads on an axis without ``[friction]`` (no pads).
    """
    drive = (drive or axis.require_drive()) if controlled else None
    pads = axis.pads if axis.friction is not None else ()
    return build_plant(axis.structure, drive, contact, pads if contact.pads != "free" else ())


def axis_loop(axis: Axis, contact: Contact, drive: Drive | None = None,
              controlled: bool = True):
    """Return the controlled axis with a contact: continuous or sampled-data.

    Parameters
    ----------
    axis : Axis
        The axis: its structure and, when it has ``[friction]``, its pads.
    contact : Contact
        The guide-way contact model (a ``free`` contact gets no pads).
    drive : Drive, optional
        The drive (default: the axis' own); ignored when ``controlled`` is False.
    controlled : bool
        With the drive (True) or without motion control (False).

    Returns
    -------
    servotune.closed_loop.ContinuousAxis or servotune.digital.SampledAxis
        :func:`servotune.closed_loop.closed_loop` of the axis.

    Raises
    ------
    AxisFormatError
        Controlled, with no ``drive`` given and no ``[drive]`` in the axis.
    ValueError
        A contact acting at the pads on an axis without ``[friction]`` (no pads).
    """
    drive = (drive or axis.require_drive()) if controlled else None
    pads = axis.pads if axis.friction is not None else ()
    return closed_loop(axis.structure, drive, contact, pads if contact.pads != "free" else ())


@dataclass(frozen=True)
class LoopReport:
    """The velocity and position loops of an axis: analyses and their frequency responses.

    Attributes
    ----------
    contact : Contact
        The guide-way contact model the loops were computed with.
    omega : numpy.ndarray
        Angular frequencies [rad/s], shape (K,).
    velocity, position : LoopAnalysis
        Margins, Ms and bandwidth of the velocity loop (position loop open) and of the position
        loop (velocity loop closed).
    l_velocity, l_position : numpy.ndarray
        The loop transfer functions L(j omega) [-] at ``omega``, complex, shape (K,).
    """

    contact: Contact
    omega: np.ndarray
    velocity: frequency.LoopAnalysis
    position: frequency.LoopAnalysis
    l_velocity: np.ndarray
    l_position: np.ndarray

    def to_dict(self) -> dict:
        """Return the report JSON-ready.

        Returns
        -------
        dict
            ``contact`` (the kind), ``contact_note``, and ``velocity_loop``,
            ``position_loop`` as :meth:`LoopAnalysis.to_dict
            <servotune.frequency.LoopAnalysis.to_dict>` gives them (no frequency responses).
        """
        return {"contact": self.contact.kind, "contact_note": self.contact.note,
                "velocity_loop": self.velocity.to_dict(),
                "position_loop": self.position.to_dict()}

    def plot(self, title: str = "Loop transfer functions"):
        """Return the Bode diagram of both loops with their margins marked.

        Parameters
        ----------
        title : str
            The figure's title.

        Returns
        -------
        matplotlib.figure.Figure
            The figure of :func:`servotune.plots.plot_bode`.
        """
        from .plots import plot_bode

        return plot_bode({"velocity": (self.omega, self.l_velocity),
                          "position": (self.omega, self.l_position)},
                         {"velocity": self.velocity, "position": self.position}, title=title)


def loop_report(axis: Axis, contact: Contact, drive: Drive | None = None,
                omega=None) -> LoopReport:
    """Return the margins, Ms and bandwidth of both loops of an axis.

    The velocity loop is opened with the position loop open, the position loop with the
    velocity loop closed, and each is analysed for margins, Ms and bandwidth: continuous
    loops by :func:`servotune.frequency.analyse_loop`, the loops of a digital drive as the
    sampled-data system it is (:class:`servotune.digital.SampledAxis`: each loop at its
    controller's rate, up to its Nyquist frequency; NaN above).

    Parameters
    ----------
    axis : Axis
        The axis: its structure and, when it has ``[friction]``, its pads.
    contact : Contact
        The guide-way contact model.
    drive : Drive, optional
        The drive (default: the axis' own).
    omega : array_like, optional
        Angular frequencies [rad/s], 1-D, increasing (default 0.1 Hz to 3 kHz, 8001 points,
        log-spaced).

    Returns
    -------
    LoopReport
        The analyses and L(j omega) of both loops.

    Raises
    ------
    UnstableLoopError
        If a closed loop is unstable (for a sampled drive the message says that its delays
        cost phase).
    AxisFormatError
        With no ``drive`` given and no ``[drive]`` in the axis.
    ValueError
        A contact acting at the pads on an axis without ``[friction]``, or a bad ``omega``.

    See Also
    --------
    compliance_curve : The work-piece compliance with the same contact.
    servotune.frequency.compliance : The compliance of a plant.
    servotune.simulate.simulator.simulate : The nonlinear time response of the axis.
    """
    drive = drive or axis.require_drive()
    omega = default_omega(0.1, 3000.0, 8001) if omega is None else np.asarray(omega, float)
    model = axis_loop(axis, contact, drive)
    out = {}
    for loop in ("velocity", "position"):
        try:
            analysed = model.analyse_loop(loop, omega)
        except UnstableLoopError as exc:
            if drive.sampling is not None and not drive.sampling.is_continuous:
                raise UnstableLoopError(
                    f"{exc}. The drive is sampled ([drive.sampling]): its sample-and-hold and "
                    "computation delays cost phase that a continuous model does not show; tune "
                    "the gains (servotune tune) or, for the paper's continuous model, pass "
                    "--continuous") from None
            raise
        out[loop] = (analysed, model.loop_response(loop, omega))
    return LoopReport(contact, omega, out["velocity"][0], out["position"][0],
                      out["velocity"][1], out["position"][1])


@dataclass(frozen=True)
class ComplianceCurve:
    """A work-piece compliance curve and its peak (SI).

    Attributes
    ----------
    label : str
        Name of the curve (legend).
    omega : numpy.ndarray
        Angular frequencies [rad/s], shape (K,).
    values : numpy.ndarray
        Complex compliance [m/N], shape (K,).
    peak_compliance : float
        Largest |compliance| within ``band`` [m/N], refined between grid points
        (:func:`servotune.frequency.peak`).
    peak_frequency : float
        Where it occurs [rad/s].
    band : tuple of float, optional
        The band the peak was sought in [rad/s].
    """

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
        """Return the peak JSON-ready.

        Returns
        -------
        dict
            ``label``, ``peak_compliance`` [m/N], ``peak_frequency_hz`` [Hz] and
            ``peak_at_edge`` (:attr:`at_edge`); the curve itself is left out.
        """
        return {"label": self.label, "peak_compliance": self.peak_compliance,
                "peak_frequency_hz": self.peak_frequency * HZ_PER_RAD_S,
                "peak_at_edge": self.at_edge}


def _in_band(omega: np.ndarray, band) -> np.ndarray:
    """The points of ``omega`` inside ``band``; a ValueError naming both when there are none."""
    sel = (omega >= band[0]) & (omega <= band[1])
    if not np.any(sel):
        grid = (f"{omega.min():.4g} to {omega.max():.4g} rad/s, {omega.size} points"
                if omega.size else "empty")
        raise ValueError(
            f"no point of omega ({grid}) lies in the requirement band {band[0]:.4g} to "
            f"{band[1]:.4g} rad/s ({band[0] * HZ_PER_RAD_S:.4g} to {band[1] * HZ_PER_RAD_S:.4g} "
            "Hz): give omega points inside the band")
    return sel


def _curve(label, model, omega, band) -> ComplianceCurve:
    sel = _in_band(omega, band)
    model.require_stable()
    values = model.compliance(omega)[0]
    value, where = frequency.peak(omega[sel], values[sel])
    return ComplianceCurve(label, omega, values, value, where, (float(band[0]), float(band[1])))


def compliance_curve(axis: Axis, contact: Contact, drive: Drive | None = None, omega=None,
                     label: str | None = None, controlled: bool | None = None
                     ) -> ComplianceCurve:
    """Return the work-piece X compliance of an axis with a contact model, and its peak.

    Closed loop when the axis has a drive (or ``drive`` is given, or ``controlled`` says so);
    the peak is taken over the axis' requirement band (``[requirements] band_hz``, default
    5 to 300 Hz).

    Parameters
    ----------
    axis : Axis
        The axis: its structure, pads, drive and requirement band.
    contact : Contact
        The guide-way contact model.
    drive : Drive, optional
        The drive (default: the axis' own).
    omega : array_like, optional
        Angular frequencies [rad/s], 1-D, increasing (default 1 Hz to 1 kHz, 3000 points,
        log-spaced); it should cover the band.
    label : str, optional
        Name of the curve (default: the contact's note, else its kind).
    controlled : bool, optional
        With or without motion control (default: with, when there is a drive).

    Returns
    -------
    ComplianceCurve
        x/F at ``wp.x`` [m/N] and its peak in the band.

    Raises
    ------
    UnstableLoopError
        If the closed loop is unstable (a compliance of an unstable loop means nothing).
    AxisFormatError
        Controlled, with no ``drive`` given and no ``[drive]`` in the axis.
    ValueError
        A contact acting at the pads on an axis without ``[friction]``, a bad ``omega``, or
        no point of ``omega`` in the band.

    See Also
    --------
    loop_report : The margins of the loops with the same contact.
    servotune.frequency.compliance : The compliance of a plant.
    servotune.friction.equivalent.describing_function : Ceq and Keq of an ``equivalent``
        contact.
    """
    omega = default_omega() if omega is None else np.asarray(omega, float)
    if controlled is None:
        controlled = drive is not None or axis.drive is not None
    _in_band(omega, axis.requirements.band)
    model = axis_loop(axis, contact, drive, controlled=controlled)
    return _curve(label or contact.note or contact.kind, model, omega, axis.requirements.band)


def uncontrolled_compliance(axis: Axis, c_values, omega=None) -> list[ComplianceCurve]:
    """Return the paper's Fig 9: the work-piece compliance with viscous damping C, no control.

    Without motion control the axis is free to move (a rigid-body pole at the origin, which
    the stability check accepts); the guide-way pads carry a viscous contact C.

    Parameters
    ----------
    axis : Axis
        The axis, with ``[friction]`` (its pads).
    c_values : iterable of float
        Total viscous damping values C [N s/m], finite and >= 0.
    omega : array_like, optional
        Angular frequencies [rad/s] (default 1 Hz to 1 kHz, 3000 points, log-spaced).

    Returns
    -------
    list of ComplianceCurve
        One per C, labelled ``"C = 5e+05 N s/m"``, peak in the requirement band.

    Raises
    ------
    ValueError
        A negative C, an axis without ``[friction]``, or no point of ``omega`` in the band.
    """
    omega = default_omega() if omega is None else np.asarray(omega, float)
    _in_band(omega, axis.requirements.band)
    curves = []
    for c in c_values:
        model = axis_loop(axis, Contact.viscous(c), controlled=False)
        curves.append(_curve(f"C = {c:.0e} N s/m", model, omega, axis.requirements.band))
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
    model = axis_loop(axis, contact, drive,
                      controlled=drive is not None or axis.drive is not None)
    model.require_stable()
    values = model.compliance(omega, f"wp.{d}", [f"wp.{d}"])
    return control.frd(values.reshape(1, 1, -1), omega, inputs=[f"f_wp_{d}"],
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
