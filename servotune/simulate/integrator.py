"""Exponential collocation integrator for a linear system with a few stiff nonlinear inputs.

The axis is ``dX/dt = A X + B_u u(t) + B_r r``, with one nonlinear input per pad,
``r_p = r(v_p, z_p)`` (:mod:`servotune.simulate.system`), or a few (remainder k is component
``k // n_pads`` of the law at pad ``k % n_pads``). A holds the structure (with its high
modes), the drive and the linearised contacts, including the bristle damper sigma1 that acts in
microseconds on the pads; r holds what is left of the LuGre law, stiff while the pads slide
(time constant g/(sigma0 |v|) ~ 1e-5 s). Both stiffnesses are handled without small steps:

* **Linear part exactly** (exponential integrator): A = V diag(lambda) V^-1 once (after
  balancing), so the flow over a step is a diagonal map, exact for any step however stiff the
  modes; conjugate pairs are carried by one complex coordinate.
* **Known inputs** u(t) are interpolated by the cubic through t, t + h/3, t + 2h/3, t + h and
  integrated exactly against the exponential (phi-functions).
* **Nonlinear inputs** by collocation at the Radau points c = 1/3, 1: r over the step is the
  line through its values R_1, R_2 at the two stage times, and the stage states are::

      xi(c_i h) = e^{lambda c_i h} xi_n + sum_k beta_ik(lambda) B_u u_k
                  + sum_j alpha_ij(lambda) B_r R_j,    alpha_ij = int_0^{c_i h} e^{lambda
                  (c_i h - s)} l_j(s) ds

  The 2 n_r unknowns R_j = r(y(c_j h)) (n_r = n_pads remainders, or 2 n_pads) are found by
  Newton's method on a system of that size (the pads couple only through their outputs v_p,
  z_p), so a step costs O(n n_r), not O(n^2) or O(n^3). For the nonlinear part the scheme is
  the 2-stage Radau IIA collocation: L-stable (the sliding bristles relax in one step without
  ringing) and stiffly accurate. Newton starts from the line through the previous step's
  stage values and stops when its update, or the error left after it as estimated from the
  contraction of the updates, is below the Newton tolerance (Hairer and Wanner, sec IV.8).
* A step whose Newton iteration does not converge (e.g. at a violent break-away), or whose
  error estimate (the deviation of r from its line, propagated to the pad outputs) exceeds the
  tolerance, is redone as two half steps, recursively down to 1/256 of the step; below that the
  integration stops (:func:`servotune.simulate.simulator.simulate` raises
  :class:`~servotune.simulate.result.SimulationError`). Steps grow back, one level at a time,
  where the error is well below the tolerance.
* Every matrix-vector product of the step (known inputs onto the modes, modes onto the pad
  outputs, the powers and the recorded outputs) runs with its long loop innermost over
  transposed matrices, which the compiler vectorises without reordering any sum: the results
  do not depend on how the kernel was compiled.

The energies are integrated alongside: the power of the work-piece forces, of the motor torque,
of the friction and of the distributed damping is evaluated at every step end and accumulated by
the trapezoidal rule (its error is h^2/12 times the change of the power's derivative over the
window, not growing with the number of cycles).

References
----------
M. Hochbruck, A. Ostermann, "Exponential integrators", Acta Numerica 19 (2010) 209-286 (sec 2.3,
exponential collocation; phi-functions).
E. Hairer, G. Wanner, Solving Ordinary Differential Equations II, 2nd ed., Springer (1996),
sec IV.5 (Radau IIA, L-stability, stiff accuracy).
A. H. Al-Mohy, N. J. Higham, "Computing the action of the matrix exponential", SIAM J. Sci.
Comput. 33 (2011) 488-511 (phi-functions from one exponential of an augmented matrix).
"""

from __future__ import annotations

import hashlib
import importlib.util
import inspect
import math
import os
import sys
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np
import scipy.linalg

from ..cache import cache_folder, cached_njit, writable_folder

__all__ = ["ModalForm", "modal_form", "StepWeights", "step_weights", "phi_functions",
           "chunk_kernel", "controller_arrays", "integrate_chunk", "sum_of_squares",
           "MAX_LEVEL", "N_POWERS"]

MAX_LEVEL = 8          # steps are halved at most this many times (h/256)
C1 = 1.0 / 3.0         # first Radau point (the second is 1)
N_POWERS = 4           # work-piece force, motor, friction, distributed damping
MAX_NEWTON = 12


def phi_functions(z, order: int = 4) -> np.ndarray:
    """Return the phi-functions phi_1(z) ... phi_order(z) of complex arguments.

    ``phi_k(z) = int_0^1 e^{(1-s) z} s^(k-1)/(k-1)! ds = sum_j z^j / (j + k)!``: the Taylor
    series for |z| < 1 (where the recurrence would cancel), else the recurrence
    ``phi_{k+1}(z) = (phi_k(z) - 1/k!) / z`` from phi_0 = e^z (Hochbruck and Ostermann 2010,
    sec 2.1), which loses at most a few digits of the last place for |z| >= 1.

    Parameters
    ----------
    z : array_like
        Complex arguments (lambda t, dimensionless), any shape.
    order : int
        Highest k.

    Returns
    -------
    numpy.ndarray
        Complex, shape ``z.shape + (order,)``: ``[..., k - 1]`` is phi_k(z).

    Examples
    --------
    >>> phi = phi_functions(np.array([0.0, -50.0]))
    >>> np.round(phi[0].real, 6).tolist()             # 1/k! at z = 0
    [1.0, 0.5, 0.166667, 0.041667]
    >>> round(float(phi[1, 0].real), 6)               # (e^z - 1)/z
    0.02
    """
    z = np.asarray(z, dtype=complex)
    out = np.empty((*z.shape, order), dtype=complex)
    small = np.abs(z) < 1.0
    zs = z[small]
    for k in range(1, order + 1):
        term = np.full(zs.shape, 1.0 / math.factorial(k), dtype=complex)
        acc = term.copy()
        for j in range(1, 30):
            term = term * zs / (j + k)
            acc += term
        out[small, k - 1] = acc
    zl = z[~small]
    prev = np.exp(zl)
    for k in range(1, order + 1):
        prev = (prev - 1.0 / math.factorial(k - 1)) / zl
        out[~small, k - 1] = prev
    return out


@dataclass(frozen=True, eq=False)
class ModalForm:
    """A = V diag(lambda) V^-1 with one coordinate per real eigenvalue or conjugate pair.

    ``X = Re(vectors @ xi)`` (pairs carry a factor 2) and ``d xi/dt = lam xi + left @ (B w)``.
    """

    lam: np.ndarray
    vectors: np.ndarray
    left: np.ndarray
    condition: float


def modal_form(a: np.ndarray, times=(1e-4, 1e-2), check: float = 1e-7) -> ModalForm:
    """Diagonalise a real A after balancing; check the flow against ``expm``.

    Parameters
    ----------
    a : (n, n) array_like
        Real system matrix A [1/s].
    times : sequence of float
        Times t [s] at which the modal flow ``Re(V diag(e^{lambda t}) V^-1)`` is checked
        against ``scipy.linalg.expm(A t)`` (the steps the integration will use).
    check : float
        Largest relative error of that flow allowed (relative to the largest entry of
        e^{A t}).

    Returns
    -------
    ModalForm
        The eigenvalues with Im >= 0 (m <= n of them), the eigenvectors (conjugate pairs with
        a factor 2, so that ``X = Re(vectors @ xi)``), the matching rows of V^-1 and the
        1-norm condition number of the balanced eigenvector matrix.

    Raises
    ------
    ValueError
        When A is (nearly) defective, so that the modal flow e^{A t} differs from scipy's
        ``expm`` by more than ``check`` (relative) at the given times [s] (the steps used).
    """
    a = np.asarray(a, dtype=float)
    ab, (scale, _) = scipy.linalg.matrix_balance(a, permute=False, separate=True)
    lam, v = np.linalg.eig(ab)
    v = scale[:, None] * v                      # back to the unbalanced states
    w = np.linalg.inv(v)
    keep = lam.imag >= 0.0
    mult = np.where(lam.imag > 0.0, 2.0, 1.0)
    real = lam.imag == 0.0
    v[:, real] = v[:, real].real
    w[real] = w[real].real
    vb = v / scale[:, None]
    cond = float(np.linalg.norm(vb, 1) * np.linalg.norm(np.linalg.inv(vb), 1))
    form = ModalForm(lam=lam[keep].copy(), vectors=(v * mult)[:, keep].copy(),
                     left=w[keep].copy(), condition=cond)
    # a posteriori: the flow over the given times against expm
    for t in times:
        ref = scipy.linalg.expm(a * t)
        got = (form.vectors * np.exp(form.lam * t)) @ form.left
        err = np.abs(got.real - ref).max() / max(np.abs(ref).max(), 1e-300)
        if not err <= check:
            raise ValueError(
                f"the linear part of the axis is too close to defective for the modal "
                f"integrator (flow error {err:.2g} at t = {t:.3g} s, eigenvector condition "
                f"{cond:.3g}); perturb the model slightly (e.g. damping) or report the model")
    return form


@dataclass(frozen=True, eq=False)
class StepWeights:
    """Exponential and collocation weights of steps h / 2^L, L = 0..levels.

    Shapes (m modes): ``prop (L, 2, m)`` = e^{lambda c_i h}; ``alpha (L, 2, 2, m)``;
    ``beta (L, 2, 4, m)``; ``gamma (L, m)`` the weight of the error term; ``kmat (L, 2, 2,
    2 n_r, n_r)`` = Re(C_y diag(alpha_ij) B_r); ``kerr (L, 2 n_r, n_r)`` = Re(C_y diag(gamma)
    B_r).
    """

    h: float
    prop: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray
    gamma: np.ndarray
    kmat: np.ndarray
    kerr: np.ndarray


def _lagrange_coefficients(nodes: np.ndarray) -> np.ndarray:
    """Coefficients c[j, q] of the Lagrange basis l_j(x) = sum_q c[j, q] x^q on the nodes."""
    van = np.vander(nodes, len(nodes), increasing=True)   # van[i, q] = nodes_i^q
    return np.linalg.inv(van).T


def step_weights(lam: np.ndarray, h: float, cy_br=None, levels: int = MAX_LEVEL) -> StepWeights:
    """Return the exponential and collocation weights of steps h/2^L, L = 0..levels.

    See :class:`StepWeights` and the module docstring. The weights are the integrals
    ``int_0^{c h} e^{lambda (c h - s)} p(s) ds`` of the Lagrange polynomials p of the known
    inputs (nodes 0, 1/3, 2/3, 1) and of the remainders (Radau nodes 1/3, 1), from the
    phi-functions (Hochbruck and Ostermann 2010, sec 2.3). The error weight
    gamma = int_0^h e^{lambda (h - s)} (s/h - 1/3)(s/h - 1) ds propagates the
    deviation of r from its line through the stage values, ``e(s) = r''/2 (s - h/3)(s - h)``,
    to the end of the step.

    Parameters
    ----------
    lam : (m,) array_like
        Eigenvalues lambda [1/s] of the modal form.
    h : float
        Base step [s].
    cy_br : tuple of numpy.ndarray, optional
        ``(C_y V (2 n_r, m), V^-1 B_r (m, n_r))`` for the nonlinear inputs, or None (no
        remainder: ``kmat`` and ``kerr`` are empty).
    levels : int
        Deepest level L (steps down to h/2^levels).

    Returns
    -------
    StepWeights
        Arrays over the ``levels + 1`` levels.
    """
    lam = np.asarray(lam, dtype=complex)
    m = lam.size
    cu = _lagrange_coefficients(np.array([0.0, 1 / 3, 2 / 3, 1.0]))   # in s/h
    cw = _lagrange_coefficients(np.array([C1, 1.0]))
    quad = np.array([1.0 / 3.0, -4.0 / 3.0, 1.0])    # (x - 1/3)(x - 1) = 1/3 - 4/3 x + x^2
    prop = np.empty((levels + 1, 2, m), dtype=complex)
    alpha = np.empty((levels + 1, 2, 2, m), dtype=complex)
    beta = np.empty((levels + 1, 2, 4, m), dtype=complex)
    gamma = np.empty((levels + 1, m), dtype=complex)
    for lev in range(levels + 1):
        hl = h / 2**lev
        for i, c in enumerate((C1, 1.0)):
            t = c * hl
            phi = phi_functions(lam * t)                         # (m, 4)
            # int_0^t e^{lam (t - s)} (s/hl)^q ds = t^(q+1) q! phi_{q+1}(lam t) / hl^q
            mono = np.stack([t ** (q + 1) * math.factorial(q) * phi[:, q] / hl**q
                             for q in range(4)], axis=0)         # (4, m)
            prop[lev, i] = np.exp(lam * t)
            beta[lev, i] = cu @ mono
            alpha[lev, i] = cw @ mono[:2]
            if i == 1:
                gamma[lev] = quad @ mono[:3]
    nr = 0 if cy_br is None else cy_br[1].shape[1]
    kmat = np.zeros((levels + 1, 2, 2, 2 * nr, nr))
    kerr = np.zeros((levels + 1, 2 * nr, nr))
    if nr:
        cy, br = cy_br
        for lev in range(levels + 1):
            for i in range(2):
                for j in range(2):
                    kmat[lev, i, j] = ((cy * alpha[lev, i, j][None, :]) @ br).real
            kerr[lev] = ((cy * gamma[lev][None, :]) @ br).real
    return StepWeights(h=h, prop=prop, alpha=alpha, beta=beta, gamma=gamma, kmat=kmat,
                       kerr=kerr)


# ------------------------------------------------------------------------------------------
# the compiled kernel (complex numbers carried as separate real and imaginary arrays)

# reassociation lets the compiler vectorise the sums; NaN and infinity stay honoured (the
# kernel checks for them)
_FAST = False  # bit-reproducible: results must not depend on how the kernel was compiled

@cached_njit(fastmath=_FAST)
def _u_into(samples, s, out):
    """Known inputs at position s (in sample units) into out: the sample itself on a sample,
    else the cubic through the four samples around s."""
    n = samples.shape[0]
    nu = samples.shape[1]
    i = int(math.floor(s))  # noqa: RUF046 (an integer in the compiled kernel too)
    if s == i and 0 <= i < n:
        for c in range(nu):
            out[c] = samples[i, c]
        return
    i0 = min(max(i - 1, 0), n - 4)
    x = s - i0
    for c in range(nu):
        out[c] = 0.0
    for a in range(4):
        wgt = 1.0
        for b in range(4):
            if b != a:
                wgt *= (x - b) / (a - b)
        for c in range(nu):
            out[c] += wgt * samples[i0 + a, c]


@cached_njit
def _solve_small(a, x, n):
    """Solve a[:n, :n] x = x in place (Gaussian elimination with partial pivoting; a is
    overwritten). Returns False for a singular matrix."""
    for k in range(n):
        p = k
        big = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > big:
                big = abs(a[i, k])
                p = i
        if big == 0.0 or not math.isfinite(big):
            return False
        if p != k:
            for j in range(n):
                tmp = a[k, j]
                a[k, j] = a[p, j]
                a[p, j] = tmp
            tmp = x[k]
            x[k] = x[p]
            x[p] = tmp
        for i in range(k + 1, n):
            f = a[i, k] / a[k, k]
            if f != 0.0:
                for j in range(k, n):
                    a[i, j] -= f * a[k, j]
                x[i] -= f * x[k]
    for k in range(n - 1, -1, -1):
        acc = x[k]
        for j in range(k + 1, n):
            acc -= a[k, j] * x[j]
        x[k] = acc / a[k, k]
    return True


@cached_njit(fastmath=_FAST)
def sum_of_squares(rows_re, rows_im, xr, xm):
    """Return sum_q (Re(rows[q] . xi))^2 for xi = xr + i xm (energies at checkpoints).

    Compiled (numba).

    Parameters
    ----------
    rows_re, rows_im : (k, m) numpy.ndarray
        Real and imaginary parts of the rows (e.g. ``energy_rows @ V``).
    xr, xm : (m,) numpy.ndarray
        Real and imaginary parts of the modal coordinates xi.

    Returns
    -------
    float
        The sum of squares (twice the energy [J] for the energy rows).
    """
    total = 0.0
    for q in range(rows_re.shape[0]):
        acc = 0.0
        for i in range(xr.size):
            acc += rows_re[q, i] * xr[i] - rows_im[q, i] * xm[i]
        total += acc * acc
    return total


@cached_njit(fastmath=_FAST)
def _powers(xr, xm, u, r2, cpt_re, cpt_im, dpu, dpr, n_force, force_idx, n_pads, vals, out):
    """Powers [W] at one instant: work-piece forces, motor, friction, damping.

    ``cpt`` (m, rows) is the transposed map from the modal coordinates to the power rows: the
    loop over the rows is innermost and vectorises, each row summed over the modes in order.
    """
    npr = cpt_re.shape[1]
    m = xr.size
    for q in range(npr):
        vals[q] = 0.0
    for i in range(m):
        a = xr[i]
        b = xm[i]
        for q in range(npr):
            vals[q] += cpt_re[i, q] * a - cpt_im[i, q] * b
    for q in range(npr):
        acc = vals[q]
        for c in range(u.size):
            acc += dpu[q, c] * u[c]
        for p in range(r2.size):
            acc += dpr[q, p] * r2[p]
        vals[q] = acc
    p_ext = 0.0
    for f in range(n_force):
        p_ext += u[force_idx[f]] * vals[f]
    p_fric = 0.0
    b = n_force + 2
    for p in range(n_pads):
        p_fric -= vals[b + p] * vals[b + n_pads + p]
    p_damp = 0.0
    for q in range(b + 2 * n_pads, npr):
        p_damp -= vals[q] * vals[q]
    out[0] = p_ext
    out[1] = vals[n_force] * vals[n_force + 1]
    out[2] = p_fric
    out[3] = p_damp


@cached_njit
def _no_remainder(component, v, z, p):
    """The remainder of a law without one (never called: such a law has no remainder input)."""
    return math.nan, math.nan, math.nan


# the name the kernel calls; chunk_kernel() compiles the kernel with the law's remainder here
_remainder = _no_remainder


@cached_njit
def _controller_update(k, xr, xm, samples, si, meas_re, meas_im, ref_cols, ctl_every, ctl_n,
                       ctl_a, ctl_b, ctl_c, ctl_d, ctl_x, ctl_held, g, tmp):
    """The digital drive's controllers at fast sample k (levels slow to fast; see
    :meth:`servotune.digital.DigitalController.step`): g = [measured, references, held]."""
    nm = meas_re.shape[1]
    n_ref = ref_cols.size
    n_lev = ctl_every.size
    for q in range(nm):
        acc = 0.0
        for i in range(xr.size):
            acc += meas_re[i, q] * xr[i] - meas_im[i, q] * xm[i]
        g[q] = acc
    for q in range(n_ref):
        g[nm + q] = samples[si, ref_cols[q]] if ref_cols[q] >= 0 else 0.0
    for j in range(n_lev):
        g[nm + n_ref + j] = ctl_held[j]
    for j in range(n_lev):
        if k % ctl_every[j] != 0:
            continue
        nj = ctl_n[j]
        y = 0.0
        for c in range(g.size):
            y += ctl_d[j, c] * g[c]
        for i in range(nj):
            y += ctl_c[j, i] * ctl_x[j, i]
        for i in range(nj):
            acc = 0.0
            for c in range(nj):
                acc += ctl_a[j, i, c] * ctl_x[j, c]
            for c in range(g.size):
                acc += ctl_b[j, i, c] * g[c]
            tmp[i] = acc
        for i in range(nj):
            ctl_x[j, i] = tmp[i]
        ctl_held[j] = y
        g[nm + n_ref + j] = y


def controller_arrays(controller, data: dict, inputs, samples_per_step: int) -> tuple:
    """The trailing arguments of the kernel for a digital drive's controllers (or none).

    Parameters
    ----------
    controller : DigitalController or None
        The controllers (None: no digital drive; the kernel then computes none).
    data : dict
        The prepared data of :func:`servotune.simulate.simulator.simulate` (``meas_re``,
        ``meas_im``: the sampled outputs projected on the modes).
    inputs : sequence of str
        The known inputs of the linear part (``voltage`` and the references among them).
    samples_per_step : int
        Base steps per fast sample (0: none).

    Returns
    -------
    tuple
        ``ctl_every, ctl_n, ctl_a, ctl_b, ctl_c, ctl_d, ctl_x, ctl_held, ctl_state, meas_re,
        meas_im, ref_cols, volt_col, samples_per_step`` (the state arrays are updated in
        place by the kernel).
    """
    inputs = list(inputs)
    if controller is None:
        z2, z3 = np.zeros((0, 1)), np.zeros((0, 1, 1))
        return (np.zeros(0, np.int64), np.zeros(0, np.int64), z3, z3, z2, z2, z2,
                np.zeros(0), np.full(1, -1, np.int64), np.zeros((1, 0)), np.zeros((1, 0)),
                np.zeros(0, np.int64), -1, 0)
    levels = controller.levels
    n_lev = len(levels)
    size = max(1, max(lv.a.shape[0] for lv in levels))
    n_g = controller.n_inputs
    a = np.zeros((n_lev, size, size))
    b = np.zeros((n_lev, size, n_g))
    c = np.zeros((n_lev, size))
    d = np.zeros((n_lev, n_g))
    for j, lv in enumerate(levels):
        n = lv.a.shape[0]
        a[j, :n, :n] = lv.a
        b[j, :n] = lv.b
        c[j, :n] = lv.c[0]
        d[j] = lv.d[0]
    if levels[-1].output != "voltage":
        raise ValueError("the fastest controller must drive the voltage")
    from ..digital import REFERENCES

    refs = np.array([inputs.index(r) if r in inputs else -1 for r in REFERENCES], np.int64)
    return (np.array([lv.every for lv in levels], np.int64),
            np.array([lv.a.shape[0] for lv in levels], np.int64), a, b, c, d,
            np.zeros((n_lev, size)), np.zeros(n_lev), np.full(1, -1, np.int64),
            data["meas_re"], data["meas_im"], refs, inputs.index("voltage"),
            int(samples_per_step))


def integrate_chunk(h, n0, n1, record_every, level, xr, xm, r_last, energy, power, samples,
                    s_base, but_re, but_im, brt_re, brt_im, cyt_re, cyt_im, prop_re, prop_im,
                    alpha_re, alpha_im, beta_re, beta_im, kmat, kerr, rparams, r_tol,
                    err_scale, tol, cpt_re, cpt_im, dpu, dpr, n_force, force_idx, n_pads,
                    cot_re, cot_im, dou, dor, rec_out, rec_energy, stats, ctl_every, ctl_n,
                    ctl_a, ctl_b, ctl_c, ctl_d, ctl_x, ctl_held, ctl_state, meas_re, meas_im,
                    ref_cols, volt_col, samples_per_step):
    """Integrate the base steps n0..n1-1 (of length h) in place (the kernel's source).

    The compiled kernel of a friction law is :func:`chunk_kernel` ``(law.remainder())``: this
    function's source compiled with ``_remainder`` the law's remainder. Remainder input k is
    component ``k // n_pads`` of the law, evaluated at the velocity and state rows of input k.

    State: modal coordinates ``xr + i xm``, the last stage remainders ``r_last`` (2 n_r),
    cumulative works ``energy`` (4) and current powers ``power`` (4); ``level`` is the current
    step level (step h / 2^level). Records (outputs and works) are taken at the end of every
    base step n with (n + 1) % record_every == 0. ``stats``: [steps, Newton iterations,
    rejected steps, deepest level].

    The projections are passed transposed, ``but = (V^-1 B_u)^T`` (nu, m), ``brt`` (n_r, m),
    ``cyt = (C_y V)^T`` (m, 2 n_r), ``cpt`` and ``cot`` (m, rows): every matrix-vector product
    then runs with the loop over the modes (or the rows) innermost, which the compiler
    vectorises without reordering any sum.

    Parameters
    ----------
    h : float
        Base step [s].
    n0, n1 : int
        First base step and the one after the last (absolute indices from t = 0).
    record_every : int
        Base steps between records.
    level : int
        Step level to start with (step h / 2^level).
    xr, xm : (m,) numpy.ndarray
        Modal coordinates, real and imaginary parts; updated in place.
    r_last : (2 n_r,) numpy.ndarray
        Remainders at the two stages of the last step; updated in place.
    energy, power : (4,) numpy.ndarray
        Cumulative works [J] and current powers [W] of :data:`N_POWERS` channels; updated in
        place.
    samples : (K, nu) numpy.ndarray
        Known inputs sampled every h/3: row j is sample ``s_base + j`` (sample i at t = i h/3).
        The rows must reach from one sample before ``3 n0`` (or from sample 0) to three after
        ``3 n1`` (or the last sample), the neighbours of the cubic interpolation.
    s_base : int
        Index of the first row of ``samples`` among all samples (0: they start at t = 0). A long
        run thus holds only a window of its inputs at a time.
    but_re, but_im : (nu, m) numpy.ndarray
        ``(V^-1 B_u)^T``.
    brt_re, brt_im : (n_r, m) numpy.ndarray
        ``(V^-1 B_r)^T``.
    cyt_re, cyt_im : (m, 2 n_r) numpy.ndarray
        ``(C_y V)^T``: the velocity and state each remainder input reads.
    prop_re, prop_im, alpha_re, alpha_im, beta_re, beta_im : numpy.ndarray
        :class:`StepWeights` ``prop``, ``alpha``, ``beta`` (real and imaginary parts).
    kmat, kerr : numpy.ndarray
        :class:`StepWeights` ``kmat`` and ``kerr``.
    rparams : numpy.ndarray
        Parameters of the law's remainder
        (:meth:`~servotune.friction.law.FrictionLaw.remainder_parameters`).
    r_tol : float
        Newton tolerance on the remainders [m/s].
    err_scale : (2 n_r,) numpy.ndarray
        Scales of the pad velocities [m/s] and states of the error estimate.
    tol : float
        Local error allowed per step, relative to ``err_scale``.
    cpt_re, cpt_im : (m, rows) numpy.ndarray
        Map from the modal coordinates to the power rows, transposed.
    dpu, dpr : numpy.ndarray
        Feed-through of the known inputs and the remainders into the power rows.
    n_force : int
        Number of work-piece forces.
    force_idx : numpy.ndarray
        Their indices among the known inputs.
    n_pads : int
        Number of pads (remainder input k is component ``k // n_pads``).
    cot_re, cot_im : (m, n_out) numpy.ndarray
        Map from the modal coordinates to the recorded outputs, transposed.
    dou, dor : numpy.ndarray
        Feed-through of the known inputs and the remainders into the outputs.
    rec_out : (n_rec, n_out) numpy.ndarray
        Recorded outputs of this chunk; filled in place.
    rec_energy : (n_rec, 4) numpy.ndarray
        Recorded cumulative works [J]; filled in place.
    stats : (4,) numpy.ndarray of int64
        Counters, incremented in place.
    ctl_every, ctl_n : numpy.ndarray of int64
        A digital drive's controllers (:func:`controller_arrays`), slow to fast: fast samples
        per update and state sizes. At the start of every base step that begins a fast sample
        (every ``samples_per_step`` base steps) the controllers due are computed from the
        sampled outputs and the references, and the voltage is held over the step.
    ctl_a, ctl_b, ctl_c, ctl_d : numpy.ndarray
        Their matrices, B and D on the vector [measured, references, held outputs].
    ctl_x, ctl_held : numpy.ndarray
        Their states and held outputs; updated in place.
    ctl_state : numpy.ndarray of int64
        ``[0]``: the position of the last update (a rejected step is redone without a second
        update); updated in place.
    meas_re, meas_im : numpy.ndarray
        The sampled outputs projected on the modes, transposed (m, 3).
    ref_cols : numpy.ndarray of int64
        Columns of the references in ``samples`` (-1: absent, read as 0).
    volt_col : int
        Column of the held voltage among the known inputs (-1: no controller).
    samples_per_step : int
        Base steps per fast sample (0: no controller).

    Returns
    -------
    steps : int
        Base steps completed: fewer than ``n1 - n0`` means a step failed at the deepest level.
    level : int
        The step level reached (to start the next chunk with).
    """
    m = xr.size
    nu = samples.shape[1]
    nr = brt_re.shape[0]
    ny = 2 * nr
    nlev = prop_re.shape[0]
    top = nlev - 1
    unit = 1 << top                     # finest steps per base step
    # workspace
    un = np.empty((4, nu))
    bun_re = np.empty((4, m))
    bun_im = np.empty((4, m))
    base_re = np.empty((2, m))
    base_im = np.empty((2, m))
    ypred = np.empty((2, ny))
    y = np.empty((2, ny))
    rr = np.empty(2 * nr)
    res = np.empty(2 * nr)
    jac = np.empty((2 * nr, 2 * nr))
    dv = np.empty(2 * nr)
    dz = np.empty(2 * nr)
    d2 = np.empty(nr)
    u_end = np.empty(nu)
    vals = np.empty(cpt_re.shape[1])
    n_out = cot_re.shape[1]
    p_new = np.empty(4)
    n_rec = 0
    prev_lev = -1                       # level of the previous step (-1: none in this chunk)
    pos = n0 * unit
    end = n1 * unit
    n_lev = ctl_every.size
    g_ctl = np.zeros(meas_re.shape[1] + ref_cols.size + n_lev)
    tmp_ctl = np.zeros(max(1, ctl_x.shape[1]))
    while pos < end:
        lev = level
        span = 1 << (top - lev)
        s0 = pos * 3.0 / unit - s_base
        ds = 1.0 / (1 << lev)
        if samples_per_step > 0 and pos % (unit * samples_per_step) == 0 \
                and pos != ctl_state[0]:
            ctl_state[0] = pos
            _controller_update(pos // (unit * samples_per_step), xr, xm, samples,
                               (pos * 3) // unit - s_base, meas_re, meas_im, ref_cols,
                               ctl_every, ctl_n, ctl_a, ctl_b, ctl_c, ctl_d, ctl_x, ctl_held,
                               g_ctl, tmp_ctl)
        # known inputs projected on the modes at the four nodes
        for k in range(4):
            _u_into(samples, s0 + k * ds, un[k])
            if volt_col >= 0:
                un[k, volt_col] = ctl_held[n_lev - 1]
            for i in range(m):
                bun_re[k, i] = 0.0
                bun_im[k, i] = 0.0
            for c in range(nu):
                w = un[k, c]
                for i in range(m):
                    bun_re[k, i] += but_re[c, i] * w
                    bun_im[k, i] += but_im[c, i] * w
        for st in range(2):
            for i in range(m):
                pr = prop_re[lev, st, i]
                pi = prop_im[lev, st, i]
                base_re[st, i] = pr * xr[i] - pi * xm[i]
                base_im[st, i] = pr * xm[i] + pi * xr[i]
            for k in range(4):
                for i in range(m):
                    wr = beta_re[lev, st, k, i]
                    wi = beta_im[lev, st, k, i]
                    base_re[st, i] += wr * bun_re[k, i] - wi * bun_im[k, i]
                    base_im[st, i] += wr * bun_im[k, i] + wi * bun_re[k, i]
        ok = True
        its = 0
        err = 0.0
        if nr > 0:
            for st in range(2):
                for q in range(ny):
                    ypred[st, q] = 0.0
                for i in range(m):
                    a = base_re[st, i]
                    b = base_im[st, i]
                    for q in range(ny):
                        ypred[st, q] += cyt_re[i, q] * a - cyt_im[i, q] * b
            if prev_lev >= 0:
                # start from the line through the previous step's stage values, extended
                ratio = 1.5 * (1 << prev_lev) / (1 << lev)   # h / ((1 - c1) h_prev)
                for p in range(nr):
                    slope = (r_last[nr + p] - r_last[p]) * ratio
                    rr[p] = r_last[nr + p] + C1 * slope
                    rr[nr + p] = r_last[nr + p] + slope
            else:
                for p in range(nr):       # (first step of a chunk) from the last value of r
                    rr[p] = r_last[nr + p]
                    rr[nr + p] = r_last[nr + p]
            ok = False
            big_prev = 0.0
            while its < MAX_NEWTON:
                its += 1
                for st in range(2):
                    for q in range(ny):
                        acc = ypred[st, q]
                        for sj in range(2):
                            for p in range(nr):
                                acc += kmat[lev, st, sj, q, p] * rr[sj * nr + p]
                        y[st, q] = acc
                for st in range(2):
                    for p in range(nr):
                        row = st * nr + p
                        val, a_v, a_z = _remainder(p // n_pads, y[st, p], y[st, nr + p],
                                                   rparams)
                        res[row] = val - rr[row]
                        dv[row] = a_v
                        dz[row] = a_z
                for st in range(2):
                    for p in range(nr):
                        row = st * nr + p
                        for sj in range(2):
                            for pp in range(nr):
                                jac[row, sj * nr + pp] = -(
                                    dv[row] * kmat[lev, st, sj, p, pp]
                                    + dz[row] * kmat[lev, st, sj, nr + p, pp])
                        jac[row, row] += 1.0
                if not _solve_small(jac, res, 2 * nr):
                    break
                big = 0.0
                finite = True
                for q in range(2 * nr):
                    rr[q] += res[q]
                    if not math.isfinite(rr[q]):
                        finite = False
                    big = max(big, abs(res[q]))
                if not finite:
                    break
                # converged when the update, or the error left after it as estimated from
                # the contraction theta = big / big_prev (theta / (1 - theta) big), is below
                # r_tol (Hairer and Wanner, sec IV.8)
                if big <= r_tol or (its > 1 and big < big_prev
                                    and big * big <= r_tol * (big_prev - big)):
                    ok = True
                    break
                big_prev = big
            if ok:
                # error estimate: r minus its line, propagated to the pad outputs
                for p in range(nr):
                    d2[p] = 1.5 * (rr[nr + p] - 3.0 * rr[p] + 2.0 * r_last[nr + p])
                for q in range(ny):
                    acc = 0.0
                    for p in range(nr):
                        acc += kerr[lev, q, p] * d2[p]
                    err = max(err, abs(acc) / err_scale[q])
                err /= tol
        stats[1] += its
        if not ok or err > 1.0:
            stats[2] += 1
            if lev >= top:
                return pos // unit - n0, level
            level = lev + 1
            continue
        # accept: the new state
        for i in range(m):
            xr[i] = base_re[1, i]
            xm[i] = base_im[1, i]
        for sj in range(2):
            for p in range(nr):
                g = rr[sj * nr + p]
                for i in range(m):
                    wr = alpha_re[lev, 1, sj, i]
                    wi = alpha_im[lev, 1, sj, i]
                    xr[i] += (wr * brt_re[p, i] - wi * brt_im[p, i]) * g
                    xm[i] += (wr * brt_im[p, i] + wi * brt_re[p, i]) * g
        for q in range(2 * nr):
            r_last[q] = rr[q]
        prev_lev = lev
        stats[0] += 1
        if lev > stats[3]:
            stats[3] = lev
        pos += span
        for c in range(nu):
            u_end[c] = un[3, c]
        _powers(xr, xm, u_end, r_last[nr:], cpt_re, cpt_im, dpu, dpr, n_force, force_idx,
                n_pads, vals, p_new)
        dt = h / (1 << lev)
        for q in range(4):
            energy[q] += 0.5 * dt * (power[q] + p_new[q])
            power[q] = p_new[q]
        # coarser next time if the error allows and the position is aligned
        if nr > 0 and lev > 0 and err < 0.0625 and pos % (2 * span) == 0:
            level = lev - 1
        if pos % unit == 0:
            n = pos // unit - 1
            if (n + 1) % record_every == 0:
                row = rec_out[n_rec]
                for q in range(n_out):
                    row[q] = 0.0
                for i in range(m):
                    a = xr[i]
                    b = xm[i]
                    for q in range(n_out):
                        row[q] += cot_re[i, q] * a - cot_im[i, q] * b
                for q in range(n_out):
                    acc = row[q]
                    for c in range(nu):
                        acc += dou[q, c] * u_end[c]
                    for p in range(nr):
                        acc += dor[q, p] * r_last[nr + p]
                    row[q] = acc
                for q in range(4):
                    rec_energy[n_rec, q] = energy[q]
                n_rec += 1
    return n1 - n0, level


# ------------------------------------------------------------------------------------------
# one compiled kernel per friction law

_KERNELS: dict = {}


def _code_names(code) -> set:
    names = set(code.co_names)
    for const in code.co_consts:
        if hasattr(const, "co_names"):
            names |= _code_names(const)
    return names


def _compiled_sources(dispatcher, files: dict) -> dict:
    """The source files of a numba function and of every compiled function it calls, found
    through its global names (recursively), with their contents."""
    py = dispatcher.py_func
    path = inspect.getsourcefile(py)
    if path in files:
        return files
    files[path] = Path(path).read_bytes()
    for name in sorted(_code_names(py.__code__)):
        obj = py.__globals__.get(name)
        if isinstance(obj, numba.core.dispatcher.Dispatcher):
            _compiled_sources(obj, files)
    return files


def _kernel_directory() -> Path:
    """Where the generated kernel modules are written, numba's caches of them in its
    ``__pycache__``: ``SERVOTUNE_KERNEL_DIR``, else the ``kernels`` folder of servotune's user
    cache (:mod:`servotune.cache`); never the package."""
    env = os.environ.get("SERVOTUNE_KERNEL_DIR")
    return writable_folder(env) if env else cache_folder("kernels")


def _prune(folder: Path, current: Path, age: float = 86400.0) -> None:
    """Remove the kernels of the same remainder built from older sources (unused for a day:
    a process still running older code keeps its own), with numba's cache files of them."""
    stem = current.stem.rsplit("_", 1)[0] + "_"
    now = time.time()
    for old in folder.glob(f"{stem}*.py"):
        try:
            if old != current and now - old.stat().st_mtime > age:
                for cached in (folder / "__pycache__").glob(f"{old.stem}.*"):
                    cached.unlink()
                old.unlink()
        except OSError:
            pass


def chunk_kernel(remainder=None):
    """The compiled :func:`integrate_chunk` of a friction law's remainder.

    Parameters
    ----------
    remainder : numba dispatcher, optional
        The law's compiled remainder ``(component, v, z, p) -> (r, dr_dv, dr_dz)``, a
        module-level ``numba.njit`` function (:meth:`servotune.friction.law.FrictionLaw.remainder`);
        None for a law without one.

    Returns
    -------
    numba dispatcher
        :func:`integrate_chunk` compiled with the remainder called directly (a direct call is
        several times faster than a function passed as an argument), cached on disk by numba
        next to the generated module, in servotune's user cache.

    Raises
    ------
    TypeError
        If ``remainder`` is not a ``numba.njit`` function, or not a module-level function
        importable by its name.
    servotune.cache.CacheFolderError
        If the kernel folder cannot be created or written.

    Notes
    -----
    The kernel is the source of :func:`integrate_chunk` in a generated module that imports the
    remainder by name, written once into a kernel folder (``SERVOTUNE_KERNEL_DIR``, else the
    ``kernels`` folder of servotune's user cache, :mod:`servotune.cache`; never into the
    package, which may be read-only once installed); numba caches it in the ``__pycache__``
    of that folder (or in ``NUMBA_CACHE_DIR`` if the user set one). numba's on-disk
    cache checks only the time stamp of a cached function's own file, not of the functions it
    calls; so the module's name carries a hash of this file and of the source files of the
    remainder and of every compiled function it calls (found through their global names), and
    of the numba version: a changed or new law gets a new module and is compiled afresh, never
    served stale code. No law is listed anywhere: any registered law's remainder can be passed.
    Kernels of the same remainder from older sources are removed once they are a day old.
    """
    remainder = _no_remainder if remainder is None else remainder
    if not isinstance(remainder, numba.core.dispatcher.Dispatcher):
        raise TypeError(f"the remainder must be a numba.njit function, got {remainder!r}")
    key = id(remainder)
    if key in _KERNELS and _KERNELS[key][0] is remainder:
        return _KERNELS[key][1]
    module_name = remainder.py_func.__module__
    func_name = remainder.py_func.__name__
    if getattr(sys.modules.get(module_name), func_name, None) is not remainder:
        raise TypeError(f"the remainder {module_name}.{func_name} must be a module-level "
                        f"function of its module, importable by that name")
    files = _compiled_sources(remainder, {})
    files[__file__] = Path(__file__).read_bytes()
    digest = hashlib.sha256()
    for path in sorted(files):
        digest.update(path.encode() + b"\0" + files[path] + b"\0")
    digest.update(f"{module_name}.{func_name} numba {numba.__version__}".encode())
    tag = f"{module_name.rsplit('.', 1)[-1]}_{func_name}_{digest.hexdigest()[:16]}"
    source = textwrap.dedent(inspect.getsource(integrate_chunk))
    text = (f'"""Generated by servotune.simulate.integrator.chunk_kernel for '
            f'{module_name}.{func_name}."""\n\n'
            f"import math\n\nimport numba\nimport numpy as np\n\n"
            f"from servotune.simulate.integrator import (C1, MAX_NEWTON, _FAST,\n"
            f"                                          _controller_update, _powers,\n"
            f"                                          _solve_small, _u_into)\n"
            f"from {module_name} import {func_name} as _remainder\n\n\n"
            f"@numba.njit(cache=True, fastmath=_FAST)\n{source}")
    folder = _kernel_directory()
    path = folder / f"_kernel_{tag}.py"
    if not path.exists() or path.read_text() != text:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(text)
        os.replace(tmp, path)
        _prune(folder, path)
    name = f"servotune_kernel_{tag}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    kernel = module.integrate_chunk
    _KERNELS[key] = (remainder, kernel)
    return kernel
