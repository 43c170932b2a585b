"""Equivalent viscous damping of friction by the describing function (paper sec 4.2, Eq 8-10).

A friction element driven by x = A sin(w t) dissipates, per cycle, the area of its hysteresis
loop. The viscous damper that dissipates the same energy has (Bianchi et al. 2014, Eq 8)::

    Ceq = area / (pi w A^2)

and, more generally, the first harmonic of the periodic force defines the describing function
``F ~ Keq x + Ceq dx/dt``::

    Keq = (1 / (pi A)) int_0^2pi F sin(theta) dtheta
    Ceq = (1 / (pi A w)) int_0^2pi F cos(theta) dtheta        (x = A sin(theta), theta = w t)

Two describing functions are provided:

* :func:`stiction_describing_function` / :func:`equivalent_damping_stiction`: the paper's
  idealised stiction cycle (Fig 6) in closed form: an elasto-plastic (Jenkins) element, a spring
  sigma0 in series with a Coulomb slider Fs.
* :func:`describing_function`: the full LuGre element, from its simulated periodic steady state
  (:func:`servotune.friction.lugre_cycle`), vectorised over amplitudes and frequencies.

References
----------
G. Bianchi, S. Cagna, N. Cau, F. Paolucci, "Analysis of vibration damping in machine tools",
Procedia CIRP 21 (2014) 367-372, sec 4.2, Eq 8-10, Fig 6.
A. Gelb, W. E. Vander Velde, Multiple-Input Describing Functions and Nonlinear System Design,
McGraw-Hill (1968), ch 2 (describing functions of hysteretic nonlinearities).
"""

from __future__ import annotations

import math

import numpy as np

from .lugre import DEFAULT_CYCLE_STEPS, LuGreParameters, lugre_cycle

__all__ = [
    "describing_function",
    "equivalent_damping_stiction",
    "stiction_describing_function",
    "stiction_peak_damping",
]


def _positive(name: str, value) -> np.ndarray:
    value = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(value)) or np.any(value <= 0.0):
        raise ValueError(f"{name} must be positive and finite")
    return value


def equivalent_damping_stiction(fs, sigma0, amplitude, omega) -> np.ndarray:
    """Equivalent viscous damping of the paper's stiction cycle [N s/m] (Eq 8-10, corrected).

    Parameters
    ----------
    fs : array_like
        Static friction force Fs [N].
    sigma0 : array_like
        Presliding (bristle) stiffness [N/m].
    amplitude : array_like
        Displacement amplitude A [m].
    omega : array_like
        Angular frequency w [rad/s]. All four broadcast.

    Returns
    -------
    numpy.ndarray
        ``Ceq = 4 Fs (A - Fs/sigma0) / (pi w A^2)`` for A > Fs/sigma0, 0 below.

    Notes
    -----
    The cycle of Fig 6 (the LuGre transition made linear, sigma1 = sigma2 = 0): from a reversal
    the force changes with slope sigma0 by 2 Fs, over a displacement 2 Fs/sigma0, then slides at
    +-Fs. It is a parallelogram of height 2 Fs and width 2 (A - Fs/sigma0), so::

        area = 4 Fs (A - Fs/sigma0)                         (A > Fs/sigma0; 0 below)
        Ceq  = 4 Fs (A - Fs/sigma0) / (pi w A^2)
        max over A at A = 2 Fs/sigma0:  Ceq_max = sigma0 / (pi w)

    The printed Eq 9 and 10 carry half this area (area = 2 Fs (A - Fs/sigma0), maximum
    sigma0 / (2 pi w)) and say that sliding needs A >= 2 Fs/sigma0. Both disagree with the
    paper's own Fig 6 and Eq 8. With x = A sin(w t) the stroke is 2A; after each reversal the
    element sticks over 2 Fs/sigma0 of it and slides over the remaining 2 (A - Fs/sigma0), so
    sliding starts at A = Fs/sigma0 and the parallelogram of height 2 Fs encloses
    4 Fs (A - Fs/sigma0). An independent check: for A >> Fs/sigma0 the element is a Coulomb
    slider, whose equivalent damping is the classical 4 Fs / (pi w A) (the first harmonic of a
    square wave of height Fs); this form tends to it, the printed one to half of it. The tests
    check this form against the loop area of an exactly integrated elasto-plastic element.

    Examples
    --------
    The paper's axis at 20 Hz: the peak is sigma0 / (pi w), at A = 2 Fs/sigma0 (about 2 um).

    >>> w = 2 * math.pi * 20.0
    >>> c = equivalent_damping_stiction(6013.0, 5.9e9, 2 * 6013.0 / 5.9e9, w)
    >>> bool(abs(c / (5.9e9 / (math.pi * w)) - 1.0) < 1e-12)
    True
    >>> float(equivalent_damping_stiction(6013.0, 5.9e9, 1e-6, w))   # below Fs/sigma0
    0.0
    """
    fs = _positive("fs", fs)
    sigma0 = _positive("sigma0", sigma0)
    amplitude = _positive("amplitude", amplitude)
    omega = _positive("omega", omega)
    slip = np.maximum(amplitude - fs / sigma0, 0.0)
    return 4.0 * fs * slip / (math.pi * omega * amplitude**2)


def stiction_describing_function(fs, sigma0, amplitude, omega):
    """Equivalent damping and stiffness of the paper's stiction cycle, in closed form.

    Parameters
    ----------
    fs, sigma0, amplitude, omega : array_like
        As in :func:`equivalent_damping_stiction`.

    Returns
    -------
    (ceq, keq) : tuple of numpy.ndarray
        Equivalent damping [N s/m] (:func:`equivalent_damping_stiction`) and first-harmonic
        stiffness [N/m].

    Notes
    -----
    For the elasto-plastic element with a = Fs/sigma0 and A > a, let
    ``cos(beta) = 1 - 2 a / A`` (beta is the phase spent sticking after a reversal). Then::

        Keq = (sigma0 / pi) (beta - sin(2 beta) / 2)

    which equals sigma0 at A = a (beta = pi) and falls to 0 as A grows. Below A = a the element
    is a spring: Keq = sigma0, Ceq = 0. (Derived here by integrating F cos over the stick and
    slip arcs; the classical describing function of the Jenkins element, cf. Gelb and Vander
    Velde, ch 2.)

    Examples
    --------
    >>> c, k = stiction_describing_function(1.0, 1.0, [0.5, 1.0, 1e6], 1.0)
    >>> [float(x) for x in k[:2]], bool(k[2] < 1e-8)
    ([1.0, 1.0], True)
    """
    ceq = equivalent_damping_stiction(fs, sigma0, amplitude, omega)
    fs = np.asarray(fs, dtype=float)
    sigma0 = np.asarray(sigma0, dtype=float)
    amplitude = np.asarray(amplitude, dtype=float)
    ratio = np.clip(1.0 - 2.0 * fs / (sigma0 * amplitude), -1.0, 1.0)
    beta = np.arccos(ratio)
    keq = sigma0 / math.pi * (beta - 0.5 * np.sin(2.0 * beta))
    keq = np.where(amplitude <= fs / sigma0, sigma0 * np.ones_like(keq), keq)
    return ceq, np.broadcast_to(keq, ceq.shape).copy()


def stiction_peak_damping(fs, sigma0, omega) -> tuple[np.ndarray, np.ndarray]:
    """Where the stiction cycle damps most: ``(A = 2 Fs/sigma0, Ceq_max = sigma0/(pi w))``.

    Examples
    --------
    >>> a, c = stiction_peak_damping(6013.0, 5.9e9, 2 * math.pi * 20.0)
    >>> round(float(a) * 1e6, 3), round(float(c) / 1e7, 4)
    (2.038, 1.4945)
    """
    fs = _positive("fs", fs)
    sigma0 = _positive("sigma0", sigma0)
    omega = _positive("omega", omega)
    return 2.0 * fs / sigma0, sigma0 / (math.pi * omega)


def describing_function(params: LuGreParameters, amplitude, omega,
                        n_steps: int = DEFAULT_CYCLE_STEPS):
    """Equivalent damping and stiffness of the LuGre element from its periodic steady state.

    Parameters
    ----------
    params : LuGreParameters
    amplitude : array_like
        Displacement amplitudes A [m], > 0.
    omega : array_like
        Angular frequencies w [rad/s], > 0; broadcast against ``amplitude`` (pass
        ``amplitude[:, None]`` and ``omega[None, :]`` for a table).
    n_steps : int
        Integration steps per period (see :func:`servotune.friction.lugre_cycle`).

    Returns
    -------
    (ceq, keq) : tuple of numpy.ndarray
        ``Ceq = E / (pi w A^2)`` [N s/m] with E the energy dissipated per cycle, and the
        first-harmonic stiffness Keq [N/m], of the broadcast shape.

    Notes
    -----
    Unlike the closed-form stiction cycle, the LuGre element dissipates at any amplitude: its
    bristle damping gives Ceq -> sigma1 + sigma2 and Keq -> sigma0 as A -> 0 (the presliding
    linearisation), and its exponential presliding curve dissipates before Fs is reached. At
    large amplitude both tend to the Coulomb-like 4 g / (pi w A) (with g the friction level)
    plus sigma2. A velocity-dependent micro-damping (``params.sigma1_decay_speed``) enters
    through the force of the cycle: the small-amplitude limit keeps sigma1 + sigma2, while
    strokes faster than v_d lose the bristle damping.

    Examples
    --------
    Large strokes on the paper's axis at 20 Hz: the closed form and LuGre agree within 30 %.

    >>> p = LuGreParameters.named("bianchi2014")
    >>> w = 2 * math.pi * 20.0
    >>> ceq, keq = describing_function(p, 50e-6, w)
    >>> closed = equivalent_damping_stiction(p.fs, p.sigma0, 50e-6, w)
    >>> bool(abs(float(ceq) / float(closed) - 1.0) < 0.3)
    True
    """
    cycle = lugre_cycle(params, amplitude, omega, n_steps=n_steps)
    return cycle.ceq, cycle.keq
