"""Linear analyses of an axis description: plants per contact model, loops, compliance, lobes.

These functions join an :class:`~servotune.axis.Axis` to the model and analysis layers
(:mod:`servotune.plant`, :mod:`servotune.frequency`, :mod:`servotune.chatter`) so that the
command line and the report only call them. Every result is a frozen dataclass in SI units with
a ``to_dict()`` for JSON (frequencies also in Hz under ``*_hz`` keys).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import control
import numpy as np

from . import frequency
from .axis import Axis
from .chatter import compliance_matrix, oriented_frf, stability_lobes
from .closed_loop import closed_loop
from .drive import Drive
from .peaks import BandPeak, ModeBand, band_peak, extreme_edge, mode_band
from .plant import (
    Contact,
    UnstableLoopError,
    build_contact,
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
    "chatter_minimum_edge",
    "default_omega",
    "default_band",
    "band_omega",
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


def default_band(axis: Axis, dof: str = "wp.x") -> ModeBand:
    """Return the default band of an axis' analyses: its requirement band, widened for its modes.

    The modes that move the work piece are those of the structure in every configuration the
    axis can be in (the guide-way pads held or free when it has ``[friction]``, the motor
    rotor held or free when it has ``[drive]``; :meth:`~servotune.axis.Axis.configuration`,
    as ``servotune modes`` takes them) that carry a significant share of the static
    compliance at ``dof`` (:func:`servotune.peaks.mode_band`). The band is
    ``[requirements] band_hz`` widened to hold each of them with the margin
    :data:`servotune.peaks.BAND_MARGIN`.

    Parameters
    ----------
    axis : Axis
        The axis: its structure, requirement band and sections.
    dof : str
        The work-piece DOF (default ``"wp.x"``).

    Returns
    -------
    servotune.peaks.ModeBand
        The band [rad/s], the requirement band and the modes; its
        :meth:`~servotune.peaks.ModeBand.note` says it in one line.

    See Also
    --------
    compliance_curve : the compliance over a band.
    """
    pads = ("locked", "free") if axis.friction is not None else ("free",)
    motor = ("locked", "free") if axis.drive is not None else ("free",)
    models = [axis.configuration(pads=p, motor=m) for p in pads for m in motor]
    return mode_band(axis.requirements.band, models, dof)


def band_omega(band, per_decade: int = 1000, f_min_hz: float = 1.0,
               f_max_hz: float = 1000.0) -> np.ndarray:
    """Return a log-spaced grid [rad/s] that covers a band and 1 Hz to 1 kHz.

    Parameters
    ----------
    band : (float, float)
        The band [rad/s] the grid must cover.
    per_decade : int
        Points per decade.
    f_min_hz, f_max_hz : float
        The grid covers at least this range [Hz] (the default grid of
        :func:`compliance_curve`).

    Returns
    -------
    numpy.ndarray
        ``2 pi geomspace(lo, hi, n)`` [rad/s] with ``lo <= f_min_hz``, ``hi >= f_max_hz``, and
        the band's ends themselves, so that the band's first and last samples are its ends.
    """
    lo = min(f_min_hz, band[0] * HZ_PER_RAD_S)
    hi = max(f_max_hz, band[1] * HZ_PER_RAD_S)
    n = max(3, math.ceil(per_decade * math.log10(hi / lo)))
    grid = default_omega(lo, hi, n)
    ends = np.array([float(band[0]), float(band[1])])
    near = np.any(np.abs(grid[:, None] / ends[None, :] - 1) < 1e-6, axis=1)
    return np.union1d(grid[~near], ends)


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
            return build_contact(kind, None, **{p: values[p] for p in spec.parameters})
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
            <servotune.frequency.LoopAnalysis.to_dict>` gives them (no frequency responses),
            each with ``ms_at_band_edge`` (:meth:`ms_edge`) and ``band_hz``, the grid's ends.
        """
        band = [float(self.omega[0]) * HZ_PER_RAD_S, float(self.omega[-1]) * HZ_PER_RAD_S]
        return {"contact": self.contact.kind, "contact_note": self.contact.note,
                "velocity_loop": dict(self.velocity.to_dict(),
                                      ms_at_band_edge=self.ms_edge("velocity"), band_hz=band),
                "position_loop": dict(self.position.to_dict(),
                                      ms_at_band_edge=self.ms_edge("position"), band_hz=band)}

    def ms_edge(self, loop: str) -> str | None:
        """Return whether a loop's sensitivity peak Ms lies at an edge of the frequency grid.

        By the rule of :func:`servotune.peaks.extreme_edge` on |1/(1 + L)|: at the grid's first
        or last point the largest value is no peak (the sensitivity still rises beyond);
        a sampled loop's values beyond its Nyquist frequency (NaN) are left out.

        Parameters
        ----------
        loop : {"velocity", "position"}
            The loop.

        Returns
        -------
        str or None
            ``"low"``, ``"high"`` or None (inside the grid).
        """
        l_loop = {"velocity": self.l_velocity, "position": self.l_position}[loop]
        with np.errstate(divide="ignore", invalid="ignore"):
            return extreme_edge(np.abs(1.0 / (1.0 + np.asarray(l_loop))))

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
    """A work-piece compliance curve and its largest value over a band (SI).

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
        (:func:`servotune.frequency.peak`); a resonance only when :attr:`edge` is None.
    peak_frequency : float
        Where it occurs [rad/s].
    band : tuple of float, optional
        The band the peak was sought in [rad/s].
    band_peak : servotune.peaks.BandPeak, optional
        The largest value by the rule of :mod:`servotune.peaks`: whether it lies at an edge
        of the band (then it is no resonance), the largest resonance inside, a rigid-body
        mode.
    """

    label: str
    omega: np.ndarray
    values: np.ndarray
    peak_compliance: float
    peak_frequency: float
    band: tuple[float, float] | None = None     # where the peak was sought [rad/s]
    band_peak: BandPeak | None = None

    @property
    def edge(self) -> str | None:
        """``"low"`` or ``"high"`` when the largest value is at that edge of the band (no
        resonance: the response still rises there), None when it lies inside."""
        return None if self.band_peak is None else self.band_peak.edge

    @property
    def at_edge(self) -> bool:
        """Whether the largest value is at an edge of the band (:attr:`edge`)."""
        return self.edge is not None

    def to_dict(self) -> dict:
        """Return the peak JSON-ready.

        Returns
        -------
        dict
            ``label``, ``peak_compliance`` [m/N] and ``peak_frequency_hz`` [Hz] (the
            resonance: None when the largest value is at an edge of the band), and the keys
            of :meth:`servotune.peaks.BandPeak.to_dict` (``peak_at_band_edge``,
            ``largest_compliance``, ``largest_at_hz``, ``resonance_hz``, ...); the curve
            itself is left out.
        """
        out = {"label": self.label}
        if self.band_peak is None:
            return dict(out, peak_compliance=self.peak_compliance,
                        peak_frequency_hz=self.peak_frequency * HZ_PER_RAD_S,
                        peak_at_band_edge=None)
        data = self.band_peak.to_dict("compliance")
        return {**out, **data, "peak_frequency_hz": data["resonance_hz"]}


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


def _refine(omega, magnitude):
    value, where = frequency.peak(omega, magnitude)
    return where, value


def _rigid_body(model) -> bool:
    """Whether a continuous model has a pole at the origin (a rigid-body mode)."""
    plant = getattr(model, "plant", None)
    if plant is None:
        return False
    poles = np.abs(np.asarray(control.ss(plant).poles()))
    return bool(poles.size and np.any(poles <= 1e-6 * poles.max()))


def _curve(label, model, omega, band, controlled=True) -> ComplianceCurve:
    sel = _in_band(omega, band)
    model.require_stable()
    values = model.compliance(omega)[0]
    found = band_peak(omega[sel], values[sel], refine=_refine, unit="m/N")
    if found.edge == "low" and not controlled and _rigid_body(model):
        found = dataclasses.replace(found, rigid_body=True)
    return ComplianceCurve(label, omega, values, found.largest, found.largest_frequency,
                           (float(band[0]), float(band[1])), found)


def compliance_curve(axis: Axis, contact: Contact, drive: Drive | None = None, omega=None,
                     label: str | None = None, controlled: bool | None = None,
                     band=None) -> ComplianceCurve:
    """Return the work-piece X compliance of an axis with a contact model, and its peak.

    Closed loop when the axis has a drive (or ``drive`` is given, or ``controlled`` says so);
    the peak is taken over ``band``, by default the axis' requirement band
    (``[requirements] band_hz``, default 5 to 300 Hz). A largest value at an edge of the band
    is flagged and is no resonance (:mod:`servotune.peaks`).

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
    band : (float, float), optional
        The band [rad/s] of the peak (default the requirement band; :func:`default_band`
        widens it to hold the work-piece modes).

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
    band = axis.requirements.band if band is None else band
    if controlled is None:
        controlled = drive is not None or axis.drive is not None
    _in_band(omega, band)
    model = axis_loop(axis, contact, drive, controlled=controlled)
    return _curve(label or contact.note or contact.kind, model, omega, band, controlled)


def uncontrolled_compliance(axis: Axis, c_values, omega=None, band=None
                            ) -> list[ComplianceCurve]:
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
    band : (float, float), optional
        The band [rad/s] of the peaks (default the requirement band). The rigid-body mode
        makes the compliance rise towards 0 Hz: where that is the largest value in the band,
        the curve says so (:attr:`ComplianceCurve.band_peak`).

    Returns
    -------
    list of ComplianceCurve
        One per C, labelled ``"C = 5e+05 N s/m"``, peak in the band.

    Raises
    ------
    ValueError
        A negative C, an axis without ``[friction]``, or no point of ``omega`` in the band.
    """
    omega = default_omega() if omega is None else np.asarray(omega, float)
    band = axis.requirements.band if band is None else band
    _in_band(omega, band)
    curves = []
    for c in c_values:
        model = axis_loop(axis, Contact.viscous(c), controlled=False)
        curves.append(_curve(f"C = {c:.0e} N s/m", model, omega, band, controlled=False))
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


def chatter_minimum_edge(system, setup, direction: str = "x", omega=None) -> str | None:
    """Return whether the minimum of Re G of chatter lies at an edge of the frequency grid.

    The absolute stability limit b_crit comes from the most negative real part of the
    oriented transfer function (:func:`servotune.chatter.oriented_frf`). At the grid's first
    or last frequency (:func:`servotune.peaks.extreme_edge`) that minimum is the value at the
    edge, not the chatter resonance: the real part still falls beyond, and b_crit is not a
    limit found inside the grid.

    Parameters
    ----------
    system : control.StateSpace, control.FrequencyResponseData or (omega, H)
        The compliance, as :func:`servotune.chatter.stability_lobes` takes it.
    setup : servotune.chatter.MillingSetup
        The milling set-up.
    direction : {"x", "y"}
        Flexible direction of a SISO compliance.
    omega : array_like, optional
        The frequency grid [rad/s] (default: the one the lobes use).

    Returns
    -------
    str or None
        ``"low"``, ``"high"`` or None (the minimum lies inside the grid).

    See Also
    --------
    axis_lobes : the lobes of an axis.
    """
    _, g = compliance_matrix(system, omega, direction)
    return extreme_edge(oriented_frf(g, setup).real.min(axis=1), minimum=True)
