"""Frequency responses of the axis: fast evaluation, port coupling, loop margins and poles.

Two independent ways of evaluating the closed-loop axis are provided:

* :func:`fast_frequency_response` evaluates any python-control ``StateSpace`` in its modal
  (eigenvector) coordinates: with A = V diag(lambda) V^-1 computed once,
  ``H(jw) = (C V) diag(1/(jw - lambda)) (V^-1 B) + D`` costs O(n p m) per frequency instead of
  a linear solve. When V is too ill-conditioned for the requested accuracy it falls back to a
  Hessenberg reduction (``scipy.linalg.hessenberg``) with one solve per frequency.
* :func:`port_compliance` never builds the closed-loop state space: it takes the structure's
  receptance at the ports (work piece, pads, motor, encoder) from the modal sum and closes the
  contacts and the cascade around it with a small complex linear system per frequency. The
  tuning evaluates the same equations in real arithmetic.

Loop analysis (:func:`analyse_loop`) gives gain and phase margins, the sensitivity peak
Ms = max |1/(1 + L)| and the closed-loop -3 dB bandwidth on a dense frequency grid.

References
----------
A. J. Laub, "Efficient multivariable frequency response computations", IEEE Trans. Automatic
Control 26 (1981) 407-408 (Hessenberg method, as SLICOT's TB05AD).
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
from .plant import Contact, UnstableLoopError
from .structure.model import ModalModel

__all__ = [
    "fast_frequency_response",
    "modal_receptance",
    "port_compliance",
    "compliance",
    "LoopAnalysis",
    "analyse_loop",
    "ClosedLoopPoles",
    "closed_loop_poles",
    "require_stable",
    "following_error",
    "peak",
]

HZ = 1.0 / (2.0 * math.pi)


def _omega(omega) -> np.ndarray:
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    if omega.ndim != 1 or not np.all(np.isfinite(omega)) or np.any(omega < 0):
        raise ValueError("omega must be a 1-D array of finite angular frequencies >= 0 rad/s")
    return omega


def fast_frequency_response(sys: control.StateSpace, omega, inputs=None, outputs=None,
                            rtol: float = 1e-10) -> control.FrequencyResponseData:
    """Frequency response of a state-space system by modal (eigenvector) evaluation.

    Parameters
    ----------
    sys : control.StateSpace
    omega : array_like
        Angular frequencies [rad/s].
    inputs, outputs : list of str, optional
        Restrict to these named signals (default: all).
    rtol : float
        Accuracy wanted. The modal result is checked against a Hessenberg solve at the
        frequencies of largest response and a spread of others; if they differ by more than
        ``rtol`` (relative to the largest response), the Hessenberg method is used throughout.

    Returns
    -------
    control.FrequencyResponseData
        With the chosen signal names.

    Examples
    --------
    A first-order lag has |H| = 1/sqrt(2) at its corner:

    >>> lag = control.ss(control.tf([1.0], [0.1, 1.0]))
    >>> round(abs(complex(fast_frequency_response(lag, [10.0]).complex.ravel()[0])), 6)
    0.707107
    """
    omega = _omega(omega)
    sys = control.ss(sys)
    i_in = [sys.input_labels.index(s) for s in inputs] if inputs else list(range(sys.ninputs))
    i_out = [sys.output_labels.index(s) for s in outputs] if outputs else list(
        range(sys.noutputs))
    a, b, c, d = sys.A, sys.B[:, i_in], sys.C[i_out], sys.D[np.ix_(i_out, i_in)]
    s = 1j * omega
    resp = None
    if a.shape[0]:
        # balancing (a diagonal similarity) equalises the scales of the states (displacements
        # in m, currents in A, integrals ...), which the accuracy of both methods needs
        a, t = scipy.linalg.matrix_balance(a, permute=False, separate=True)
        t = t[0]
        b, c = b / t[:, None], c * t[None, :]
        eye = np.eye(a.shape[0])
        check = None
        for attempt in (_modal_response, _deflated_modal_response):
            resp = attempt(a, b, c, s)
            if resp is None:
                continue
            # a posteriori check against direct solves where the response is largest (next to
            # the least damped poles) and at a spread of frequencies
            if check is None:
                mag = np.abs(resp).reshape(-1, s.size).max(axis=0)
                check = np.unique(np.concatenate([np.argsort(mag)[-4:],
                                                  np.linspace(0, s.size - 1, 6).astype(int)]))
                exact = np.moveaxis(c @ np.linalg.solve(s[check, None, None] * eye - a, b),
                                    0, -1)
            err = np.abs(resp[:, :, check] - exact).max() / max(np.abs(exact).max(), 1e-300)
            if err <= rtol:
                break
            resp = None
        if resp is None:
            h, q = scipy.linalg.hessenberg(a, calc_q=True)
            resp = _hessenberg_response(h, q.T @ b, c @ q, s)
    else:
        resp = np.zeros((len(i_out), len(i_in), omega.size), dtype=complex)
    resp = resp + d[:, :, None]
    return control.frd(resp, omega, inputs=[sys.input_labels[i] for i in i_in],
                       outputs=[sys.output_labels[i] for i in i_out])


def _modal_response(a, b, c, s):
    """C (sI - A)^-1 B from the eigenvectors of A: residues (C v_i)(w_i^T B) summed against
    1/(s - lambda_i) in one matrix product; None if V is singular."""
    lam, v = np.linalg.eig(a)
    try:
        wb = np.linalg.solve(v, b)
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(wb)):
        return None
    residues = ((c @ v)[:, None, :] * wb.T[None, :, :]).reshape(-1, lam.size)
    return (residues @ (1.0 / (s[None, :] - lam[:, None]))).reshape(
        c.shape[0], b.shape[1], s.size)


def _deflated_modal_response(a, b, c, s):
    """The modal form with the eigenvalues near zero split off first.

    Integrators and rigid-body modes often form a defective (Jordan) block at s = 0, which
    makes the eigenvectors of A useless. An ordered Schur form puts those eigenvalues first,
    a Sylvester equation decouples them (A ~ diag(T11, T22)), and the small T11 block is
    solved directly at each frequency while T22 goes through the modal form.
    """
    scale = max(float(np.abs(a).max()), 1e-300)
    tol = 1e-6 * scale
    t, z, k = scipy.linalg.schur(a.astype(complex), output="complex",
                                 sort=lambda x: abs(x) < tol)
    if k == 0 or k == a.shape[0]:
        return None
    t11, t12, t22 = t[:k, :k], t[:k, k:], t[k:, k:]
    x = scipy.linalg.solve_sylvester(t11, -t22, -t12)
    cz, zb = c @ z, z.conj().T @ b
    c1, c2 = cz[:, :k], cz[:, :k] @ x + cz[:, k:]
    b1, b2 = zb[:k] - x @ zb[k:], zb[k:]
    tail = _modal_response(t22, b2, c2, s)
    if tail is None:
        return None
    head = np.linalg.solve(s[:, None, None] * np.eye(k) - t11,
                           np.broadcast_to(b1, (s.size, *b1.shape)))
    return tail + np.moveaxis(c1 @ head, 0, -1)


def _hessenberg_response(h, qb, cq, s) -> np.ndarray:
    """C (sI - A)^-1 B with A = Q H Q^T upper Hessenberg, batched over frequencies."""
    n = h.shape[0]
    eye = np.eye(n)
    resp = np.empty((cq.shape[0], qb.shape[1], s.size), dtype=complex)
    chunk = max(1, 2_000_000 // (n * n))  # bounded memory per batch
    for i in range(0, s.size, chunk):
        sk = s[i:i + chunk, None, None]
        x = np.linalg.solve(sk * eye - h, np.broadcast_to(qb, (sk.shape[0], *qb.shape)))
        resp[:, :, i:i + chunk] = np.moveaxis(cq @ x, 0, -1)
    return resp


def modal_receptance(structure: ModalModel, omega, inputs, outputs) -> np.ndarray:
    """Receptance X/F(j omega) of the structure alone from the modal sum.

    ``H(jw) = sum_r phi_r phi_r^T / (omega_r^2 - w^2 + 2 j zeta_r omega_r w)`` with
    mass-normalised real modes; exact when the damping matrix is diagonal in modal coordinates
    (modal damping, as :class:`ModalModel` builds it). Otherwise the direct solve of
    ``(K - w^2 M + j w D) X = F`` is used.

    Returns
    -------
    numpy.ndarray
        Shape (len(outputs), len(inputs), len(omega)).
    """
    omega = _omega(omega)
    i_in, i_out = structure.index(list(inputs)), structure.index(list(outputs))
    wr = structure.natural_frequencies()
    phi = structure.mode_shapes()
    modal_d = phi.T @ structure.damping @ phi
    off = modal_d - np.diag(np.diag(modal_d))
    if np.abs(off).max(initial=0.0) > 1e-9 * max(np.abs(modal_d).max(initial=0.0), 1e-300):
        return np.moveaxis(structure.receptance(omega, inputs, outputs), 0, -1)
    two_zeta_w = np.diag(modal_d)
    inv_den = 1.0 / (wr[:, None] ** 2 - omega[None, :] ** 2
                     + 1j * omega[None, :] * two_zeta_w[:, None])  # (r, k)
    shapes = phi[i_out][:, None, :] * phi[i_in][None, :, :]  # (p, m, r)
    return (shapes.reshape(-1, wr.size) @ inv_den).reshape(len(i_out), len(i_in), omega.size)


def _tf_values(tf, s: np.ndarray) -> np.ndarray:
    """A SISO transfer function evaluated at complex frequencies (vectorised)."""
    num = np.asarray(tf.num[0][0], dtype=float)
    den = np.asarray(tf.den[0][0], dtype=float)
    return np.polyval(num, s) / np.polyval(den, s)


def port_compliance(structure: ModalModel, omega, drive: Drive | None = None,
                    contact: Contact | None = None, pads=(), force: str = "wp.x",
                    outputs=("wp.x",)) -> np.ndarray:
    """Closed-loop compliance by coupling the structure's port receptances (no state space).

    The structure's receptance between its ports (the force DOF, the pads, the motor rotor and
    stator and the encoder) comes from :func:`modal_receptance`; at each frequency the port
    forces are expressed through the port displacements, ``f = G(jw) x``:

    * pad (each of n): ``f = -(k + j w c)/n * x`` for spring/damper contacts, or
      ``f = -Z(jw)/n * j w x`` for a dynamic (sliding) contact Z: v -> F;
    * motor: ``T = (C_i T_set - kt ke j w phi) / (j w L + R + C_i)`` with
      ``T_set = F_lp F_notch C_v (omega_cmd - j w phi)``,
      ``omega_cmd = -(Kv / r) x_fb`` (no reference), phi = rotor - stator angle,

    and the small linear systems ``(I - R G) x = R e_F`` are solved for all frequencies at
    once. The cost grows with the number of modes times the number of ports squared, not with
    the cube of the closed loop's state dimension.

    Returns
    -------
    numpy.ndarray
        Complex compliance, shape (len(outputs), len(omega)) [m/N].
    """
    omega = _omega(omega)
    contact = Contact.free() if contact is None else contact
    pads = list(pads)
    if contact.kind == "locked":
        structure = structure.locked(pads)
    if contact.kind in ("locked", "free"):
        pads = []
    motor = []
    if drive is not None:
        motor = [drive.motor.rotor] + ([drive.motor.stator] if drive.motor.stator else [])
    ports = list(dict.fromkeys([force, *outputs, *pads, *motor]
                               + ([drive.encoder] if drive is not None
                                  and drive.feedback == "linear" else [])))
    rec = np.moveaxis(modal_receptance(structure, omega, ports, ports), -1, 0)  # (k, p, p)
    idx = {p: i for i, p in enumerate(ports)}
    n, s = len(ports), 1j * omega
    g = np.zeros((omega.size, n, n), dtype=complex)  # port forces per port displacement
    if pads:
        if contact.kind == "sliding":
            z = _tf_values(control.tf(contact.system), s) * s
        else:
            z = contact.stiffness + s * contact.damping
        for p in pads:
            g[:, idx[p], idx[p]] -= z / len(pads)
    if drive is not None:
        m = drive.motor
        parts = cascade_response(drive, s)
        rel = np.zeros(n)  # phi = rel . x
        rel[idx[m.rotor]] = 1.0
        if m.stator:
            rel[idx[m.stator]] = -1.0
        if drive.feedback == "linear":
            fb = np.zeros(n)
            fb[idx[drive.encoder]] = 1.0
        else:
            fb = drive.ratio * rel
        a = parts.current_forward * parts.setpoint * parts.velocity_pi
        b = m.torque_constant * m.back_emf_constant
        k_pos = parts.position_delay * drive.kv / drive.ratio
        # T = -(a D_p Kv/r fb + (a M_v + b) s rel) . x / den
        torque = -((a * k_pos)[:, None] * fb[None, :]
                   + ((a * parts.speed_measurement + b) * s)[:, None] * rel[None, :]
                   ) / parts.winding[:, None]
        g += rel[None, :, None] * torque[:, None, :]
    e = np.zeros(n)
    e[idx[force]] = 1.0
    x = np.linalg.solve(np.eye(n)[None] - rec @ g, (rec @ e)[:, :, None])[:, :, 0]
    return x[:, [idx[o] for o in outputs]].T


def compliance(plant: control.StateSpace, omega, force: str = "f_wp_x",
               output: str = "wp_x") -> np.ndarray:
    """Work-piece compliance [m/N] of a plant from :func:`~servotune.plant.build_plant`.

    Raises
    ------
    UnstableLoopError
        If the plant is unstable (a compliance of an unstable loop means nothing).
    """
    require_stable(plant)
    frd = fast_frequency_response(plant, omega, inputs=[force], outputs=[output])
    return frd.complex[0, 0] if frd.complex.ndim == 3 else frd.complex


def peak(omega, response) -> tuple[float, float]:
    """(max |response|, omega at the max), refined between grid points.

    Near a resonance ``1/|H|^2`` is a quadratic in omega^2 (exactly so for one mode,
    ``(wn^2 - w^2)^2 + (2 zeta wn w)^2``), so a parabola through the three grid points around
    the maximum, in those coordinates, places the peak between them.
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


@dataclass(frozen=True)
class LoopAnalysis:
    """Robustness of one loop from its loop transfer function L (SI; Hz/deg/dB at the edges).

    Attributes
    ----------
    gain_margin : float
        Gain margin [-] (inf when the phase never crosses -180 deg).
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
    """

    gain_margin: float
    phase_margin: float
    crossover: float
    phase_crossover: float
    ms: float
    ms_frequency: float
    bandwidth: float

    @property
    def gain_margin_db(self) -> float:
        return 20.0 * math.log10(self.gain_margin) if self.gain_margin > 0 else -math.inf

    @property
    def phase_margin_deg(self) -> float:
        return math.degrees(self.phase_margin)

    @property
    def bandwidth_hz(self) -> float:
        return self.bandwidth * HZ

    def to_dict(self) -> dict:
        """JSON-ready: SI plus the usual engineering units under suffixed keys."""
        gm_db = self.gain_margin_db
        return {
            "gain_margin": self.gain_margin if math.isfinite(self.gain_margin) else None,
            "gain_margin_db": gm_db if math.isfinite(gm_db) else None,
            "phase_margin_deg": self.phase_margin_deg,
            "crossover_hz": self.crossover * HZ,
            "phase_crossover_hz": (self.phase_crossover * HZ
                                   if math.isfinite(self.phase_crossover) else None),
            "ms": self.ms,
            "ms_frequency_hz": self.ms_frequency * HZ,
            "bandwidth_hz": self.bandwidth_hz,
        }


def analyse_loop(loop: control.StateSpace, omega=None) -> LoopAnalysis:
    """Margins, sensitivity peak and bandwidth of a loop transfer function L(s).

    The closed loop L/(1+L) must be stable (checked on its poles).

    Parameters
    ----------
    loop : control.StateSpace
        SISO loop transfer function (see :func:`servotune.plant.loop_transfer`).
    omega : array_like, optional
        Dense grid [rad/s]; default 4000 log-spaced points over 0.1 Hz .. 10 kHz.

    Raises
    ------
    UnstableLoopError
        If the closed loop is unstable.

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
    # phase crossover: where the phase passes -180 deg (mod 360) with |L| largest -> GM
    k = np.floor((phase + math.pi) / (2 * math.pi))
    flips = np.nonzero(np.diff(k) != 0)[0]
    gm, wpc = math.inf, math.nan
    for i in flips:
        target = (max(k[i], k[i + 1])) * 2 * math.pi - math.pi
        f = (target - phase[i]) / (phase[i + 1] - phase[i])
        m_at = math.exp(math.log(mag[i]) + f * (math.log(mag[i + 1]) - math.log(mag[i])))
        if 1.0 / m_at < gm:
            gm = 1.0 / m_at
            wpc = float(omega[i] * (omega[i + 1] / omega[i]) ** f)
    # the closed-loop gain two decades below the grid stands for the DC gain: the state
    # space's own dcgain() is ill-conditioned when the loop carries a rigid-body mode (a free
    # integrator of position)
    l_low = complex(fast_frequency_response(loop, [omega[0] / 100.0],
                                            rtol=1e-7).complex.reshape(-1)[0])
    t0 = abs(l_low / (1.0 + l_low))
    below = np.nonzero(t < t0 / math.sqrt(2.0))[0]
    if below.size and below[0] > 0:
        i = below[0]
        f = (math.log(t0 / math.sqrt(2.0)) - math.log(t[i - 1])) / (
            math.log(t[i]) - math.log(t[i - 1]))
        bw = float(omega[i - 1] * (omega[i] / omega[i - 1]) ** f)
    else:
        bw = float(omega[below[0]]) if below.size else math.inf
    return LoopAnalysis(gain_margin=gm, phase_margin=pm, crossover=wc, phase_crossover=wpc,
                        ms=ms, ms_frequency=w_ms, bandwidth=bw)


@dataclass(frozen=True)
class ClosedLoopPoles:
    """Closed-loop poles with their natural frequencies [rad/s] and damping ratios."""

    poles: np.ndarray
    natural_frequencies: np.ndarray
    damping_ratios: np.ndarray

    @property
    def stable(self) -> bool:
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
    """Poles of a (closed-loop) system sorted by frequency, with wn and zeta."""
    p = np.linalg.eigvals(control.ss(sys).A) if control.ss(sys).nstates else np.array([])
    p = p[np.argsort(np.abs(p))]
    wn = np.abs(p)
    with np.errstate(divide="ignore", invalid="ignore"):
        zeta = np.where(wn > 0, -p.real / wn, 1.0)
    return ClosedLoopPoles(p, wn, zeta)


def require_stable(sys: control.StateSpace, what: str = "closed-loop axis") -> None:
    """Raise :class:`UnstableLoopError` naming the unstable poles if ``sys`` is unstable.

    Poles at the origin are accepted only if ``sys`` has none at all (a marginal rigid-body
    mode of an uncontrolled axis is reported as such).
    """
    poles = closed_loop_poles(sys)
    scale = max(float(np.abs(poles.poles).max(initial=0.0)), 1.0)
    bad = poles.poles[poles.poles.real > 1e-9 * scale]
    if bad.size:
        listed = ", ".join(f"{p.real:.3g}{p.imag:+.3g}j" for p in bad[:4])
        raise UnstableLoopError(
            f"the {what} is unstable: {bad.size} pole(s) in the right half plane ({listed} "
            "rad/s); lower the loop gains (Kv, Kp) or raise Ti, or add damping")


def following_error(plant: control.StateSpace, feed: float) -> float:
    """Steady following error [m] at a constant feed [m/s] from the plant's DC behaviour.

    For a ramp x_ref = v t with v_ref = v, a_ref = 0, the error settles at
    ``v (G_xe'(0) + G_ve(0))`` where ``G'(0) = -C A^-2 B`` and ``G(0) = D - C A^-1 B``.
    """
    require_stable(plant)
    sys = control.ss(plant)
    o = sys.output_labels.index("following_error")
    ix, iv = sys.input_labels.index("x_ref"), sys.input_labels.index("v_ref")
    a_inv_b = np.linalg.solve(sys.A, sys.B[:, [ix, iv]])
    slope = -sys.C[o] @ np.linalg.solve(sys.A, a_inv_b[:, 0])
    g_v0 = sys.D[o, iv] - sys.C[o] @ a_inv_b[:, 1]
    return float(feed * (slope + g_v0))
