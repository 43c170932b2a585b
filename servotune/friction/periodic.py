"""LuGre friction on its periodic orbit: the force for a given periodic sliding velocity.

For a prescribed periodic velocity v(t) the LuGre bristle equation (Bianchi et al. 2014, Eq 3;
Canudas de Wit et al. 1995)::

    dz/dt = v - a(v) z,        a(v) = sigma0 |v| / g(v),   g(v) = Fc + (Fs - Fc) e^{-|v/vs|^delta}
    F     = sigma0 z + sigma1 e(v) dz/dt + sigma2 v,        e(v) = exp(-(v/v_d)^2)  (or 1)

is *linear* in z. Its periodic orbit therefore has a closed form over one period, which is what
the alternating frequency-time scheme of a harmonic balance needs (Cameron and Griffin 1989;
Krack and Gross 2019, sec 3.5): the velocity is known on N equally spaced instants, and with v
held at the mean of its end values over each interval h = T/N the step is exact::

    z_{i+1} = E_i z_i + b_i,      E_i = exp(-a_i h),   b_i = u_i (1 - E_i) / a_i   (-> u_i h)

so that after one period ``z_N = Phi z_0 + psi`` with ``Phi = prod E_i = exp(-h sum a_i)``,
and the periodic orbit starts at ``z_0 = psi / (1 - Phi)``. No explicit time stepping: the
sliding bristle relaxes in ~1e-5 s (a h >> 1), which the exponential step takes exactly. When
the pads never move (Phi = 1) the orbit is z = 0.

References
----------
C. Canudas de Wit, H. Olsson, K. J. Astrom, P. Lischinsky, "A new model for control of systems
with friction", IEEE Trans. Automatic Control 40(3) (1995) 419-425.
H. Olsson et al., "Friction models and friction compensation", European Journal of Control 4
(1998) 176-195 (velocity-dependent micro-damping).
T. M. Cameron, J. H. Griffin, "An alternating frequency/time domain method for calculating the
steady-state response of nonlinear dynamic systems", J. Applied Mechanics 56 (1989) 149-154.
M. Krack, J. Gross, "Harmonic Balance for Nonlinear Vibration Problems", Springer (2019).
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014).
"""

from __future__ import annotations

import math

import numpy as np

from ..cache import cached_njit
from .lugre import LuGreParameters

__all__ = ["lugre_periodic_force", "lugre_periodic_state", "lugre_periodic_jacobian"]


@cached_njit
def _stribeck(au, fc, fs, vs, delta):
    """g(|u|) and dg/d|u| (one exponential; no power for delta = 1)."""
    x = au / vs
    if delta == 1.0:
        e = math.exp(-x)
        return fc + (fs - fc) * e, -(fs - fc) * e / vs
    xd = x ** delta
    e = math.exp(-xd)
    slope = -(fs - fc) * delta * xd / au * e if au > 0.0 else 0.0
    return fc + (fs - fc) * e, slope


@cached_njit
def _rate(u, sigma0, fc, fs, vs, delta):
    """a(u) = sigma0 |u| / g(u) [1/s]."""
    au = abs(u)
    if au == 0.0:
        return 0.0
    g, _ = _stribeck(au, fc, fs, vs, delta)
    return sigma0 * au / g


@cached_njit
def _periodic_orbit(v, h, sigma0, sigma1, sigma2, fc, fs, vs, delta, vd, z, force):
    n = v.size
    e_step = np.empty(n)
    b_step = np.empty(n)
    total = 0.0
    for i in range(n):
        u = 0.5 * (v[i] + v[(i + 1) % n])
        a = _rate(u, sigma0, fc, fs, vs, delta)
        ah = a * h
        total += ah
        e_step[i] = math.exp(-ah)
        if ah < 1e-12:
            b_step[i] = u * h
        else:
            b_step[i] = -u * math.expm1(-ah) / a
    one_minus_phi = -math.expm1(-total)
    z0 = 0.0
    if one_minus_phi > 1e-300:
        psi = 0.0
        for i in range(n):
            psi = e_step[i] * psi + b_step[i]
        z0 = psi / one_minus_phi
    zi = z0
    for i in range(n):
        z[i] = zi
        vi = v[i]
        a = _rate(vi, sigma0, fc, fs, vs, delta)
        zdot = vi - a * zi
        damp = sigma1
        if vd > 0.0:
            x = vi / vd
            damp = sigma1 * math.exp(-x * x)
        force[i] = sigma0 * zi + damp * zdot + sigma2 * vi
        zi = e_step[i] * zi + b_step[i]


@cached_njit
def _rate_and_slope(u, sigma0, fc, fs, vs, delta):
    """a(u) = sigma0 |u| / g(u) and da/du (0 at u = 0, where |u| has no derivative)."""
    au = abs(u)
    if au == 0.0:
        return 0.0, 0.0
    g, dg = _stribeck(au, fc, fs, vs, delta)
    sgn = 1.0 if u > 0.0 else -1.0
    return sigma0 * au / g, sigma0 * sgn * (1.0 / g - au * dg / (g * g))


@cached_njit
def _periodic_jacobian(v, h, sigma0, sigma1, sigma2, fc, fs, vs, delta, vd, basis, force, out):
    """Force on the periodic orbit and ``(dF/dv) @ basis`` (N x m) by forward sensitivities
    of the exact steps with the periodicity condition on them, in O(N m)."""
    n = v.size
    m = basis.shape[1]
    e_step = np.empty(n)
    b_step = np.empty(n)
    c_step = np.empty(n)
    de_step = np.empty(n)
    z = np.empty(n + 1)
    total = 0.0
    for i in range(n):
        u = 0.5 * (v[i] + v[(i + 1) % n])
        a, da = _rate_and_slope(u, sigma0, fc, fs, vs, delta)
        ah = a * h
        total += ah
        e_step[i] = math.exp(-ah)
        if ah < 1e-8:
            phi = h * (1.0 - 0.5 * ah)
            dphi = -0.5 * h * h
        else:
            phi = -math.expm1(-ah) / a
            dphi = (h * e_step[i] - phi) / a
        b_step[i] = u * phi
        c_step[i] = phi + u * dphi * da          # db/du; dE/du z_i is added below
        de_step[i] = -h * da * e_step[i]         # dE/du
    one_minus_phi = -math.expm1(-total)
    z0 = 0.0
    if one_minus_phi > 1e-300:
        psi = 0.0
        for i in range(n):
            psi = e_step[i] * psi + b_step[i]
        z0 = psi / one_minus_phi
    z[0] = z0
    for i in range(n):
        z[i + 1] = e_step[i] * z[i] + b_step[i]
        c_step[i] += de_step[i] * z[i]
    # the basis on the interval velocities u_j = (v_j + v_{j+1}) / 2
    bu = np.empty((n, m))
    for j in range(n):
        for k in range(m):
            bu[j, k] = 0.5 * (basis[j, k] + basis[(j + 1) % n, k])
    # W_i = sum_j (dz_i/du_j) bu_j:  W_0 = sum_j c_j prod_{l>j} E_l bu_j / (1 - Phi),
    # W_{i+1} = E_i W_i + c_i bu_i
    w = np.zeros(m)
    if one_minus_phi > 1e-300:
        tail = 1.0 / one_minus_phi
        for j in range(n - 1, -1, -1):
            for k in range(m):
                w[k] += c_step[j] * tail * bu[j, k]
            tail *= e_step[j]
    for i in range(n):
        vi = v[i]
        a, da = _rate_and_slope(vi, sigma0, fc, fs, vs, delta)
        damp = sigma1
        ddamp = 0.0
        if vd > 0.0:
            x = vi / vd
            damp = sigma1 * math.exp(-x * x)
            ddamp = -2.0 * x / vd * damp
        zi = z[i]
        zdot = vi - a * zi
        force[i] = sigma0 * zi + damp * zdot + sigma2 * vi
        dfdz = sigma0 - damp * a
        direct = ddamp * zdot + damp * (1.0 - da * zi) + sigma2
        for k in range(m):
            out[i, k] = dfdz * w[k] + direct * basis[i, k]
            w[k] = e_step[i] * w[k] + c_step[i] * bu[i, k]

@cached_njit
def _orbit_rows(v, h, sigma0, sigma1, sigma2, fc, fs, vs, delta, vd, z, force):
    for r in range(v.shape[0]):
        _periodic_orbit(v[r], h, sigma0, sigma1, sigma2, fc, fs, vs, delta, vd, z[r], force[r])


@cached_njit
def _jacobian_rows(v, h, sigma0, sigma1, sigma2, fc, fs, vs, delta, vd, basis, force, out):
    for r in range(v.shape[0]):
        _periodic_jacobian(v[r], h, sigma0, sigma1, sigma2, fc, fs, vs, delta, vd, basis,
                           force[r], out[r])


def _prepare(params, velocity, period):
    if not isinstance(params, LuGreParameters):
        raise TypeError("params must be LuGreParameters (axis total or one pad's share), e.g. "
                        "LuGreParameters.named('bianchi2014')")
    period = float(period)
    if not (math.isfinite(period) and period > 0.0):
        raise ValueError(f"period must be finite and > 0 s, got {period!r}")
    v = np.ascontiguousarray(velocity, dtype=float)
    if v.ndim not in (1, 2) or v.shape[-1] < 2:
        raise ValueError("velocity must be a 1-D array of at least 2 samples over one period "
                         f"[m/s] (or 2-D, one such row per contact), got shape {v.shape}")
    if not math.isfinite(float(np.sum(v))):
        raise ValueError("velocity samples must be finite")
    return v, period / v.shape[-1]


def lugre_periodic_state(params: LuGreParameters, velocity, period: float
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Bristle deflection and friction force on the LuGre periodic orbit.

    Parameters
    ----------
    params : LuGreParameters
        Friction of the contact (axis total, or one pad's share from
        :meth:`LuGreParameters.scaled`).
    velocity : array_like, shape (N,) or (n, N)
        Sliding velocity [m/s] at the N equally spaced instants ``t_i = i T / N`` of one period
        (a row per contact for n contacts with the same parameters).
    period : float
        The period T [s].

    Returns
    -------
    z : numpy.ndarray, shape of ``velocity``
        Bristle deflection [m] at the instants.
    force : numpy.ndarray, shape of ``velocity``
        Friction force [N] at the instants (positive along positive velocity).

    Raises
    ------
    TypeError
        If ``params`` are not :class:`LuGreParameters`.
    ValueError
        If the period is not finite and positive, or the velocity is not a finite 1-D or 2-D
        array of at least 2 samples per period.

    See Also
    --------
    lugre_periodic_force : the force alone.
    servotune.friction.lugre_force : the force for a given state.

    Notes
    -----
    The velocity is held at the mean of the two end samples over each interval and the bristle
    equation stepped exactly (module docstring), a second-order scheme in h = T/N.
    """
    v, h = _prepare(params, velocity, period)
    p = params
    vd = -1.0 if p.sigma1_decay_speed is None else float(p.sigma1_decay_speed)
    z = np.empty_like(v)
    force = np.empty_like(v)
    _orbit_rows(np.atleast_2d(v), h, p.sigma0, p.sigma1, p.sigma2, p.fc, p.fs, p.vs, p.delta,
                vd, np.atleast_2d(z), np.atleast_2d(force))
    return z, force


def lugre_periodic_force(params: LuGreParameters, velocity, period: float) -> np.ndarray:
    """Friction force [N] of LuGre on its periodic orbit for periodic velocity samples.

    Parameters
    ----------
    params : LuGreParameters
        Friction of the contact (axis total, or one pad's share).
    velocity : array_like, shape (N,) or (n, N)
        Sliding velocity [m/s] at N equally spaced instants over one period (a row per
        contact).
    period : float
        The period [s].

    Returns
    -------
    numpy.ndarray, shape of ``velocity``
        The friction force at the same instants, on the periodic orbit of the bristle state.

    Raises
    ------
    TypeError, ValueError
        As :func:`lugre_periodic_state`.

    See Also
    --------
    lugre_periodic_state : with the bristle deflection.
    servotune.harmonic.periodic_friction_force : the dispatch through which harmonic balance
        calls friction laws.

    Notes
    -----
    Exact for a velocity constant over each sample interval (module docstring). With
    ``sigma1_decay_speed`` = v_d the bristle damper is ``sigma1 exp(-(v/v_d)^2)`` (Olsson et al.
    1998).

    Examples
    --------
    Steady sliding at 30 mm/s gives the Stribeck curve, g(v) + sigma2 v:

    >>> p = LuGreParameters.named("bianchi2014")
    >>> f = lugre_periodic_force(p, np.full(64, 0.03), 0.02)
    >>> g = p.fc + (p.fs - p.fc) * np.exp(-3.0) + p.sigma2 * 0.03
    >>> bool(np.allclose(f, g, rtol=1e-9))
    True
    """
    return lugre_periodic_state(params, velocity, period)[1]


def lugre_periodic_jacobian(params: LuGreParameters, velocity, period: float, basis=None
                            ) -> tuple[np.ndarray, np.ndarray]:
    """Friction force on the LuGre periodic orbit and its derivative by the velocity samples.

    Parameters
    ----------
    params : LuGreParameters
        Friction of the contact (axis total, or one pad's share).
    velocity : array_like, shape (N,) or (n, N)
        Sliding velocity [m/s] at N equally spaced instants over one period (a row per
        contact).
    period : float
        The period [s].
    basis : array_like, shape (N, m), optional
        Velocity directions: the derivative is returned along them, ``(dF/dv) @ basis``, in
        O(N m) operations (default: the identity, the full N x N matrix).

    Returns
    -------
    force : numpy.ndarray, shape of ``velocity``
        As :func:`lugre_periodic_force`.
    jacobian : numpy.ndarray, shape (N, m) or (n, N, m)
        ``(dF_i / dv_l) @ basis`` [N s/m] of the discrete scheme (exact derivatives of the
        exponential steps and of the periodicity condition ``z_0 = psi / (1 - Phi)``).

    Raises
    ------
    TypeError, ValueError
        As :func:`lugre_periodic_state`; ValueError also for a ``basis`` that is not of shape
        (N, m).

    See Also
    --------
    lugre_periodic_force

    Notes
    -----
    With ``S_ij = dz_i/du_j`` (u_j the interval velocity) the steps give
    ``S_(i+1) = E_i S_i + c_i e_i``, ``c_i = (dE_i/du_i) z_i + db_i/du_i``, and periodicity
    ``S_0 = S_N``, so ``S_0j = c_j prod_(m>j) E_m / (1 - Phi)``. The products with the
    basis follow the same recursion, ``W_(i+1) = E_i W_i + c_i B_i``, so the full matrix is
    never formed. At v = 0 the derivative of |v| is taken as 0.
    """
    v, h = _prepare(params, velocity, period)
    p = params
    vd = -1.0 if p.sigma1_decay_speed is None else float(p.sigma1_decay_speed)
    n = v.shape[-1]
    basis = np.eye(n) if basis is None else np.ascontiguousarray(basis, dtype=float)
    if basis.ndim != 2 or basis.shape[0] != n:
        raise ValueError(f"basis must have shape (N, m) with N = {n}, got {basis.shape}")
    force = np.empty_like(v)
    jac = np.empty((*v.shape, basis.shape[1]))
    _jacobian_rows(np.atleast_2d(v), h, p.sigma0, p.sigma1, p.sigma2, p.fc, p.fs, p.vs,
                   p.delta, vd, basis, np.atleast_2d(force), jac.reshape(-1, n, basis.shape[1]))
    return force, jac
