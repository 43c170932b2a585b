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
* :func:`describing_function`: the full LuGre element, from its periodic steady state computed
  as :func:`servotune.friction.lugre_cycle` does, over half a period (the state is
  antisymmetric), vectorised over amplitudes and frequencies.

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

from ..validation import positive_array
from . import _exponential
from .lugre import LuGreParameters, _rate, _steady_deflection, micro_damping

__all__ = [
    "DESCRIBING_FUNCTION_STEPS",
    "describing_function",
    "equivalent_damping_stiction",
    "stiction_describing_function",
    "stiction_peak_damping",
]


#: Steps per period of :func:`describing_function` (see its convergence study).
DESCRIBING_FUNCTION_STEPS = 512
#: Grading of the phase steps towards the reversals (see :func:`describing_function`): the
#: steps next to a reversal are GRADING times the phase over which the friction changes there,
#: and at least MIN_BETA times the uniform step.
GRADING = 4.0
MIN_BETA = 0.02


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
    fs = positive_array("equivalent_damping_stiction:", "fs", fs, "N")
    sigma0 = positive_array("equivalent_damping_stiction:", "sigma0", sigma0, "N/m")
    amplitude = positive_array("equivalent_damping_stiction:", "amplitude", amplitude, "m")
    omega = positive_array("equivalent_damping_stiction:", "omega", omega, "rad/s")
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
    """Return where the stiction cycle damps most: ``A = 2 Fs/sigma0``, ``Ceq = sigma0/(pi w)``.

    The maximum over A of :func:`equivalent_damping_stiction` (see its Notes).

    Parameters
    ----------
    fs : array_like
        Static friction force Fs [N], > 0.
    sigma0 : array_like
        Presliding (bristle) stiffness [N/m], > 0.
    omega : array_like
        Angular frequency w [rad/s], > 0. All three broadcast.

    Returns
    -------
    amplitude : numpy.ndarray
        The amplitude of the maximum, 2 Fs/sigma0 [m].
    ceq_max : numpy.ndarray
        The maximum equivalent damping, sigma0/(pi w) [N s/m].

    Raises
    ------
    ValueError
        If a value is not positive and finite.

    Examples
    --------
    >>> a, c = stiction_peak_damping(6013.0, 5.9e9, 2 * math.pi * 20.0)
    >>> round(float(a) * 1e6, 3), round(float(c) / 1e7, 4)
    (2.038, 1.4945)
    """
    fs = positive_array("stiction_peak_damping:", "fs", fs, "N")
    sigma0 = positive_array("stiction_peak_damping:", "sigma0", sigma0, "N/m")
    omega = positive_array("stiction_peak_damping:", "omega", omega, "rad/s")
    return 2.0 * fs / sigma0, sigma0 / (math.pi * omega)


def describing_function(params: LuGreParameters, amplitude, omega,
                        n_steps: int = DESCRIBING_FUNCTION_STEPS):
    """Equivalent damping and stiffness of the LuGre element from its periodic steady state.

    Parameters
    ----------
    params : LuGreParameters
        The LuGre element (sigma0 [N/m], sigma1, sigma2 [N s/m], Fc, Fs [N], vs [m/s] and the
        optional micro-damping decay speed); axis totals give axis-total Ceq and Keq.
    amplitude : array_like
        Displacement amplitudes A [m], > 0.
    omega : array_like
        Angular frequencies w [rad/s], > 0; broadcast against ``amplitude`` (pass
        ``amplitude[:, None]`` and ``omega[None, :]`` for a table).
    n_steps : int
        Integration steps per period, a multiple of 4 (>= 8). The default
        (:data:`DESCRIBING_FUNCTION_STEPS` = 512) comes from the convergence study below.

    Returns
    -------
    (ceq, keq) : tuple of numpy.ndarray
        ``Ceq = E / (pi w A^2)`` [N s/m] with E the energy dissipated per cycle, and the
        first-harmonic stiffness Keq [N/m], of the broadcast shape.

    Raises
    ------
    ValueError
        If an amplitude or frequency is not positive and finite, or ``n_steps`` is not a
        multiple of 4 >= 8.

    See Also
    --------
    servotune.analysis.compliance_curve : The compliance with an ``equivalent`` contact, whose
        Ceq and Keq this gives (:func:`servotune.plant.friction_contact`).
    servotune.simulate.simulator.simulate : The time response with the full LuGre law, the
        check of the linear equivalent.
    stiction_describing_function : The closed form of the paper's idealised cycle.

    Notes
    -----
    The periodic state is computed as by :func:`servotune.friction.lugre_cycle` (exponential
    steps in the bristle time, the reversals on nodes, Simpson's rule per half period), with
    two differences:

    * only half a period is integrated: under x = A sin(w t) the LuGre equation is odd in
      (z, v), so the periodic state is antisymmetric, ``z(theta + pi) = -z(theta)``. With
      ``z -> P z + B`` the map over the half period from the reversal at x = -A, the periodic
      state starts at ``z0 = -B / (1 + P)``, and F cos(theta) and F sin(theta) integrate to
      the same over both halves;
    * the phase steps are graded towards the reversals, where the friction changes over a
      phase of about ``d = min(v_c / (A w), sqrt(2 Fs / (sigma0 A)))`` (the Stribeck
      velocity, or the micro-damping decay speed if smaller, reached; the presliding
      deflection Fs/sigma0 taken up): ``theta = -pi/2 + pi g(s)`` with s uniform and
      ``g(s) = s - (1 - beta) sin(2 pi s) / (2 pi)``, so the steps there are beta times the
      uniform ones, ``beta = clip(4 d, 0.02, 1)``; slow small strokes keep uniform steps.

    Unlike the closed-form stiction cycle, the LuGre element dissipates at any amplitude: its
    bristle damping gives Ceq -> sigma1 + sigma2 and Keq -> sigma0 as A -> 0 (the presliding
    linearisation), and its exponential presliding curve dissipates before Fs is reached. At
    large amplitude both tend to the Coulomb-like 4 g / (pi w A) (with g the friction level)
    plus sigma2. A velocity-dependent micro-damping (``params.sigma1_decay_speed``) enters
    through the force of the cycle: the small-amplitude limit keeps sigma1 + sigma2, while
    strokes faster than v_d lose the bristle damping.

    **Convergence study behind the default** (``python benchmarks/friction_describing_function.py
    --convergence``; the table is in benchmarks/README.md). Error of the describing function
    N = Keq + j w Ceq, ``|N_n - N_ref| / |N_ref|``, against n = 65536 steps (which agrees with
    scipy's Radau at rtol 1e-10 to 4e-12 in the tests' cases), for the Bianchi 2014 and
    Canudas de Wit 1995 parameters and Bianchi 2014 with a micro-damping decay speed of
    1 mm/s, 21 amplitudes from 0.01 to 1000 Fs/sigma0 and 7 frequencies from 1 Hz to 1 kHz
    (peak speeds up to 640 vs, 94,000 vs for Canudas): it falls at fourth order in 1/n, and
    the largest error over the study is 4e-4 at 256 steps, 5e-5 at 512 and 7e-6 at 1024 (for
    Ceq alone 1e-5, 7e-7 and 6e-8); the largest errors are for millimetre strokes at tens of
    Hz (A w ~ 6-20 vs). 512 steps per period, the default, give N to 1e-4 throughout. With
    uniform steps (as ``lugre_cycle``) the same study leaves 1e-3 at 2048 steps and 2.4e-4 at
    4096 (the micro-damping set at 1 kHz).

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
    amplitude = positive_array("describing_function:", "amplitude", amplitude, "m")
    omega = positive_array("describing_function:", "omega", omega, "rad/s")
    n_steps = int(n_steps)
    if n_steps < 8 or n_steps % 4:
        raise ValueError(f"n_steps must be a multiple of 4 and >= 8, got {n_steps}")
    amplitude, omega = np.broadcast_arrays(amplitude, omega)
    shape = amplitude.shape
    a_col = amplitude.reshape(-1, 1)
    w_col = omega.reshape(-1, 1)
    half = n_steps // 2
    # phase grid over the half period, graded towards the reversals where the stroke is fast
    # against the Stribeck (or micro-damping) speed: theta = -pi/2 + pi g(s), s uniform,
    # g(s) = s - (1 - beta) sin(2 pi s) / (2 pi), steps beta times the uniform ones there
    v_char = params.vs if params.sigma1_decay_speed is None else min(
        params.vs, params.sigma1_decay_speed)
    width = np.minimum(v_char / (a_col * w_col),
                       np.sqrt(2.0 * params.fs / (params.sigma0 * a_col)))
    beta = np.clip(GRADING * width, MIN_BETA, 1.0)     # (rows, 1)
    s_nodes = np.arange(half + 1) / half
    g = s_nodes - (1.0 - beta) * np.sin(2.0 * math.pi * s_nodes) / (2.0 * math.pi)
    theta = -0.5 * math.pi + math.pi * g
    theta[:, 0] = -0.5 * math.pi   # exact reversals
    theta[:, -1] = 0.5 * math.pi
    dtheta_ds = math.pi * (1.0 - (1.0 - beta) * np.cos(2.0 * math.pi * s_nodes))

    def velocity(th):
        return a_col * w_col * np.cos(th)

    def rate(th):  # bristle time per radian of phase
        return _rate(params, velocity(th)) / w_col

    th0, th1 = theta[:, :-1], theta[:, 1:]
    h1, h2 = _exponential.half_step_increments(rate, th0, th1)
    v_nodes = velocity(theta)
    v_nodes[:, [0, half]] = 0.0
    zss_mid = _steady_deflection(params, velocity(0.5 * (th0 + th1)))
    zss = _steady_deflection(params, v_nodes)
    sliding = params.fs / params.sigma0  # z_ss next to a reversal (v > 0 on this half)
    zss[:, [0, half]] = sliding
    alpha, beta_ = _exponential.step_coefficients(h1, h2, zss[:, :-1], zss_mid, zss[:, 1:])
    p, b = _exponential.affine_scan(alpha, beta_)
    z_start = -b[:, -1] / (1.0 + p[:, -1])
    z = np.concatenate([z_start[:, None], p * z_start[:, None] + b], axis=-1)
    zdot = v_nodes - _rate(params, v_nodes) * z
    force = params.sigma0 * z + micro_damping(params, v_nodes) * zdot + params.sigma2 * v_nodes
    simpson = np.ones(half + 1)  # Simpson in s over the half period, doubled
    simpson[1:-1:2] = 4.0
    simpson[2:-1:2] = 2.0
    weights = (2.0 / (3.0 * half)) * simpson * dtheta_ds
    energy = a_col[:, 0] * np.sum(force * np.cos(theta) * weights, axis=-1)
    keq = np.sum(force * np.sin(theta) * weights, axis=-1) / (math.pi * a_col[:, 0])
    ceq = energy / (math.pi * w_col[:, 0] * a_col[:, 0] ** 2)
    return ceq.reshape(shape), keq.reshape(shape)
