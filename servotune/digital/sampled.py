"""The axis under its digital drive as the sampled-data system it is.

:class:`SampledAxis` joins the continuous axis driven by its motor voltage
(:func:`servotune.plant.build_open_plant`: structure, guide-way contact, winding) with the
drive's multi-rate controller (:func:`servotune.digital.controller.digital_controller`):

* **Stability**: the plant discretised exactly under the zero-order hold of the voltage
  (``expm`` of the augmented matrix over one current period), the controllers' difference
  equations, and the loop lifted over the slowest period: the product of the per-sample maps
  over one frame (the monodromy matrix, :meth:`SampledAxis.monodromy`) has all its
  eigenvalues inside the unit circle.
* **Loops**: the velocity loop at the velocity rate (position loop open) and the position
  loop at the position rate (velocity loop closed), each broken at its controller and
  evaluated exactly at ``z = exp(j w T')`` up to its Nyquist frequency (the faster loops
  lifted, :mod:`servotune.digital.cascade`); margins, Ms and bandwidths from those.
* **Compliance**: the fundamental of the sampled-data response to a sinusoidal force
  (:func:`servotune.digital.cascade.fundamental`), and how large the aliases it leaves out are
  (:meth:`SampledAxis.alias_fraction`).

References
----------
T. Chen, B. Francis, Optimal Sampled-Data Control Systems, Springer (1995), ch 3 (exact
discretisation), ch 8 (lifting), sec 10.5. K. J. Astrom, B. Wittenmark, Computer-Controlled
Systems, 3rd ed. (1997), sec 2.3 (zero-order-hold sampling of a state-space system), sec 7.3.
"""

from __future__ import annotations

import dataclasses
import math
from functools import cached_property

import numpy as np
import scipy.linalg

from ..drive import Drive
from ..frequency import LoopAnalysis, analyse_response
from ..plant import Contact, UnstableLoopError, build_open_plant
from ..structure.model import ModalModel, signal_name
from . import cascade
from .controller import MEASURED, DigitalController, digital_controller

__all__ = ["SampledAxis", "discrete_response", "hold_fundamental", "lift",
           "multipliers_stable"]


def hold_fundamental(omega, period: float) -> np.ndarray:
    """Return the zero-order hold's fundamental ``(1 - exp(-j w T)) / (j w T)`` (1 at w = 0).

    Parameters
    ----------
    omega : array_like
        Angular frequencies [rad/s].
    period : float
        The hold's period T [s].

    Returns
    -------
    numpy.ndarray
        Complex, shape of ``omega``.

    Examples
    --------
    At half the sample rate the hold passes 2/pi of the amplitude, a quarter period late:

    >>> h = hold_fundamental(np.pi / 1e-3, 1e-3)
    >>> round(abs(complex(h)), 6), round(float(np.angle(h, deg=True)), 3)
    (0.63662, -90.0)
    """
    x = np.asarray(omega, dtype=float) * period
    with np.errstate(invalid="ignore", divide="ignore"):
        h = (1.0 - np.exp(-1j * x)) / (1j * x)
    return np.where(np.abs(x) < 1e-8, 1.0 - 0.5j * x, h)


def _box(omega, period: float, n: int) -> np.ndarray:
    """``B_N(w) = sum_{k<N} exp(-j w k T)`` (the hold of N fast samples)."""
    k = np.arange(n)
    return np.exp(-1j * np.multiply.outer(np.asarray(omega, dtype=float), k) * period).sum(-1)


def lift(values, omega, period: float, n: int) -> np.ndarray:
    """Return the lifted response of a faster loop seen through a hold of ``n`` periods.

    Parameters
    ----------
    values : numpy.ndarray
        The faster loop's response at the shifted frequencies, shape ``(..., n)``: column l at
        ``omega + l 2 pi / (n period)``.
    omega : array_like
        The frequencies w [rad/s], shape ``(...)``.
    period : float
        The faster rate's period T' [s].
    n : int
        Faster periods per slower one.

    Returns
    -------
    numpy.ndarray
        ``(1/n) sum_l B_n(w_l) values[..., l]`` (see :mod:`servotune.digital.cascade`).
    """
    omega = np.asarray(omega, dtype=float)
    shifts = omega[..., None] + 2 * math.pi / (n * period) * np.arange(n)
    return (_box(shifts, period, n) * values).sum(-1) / n


def multipliers_stable(m: np.ndarray, frame: float) -> tuple[bool, np.ndarray]:
    """Return whether a monodromy matrix is stable, and its multipliers as exponents [1/s].

    The multipliers mu (eigenvalues) become exponents ``p = log(mu) / T_frame``; the loop is
    stable when every p passes the criterion of :func:`servotune.frequency.require_stable`
    (``Re p <= 1e-9 |p|`` plus what rounding of the matrix can put there, ``10 eps ||M_b||
    kappa / |mu|``), so a multiplier on the unit circle through rounding only (the rigid-body
    travel of an uncontrolled DOF) is accepted.

    Parameters
    ----------
    m : numpy.ndarray
        The monodromy matrix.
    frame : float
        The frame [s] it spans.

    Returns
    -------
    (bool, numpy.ndarray)
        Stability and the exponents p (complex, -inf real part for a zero multiplier).
    """
    if not m.size:
        return True, np.array([], dtype=complex)
    m_b, _ = scipy.linalg.matrix_balance(m, permute=False)
    eps = np.finfo(float).eps
    mu = scipy.linalg.eigvals(m_b, check_finite=False)
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.log(mu.astype(complex)) / frame
        edge = np.where(np.isfinite(p.real), p.real - 1e-9 * np.abs(p), -np.inf)
        cap = 20.0 * eps * np.linalg.norm(m_b, 1) / math.sqrt(eps) / np.abs(mu) / frame
    if (edge <= 0.0).all():      # settled by the eigenvalues alone
        return True, p
    if (edge > np.nan_to_num(cap, nan=0.0, posinf=0.0)).any():
        return False, p
    mu, left, right = scipy.linalg.eig(m_b, left=True, right=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.log(mu.astype(complex)) / frame
        overlap = np.abs(np.sum(left.conj() * right, axis=0))
        size = np.linalg.norm(left, axis=0) * np.linalg.norm(right, axis=0)
        kappa = np.minimum(size / overlap, 1.0 / math.sqrt(eps))
        slack = 10.0 * eps * np.linalg.norm(m_b, 1) * kappa / np.abs(mu) / frame
    finite = np.isfinite(p.real)
    bad = finite & (p.real > 1e-9 * np.abs(p) + np.nan_to_num(slack, nan=0.0, posinf=0.0))
    return not bad.any(), p


class DiscreteForm:
    """``C (z I - A)^-1 B`` of a discrete system at any points z on the unit circle.

    A is balanced and decomposed once, as :func:`servotune.frequency.fast_frequency_response`
    does for continuous systems: the eigenvector (modal) form, else the modal form with the
    ill-conditioned eigenvalues (nearly defective ones, and those at z = 1: integrators and
    rigid-body travel) split off into a small triangular block; a form is used when it agrees
    with direct solves (Gaussian elimination on the Hessenberg form, backward stable) within
    1e-8 of each output's largest response at 48 points of the unit circle (spread over
    ``exp(j w)``, w in (0, pi], and next to the angle of every eigenvalue), else every point is
    solved directly on the Hessenberg form (O(n^2) per point).

    Parameters
    ----------
    ad, bd, cd : numpy.ndarray
        The system (n, n), (n, m), (p, n).
    """

    def __init__(self, ad: np.ndarray, bd: np.ndarray, cd: np.ndarray):
        from ..frequency import _condition_numbers, _deflated_form, _modal_form

        n = ad.shape[0]
        t = np.ones(n)
        if n:
            _, (t, _) = scipy.linalg.matrix_balance(ad, permute=False, separate=True)
        self.a = ad * (1.0 / t)[:, None] * t[None, :]
        self.b = bd / t[:, None]
        self.c = cd * t[None, :]
        self.shape = (cd.shape[0], bd.shape[1])
        self.form = None
        if not n:
            return
        lam = np.linalg.eigvals(self.a)
        angles = np.concatenate([np.geomspace(1e-3, math.pi, 24),
                                 np.clip(np.abs(np.angle(lam)), 1e-3, math.pi)[:24]])
        self._z = np.exp(1j * np.unique(angles))
        self._direct = _direct(self.a, self.b, self.c, self._z)
        with np.errstate(all="ignore"):
            form = _modal_form(self.a, self.b, self.c)
            if form is not None and self._passes(form):
                self.form = form
                return
            if form is not None:
                kappa = _condition_numbers(form)
                split = (np.abs(form.lam - 1.0) < 1e-6) | (kappa > 1e4)
                deflated = _deflated_form(self.a, self.b, self.c, form.lam, split)
                if deflated is not None and self._passes(deflated):
                    self.form = deflated

    def _passes(self, form) -> bool:
        resp = _form_at(form, self._z)
        scale = np.maximum(np.abs(self._direct).max(axis=-1, keepdims=True), 1e-300)
        return bool(np.all(np.isfinite(resp))
                    and float((np.abs(resp - self._direct) / scale).max()) <= 1e-8)

    def __call__(self, z) -> np.ndarray:
        """The response at points ``z``, shape ``(p, m) + z.shape``."""
        z = np.asarray(z, dtype=complex)
        flat = z.reshape(-1)
        if self.form is not None:
            resp = _form_at(self.form, flat)
        elif self.a.shape[0]:
            resp = _direct(self.a, self.b, self.c, flat)
        else:
            resp = np.zeros((*self.shape, flat.size), dtype=complex)
        return resp.reshape(*self.shape, *z.shape)


class ContinuousForm:
    """``C (j w I - A)^-1 B`` of a continuous system at any frequencies, decomposed once.

    As :class:`DiscreteForm` on the imaginary axis: the balanced modal form, else the modal
    form with ill-conditioned eigenvalues (and those at s = 0) split off into a triangular
    block, each checked against direct Hessenberg solves within 1e-8 of each output's largest
    response (to any input) at 48 frequencies (24 from 1e-2 to 1e6 rad/s and next to every
    eigenvalue's frequency), else direct solves at every frequency.

    Parameters
    ----------
    a, b, c : numpy.ndarray
        The system (n, n), (n, m), (p, n).
    """

    def __init__(self, a: np.ndarray, b: np.ndarray, c: np.ndarray):
        from ..frequency import (
            _condition_numbers,
            _deflated_form,
            _DirectSolves,
            _modal_form,
            _system_balance,
        )

        n = a.shape[0]
        self.shape = (c.shape[0], b.shape[1])
        t = _system_balance(a, b, c) if n else np.ones(0)
        self.a = a * (1.0 / t)[:, None] * t[None, :]
        self.b = b / t[:, None]
        self.c = c * t[None, :]
        self.form = None
        self._direct = _DirectSolves(self.a, self.b, self.c)
        if not n:
            return
        lam = np.linalg.eigvals(self.a)
        w = np.unique(np.concatenate([np.geomspace(1e-2, 1e6, 24),
                                      np.clip(np.abs(lam.imag), 1e-2, None)[:24]]))
        ref = self._direct(w)
        # each output against its largest response to any input (a pair that is zero but for
        # rounding, e.g. a force across the feed direction, is not asked to be accurate)
        scale = np.maximum(np.abs(ref).max(axis=(1, 2), keepdims=True), 1e-300)

        def passes(form):
            with np.errstate(all="ignore"):
                resp = form.response(w)
            return bool(np.all(np.isfinite(resp))
                        and float((np.abs(resp - ref) / scale).max()) <= 1e-8)

        with np.errstate(all="ignore"):
            form = _modal_form(self.a, self.b, self.c)
            if form is not None and passes(form):
                self.form = form
                return
            if form is not None:
                kappa = _condition_numbers(form)
                near_zero = np.abs(form.lam) < 1e-6 * max(float(np.abs(self.a).max()), 1e-300)
                deflated = _deflated_form(self.a, self.b, self.c, form.lam,
                                          near_zero | (kappa > 1e4))
                if deflated is not None and passes(deflated):
                    self.form = deflated

    def __call__(self, omega, inputs=None, outputs=None) -> np.ndarray:
        """The responses at ``omega`` [rad/s] for the selected inputs and outputs (indices),
        shape (outputs, inputs, K)."""
        omega = np.asarray(omega, dtype=float).reshape(-1)
        i_in = list(range(self.shape[1])) if inputs is None else list(inputs)
        i_out = list(range(self.shape[0])) if outputs is None else list(outputs)
        if not self.a.shape[0]:
            return np.zeros((len(i_out), len(i_in), omega.size), dtype=complex)
        if self.form is not None:
            f = self.form
            sub = type(f)(f.t, f.lam, f.s, f.lu, f.cs[i_out], f.sb[:, i_in])
            return sub.response(omega)
        return self._direct(omega)[np.ix_(i_out, i_in)]


def _form_at(form, z) -> np.ndarray:
    """``C S (z I - J)^-1 S^-1 B`` of a block modal form (J = diag(T, diag(lam))) at z."""
    k = form.t.shape[0]
    p, m = form.cs.shape[0], form.sb.shape[1]
    out = np.zeros((p, m, z.size), dtype=complex)
    if form.lam.size:
        residues = (form.cs[:, None, k:] * form.sb.T[None, :, k:]).reshape(p * m, -1)
        out += (residues @ (1.0 / (z[None, :] - form.lam[:, None]))).reshape(p, m, z.size)
    if k:
        diag = np.diag(form.t)
        x = np.empty((k, m, z.size), dtype=complex)
        for i in range(k - 1, -1, -1):
            acc = np.broadcast_to(form.sb[i][:, None], x.shape[1:])
            if i < k - 1:
                acc = acc + np.tensordot(form.t[i, i + 1:], x[i + 1:], axes=1)
            x[i] = acc / (z - diag[i])
        out += np.einsum("pk,kmw->pmw", form.cs[:, :k], x)
    return out


def discrete_response(ad: np.ndarray, bd: np.ndarray, cd: np.ndarray, z) -> np.ndarray:
    """Return ``C (z I - A)^-1 B`` of a discrete system at points z (:class:`DiscreteForm`).

    Parameters
    ----------
    ad, bd, cd : numpy.ndarray
        The system (n, n), (n, m), (p, n).
    z : array_like of complex
        The points (on the unit circle).

    Returns
    -------
    numpy.ndarray
        Shape ``(p, m) + z.shape``.

    Examples
    --------
    One sample of delay: 1/z.

    >>> complex(discrete_response(np.zeros((1, 1)), np.ones((1, 1)), np.ones((1, 1)),
    ...                           [1j])[0, 0, 0])
    -1j
    """
    return DiscreteForm(ad, bd, cd)(z)


def _direct(a, b, c, z):
    """``C (z I - A)^-1 B`` by Gaussian elimination on the Hessenberg form of A (backward
    stable, O(n^2) per point; :func:`servotune._frequency_kernels.hessenberg_solve_shifts`)."""
    from .._frequency_kernels import hessenberg_solve_shifts

    h, q = scipy.linalg.hessenberg(a, calc_q=True, check_finite=False)
    x = np.empty((z.size, a.shape[0], b.shape[1]), dtype=complex)
    hessenberg_solve_shifts(np.ascontiguousarray(h), np.ascontiguousarray(z, dtype=complex),
                            np.ascontiguousarray(q.T @ b, dtype=complex), x)
    return np.einsum("pi,kim->pmk", c @ q, x)


class SampledAxis:
    """The axis with its digital drive: exact sampled-data stability, loops and compliance.

    Parameters
    ----------
    structure : ModalModel
        The reduced structure.
    drive : Drive
        A sampled drive (its :class:`~servotune.drive.Sampling` has periods).
    contact : Contact, optional
        The guide-way contact (default: free).
    pads : sequence of str
        The pad DOFs where the contact acts.
    force_pads : bool
        With the pad forces as inputs and the pad displacements as outputs (a free contact;
        for harmonic balance).

    Raises
    ------
    ValueError
        A continuous drive, or a contact without pads.

    Examples
    --------
    See ``docs/digital_drive.md`` and the tests in ``tests/test_digital.py``.
    """

    def __init__(self, structure: ModalModel, drive: Drive, contact: Contact | None = None,
                 pads=(), force_pads: bool = False):
        self.structure = structure
        self.drive = drive
        self.controller: DigitalController = digital_controller(drive)
        self.contact = contact
        self.pads = tuple(pads)
        self.plant = build_open_plant(structure, drive, contact, pads, force_pads)
        s = drive.sampling
        self.period = s.current_period
        self.n_v, self.n_p = s.multiples()
        self.velocity_period = self.period * self.n_v
        self.position_period = self.velocity_period * self.n_p
        self.frame = self.position_period
        n = self.plant.nstates
        a = np.asarray(self.plant.A, dtype=float).reshape(n, n)
        iv = list(self.plant.input_labels).index("voltage")
        b = np.asarray(self.plant.B, dtype=float).reshape(n, -1)[:, [iv]]
        aug = np.zeros((n + 1, n + 1))
        aug[:n, :n] = a
        aug[:n, n:] = b
        e = scipy.linalg.expm(aug * self.period)
        self.ad, self.bd = e[:n, :n], e[:n, n:]
        rows = [list(self.plant.output_labels).index(m) for m in MEASURED]
        self.cy = np.asarray(self.plant.C, dtype=float).reshape(-1, n)[rows]

    # ------------------------------------------------------------------ stability
    @cached_property
    def monodromy(self) -> np.ndarray:
        """The closed loop's state transition over one frame (the position period)."""
        return self.controller.monodromy(self.ad, self.bd, self.cy)

    @cached_property
    def _stability(self):
        return multipliers_stable(self.monodromy, self.frame)

    def is_stable(self) -> bool:
        """Return whether the multi-rate closed loop is stable (monodromy multipliers).

        Returns
        -------
        bool
        """
        return self._stability[0]

    def require_stable(self, what: str = "closed-loop axis") -> None:
        """Raise :class:`~servotune.plant.UnstableLoopError` when the loop is unstable.

        Parameters
        ----------
        what : str
            What the loop is, for the message.

        Raises
        ------
        UnstableLoopError
            Naming the growing multipliers as exponents [1/s] and frequencies.
        """
        ok, p = self._stability
        if ok:
            return
        # the frame's multipliers know a frequency only modulo the frame rate: where the
        # faster loops (between the position controller's updates) grow on their own, their
        # multipliers over one velocity period name it up to the speed controller's Nyquist
        fast = None
        if self.controller.frame > self.n_v:
            maps = self.controller.sample_maps(self.ad, self.bd, self.cy)
            m = maps[1][0]
            for phi, _ in maps[2:1 + self.n_v]:
                m = phi @ m
            fast_ok, q = multipliers_stable(m, self.velocity_period)
            if not fast_ok:
                fast = q
        if fast is not None:
            bad = fast[np.isfinite(fast.real) & (fast.real > 1e-9 * np.abs(fast))]
            note = ""
        else:
            bad = p[np.isfinite(p.real) & (p.real > 1e-9 * np.abs(p))]
            note = (f" (a frequency modulo the position controller's rate, "
                    f"{1.0 / self.frame:.4g} Hz)")
        # one of each conjugate pair, and not the integrators' rounding (well below 1e-3 1/s)
        bad = bad[(bad.imag >= 0) & (bad.real > 1e-3 * max(1.0, float(bad.real.max())))]
        bad = bad[np.argsort(-bad.real)][:4]
        listed = ", ".join(f"grows at {q.real:.3g} 1/s near {abs(q.imag) / (2 * math.pi):.4g} Hz"
                           for q in bad) + note
        raise UnstableLoopError(
            f"the {what} is unstable as the sampled-data system the drive is ({listed}); "
            "lower the loop gains (Kv, Kp) or raise Ti, or add damping")

    # ------------------------------------------------------------------ responses
    def _continuous_form(self, inputs: tuple, outputs: tuple) -> ContinuousForm:
        """The decomposed continuous plant between some inputs and outputs, made once each
        (its accuracy is checked on those only: a pair that is zero but for rounding, such as
        a force across the feed direction, would fail any relative check)."""
        forms = self.__dict__.setdefault("_forms", {})
        if (inputs, outputs) not in forms:
            n = self.plant.nstates
            i_in = [list(self.plant.input_labels).index(s) for s in inputs]
            i_out = [list(self.plant.output_labels).index(s) for s in outputs]
            forms[inputs, outputs] = ContinuousForm(
                np.asarray(self.plant.A, dtype=float).reshape(n, n),
                np.asarray(self.plant.B, dtype=float).reshape(n, -1)[:, i_in],
                np.asarray(self.plant.C, dtype=float).reshape(-1, n)[i_out])
        return forms[inputs, outputs]

    def _continuous(self, omega, inputs, outputs) -> np.ndarray:
        """The continuous plant's responses, shape (outputs, inputs, K) (no feed-through:
        the open plant's outputs are states)."""
        return self._continuous_form(tuple(inputs), tuple(outputs))(
            np.asarray(omega, dtype=float))

    def zoh_response(self, omega) -> np.ndarray:
        """Return the plant's sampled outputs per held voltage, exact at the samples.

        Parameters
        ----------
        omega : array_like
            Angular frequencies [rad/s] (any shape).

        Returns
        -------
        numpy.ndarray
            Shape ``(3,) + omega.shape``: current [A/V], angle [rad/V], position [m/V]
            (:data:`~servotune.digital.controller.MEASURED`) at ``z = exp(j w T)``.
        """
        omega = np.asarray(omega, dtype=float)
        z = np.exp(1j * omega * self.period)
        return self._zoh_form(z)[:, 0]

    @cached_property
    def _zoh_form(self) -> DiscreteForm:
        return DiscreteForm(self.ad, self.bd, self.cy)

    def _k(self, level: str, signal: str, omega, period: float) -> np.ndarray:
        return self.controller.response(level, signal, np.exp(1j * np.asarray(omega) * period))

    def _current(self, theta):
        g = self.zoh_response(theta)
        return cascade.current_level(g[0], g[1], g[2],
                                     self._k("current", "current", theta, self.period),
                                     self._k("current", "torque_set", theta, self.period))

    def _velocity(self, omega):
        omega = np.asarray(omega, dtype=float)
        shifts = omega[..., None] + 2 * math.pi / self.velocity_period * np.arange(self.n_v)
        cur = self._current(shifts)
        g_vphi = lift(cur.phi_t, omega, self.period, self.n_v)
        g_vx = lift(cur.x_t, omega, self.period, self.n_v)
        return cascade.velocity_level(
            g_vphi, g_vx, self._k("velocity", "motor_angle", omega, self.velocity_period),
            self._k("velocity", "omega_cmd", omega, self.velocity_period))

    def _position(self, omega, with_velocity: bool = False):
        omega = np.asarray(omega, dtype=float)
        shifts = omega[..., None] + 2 * math.pi / self.position_period * np.arange(self.n_p)
        vel = self._velocity(shifts)
        g_px = lift(vel.x_omega, omega, self.velocity_period, self.n_p)
        pos = cascade.position_level(g_px, self._k("position", "x_fb", omega,
                                                   self.position_period))
        if not with_velocity:
            return pos
        # the velocity level at omega itself is the first shift's
        first = type(vel)(*(np.asarray(getattr(vel, f))[..., 0] for f in
                            ("l_v", "r_v", "x_omega", "g_vphi", "g_vx")))
        return pos, first

    def nyquist(self, loop: str) -> float:
        """Return half the sample rate [rad/s] of a loop's controller.

        Parameters
        ----------
        loop : {"velocity", "position"}

        Returns
        -------
        float
        """
        period = {"velocity": self.velocity_period, "position": self.position_period}[loop]
        return math.pi / period

    def loop_response(self, loop: str, omega) -> np.ndarray:
        """Return a loop transfer function at ``z = exp(j w T')`` (T' the loop's period).

        The velocity loop is broken at the velocity controller with the position loop open;
        the position loop at the position controller with the velocity loop closed. Above the
        loop's Nyquist frequency the response repeats; NaN is returned there.

        Parameters
        ----------
        loop : {"velocity", "position"}
        omega : array_like
            Angular frequencies [rad/s], 1-D.

        Returns
        -------
        numpy.ndarray
            Complex L, shape of ``omega``.
        """
        omega = np.asarray(omega, dtype=float)
        if loop not in ("velocity", "position"):
            raise ValueError(f"loop must be 'velocity' or 'position', got {loop!r}")
        inside = omega < self.nyquist(loop) * (1.0 - 1e-9)
        out = np.full(omega.shape, np.nan + 0j)
        if inside.any():
            w = omega[inside]
            out[inside] = self._velocity(w).l_v if loop == "velocity" else self._position(w).l_p
        return out

    def analyse_loop(self, loop: str, omega=None) -> LoopAnalysis:
        """Margins, Ms and bandwidth of a loop of the sampled-data axis.

        The closed loop must be stable (the monodromy multipliers; the velocity loop with the
        position loop open is judged by its own multipliers).

        Parameters
        ----------
        loop : {"velocity", "position"}
        omega : array_like, optional
            Dense grid [rad/s], 1-D, increasing (default 4000 log-spaced points from 0.1 Hz);
            cut at the loop's Nyquist frequency.

        Returns
        -------
        LoopAnalysis

        Raises
        ------
        UnstableLoopError
            If the loop is unstable.
        """
        if loop == "velocity":
            self.velocity_loop_axis().require_stable("closed velocity loop")
        else:
            self.require_stable("closed loop")
        top = self.nyquist(loop)
        omega = (2 * math.pi * np.geomspace(0.1, 1e4, 4000) if omega is None
                 else np.asarray(omega, dtype=float))
        omega = omega[omega < top * (1.0 - 1e-6)]
        l_jw = self.loop_response(loop, omega)
        l_low = self.loop_response(loop, np.array([omega[0] / 100.0]))[0]
        return analyse_response(omega, l_jw, l_low)

    def largest_stable_kp(self, ti: float | None = None, rtol: float = 1e-4) -> float:
        """Return the largest velocity-loop gain Kp [N m s/rad] that keeps the velocity loop
        stable with the position loop open, at integral time ``ti`` (default the drive's).

        Bisection in log Kp on the multipliers of the lifted loop (:meth:`is_stable` of
        :meth:`velocity_loop_axis`), from a bracket grown by factors of 2 around the drive's
        own Kp. (A gain below which the loop is unstable too, as with a friction that falls
        with speed, is not sought: the result is the upper edge of the stable range that
        holds the smaller of the drive's Kp and the bracket's lower end.)

        Parameters
        ----------
        ti : float, optional
            Integral time [s].
        rtol : float
            Relative width of the final bracket.

        Returns
        -------
        float
            The largest stable Kp (``inf`` when no upper limit is found below 1e6 times the
            drive's Kp; 0 when even 1e-6 times it is unstable).
        """
        from ..drive import PIController

        pi = self.drive.velocity_loop
        ti = pi.ti if ti is None else float(ti)
        base = self.velocity_loop_axis()

        def stable(kp):
            drive = dataclasses.replace(self.drive, velocity_loop=PIController(kp, ti))
            clone = object.__new__(SampledAxis)
            clone.__dict__.update({k: v for k, v in base.__dict__.items()
                                   if k not in ("monodromy", "_stability", "_vel_axis")})
            ctl = digital_controller(drive)
            pos = ctl.levels[0]
            clone.controller = DigitalController(
                (type(pos)(pos.name, pos.period, pos.every, pos.system, pos.a, 0.0 * pos.b,
                           pos.c, 0.0 * pos.d, pos.output), *ctl.levels[1:]),
                ctl.period, ctl.frame)
            return clone.is_stable()

        lo = hi = pi.kp
        if stable(lo):
            while stable(hi):
                lo, hi = hi, 2.0 * hi
                if hi > 1e6 * pi.kp:
                    return math.inf
        else:
            while not stable(lo):
                hi, lo = lo, 0.5 * lo
                if lo < 1e-6 * pi.kp:
                    return 0.0
        while hi / lo > 1.0 + rtol:
            mid = math.sqrt(lo * hi)
            lo, hi = (mid, hi) if stable(mid) else (lo, mid)
        return lo

    def velocity_loop_axis(self) -> SampledAxis:
        """Return the same axis with the position loop open, for the velocity loop's own
        stability.

        Returns
        -------
        SampledAxis
            The axis whose position controller reads nothing (its output stays zero).
        """
        if getattr(self, "_vel_axis", None) is None:
            ctl = self.controller
            pos = ctl.level("position")
            levels = (type(pos)(pos.name, pos.period, pos.every, pos.system, pos.a,
                                0.0 * pos.b, pos.c, 0.0 * pos.d, pos.output),
                      *ctl.levels[1:])
            clone = object.__new__(SampledAxis)
            clone.__dict__.update({k: v for k, v in self.__dict__.items()
                                   if k not in ("monodromy", "_stability", "_vel_axis")})
            clone.controller = DigitalController(levels, ctl.period, ctl.frame)
            clone._vel_axis = clone
            self._vel_axis = clone
        return self._vel_axis

    def response(self, omega, force, outputs) -> np.ndarray:
        """Return the fundamental of continuous outputs per sinusoidal forces.

        Parameters
        ----------
        omega : array_like
            Angular frequencies [rad/s], 1-D, > 0.
        force : str or sequence of str
            Input signal(s) of the plant (``f_wp_x``, ``f_pad1_x``, ``t_dist``).
        outputs : sequence of str
            Output signals of the plant (``wp_x``, ``pad1_x``, ``slide_x`` ...).

        Returns
        -------
        numpy.ndarray
            Complex, shape ``(len(outputs), len(omega))`` for one force, else
            ``(len(outputs), len(force), len(omega))``.
        """
        omega = np.asarray(omega, dtype=float)
        single = isinstance(force, str)
        forces = [force] if single else list(force)
        outputs = list(outputs)
        names = list(MEASURED) + outputs
        p_all = self._continuous(omega, forces, names)
        p_u = self._continuous(omega, ["voltage"], outputs)[:, 0]
        cur = self._current(omega)
        vel = self._velocity(omega)
        pos = self._position(omega)
        k = dict(k_ci=self._k("current", "current", omega, self.period),
                 k_vphi=self._k("velocity", "motor_angle", omega, self.velocity_period),
                 k_vomega=self._k("velocity", "omega_cmd", omega, self.velocity_period),
                 k_px=self._k("position", "x_fb", omega, self.position_period),
                 h0=hold_fundamental(omega, self.period),
                 hold_v=_box(omega, self.period, self.n_v) / self.n_v,
                 hold_p=_box(omega, self.velocity_period, self.n_p) / self.n_p)
        out = np.empty((len(outputs), len(forces), omega.size), dtype=complex)
        for f in range(len(forces)):
            p_f = p_all[:, f]
            for j in range(len(outputs)):
                out[j, f] = cascade.fundamental(cur, vel, pos, i_f=p_f[0], phi_f=p_f[1],
                                                x_f=p_f[2], y_f=p_f[3 + j], y_u=p_u[j], **k)
        return out[:, 0] if single else out

    def compliance(self, omega, force: str = "wp.x", outputs=("wp.x",)) -> np.ndarray:
        """Return the work-piece compliance [m/N]: the fundamental of the displacement.

        Parameters
        ----------
        omega : array_like
            Angular frequencies [rad/s], 1-D, > 0.
        force : str
            DOF of the force.
        outputs : sequence of str
            DOFs of the displacements.

        Returns
        -------
        numpy.ndarray
            Complex, shape ``(len(outputs), len(omega))``.
        """
        return self.response(omega, signal_name(force, "f_"),
                             [signal_name(o) for o in outputs])

    def alias_fraction(self, omega, force: str = "wp.x", output: str = "wp.x",
                       n_alias: int = 8) -> np.ndarray:
        """Return how large the aliases the fundamental leaves out are, relative to it.

        The held voltage's component at w + k 2 pi / T (k = +-1 .. +-n_alias) reaches the
        continuous output through the plant; their root-sum-square over the fundamental is
        returned (the position loop's hold adds components at w + l 2 pi / T_p through the
        closed velocity loop; those are included for l = +-1 .. +-n_alias too).

        Parameters
        ----------
        omega : array_like
            Angular frequencies [rad/s], 1-D, > 0.
        force, output : str
            DOFs of the force and of the displacement.
        n_alias : int
            Aliases counted on each side.

        Returns
        -------
        numpy.ndarray
            ``sqrt(sum |alias|^2) / |fundamental|``, shape of ``omega``; NaN at whole
            multiples of the position controller's rate (an alias there is a constant speed
            command).
        """
        omega = np.asarray(omega, dtype=float)
        f_in, y_out = signal_name(force, "f_"), signal_name(output)
        names = [*MEASURED, y_out]
        p_f = self._continuous(omega, [f_in], names)[:, 0]
        cur = self._current(omega)
        vel = self._velocity(omega)
        pos = self._position(omega)
        k_ci = self._k("current", "current", omega, self.period)
        k_vphi = self._k("velocity", "motor_angle", omega, self.velocity_period)
        k_vomega = self._k("velocity", "omega_cmd", omega, self.velocity_period)
        k_px = self._k("position", "x_fb", omega, self.position_period)
        hold_v = _box(omega, self.period, self.n_v) / self.n_v
        hold_p = _box(omega, self.velocity_period, self.n_p) / self.n_p
        fund = self.compliance(omega, force, [output])[0]
        # the voltage sequence's fundamental (as in cascade.fundamental)
        u_f = k_ci * p_f[0] * cur.r_c
        phi_fc = p_f[1] + cur.g_phi * u_f
        x_fc = p_f[2] + cur.g_x * u_f
        t_vf = k_vphi * phi_fc * vel.r_v
        omega_p = k_px * (x_fc + vel.g_vx * t_vf) * pos.r_p
        u = u_f + cur.k_ct * cur.r_c * hold_v * (t_vf + k_vomega * vel.r_v * hold_p * omega_p)
        total = np.zeros(omega.size)
        ws = 2 * math.pi / self.period
        for k in range(1, n_alias + 1):
            for sign in (1, -1):
                wk = np.abs(omega + sign * k * ws)
                p_u = self._continuous(np.maximum(wk, 1e-9), ["voltage"], [y_out])[0, 0]
                p_u = np.where(omega + sign * k * ws < 0, np.conj(p_u), p_u)
                h = hold_fundamental(omega + sign * k * ws, self.period)
                total += np.abs(p_u * h * u) ** 2
        # the position hold's aliases through the closed velocity loop
        wp = 2 * math.pi / self.position_period
        for k in range(1, min(n_alias, self.n_p * self.n_v - 1) + 1):
            for sign in (1, -1):
                wk = omega + sign * k * wp
                if (k * self.n_v) % (self.n_p * self.n_v) == 0:
                    continue
                # an alias at w = 0 (w a multiple of the position rate) is a constant speed
                # command the position loop itself removes: left out (NaN where it falls)
                zero = np.abs(wk) < 1e-9 * wp
                total = np.where(zero, np.nan, total)
                wk = np.where(zero, wp, wk)
                box = _box(wk, self.velocity_period, self.n_p) / self.n_p
                vel_k = self._velocity(np.abs(wk))
                cur_k = self._current(np.abs(wk))
                p_u = self._continuous(np.maximum(np.abs(wk), 1e-9), ["voltage"], [y_out])[0, 0]
                h = hold_fundamental(np.abs(wk), self.period)
                k_vo = self._k("velocity", "omega_cmd", np.abs(wk), self.velocity_period)
                u_k = cur_k.k_ct * cur_k.r_c * (_box(np.abs(wk), self.period, self.n_v)
                                                / self.n_v) * k_vo * vel_k.r_v * np.abs(box)
                total += np.abs(p_u * h * u_k * omega_p) ** 2
        return np.sqrt(total) / np.abs(fund)
