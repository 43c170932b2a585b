"""Compiled (numba) kernels of :mod:`servotune.frequency`, imported on first use.

Each kernel is an elementwise map over (pole or mode, frequency) with the frequency loop
innermost, so that the compiler vectorises it without reordering any sum (the results do not
depend on how the kernel was compiled).
"""

from __future__ import annotations

import math

import numpy as np

from .cache import cached_njit

__all__ = ["pole_terms", "pole_sum", "mode_terms", "solve_batched", "hessenberg_solve"]


@cached_njit(error_model="numpy")
def pole_terms(lam_re, lam_im, omega, p, q):
    """``p + j q = 1 / (j omega_k - lambda_i)`` into p, q of shape (n, K)."""
    for i in range(lam_re.size):
        lr = lam_re[i]
        li = lam_im[i]
        l2 = lr * lr
        for k in range(omega.size):
            d = omega[k] - li
            inv = 1.0 / (l2 + d * d)
            p[i, k] = -lr * inv
            q[i, k] = -d * inv


@cached_njit(error_model="numpy")
def pole_sum(res_re, res_im, lam_re, lam_im, omega, out_re, out_im):
    """``out += sum_i R[:, i] / (j omega_k - lambda_i)`` for residues R (q, n), out (q, K)."""
    tp = np.empty(omega.size)
    tq = np.empty(omega.size)
    for i in range(lam_re.size):
        lr = lam_re[i]
        li = lam_im[i]
        l2 = lr * lr
        for k in range(omega.size):
            d = omega[k] - li
            inv = 1.0 / (l2 + d * d)
            tp[k] = -lr * inv
            tq[k] = -d * inv
        for j in range(res_re.shape[0]):
            rr = res_re[j, i]
            ri = res_im[j, i]
            for k in range(omega.size):
                out_re[j, k] += rr * tp[k] - ri * tq[k]
                out_im[j, k] += rr * tq[k] + ri * tp[k]


@cached_njit(error_model="numpy")
def mode_terms(omega2_r, damping_r, omega, p, q):
    """``p + j q = 1 / (omega_r^2 - omega_k^2 + j omega_k d_r)`` into p, q of shape (r, K)
    (d_r = 2 zeta_r omega_r, the modal damping)."""
    for i in range(omega2_r.size):
        w2 = omega2_r[i]
        c = damping_r[i]
        for k in range(omega.size):
            re = w2 - omega[k] * omega[k]
            im = omega[k] * c
            inv = 1.0 / (re * re + im * im)
            p[i, k] = re * inv
            q[i, k] = -im * inv


@cached_njit
def solve_batched(a, b):
    """Solve ``a[k] x[k] = b[k]`` for a stack of small complex systems (K, n, n), (K, n) in
    place (Gaussian elimination with partial pivoting); b receives x (NaN for a singular
    system)."""
    n = a.shape[1]
    for k in range(a.shape[0]):
        singular = False
        for c in range(n):
            piv = c
            big = abs(a[k, c, c])
            for i in range(c + 1, n):
                if abs(a[k, i, c]) > big:
                    big = abs(a[k, i, c])
                    piv = i
            if big == 0.0:
                singular = True
                break
            if piv != c:
                for j in range(n):
                    tmp = a[k, c, j]
                    a[k, c, j] = a[k, piv, j]
                    a[k, piv, j] = tmp
                tmp = b[k, c]
                b[k, c] = b[k, piv]
                b[k, piv] = tmp
            inv = 1.0 / a[k, c, c]
            for i in range(c + 1, n):
                f = a[k, i, c] * inv
                if f != 0.0:
                    for j in range(c + 1, n):
                        a[k, i, j] -= f * a[k, c, j]
                    b[k, i] -= f * b[k, c]
        if singular:
            for c in range(n):
                b[k, c] = complex(math.nan, math.nan)
            continue
        for c in range(n - 1, -1, -1):
            acc = b[k, c]
            for j in range(c + 1, n):
                acc -= a[k, c, j] * b[k, j]
            b[k, c] = acc / a[k, c, c]


@cached_njit
def hessenberg_solve(h, omega, rhs, out):
    """Solve ``(j omega_k I - H) x_k = rhs`` for an upper Hessenberg H (n, n), rhs (n, m)
    complex, x into out (K, n, m).

    Gaussian elimination with partial pivoting, where the pivot candidates of a Hessenberg
    matrix are the diagonal and the one subdiagonal entry: O(n^2 m) per frequency instead of
    the O(n^3) of a dense LU (the method of the Hessenberg frequency response: A. J. Laub,
    "Efficient multivariable frequency response computations", IEEE TAC 26 (1981) 407-408).
    A singular system gives NaN.
    """
    shifts = np.empty(omega.size, dtype=np.complex128)
    for k in range(omega.size):
        shifts[k] = 1j * omega[k]
    hessenberg_solve_shifts(h, shifts, rhs, out)


@cached_njit
def hessenberg_solve_shifts(h, shifts, rhs, out):
    """Solve ``(s_k I - H) x_k = rhs`` at complex shifts s_k (e.g. the points z of a discrete
    system's frequency response); otherwise as :func:`hessenberg_solve`."""
    n = h.shape[0]
    m = rhs.shape[1]
    w = np.empty((n, n), dtype=np.complex128)
    x = np.empty((n, m), dtype=np.complex128)
    for k in range(shifts.size):
        s = shifts[k]
        for i in range(n):
            for j in range(max(i - 1, 0), n):
                w[i, j] = -h[i, j]
            w[i, i] += s
            for r in range(m):
                x[i, r] = rhs[i, r]
        singular = False
        for c in range(n - 1):
            if abs(w[c + 1, c]) > abs(w[c, c]):
                for j in range(c, n):
                    tmp = w[c, j]
                    w[c, j] = w[c + 1, j]
                    w[c + 1, j] = tmp
                for r in range(m):
                    tmp = x[c, r]
                    x[c, r] = x[c + 1, r]
                    x[c + 1, r] = tmp
            if w[c, c] == 0.0:
                singular = True
                break
            f = w[c + 1, c] / w[c, c]
            if f != 0.0:
                for j in range(c + 1, n):
                    w[c + 1, j] -= f * w[c, j]
                for r in range(m):
                    x[c + 1, r] -= f * x[c, r]
        if singular or w[n - 1, n - 1] == 0.0:
            for i in range(n):
                for r in range(m):
                    out[k, i, r] = complex(math.nan, math.nan)
            continue
        for i in range(n - 1, -1, -1):
            inv = 1.0 / w[i, i]
            for r in range(m):
                acc = x[i, r]
                for j in range(i + 1, n):
                    acc -= w[i, j] * x[j, r]
                x[i, r] = acc * inv
        for i in range(n):
            for r in range(m):
                out[k, i, r] = x[i, r]
