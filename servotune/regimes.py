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

import numpy as np

from .closed_loop import axis_compliance
from .friction.law import FrictionLaw
from .friction.laws.lugre import LuGreFriction
from .friction.lugre import LuGreParameters
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
    "friction_spread",
    "as_law",
    "regime_models",
    "stribeck_slope",
    "axis_regimes",
    "process_amplitude",
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


def as_law(friction) -> FrictionLaw | None:
    """Return the friction as a law: a :class:`~servotune.friction.law.FrictionLaw` as it is,
    LuGre parameters as :class:`~servotune.friction.laws.lugre.LuGreFriction`, None as None.

    Parameters
    ----------
    friction : FrictionLaw, LuGreParameters or None
        The friction (axis totals).

    Returns
    -------
    FrictionLaw or None

    Raises
    ------
    ValueError
        For anything else (the message names what was given).
    """
    if friction is None or isinstance(friction, FrictionLaw):
        return friction
    if isinstance(friction, LuGreParameters):
        return LuGreFriction(friction)
    raise ValueError(f"the friction must be a FrictionLaw or LuGreParameters, got {friction!r}")


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
        The guide-way model: the law's presliding contact (for LuGre the spring sigma0 and the
        damper sigma1), its describing function at ``amplitude`` and ``frequency``, the law
        linearised about steady sliding at ``speed``, or the viscous damper C alone.
    friction : FrictionLaw or LuGreParameters, optional
        The friction law (axis totals) of the model; its viscous part is replaced by the
        design's C (:meth:`~servotune.friction.law.FrictionLaw.with_viscous`). LuGre
        parameters are taken as :class:`~servotune.friction.laws.lugre.LuGreFriction`.
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
        If ``kind`` is unknown, a non-viscous model has no friction law, a sliding model no
        speed > 0, or a describing-function model no finite amplitude and frequency > 0.
    """

    regime: str
    kind: str
    friction: FrictionLaw | None = None
    speed: float = 0.0
    amplitude: float | None = None
    frequency: float | None = None
    sample: str = "nominal"
    cutting: bool = True
    _keq_ceq: tuple = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.kind not in REGIME_KINDS:
            raise ValueError(f"RegimeModel.kind must be one of {REGIME_KINDS}, got {self.kind!r}")
        if isinstance(self.friction, LuGreParameters):
            object.__setattr__(self, "friction", LuGreFriction(self.friction))
        if self.kind != "viscous" and not isinstance(self.friction, FrictionLaw):
            raise ValueError(f"a {self.kind} model needs the friction law of the axis, got "
                             f"{self.friction!r}")
        if self.kind == "sliding":
            positive("RegimeModel", "speed", self.speed, "m/s", "a sliding model moves")
        if self.kind == "describing":
            for name, unit in (("amplitude", "m"), ("frequency", "rad/s")):
                positive("RegimeModel", name, getattr(self, name), unit,
                         "a describing-function model needs it")
            base = self.friction.with_viscous(0.0)
            ceq, keq = base.describing_function(self.amplitude, self.frequency)
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

        The pad force per pad displacement: 0 for the viscous model; ``k + jw d`` presliding
        (the law's presliding spring and damper without its viscous part; LuGre: sigma0,
        sigma1); ``Keq + jw Ceq`` for the describing function (computed without the viscous
        part); ``jw G(jw)`` sliding, with G the law's sliding linearisation without its viscous
        part, from velocity to force
        (:meth:`~servotune.friction.law.FrictionLaw.sliding_system`).

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
        if self.kind == "viscous":
            return np.zeros_like(s)
        base = self.friction.with_viscous(0.0)
        if self.kind == "presliding":
            k, d = base.presliding()
            return k + s * d
        if self.kind == "describing":
            keq, ceq = self._keq_ceq
            return keq + s * ceq
        sys = base.sliding_system(self.speed)
        a, b = np.atleast_2d(np.asarray(sys.A, float)), np.asarray(sys.B, float)
        c, d = np.asarray(sys.C, float), float(np.asarray(sys.D).ravel()[0])
        if sys.nstates == 0:
            return s * d
        if sys.nstates == 1:
            a, b, c = float(a[0, 0]), float(b.ravel()[0]), float(c.ravel()[0])
            return s * (c * b / (s - a) + d)
        lam, vec = np.linalg.eig(a)   # G(s) = (C V) diag(1/(s - lam)) (V^-1 B) + D
        left = (c @ vec).ravel()
        right = np.linalg.solve(vec, b).ravel()
        g = (left * right / (s[..., None] - lam)).sum(axis=-1) + d
        return s * g

    def contact(self, c: float) -> Contact:
        """Return the python-control contact of the model with total viscous damping ``c``.

        Parameters
        ----------
        c : float
            Total viscous guide-way damping C [N s/m], in place of the law's viscous part.

        Returns
        -------
        Contact
            ``Contact.viscous(c)``; presliding ``Contact.stiction(k, d, c)`` with the law's
            presliding spring and damper without its viscous part (k = 0 for a law without a
            presliding spring: a damper alone); describing function a sliding contact
            ``F = Keq x + (Ceq + c) v``; sliding the law's sliding linearisation with the
            viscous part c at the model's speed.
        """
        c = float(c)
        if self.kind == "viscous":
            return Contact.viscous(c)
        if self.kind == "presliding":
            k, d = self.friction.with_viscous(0.0).presliding()
            return Contact.stiction(k, d, c)
        if self.kind == "describing":
            # a spring and a damper on the pads' own motion: no state of its own (an
            # integrator of the pad velocity would repeat the structure's displacement, a
            # neutral mode whose rounding can read as growth)
            keq, ceq = self._keq_ceq
            return Contact("equivalent", stiffness=keq, damping=ceq + c,
                           note=f"describing function at A = {self.amplitude:.3g} m, "
                                f"{self.frequency * HZ_PER_RAD_S:.1f} Hz: Keq = {keq:.3g} N/m, "
                                f"Ceq = {ceq + c:.3g} N s/m")
        return Contact.sliding(self.friction.with_viscous(c).sliding_system(self.speed),
                               self.speed)

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
        """Return the sliding model's steady friction slope dF/dv without the viscous part.

        Returns
        -------
        float or None
            For LuGre ``g'(v) sgn(v)`` [N s/m] at the model's speed (see
            :meth:`~servotune.friction.law.FrictionLaw.steady_slope`); None when the model is
            not a sliding one.
        """
        if self.kind != "sliding":
            return None
        return self.friction.with_viscous(0.0).steady_slope(self.speed)

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
               "sample": self.sample, "speed_m_per_s": self.speed, "cutting": self.cutting,
               "friction_law": None if self.friction is None else self.friction.name}
        if self.kind == "describing":
            keq, ceq = self._keq_ceq
            out.update(amplitude_m=self.amplitude, frequency_hz=self.frequency * HZ_PER_RAD_S,
                       keq=keq, ceq_without_c=ceq)
        if self.kind == "sliding":
            out["friction_slope_without_c"] = self.slope()
            out["friction_level_n"] = abs(self.friction.with_viscous(0.0).steady_force(
                self.speed))
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
    friction : FrictionLaw or LuGreParameters, optional
        The axis' friction law (None: the viscous model alone). A spread and extra samples
        vary LuGre parameters: they need a LuGre law.
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
    law = as_law(friction)
    lugre = getattr(law, "lugre_parameters", None)
    if lugre is not None:
        samples = [(label, LuGreFriction(p))
                   for label, p in friction_samples(lugre, spread, extra_samples)]
    elif spread or extra_samples:
        raise ValueError(f"a friction spread and friction samples vary LuGre parameters; the "
                         f"axis' friction law is {law.name!r} (remove [tuning] friction_spread "
                         f"and --spread-from, or describe the guide ways with [friction.lugre])")
    else:
        samples = [("nominal", law)]
    models = []
    for label, params in samples:
        if operation.standing:
            models.append(RegimeModel("standing", "presliding", params, sample=label))
            if amplitude is not None and frequency is not None:
                models.append(RegimeModel("standing", "describing", params, amplitude=amplitude,
                                          frequency=frequency, sample=label))
        for v in operation.feed_speeds:
            models.append(RegimeModel(f"feeding {v * 1e3:.3g} mm/s", "sliding", params, speed=v,
                                      sample=label))
    return tuple(models)


def _short(value: float) -> str:
    """A number in 3 significant digits without a ``+`` or leading zeros in its exponent."""
    text = f"{value:.3g}"
    if "e" in text:
        mantissa, exponent = text.split("e")
        text = f"{mantissa}e{int(exponent)}"
    return text


@dataclass(frozen=True)
class FrictionSpread:
    """A box of LuGre parameters around the nominal friction: the friction a design must hold.

    Each spread parameter lies between a low and a high value, the others stay nominal; the
    corners of the box are every combination of the lows and highs (2^n for n parameters).
    A spread is given in one of three forms per parameter: ``"fraction"`` (+- a fraction of
    the nominal value, as ``[tuning] friction_spread`` gives fc, fs, sigma1), ``"factor"``
    (x/÷ a factor, as it gives sigma0) or ``"absolute"`` (+- a value in SI units, as an
    identification reports its variation: ``[friction] variation``).

    Parameters
    ----------
    nominal : LuGreParameters
        The nominal friction (axis totals).
    deviations : Mapping
        Parameter name (:data:`SPREAD_PARAMETERS`) -> ``(form, value)``: ``("fraction", f)``
        with f in (0, 1), ``("factor", k)`` with k > 1, ``("absolute", d)`` with
        0 < d < the nominal value [SI].
    source : str
        Where the spread comes from (shown with the results), e.g. ``"[friction] variation"``.

    Raises
    ------
    ValueError
        An unknown parameter or form, a value outside its range, or no parameter.

    Examples
    --------
    The paper's measured variation of its identified set spans a box of 8 corners:

    >>> from servotune.friction.lugre import BIANCHI2014
    >>> box = FrictionSpread.absolute(BIANCHI2014, {"fs": 258.0, "sigma0": 1.17e9})
    >>> box.describe(), len(box.corners())
    ('fs +-258 N, sigma0 +-1.17e9 N/m', 4)
    >>> box.corners()[0][0]
    'fs -258 N, sigma0 -1.17e9 N/m'
    """

    nominal: LuGreParameters
    deviations: Mapping
    source: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.nominal, LuGreParameters):
            raise ValueError(f"FrictionSpread.nominal must be LuGreParameters, got "
                             f"{self.nominal!r}")
        out = {}
        for name, pair in dict(self.deviations).items():
            if name not in SPREAD_PARAMETERS:
                raise ValueError(f"friction spread of {name!r}: choose among "
                                 f"{', '.join(SPREAD_PARAMETERS)}")
            form, value = pair
            value = float(value)
            base = float(getattr(self.nominal, name))
            if form == "fraction":
                ok, why = 0.0 < value < 1.0, "a fraction in (0, 1)"
            elif form == "factor":
                ok, why = value > 1.0 and math.isfinite(value), "a factor > 1"
            elif form == "absolute":
                ok = 0.0 < value < base
                why = (f"a value > 0 and below the nominal {_short(base)} "
                       f"{SPREAD_PARAMETERS[name]} (the low corner must stay positive)")
            else:
                raise ValueError(f"friction spread of {name}: form {form!r} is not one of "
                                 "fraction, factor, absolute")
            if not ok:
                raise ValueError(f"friction spread of {name} ({form}) is {why}, got {value!r}")
            out[name] = (form, value)
        if not out:
            raise ValueError("a friction spread needs at least one parameter")
        object.__setattr__(self, "deviations", MappingProxyType(out))

    @classmethod
    def relative(cls, nominal: LuGreParameters, spread: Mapping,
                 source: str = "[tuning] friction_spread") -> FrictionSpread:
        """Return the spread of ``[tuning] friction_spread``: fractions, a factor for sigma0.

        Parameters
        ----------
        nominal : LuGreParameters
            The nominal friction.
        spread : Mapping
            ``fc``, ``fs``, ``sigma1``: +- fraction in (0, 1); ``sigma0``: a factor > 1 (as
            :func:`friction_samples`).
        source : str
            Where it comes from.

        Returns
        -------
        FrictionSpread
            The box.
        """
        return cls(nominal, {k: ("factor" if k == "sigma0" else "fraction", float(v))
                             for k, v in dict(spread).items()}, source)

    @classmethod
    def absolute(cls, nominal: LuGreParameters, variation: Mapping,
                 source: str = "[friction] variation") -> FrictionSpread:
        """Return the spread of an identified variation: +- values in SI units.

        Parameters
        ----------
        nominal : LuGreParameters
            The nominal (identified) friction.
        variation : Mapping
            Parameter name -> +- value [N, N/m, N s/m], e.g.
            :data:`servotune.friction.lugre.BIANCHI2014_SPREAD`.
        source : str
            Where it comes from.

        Returns
        -------
        FrictionSpread
            The box.
        """
        return cls(nominal, {k: ("absolute", float(v)) for k, v in dict(variation).items()},
                   source)

    def bounds(self, name: str) -> tuple[float, float]:
        """Return the low and high value [SI] of a spread parameter.

        Parameters
        ----------
        name : str
            A parameter of the spread.

        Returns
        -------
        (float, float)
            ``(low, high)``.
        """
        form, value = self.deviations[name]
        base = float(getattr(self.nominal, name))
        if form == "fraction":
            return base * (1.0 - value), base * (1.0 + value)
        if form == "factor":
            return base / value, base * value
        return base - value, base + value

    def _labels(self, name: str) -> tuple[str, str, str]:
        """(low label, high label, range text) of a parameter."""
        form, value = self.deviations[name]
        unit = SPREAD_PARAMETERS[name]
        if form == "fraction":
            return (f"{name} -{value:.0%}", f"{name} +{value:.0%}", f"{name} +-{value:.0%}")
        if form == "factor":
            return (f"{name} / {value:g}", f"{name} x {value:g}", f"{name} / {value:g} to "
                                                                  f"x {value:g}")
        return (f"{name} -{_short(value)} {unit}", f"{name} +{_short(value)} {unit}",
                f"{name} +-{_short(value)} {unit}")

    def describe(self) -> str:
        """Return the spread in one line, e.g. ``"fs +-258 N, sigma0 +-1.17e9 N/m"``.

        Returns
        -------
        str
            The range of each parameter, in the order given.
        """
        return ", ".join(self._labels(name)[2] for name in self.deviations)

    def corners(self) -> tuple[tuple[str, LuGreParameters], ...]:
        """Return the corners of the box: every combination of the lows and highs.

        A corner whose Fs falls below its Fc keeps Fs and lowers Fc to it when the spread
        lowered Fs, else raises Fs to Fc (no Stribeck drop either way; the label says so).

        Returns
        -------
        tuple of (str, LuGreParameters)
            ``(label, friction)`` per corner, 2^n of them, the label naming each parameter's
            side (``"fs -258 N, sigma0 x 3"``); the first parameter varies slowest.
        """
        names = list(self.deviations)
        out = []
        for sides in itertools.product((0, 1), repeat=len(names)):
            changes, labels = {}, []
            for name, side in zip(names, sides, strict=True):
                changes[name] = self.bounds(name)[side]
                labels.append(self._labels(name)[side])
            fc = changes.get("fc", self.nominal.fc)
            fs = changes.get("fs", self.nominal.fs)
            if fs < fc:
                if "fs" in changes and changes["fs"] < self.nominal.fs:
                    changes["fc"] = fs
                    labels.append("fc lowered to fs")
                else:
                    changes["fs"] = fc
                    labels.append("fs raised to fc")
            out.append((", ".join(labels), dataclasses.replace(self.nominal, **changes)))
        return tuple(out)

    def to_dict(self) -> dict:
        """Return the spread as JSON-ready data.

        Returns
        -------
        dict
            ``source``, ``text`` (:meth:`describe`), ``corners`` (their number) and
            ``parameters``: per name its ``form``, ``value``, ``nominal``, ``low``, ``high``
            (SI) and ``unit``.
        """
        params = {}
        for name, (form, value) in self.deviations.items():
            low, high = self.bounds(name)
            params[name] = {"form": form, "value": value,
                            "nominal": float(getattr(self.nominal, name)), "low": low,
                            "high": high, "unit": SPREAD_PARAMETERS[name]}
        return {"source": self.source, "text": self.describe(),
                "corners": 2 ** len(self.deviations), "parameters": params}


def friction_spread(nominal: LuGreParameters | None, spread: Mapping | None = None,
                    variation: Mapping | None = None) -> FrictionSpread | None:
    """Return the friction spread a design is verified over, or None.

    ``spread`` (``[tuning] friction_spread``, the spread the tuning covers too) when given,
    else ``variation`` (the identified set's own variation, ``[friction] variation``).

    Parameters
    ----------
    nominal : LuGreParameters or None
        The nominal friction (None: no spread).
    spread : Mapping, optional
        Fractions for fc, fs, sigma1 and a factor for sigma0 (:meth:`FrictionSpread.relative`).
    variation : Mapping, optional
        Absolute +- values [SI] (:meth:`FrictionSpread.absolute`).

    Returns
    -------
    FrictionSpread or None
        None when there is no LuGre friction or neither is given.
    """
    if nominal is None:
        return None
    if spread:
        return FrictionSpread.relative(nominal, spread)
    if variation:
        return FrictionSpread.absolute(nominal, variation)
    return None


# ------------------------------------------------------------- the regimes of an axis
def process_amplitude(axis, drive, c: float, force_pp: float,
                      friction=None) -> tuple[float, float]:
    """Return the pad vibration amplitude and frequency at the standing regime's compliance peak.

    The work-piece compliance ``wp.x`` is evaluated with the pads on the LuGre presliding
    contact (spring sigma0, damper sigma1 + C) at 3000 log-spaced frequencies over
    ``axis.requirements.band``; at its peak, the pad amplitude is the mean magnitude of the
    pads' receptances to the work-piece force times half the peak-to-peak force. This is the
    amplitude of the describing-function model of the standing regime.

    Parameters
    ----------
    axis : Axis
        The axis (structure, pads, requirements; its friction unless ``friction`` is given).
    drive : Drive or None
        The drive closing the loop; None for the structure without a motor.
    c : float
        Viscous guide-way damping C [N s/m] added to sigma1 in the presliding contact.
    force_pp : float
        Peak-to-peak work-piece force [N].
    friction : FrictionLaw or LuGreParameters, optional
        The pads' friction law; default the axis' (``axis.friction.law``).

    Returns
    -------
    amplitude : float
        Pad vibration amplitude [m] (half the peak to peak), at least 1e-12.
    frequency : float
        Angular frequency [rad/s] of the compliance peak.
    """
    law = as_law(axis.friction.law if friction is None else friction)
    omega = 2 * math.pi * np.geomspace(*(np.array(axis.requirements.band) / (2 * math.pi)),
                                       3000)
    k, d = law.with_viscous(0.0).presliding()
    contact = Contact.stiction(k, d, c)
    h = axis_compliance(axis.structure, omega, drive, contact, axis.pads,
                        outputs=("wp.x", *axis.pads))
    i = int(np.argmax(np.abs(h[0])))
    amplitude = float(np.mean(np.abs(h[1:, i]))) * 0.5 * force_pp
    return max(amplitude, 1e-12), float(omega[i])


def axis_regimes(axis, c: float | None = None) -> tuple[RegimeModel, ...]:
    """Return the regime models of an axis (:func:`servotune.regimes.regime_models`).

    Without ``[drive]``, ``[friction]`` or ``[operation]``: the viscous pads alone (the paper's
    sec 4.1). Else standing (presliding, and the describing function at the process amplitude
    of :func:`process_amplitude` under ``[operation] process_force_pp``, 600 N when unset) and
    feeding at each feed speed, for the nominal friction, the corners of
    ``[tuning] friction_spread`` and the extra ``[tuning]`` friction samples; plus a
    rapid-traverse model (sliding at ``[operation] rapid_speed``, 0.1 m/s when unset, not
    cutting) for the loops when the axis has no feed speeds.

    Parameters
    ----------
    axis : Axis
        The axis description.
    c : float, optional
        Viscous guide-way damping C [N s/m] at which the process amplitude is computed;
        default the axis' ``[friction] viscous``. (The process amplitude is computed on the
        structure without a motor.)

    Returns
    -------
    tuple of RegimeModel
        The models, the nominal friction first.
    """
    if axis.drive is None or axis.friction is None or axis.operation is None:
        return regime_models(None, None)
    op = axis.operation
    c = axis.friction.viscous if c is None else c
    amplitude = frequency = None
    if op.standing:
        force = op.process_force_pp or 600.0
        amplitude, frequency = process_amplitude(axis, None, c, force)
    models = regime_models(axis.friction.law, op, amplitude, frequency,
                           dict(axis.tuning.friction_spread),
                           extra_samples=axis.tuning.friction_samples)
    if not op.feed_speeds:
        speed = op.rapid_speed or 0.1
        models += (RegimeModel(f"traverse {speed * 1e3:.3g} mm/s", "sliding", axis.friction.law,
                               speed=speed, cutting=False),)
    return models
