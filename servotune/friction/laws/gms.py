"""The generalized Maxwell-slip (GMS) friction law (Al-Bender, Lampaert and Swevers 2005).

N elasto-slide elements act in parallel; element i has a stiffness k_i, a micro-damping sigma1_i
and carries the fraction alpha_i of the Stribeck curve ``s(v) = Fc + (Fs - Fc) exp(-(|v|/vs)^
delta)`` [N] (sum alpha_i = 1). Its deflection z_i [m] sticks, ``dz_i/dt = v``, until its spring
force k_i z_i reaches alpha_i s(v); it then slips, relaxing at the attraction rate C [m/s]
towards that level (Al-Bender et al. 2005, Eq 5-7; Lampaert et al. 2003, Eq 10-12)::

    sticking:   dz_i/dt = v
    slipping:   dz_i/dt = sgn(v) C (1 - z_i / Delta_i(v)),     Delta_i(v) = alpha_i s(v) / k_i
    F = sum_i (k_i z_i + sigma1_i dz_i/dt) + sigma2 v

(the papers write the slip law with the deflection normalised by the element's share of the
Stribeck curve; here alpha_i is the force fraction and Delta_i the slip deflection in metres).

**Memoryless form.** The papers switch an element from slip back to stick when v changes sign, a
discrete state. Here each element follows the slower of its two rates, in the direction of v::

    dz_i/dt = sgn(v) min(|v|, C (1 - sgn(v) z_i / Delta_i(v)))

which is continuous in (v, z_i) (the implicit time integration needs that) and equal to the
switched law but in a band of width Delta_i |v| / C below the slip deflection, where the element
starts slipping early (|v| << C there: a relative 1e-3 at 0.1 m/s with the default C). Sticking
elements keep their deflection through a reversal; a slipping element stops slipping when v
reverses (its rate turns to v) -- the stick-slip memory of the Maxwell-slip model: the
presliding hysteresis has non-local memory with the wiping-out property of Preisach-type
hysteresis (Lampaert et al. 2003, sec III; Al-Bender et al. 2005, sec II), and steady sliding
gives the Stribeck curve ``F = sgn(v) s(v) + sigma2 v``.

For the time simulation (:mod:`servotune.simulate`) each element has one remainder: the linear
block carries ``dz_i/dt = a0_i + av_i v + az_i z_i - r_i`` (about rest the stick law, a0 = az = 0,
av = 1; about steady sliding at v0 the tangent of the slip law at z_i = sgn(v0) Delta_i(v0)) and
:func:`gms_remainder` the rest, ``r_i = a0_i + av_i v + az_i z_i - dz_i/dt``.

References
----------
F. Al-Bender, V. Lampaert, J. Swevers, "The generalized Maxwell-slip model: a novel model for
friction simulation and compensation", IEEE Trans. Automatic Control 50(11) (2005) 1883-1887,
Eq 5-7 (element and slip laws), Eq 8 (force), sec III (hysteresis with non-local memory).
V. Lampaert, F. Al-Bender, J. Swevers, "A generalized Maxwell-slip friction model appropriate for
control purposes", Proc. IEEE PhyCon 2003, Eq 10-12, sec III.
H. Olsson, K. J. Astrom, C. Canudas de Wit, M. Gafvert, P. Lischinsky, "Friction models and
friction compensation", European Journal of Control 4 (1998) 176-195 (micro-damping that
destabilises while sliding).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import control
import numpy as np

from ...cache import cached_njit
from ...structure.model import signal_name
from ..law import FrictionLaw

__all__ = ["GMSParameters", "GMSFriction", "gms_remainder", "gms_rate", "gms_states",
           "BIANCHI2014_GMS"]

N_FIXED = 5          # leading entries of the remainder parameters: C, Fc, Fs, vs, delta
PER_ELEMENT = 4      # then per element: Delta_i / s, a0_i, av_i, az_i
SUBSTEPS = 16        # sub-steps per sample interval in gms_states
PERIODIC_SUBSTEPS = 256   # and in periodic_force (a slipping element's micro-damping force
                          # follows its lag behind Delta_i(v), resolved to ~1e-6 of the force)


def _tuple(name: str, value) -> tuple[float, ...]:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        value = (value,)
    try:
        out = tuple(float(x) for x in value)
    except (TypeError, ValueError):
        raise ValueError(f"GMSParameters.{name} must be a list of numbers, got {value!r}") \
            from None
    if not out or not all(math.isfinite(x) for x in out):
        raise ValueError(f"GMSParameters.{name} must be a non-empty list of finite numbers, got "
                         f"{value!r}")
    return out


@dataclass(frozen=True)
class GMSParameters:
    """The parameters of the GMS law, SI, axis totals.

    Parameters
    ----------
    stiffness : sequence of float
        Element stiffnesses k_i [N/m], > 0; their sum is the presliding (initial) stiffness.
    fractions : sequence of float
        alpha_i [-], > 0, summing to 1: each element's share of the Stribeck curve.
    damping : sequence of float
        Element micro-dampings sigma1_i [N s/m], >= 0 (one per element).
    fc : float
        Coulomb friction Fc [N], > 0.
    fs : float
        Static friction Fs [N], >= Fc.
    vs : float
        Stribeck velocity [m/s], > 0.
    delta : float
        Stribeck exponent [-], > 0.
    sigma2 : float
        Viscous friction [N s/m], >= 0.
    attraction : float
        The slip attraction rate C [m/s], > 0: a slipping element relaxes to its level with the
        time constant Delta_i / C.

    Raises
    ------
    ValueError
        A value out of its range, lists of different lengths, fractions not summing to 1 (the
        message names the parameter and how to fix it).

    Examples
    --------
    >>> p = BIANCHI2014_GMS
    >>> sum(p.stiffness), p.fs
    (5900000000.0, 6013.0)
    >>> [round(d * 1e6, 3) for d in p.slip_deflections()]    # Delta_i at rest [um]
    [0.408, 0.815, 1.223, 1.631]
    """

    stiffness: tuple
    fractions: tuple
    damping: tuple
    fc: float
    fs: float
    vs: float
    delta: float
    sigma2: float
    attraction: float

    def __post_init__(self) -> None:
        for name in ("stiffness", "fractions", "damping"):
            object.__setattr__(self, name, _tuple(name, getattr(self, name)))
        n = len(self.stiffness)
        if len(self.fractions) != n or len(self.damping) != n:
            raise ValueError(f"GMSParameters: stiffness, fractions and damping need one value per "
                             f"element; got {n}, {len(self.fractions)} and {len(self.damping)}")
        if min(self.stiffness) <= 0:
            raise ValueError(f"GMSParameters.stiffness must be > 0 N/m, got {self.stiffness}")
        if min(self.fractions) <= 0 or abs(sum(self.fractions) - 1.0) > 1e-9:
            raise ValueError(f"GMSParameters.fractions must be > 0 and sum to 1, got "
                             f"{self.fractions} (sum {sum(self.fractions):.12g}); scale them")
        if min(self.damping) < 0:
            raise ValueError(f"GMSParameters.damping must be >= 0 N s/m, got {self.damping}")
        for name in ("fc", "fs", "vs", "delta", "sigma2", "attraction"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not \
                    math.isfinite(value):
                raise ValueError(f"GMSParameters.{name} must be a finite number, got {value!r}")
            object.__setattr__(self, name, float(value))
        for name, unit in (("fc", "N"), ("vs", "m/s"), ("delta", ""), ("attraction", "m/s")):
            if getattr(self, name) <= 0:
                raise ValueError(f"GMSParameters.{name} must be > 0 {unit}, got "
                                 f"{getattr(self, name)!r}")
        if self.fs < self.fc:
            raise ValueError(f"GMSParameters.fs ({self.fs!r} N) must be >= fc ({self.fc!r} N)")
        if self.sigma2 < 0:
            raise ValueError(f"GMSParameters.sigma2 must be >= 0 N s/m, got {self.sigma2!r}")

    @property
    def n_elements(self) -> int:
        """The number of elements N."""
        return len(self.stiffness)

    def scaled(self, factor: float) -> GMSParameters:
        """Return the same contact with forces and coefficients times a factor.

        k_i, sigma1_i, Fc, Fs and sigma2 scale; alpha_i, vs, delta and C do not, so the deflections
        move exactly as the total's: ``1/n`` shares an axis total among n pads.

        Parameters
        ----------
        factor : float
            The factor, > 0.

        Returns
        -------
        GMSParameters
        """
        factor = float(factor)
        if not (math.isfinite(factor) and factor > 0):
            raise ValueError(f"factor must be > 0, got {factor!r}")
        return dataclasses.replace(
            self, stiffness=tuple(k * factor for k in self.stiffness),
            damping=tuple(c * factor for c in self.damping), fc=self.fc * factor,
            fs=self.fs * factor, sigma2=self.sigma2 * factor)

    def stribeck(self, v) -> np.ndarray:
        """Return the Stribeck curve s(v) = Fc + (Fs - Fc) exp(-(|v|/vs)^delta).

        Parameters
        ----------
        v : array_like
            Velocity [m/s].

        Returns
        -------
        numpy.ndarray
            s(v) [N].
        """
        v = np.asarray(v, dtype=float)
        return self.fc + (self.fs - self.fc) * np.exp(-(np.abs(v) / self.vs) ** self.delta)

    def slip_deflections(self, v: float = 0.0) -> tuple[float, ...]:
        """Return the slip deflections Delta_i(v) = alpha_i s(v) / k_i.

        Parameters
        ----------
        v : float
            Velocity [m/s].

        Returns
        -------
        tuple of float
            Delta_i [m], one per element.
        """
        s = float(self.stribeck(v))
        return tuple(a * s / k for a, k in zip(self.fractions, self.stiffness, strict=True))

    def to_dict(self) -> dict:
        """Return the parameters as a plain dictionary.

        Returns
        -------
        dict
            SI values, lists for the elements.
        """
        d = dataclasses.asdict(self)
        return {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}


#: A four-element GMS law matched to the paper's identified LuGre set (Bianchi et al. 2014, table
#: after Fig 8): the same initial stiffness (sum k_i = sigma0), Stribeck curve and sigma2; equal
#: stiffnesses and fractions 0.1..0.4, so the virgin curve bends over 0.4-1.6 um instead of
#: LuGre's exponential; C = 0.1 m/s (not identified: a slipping element relaxes in Delta_i / C
#: ~ 10 us, as LuGre's bristles do while sliding). No micro-damping: while an element slips,
#: sigma1_i dz_i/dt has the slope sigma1_i C Delta_i'(v) / Delta_i in v, a negative damping
#: (about -60 sigma1_i s/m below vs); the paper's sigma1 spread over the elements makes the pads
#: chatter, as LuGre's constant sigma1 does (Olsson et al. 1998; README.md, "Friction"). The
#: elements' hysteresis dissipates instead, once they slip.
BIANCHI2014_GMS = GMSParameters(
    stiffness=(1.475e9,) * 4, fractions=(0.1, 0.2, 0.3, 0.4), damping=(0.0,) * 4,
    fc=2198.0, fs=6013.0, vs=0.01, delta=1.0, sigma2=5578.0, attraction=0.1)

_NAMED = {"bianchi2014": BIANCHI2014_GMS}


# ---------------------------------------------------------------- the compiled element law

@cached_njit
def gms_rate(v, z, lam, c, fc, fs, vs, delta):
    """Return dz/dt of one element and its partial derivatives (memoryless form).

    At v = 0 the rate is 0 and its v-derivative the stick slope 1 (module docstring).

    Parameters
    ----------
    v : float
        Sliding velocity [m/s].
    z : float
        Element deflection [m].
    lam : float
        alpha_i / k_i [m/N] (Delta_i = lam s(v)).
    c : float
        Attraction rate C [m/s].
    fc, fs : float
        Coulomb and static friction [N] (of the same share as k_i).
    vs : float
        Stribeck velocity [m/s].
    delta : float
        Stribeck exponent [-].

    Returns
    -------
    (rate, d_dv, d_dz) : tuple of float
        dz/dt [m/s] and its partial derivatives [-], [1/s].
    """
    if v == 0.0:
        return 0.0, 1.0, 0.0
    sgn = 1.0 if v > 0.0 else -1.0
    av = abs(v)
    x = av / vs
    e = math.exp(-(x ** delta))
    s = fc + (fs - fc) * e
    dlt = lam * s
    slip = c * (1.0 - sgn * z / dlt)
    if av <= slip:
        return v, 1.0, 0.0
    # slipping: sgn C (1 - sgn z / Delta(v)); dDelta/dv = lam s'(v), s' = -(fs-fc) delta x^(d-1)
    # e / vs * sgn
    ds = -(fs - fc) * delta * x ** (delta - 1.0) * e / vs * sgn
    return sgn * slip, c * z * lam * ds / (dlt * dlt), -c / dlt


@cached_njit
def gms_remainder(component, v, z, p):
    """Return the remainder of one element, ``r = a0 + av v + az z - dz/dt``, and its derivatives.

    Parameters
    ----------
    component : int
        The element.
    v : float
        Sliding velocity [m/s].
    z : float
        The element's deflection [m].
    p : numpy.ndarray
        ``(C, Fc, Fs, vs, delta)`` then per element ``(lam_i, a0_i, av_i, az_i)``; Fc and Fs of
        any share (they enter through Delta_i = lam_i s).

    Returns
    -------
    (r, dr_dv, dr_dz) : tuple of float
        r [m/s], dr/dv [-], dr/dz [1/s].
    """
    b = N_FIXED + PER_ELEMENT * component
    rate, d_v, d_z = gms_rate(v, z, p[b], p[0], p[1], p[2], p[3], p[4])
    return p[b + 1] + p[b + 2] * v + p[b + 3] * z - rate, p[b + 2] - d_v, p[b + 3] - d_z


@cached_njit
def _advance(z, v, tau, lam, c, fc, fs, vs, delta):
    """z after a time tau at constant v (exact for the memoryless element law)."""
    if v == 0.0 or tau <= 0.0:
        return z
    sgn = 1.0 if v > 0.0 else -1.0
    av = abs(v)
    u = sgn * z                                    # deflection in the direction of motion
    dlt = lam * (fc + (fs - fc) * math.exp(-((av / vs) ** delta)))
    knee = dlt * (1.0 - av / c)                    # where the stick and slip rates are equal
    if u < knee:
        t_knee = (knee - u) / av
        if tau <= t_knee:
            return sgn * (u + av * tau)
        u = knee
        tau -= t_knee
    return sgn * (dlt + (u - dlt) * math.exp(-c * tau / dlt))


@cached_njit
def _march(v0, v1, h, z, lam, c, fc, fs, vs, delta, substeps):
    """Advance the element states z (in place) over an interval h whose velocity goes linearly
    from v0 to v1, in sub-steps at their mid-point velocity."""
    dt = h / substeps
    for j in range(substeps):
        v = v0 + (v1 - v0) * (j + 0.5) / substeps
        for i in range(z.size):
            z[i] = _advance(z[i], v, dt, lam[i], c, fc, fs, vs, delta)


@cached_njit
def _orbit(v_mid, substeps, h, z, lam, c, fc, fs, vs, delta, max_periods, tol, out):
    """Integrate periods from z until z repeats within tol (per element); ``v_mid`` holds the
    velocity at the mid-points of the ``substeps`` sub-steps of every sample interval (step h);
    out (n, N) receives z at the samples of the last period. Returns the periods integrated."""
    n = out.shape[0]
    dt = h / substeps
    for period in range(max_periods):
        start = z.copy()
        for j in range(n):
            for i in range(z.size):
                out[j, i] = z[i]
            for m in range(substeps):
                v = v_mid[j * substeps + m]
                for i in range(z.size):
                    z[i] = _advance(z[i], v, dt, lam[i], c, fc, fs, vs, delta)
        done = True
        for i in range(z.size):
            if abs(z[i] - start[i]) > tol[i]:
                done = False
        if done:
            return period + 1
    return max_periods


def _midpoint_velocity(v: np.ndarray, substeps: int) -> np.ndarray:
    """The periodic samples v interpolated trigonometrically (band-limited, exact for a
    velocity of fewer than n/2 harmonics) at the mid-points of ``substeps`` sub-steps of every
    sample interval."""
    n = v.size
    spec = np.fft.rfft(v)
    harmonic = np.arange(spec.size)
    spec = spec * np.exp(2j * np.pi * harmonic * (0.5 / substeps) / n)   # half a sub-step later
    if n % 2 == 0:
        spec[-1] *= 0.5               # the Nyquist term, split over +- n/2 in the finer grid
    return np.fft.irfft(spec * substeps, n * substeps)


@cached_njit
def _force_kernel(v, z, lam, k, c1, sigma2, c, fc, fs, vs, delta, out):
    for j in range(v.size):
        acc = sigma2 * v[j]
        for i in range(lam.size):
            rate = gms_rate(v[j], z[j, i], lam[i], c, fc, fs, vs, delta)[0]
            acc += k[i] * z[j, i] + c1[i] * rate
        out[j] = acc


def _forces(params: GMSParameters, v: np.ndarray, z: np.ndarray) -> np.ndarray:
    """F [N] at velocities v (m,) and element states z (m, N)."""
    k = np.array(params.stiffness)
    out = np.empty(v.size)
    _force_kernel(np.ascontiguousarray(v, dtype=float), np.ascontiguousarray(z, dtype=float),
                  np.array(params.fractions) / k, k, np.array(params.damping), params.sigma2,
                  params.attraction, params.fc, params.fs, params.vs, params.delta, out)
    return out


def gms_states(params: GMSParameters, t, velocity, z0=None) -> tuple[np.ndarray, np.ndarray]:
    """Integrate the element deflections and friction force under an imposed velocity history.

    Parameters
    ----------
    params : GMSParameters
        The law's parameters (any share).
    t : array_like
        Increasing times [s].
    velocity : array_like
        The sliding velocity [m/s] at ``t`` (linear in between).
    z0 : array_like, optional
        Initial deflections [m] (default 0: the virgin state).

    Returns
    -------
    (z, force) : tuple of numpy.ndarray
        z of shape (len(t), N) [m] and the force [N] at ``t``.

    Raises
    ------
    ValueError
        Times not increasing, shapes that do not match, values not finite.
    """
    t = np.asarray(t, dtype=float)
    v = np.asarray(velocity, dtype=float)
    if t.ndim != 1 or v.shape != t.shape or t.size < 1:
        raise ValueError("t and velocity must be 1-D arrays of the same length")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v)) and np.all(np.diff(t) > 0)):
        raise ValueError("t must be increasing and t, velocity finite")
    n = params.n_elements
    z = np.zeros(n) if z0 is None else np.array(z0, dtype=float).reshape(n)
    lam = np.array(params.fractions) / np.array(params.stiffness)
    out = np.empty((t.size, n))
    out[0] = z
    for j in range(t.size - 1):
        _march(v[j], v[j + 1], t[j + 1] - t[j], z, lam, params.attraction, params.fc, params.fs,
               params.vs, params.delta, SUBSTEPS)
        out[j + 1] = z
    return out, _forces(params, v, out)


@dataclass(frozen=True)
class GMSFriction(FrictionLaw):
    """The GMS friction law at the guide-way pads (axis totals, shared equally by the pads).

    Parameters
    ----------
    params : GMSParameters
        Axis totals, e.g. :data:`BIANCHI2014_GMS`.

    Raises
    ------
    ValueError
        If ``params`` is not a :class:`GMSParameters`.

    See Also
    --------
    servotune.friction.law.FrictionLaw : the interface.
    servotune.friction.laws.lugre.LuGreFriction : the paper's law.

    References
    ----------
    F. Al-Bender, V. Lampaert, J. Swevers, IEEE Trans. Automatic Control 50(11) (2005)
    1883-1887, Eq 5-8.

    Examples
    --------
    At rest every element sticks: the presliding contact is the sum of the springs and of the
    dampers.

    >>> law = GMSFriction(BIANCHI2014_GMS)
    >>> law.presliding()
    (5900000000.0, 5578.0)
    """

    params: GMSParameters
    name = "gms"
    nonlinear = True
    table_hint = ("give stiffness, fractions and damping (one value per element), fc, fs, vs, "
                  "delta, sigma2 and attraction in SI units, or gms = \"bianchi2014\"")

    def __post_init__(self) -> None:
        if not isinstance(self.params, GMSParameters):
            raise ValueError("GMSFriction needs GMSParameters, e.g. "
                             "servotune.friction.laws.gms.BIANCHI2014_GMS")

    @classmethod
    def from_table(cls, value) -> GMSFriction:
        """Build the law from ``[friction.gms]`` of an axis description: the fields of
        :class:`GMSParameters` (SI, lists for the elements), or ``gms = "bianchi2014"``.

        Parameters
        ----------
        value : dict or str
            The entry of the axis file.

        Returns
        -------
        GMSFriction

        Raises
        ------
        ValueError
            A parameter is missing, unknown or out of range.
        """
        if isinstance(value, str):
            if value.lower() not in _NAMED:
                raise ValueError(f"unknown GMS set {value!r}; choose one of {sorted(_NAMED)}")
            return cls(_NAMED[value.lower()])
        if not isinstance(value, dict):
            raise ValueError(f"give a parameter table, got {value!r}")
        return cls(GMSParameters(**value))

    # ------------------------------------------------------------ linear contacts

    @property
    def viscous_part(self) -> float:
        """sigma2 [N s/m]."""
        return self.params.sigma2

    def with_viscous(self, c: float) -> GMSFriction:
        """Return the law with sigma2 = ``c`` [N s/m].

        Parameters
        ----------
        c : float
            Viscous damping [N s/m], >= 0.

        Returns
        -------
        GMSFriction
        """
        return GMSFriction(dataclasses.replace(self.params, sigma2=float(c)))

    def steady_force(self, speed: float) -> float:
        """Return the steady sliding friction ``sgn(v) s(v) + sigma2 v`` [N]: every element
        slips at its share of the Stribeck curve (Al-Bender et al. 2005, sec II).

        Parameters
        ----------
        speed : float
            Sliding speed v [m/s].

        Returns
        -------
        float
        """
        v = float(speed)
        return math.copysign(float(self.params.stribeck(v)), v) + self.params.sigma2 * v

    def steady_slope(self, speed: float) -> float:
        """Return ``s'(|v|) + sigma2`` [N s/m], the slope of :meth:`steady_force` (at 0 the
        slope of s is taken as 0).

        Parameters
        ----------
        speed : float
            Sliding speed v [m/s].

        Returns
        -------
        float
        """
        p = self.params
        u = abs(float(speed)) / p.vs
        if u == 0.0:
            return p.sigma2
        return (-(p.fs - p.fc) * math.exp(-u ** p.delta) * p.delta * u ** (p.delta - 1.0) / p.vs
                + p.sigma2)

    def presliding(self) -> tuple[float, float]:
        """Return the contact linearised at rest, axis totals: all elements stick, (sum k_i, sum
        sigma1_i + sigma2).

        Returns
        -------
        (stiffness, damping) : tuple of float
            Spring [N/m] and damper [N s/m].
        """
        p = self.params
        return float(sum(p.stiffness)), float(sum(p.damping) + p.sigma2)

    def _tangent(self, speed: float) -> np.ndarray:
        """(a0_i, av_i, az_i) per element, rows: the tangent of dz_i/dt about rest (stick) or
        about steady sliding at ``speed`` (z_i = sgn(v0) Delta_i(v0))."""
        speed = float(speed)
        if not math.isfinite(speed):
            raise ValueError(f"the operating speed must be finite, got {speed!r}")
        p = self.params
        n = p.n_elements
        if speed == 0.0:
            return np.tile([0.0, 1.0, 0.0], (n, 1))
        rows = []
        for i, dlt in enumerate(p.slip_deflections(speed)):
            z0 = math.copysign(dlt, speed)
            lam = p.fractions[i] / p.stiffness[i]
            rate, d_v, d_z = gms_rate(speed, z0, lam, p.attraction, p.fc, p.fs, p.vs, p.delta)
            rows.append((rate - d_v * speed - d_z * z0, d_v, d_z))
        return np.array(rows, dtype=float)

    def sliding_system(self, speed: float) -> control.StateSpace:
        """Return the contact linearised about steady sliding at a speed, axis total: all elements
        slipping, per element ``dz_i/dt = av_i v + az_i z_i`` (deviations) and ``F = sum (k_i z_i +
        sigma1_i dz_i/dt) + sigma2 v``; its DC gain is the slope of the Stribeck curve, its poles -C
        / Delta_i(v0).

        Parameters
        ----------
        speed : float
            Sliding speed v0 [m/s], non-zero.

        Returns
        -------
        control.StateSpace
            SISO, from the velocity deviation [m/s] to the force deviation [N].

        Raises
        ------
        ValueError
            If ``speed`` is 0 or not finite.
        """
        if not speed:
            raise ValueError("the sliding contact needs a non-zero speed v0 [m/s]")
        p = self.params
        tan = self._tangent(speed)
        k, c1 = np.array(p.stiffness), np.array(p.damping)
        return control.ss(np.diag(tan[:, 2]), tan[:, 1:2], [k + c1 * tan[:, 2]],
                          [[float(c1 @ tan[:, 1]) + p.sigma2]], inputs=["velocity"],
                          outputs=["force"], name="gms_sliding")

    # ------------------------------------------------------------ time simulation

    @property
    def remainder_prefixes(self) -> tuple[str, ...]:
        """``r1_``, ``r2_``, ...: one remainder per element."""
        return tuple(f"r{i + 1}_" for i in range(self.params.n_elements))

    def _states(self, pad: str) -> tuple[str, ...]:
        return tuple(signal_name(pad, f"z{i + 1}_") for i in range(self.params.n_elements))

    def remainder_states(self, pad: str) -> tuple[str, ...]:
        """Return the state each remainder component reads: element i's remainder reads its
        deflection ``z<i>_<pad>``.

        Parameters
        ----------
        pad : str
            The pad DOF.

        Returns
        -------
        tuple of str
            One state name per remainder component.
        """
        return self._states(pad)

    def spring_states(self, pad: str, n_pads: int) -> tuple[tuple[str, float], ...]:
        """Return one pad's elastic states with their stiffnesses: the element springs k_i / n_pads.

        Parameters
        ----------
        pad : str
            The pad DOF.
        n_pads : int
            The number of pads sharing the law.

        Returns
        -------
        tuple of (str, float)
            (state name, stiffness [N/m]) pairs.
        """
        return tuple((z, k / n_pads) for z, k in zip(self._states(pad), self.params.stiffness,
                                                      strict=True))

    def pad_block(self, pad: str, n_pads: int, speed: float = 0.0) -> control.StateSpace:
        """Return the linear part for one pad: the element deflections z_i, linearised about rest
        (stick) or steady sliding (module docstring).

        Parameters
        ----------
        pad : str
            The pad DOF.
        n_pads : int
            The number of pads sharing the axis-total law equally.
        speed : float
            Operating speed [m/s] of the linearisation (0: at rest).

        Returns
        -------
        control.StateSpace
            Inputs ``v_<pad>``, ``r<i>_<pad>`` per element, ``one``; outputs ``f_<pad>``,
            ``F_<pad>`` and the ``z<i>_<pad>``.
        """
        p = self.params.scaled(1.0 / n_pads)
        n = p.n_elements
        tan = self._tangent(speed)
        a0, av, az = tan[:, 0], tan[:, 1], tan[:, 2]
        k, c1 = np.array(p.stiffness), np.array(p.damping)
        b = np.hstack([av[:, None], -np.eye(n), a0[:, None]])
        c_force = k + c1 * az
        d_force = np.concatenate([[float(c1 @ av) + p.sigma2], -c1, [float(c1 @ a0)]])
        states = list(self._states(pad))
        return control.ss(np.diag(az), b, np.vstack([-c_force, c_force, np.eye(n)]),
                          np.vstack([-d_force, d_force, np.zeros((n, n + 2))]),
                          inputs=[signal_name(pad, "v_"), *self.remainder_signals(pad), "one"],
                          outputs=[signal_name(pad, "f_"), signal_name(pad, "F_"), *states],
                          states=states, name=f"friction_{signal_name(pad)}")

    def remainder(self):
        """Return the compiled remainder: :func:`gms_remainder`, one component per element.

        Returns
        -------
        numba dispatcher
            ``(component, v, z, p) -> (r, dr_dv, dr_dz)``.
        """
        return gms_remainder

    def remainder_parameters(self, speed: float = 0.0) -> np.ndarray:
        """Return the parameters of :meth:`remainder` for a linearisation: ``(C, Fc, Fs, vs,
        delta)`` then per element ``(alpha_i / k_i, a0_i, av_i, az_i)``.

        Parameters
        ----------
        speed : float
            Operating speed [m/s] of the linear part (0: at rest).

        Returns
        -------
        numpy.ndarray
            The remainder's parameter vector.
        """
        p = self.params
        lam = np.array(p.fractions) / np.array(p.stiffness)
        per = np.column_stack([lam, self._tangent(speed)])
        return np.concatenate([[p.attraction, p.fc, p.fs, p.vs, p.delta], per.ravel()])

    def error_scales(self) -> tuple[float, tuple[float, ...]]:
        """Return the scales of the integrator's error control: vs and the slip deflections at rest
        Delta_i(0).

        Returns
        -------
        (v_scale, z_scales) : tuple
            Velocity scale [m/s] and one state scale [m] per remainder component.
        """
        return self.params.vs, self.params.slip_deflections(0.0)

    def newton_tolerance(self, step: float) -> float:
        """Return the tolerance on the remainders in the Newton iteration: 1e-10 Fc through the
        elements' dampers and springs over a step.

        Parameters
        ----------
        step : float
            The integration step [s].

        Returns
        -------
        float
            Tolerance [m/s].
        """
        p = self.params
        return 1e-10 * p.fc / (sum(p.damping) + sum(p.stiffness) * step)

    def friction_force(self, v, z):
        """Return the friction force [N], axis total: ``sum (k_i z_i + sigma1_i dz_i/dt) + sigma2
        v``.

        Parameters
        ----------
        v : array_like
            Pad velocity [m/s].
        z : array_like
            Element deflections [m], shape (len(v), N).

        Returns
        -------
        numpy.ndarray
            Friction force [N].
        """
        v = np.atleast_1d(np.asarray(v, dtype=float))
        z = np.asarray(z, dtype=float).reshape(v.size, self.params.n_elements)
        return _forces(self.params, v, z)

    # ------------------------------------------------------------ harmonic balance

    def periodic_force(self, velocity, period: float, share: float = 1.0) -> np.ndarray:
        """Force [N] of one pad carrying ``share`` of the law, on the periodic orbit.

        Parameters
        ----------
        velocity : array_like
            Pad velocity [m/s] at N equally spaced instants of one period (periodic).
        period : float
            The period [s], > 0.
        share : float
            The pad's share of the axis-total law, > 0.

        Returns
        -------
        numpy.ndarray
            The force [N] at the same instants.

        Raises
        ------
        ValueError
            Bad velocity samples, period or share.

        Notes
        -----
        The deflections are integrated over whole periods until they repeat (to 1e-12 of each
        slip deflection; an element that slips in both directions forgets its start within a
        period, wiping-out), each sample interval in 256 sub-steps at constant velocity, where
        the element law has a closed-form solution (stick at v up to the knee, then the
        exponential approach to Delta_i); the velocity at the sub-steps' mid-points is the
        trigonometric interpolation of the periodic samples. Elements that never slip have a
        periodic orbit for any offset; they start (and so stay) centred, ``z_i = x - mean(x)``
        with x the displacement -- the orbit reached from the virgin state under a displacement
        of zero mean. The deflections do not depend on the share; the force scales with it.
        """
        v = np.asarray(velocity, dtype=float)
        period, share = float(period), float(share)
        if v.ndim != 1 or v.size < 2 or not np.all(np.isfinite(v)):
            raise ValueError("velocity must be a 1-D array of at least 2 finite samples [m/s]")
        if not (math.isfinite(period) and period > 0 and math.isfinite(share) and share > 0):
            raise ValueError(f"period [s] and share must be > 0, got {period!r} and {share!r}")
        p = self.params
        h = period / v.size
        # displacement at the samples (trapezoid, linear velocity in between), mean removed
        x = np.concatenate([[0.0], np.cumsum(0.5 * h * (v[:-1] + v[1:]))])
        rest = np.array(p.slip_deflections(0.0))
        z = np.clip(-x.mean(), -rest, rest)
        lam = np.array(p.fractions) / np.array(p.stiffness)
        out = np.empty((v.size, p.n_elements))
        _orbit(_midpoint_velocity(v, PERIODIC_SUBSTEPS), PERIODIC_SUBSTEPS, h, z, lam,
               p.attraction, p.fc, p.fs, p.vs, p.delta, 1000, 1e-12 * rest, out)
        return share * _forces(p, v, out)
