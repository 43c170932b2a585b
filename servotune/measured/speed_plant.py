"""The drive's measured speed plant and the velocity loop closed on it (non-parametric).

The measuring function of an industrial drive excites the motor torque and records the motor
speed: the *speed plant* P(j w) = Omega / T [rad/(s N m)], motor speed (rotor minus stator)
over the air-gap torque (rotor +, stator -). At standstill with a small excitation the guide
ways stay in their presliding regime, so the model it is compared with is the axis with its
``stiction`` contact (:func:`model_speed_plant`).

An auto-tuner then closes the velocity loop on the measured P instead of on a model: the loop
transfer function L(j w) is the drive's own elements times the measurement
(:func:`velocity_loop_response`). Here the elements are those of the model the rest of
servotune uses, so a measured P gives the same loop as the model it came from:

* the continuous drive of the paper (:func:`servotune.drive.cascade_response`): with the
  winding ``L di/dt = u - R i - ke Omega`` and ``Omega = P kt i``::

      L(s) = C_v F C_i P / (s L + R + C_i + kt ke P)

  (C_v the velocity PI, F the torque set-point filters, C_i the current PI);
* a digital drive (:mod:`servotune.digital`): the continuous plant from the held voltage to
  the sampled current and rotor angle, built from P, is

      Y_i = W / (1 + kt ke P W),   W = 1 / (s L + R),   Y_phi = kt P Y_i / s

  and its zero-order-hold equivalent at ``z = exp(j w T)`` is the alias sum
  ``G(w) = sum_k h0(w_k) Y(j w_k)``, ``w_k = w + k 2 pi / T``, h0 the hold's fundamental
  (:func:`servotune.digital.hold_fundamental`); the winding's own part ``W`` is summed in
  closed form, ``(1 - p) / (R (z - p))`` with ``p = exp(-R T / L)``, so the remainder falls
  as ``1/k^4`` and ``|k| <= 20`` leaves it below 1e-6 of the loop. These replace the model's
  sampled responses in the same cascade algebra (:func:`servotune.digital.cascade.current_level`,
  :func:`~servotune.digital.lift`, :func:`~servotune.digital.cascade.velocity_level`) with the
  controllers' own difference equations (:meth:`servotune.digital.DigitalController.response`:
  the current PI and set-point filters, the speed as the backward difference of the sampled
  angle with its filter, the velocity PI, the computation delays). The velocity loop is so
  the one :meth:`servotune.digital.SampledAxis.loop_response` gives, broken at the velocity
  controller with the position loop open.

The fundamental needs P only on the measured lines; the aliases (and, for a velocity
controller slower than the current controller, the lifted lines) need it elsewhere: between
lines it is interpolated linearly, above the last line it is continued as the inertia line
``1 / (j w J)`` with J from the top tenth of the measured band (:class:`SpeedPlantResponse`).
Below about half the current controller's Nyquist frequency those terms change the loop by
well under 1e-4.

References
----------
T. Chen, B. Francis, Optimal Sampled-Data Control Systems, Springer (1995), sec 3.3 and
10.5 (the zero-order-hold equivalent as the alias sum). K. J. Astrom, B. Wittenmark,
Computer-Controlled Systems, 3rd ed. (1997), sec 7.3. G. Ellis, Control System Design Guide,
4th ed. (2012), ch 14 (measuring the mechanical plant through the drive and tuning on it);
SINAMICS S120 Function Manual, "Measuring function speed controller" (the speed controlled
system measured from the torque set-point).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..drive import Drive
from ..frequency import LoopAnalysis, analyse_response
from ..plant import Contact, UnstableLoopError, build_open_plant
from ..structure.model import ModalModel
from ..units import HZ_PER_RAD_S

__all__ = ["ALIASES", "SPEED_PLANT_CONTACT", "SpeedPlantComparison", "SpeedPlantResponse",
           "compare_speed_plant", "encircled_poles", "model_speed_plant",
           "velocity_loop_response"]

#: the guide-way contact of a speed-plant measurement: standstill, small excitation (presliding)
SPEED_PLANT_CONTACT = "stiction"
#: alias terms on either side in the zero-order-hold sums (|k| <= ALIASES)
ALIASES = 20
#: the share of the measured band (its top) the inertia line above it is taken from
_TOP_SHARE = 0.1


def model_speed_plant(structure: ModalModel, drive: Drive, omega, contact: Contact | None = None,
                      pads=()) -> np.ndarray:
    """Return the model's speed plant, motor speed over motor torque, at ``omega``.

    The torque acts between rotor and stator as the motor's does (``motor_port`` of
    :mod:`servotune.plant`), the speed is the rotor's minus the stator's, the winding plays no
    part:
    ``P = H_Omega,u / H_T,u``, the speed and the torque per winding voltage of the open plant
    (:func:`servotune.plant.build_open_plant`), whose only path from the voltage to the
    mechanics is the torque.

    Parameters
    ----------
    structure : ModalModel
        The reduced structure.
    drive : Drive
        The drive (its motor DOFs; the controllers are not used).
    omega : array_like
        Angular frequencies [rad/s] (any sign: P(-j w) is the conjugate of P(j w)).
    contact : Contact, optional
        The guide-way contact (default free); a speed-plant measurement is at standstill,
        the pads in presliding: the axis' ``stiction`` contact.
    pads : sequence of str
        The pad DOFs where the contact acts.

    Returns
    -------
    numpy.ndarray
        P(j omega) [rad/(s N m)], complex, shape of ``omega``.

    See Also
    --------
    velocity_loop_response : the velocity loop closed on a speed plant.
    """
    from ..frequency import fast_frequency_response

    omega = np.asarray(omega, dtype=float)
    plant = build_open_plant(structure, drive, contact, pads)
    w = np.abs(omega.reshape(-1))
    r = fast_frequency_response(plant, w, inputs=["voltage"],
                                outputs=["omega_motor", "torque"]).complex
    p = r[0, 0] / r[1, 0]
    return np.where(omega.reshape(-1) < 0, p.conj(), p).reshape(omega.shape)


@dataclass(frozen=True)
class SpeedPlantResponse:
    """A measured speed plant as a function of frequency, for the alias sums.

    On the measured lines the measurement itself; between them linear interpolation of the
    real and imaginary parts; above the last line the inertia line ``1 / (j w J)``, J the
    median of ``Re 1 / (j w P)`` over the top tenth of the band (the inertia the drive
    accelerates there); below the first line the first value. ``P(-j w)`` is the conjugate.

    Attributes
    ----------
    omega : numpy.ndarray
        The measured angular frequencies [rad/s], increasing.
    values : numpy.ndarray
        P at them [rad/(s N m)].
    inertia : float
        J [kg m^2] of the continuation above the band.
    """

    omega: np.ndarray
    values: np.ndarray
    inertia: float = field(init=False)

    def __post_init__(self):
        omega = np.asarray(self.omega, dtype=float)
        values = np.asarray(self.values, dtype=complex)
        top = omega >= omega[-1] * (1.0 - _TOP_SHARE)
        top &= omega > 0
        inertia = float(np.median((1.0 / (1j * omega[top] * values[top])).real))
        if not (inertia > 0 and math.isfinite(inertia)):
            raise ValueError("the measured speed plant does not fall as an inertia 1/(j w J) "
                             "at the top of its band (Re 1/(j w P) there is "
                             f"{inertia:g} kg m^2); is it motor speed over motor torque?")
        object.__setattr__(self, "omega", omega)
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "inertia", inertia)

    def __call__(self, omega) -> np.ndarray:
        """Return P at angular frequencies ``omega`` [rad/s] (any shape, any sign)."""
        omega = np.asarray(omega, dtype=float)
        w = np.abs(omega)
        out = (np.interp(w, self.omega, self.values.real)
               + 1j * np.interp(w, self.omega, self.values.imag))
        above = w > self.omega[-1]
        out[above] = 1.0 / (1j * w[above] * self.inertia)
        return np.where(omega < 0, out.conj(), out)


def velocity_loop_response(drive: Drive, plant, omega, aliases: int = ALIASES) -> np.ndarray:
    """Return the velocity loop transfer function L(j w) closed on a speed plant.

    Broken at the velocity controller, the position loop open, as
    :meth:`servotune.digital.SampledAxis.loop_response` (digital drive) and
    :func:`servotune.plant.loop_transfer` (continuous drive) break it; the formulas are in the
    module's docstring::

        omega_cmd = 0 -->(+)--[ C_v ]--[ D_v ]--> T_set --[ current loop, hold ]--> T
                        -^                                                          |
                         +----[ speed: backward difference of the sampled angle ]--[ P ]

    Parameters
    ----------
    drive : Drive
        The drive: motor, current and velocity PIs, set-point filters, sampling.
    plant : callable
        P(w) [rad/(s N m)] at any real angular frequencies (array in, array out), e.g. a
        :class:`SpeedPlantResponse`; a continuous drive calls it at ``omega`` only.
    omega : array_like
        Angular frequencies [rad/s], 1-D, > 0.
    aliases : int
        Alias terms on either side in the zero-order-hold sums (digital drive).

    Returns
    -------
    numpy.ndarray
        Complex L, shape of ``omega``; NaN at and above the velocity controller's Nyquist
        frequency (a sampled loop repeats there).
    """
    from ..drive import cascade_response

    omega = np.asarray(omega, dtype=float)
    m = drive.motor
    kk = m.torque_constant * m.back_emf_constant
    sampling = drive.digital
    if sampling.is_continuous:
        c = cascade_response(drive, 1j * omega)
        p = plant(omega)
        return c.velocity_pi * c.setpoint * c.current_forward * p / (c.winding + kk * p)
    from ..digital import digital_controller, hold_fundamental, lift
    from ..digital.cascade import current_level, velocity_level

    t = sampling.current_period
    n_v, _ = sampling.multiples()
    t_v = n_v * t
    ctl = digital_controller(drive)
    out = np.full(omega.shape, np.nan + 0j)
    inside = omega < math.pi / t_v * (1.0 - 1e-9)
    w = omega[inside]
    shifts = w[:, None] + 2 * math.pi / t_v * np.arange(n_v)        # (K, n_v)
    wk = shifts[..., None] + 2 * math.pi / t * np.arange(-aliases, aliases + 1)
    p = plant(wk)
    s = 1j * wk
    winding = 1.0 / (s * m.inductance + m.resistance)
    y_i = winding / (1.0 + kk * p * winding)
    h0 = hold_fundamental(wk, t)
    z = np.exp(1j * shifts * t)
    q = math.exp(-m.resistance * t / m.inductance)
    g_i = (1.0 - q) / (m.resistance * (z - q)) + (h0 * (y_i - winding)).sum(-1)
    g_phi = (h0 * m.torque_constant * p * y_i / s).sum(-1)
    cur = current_level(g_i, g_phi, np.zeros_like(g_phi), ctl.response("current", "current", z),
                        ctl.response("current", "torque_set", z))
    g_vphi = lift(cur.phi_t, w, t, n_v)
    z_v = np.exp(1j * w * t_v)
    vel = velocity_level(g_vphi, np.zeros_like(g_vphi),
                         ctl.response("velocity", "motor_angle", z_v),
                         ctl.response("velocity", "omega_cmd", z_v))
    out[inside] = vel.l_v
    return out


def encircled_poles(l_jw) -> int | None:
    """Return how many closed-loop poles are unstable, by the Nyquist criterion on L's lines.

    The argument of ``F = 1 + L`` is unwrapped from its principal value at the first line to
    the last; with the conjugate half and a small detour around ``s = 0`` (``z = 1``) the
    whole contour turns ``2 arg F(last)`` (the detour adds ``2 Arg F(first)``, the real
    direction of a positive integrator's or a finite low-frequency loop), so the closed loop
    has ``-arg F(last) / pi`` poles in the right half plane (outside the unit circle). The
    last line must close the contour: the velocity controller's Nyquist frequency (F real
    there) or, for a continuous loop, a line where ``|L| < 1/2`` and falling (nothing beyond
    it can reach -1 if it keeps falling).

    Parameters
    ----------
    l_jw : array_like of complex
        L at increasing frequencies from near 0 to the top, dense enough that ``1 + L`` turns
        by less than pi between lines.

    Returns
    -------
    int or None
        The number of unstable closed-loop poles (0: stable), or None when the last line
        does not close the contour (``|L| >= 1/2`` there).

    Notes
    -----
    Assumes the open loop stable apart from integrators at ``s = 0`` with positive gain: the
    measured plant of a mechanism at rest and the drive's current loop, filters and
    controllers are (the criterion counts ``Z - P`` and takes P as 0). Skogestad and
    Postlethwaite, "Multivariable Feedback Control", 2nd ed. (2005), sec 4.9.2; for sampled
    loops on the unit circle, Franklin, Powell and Workman, "Digital Control of Dynamic
    Systems", 3rd ed. (1998), sec 7.5.

    Examples
    --------
    A PI loop on an integrator, ``L = 2 (1 + 1/s) / s``: stable.

    >>> w = np.geomspace(1e-3, 1e3, 4001)
    >>> encircled_poles(2 * (1 + 1 / (1j * w)) / (1j * w))
    0
    """
    l_jw = np.asarray(l_jw, dtype=complex)
    if abs(l_jw[-1]) >= 0.5 and abs(l_jw[-1].imag) > 1e-4 * abs(l_jw[-1]):
        return None
    phase = np.unwrap(np.angle(1.0 + l_jw))
    return int(max(0, -round(phase[-1] / math.pi)))


def _error(model: np.ndarray, measured: np.ndarray) -> float:
    """Relative RMS of the difference over the measurement, as the model updating's."""
    size = float(np.sum(np.abs(measured) ** 2))
    return math.sqrt(float(np.sum(np.abs(model - measured) ** 2)) / size) if size > 0 else math.inf


def _analysis_dict(a: LoopAnalysis | None) -> dict | None:
    return None if a is None else a.to_dict()


@dataclass(frozen=True)
class SpeedPlantComparison:
    """A measured speed plant against the model's, and the velocity loop closed on each.

    Attributes
    ----------
    omega : numpy.ndarray
        The measured angular frequencies [rad/s].
    measured, model : numpy.ndarray
        The measured and the model's speed plant [rad/(s N m)] at ``omega``.
    band : (float, float)
        The band [rad/s] of the FRF error.
    frf_error : float
        Relative RMS of model minus measurement over the band.
    l_measured, l_model : numpy.ndarray
        The velocity loop on the measured and on the model's plant at ``omega`` (NaN from the
        velocity controller's Nyquist frequency on).
    measured_loop : LoopAnalysis
        Margins, Ms and bandwidth of the loop on the measured plant.
    measured_unstable_poles : int or None
        Its unstable closed-loop poles by the Nyquist criterion (:func:`encircled_poles`;
        0: stable; None: the measurement does not reach far enough to tell).
    model_loop : LoopAnalysis or None
        The same of the model's own loop on the same lines (None when it is unstable).
    model_unstable : str or None
        Why the model's loop has no margins (its closed loop is unstable).
    drive_kind : str
        ``"sampled"`` or ``"continuous"``.
    nyquist : float
        The velocity controller's Nyquist frequency [rad/s] (inf for a continuous drive).
    contact : Contact
        The guide-way contact of the model (presliding).
    notes, warnings : tuple of str
        What was assumed, and what limits the result.

    See Also
    --------
    servotune.measured.figures.plot_speed_plant : its figure.
    """

    omega: np.ndarray
    measured: np.ndarray
    model: np.ndarray
    band: tuple[float, float]
    frf_error: float
    l_measured: np.ndarray
    l_model: np.ndarray
    measured_loop: LoopAnalysis
    measured_unstable_poles: int | None
    model_loop: LoopAnalysis | None
    model_unstable: str | None
    drive_kind: str
    nyquist: float
    contact: Contact
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    def velocity_loop(self) -> dict:
        """Return the velocity loop's margins, measured and model, JSON-ready.

        Returns
        -------
        dict
            The measured loop's ``gain_margin_db``, ``phase_margin_deg``, ``ms``,
            ``bandwidth_hz`` ... (:meth:`LoopAnalysis.to_dict
            <servotune.frequency.LoopAnalysis.to_dict>`) with ``stable`` and
            ``unstable_poles`` (Nyquist) at the top level and under ``measured``; the model's
            under ``model`` (None when its loop is unstable, the reason in
            ``model_unstable``); ``difference``, measured minus model;
            ``drive`` (sampled or continuous), ``nyquist_hz``, ``band_hz`` (the lines the
            margins were searched on) and ``bandwidth_reference_hz`` (the line whose
            closed-loop gain is the bandwidth's reference).
        """
        poles = self.measured_unstable_poles
        measured = dict(self.measured_loop.to_dict(), unstable_poles=poles,
                        stable=None if poles is None else poles == 0)
        model = _analysis_dict(self.model_loop)
        if model is not None:
            model.update(stable=True)
        difference = None
        if model is not None:
            difference = {}
            for key in ("gain_margin_db", "phase_margin_deg", "ms", "bandwidth_hz",
                        "crossover_hz", "phase_crossover_hz"):
                a, b = measured[key], model[key]
                difference[key] = None if a is None or b is None else a - b
        inside = np.isfinite(self.l_measured)
        return {**measured, "measured": measured, "model": model,
                "model_unstable": self.model_unstable, "difference": difference,
                "drive": self.drive_kind,
                "nyquist_hz": (self.nyquist * HZ_PER_RAD_S if math.isfinite(self.nyquist)
                               else None),
                "band_hz": [float(self.omega[inside][0] * HZ_PER_RAD_S),
                            float(self.omega[inside][-1] * HZ_PER_RAD_S)],
                "bandwidth_reference_hz": float(self.omega[inside][0] * HZ_PER_RAD_S)}

    def to_dict(self) -> dict:
        """Return the comparison JSON-ready (no frequency responses).

        Returns
        -------
        dict
            ``quantity``, ``contact``, ``contact_note``, ``frf_error`` (relative RMS over
            ``frf_band_hz``), ``velocity_loop`` (:meth:`velocity_loop`), ``notes``,
            ``warnings``.
        """
        return {"quantity": "speed_per_torque", "contact": self.contact.kind,
                "contact_note": self.contact.note, "frf_error": self.frf_error,
                "frf_band_hz": [self.band[0] * HZ_PER_RAD_S, self.band[1] * HZ_PER_RAD_S],
                "velocity_loop": self.velocity_loop(), "notes": list(self.notes),
                "warnings": list(self.warnings)}


def compare_speed_plant(measured, structure: ModalModel, drive: Drive, contact: Contact,
                        pads=(), band=None) -> SpeedPlantComparison:
    """Compare a measured speed plant with the model's; close the velocity loop on both.

    Parameters
    ----------
    measured : MeasuredFrf
        The measured speed plant (quantity ``speed_per_torque``), lines > 0 Hz.
    structure : ModalModel
        The axis' reduced structure.
    drive : Drive
        The axis' drive: its controllers close the loop on the measured plant.
    contact : Contact
        The guide-way contact of the model (the axis' presliding ``stiction`` contact).
    pads : sequence of str
        The pad DOFs.
    band : (float, float), optional
        The band [rad/s] of the FRF error (default: the whole measurement).

    Returns
    -------
    SpeedPlantComparison

    Raises
    ------
    ValueError
        A measurement that is not a speed per torque, or that does not fall as an inertia at
        the top of its band.
    """
    from ..closed_loop import closed_loop

    if measured.quantity != "speed_per_torque":
        raise ValueError(f"{measured.name} is a {measured.quantity}; the speed plant is motor "
                         "speed over motor torque (speed_per_torque, rad/s/N m)")
    keep = measured.omega > 0
    omega, values = measured.omega[keep], measured.values[keep]
    notes, warnings = [], []
    if not keep.all():
        notes.append(f"{measured.name}: the 0 Hz line left out (a loop has no margin there)")
    response = SpeedPlantResponse(omega, values)
    model = model_speed_plant(structure, drive, omega, contact, pads)
    lo, hi = (omega[0], omega[-1]) if band is None else band
    in_band = (omega >= lo * (1 - 1e-9)) & (omega <= hi * (1 + 1e-9))
    if not in_band.any():
        raise ValueError(f"the band {lo * HZ_PER_RAD_S:g}-{hi * HZ_PER_RAD_S:g} Hz holds no "
                         f"line of {measured.name}")
    error = _error(model[in_band], values[in_band])
    sampled = not drive.digital.is_continuous
    l_measured = velocity_loop_response(drive, response, omega)
    loop_model = closed_loop(structure, drive, contact, pads)
    l_model = loop_model.loop_response("velocity", omega)
    inside = np.isfinite(l_measured)
    nyquist = loop_model.nyquist("velocity") if sampled else math.inf
    w = omega[inside]
    if w.size < 2:
        raise ValueError(f"{measured.name} has fewer than two lines below the velocity "
                         f"controller's Nyquist frequency {nyquist * HZ_PER_RAD_S:g} Hz")
    measured_loop = analyse_response(w, l_measured[inside], l_measured[inside][0])
    top = w
    l_top = l_measured[inside]
    if sampled and w[-1] < nyquist * (1.0 - 2e-7):  # close the contour at the Nyquist line
        edge = np.array([nyquist * (1.0 - 1e-7)])
        top = np.append(w, edge)
        l_top = np.append(l_top, velocity_loop_response(drive, response, edge))
    poles = encircled_poles(l_top)
    if poles is None:
        warnings.append(f"|L| is {abs(l_top[-1]):.3g} at the last line "
                        f"({top[-1] * HZ_PER_RAD_S:g} Hz): the measurement ends before the "
                        "loop has fallen, its closed-loop stability is not judged")
    elif poles:
        warnings.append(f"the velocity loop closed on the measured plant is unstable "
                        f"({poles} unstable closed-loop poles by the Nyquist criterion): its "
                        "margins describe no working loop; lower the velocity gain or add "
                        "filters (servotune tune)")
    model_loop, unstable = None, None
    try:
        if sampled:
            loop_model.velocity_loop_axis().require_stable("closed velocity loop")
        else:
            loop_model.analyse_loop("velocity", w[:2])  # checks the closed loop's poles
        model_loop = analyse_response(w, l_model[inside], l_model[inside][0])
    except UnstableLoopError as exc:
        unstable = str(exc)
        warnings.append(f"the model's velocity loop is unstable ({exc}); the margins on the "
                        "measured plant are those of the same loop")
    notes.append(f"the model's guide ways: {contact.note} (standstill, small excitation)")
    notes.append("the loop on the measurement is judged stable or not by the Nyquist criterion "
                 "from its first line to the top, assuming the measured mechanism and the "
                 "drive's current loop stable on their own and 1 + L not turning below the "
                 "first line")
    notes.append(f"the bandwidth is taken relative to the closed-loop gain at the first line, "
                 f"{w[0] * HZ_PER_RAD_S:g} Hz (for measured and model alike)")
    if sampled:
        notes.append(f"the loop is the sampled-data velocity loop of the drive (current "
                     f"controller every {drive.digital.current_period * 1e6:g} us, velocity "
                     f"every {drive.digital.velocity_period * 1e6:g} us); above the last line "
                     f"({omega[-1] * HZ_PER_RAD_S:g} Hz) the aliases see the measured plant as "
                     f"the inertia line 1/(j w J), J = {response.inertia:.4g} kg m^2")
        if omega[-1] < 0.999 * nyquist:
            warnings.append(f"the measurement ends at {omega[-1] * HZ_PER_RAD_S:g} Hz, below "
                            f"the velocity controller's Nyquist frequency "
                            f"{nyquist * HZ_PER_RAD_S:g} Hz: a phase crossover above it is not "
                            "seen (the gain margin may be missing or too large)")
    return SpeedPlantComparison(omega, values, model, (float(lo), float(hi)), error,
                                l_measured, l_model, measured_loop, poles, model_loop,
                                unstable,
                                "sampled" if sampled else "continuous", nyquist, contact,
                                tuple(notes), tuple(warnings))
