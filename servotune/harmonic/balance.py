"""Multi-harmonic balance of the closed-loop axis, condensed to the guide-way pads.

The axis is linear except for the friction at its n pads. With the closed-loop receptance G of
the linear part (:mod:`servotune.harmonic.linear`: inputs the pad friction forces and the
work-piece force, outputs the pad and work-piece displacements), a periodic response to the
work-piece force ``F(t) = Re(F_a e^{j w t})`` satisfies, harmonic by harmonic (k = 1..H)::

    X_p,k = sum_q G_pq(j k w) (-Fr_q,k(X)) + G_pF(j w) F_a delta_k1       (p = 1..n)    (1)
    X_wp,k = sum_q G_wq(j k w) (-Fr_q,k(X)) + G_wF(j w) F_a delta_k1                    (2)

where Fr_q,k are the harmonics of pad q's friction force, computed from the pad velocities by
AFT (:mod:`servotune.harmonic.aft`). The unknowns are the pad displacement harmonics only,
n x 2H real numbers; (2) then gives the work-piece displacement. The drive's delays stay exact
(they are factors e^{-j k w tau} in G).

The mean (0th harmonic): while the axis feeds at constant speed V under position control, the
pads slide on average at exactly V (the position loop keeps the slide on its ramp, so the
deviation is bounded and its mean rate is zero). The pad velocity is therefore
``V + sum_k Re(j k w X_k e^{j k w t})``; the mean friction force (about Fc + sigma2 V) is taken
by the drive's integral action and only shifts the mean position, which no friction law here
depends on. So the mean term is known, not solved for: V = 0 at rest, V while feeding.

Equations (1) are solved by Newton's method. The Jacobian of the friction harmonics is
block-diagonal over the pads (each pad's force depends on its own motion only); per pad it is
``E dF/dv D`` with D the map from displacement harmonics to velocity samples, E the discrete
Fourier transform and dF/dv the exact derivative of the law's periodic force
(:func:`servotune.harmonic.aft.periodic_friction_jacobian`), or, for a law that gives only its
force, finite differences with all pads perturbed at once (2H evaluations per Jacobian).

References
----------
M. Krack, J. Gross, "Harmonic Balance for Nonlinear Vibration Problems", Springer (2019),
ch 2-4.
E. P. Petrov, D. J. Ewins, "Analytical formulation of friction interface elements for analysis
of nonlinear multi-harmonic vibrations of bladed disks", J. Turbomachinery 125 (2003) 364-371.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..friction.lugre import LuGreParameters
from .aft import (
    harmonics_from_samples,
    periodic_friction_force,
    periodic_friction_jacobian,
    samples_from_harmonics,
)
from .linear import PadReceptance

__all__ = ["HarmonicSettings", "PadBalance", "ConvergenceError"]


class ConvergenceError(RuntimeError):
    """Newton's method did not converge on the harmonic balance equations."""


@dataclass(frozen=True)
class HarmonicSettings:
    """Discretisation and tolerances of the harmonic balance.

    Parameters
    ----------
    harmonics : int
        H, the highest harmonic kept (1 is the describing-function approximation).
    samples : int, optional
        N, the instants per period of AFT (default: the power of 2 at least 6 H and 32, 64 for
        H = 9: the friction force's harmonics above N - H alias onto the kept ones, which moves
        the peak by 2e-4 of the value with N = 256 at 600 and 2000 N on the bundled axis, a
        fifth of the time simulation's 1e-3 it is checked against; docs/harmonic_balance.md).
    tolerance : float
        Newton stops when the norm of the residual of (1) is at most ``tolerance`` times the
        norm of the pad response (relative, in (0, 0.01); the continuation's corrector uses
        the same test).
    max_iterations : int
        Newton iterations per fixed-frequency solve (:meth:`PadBalance.solve`), at least 1.
    secant_updates : int
        For a law without an exact derivative of its periodic force (no
        ``periodic_force_jacobian``; LuGre has one): how many times the finite-difference
        Jacobian of the friction harmonics (2H + 1 law evaluations per pad) is carried on by
        Broyden's rank-one update (one evaluation per pad) before it is taken afresh; it is
        taken afresh too when the frequency moves by more than 2 % or the pad response by more
        than 20 % since. The solutions are those of the residual either way (Newton's test is
        on the residual); 0 takes it afresh every time (Broyden 1965; Kelley, Iterative Methods
        for Linear and Nonlinear Equations, SIAM 1995, ch 7).

    Raises
    ------
    ValueError
        If ``harmonics`` is not a whole number >= 1, ``samples`` not a whole number > 2 H,
        ``tolerance`` not in (0, 0.01) or ``max_iterations`` below 1.
    """

    harmonics: int = 9
    samples: int | None = None
    tolerance: float = 1e-8
    max_iterations: int = 40
    secant_updates: int = 8

    def __post_init__(self) -> None:
        h = int(self.harmonics)
        if h < 1 or h != self.harmonics:
            raise ValueError(f"harmonics must be a whole number >= 1, got {self.harmonics!r}")
        n = self.samples
        if n is None:
            n = 1 << max(5, math.ceil(math.log2(6 * h)))
        if int(n) != n or n <= 2 * h:
            raise ValueError(f"samples must be a whole number > 2 harmonics ({2 * h}), got {n!r}")
        object.__setattr__(self, "samples", int(n))
        if not (0.0 < self.tolerance < 1e-2):
            raise ValueError(f"tolerance must be in (0, 0.01), got {self.tolerance!r}")
        if (isinstance(self.max_iterations, bool) or int(self.max_iterations) != self.max_iterations
                or self.max_iterations < 1):
            raise ValueError("HarmonicSettings.max_iterations must be a whole number >= 1, got "
                             f"{self.max_iterations!r}")
        object.__setattr__(self, "max_iterations", int(self.max_iterations))
        if (isinstance(self.secant_updates, bool) or int(self.secant_updates) != self.secant_updates
                or self.secant_updates < 0):
            raise ValueError("HarmonicSettings.secant_updates must be a whole number >= 0, got "
                             f"{self.secant_updates!r}")
        object.__setattr__(self, "secant_updates", int(self.secant_updates))


class PadBalance:
    """The harmonic balance equations (1) of one axis, force level and speed.

    Parameters
    ----------
    receptance : PadReceptance
        The linear part, G of (1) and (2) (:func:`~servotune.harmonic.linear.pad_receptance`).
    law : object
        The friction law (axis totals, shared equally by the pads), reached through
        :func:`~servotune.harmonic.aft.periodic_friction_force`.
    force_amplitude : float
        F_a [N], half the peak-to-peak work-piece force.
    speed : float
        Mean pad sliding speed V [m/s] (0 at rest).
    settings : HarmonicSettings, optional
        Harmonics, AFT samples and tolerances (default ``HarmonicSettings()``).

    Notes
    -----
    The unknown vector ``y`` holds, pad by pad, ``Re X_1..Re X_H, Im X_1..Im X_H`` [m]
    (n x 2H real numbers). The residual is ``R(y, w) = y - [G_pF F_a delta_k1 - G_pp Fr(y)]``,
    equation (1) in real form, and its Jacobian ``I + G_pp dFr/dy`` with ``dFr/dy``
    block-diagonal over the pads (Krack and Gross 2019, ch 2-4, with the condensation to the
    nonlinear DOFs of sec 3.4 and AFT of sec 3.5).
    """

    def __init__(self, receptance: PadReceptance, law, force_amplitude: float,
                 speed: float = 0.0, settings: HarmonicSettings | None = None) -> None:
        self.receptance = receptance
        self.law = law
        self.force_amplitude = float(force_amplitude)
        self.speed = float(speed)
        self.settings = settings or HarmonicSettings()
        self.n_pads = receptance.n_pads
        self.harmonics = self.settings.harmonics
        self.samples = self.settings.samples
        self.share = 1.0 / self.n_pads
        self._k = np.arange(1, self.harmonics + 1)
        self._cache = (None, None)
        self._secant = None   # (y, omega, friction harmonics, their Jacobian, updates since FD)
        self._pad_law, self._pad_share = law, self.share
        if not callable(getattr(law, "periodic_force", None)):
            params = law if isinstance(law, LuGreParameters) else getattr(law, "params", None)
            if isinstance(params, LuGreParameters):   # scaled once, not at every evaluation
                self._pad_law, self._pad_share = params.scaled(self.share), 1.0
        theta = 2.0 * math.pi * np.outer(np.arange(self.samples), self._k) / self.samples
        cos, sin = np.cos(theta), np.sin(theta)                     # (N, H)
        self._synthesis = np.hstack([-sin, -cos]) * np.tile(self._k, 2)   # v per (Re, Im) X / w
        self._analysis = np.vstack([cos.T, -sin.T]) * (2.0 / self.samples)   # (2H, N)

    @property
    def size(self) -> int:
        """Number of real unknowns, n x 2H."""
        return 2 * self.n_pads * self.harmonics

    def _g(self, omega: float) -> np.ndarray:
        if self._cache[0] != omega:
            self._cache = (omega, self.receptance(omega * self._k))
        return self._cache[1]

    def complex_of(self, y) -> np.ndarray:
        """Return the pad displacement harmonics from the real unknowns.

        Parameters
        ----------
        y : array_like, shape (n 2H,)
            Real unknowns [m], pad by pad ``Re X_1..Re X_H, Im X_1..Im X_H``.

        Returns
        -------
        numpy.ndarray, complex, shape (n, H)
            X_p,k [m].
        """
        y = np.asarray(y, dtype=float).reshape(self.n_pads, 2, self.harmonics)
        return y[:, 0] + 1j * y[:, 1]

    def real_of(self, x) -> np.ndarray:
        """Return the real unknowns of complex pad harmonics.

        Parameters
        ----------
        x : numpy.ndarray, complex, shape (n, H)
            X_p,k [m].

        Returns
        -------
        numpy.ndarray, shape (n 2H,)
            Pad by pad ``Re X_1..Re X_H, Im X_1..Im X_H`` [m] (the inverse of
            :meth:`complex_of`).
        """
        return np.stack([x.real, x.imag], axis=1).reshape(-1)

    def friction_harmonics(self, x, omega: float) -> np.ndarray:
        """Return the friction force harmonics of every pad by AFT.

        Parameters
        ----------
        x : numpy.ndarray, complex, shape (n, H)
            Pad displacement harmonics [m].
        omega : float
            Angular frequency [rad/s].

        Returns
        -------
        numpy.ndarray, complex, shape (n, H)
            Friction force harmonics Fr_p,k [N] (along positive pad velocity), from the pad
            velocities ``V + sum_k Re(j k w X_k e^{j k w t})`` at the N AFT instants.
        """
        period = 2.0 * math.pi / omega
        v = samples_from_harmonics(1j * omega * self._k * x, self.samples, self.speed)
        force = periodic_friction_force(self._pad_law, v, period, self._pad_share)
        return harmonics_from_samples(force, self.harmonics)[1]

    def _analytic_jacobian(self, x, omega: float):
        """Friction harmonics (n, H) and their real-form Jacobian (n, 2H, 2H), or None when
        the law gives no derivative."""
        period = 2.0 * math.pi / omega
        v = samples_from_harmonics(1j * omega * self._k * x, self.samples, self.speed)
        out = periodic_friction_jacobian(self._pad_law, v, period, self._pad_share,
                                         omega * self._synthesis)
        if out is None:
            return None
        force, dforce = out
        return harmonics_from_samples(force, self.harmonics)[1], self._analysis @ dforce

    def _excitation(self, omega: float) -> np.ndarray:
        g = self._g(omega)
        out = np.zeros((self.n_pads + 1, self.harmonics), dtype=complex)
        out[:, 0] = g[:, self.n_pads, 0] * self.force_amplitude
        return out

    def response(self, x, omega: float, friction=None) -> np.ndarray:
        """Return the pad and work-piece displacement harmonics by (1) and (2).

        Parameters
        ----------
        x : numpy.ndarray, complex, shape (n, H)
            Pad displacement harmonics [m] whose friction acts.
        omega : float
            Angular frequency [rad/s].
        friction : numpy.ndarray, complex, shape (n, H), optional
            Their friction harmonics [N], when already known (default: computed by
            :meth:`friction_harmonics`).

        Returns
        -------
        numpy.ndarray, complex, shape (n + 1, H)
            Pads, then the work piece [m].
        """
        g = self._g(omega)
        fr = self.friction_harmonics(x, omega) if friction is None else friction
        n = self.n_pads
        return self._excitation(omega) - np.einsum("oqk,qk->ok", g[:, :n], fr)

    def residual(self, y, omega: float) -> np.ndarray:
        """Return the residual of (1).

        Parameters
        ----------
        y : array_like, shape (n 2H,)
            Real unknowns [m].
        omega : float
            Angular frequency [rad/s].

        Returns
        -------
        numpy.ndarray, shape (n 2H,)
            ``y`` minus the pad harmonics that (1) gives for its friction, in real form [m].
        """
        x = self.complex_of(y)
        return np.asarray(y, dtype=float) - self.real_of(self.response(x, omega)[:self.n_pads])

    def _secant_jacobian(self, y, omega: float, fr) -> np.ndarray:
        """The friction Jacobian by finite differences, carried on by Broyden updates
        (``settings.secant_updates``) while the point stays near the last one."""
        n, h2 = self.n_pads, 2 * self.harmonics
        last = self._secant
        if last is not None and last[4] < self.settings.secant_updates:
            y0, w0, fr0, jac, age = last
            dy = (y - y0).reshape(n, h2)
            near = (abs(omega / w0 - 1.0) <= 0.02
                    and np.linalg.norm(y - y0) <= 0.2 * max(np.linalg.norm(y0), 1e-300))
            if near:
                df = (np.concatenate([fr.real, fr.imag], axis=1)
                      - np.concatenate([fr0.real, fr0.imag], axis=1))
                jac = jac.copy()
                for p in range(n):
                    step = dy[p]
                    norm2 = float(step @ step)
                    if norm2 > 0.0:
                        jac[p] += np.outer(df[p] - jac[p] @ step, step) / norm2
                self._secant = (np.array(y), omega, fr, jac, age + 1)
                return jac
        jac = self._friction_jacobian(y, omega, fr)
        self._secant = (np.array(y), omega, fr, jac, 0)
        return jac

    def _friction_jacobian(self, y, omega: float, base) -> np.ndarray:
        """d(friction harmonics, real form)/dy, block-diagonal: shape (n, 2H, 2H)."""
        n, h = self.n_pads, self.harmonics
        yy = np.asarray(y, dtype=float).reshape(n, 2 * h)
        scale = np.maximum(np.abs(yy).max(axis=1), 1e-15)
        f0 = np.concatenate([base.real, base.imag], axis=1)      # (n, 2H)
        jac = np.empty((n, 2 * h, 2 * h))
        for j in range(2 * h):
            step = 1e-7 * scale
            yp = yy.copy()
            yp[:, j] += step
            x = yp[:, :h] + 1j * yp[:, h:]
            fr = self.friction_harmonics(x, omega)
            jac[:, :, j] = (np.concatenate([fr.real, fr.imag], axis=1) - f0) / step[:, None]
        return jac

    def _g_real(self, omega: float) -> np.ndarray:
        """The pad-pad receptance as a real matrix acting on the real form, (n 2H, n 2H)."""
        g = self._g(omega)[:self.n_pads, :self.n_pads]     # (n, n, H)
        n, h = self.n_pads, self.harmonics
        out = np.zeros((n, 2, h, n, 2, h))
        idx = np.arange(h)
        re, im = g.real, g.imag
        out[:, 0, idx, :, 0, idx] = re.transpose(2, 0, 1)
        out[:, 0, idx, :, 1, idx] = -im.transpose(2, 0, 1)
        out[:, 1, idx, :, 0, idx] = im.transpose(2, 0, 1)
        out[:, 1, idx, :, 1, idx] = re.transpose(2, 0, 1)
        return out.reshape(n * 2 * h, n * 2 * h)

    def jacobian(self, y, omega: float, with_omega: bool = False):
        """Residual and its Jacobian.

        Parameters
        ----------
        y : array_like, shape (m,)
            Real unknowns [m], m = n 2H.
        omega : float
            Angular frequency [rad/s].
        with_omega : bool
            Also the derivative of the residual with respect to omega
            (:meth:`omega_derivative`, a forward difference).

        Returns
        -------
        residual : numpy.ndarray, shape (m,)
            R(y, w) [m], as :meth:`residual`.
        jac_y : numpy.ndarray, shape (m, m)
            dR/dy, ``I + G_pp dFr/dy`` (dimensionless): the friction derivative is the law's
            exact one (:func:`~servotune.harmonic.aft.periodic_friction_jacobian`) where it
            has one, else forward differences with all pads perturbed at once.
        jac_omega : numpy.ndarray, shape (m,)
            dR/dw [m s/rad]; only when ``with_omega``.
        """
        y = np.asarray(y, dtype=float)
        x = self.complex_of(y)
        analytic = self._analytic_jacobian(x, omega)
        if analytic is None:
            fr = self.friction_harmonics(x, omega)
            dfr = self._secant_jacobian(y, omega, fr)
        else:
            fr, dfr = analytic
        r = y - self.real_of(self.response(x, omega, friction=fr)[:self.n_pads])
        n, h2 = self.n_pads, 2 * self.harmonics
        block = np.zeros((n * h2, n * h2))
        for p in range(n):
            block[p * h2:(p + 1) * h2, p * h2:(p + 1) * h2] = dfr[p]
        # y - [G_F F_a - G fr(y)]  ->  I + G dfr/dy
        jac = np.eye(n * h2) + self._g_real(omega) @ block
        if not with_omega:
            return r, jac
        return r, jac, self.omega_derivative(y, omega, r)

    def omega_derivative(self, y, omega: float, r=None) -> np.ndarray:
        """Return the derivative of the residual by the frequency (forward difference).

        Parameters
        ----------
        y : array_like, shape (n 2H,)
            Real unknowns [m].
        omega : float
            Angular frequency [rad/s].
        r : numpy.ndarray, shape (n 2H,), optional
            The residual at ``(y, omega)`` when already known.

        Returns
        -------
        numpy.ndarray, shape (n 2H,)
            dR/domega [m s/rad], ``(R(y, w + dw) - R(y, w)) / dw`` with ``dw = 1e-7 w``.
        """
        r = self.residual(y, omega) if r is None else r
        d = 1e-7 * omega
        return (self.residual(y, omega + d) - r) / d

    def converged(self, r, y) -> bool:
        """Tell whether a residual is small enough (relative to the pad response).

        Parameters
        ----------
        r : numpy.ndarray
            Residual of (1) [m].
        y : numpy.ndarray
            The unknowns it belongs to [m].

        Returns
        -------
        bool
            True when ``|r| <= tolerance |y|`` (Euclidean norms; ``tolerance`` of the
            settings).
        """
        size = max(float(np.linalg.norm(y)), 1e-300)
        return float(np.linalg.norm(r)) <= self.settings.tolerance * size

    def solve(self, omega: float, y0=None) -> tuple[np.ndarray, int]:
        """Solve (1) at a fixed frequency by Newton's method.

        Parameters
        ----------
        omega : float
            Angular frequency [rad/s].
        y0 : array_like, shape (n 2H,), optional
            Start [m] (default: no pad motion; the first step is then the linearisation about
            it).

        Returns
        -------
        y : numpy.ndarray, shape (n 2H,)
            The solution [m].
        iterations : int
            Newton iterations taken (at least 1: the start is always corrected once).

        Raises
        ------
        ConvergenceError
            If Newton's method does not converge within ``max_iterations``.

        Notes
        -----
        Each Newton step is damped: the full step is taken when the residual norm falls,
        otherwise it is halved until it does, down to a factor of 1/1024, which is then taken
        whether or not the residual fell.
        """
        y = np.zeros(self.size) if y0 is None else np.array(y0, dtype=float)
        for it in range(1, self.settings.max_iterations + 1):
            r, jac = self.jacobian(y, omega)
            step = np.linalg.solve(jac, -r)
            # damped: accept the full step when the residual falls, else halve it
            norm = np.linalg.norm(r)
            lam = 1.0
            for _ in range(12):
                trial = y + lam * step
                rt = self.residual(trial, omega)
                if np.linalg.norm(rt) < norm or lam < 1e-3:
                    break
                lam *= 0.5
            y = trial
            if self.converged(rt, y):
                return y, it
        raise ConvergenceError(f"harmonic balance did not converge at {omega / (2 * math.pi):.3g}"
                               f" Hz within {self.settings.max_iterations} Newton iterations")

    def work_piece(self, y, omega: float) -> np.ndarray:
        """Return the work-piece displacement harmonics of a solution by (2).

        Parameters
        ----------
        y : array_like, shape (n 2H,)
            Real unknowns [m], a solution of (1).
        omega : float
            Angular frequency [rad/s].

        Returns
        -------
        numpy.ndarray, complex, shape (H,)
            X_wp,1..H [m].
        """
        return self.response(self.complex_of(y), omega)[self.n_pads]
