"""Operating regimes of a feed axis and the linear guide-way model of each.

Guide-way friction makes the axis a different linear system in each way it works (the paper's
Table 3 and its remarks A-C):

* **standing** (cutting with the axis at rest, or reversing): the pads stick. The friction is
  the LuGre presliding contact, a spring sigma0 with a damper sigma1 (plus the viscous part C),
  and at the vibration amplitude A the cutting forces give, the LuGre describing function
  (Keq, Ceq at A; Eq 8-10 of the paper, computed for the whole LuGre element);
* **feeding** at a speed v (cutting while the axis moves): the pads slide. The friction is LuGre
  linearised about steady sliding at v: the slope of the Stribeck curve plus the viscous part,
  through the bristle lag. Below the Stribeck speed the slope is negative and may destabilise
  the axis (stick-slip);
* **viscous**: the paper's viscous-only model of sec 4.1 (the pads as a damper C alone), used for
  an axis without a drive (the two-mass analysis).

In every model the design's guide-way damping C is the *total viscous part* of the friction: it
takes the place of the LuGre sigma2 (a design with C above the identified sigma2 adds viscous
damping, for example hydrostatic guides). A model's contact impedance at the pads is therefore
``Z(jw) = Z_0(jw) + j w C`` with ``Z_0`` the friction model without its viscous part.

Friction is never known exactly: :func:`friction_samples` gives the corners of a spread of the
identified parameters (by default the spread the paper measured over six tests), each a further
model of every regime; :class:`FrictionSpread` is the box of such a spread, whose every corner
the nonlinear verdict checks (:mod:`servotune.verdict`).

References
----------
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 4.2, 5.3 (Table 3, remarks A-C).
C. Canudas de Wit et al., "A new model for control of systems with friction", IEEE Trans.
Automatic Control 40(3) (1995) 419-425 (LuGre; linearisations).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import control
import numpy as np

from .friction.equivalent import describing_function
from .friction.lugre import LuGreParameters, sliding_linearisation, stribeck_curve
from .plant import Contact
from .units import HZ_PER_RAD_S
from .validation import positive

__all__ = [
    "REGIME_KINDS",
    "SPREAD_PARAMETERS",
    "FrictionSpread",
    "Operation",
    "RegimeModel",
    "friction_samples",
    "regime_models",
    "stribeck_slope",
]

REGIME_KINDS = ("presliding", "describing", "sliding", "viscous")
#: The LuGre parameters a friction spread may vary, with their units.
SPREAD_PARAMETERS = MappingProxyType({"fc": "N", "fs": "N", "sigma0": "N/m", "sigma1": "N s/m"})


@dataclass(frozen=True)
class Operation:
    """How the axis works: its cutting feeds, its rapid traverse, its acceleration (SI).

    Parameters
    ----------
    feed_speeds : tuple of float
        Slide speeds while cutting [m/s] (each a *feeding* regime).
    rapid_speed : float, optional
        Rapid-traverse speed [m/s] (for the peak-thrust budget).
    acceleration : float
        Acceleration of rapid moves [m/s^2].
    process_force_pp : float, optional
        Peak-to-peak cutting force at the work piece in the flexible direction [N], the force
        the standing regime is judged at (default: from ``[cutting]`` at the required depth).
    feed_force : float
        Mean cutting force against the feed [N] (a continuous load on the drive).
    standing : bool
        Whether the axis also cuts standing still (the standing regime).
    defaults : tuple of str
        Which values were defaulted and from what (shown to the user).

    Raises
    ------
    ValueError
        If a speed, the acceleration or the process force is not finite and > 0, the feed
        force is negative or not finite, a feed speed exceeds the rapid speed, or the axis
        neither stands nor feeds (``standing=False`` and no feed speeds).

    Notes
    -----
    The feed speeds are stored sorted, without repeats.
    """

    feed_speeds: tuple[float, ...] = ()
    rapid_speed: float | None = None
    acceleration: float = 1.0
    process_force_pp: float | None = None
    feed_force: float = 0.0
    standing: bool = True
    defaults: tuple[str, ...] = field(default=(), compare=False)

    def __post_init__(self) -> None:
        speeds = tuple(positive("Operation", "feed_speeds", v, "m/s") for v in self.feed_speeds)
        object.__setattr__(self, "feed_speeds", tuple(sorted(set(speeds))))
        if self.rapid_speed is not None:
            object.__setattr__(self, "rapid_speed",
                               positive("Operation", "rapid_speed", self.rapid_speed, "m/s"))
            if self.feed_speeds and max(self.feed_speeds) > self.rapid_speed:
                raise ValueError(f"Operation.feed_speeds ({max(self.feed_speeds):g} m/s) exceed "
                                 f"the rapid speed {self.rapid_speed:g} m/s")
        object.__setattr__(self, "acceleration",
                           positive("Operation", "acceleration", self.acceleration, "m/s^2"))
        if self.process_force_pp is not None:
            object.__setattr__(self, "process_force_pp", positive(
                "Operation", "process_force_pp", self.process_force_pp, "N"))
        object.__setattr__(self, "feed_force", positive("Operation", "feed_force", self.feed_force,
                                                        "N", allow_zero=True))
        if not self.standing and not self.feed_speeds:
            raise ValueError("Operation: no regime left (standing = false and no feed_speeds)")

    def to_dict(self) -> dict:
        """Return the operation as JSON-ready data.

        Returns
        -------
        dict
            The fields by name (SI), tuples as lists.
        """
        return {"feed_speeds": list(self.feed_speeds), "rapid_speed": self.rapid_speed,
                "acceleration": self.acceleration, "process_force_pp": self.process_force_pp,
                "feed_force": self.feed_force, "standing": self.standing,
                "defaults": list(self.defaults)}


def stribeck_slope(params: LuGreParameters, speed: float) -> float:
    """Return dF/dv of the steady sliding friction, sigma2 included.

    ``dF_ss/dv = g'(v) sgn(v) + sigma2`` with ``g(v) = Fc + (Fs - Fc) exp(-|v/vs|^delta)``
    (:func:`servotune.friction.lugre.steady_state_slope`): negative below the Stribeck speed
    where the friction falls faster than sigma2 rises.

    Parameters
    ----------
    params : LuGreParameters
        The friction (axis totals).
    speed : float
        Sliding speed [m/s]; at 0 the slope of g is taken as 0.

    Returns
    -------
    float
        The slope [N s/m].
    """
    from .friction.lugre import steady_state_slope

    return float(steady_state_slope(params, speed))


@dataclass(frozen=True)
class RegimeModel:
    """One linear guide-way model of one operating regime.

    Parameters
    ----------
    regime : str
        The operating regime it belongs to (``"standing"``, ``"feeding 30 mm/s"``,
        ``"viscous"``); a regime's claim is the worst of its models.
    kind : {"presliding", "describing", "sliding", "viscous"}
        The guide-way model: LuGre presliding (spring sigma0, damper sigma1), the LuGre
        describing function at ``amplitude`` and ``frequency``, LuGre linearised about steady
        sliding at ``speed``, or the viscous damper C alone.
    friction : LuGreParameters, optional
        The friction (axis totals) of the model; its sigma2 is replaced by the design's C.
    speed : float
        Sliding speed [m/s] (feeding models).
    amplitude, frequency : float, optional
        Pad vibration amplitude [m] and angular frequency [rad/s] of a describing-function
        model.
    sample : str
        The friction sample (``"nominal"`` or a corner of the spread).
    cutting : bool
        Whether the axis cuts in this regime (its compliance is judged); False for a regime
        that only moves the axis (rapid traverse), where only the loops are judged.

    Raises
    ------
    ValueError
        If ``kind`` is unknown, a non-viscous model has no LuGre friction, a sliding model no
        speed > 0, or a describing-function model no finite amplitude and frequency > 0.
    """

    regime: str
    kind: str
    friction: LuGreParameters | None = None
    speed: float = 0.0
    amplitude: float | None = None
    frequency: float | None = None
    sample: str = "nominal"
    cutting: bool = True
    _keq_ceq: tuple = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.kind not in REGIME_KINDS:
            raise ValueError(f"RegimeModel.kind must be one of {REGIME_KINDS}, got {self.kind!r}")
        if self.kind != "viscous" and not isinstance(self.friction, LuGreParameters):
            raise ValueError(f"a {self.kind} model needs the LuGre friction of the axis")
        if self.kind == "sliding":
            positive("RegimeModel", "speed", self.speed, "m/s", "a sliding model moves")
        if self.kind == "describing":
            for name, unit in (("amplitude", "m"), ("frequency", "rad/s")):
                positive("RegimeModel", name, getattr(self, name), unit,
                         "a describing-function model needs it")
            base = dataclasses.replace(self.friction, sigma2=0.0)
            ceq, keq = describing_function(base, self.amplitude, self.frequency)
            object.__setattr__(self, "_keq_ceq", (float(keq), float(ceq)))

    @property
    def name(self) -> str:
        """A readable name: regime, model and (when not nominal) friction sample."""
        what = {"presliding": "presliding", "describing": "describing function",
                "sliding": "sliding", "viscous": "viscous"}[self.kind]
        text = self.regime if self.regime == what else f"{self.regime}: {what}"
        if self.kind == "describing":
            text += f" at {self.amplitude:.3g} m"
        return text + ("" if self.sample == "nominal" else f" ({self.sample})")

    def impedance(self, omega) -> np.ndarray:
        """Return the contact impedance without the viscous part, Z_0(jw) (axis total).

        The pad force per pad displacement: 0 for the viscous model; ``sigma0 + jw sigma1``
        presliding; ``Keq + jw Ceq`` for the describing function (computed with sigma2 = 0);
        ``jw G(jw)`` sliding, with G the LuGre sliding linearisation (sigma2 = 0) from velocity
        to force (:func:`servotune.friction.lugre.sliding_linearisation`).

        Parameters
        ----------
        omega : array_like
            Angular frequencies [rad/s].

        Returns
        -------
        numpy.ndarray
            Complex impedance [N/m], the shape of ``omega``.
        """
        s = 1j * np.asarray(omega, dtype=float)
        p = self.friction
        if self.kind == "viscous":
            return np.zeros_like(s)
        if self.kind == "presliding":
            return p.sigma0 + s * p.sigma1
        if self.kind == "describing":
            keq, ceq = self._keq_ceq
            return keq + s * ceq
        sys = sliding_linearisation(dataclasses.replace(p, sigma2=0.0), self.speed)
        a, b, c, d = (float(np.asarray(m).ravel()[0]) for m in (sys.A, sys.B, sys.C, sys.D))
        return s * (c * b / (s - a) + d)

    def contact(self, c: float) -> Contact:
        """Return the python-control contact of the model with total viscous damping ``c``.

        Parameters
        ----------
        c : float
            Total viscous guide-way damping C [N s/m], in place of the LuGre sigma2.

        Returns
        -------
        Contact
            ``Contact.viscous(c)``; presliding ``Contact.stiction(sigma0, sigma1, c)``;
            describing function a sliding contact ``F = Keq x + (Ceq + c) v``; sliding the
            LuGre sliding linearisation with sigma2 = c at the model's speed.
        """
        c = float(c)
        if self.kind == "viscous":
            return Contact.viscous(c)
        p = self.friction
        if self.kind == "presliding":
            return Contact.stiction(p.sigma0, p.sigma1, c)
        if self.kind == "describing":
            keq, ceq = self._keq_ceq
            element = control.ss([[0.0]], [[1.0]], [[keq]], [[ceq + c]])
            return Contact("sliding", system=element,
                           note=f"describing function at A = {self.amplitude:.3g} m, "
                                f"{self.frequency * HZ_PER_RAD_S:.1f} Hz: Keq = {keq:.3g} N/m, "
                                f"Ceq = {ceq + c:.3g} N s/m")
        return Contact.sliding(sliding_linearisation(dataclasses.replace(p, sigma2=c),
                                                     self.speed), self.speed)

    def with_amplitude(self, amplitude: float, frequency: float) -> RegimeModel:
        """Return the model at another amplitude and frequency.

        For a describing-function model, Keq and Ceq are computed anew there.

        Parameters
        ----------
        amplitude : float
            Pad vibration amplitude [m].
        frequency : float
            Angular frequency [rad/s].

        Returns
        -------
        RegimeModel
            A copy with the new amplitude and frequency.

        Raises
        ------
        ValueError
            If the model is a describing-function one and a value is not finite and > 0.
        """
        return dataclasses.replace(self, amplitude=float(amplitude), frequency=float(frequency))

    def slope(self) -> float | None:
        """Return the sliding model's steady friction slope dF/dv with sigma2 = 0.

        Returns
        -------
        float or None
            ``g'(v) sgn(v)`` [N s/m] at the model's speed (see :func:`stribeck_slope`); None
            when the model is not a sliding one.
        """
        if self.kind != "sliding":
            return None
        return stribeck_slope(dataclasses.replace(self.friction, sigma2=0.0), self.speed)

    def to_dict(self) -> dict:
        """Return the model as JSON-ready data.

        Returns
        -------
        dict
            Regime, kind (``model``), name, sample, speed [m/s] and cutting; a
            describing-function model adds amplitude [m], frequency [Hz], Keq [N/m] and Ceq
            without C [N s/m]; a sliding one the friction slope without C [N s/m] and the
            friction level g(v) [N].
        """
        out = {"regime": self.regime, "model": self.kind, "name": self.name,
               "sample": self.sample, "speed_m_per_s": self.speed, "cutting": self.cutting}
        if self.kind == "describing":
            keq, ceq = self._keq_ceq
            out.update(amplitude_m=self.amplitude, frequency_hz=self.frequency * HZ_PER_RAD_S,
                       keq=keq, ceq_without_c=ceq)
        if self.kind == "sliding":
            out["friction_slope_without_c"] = self.slope()
            out["friction_level_n"] = float(stribeck_curve(self.friction, self.speed))
        return out


def friction_samples(params: LuGreParameters, spread: dict | None,
                     extra=()) -> list[tuple[str, LuGreParameters]]:
    """Return the nominal friction, the corners of a spread and further given samples.

    Each parameter of the spread gives a low and a high sample, the others nominal
    (one-at-a-time corners: the extremes of a monotone response; the corners of all
    combinations would grow as 2^n). A corner that moves Fc above Fs raises Fs with it, and
    one that moves Fs below Fc lowers Fc with it.

    Parameters
    ----------
    params : LuGreParameters
        The nominal friction.
    spread : dict or None
        Parameter name -> relative spread: ``fc``, ``fs``, ``sigma1``: +- fraction in (0, 1)
        (0.3 = 30 %); ``sigma0``: a factor > 1 (3.0 = x/÷ 3).
    extra : sequence of (str, dict)
        ``(label, {parameter: value})`` samples, e.g. a study's worst ones
        (:func:`servotune.study.spread.spread_from_study`): the named parameters replace the
        nominal ones.

    Returns
    -------
    list of (str, LuGreParameters)
        ``("nominal", params)``, the extra samples, then the low and high corner of each
        spread parameter, in the order given.

    Raises
    ------
    ValueError
        If ``spread`` names another parameter, or a spread lies outside its range.
    """
    out = [("nominal", params)]
    for label, values in extra:
        out.append((str(label), dataclasses.replace(params, **dict(values))))
    for name, value in (spread or {}).items():
        if name not in ("fc", "fs", "sigma0", "sigma1"):
            raise ValueError(f"friction spread of {name!r}: choose among fc, fs, sigma0, sigma1")
        value = float(value)
        base = getattr(params, name)
        if name == "sigma0":
            if not (math.isfinite(value) and value > 1.0):
                raise ValueError(f"friction spread of sigma0 is a factor > 1, got {value!r}")
            pairs = ((f"sigma0 / {value:g}", base / value), (f"sigma0 x {value:g}", base * value))
        else:
            if not (math.isfinite(value) and 0.0 < value < 1.0):
                raise ValueError(f"friction spread of {name} is a fraction in (0, 1), got "
                                 f"{value!r}")
            pairs = ((f"{name} -{value:.0%}", base * (1 - value)),
                     (f"{name} +{value:.0%}", base * (1 + value)))
        for label, new in pairs:
            changes = {name: new}
            if name == "fc" and new > params.fs:
                changes["fs"] = new
            if name == "fs" and new < params.fc:
                changes["fc"] = new
            out.append((label, dataclasses.replace(params, **changes)))
    return out


def regime_models(friction: LuGreParameters | None, operation: Operation | None,
                  amplitude: float | None = None, frequency: float | None = None,
                  spread: dict | None = None, viscous_only: bool = False,
                  extra_samples=()) -> tuple[RegimeModel, ...]:
    """Return the linear models of an axis' regimes.

    For each friction sample (:func:`friction_samples`): when the axis stands, the presliding
    model and, with ``amplitude`` and ``frequency``, the describing-function model of the
    standing regime; a sliding model per feed speed.

    Parameters
    ----------
    friction : LuGreParameters, optional
        The axis' friction (None: the viscous model alone).
    operation : Operation, optional
        How the axis works (None: the viscous model alone).
    amplitude, frequency : float, optional
        Pad vibration amplitude [m] and angular frequency [rad/s] at the process force; when
        given, the standing regime gets the describing-function model there.
    spread : dict, optional
        Friction spread (see :func:`friction_samples`): further models of every regime.
    viscous_only : bool
        Return the viscous model alone.
    extra_samples : sequence of (str, dict), optional
        Further friction samples (see :func:`friction_samples`).

    Returns
    -------
    tuple of RegimeModel
        The models, sample by sample (nominal first); ``(RegimeModel("viscous",
        "viscous"),)`` for the viscous model alone.

    Raises
    ------
    ValueError
        As :func:`friction_samples` and :class:`RegimeModel`.
    """
    if viscous_only or friction is None or operation is None:
        return (RegimeModel("viscous", "viscous"),)
    models = []
    for label, params in friction_samples(friction, spread, extra_samples):
        if operation.standing:
            models.append(RegimeModel("standing", "presliding", params, sample=label))
            if amplitude is not None and frequency is not None:
                models.append(RegimeModel("standing", "describing", params, amplitude=amplitude,
                                          frequency=frequency, sample=label))
        for v in operation.feed_speeds:
            models.append(RegimeModel(f"feeding {v * 1e3:.3g} mm/s", "sliding", params, speed=v,
                                      sample=label))
    return tuple(models)
