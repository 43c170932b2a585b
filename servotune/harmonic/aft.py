"""The alternating frequency-time (AFT) scheme for the guide-way friction forces.

Harmonic balance works with Fourier coefficients; a friction law works in time. AFT goes from
one to the other and back (Cameron and Griffin 1989; Krack and Gross 2019, sec 3.5)::

    pad displacement harmonics X_k  --(j k w X_k, inverse FFT, + mean speed V)-->  v(t_i)
    v(t_i) --(law on its periodic orbit)--> F(t_i) --(FFT)--> friction harmonics F_k

on N equally spaced instants t_i = i T / N of one period T = 2 pi / w. Friction laws are reached
only through :func:`periodic_friction_force`: a law object with a method
``periodic_force(velocity, period, share=1.0)`` is asked directly (the interface of the
simulation's law classes, so that a new law works here unchanged); the LuGre law without that
method goes to :func:`servotune.friction.periodic.lugre_periodic_force`; viscous damping is
linear (F = c v).

Conventions: a real periodic signal is ``x(t) = x_0 + sum_{k=1..H} Re(X_k e^{j k w t})``.

References
----------
T. M. Cameron, J. H. Griffin, "An alternating frequency/time domain method for calculating the
steady-state response of nonlinear dynamic systems", J. Applied Mechanics 56 (1989) 149-154.
M. Krack, J. Gross, "Harmonic Balance for Nonlinear Vibration Problems", Springer (2019).
"""

from __future__ import annotations

import numpy as np

from ..friction.lugre import LuGreParameters
from ..friction.periodic import lugre_periodic_force, lugre_periodic_jacobian

__all__ = ["periodic_friction_force", "periodic_friction_jacobian", "samples_from_harmonics",
           "harmonics_from_samples"]


def periodic_friction_force(law, velocity, period: float, share: float = 1.0) -> np.ndarray:
    """Friction force [N] of one pad on the periodic orbit of its law, for velocity samples.

    The one place where harmonic balance calls a friction law.

    Parameters
    ----------
    law : object
        A law with ``periodic_force(velocity, period, share=1.0) -> ndarray`` (duck-typed: any
        :class:`servotune.simulate.PadFriction` that has it), a
        :class:`servotune.simulate.LuGreFriction` or :class:`LuGreParameters` (axis totals;
        :func:`~servotune.friction.periodic.lugre_periodic_force`), or a
        :class:`servotune.simulate.ViscousFriction` (``F = c v``).
    velocity : array_like, shape (N,) or (n, N)
        Pad sliding velocity [m/s] at N equally spaced instants over one period (a row per
        pad; a law's ``periodic_force`` is asked row by row).
    period : float
        The period T [s] (2 pi / w).
    share : float
        The pad's share of the axis-total law, dimensionless (1/n for n equal pads): a LuGre
        law is scaled by it (:meth:`~servotune.friction.lugre.LuGreParameters.scaled`), a
        viscous coefficient multiplied, and a law with ``periodic_force`` receives it.

    Returns
    -------
    numpy.ndarray, shape of ``velocity``
        The pad's friction force [N] at the instants (along positive velocity).

    Raises
    ------
    TypeError
        If the law has no ``periodic_force`` method, is not a LuGre law (a
        :class:`LuGreParameters` or an object whose ``params`` is one) and is not linear
        viscous damping (an attribute ``c`` and ``nonlinear`` false).

    See Also
    --------
    servotune.friction.periodic.lugre_periodic_force

    Examples
    --------
    Viscous damping is linear: a quarter of c = 4000 N s/m at 1 m/s gives 1000 N.

    >>> from servotune.simulate import ViscousFriction
    >>> periodic_friction_force(ViscousFriction(4000.0), np.ones(4), 0.1, share=0.25)
    array([1000., 1000., 1000., 1000.])
    """
    method = getattr(law, "periodic_force", None)
    if callable(method):
        v = np.asarray(velocity, dtype=float)
        if v.ndim == 2:                       # the interface takes one contact at a time
            return np.array([method(row, period, share=share) for row in v], dtype=float)
        return np.asarray(method(v, period, share=share), dtype=float)
    params = law if isinstance(law, LuGreParameters) else getattr(law, "params", None)
    if isinstance(params, LuGreParameters):
        if share != 1.0:
            params = params.scaled(share)
        return lugre_periodic_force(params, velocity, period)
    c = getattr(law, "c", None)
    if c is not None and not getattr(law, "nonlinear", False):
        return float(c) * share * np.asarray(velocity, dtype=float)
    raise TypeError(f"{type(law).__name__} is not a friction law harmonic balance can use: give "
                    "it a method periodic_force(velocity, period, share=1.0)")


def periodic_friction_jacobian(law, velocity, period: float, share: float = 1.0,
                               basis=None):
    """Friction force and its derivative by the velocity samples, where the law gives it.

    Parameters
    ----------
    law, velocity, period, share
        As :func:`periodic_friction_force` (velocity [m/s], shape (N,) or (n, N); period [s]).
    basis : array_like, shape (N, m), optional
        Velocity directions along which the derivative is wanted [m/s per unit of the m
        coordinates] (default: every sample, the identity).

    Returns
    -------
    tuple of numpy.ndarray or None
        ``(force [N] (N,), dforce_dvelocity @ basis [N s/m] (N, m))`` (with a leading pad axis
        for 2-D velocities): from the law's
        ``periodic_force_jacobian(velocity, period, share=1.0)`` (times the basis) when it has
        one, from
        :func:`~servotune.friction.periodic.lugre_periodic_jacobian` for a LuGre law that
        :func:`periodic_friction_force` evaluates itself, ``c share I`` for viscous damping;
        None otherwise (the caller then differentiates :func:`periodic_friction_force`
        numerically).

    See Also
    --------
    periodic_friction_force
    """
    method = getattr(law, "periodic_force_jacobian", None)
    if callable(method):
        v = np.asarray(velocity, dtype=float)
        rows = [method(row, period, share=share) for row in np.atleast_2d(v)]
        force = np.array([f for f, _ in rows], dtype=float)
        jac = np.array([j for _, j in rows], dtype=float)
        jac = jac if basis is None else jac @ basis
        return (force, jac) if v.ndim == 2 else (force[0], jac[0])
    if callable(getattr(law, "periodic_force", None)):
        return None
    params = law if isinstance(law, LuGreParameters) else getattr(law, "params", None)
    if isinstance(params, LuGreParameters):
        if share != 1.0:
            params = params.scaled(share)
        return lugre_periodic_jacobian(params, velocity, period, basis)
    c = getattr(law, "c", None)
    if c is not None and not getattr(law, "nonlinear", False):
        v = np.asarray(velocity, dtype=float)
        eye = np.eye(v.shape[-1]) if basis is None else np.asarray(basis, dtype=float)
        return float(c) * share * v, np.broadcast_to(float(c) * share * eye,
                                                     v.shape[:-1] + eye.shape).copy()
    return None


def samples_from_harmonics(coefficients, samples: int, mean=0.0) -> np.ndarray:
    """Time samples of ``x(t) = mean + sum_k Re(X_k e^{j k w t})`` at ``t_i = i T / N``.

    Parameters
    ----------
    coefficients : array_like, complex, shape (..., H)
        X_1 .. X_H.
    samples : int
        N (> 2 H, so that the harmonics are not aliased).
    mean : float or array_like
        The constant part (broadcast over the leading axes).

    Returns
    -------
    numpy.ndarray, shape (..., N)
        ``x(t_i)``, i = 0..N-1, in the unit of the coefficients.

    Raises
    ------
    ValueError
        If N is not above 2 H.

    Notes
    -----
    An inverse real FFT of the one-sided spectrum ``N mean`` (bin 0) and ``N X_k / 2`` (bin k),
    the synthesis step of AFT (Krack and Gross 2019, sec 3.5).

    See Also
    --------
    harmonics_from_samples : the inverse.
    """
    c = np.asarray(coefficients, dtype=complex)
    h = c.shape[-1]
    if samples <= 2 * h:
        raise ValueError(f"{samples} samples cannot carry {h} harmonics; take N > 2 H")
    spectrum = np.zeros((*c.shape[:-1], samples // 2 + 1), dtype=complex)
    spectrum[..., 1:h + 1] = 0.5 * samples * c
    spectrum[..., 0] = samples * np.asarray(mean, dtype=float)
    return np.fft.irfft(spectrum, samples, axis=-1)


def harmonics_from_samples(values, harmonics: int) -> tuple[np.ndarray, np.ndarray]:
    """Mean and harmonics 1..H of equally spaced samples over one period.

    Parameters
    ----------
    values : array_like, shape (..., N)
        Samples at N equally spaced instants of one period.
    harmonics : int
        H, below N / 2 (not checked: at H = N / 2 the last coefficient, the Nyquist bin, comes
        back doubled, and above it fewer than H coefficients come back).

    Returns
    -------
    mean : numpy.ndarray, shape (...)
        ``x_0``, the average of the samples, in their unit.
    coefficients : numpy.ndarray, complex, shape (..., H)
        ``X_1 .. X_H``, twice the real FFT bins 1..H divided by N (the analysis step of AFT,
        Krack and Gross 2019, sec 3.5).

    See Also
    --------
    samples_from_harmonics : the inverse.

    Examples
    --------
    >>> t = np.arange(8) / 8
    >>> m, c = harmonics_from_samples(1.0 + 2.0 * np.cos(2 * np.pi * t - 0.5), 2)
    >>> round(float(m), 12), complex(np.round(c[0], 8)), float(abs(c[1])) < 1e-12
    (1.0, (1.75516512-0.95885108j), True)
    """
    v = np.asarray(values, dtype=float)
    n = v.shape[-1]
    if not 1 <= harmonics < n / 2:
        raise ValueError(f"harmonics_from_samples: {n} samples resolve harmonics 1 to "
                         f"{(n - 1) // 2}, not {harmonics} (give more samples than twice the "
                         "harmonics)")
    spectrum = np.fft.rfft(v, axis=-1)
    return spectrum[..., 0].real / n, 2.0 * spectrum[..., 1:harmonics + 1] / n
