"""Frequency responses of the axis: fast evaluation, port coupling, loop margins and poles.

Two independent ways of evaluating the closed-loop axis are provided:

* :func:`fast_frequency_response` evaluates any python-control ``StateSpace`` in its modal
  (eigenvector) coordinates: with A = V diag(lambda) V^-1 computed once,
  ``H(jw) = (C V) diag(1/(jw - lambda)) (V^-1 B) + D`` costs O(n p m) per frequency instead of
  a linear solve. Where the eigenvectors are ill-conditioned (integrators, rigid bodies) those
  eigenvalues are split off into a small triangular block; the complex Schur form (O(n^2) per
  frequency, backward stable) is the last resort. Every form but the last is checked a
  posteriori against direct solves at a few frequencies.
* :func:`port_compliance` does not evaluate the closed-loop state space: it takes the
  structure's receptance at the ports (work piece, pads, motor, encoder) from the modal sum and
  closes the contacts and the cascade around it with a small complex linear system per
  frequency (the state space serves only its stability check, one eigenvalue problem). The
  tuning evaluates the same equations in real arithmetic.

Loop analysis (:func:`analyse_loop`) gives gain and phase margins, the sensitivity peak
Ms = max |1/(1 + L)| and the closed-loop -3 dB bandwidth on a dense frequency grid.

References
----------
A. J. Laub, "Efficient multivariable frequency response computations", IEEE Trans. Automatic
Control 26 (1981) 407-408 (Hessenberg method, as SLICOT's TB05AD, python-control's evaluation).
C. Bavely, G. W. Stewart, "An algorithm for computing reducing subspaces by block
diagonalization", SIAM J. Numer. Anal. 16 (1979) 359-367.
K. J. Astrom, R. M. Murray, Feedback Systems, 2nd ed. (2021), sec 10.3 and 13.3 (margins,
sensitivity peak Ms).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg

from .drive import Drive, cascade_response
from .plant import Contact, UnstableLoopError, build_plant
from .structure.model import ModalModel
from .units import HZ_PER_RAD_S

__all__ = [
    "fast_frequency_response",
    "modal_receptance",
    "port_compliance",
    "compliance",
    "LoopAnalysis",
    "analyse_loop",
    "analyse_response",
    "ClosedLoopPoles",
    "closed_loop_poles",
    "require_stable",
    "is_stable",
    "is_stable_matrix",
    "following_error",
    "peak",
]



def _omega(omega) -> np.ndarray:
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    if omega.ndim != 1 or not np.all(np.isfinite(omega)) or np.any(omega < 0):
        raise ValueError("omega must be a 1-D array of finite angular frequencies >= 0 rad/s")
    return omega


def fast_frequency_response(sys: control.StateSpace, omega, inputs=None, outputs=None,
                            rtol: float = 1e-10) -> control.FrequencyResponseData:
    """Frequency response of a state-space system from a (block) modal form.

    ``A`` is balanced (a diagonal similarity) and decomposed once, ``A = S J S^-1``; then
    ``H(jw) = (C S) (jw I - J)^-1 (S^-1 B) + D`` costs O(n) per frequency and input/output
    pair where J is diagonal, and O(k^2) where it keeps an upper triangular block of size k.
    Three forms are tried in turn:

    1. the eigenvector (modal) form, J diagonal;
    2. the modal form with the eigenvalues whose eigenvectors are ill-conditioned (defective
       or nearly so: integrators and rigid-body modes at s = 0, coalescing poles) split off by
       an ordered Schur form and a Sylvester equation (Bavely-Stewart block
       diagonalisation) into a small triangular block solved at each frequency;
    3. the complex Schur form, J upper triangular: back substitution at each frequency,
       O(n^2), backward stable (this one is not checked).

    Forms 1 and 2 are checked a posteriori at the four frequencies of largest response, 24
    spread over the grid and the grid points nearest to the frequency of each eigenvalue of A
    (where an ill-conditioned eigenvector spoils the modal sum): there their responses are
    compared with direct solves ``C (jw I - A)^-1 B`` (Gaussian elimination with partial
    pivoting on the Hessenberg form of A, backward stable like a dense LU, O(n^2) per
    frequency), and a form passes if they agree within ``max(rtol, 1e-8)`` relative to the
    largest response (a direct solve is itself accurate only to the conditioning of
    jw I - A, a few 1e-10 for a loop with an integrator and a rigid body). Forms 1 and 2 cost
    one eigenvalue decomposition (and a Schur form) plus O(n) per frequency; form 3 O(n^2)
    per frequency, as the Hessenberg method of python-control (SLICOT TB05AD).

    Parameters
    ----------
    sys : control.StateSpace
        The system (n states, m inputs, p outputs); anything ``control.ss`` accepts (a
        transfer function) is converted.
    omega : array_like
        Angular frequencies [rad/s], 1-D, finite, >= 0 (a scalar is one frequency).
    inputs, outputs : list of str, optional
        Restrict to these named signals (default: all).
    rtol : float
        Accuracy wanted, relative to the largest response; a form that misses it (or 1e-8,
        whichever is looser) gives way to the next, and the last, the backward-stable Schur
        form, is returned unchecked.

    Returns
    -------
    control.FrequencyResponseData
        With the chosen signal names; ``.complex`` has shape (p, m, len(omega)), squeezed by
        python-control for a SISO response to (len(omega),).

    Raises
    ------
    ValueError
        If ``omega`` is not a 1-D array of finite frequencies >= 0, or a name in ``inputs`` or
        ``outputs`` is not a signal of ``sys``.

    References
    ----------
    C. Bavely, G. W. Stewart, "An algorithm for computing reducing subspaces by block
    diagonalization", SIAM J. Numer. Anal. 16 (1979) 359-367. N. J. Higham, Accuracy and
    Stability of Numerical Algorithms, 2nd ed. (2002), ch. 7 and 12 (backward error of a
    linear system, iterative refinement).

    Examples
    --------
    A first-order lag has |H| = 1/sqrt(2) at its corner:

    >>> lag = control.ss(control.tf([1.0], [0.1, 1.0]))
    >>> round(abs(complex(fast_frequency_response(lag, [10.0]).complex.ravel()[0])), 6)
    0.707107
    """
    omega = _omega(omega)
    if not isinstance(sys, control.StateSpace):
        sys = control.ss(sys)
    labels_in, labels_out = sys.input_labels, sys.output_labels
    i_in = [labels_in.index(s) for s in inputs] if inputs else list(range(sys.ninputs))
    i_out = [labels_out.index(s) for s in outputs] if outputs else list(range(sys.noutputs))
    a, b, c = sys.A, sys.B[:, i_in], sys.C[i_out]
    d = sys.D[np.ix_(i_out, i_in)]
    if a.shape[0]:
        # balancing (a diagonal similarity) equalises the scales of the states (displacements
        # in m, currents in A, integrals ...), which the accuracy of every form needs; it is
        # done on the system matrix [[A, B], [C, 0]] (as SLICOT's TB01ID), not on A alone,
        # which can scale a state that only an input reaches by 1e20 and ruin B
        t = _system_balance(a, b, c)
        a = a * (1.0 / t)[:, None] * t[None, :]
        resp = _state_space_response(a, b / t[:, None], c * t[None, :], omega, rtol)
    else:
        resp = np.zeros((len(i_out), len(i_in), omega.size), dtype=complex)
    resp += d[:, :, None]
    return control.frd(resp, omega, inputs=[labels_in[i] for i in i_in],
                       outputs=[labels_out[i] for i in i_out])


_EPS = float(np.finfo(float).eps)


def _system_balance(a, b, c) -> np.ndarray:
    """Scales t of the states that balance the system matrix ``[[A, B], [C, 0]]`` (padded to a
    square), powers of 2 (so that scaling is exact): A -> T^-1 A T, B -> T^-1 B, C -> C T."""
    n, m, p = a.shape[0], b.shape[1], c.shape[0]
    k = max(m, p)
    z = np.zeros((n + k, n + k))
    z[:n, :n] = a
    z[:n, n:n + m] = np.abs(b)
    z[n:n + p, :n] = np.abs(c)
    _, (scale, _) = scipy.linalg.matrix_balance(z, permute=False, separate=True)
    return scale[:n] / scale[n] if k else scale[:n]


@dataclass(frozen=True)
class _BlockModalForm:
    """``A = S J S^-1``, J = diag(T, diag(lam)) with T upper triangular (k x k, k >= 0).

    ``cs = C S`` and ``sb = S^-1 B``; ``lu`` factors S (None when S is unitary, then
    S^-1 = S^H).
    """

    t: np.ndarray
    lam: np.ndarray
    s: np.ndarray
    lu: tuple | None
    cs: np.ndarray
    sb: np.ndarray

    def solve_s(self, rhs):
        """S^-1 rhs."""
        if self.lu is None:
            return self.s.conj().T @ rhs
        return scipy.linalg.lu_solve(self.lu, rhs, check_finite=False)

    def inner(self, rhs, omega):
        """(jw I - J)^-1 rhs for rhs (n, m): shape (n, m, K)."""
        k = self.t.shape[0]
        out = np.empty((rhs.shape[0], rhs.shape[1], omega.size), dtype=complex)
        if k:
            out[:k] = _triangular_solve(self.t, rhs[:k], omega)
        if self.lam.size:
            out[k:] = rhs[k:, :, None] / (1j * omega[None, None, :] - self.lam[:, None, None])
        return out

    def response(self, omega):
        """C (jw I - A)^-1 B, shape (p, m, K)."""
        k = self.t.shape[0]
        p, m = self.cs.shape[0], self.sb.shape[1]
        out = np.zeros((p, m, omega.size), dtype=complex)
        if self.lam.size:
            residues = (self.cs[:, None, k:] * self.sb.T[None, :, k:]).reshape(p * m, -1)
            out += _pole_sum(residues, self.lam, omega).reshape(p, m, omega.size)
        if k:
            out += np.einsum("pk,kmw->pmw", self.cs[:, :k],
                             _triangular_solve(self.t, self.sb[:k], omega))
        return out


def _pole_sum(residues, lam, omega):
    """sum_i R_i / (jw - lam_i) for residues (q, n) and poles (n,), by a compiled kernel
    (for many residue rows: the terms 1/(jw - lam_i) by the kernel, the sums as one real
    matrix product)."""
    from ._frequency_kernels import pole_sum, pole_terms

    n, q = lam.size, residues.shape[0]
    lr, li = np.ascontiguousarray(lam.real), np.ascontiguousarray(lam.imag)
    if q <= 8:
        out = np.zeros((2, q, omega.size))
        pole_sum(np.ascontiguousarray(residues.real), np.ascontiguousarray(residues.imag),
                 lr, li, omega, out[0], out[1])
        return out[0] + 1j * out[1]
    terms = np.empty((2 * n, omega.size))
    pole_terms(lr, li, omega, terms[:n], terms[n:])
    rr, ri = residues.real, residues.imag
    both = np.block([[rr, -ri], [ri, rr]]) @ terms  # (2q, K): real parts, imaginary parts
    return both[:q] + 1j * both[q:]


def _triangular_solve(t, rhs, omega, chunk: int = 512):
    """(jw I - T)^-1 rhs for T upper triangular (k, k), rhs (k, m): back substitution over
    the rows, vectorised over the frequencies; O(k^2 m) per frequency. Shape (k, m, K)."""
    k = t.shape[0]
    out = np.empty((k, rhs.shape[1], omega.size), dtype=complex)
    diag = np.diag(t)
    for lo in range(0, omega.size, chunk):
        s = 1j * omega[lo:lo + chunk]
        x = np.empty((k, rhs.shape[1], s.size), dtype=complex)
        for i in range(k - 1, -1, -1):
            acc = np.broadcast_to(rhs[i][:, None], x.shape[1:])
            if i < k - 1:
                acc = acc + np.tensordot(t[i, i + 1:], x[i + 1:], axes=1)
            with np.errstate(divide="ignore", invalid="ignore"):
                x[i] = acc / (s - diag[i])
        out[:, :, lo:lo + chunk] = x
    return out


def _modal_form(a, b, c):
    """Form 1: the eigenvectors (S = V, J = diag(lambda)); None if they are singular."""
    lam, v = np.linalg.eig(a)
    try:
        lu = scipy.linalg.lu_factor(v, check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        return None
    if not np.all(np.isfinite(lu[0])) or np.any(np.abs(np.diag(lu[0])) == 0.0):
        return None
    sb = scipy.linalg.lu_solve(lu, b.astype(complex), check_finite=False)
    if not np.all(np.isfinite(sb)):
        return None
    return _BlockModalForm(np.zeros((0, 0), complex), lam, v, lu, c @ v, sb)


def _condition_numbers(form):
    """Condition number ||v_i|| ||w_i|| of each eigenvalue (v_i the eigenvectors, w_i the rows
    of V^-1); large for nearly defective eigenvalues."""
    w = scipy.linalg.lu_solve(form.lu, np.eye(form.s.shape[0]), check_finite=False)
    return np.linalg.norm(w, axis=1) * np.linalg.norm(form.s, axis=0)


def _deflated_form(a, b, c, lam, split):
    """Form 2: the eigenvalues ``lam[split]`` (bool mask) in a triangular block, the rest
    modal. Ordered complex Schur form (ZTRSEN), the off-diagonal block removed by a
    Sylvester equation (ZTRSYL), eigenvectors of the remaining triangular block."""
    n = a.shape[0]
    k = int(split.sum())
    if k == 0 or k == n:
        return None
    t, z = scipy.linalg.schur(a, output="complex", check_finite=False)
    # mark the Schur diagonal entries nearest to the split eigenvalues (one each)
    diag = np.diag(t).copy()
    select = np.zeros(n, dtype=np.int32)
    for value in lam[split]:
        dist = np.abs(diag - value)
        dist[select.astype(bool)] = np.inf
        select[int(np.argmin(dist))] = 1
    ztrsen = scipy.linalg.lapack.ztrsen
    t, z, _, m, _, _, info = ztrsen(select, t, z, job="N")
    if info != 0 or m != k:
        return None
    t11, t12, t22 = t[:k, :k], t[:k, k:], t[k:, k:]
    x, scale, info = scipy.linalg.lapack.ztrsyl(t11, t22, -t12, isgn=-1)
    if info < 0 or not np.all(np.isfinite(x)) or scale == 0.0:
        return None
    x = x / scale
    lam2, v2 = np.linalg.eig(t22)
    # S = Z [[I, X], [0, I]] diag(I, V2)
    s = np.empty((n, n), dtype=complex)
    s[:, :k] = z[:, :k]
    s[:, k:] = (z[:, :k] @ x + z[:, k:]) @ v2
    try:
        lu = scipy.linalg.lu_factor(s, check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        return None
    sb = scipy.linalg.lu_solve(lu, b.astype(complex), check_finite=False)
    if not np.all(np.isfinite(sb)):
        return None
    return _BlockModalForm(t11, lam2, s, lu, c @ s, sb)


def _schur_form(a, b, c):
    """Form 3: the complex Schur form A = Z T Z^H (backward stable)."""
    t, z = scipy.linalg.schur(a, output="complex", check_finite=False)
    return _BlockModalForm(t, np.zeros(0, complex), z, None, c @ z, z.conj().T @ b)


class _DirectSolves:
    """The reference responses ``C (jw I - A)^-1 B`` of the a posteriori check, by solves
    with the Hessenberg form ``A = Q H Q^T`` (computed once, on first use): Gaussian
    elimination with partial pivoting on ``jw I - H`` is backward stable like a dense LU of
    ``jw I - A`` and costs O(n^2) per frequency instead of O(n^3)."""

    def __init__(self, a, b, c):
        self.a, self.b, self.c = a, b, c
        self._form = None

    def __call__(self, omega: np.ndarray) -> np.ndarray:
        from ._frequency_kernels import hessenberg_solve

        if self._form is None:
            h, q = scipy.linalg.hessenberg(self.a, calc_q=True, check_finite=False)
            self._form = (np.ascontiguousarray(h), np.ascontiguousarray(q.T @ self.b,
                                                                        dtype=complex),
                          self.c @ q)
        h, qtb, cq = self._form
        x = np.empty((omega.size, h.shape[0], qtb.shape[1]), dtype=complex)
        hessenberg_solve(h, np.ascontiguousarray(omega, dtype=float), qtb, x)
        return np.moveaxis(cq @ x, 0, -1)


def _accepted(form, direct: _DirectSolves, omega_chk, y_chk, rtol) -> bool:
    """The a posteriori check of a form at a few frequencies (see fast_frequency_response):
    its responses against direct solves ``C (jw I - A)^-1 B`` there (:class:`_DirectSolves`),
    within ``rtol`` or 1e-8 (relative to the largest), whichever is looser (a direct solve is
    itself accurate only to the conditioning of jw I - A, a few 1e-10 for a loop with an
    integrator and a rigid body). The direct solve is the reference because a form built on
    a badly scaled B (balancing A alone can scale an input row by 1e20) loses digits to
    cancellation in its modal sum while its own residual still looks small."""
    y = direct(omega_chk)
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(y_chk))):
        return False
    scale = max(float(np.abs(y).max()), 1e-300)
    err = float(np.abs(y_chk - y).max()) / scale
    return bool(np.isfinite(err) and err <= max(rtol, 1e-8))


def _state_space_response(a, b, c, omega, rtol):
    """C (jw I - A)^-1 B for a balanced A, shape (p, m, K): forms 1, 2, 3 (see
    :func:`fast_frequency_response`)."""
    with np.errstate(all="ignore"):  # a failed form may overflow; the checks reject it
        return _forms_response(a, b, c, omega, rtol)


def _forms_response(a, b, c, omega, rtol):
    form = _modal_form(a, b, c)
    direct = _DirectSolves(a, b, c)
    if form is not None:
        resp = form.response(omega)
        if _passes(form, resp, a, direct, omega, rtol):
            return resp
        # split off the eigenvalues with ill-conditioned eigenvectors (and those at s = 0)
        kappa = _condition_numbers(form)
        near_zero = np.abs(form.lam) < 1e-6 * max(float(np.abs(a).max()), 1e-300)
        split = near_zero | (kappa > max(10.0, 1e-3 * rtol / _EPS))
        deflated = _deflated_form(a, b, c, form.lam, split)
        if deflated is not None:
            resp = deflated.response(omega)
            if _passes(deflated, resp, a, direct, omega, rtol):
                return resp
    return _schur_form(a, b, c).response(omega)


def _passes(form, resp, a, direct, omega, rtol) -> bool:
    check = _check_points(np.abs(resp).reshape(-1, omega.size).max(axis=0), omega, a)
    return _accepted(form, direct, omega[check], resp[:, :, check], rtol)


def _check_points(mag, omega, a):
    """Indices of the four largest responses, 24 spread over the grid and the grid points
    nearest to the frequency of every eigenvalue of A (where an ill-conditioned eigenvector
    spoils the modal sum, the error is largest near its pole, between the other points)."""
    finite = np.where(np.isfinite(mag), mag, np.inf)
    lam = np.linalg.eigvals(a)
    near = np.searchsorted(omega, np.abs(lam.imag))
    near = np.clip(np.concatenate([near, near - 1]), 0, omega.size - 1)
    return np.unique(np.concatenate([np.argsort(finite)[-4:],
                                     np.linspace(0, mag.size - 1, 24).astype(int), near]))


def _modal_data(structure: ModalModel):
    """(omega_r^2, modal damping 2 zeta_r omega_r, mass-normalised shapes) when the damping
    is diagonal in the undamped modes (as :class:`ModalModel` builds it), else None."""
    wr = structure.natural_frequencies()
    phi = structure.mode_shapes()
    modal_d = phi.T @ structure.damping @ phi
    off = modal_d - np.diag(np.diag(modal_d))
    if np.abs(off).max(initial=0.0) > 1e-9 * max(np.abs(modal_d).max(initial=0.0), 1e-300):
        return None
    return wr * wr, np.ascontiguousarray(np.diag(modal_d)), phi


def _receptance_between(structure: ModalModel, omega, left, right) -> np.ndarray:
    """``left^T H(jw) right`` for DOF-space vectors left (n, p), right (n, q): the structure's
    receptance between combinations of DOFs, shape (p, q, K).

    Modal sum with the terms 1/(w_r^2 - w^2 + j w d_r) from a compiled kernel and the sums as
    one real matrix product, or the direct solution when the damping is not modal.
    """
    data = _modal_data(structure)
    if data is None:
        x = np.empty((omega.size, structure.n, right.shape[1]), dtype=complex)
        for j, w in enumerate(omega):
            dyn = structure.stiffness - w * w * structure.mass + 1j * w * structure.damping
            x[j] = np.linalg.solve(dyn, right)
        return np.moveaxis(left.T @ x, 0, -1)
    from ._frequency_kernels import mode_terms

    omega2, damping, phi = data
    r = omega2.size
    terms = np.empty((2 * r, omega.size))
    mode_terms(omega2, damping, omega, terms[:r], terms[r:])
    pl, pr = left.T @ phi, right.T @ phi  # (p, r), (q, r)
    shapes = (pl[:, None, :] * pr[None, :, :]).reshape(-1, r)
    both = shapes @ terms.reshape(2, r, omega.size)  # (2, p q, K)
    return (both[0] + 1j * both[1]).reshape(pl.shape[0], pr.shape[0], omega.size)


def modal_receptance(structure: ModalModel, omega, inputs, outputs) -> np.ndarray:
    """Receptance X/F(j omega) of the structure alone from the modal sum.

    ``H(jw) = sum_r phi_r phi_r^T / (omega_r^2 - w^2 + 2 j zeta_r omega_r w)`` with
    mass-normalised real modes; exact when the damping matrix is diagonal in modal coordinates
    (modal damping, as :class:`ModalModel` builds it). Otherwise the direct solve of
    ``(K - w^2 M + j w D) X = F`` is used.

    Parameters
    ----------
    structure : ModalModel
        The structure (mass, damping and stiffness matrices over its named DOFs).
    omega : array_like
        Angular frequencies [rad/s], 1-D, finite, >= 0.
    inputs : sequence of str
        DOFs where the forces [N] act.
    outputs : sequence of str
        DOFs whose displacements [m] are returned.

    Returns
    -------
    numpy.ndarray
        Complex receptance [m/N], shape (len(outputs), len(inputs), len(omega)).

    Raises
    ------
    ValueError
        If ``omega`` is not a 1-D array of finite frequencies >= 0.
    UnknownDofError
        A DOF the structure does not have.
    """
    omega = _omega(omega)
    i_in, i_out = structure.index(list(inputs)), structure.index(list(outputs))
    eye = np.eye(structure.n)
    return _receptance_between(structure, omega, eye[:, i_out], eye[:, i_in])


def _tf_values(tf, s: np.ndarray) -> np.ndarray:
    """A SISO transfer function evaluated at complex frequencies (vectorised)."""
    num = np.asarray(tf.num[0][0], dtype=float)
    den = np.asarray(tf.den[0][0], dtype=float)
    return np.polyval(num, s) / np.polyval(den, s)


def port_compliance(structure: ModalModel, omega, drive: Drive | None = None,
                    contact: Contact | None = None, pads=(), force: str = "wp.x",
                    outputs=("wp.x",), check_stability: bool = False) -> np.ndarray:
    """Closed-loop compliance by coupling the structure's port receptances (no state space).

    The contacts and the motor act on the structure through a few generalised forces: the
    force f_p of each of the n pads and the motor torque T (on the rotor, and its reaction on
    the stator: the direction ``rel``, phi = rel . x the rotor minus stator angle). At each
    frequency they depend on port displacements:

    * pad: ``f_p = -(k + j w c)/n * x_p`` for spring/damper contacts, or
      ``f_p = -Z(jw)/n * j w x_p`` for a dynamic (sliding) contact Z: v -> F;
    * motor: ``T = (C_i T_set - kt ke j w phi) / (j w L + R + C_i)`` with
      ``T_set = F_lp F_notch C_v (omega_cmd - j w phi)``,
      ``omega_cmd = -(Kv / r) x_fb`` (no reference), x_fb the encoder (or r phi).

    With the structure's receptances H between the force DOF, the outputs, the pads, ``rel``
    and the feedback (from the modal sum, :func:`modal_receptance`), the displacements are
    ``x = H_F + H_u u`` for u = (f_1 .. f_n, T), so u solves the (n + 1) x (n + 1) system
    ``u = G(jw) (H_F + H_u u)`` at each frequency (a compiled batched elimination), and the
    outputs follow. The cost grows with the number of modes times the number of ports
    squared, not with the cube of the closed loop's state dimension.

    Parameters
    ----------
    structure : ModalModel
        The reduced structure.
    omega : array_like
        Angular frequencies [rad/s], 1-D, finite, >= 0.
    drive : Drive, optional
        The cascade (default: none, the structure with its contacts only).
    contact : Contact, optional
        Guide-way model, axis totals shared equally by the pads (default: free). A ``locked``
        contact removes the pad DOFs from the structure.
    pads : sequence of str
        The pad DOFs where the contact acts (ignored by a ``free`` contact; any other contact
        needs them).
    force : str
        DOF of the exciting force [N].
    outputs : sequence of str
        DOFs whose displacements [m] are returned.
    check_stability : bool, optional
        Check, as :func:`compliance` does, that the coupled system is stable (its poles from
        :func:`~servotune.plant.build_plant` and :func:`require_stable`) when it can be
        unstable: with a drive, or with a dynamic (sliding) contact; springs and dampers
        alone on the structure are passive and are not checked. Off by default: the check
        builds the closed loop's state space and solves its eigenvalue problem, several
        times the cost of the coupling itself, and the callers that judge designs check (or
        report) stability on their own. Pass True wherever the stability is not known.

    Returns
    -------
    numpy.ndarray
        Complex compliance, shape (len(outputs), len(omega)) [m/N].

    Raises
    ------
    ValueError
        If ``omega`` is not a 1-D array of finite frequencies >= 0, or a contact other than
        ``free`` is given without pads.
    UnstableLoopError
        If ``check_stability`` and the coupled system is unstable (the message names the
        unstable poles): a compliance of an unstable loop means nothing.
    UnknownDofError
        A force, output, pad, motor or encoder DOF the structure does not have.

    Notes
    -----
    Without ``check_stability`` the stability of the loop is not checked: for an unstable
    loop the result is the (meaningless) steady-state response formula.
    """
    omega = _omega(omega)
    contact = Contact.free() if contact is None else contact
    pads = list(pads)
    if contact.pads != "free" and not pads:
        raise ValueError(f"a {contact.kind!r} contact needs the pad DOFs (pads=...)")
    if check_stability and (drive is not None or contact.system is not None):
        what = "closed-loop axis" if drive is not None else "axis with its sliding contact"
        require_stable(build_plant(structure, drive, contact, pads), what=what)
    if contact.pads == "locked":
        structure = structure.locked(pads)
    if contact.pads != "contact":
        pads = []
    outputs = list(outputs)
    n_dof = structure.n
    eye = np.eye(n_dof)
    # the ports as DOF-space vectors: force, outputs, pads, then rel and the feedback
    columns = [eye[:, int(structure.index(force))]]
    columns += [eye[:, int(structure.index(o))] for o in outputs]
    columns += [eye[:, int(structure.index(p))] for p in pads]
    if drive is not None:
        m = drive.motor
        rel = eye[:, int(structure.index(m.rotor))].copy()
        if m.stator:
            rel -= eye[:, int(structure.index(m.stator))]
        fb = (eye[:, int(structure.index(drive.encoder))] if drive.feedback == "linear"
              else drive.ratio * rel)
        columns += [rel, fb]
    ports = np.column_stack(columns)
    i_out = 1 + np.arange(len(outputs))
    i_pad = 1 + len(outputs) + np.arange(len(pads))
    acting = list(i_pad) + ([ports.shape[1] - 2] if drive is not None else [])  # f_p, T
    rec = _receptance_between(structure, omega, ports, ports[:, [0, *acting]])
    h_f, h_u = rec[:, 0], rec[:, 1:]  # (ports, K), (ports, n_u, K)
    n_u = len(acting)
    if n_u == 0:
        return h_f[i_out]
    s = 1j * omega
    # u = G x: each pad force from its pad's displacement, the torque from the rotor-stator
    # angle (port -2) and the feedback (port -1); then (I - G H_u) u = G H_F
    gh = np.empty((omega.size, n_u, n_u), dtype=complex)
    u = np.empty((omega.size, n_u), dtype=complex)
    if pads:
        if contact.system is not None:
            z = _tf_values(control.tf(contact.system), s) * s
        else:
            z = contact.stiffness + s * contact.damping
        g_pad = -z / len(pads)
        for j, col in enumerate(i_pad):
            gh[:, j, :] = (g_pad * h_u[col]).T
            u[:, j] = g_pad * h_f[col]
    if drive is not None:
        # the continuous cascade (servotune.drive.cascade_response):
        # T = -(a Kv/r x_fb + (a + b) s phi) / den
        parts = cascade_response(drive, s)
        den = parts.winding
        a = parts.current_forward * parts.setpoint * parts.velocity_pi
        b = m.torque_constant * m.back_emf_constant
        g_fb = -(a * drive.kv / drive.ratio) / den  # per feedback x
        g_rel = -(a + b) * s / den                  # per rotor angle
        gh[:, -1, :] = (g_fb * h_u[-1] + g_rel * h_u[-2]).T
        u[:, -1] = g_fb * h_f[-1] + g_rel * h_f[-2]
    lhs = np.eye(n_u)[None] - gh
    from ._frequency_kernels import solve_batched

    solve_batched(lhs, u)
    return h_f[i_out] + (h_u[i_out] * u.T[None]).sum(axis=1)


def compliance(plant: control.StateSpace, omega, force: str = "f_wp_x",
               output: str = "wp_x") -> np.ndarray:
    """Return the work-piece compliance [m/N] of a plant from :func:`~servotune.plant.build_plant`.

    The frequency response x/F from a force input to a displacement output of the linearised
    axis (the quantity of Bianchi et al. 2014, Fig 9), evaluated by
    :func:`fast_frequency_response` once the plant is checked stable (:func:`require_stable`;
    a rigid-body pole at the origin of an uncontrolled axis is accepted).

    Parameters
    ----------
    plant : control.StateSpace
        The linearised axis, with the named signals of :func:`~servotune.plant.build_plant`.
    omega : array_like
        Angular frequencies [rad/s], 1-D, finite, >= 0.
    force : str
        Input signal: the force [N] on the work piece (``f_wp_x``, ``f_wp_y``, ``f_wp_z``).
    output : str
        Output signal: the displacement [m] (``wp_x``, ``wp_y``, ``wp_z``, ``slide_x``).

    Returns
    -------
    numpy.ndarray
        Complex compliance [m/N], shape (len(omega),).

    Raises
    ------
    UnstableLoopError
        If the plant is unstable (a compliance of an unstable loop means nothing).
    ValueError
        If ``omega`` is not a 1-D array of finite frequencies >= 0, or ``force`` or ``output``
        is not a signal of the plant.

    See Also
    --------
    servotune.analysis.compliance_curve : The compliance of an axis description, with its peak.
    servotune.analysis.loop_report : Margins of the loops of the same axis.
    servotune.simulate.simulator.simulate : The nonlinear time response.

    Examples
    --------
    A 1 kg work piece on a 1e4 N/m spring with 2 % damping: the compliance is 1/k at low
    frequency and Q/k = 1/(2 zeta k) at resonance, sqrt(k/m) = 100 rad/s.

    >>> from servotune.plant import build_plant
    >>> from servotune.structure.model import ModalModel
    >>> plant = build_plant(ModalModel([[1.0]], [[1e4]], ["wp.x"], damping_ratio=0.02))
    >>> h = compliance(plant, [1e-3, 100.0])
    >>> [round(float(v) * 1e4, 3) for v in abs(h)]
    [1.0, 25.0]
    """
    require_stable(plant)
    frd = fast_frequency_response(plant, omega, inputs=[force], outputs=[output])
    return frd.complex[0, 0] if frd.complex.ndim == 3 else frd.complex


def peak(omega, response) -> tuple[float, float]:
    """Return the peak of a frequency response, refined between grid points.

    Near a resonance ``1/|H|^2`` is a quadratic in omega^2 (exactly so for one mode,
    ``(wn^2 - w^2)^2 + (2 zeta wn w)^2``), so a parabola through the three grid points around
    the maximum, in those coordinates, places the peak between them. At an end of the grid, or
    where the parabola does not open upwards or its vertex falls outside the three points, the
    grid maximum is returned.

    Parameters
    ----------
    omega : array_like
        Angular frequencies [rad/s], increasing, same length as ``response``.
    response : array_like
        Complex or real response at ``omega`` (any unit).

    Returns
    -------
    magnitude : float
        max |response|, in the unit of ``response``.
    frequency : float
        Where it occurs [rad/s].

    Raises
    ------
    ValueError
        If ``response`` is empty.
    """
    omega = np.asarray(omega, dtype=float)
    mag = np.abs(np.asarray(response)).reshape(-1)
    i = int(np.argmax(mag))
    if 0 < i < mag.size - 1:
        x = omega[i - 1:i + 2] ** 2
        y = 1.0 / mag[i - 1:i + 2] ** 2
        x0 = x[1]
        a, b, c = np.polyfit((x - x0) / x0, y / y[1], 2)
        if a > 0:
            xm = -b / (2 * a)
            if x[0] <= x0 * (1 + xm) <= x[2]:
                ym = (c - b * b / (4 * a)) * y[1]
                if ym > 0:
                    return float(1.0 / math.sqrt(ym)), float(math.sqrt(x0 * (1 + xm)))
    return float(mag[i]), float(omega[i])


#: Below this largest closed-loop gain |L/(1+L)| over the grid a loop does nothing
#: (:attr:`LoopAnalysis.inert`): a working loop follows its set-point, |T| -> 1.
INERT_GAIN = 0.1


@dataclass(frozen=True)
class LoopAnalysis:
    """Robustness of one loop from its loop transfer function L (SI; Hz/deg/dB at the edges).

    Attributes
    ----------
    gain_margin : float
        Gain margin [-]: the factor by which the loop gain may rise before the closed loop
        becomes unstable, 1/|L| at the phase crossings where |L| < 1 (inf when there is none).
    phase_margin : float
        Phase margin [rad].
    crossover : float
        Gain crossover |L| = 1 [rad/s].
    phase_crossover : float
        Phase crossover [rad/s] (nan when none).
    ms : float
        Sensitivity peak max |1/(1+L)| [-].
    ms_frequency : float
        Where Ms occurs [rad/s].
    bandwidth : float
        Closed-loop -3 dB bandwidth of L/(1+L) [rad/s].
    gain_margin_lower : float
        Lower gain margin [-] of a conditionally stable loop: the factor (< 1) to which the
        loop gain may fall before the closed loop becomes unstable, 1/|L| at the phase
        crossings where |L| > 1 (0 when there is none: any gain reduction is tolerated). A
        velocity loop around an open-loop unstable plant (a sliding contact whose friction
        falls with speed) or with integrators has one.

    Notes
    -----
    The phase crossings lie on the negative real axis of the Nyquist plot, at -|L|; the gain
    may change by a factor k as long as no crossing passes -1, so the nearest crossing left
    of -1 bounds k from below and the nearest one right of it from above (Skogestad and
    Postlethwaite, "Multivariable Feedback Control", 2nd ed., sec 2.4.3).
    """

    gain_margin: float
    phase_margin: float
    crossover: float
    phase_crossover: float
    ms: float
    ms_frequency: float
    bandwidth: float
    gain_margin_lower: float = 0.0
    closed_loop_gain_max: float = math.nan

    @property
    def inert(self) -> bool:
        """Whether the loop does nothing: its closed-loop gain |L/(1+L)| stays below
        :data:`INERT_GAIN` over the grid (the actuator does not move what the loop measures).
        Its margins and Ms then describe no working loop, and it has no bandwidth (nan)."""
        return bool(self.closed_loop_gain_max < INERT_GAIN)

    @property
    def gain_margin_db(self) -> float:
        """Gain margin in dB (inf when there is none)."""
        return 20.0 * math.log10(self.gain_margin) if self.gain_margin > 0 else -math.inf

    @property
    def gain_margin_lower_db(self) -> float:
        """Lower gain margin in dB (negative; -inf when there is none)."""
        return (20.0 * math.log10(self.gain_margin_lower) if self.gain_margin_lower > 0
                else -math.inf)

    @property
    def phase_margin_deg(self) -> float:
        """Phase margin in degrees."""
        return math.degrees(self.phase_margin)

    @property
    def bandwidth_hz(self) -> float:
        """Closed-loop bandwidth in Hz."""
        return self.bandwidth * HZ_PER_RAD_S

    def to_dict(self) -> dict:
        """Return the analysis JSON-ready: SI plus the usual engineering units.

        Returns
        -------
        dict
            ``gain_margin`` [-], ``gain_margin_db``, ``gain_margin_lower_db`` [dB],
            ``phase_margin_deg`` [deg], ``crossover_hz``, ``phase_crossover_hz``,
            ``ms_frequency_hz``, ``bandwidth_hz`` [Hz], ``ms`` [-]; None where a value is
            infinite, nan or absent.
        """
        gm_db = self.gain_margin_db
        return {
            "gain_margin": self.gain_margin if math.isfinite(self.gain_margin) else None,
            "gain_margin_db": gm_db if math.isfinite(gm_db) else None,
            "gain_margin_lower_db": (self.gain_margin_lower_db
                                     if self.gain_margin_lower > 0 else None),
            "phase_margin_deg": self.phase_margin_deg,
            "crossover_hz": self.crossover * HZ_PER_RAD_S,
            "phase_crossover_hz": (self.phase_crossover * HZ_PER_RAD_S
                                   if math.isfinite(self.phase_crossover) else None),
            "ms": self.ms,
            "ms_frequency_hz": self.ms_frequency * HZ_PER_RAD_S,
            "bandwidth_hz": self.bandwidth_hz,
            "closed_loop_gain_max": (self.closed_loop_gain_max
                                     if math.isfinite(self.closed_loop_gain_max) else None),
            "inert": self.inert,
            **({"note": f"the loop does nothing: its closed-loop gain |L/(1+L)| stays below "
                        f"{self.closed_loop_gain_max:.3g} (the actuator does not move what the "
                        "loop measures: a structure held to the ground, a transmission of almost "
                        "nothing); its margins and Ms describe no working loop"}
               if self.inert else {}),
        }


def analyse_loop(loop: control.StateSpace, omega=None) -> LoopAnalysis:
    """Margins, sensitivity peak and bandwidth of a loop transfer function L(s).

    The closed loop L/(1+L) must be stable (checked on its poles).

    Parameters
    ----------
    loop : control.StateSpace
        SISO loop transfer function (see :func:`servotune.plant.loop_transfer`).
    omega : array_like, optional
        Dense grid [rad/s], 1-D, increasing; default 4000 log-spaced points over
        0.1 Hz .. 10 kHz. The crossings are interpolated between its points, so one outside
        the grid is not found.

    Returns
    -------
    LoopAnalysis
        Margins, crossovers, Ms and the -3 dB bandwidth (taken relative to the closed-loop
        gain two decades below the grid's lowest frequency).

    Raises
    ------
    UnstableLoopError
        If the closed loop is unstable.
    ValueError
        If ``omega`` is not a 1-D array of finite frequencies >= 0.

    See Also
    --------
    servotune.analysis.loop_report : Both loops of an axis description.

    Examples
    --------
    L = 1/s has infinite gain margin, 90 deg phase margin, Ms = 1 and a 1 rad/s bandwidth:

    >>> r = analyse_loop(control.ss(control.tf([1.0], [1.0, 0.0])))
    >>> round(r.phase_margin_deg, 3), round(r.ms, 3), round(r.bandwidth, 3)
    (90.0, 1.0, 1.0)
    """
    loop = control.ss(loop)
    closed = control.feedback(loop, 1.0)
    require_stable(closed, what="closed loop")
    omega = (2 * math.pi * np.geomspace(0.1, 1e4, 4000) if omega is None else _omega(omega))
    # margins and Ms need far less than the default 1e-10 (and the modal form then rarely falls
    # back to the slow per-frequency solves)
    l_jw = fast_frequency_response(loop, omega, rtol=1e-7).complex.reshape(-1)
    # the closed-loop gain two decades below the grid stands for the DC gain: the state
    # space's own dcgain() is ill-conditioned when the loop carries a rigid-body mode (a free
    # integrator of position)
    l_low = complex(fast_frequency_response(loop, [omega[0] / 100.0],
                                            rtol=1e-7).complex.reshape(-1)[0])
    return analyse_response(omega, l_jw, l_low)


def analyse_response(omega, l_jw, l_low: complex) -> LoopAnalysis:
    """Margins, sensitivity peak and bandwidth from a loop's frequency response.

    The closed loop's stability is the caller's to check (:func:`analyse_loop` checks the
    poles of a continuous loop, :class:`servotune.digital.SampledAxis` the multipliers of a
    sampled one).

    Parameters
    ----------
    omega : array_like
        Dense grid [rad/s], 1-D, increasing.
    l_jw : array_like of complex
        The loop transfer function on the grid.
    l_low : complex
        L two decades below the grid (the low-frequency reference of the bandwidth).

    Returns
    -------
    LoopAnalysis
        As :func:`analyse_loop`.

    Examples
    --------
    L = 1/(j w) on a grid: 90 deg phase margin, Ms 1, bandwidth 1 rad/s.

    >>> w = np.geomspace(0.01, 100.0, 2001)
    >>> r = analyse_response(w, 1.0 / (1j * w), 1.0 / (1j * 1e-4))
    >>> round(r.phase_margin_deg, 3), round(r.ms, 3), round(r.bandwidth, 3)
    (90.0, 1.0, 1.0)
    """
    omega = _omega(omega)
    l_jw = np.asarray(l_jw, dtype=complex).reshape(-1)
    sens = 1.0 / (1.0 + l_jw)
    ms, w_ms = peak(omega, sens)
    t = np.abs(l_jw / (1.0 + l_jw))
    mag = np.abs(l_jw)
    phase = np.unwrap(np.angle(l_jw))
    # gain crossover: last downward crossing of |L| = 1
    cross = np.nonzero((mag[:-1] >= 1.0) & (mag[1:] < 1.0))[0]
    if cross.size:
        i = cross[-1]
        f = (np.log(mag[i])) / (np.log(mag[i]) - np.log(mag[i + 1]))
        wc = float(np.exp(np.log(omega[i]) + f * (np.log(omega[i + 1]) - np.log(omega[i]))))
        pc = phase[i] + f * (phase[i + 1] - phase[i])
        pm = float(math.pi + pc - 2 * math.pi * math.floor((pc + math.pi) / (2 * math.pi)))
    else:
        wc, pm = math.nan, math.inf
    # phase crossings of -180 deg (mod 360): at -|L| on the Nyquist plot; the nearest one
    # inside the unit circle gives the (upper) gain margin, the nearest one outside it the
    # lower gain margin of a conditionally stable loop
    k = np.floor((phase + math.pi) / (2 * math.pi))
    flips = np.nonzero(np.diff(k) != 0)[0]
    gm, gm_lower, wpc = math.inf, 0.0, math.nan
    for i in flips:
        target = (max(k[i], k[i + 1])) * 2 * math.pi - math.pi
        f = (target - phase[i]) / (phase[i + 1] - phase[i])
        m_at = math.exp(math.log(mag[i]) + f * (math.log(mag[i + 1]) - math.log(mag[i])))
        if m_at < 1.0 and 1.0 / m_at < gm:
            gm = 1.0 / m_at
            wpc = float(omega[i] * (omega[i + 1] / omega[i]) ** f)
        elif m_at >= 1.0:
            gm_lower = max(gm_lower, 1.0 / m_at)
    t0 = abs(l_low / (1.0 + l_low))
    t_max = float(t.max())
    below = np.nonzero(t < t0 / math.sqrt(2.0))[0]
    if t_max < INERT_GAIN:
        bw = math.nan          # a loop that does nothing has no bandwidth
    elif below.size and below[0] > 0:
        i = below[0]
        f = (math.log(t0 / math.sqrt(2.0)) - math.log(t[i - 1])) / (
            math.log(t[i]) - math.log(t[i - 1]))
        bw = float(omega[i - 1] * (omega[i] / omega[i - 1]) ** f)
    else:
        bw = float(omega[below[0]]) if below.size else math.inf
    return LoopAnalysis(gain_margin=gm, phase_margin=pm, crossover=wc, phase_crossover=wpc,
                        ms=ms, ms_frequency=w_ms, bandwidth=bw, gain_margin_lower=gm_lower,
                        closed_loop_gain_max=t_max)


@dataclass(frozen=True)
class ClosedLoopPoles:
    """Closed-loop poles with their natural frequencies [rad/s] and damping ratios."""

    poles: np.ndarray
    natural_frequencies: np.ndarray
    damping_ratios: np.ndarray

    @property
    def stable(self) -> bool:
        """All poles strictly in the left half plane."""
        return bool(np.all(self.poles.real < 0))

    @property
    def least_damped(self) -> tuple[complex, float]:
        """The oscillatory pole with the smallest damping ratio, and that ratio."""
        osc = np.nonzero(np.abs(self.poles.imag) > 1e-9 * np.abs(self.poles).max())[0]
        if not osc.size:
            return complex("nan"), math.nan
        i = osc[np.argmin(self.damping_ratios[osc])]
        return complex(self.poles[i]), float(self.damping_ratios[i])


def closed_loop_poles(sys: control.StateSpace) -> ClosedLoopPoles:
    """Return the poles of a (closed-loop) system sorted by frequency, with wn and zeta.

    Parameters
    ----------
    sys : control.StateSpace
        The system (anything ``control.ss`` accepts).

    Returns
    -------
    ClosedLoopPoles
        The eigenvalues of A [rad/s] sorted by magnitude, their natural frequencies ``|p|``
        [rad/s] and damping ratios ``-Re(p)/|p|`` (1 for a pole at the origin); empty for a
        system without states.
    """
    p = np.linalg.eigvals(control.ss(sys).A) if control.ss(sys).nstates else np.array([])
    p = p[np.argsort(np.abs(p))]
    wn = np.abs(p)
    with np.errstate(divide="ignore", invalid="ignore"):
        zeta = np.where(wn > 0, -p.real / wn, 1.0)
    return ClosedLoopPoles(p, wn, zeta)


def _pole_resolution(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues of ``a`` and how far rounding can move each of them [rad/s].

    The first-order bound ``eps ||A_b|| kappa_i`` on the balanced matrix A_b, with the
    eigenvalue's condition number ``kappa_i = |y_i| |x_i| / |y_i^H x_i|`` (left and right
    eigenvectors), capped at ``kappa = 1/sqrt(eps)`` for a defective (Jordan) eigenvalue.
    """
    if not a.size:
        return np.array([], dtype=complex), np.array([])
    a_b, _ = scipy.linalg.matrix_balance(a, permute=False)
    lam, left, right = scipy.linalg.eig(a_b, left=True, right=True)
    eps = np.finfo(float).eps
    overlap = np.abs(np.sum(left.conj() * right, axis=0))
    size = np.linalg.norm(left, axis=0) * np.linalg.norm(right, axis=0)
    with np.errstate(divide="ignore"):
        kappa = np.minimum(size / overlap, 1.0 / math.sqrt(eps))
    return lam, eps * np.linalg.norm(a_b, 1) * kappa


def _stable(a: np.ndarray) -> bool:
    """The criterion of :func:`require_stable` for a state matrix, deciding by the eigenvalues
    alone where they settle it.

    The rounding term of the tolerance, ``10 eps ||A_b|| kappa_p``, lies between
    ``10 eps ||A_b||`` (kappa >= 1) and ``10 eps ||A_b|| / sqrt(eps)`` (the cap): a matrix whose
    poles all lie left of ``Re p = 1e-9 |p|`` is stable whatever the condition numbers, and one
    with a pole right of twice the largest tolerance is not. Only poles in between (e.g. the
    split double pole of a free mass) need the condition numbers, hence the eigenvectors. The
    two eigenvalue computations differ by rounding, far below the margins used.
    """
    if not a.size:
        return True
    a_b, _ = scipy.linalg.matrix_balance(a, permute=False)
    lam = scipy.linalg.eigvals(a_b, check_finite=False)
    edge = 1e-9 * np.abs(lam)
    if (lam.real <= edge).all():
        return True
    eps = np.finfo(float).eps
    if (lam.real > edge + 20.0 * eps * np.linalg.norm(a_b, 1) / math.sqrt(eps)).any():
        return False
    lam, resolution = _pole_resolution(a)
    return not (lam.real > 1e-9 * np.abs(lam) + 10.0 * resolution).any()


def is_stable_matrix(a: np.ndarray) -> bool:
    """Return whether the state matrix ``a`` is stable in the sense of :func:`require_stable`.

    Parameters
    ----------
    a : numpy.ndarray
        The state matrix (n, n).

    Returns
    -------
    bool
        False when a pole lies in the right half plane beyond what rounding could put there.
    """
    a = np.asarray(a, dtype=float)
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"a state matrix must be square, got shape {a.shape}")
    return _stable(a)


def is_stable(sys: control.StateSpace) -> bool:
    """Return whether ``sys`` is stable in the sense of :func:`require_stable`.

    Parameters
    ----------
    sys : control.StateSpace
        The system (anything ``control.ss`` accepts).

    Returns
    -------
    bool
        False when a pole lies in the right half plane beyond what rounding could put there.

    See Also
    --------
    require_stable : the same test, raising an error that names the unstable poles.
    """
    sys = control.ss(sys)
    return _stable(np.asarray(sys.A, dtype=float).reshape(sys.nstates, sys.nstates))


def require_stable(sys: control.StateSpace, what: str = "closed-loop axis") -> None:
    """Raise :class:`UnstableLoopError` naming the unstable poles if ``sys`` is unstable.

    A pole p counts as unstable when its real part exceeds what rounding of the system's
    matrix could give it, measured against the pole itself:

    ``Re p > 1e-9 |p| + 10 eps ||A_b|| kappa_p``

    with A_b the balanced state matrix and ``kappa_p`` the condition number of p (capped at
    ``1/sqrt(eps)``). A fast stable mode does not widen the tolerance of a slow pole, so a
    slowly diverging pole next to fast modes is found; poles on the imaginary axis (undamped
    modes) and at the origin (the rigid-body mode of an uncontrolled axis, an integrator),
    whose computed real parts are rounding only, are accepted.

    Parameters
    ----------
    sys : control.StateSpace
        The system (anything ``control.ss`` accepts).
    what : str
        What the system is, for the message.

    Raises
    ------
    UnstableLoopError
        If a pole lies in the right half plane (the message lists up to four of them).

    Notes
    -----
    An eigenvalue of a matrix perturbed by E moves by about ``kappa ||E||``; the eigenvalue
    solver's backward error is a small multiple of ``eps ||A_b||`` (Golub and Van Loan,
    *Matrix Computations*, 4th ed., sec. 7.2.2). A double pole at the origin (a free mass) is
    defective: rounding splits it into a pair ``+-d`` along the real axis, and its condition
    number is large in proportion, so the pair is accepted. The factor 10 covers the data
    of a reduced structure, whose rigid-body mode is singular only to rounding.

    Examples
    --------
    A pole at -1e6 rad/s does not hide one at +1e-4 rad/s:

    >>> fast_and_slow = control.ss(np.diag([-1e6, 1e-4]), np.ones((2, 1)), np.ones((1, 2)), 0)
    >>> try:
    ...     require_stable(fast_and_slow)
    ... except UnstableLoopError as err:
    ...     print(str(err).split(";")[0])
    the closed-loop axis is unstable: 1 pole(s) in the right half plane (0.0001+0j rad/s)
    """
    sys = control.ss(sys)
    a = np.asarray(sys.A, dtype=float).reshape(sys.nstates, sys.nstates)
    if _stable(a):
        return
    lam, resolution = _pole_resolution(a)
    bad = lam[lam.real > 1e-9 * np.abs(lam) + 10.0 * resolution]
    if not bad.size:  # rounding between the two eigenvalue computations: name the poles
        bad = lam[lam.real > 1e-9 * np.abs(lam)]
    bad = bad[np.argsort(np.abs(bad))]
    if bad.size:
        listed = ", ".join(f"{p.real:.3g}{p.imag:+.3g}j" for p in bad[:4])
        raise UnstableLoopError(
            f"the {what} is unstable: {bad.size} pole(s) in the right half plane ({listed} "
            "rad/s); lower the loop gains (Kv, Kp) or raise Ti, or add damping")


def following_error(plant: control.StateSpace, feed: float) -> float:
    """Return the steady following error [m] at a constant feed [m/s] from the plant's DC behaviour.

    For a ramp x_ref = v t with v_ref = v, a_ref = 0, the error settles at
    ``v (G_xe'(0) + G_ve(0))`` where ``G'(0) = -C A^-2 B`` and ``G(0) = D - C A^-1 B``
    (``G_xe(0) = 0`` is assumed: the position loop has an integrator, so the error to a
    ramp does not grow).

    Parameters
    ----------
    plant : control.StateSpace
        The controlled axis of :func:`~servotune.plant.build_plant` (inputs ``x_ref``,
        ``v_ref``, output ``following_error``).
    feed : float
        Feed speed v [m/s].

    Returns
    -------
    float
        Steady following error [m], in the sign of the plant's ``following_error`` output.

    Raises
    ------
    UnstableLoopError
        If the plant is unstable.
    ValueError
        If the plant has no ``following_error`` output or no ``x_ref``/``v_ref`` input (a
        plant built without a drive).
    numpy.linalg.LinAlgError
        If A is singular (a pole at the origin).
    """
    require_stable(plant)
    sys = control.ss(plant)
    o = sys.output_labels.index("following_error")
    ix, iv = sys.input_labels.index("x_ref"), sys.input_labels.index("v_ref")
    a_inv_b = np.linalg.solve(sys.A, sys.B[:, [ix, iv]])
    slope = -sys.C[o] @ np.linalg.solve(sys.A, a_inv_b[:, 0])
    g_v0 = sys.D[o, iv] - sys.C[o] @ a_inv_b[:, 1]
    return float(feed * (slope + g_v0))
