"""Fitting LuGre parameters to measurements (paper sec 5.1, Fig 7 and Fig 8).

Two fits, as on the paper's axis:

* :func:`fit_steady_state`: (Fc, Fs, vs, delta, sigma2) to sliding friction measured at
  constant velocities, ``F_ss(v) = g(v) sgn(v) + sigma2 v`` (Fig 7);
* :func:`fit_presliding`: (sigma0, sigma1) to a time history of displacement and force during
  small motions with reversals (Fig 2, Fig 8), the sliding parameters being known.

Both are nonlinear least squares (``scipy.optimize.least_squares``, trust-region reflective
with bounds). Standard errors come from the Gauss-Newton covariance at the optimum,
``cov = s^2 (J^T J)^-1`` with ``s^2 = SSR / (n - p)``, which assumes independent force errors
of equal variance. Data that cannot determine the parameters are refused with
:class:`IdentificationError` (a ``ValueError``) saying what is missing.

CSV files (:func:`read_friction_csv`) have one header row naming the columns. Expected, in SI:
``v_m_per_s,f_n`` for steady-state data and ``t_s,x_m,f_n`` for presliding time histories.
Also accepted: ``v``, ``velocity``, ``v_mm_per_s``; ``t``, ``time``; ``x``, ``displacement``,
``x_mm``, ``x_um``; ``f``, ``force``, ``force_n``, ``f_kn``. Units other than SI are converted
on reading and nowhere else.

References
----------
G. Bianchi, S. Cagna, N. Cau, F. Paolucci, "Analysis of vibration damping in machine tools",
Procedia CIRP 21 (2014) 367-372, sec 5.1.
B. Armstrong-Helouvry, P. Dupont, C. Canudas de Wit, "A survey of models, analysis tools and
compensation methods for the control of machines with friction", Automatica 30(7) (1994)
1083-1138 (identification of the Stribeck curve from constant-velocity tests).
"""

from __future__ import annotations

import dataclasses
import math
import types
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from ..tablefile import read_table
from .lugre import LuGreParameters, simulate_lugre

__all__ = [
    "FrictionData",
    "FrictionFit",
    "IdentificationError",
    "fit_presliding",
    "fit_steady_state",
    "read_friction_csv",
]

STEADY_NAMES = ("fc", "fs", "vs", "delta", "sigma2")
PRESLIDING_NAMES = ("sigma0", "sigma1", "f0")
_CONDITION_LIMIT = 1e12


class IdentificationError(ValueError):
    """The data cannot determine the requested parameters."""


@dataclass(frozen=True)
class FrictionFit:
    """Estimated friction parameters with their standard errors (SI).

    Attributes
    ----------
    names : tuple of str
        Names of the estimated parameters.
    values, standard_errors : numpy.ndarray
        Estimates and their standard errors (Gauss-Newton covariance).
    covariance : numpy.ndarray
        Covariance matrix of the estimates.
    fixed : Mapping[str, float]
        Parameters held at given values.
    parameters : LuGreParameters
        The full parameter set: the estimates in place of the corresponding fields of the set
        the fit started from.
    residuals : numpy.ndarray
        Measured minus fitted force [N].
    rms : float
        Root-mean-square residual [N].
    kind : str
        ``"steady_state"`` or ``"presliding"``.
    """

    names: tuple[str, ...]
    values: np.ndarray
    standard_errors: np.ndarray
    covariance: np.ndarray
    fixed: Mapping[str, float]
    parameters: LuGreParameters
    residuals: np.ndarray
    rms: float
    kind: str

    def estimate(self, name: str) -> tuple[float, float]:
        """Return the estimate of one parameter and its standard error.

        Parameters
        ----------
        name : str
            An estimated parameter (one of :attr:`names`), e.g. ``"fs"``.

        Returns
        -------
        value : float
            The estimate, in the parameter's SI unit.
        standard_error : float
            Its standard error, same unit.

        Raises
        ------
        ValueError
            If ``name`` was not estimated.
        """
        if name not in self.names:
            raise ValueError(f"{name!r} was not estimated; estimated: {self.names}")
        i = self.names.index(name)
        return float(self.values[i]), float(self.standard_errors[i])

    def to_dict(self) -> dict:
        """Return the fit JSON-ready: estimates, standard errors, fixed values, residuals.

        Returns
        -------
        dict
            ``kind``, ``estimates`` and ``standard_errors`` (name -> SI value), ``fixed``,
            ``parameters`` (:meth:`LuGreParameters.to_dict
            <servotune.friction.lugre.LuGreParameters.to_dict>`), ``rms_residual`` [N] and
            ``n_points``.
        """
        return {
            "kind": self.kind,
            "estimates": {n: float(v) for n, v in zip(self.names, self.values, strict=True)},
            "standard_errors": {n: float(s) for n, s in
                                zip(self.names, self.standard_errors, strict=True)},
            "fixed": dict(self.fixed),
            "parameters": self.parameters.to_dict(),
            "rms_residual": self.rms,
            "n_points": int(self.residuals.size),
        }


@dataclass(frozen=True)
class FrictionData:
    """Measurements read from a CSV file (SI arrays; absent columns are None)."""

    force: np.ndarray
    velocity: np.ndarray | None = None
    t: np.ndarray | None = None
    displacement: np.ndarray | None = None

    @property
    def kind(self) -> str:
        """``"steady_state"`` for (v, F) data, ``"presliding"`` for (t, x, F) histories."""
        return "steady_state" if self.velocity is not None else "presliding"


_COLUMNS = {
    "velocity": {"v_m_per_s": 1.0, "v": 1.0, "velocity": 1.0, "velocity_m_per_s": 1.0,
                 "v_mm_per_s": 1e-3},
    "t": {"t_s": 1.0, "t": 1.0, "time": 1.0, "time_s": 1.0},
    "displacement": {"x_m": 1.0, "x": 1.0, "displacement": 1.0, "displacement_m": 1.0,
                     "x_mm": 1e-3, "x_um": 1e-6},
    "force": {"f_n": 1.0, "f": 1.0, "force": 1.0, "force_n": 1.0, "f_kn": 1e3},
}


def read_friction_csv(path) -> FrictionData:
    """Read steady-state (v, F) or presliding (t, x, F) data from a CSV file with a header.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file (lines starting with ``#`` are comments).

    Returns
    -------
    FrictionData
        The force [N] with the velocity [m/s], or with time [s] and displacement [m] (each
        column converted from the unit its name gives).

    Raises
    ------
    servotune.tablefile.TableFileError
        If the file cannot be read, the header names no known force column, neither a
        velocity nor time + displacement columns, or a value is not a finite number (naming
        its line).
    """
    table = read_table(path, "friction data",
                       hint="v_m_per_s,f_n (steady state) or t_s,x_m,f_n (presliding)")
    found: dict[str, np.ndarray] = {}
    for quantity, names in _COLUMNS.items():
        for name in table.header:
            if name in names:
                found[quantity] = table.numbers(name) * names[name]
                break
    expected = "expected columns v_m_per_s,f_n (steady state) or t_s,x_m,f_n (presliding)"
    if "force" not in found:
        raise table.error(f"no force column in the header {list(table.header)}; {expected}")
    if "velocity" in found:
        return FrictionData(force=found["force"], velocity=found["velocity"])
    if "t" in found and "displacement" in found:
        return FrictionData(force=found["force"], t=found["t"],
                            displacement=found["displacement"])
    raise table.error(f"the header {list(table.header)} names neither a velocity nor time "
                      f"and displacement; {expected}")


def _covariance(jac: np.ndarray, residuals: np.ndarray, names, what: str) -> np.ndarray:
    n, p = jac.shape
    scale = np.linalg.norm(jac, axis=0)
    if np.any(scale == 0.0):
        bad = [nm for nm, s in zip(names, scale, strict=True) if s == 0.0]
        raise IdentificationError(f"the {what} data carry no information on {bad}")
    js = jac / scale
    _, sv, vt = np.linalg.svd(js, full_matrices=False)
    condition = sv[0] / sv[-1] if sv[-1] > 0 else math.inf
    if condition**2 > _CONDITION_LIMIT:
        worst = names[int(np.argmax(np.abs(vt[-1])))]
        raise IdentificationError(
            f"the {what} data cannot determine the parameters separately (condition number of "
            f"J^T J {condition**2:.2e}; least determined: {worst}); widen the range of the "
            "measurements or fix that parameter")
    s2 = float(residuals @ residuals) / max(n - p, 1)
    cov_s = (vt.T / sv**2) @ vt
    return s2 * cov_s / np.outer(scale, scale)


def _check_determined(names, values, cov, what: str) -> None:
    """Refuse estimates whose standard error exceeds their magnitude."""
    se = np.sqrt(np.diag(cov))
    loose = [f"{n} = {v:.3g} +- {e:.2g}" for n, v, e in zip(names, values, se, strict=True)
             if e > abs(v)]
    if loose:
        raise IdentificationError(
            f"the {what} data do not determine {', '.join(loose)} (standard error larger than "
            "the estimate); widen the measured range or fix these parameters")


def _check_vector(name: str, value) -> np.ndarray:
    value = np.asarray(value, dtype=float)
    if value.ndim != 1:
        raise ValueError(f"{name} must be a 1-D array")
    if not np.all(np.isfinite(value)):
        raise ValueError(f"{name} must be finite")
    return value


def fit_steady_state(v, force, *, fixed: Mapping[str, float] | None = None,
                     base: LuGreParameters | None = None) -> FrictionFit:
    """Fit (Fc, Fs, vs, delta, sigma2) to sliding friction measured at constant velocities.

    Parameters
    ----------
    v : array_like
        Sliding velocities [m/s], non-zero, of both signs.
    force : array_like
        Measured friction forces [N] (same sign as v).
    fixed : mapping, optional
        Parameters held at given values instead of being estimated, e.g. ``{"delta": 1.0}``
        (the paper's value). Keys among ``fc, fs, vs, delta, sigma2``.
    base : LuGreParameters, optional
        Supplies sigma0 and sigma1 for :attr:`FrictionFit.parameters` (the steady state does
        not depend on them). Default: the paper's values.

    Returns
    -------
    FrictionFit

    Raises
    ------
    IdentificationError
        Fewer than 3 points per estimated parameter; v = 0 samples (friction is set-valued
        there); velocities of one sign only; a velocity range of less than a decade; an
        estimated Stribeck velocity outside the measured speeds; parameters the data cannot
        separate.

    Notes
    -----
    Model: ``F = (Fc + (Fs - Fc) exp(-|v/vs|^delta)) sgn(v) + sigma2 v`` with the analytic
    Jacobian. The start is read off the data: Fc and sigma2 from a line through the fastest
    third, Fs from the slowest points, vs where the Stribeck excess has halved.

    Examples
    --------
    >>> from servotune.friction import BIANCHI2014, steady_state_friction
    >>> v = np.concatenate([-np.geomspace(1e-4, 0.5, 20), np.geomspace(1e-4, 0.5, 20)])
    >>> fit = fit_steady_state(v, steady_state_friction(BIANCHI2014, v))
    >>> round(fit.estimate("fs")[0]), round(fit.estimate("vs")[0], 4)
    (6013, 0.01)
    """
    v = _check_vector("v", v)
    force = _check_vector("force", force)
    if v.shape != force.shape:
        raise ValueError(f"v and force must have the same length, got {v.size} and {force.size}")
    fixed = dict(fixed or {})
    for key in fixed:
        if key not in STEADY_NAMES:
            raise ValueError(f"cannot fix {key!r}; steady-state parameters are {STEADY_NAMES}")
    names = tuple(n for n in STEADY_NAMES if n not in fixed)
    if not names:
        raise ValueError("every parameter is fixed: nothing to estimate")
    if v.size < 3 * len(names):
        raise IdentificationError(
            f"{v.size} points cannot determine {len(names)} parameters; measure at least "
            f"{3 * len(names)} velocities")
    if np.any(v == 0.0):
        raise IdentificationError(
            "samples at v = 0 cannot be used: friction at rest is anywhere in [-Fs, Fs]; "
            "remove them or use a presliding test")
    if np.sum(v > 0) < 2 or np.sum(v < 0) < 2:
        raise IdentificationError(
            "the velocities are all of one sign: measure both directions (the symmetric model "
            "otherwise confuses Coulomb friction with a force offset)")
    speed = np.abs(v)
    if speed.max() < 10.0 * speed.min():
        raise IdentificationError(
            f"the speeds span only {speed.min():.3g} to {speed.max():.3g} m/s; the Stribeck "
            "curve needs at least a decade (low speeds near breakaway and fast sliding)")
    sgn = np.sign(v)
    # starting values from the data
    order = np.argsort(speed)
    fast = order[-max(v.size // 3, 2):]
    slope, intercept = np.polyfit(speed[fast], force[fast] * sgn[fast], 1)
    start = {"fc": max(intercept, 1e-6 * np.max(np.abs(force))),
             "sigma2": max(slope, 0.0)}
    slow = order[:max(v.size // 10, 2)]
    start["fs"] = max(float(np.mean(force[slow] * sgn[slow])), start["fc"] * 1.01)
    excess = force * sgn - start["fc"] - start["sigma2"] * speed
    half = speed[np.abs(excess) < 0.5 * (start["fs"] - start["fc"])]
    start["vs"] = float(half.min()) if half.size else float(np.sqrt(speed.min() * speed.max()))
    start["delta"] = 1.0
    lower = {"fc": 0.0, "fs": 0.0, "vs": 1e-3 * speed.min(), "delta": 0.05, "sigma2": 0.0}
    upper = {"fc": np.inf, "fs": np.inf, "vs": 1e3 * speed.max(), "delta": 20.0,
             "sigma2": np.inf}

    def full(x):
        vals = dict(fixed)
        vals.update(zip(names, x, strict=True))
        return vals

    def model(vals):
        e = np.exp(-(speed / vals["vs"]) ** vals["delta"])
        return (vals["fc"] + (vals["fs"] - vals["fc"]) * e) * sgn + vals["sigma2"] * v

    def residual(x):
        return model(full(x)) - force

    def jacobian(x):
        vals = full(x)
        r = speed / vals["vs"]
        rd = r ** vals["delta"]
        e = np.exp(-rd)
        dfs = vals["fs"] - vals["fc"]
        cols = {"fc": sgn * (1.0 - e), "fs": sgn * e,
                "vs": sgn * dfs * e * vals["delta"] * rd / vals["vs"],
                "delta": -sgn * dfs * e * rd * np.log(r), "sigma2": v}
        return np.column_stack([cols[n] for n in names])

    x0 = np.array([start[n] for n in names])
    lo = np.array([lower[n] for n in names])
    hi = np.array([upper[n] for n in names])
    x0 = np.clip(x0, lo + 1e-12 * np.abs(lo), hi)
    sol = optimize.least_squares(residual, x0, jac=jacobian, bounds=(lo, hi), x_scale="jac",
                                 xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=2000)
    vals = full(sol.x)
    if vals["fs"] < vals["fc"]:
        raise IdentificationError(
            f"the fit gives Fs = {vals['fs']:.4g} N below Fc = {vals['fc']:.4g} N: the data "
            "show no Stribeck rise at low speed; fix fs = fc or measure slower")
    if "vs" in names and not speed.min() <= vals["vs"] <= speed.max():
        raise IdentificationError(
            f"the estimated Stribeck velocity {vals['vs']:.3g} m/s lies outside the measured "
            f"speeds [{speed.min():.3g}, {speed.max():.3g}] m/s, so the data cannot determine "
            "it; measure around it or fix vs")
    at_bound = [n for n, active in zip(names, sol.active_mask, strict=True) if active]
    if at_bound:
        raise IdentificationError(
            f"the fit drives {at_bound} to the bound of its range, so the data cannot "
            "determine it; measure the missing speed range (the Stribeck dip near vs) or fix it")
    cov = _covariance(jacobian(sol.x), sol.fun, names, "steady-state")
    _check_determined(names, sol.x, cov, "steady-state")
    base = base if base is not None else LuGreParameters.named("bianchi2014")
    params = dataclasses.replace(base, **vals)
    res = -sol.fun
    return FrictionFit(names=names, values=np.array(sol.x), standard_errors=np.sqrt(np.diag(cov)),
                       covariance=cov, fixed=types.MappingProxyType(dict(fixed)),
                       parameters=params, residuals=res, rms=float(np.sqrt(np.mean(res**2))),
                       kind="steady_state")


def fit_presliding(t, displacement, force, sliding: LuGreParameters) -> FrictionFit:
    """Fit the bristle stiffness sigma0 and damping sigma1 to a presliding time history.

    Parameters
    ----------
    t : array_like
        Strictly increasing sample times [s].
    displacement : array_like
        Relative displacement of the contact [m] (e.g. a linear encoder), smooth enough to be
        differentiated through a cubic spline; the force errors are taken to dominate.
    force : array_like
        Measured friction force [N].
    sliding : LuGreParameters
        Supplies the steady-state parameters (Fc, Fs, vs, delta, sigma2), e.g. from
        :func:`fit_steady_state`; its sigma0 and sigma1 are not used.

    Returns
    -------
    FrictionFit
        Estimates of ``sigma0`` [N/m], ``sigma1`` [N s/m] and the nuisance ``f0`` [N], the
        bristle force sigma0 z at ``t[0]`` (the record need not start at rest).

    Raises
    ------
    IdentificationError
        Fewer than 20 samples; no motion; no velocity reversal (so no presliding transition);
        parameters the data cannot determine.

    Notes
    -----
    The model force is :func:`servotune.friction.simulate_lugre` driven by the measured
    displacement. sigma0 is searched on a logarithmic grid first (between Fs over the stroke
    and 1e4 times that), then refined with ``least_squares`` in (log sigma0, sigma1, f0/Fs).
    """
    t = _check_vector("t", t)
    x = _check_vector("displacement", displacement)
    force = _check_vector("force", force)
    if not t.size == x.size == force.size:
        raise ValueError("t, displacement and force must have the same length")
    if t.size < 20:
        raise IdentificationError(f"{t.size} samples are too few; record at least 20")
    if np.any(np.diff(t) <= 0.0):
        raise ValueError("t must be strictly increasing")
    stroke = float(np.ptp(x))
    if stroke == 0.0:
        raise IdentificationError("the displacement is constant: there is no presliding motion")
    dx = np.diff(x)
    dx = dx[np.abs(dx) > 1e-9 * stroke]
    if dx.size == 0 or np.all(dx > 0) or np.all(dx < 0):
        raise IdentificationError(
            "the displacement never reverses, so the record holds no presliding transition; "
            "record small back-and-forth motions (e.g. sinusoids of a few um)")
    fs = sliding.fs
    span = float(t[-1] - t[0])

    def simulate(sigma0, sigma1, f0):
        p = dataclasses.replace(sliding, sigma0=sigma0, sigma1=sigma1)
        return simulate_lugre(p, t, displacement=x, z0=f0 / sigma0).force

    def residual(q):
        sigma0 = math.exp(q[0])
        return simulate(sigma0, q[1] * sigma0 * span, q[2] * fs) - force

    f0_start = float(np.clip(force[0], -fs, fs)) / fs
    grid = np.geomspace(fs / stroke, 1e4 * fs / stroke, 25)
    costs = [float(np.sum(residual(np.array([math.log(s), 0.0, f0_start])) ** 2)) for s in grid]
    q0 = np.array([math.log(grid[int(np.argmin(costs))]), 1e-6, f0_start])
    sol = optimize.least_squares(residual, q0, bounds=([-np.inf, 0.0, -1.0], [np.inf, np.inf, 1.0]),
                                 x_scale="jac", diff_step=1e-7, xtol=1e-12, ftol=1e-12,
                                 max_nfev=400)
    sigma0 = math.exp(sol.x[0])
    values = np.array([sigma0, sol.x[1] * sigma0 * span, sol.x[2] * fs])
    # Jacobian in natural units: d/d sigma0 = d/dq0 / sigma0; sigma1 = q1 sigma0 span
    jac_q = sol.jac
    dq_dp = np.array([
        [1.0 / sigma0, 0.0, 0.0],
        [-sol.x[1] / sigma0, 1.0 / (sigma0 * span), 0.0],
        [0.0, 0.0, 1.0 / fs],
    ])
    jac = jac_q @ dq_dp
    cov = _covariance(jac, sol.fun, PRESLIDING_NAMES, "presliding")
    se = np.sqrt(np.diag(cov))
    _check_determined(PRESLIDING_NAMES[:1], values[:1], cov[:1, :1], "presliding")
    params = dataclasses.replace(sliding, sigma0=values[0], sigma1=values[1])
    res = -sol.fun
    return FrictionFit(names=PRESLIDING_NAMES, values=values, standard_errors=se, covariance=cov,
                       fixed=types.MappingProxyType({}), parameters=params, residuals=res,
                       rms=float(np.sqrt(np.mean(res**2))), kind="presliding")

