"""The digital drive written out by hand, as the reference of ``tests/test_digital.py``.

Nothing here calls :mod:`servotune.digital` (nor :mod:`servotune.plant`): the continuous axis
is assembled from the structure's M, K, D matrices, the winding and the contact, discretised
with ``scipy.linalg.expm``, and the controllers are the difference equations of the
conventions (:class:`servotune.drive.Sampling`) written as explicit per-sample loops:

* position, every N_p N_v T:  omega_cmd = Kv/r (x_ref - x_fb) + kvff/r v_ref
* velocity, every N_v T:      speed = F[(phi_k - phi_{k-1}) / T_v],
                              F: y_k = a y_{k-1} + (1 - a) x_k, a = exp(-T_v / tau)
                              T_set = C_v(omega_cmd - speed) + J_ff/r a_ref
* current, every T:           u = C_i(F(T_set) / kt - i), F the set-point filters
                              (Tustin prewarped to each filter's frequency)
* PI: u_k = Kp (e_k + (T'/Ti) S_k) (forward Euler) or Kp (e_k + (T'/Ti) (S_k + e_k / 2))
  (Tustin), S_{k+1} = S_k + e_k
* each output applied d = computation_delay periods (of its controller) after the sample it
  was computed from, held until the controller's next update; at an instant where several
  controllers update, the slower first, the faster reads the new held output; the voltage is
  held over the current period (zero-order hold).

Only the data classes of servotune (Drive, Motor, PIController, Sampling, ModalModel, Contact)
are read, for their numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

# ------------------------------------------------------------------------ continuous plant


@dataclass(frozen=True)
class Plant:
    """The continuous axis driven by its motor voltage: x' = a x + b_u u + b_f f.

    ``c_meas`` has the rows current [A], motor angle (rotor - stator) [rad], x_fb [m];
    ``c_out`` the displacements asked for [m].
    """

    a: np.ndarray
    b_u: np.ndarray
    b_f: np.ndarray
    c_meas: np.ndarray
    c_out: np.ndarray


def open_plant(structure, drive, contact=None, pads=(), force="wp.x", outputs=("wp.x",)):
    """Assemble the voltage-driven axis from first principles.

    State [q, q', i, contact states per pad]::

        M q'' + D q' + K q = e_rotor kt i - e_stator kt i + e_force f + sum_pads e_p F_p
        L i' = u - R i - ke (q'_rotor - q'_stator)
        F_p = -(k x_p + c x'_p) / n_pads            (a static contact: stiffness, damping)
        F_p = -(Cc z_p + Dc x'_p) / n_pads,  z_p' = Ac z_p + Bc x'_p   (a dynamic contact)
    """
    dofs = list(structure.dofs)
    n = len(dofs)
    idx = {d: i for i, d in enumerate(dofs)}
    m = np.asarray(structure.mass, dtype=float)
    k = np.asarray(structure.stiffness, dtype=float).copy()
    dmp = np.asarray(structure.damping, dtype=float).copy()
    pads = list(pads)
    sys = None if contact is None else contact.system
    if contact is not None and sys is None:
        for p in pads:
            k[idx[p], idx[p]] += contact.stiffness / len(pads)
            dmp[idx[p], idx[p]] += contact.damping / len(pads)
    nc = 0 if sys is None else np.asarray(sys.A).shape[0]
    n_c = nc * len(pads)
    mot = drive.motor
    e_t = np.zeros(n)
    e_t[idx[mot.rotor]] = 1.0
    if mot.stator is not None:
        e_t[idx[mot.stator]] = -1.0
    size = 2 * n + 1 + n_c
    minv = np.linalg.inv(m)
    a = np.zeros((size, size))
    a[:n, n:2 * n] = np.eye(n)
    a[n:2 * n, :n] = -minv @ k
    a[n:2 * n, n:2 * n] = -minv @ dmp
    a[n:2 * n, 2 * n] = minv @ e_t * mot.torque_constant
    a[2 * n, n:2 * n] = -mot.back_emf_constant / mot.inductance * e_t
    a[2 * n, 2 * n] = -mot.resistance / mot.inductance
    if sys is not None:
        ac, bc = np.asarray(sys.A, float), np.asarray(sys.B, float)
        cc, dc = np.asarray(sys.C, float), np.asarray(sys.D, float)
        for j, p in enumerate(pads):
            z = slice(2 * n + 1 + j * nc, 2 * n + 1 + (j + 1) * nc)
            e_p = np.zeros(n)
            e_p[idx[p]] = 1.0
            a[z, z] = ac
            a[z, n:2 * n] = bc @ e_p[None, :]
            # force on the pad DOF: -(Cc z + Dc v) / n_pads
            a[n:2 * n, z] -= np.outer(minv @ e_p, cc[0]) / len(pads)
            a[n:2 * n, n:2 * n] -= dc[0, 0] / len(pads) * np.outer(minv @ e_p, e_p)
    b_u = np.zeros((size, 1))
    b_u[2 * n, 0] = 1.0 / mot.inductance
    b_f = np.zeros((size, 1))
    if force is not None:
        b_f[n:2 * n, 0] = minv[:, idx[force]]
    c_meas = np.zeros((3, size))
    c_meas[0, 2 * n] = 1.0
    c_meas[1, :n] = e_t
    if drive.feedback == "linear":
        c_meas[2, idx[drive.encoder]] = 1.0
    else:
        c_meas[2, :n] = drive.ratio * e_t
    c_out = np.zeros((len(outputs), size))
    for j, o in enumerate(outputs):
        c_out[j, idx[o]] = 1.0
    return Plant(a, b_u, b_f, c_meas, c_out)


def with_cosine_force(plant: Plant, omega: float) -> Plant:
    """The plant with the force f = cos(omega t) generated by two more states (c, s):
    c' = -omega s, s' = omega c, f = c, so that the zero-order hold of the voltage stays
    exact with the force continuous."""
    n = plant.a.shape[0]
    a = np.zeros((n + 2, n + 2))
    a[:n, :n] = plant.a
    a[:n, n] = plant.b_f[:, 0]
    a[n, n + 1] = -omega
    a[n + 1, n] = omega
    pad = np.zeros((1, 2))
    return Plant(a, np.vstack([plant.b_u, np.zeros((2, 1))]), np.zeros((n + 2, 1)),
                 np.hstack([plant.c_meas, np.repeat(pad, 3, 0)]),
                 np.hstack([plant.c_out, np.repeat(pad, plant.c_out.shape[0], 0)]))


def zoh(a: np.ndarray, b: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold discretisation: expm([[A, B], [0, 0]] t) (Astrom-Wittenmark
    sec 2.3)."""
    n, m = b.shape
    aug = np.zeros((n + m, n + m))
    aug[:n, :n] = a
    aug[:n, n:] = b
    e = scipy.linalg.expm(aug * t)
    return e[:n, :n], e[:n, n:]


# ------------------------------------------------------------------------ controllers


def pi_sequence(kp: float, ti: float, period: float, rule: str, e) -> np.ndarray:
    """A PI controller's outputs for an error sequence, by its difference equation."""
    out = np.empty(len(e))
    s = 0.0
    for k, ek in enumerate(e):
        integral = s + (0.5 * ek if rule == "tustin" else 0.0)
        out[k] = kp * (ek + (0.0 if math.isinf(ti) else period / ti * integral))
        s += ek
    return out


def pi_z(kp: float, ti: float, period: float, rule: str, z) -> np.ndarray:
    """The PI's transfer function from its difference equation: S = E / (z - 1), so forward
    Euler is Kp (1 + T'/(Ti (z - 1))) and Tustin Kp (1 + T'/Ti (1/(z - 1) + 1/2))."""
    z = np.asarray(z, dtype=complex)
    if math.isinf(ti):
        return np.full(z.shape, kp, dtype=complex)
    integral = 1.0 / (z - 1.0) + (0.5 if rule == "tustin" else 0.0)
    return kp * (1.0 + period / ti * integral)


def speed_z(period: float, tau: float, z) -> np.ndarray:
    """Speed per sampled angle: (1 - z^-1)/T_v, times (1 - a)/(1 - a z^-1) with a filter."""
    z = np.asarray(z, dtype=complex)
    m = (1.0 - 1.0 / z) / period
    if tau > 0.0:
        a = math.exp(-period / tau)
        m = m * (1.0 - a) / (1.0 - a / z)
    return m


def setpoint_biquads(drive, period: float) -> list[np.ndarray]:
    """The torque set-point filters (low-pass, then notch) as difference equations.

    Each continuous filter (n0 s^2 + n1 s + n2)/(d0 s^2 + d1 s + d2), written from the
    definitions of :class:`~servotune.drive.LowPassFilter` (w^2/(s^2 + 2 zeta w s + w^2)) and
    :class:`~servotune.drive.NotchFilter` ((s^2 + 2 zeta_p depth w s + w^2)/(s^2 + 2 zeta_p w s
    + w^2), zeta_p = width/2), under s = c (z - 1)/(z + 1), c = w/tan(w T/2) (Tustin
    prewarped to the filter's own frequency): (z - 1)^2 -> 1, -2, 1; z^2 - 1 -> 1, 0, -1;
    (z + 1)^2 -> 1, 2, 1. Returns [b0, b1, b2, a1, a2] per filter:
    y_k = b0 x_k + b1 x_{k-1} + b2 x_{k-2} - a1 y_{k-1} - a2 y_{k-2}.
    """
    out = []
    for f in drive.setpoint_filters:
        w = 2 * math.pi * f.f_hz
        if hasattr(f, "depth"):
            zp = 0.5 * f.width
            num, den = (1.0, 2 * zp * f.depth * w, w * w), (1.0, 2 * zp * w, w * w)
        else:
            num, den = (0.0, 0.0, w * w), (1.0, 2 * f.damping_ratio * w, w * w)
        c = w / math.tan(0.5 * w * period)

        def poly(p, c=c):
            return np.array([p[0] * c * c + p[1] * c + p[2], -2 * p[0] * c * c + 2 * p[2],
                             p[0] * c * c - p[1] * c + p[2]])

        bn, an = poly(num), poly(den)
        out.append(np.concatenate([bn / an[0], an[1:] / an[0]]))
    return out


class DigitalLoop:
    """The discretised plant and the three controllers, iterated sample by sample.

    The whole state is one array ``z`` of shape (N, batch): the plant state, then the
    controllers' memories (delay lines, previous angle, speed filter, PI sums, set-point
    filter memories) and the held outputs. References are zero unless given to :meth:`step`.
    ``position_loop=False`` opens the position loop: the held speed command is then an input,
    left as it is in ``z``.
    """

    def __init__(self, ad, bd, c_meas, drive, position_loop: bool = True):
        s = drive.sampling
        self.ad, self.bd, self.c_meas = ad, bd[:, 0], c_meas
        self.t = s.current_period
        self.n_v = round(s.velocity_period / s.current_period)
        self.n_p = round(s.position_period / s.velocity_period)
        self.frame = self.n_v * self.n_p
        self.tv = s.velocity_period
        self.d = s.computation_delay
        self.rule = s.integral_rule
        self.filter = math.exp(-self.tv / s.speed_filter) if s.speed_filter > 0 else None
        self.drive = drive
        self.position_loop = position_loop
        self.biquads = setpoint_biquads(drive, self.t)
        n = ad.shape[0]
        d = self.d
        names = [("plant", n), ("pos_line", d if position_loop else 0), ("prev_angle", 1),
                 ("speed_y", 0 if self.filter is None else 1),
                 ("vel_sum", 1), ("vel_line", d),
                 *[(f"setpoint_{j}", 4) for j in range(len(self.biquads))],
                 ("cur_sum", 1), ("cur_line", d),
                 ("omega_cmd", 1), ("torque_set", 1), ("voltage", 1)]
        self.slices, start = {}, 0
        for name, size in names:
            self.slices[name] = slice(start, start + size)
            start += size
        self.size = start

    def _delay(self, z, line: str, raw):
        """Push ``raw`` into a delay line of d samples, return what comes out."""
        if self.d == 0:
            return raw
        buf = z[self.slices[line]]
        out = buf[0].copy()
        buf[:-1] = buf[1:].copy()
        buf[-1] = raw
        return out

    def _pi(self, z, sum_name: str, pi, period, e):
        s = z[self.slices[sum_name]][0]
        integral = s + (0.5 * e if self.rule == "tustin" else 0.0)
        u = pi.kp * (e + (0.0 if math.isinf(pi.ti) else period / pi.ti * integral))
        z[self.slices[sum_name]][0] = s + e
        return u

    def step(self, z, k: int, fine=None, record=None, references=(0.0, 0.0, 0.0)) -> None:
        """Advance ``z`` in place over the fast period starting at sample ``k``.

        ``fine = (ad_h, bd_h, c_out, m)`` integrates the period in m sub-steps and appends
        ``c_out x`` at each sub-step's start to ``record``; ``references`` are x_ref [m],
        v_ref [m/s] and a_ref [m/s^2] at sample k.
        """
        drv, sl = self.drive, self.slices
        x_ref, v_ref, a_ref = references
        x = z[sl["plant"]]
        current, angle, x_fb = self.c_meas @ x
        if k % self.frame == 0 and self.position_loop:
            raw = (drv.kv / drv.ratio * (x_ref - x_fb)
                   + drv.velocity_feedforward / drv.ratio * v_ref)
            z[sl["omega_cmd"]][0] = self._delay(z, "pos_line", raw)
        if k % self.n_v == 0:
            prev = z[sl["prev_angle"]][0].copy()
            speed = (angle - prev) / self.tv
            z[sl["prev_angle"]][0] = angle
            if self.filter is not None:
                a = self.filter
                speed = a * z[sl["speed_y"]][0] + (1.0 - a) * speed
                z[sl["speed_y"]][0] = speed
            e = z[sl["omega_cmd"]][0] - speed
            raw = (self._pi(z, "vel_sum", drv.velocity_loop, self.tv, e)
                   + drv.torque_feedforward_inertia / drv.ratio * a_ref)
            z[sl["torque_set"]][0] = self._delay(z, "vel_line", raw)
        signal = z[sl["torque_set"]][0]
        for j, (b0, b1, b2, a1, a2) in enumerate(self.biquads):
            mem = z[sl[f"setpoint_{j}"]]  # x_{k-1}, x_{k-2}, y_{k-1}, y_{k-2}
            y = b0 * signal + b1 * mem[0] + b2 * mem[1] - a1 * mem[2] - a2 * mem[3]
            mem[1], mem[3] = mem[0].copy(), mem[2].copy()
            mem[0], mem[2] = signal, y
            signal = y
        e = signal / drv.motor.torque_constant - current
        raw = self._pi(z, "cur_sum", drv.current_loop, self.t, e)
        u = self._delay(z, "cur_line", raw)
        z[sl["voltage"]][0] = u
        if fine is None:
            z[sl["plant"]] = self.ad @ x + np.outer(self.bd, u)
            return
        ad_h, bd_h, c_out, m = fine
        for _ in range(m):
            record.append(c_out @ x)
            x = ad_h @ x + np.outer(bd_h[:, 0], u)
        z[sl["plant"]] = x

    def run(self, z, k0: int, steps: int) -> None:
        for k in range(k0, k0 + steps):
            self.step(z, k)

    def map(self, steps: int) -> np.ndarray:
        """The state transition over ``steps`` fast samples from phase 0: the simulation of
        every unit initial state."""
        z = np.eye(self.size)
        self.run(z, 0, steps)
        return z

    def frame_map(self) -> np.ndarray:
        """The state transition over one frame (the position period)."""
        return self.map(self.frame)

    def position_plant(self, omega) -> np.ndarray:
        """Sampled x_fb per held speed command at Z = exp(j w T_p), the velocity loop closed
        (the position loop open): x_{j+1} = Phi x_j + Gamma omega_cmd_j, the frame map of the
        simulation split into the state and the held command."""
        assert not self.position_loop
        full = self.frame_map()
        w = self.slices["omega_cmd"].start
        rest = [i for i in range(self.size) if i != w]
        phi, gam = full[np.ix_(rest, rest)], full[rest, w]
        c = np.zeros(len(rest))
        c[self.slices["plant"]] = self.c_meas[2]
        zz = np.exp(1j * np.asarray(omega, dtype=float) * self.t * self.frame)
        x = np.linalg.solve(zz[:, None, None] * np.eye(len(rest))[None] - phi[None],
                            np.broadcast_to(gam, (zz.size, len(rest)))[..., None])[..., 0]
        return x @ c


def growth_per_frame(loop: DigitalLoop, z0: np.ndarray, frames: int, burn: int) -> float:
    """Iterate from ``z0``, normalising after every frame; return the mean growth factor per
    frame over the frames after ``burn`` (geometric mean of the norm ratios)."""
    z = z0.reshape(-1, 1).copy()
    logs = []
    for f in range(frames):
        loop.run(z, f * loop.frame, loop.frame)
        norm = float(np.linalg.norm(z))
        logs.append(math.log(norm))
        z /= norm
    return math.exp(float(np.mean(logs[burn:])))


def largest_stable(stable, low: float, high: float, rtol: float = 1e-3) -> float:
    """Bisect on a gain: ``stable(low)`` is True, ``stable(high)`` False."""
    assert stable(low) and not stable(high)
    while high - low > rtol * low:
        mid = 0.5 * (low + high)
        if stable(mid):
            low = mid
        else:
            high = mid
    return 0.5 * (low + high)


# ------------------------------------------------------------------------ margins


@dataclass(frozen=True)
class Margins:
    """Ms, phase margin [deg] and gain margin [dB] of a loop, and where [rad/s]."""

    ms: float
    ms_frequency: float
    phase_margin_deg: float
    crossover: float
    gain_margin_db: float
    phase_crossover: float


def margins(loop, omega_max: float, omega_min: float = 2 * math.pi * 0.1,
            points: int = 1500) -> Margins:
    """Margins of a loop L(w) (a callable on arrays) on (omega_min, omega_max), each refined
    by root finding / scalar optimisation on L itself (not interpolated on a grid).

    PM at the last downward crossing of |L| = 1; GM = 1/|L| at the crossing of the negative
    real axis nearest -1 from inside the unit circle; Ms = max |1/(1 + L)|.
    """
    def one(w):
        return complex(loop(np.array([w]))[0])

    w = np.geomspace(omega_min, omega_max, points)
    lw = loop(w)
    s = np.abs(1.0 / (1.0 + lw))
    i = int(np.argmax(s))
    lo, hi = w[max(i - 1, 0)], w[min(i + 1, w.size - 1)]
    res = scipy.optimize.minimize_scalar(lambda v: -abs(1.0 / (1.0 + one(v))), bounds=(lo, hi),
                                         method="bounded", options={"xatol": 1e-9 * hi})
    ms, w_ms = -res.fun, res.x
    mag = np.abs(lw)
    down = np.nonzero((mag[:-1] >= 1.0) & (mag[1:] < 1.0))[0]
    j = down[-1]
    wc = scipy.optimize.brentq(lambda v: abs(one(v)) - 1.0, w[j], w[j + 1], xtol=1e-12 * w[j])
    pm = 180.0 + math.degrees(np.angle(one(wc)))
    pm = (pm + 180.0) % 360.0 - 180.0
    gm, wpc = math.inf, math.nan
    im = lw.imag
    for j in np.nonzero(np.sign(im[:-1]) != np.sign(im[1:]))[0]:
        if lw[j].real >= 0 and lw[j + 1].real >= 0:
            continue
        wx = scipy.optimize.brentq(lambda v: one(v).imag, w[j], w[j + 1], xtol=1e-12 * w[j])
        lx = one(wx)
        if lx.real < 0 and abs(lx) < 1.0 and 1.0 / abs(lx) < gm:
            gm, wpc = 1.0 / abs(lx), wx
    return Margins(ms, w_ms, pm, wc, 20.0 * math.log10(gm), wpc)


def current_loop_state_space(ad, bd, c_meas, drive):
    """The fast-rate system from the held torque set-point to the sampled angle with the
    current loop closed (state [x, S_c, delay line, set-point filter memories]), written from
    the difference equations u_k = D_c C_i(F(T_set)/kt - i_k)."""
    cl, mot, s = drive.current_loop, drive.motor, drive.sampling
    t, d, rule = s.current_period, s.computation_delay, s.integral_rule
    n = ad.shape[0]
    biquads = setpoint_biquads(drive, t)
    ki = 0.0 if math.isinf(cl.ti) else t / cl.ti
    feed = cl.kp * (1.0 + (0.5 * ki if rule == "tustin" else 0.0))  # raw = feed e + kp ki S
    c_i, c_phi = c_meas[0], c_meas[1]
    f0 = n + 1 + d  # first filter memory
    size = f0 + 4 * len(biquads)
    a = np.zeros((size, size))
    b = np.zeros((size, 1))
    # the filtered set-point y = sig_x . state + sig_t T, filter by filter
    sig_x, sig_t = np.zeros(size), 1.0
    for j, (b0, b1, b2, a1, a2) in enumerate(biquads):
        m = f0 + 4 * j  # x_{k-1}, x_{k-2}, y_{k-1}, y_{k-2}
        y_x = b0 * sig_x
        y_x[m:m + 4] += [b1, b2, -a1, -a2]
        y_t = b0 * sig_t
        a[m + 1, m] = 1.0
        a[m + 3, m + 2] = 1.0
        a[m], b[m, 0] = sig_x, sig_t
        a[m + 2], b[m + 2, 0] = y_x, y_t
        sig_x, sig_t = y_x, y_t
    # error e = y/kt - c_i x ; raw = feed e + kp ki S
    e_x = sig_x / mot.torque_constant
    e_x[:n] -= c_i
    e_t = sig_t / mot.torque_constant
    raw_x = feed * e_x
    raw_x[n] += cl.kp * ki
    raw_t = feed * e_t
    if d == 0:
        u_x, u_t = raw_x, raw_t
    else:
        u_x, u_t = np.zeros(size), 0.0
        u_x[n + 1] = 1.0
        for j in range(d - 1):
            a[n + 1 + j, n + 2 + j] = 1.0
        a[n + d] = raw_x
        b[n + d, 0] = raw_t
    a[:n] += np.outer(bd[:, 0], u_x)
    a[:n, :n] += ad
    b[:n, 0] += bd[:, 0] * u_t
    a[n] += e_x
    a[n, n] += 1.0
    b[n, 0] = e_t
    c = np.zeros((1, size))
    c[0, :n] = c_phi
    return a, b, c


def velocity_loop(ad, bd, c_meas, drive, omega) -> np.ndarray:
    """The velocity loop L_v at z = exp(j w T_v), broken at the velocity controller, the
    position loop open: L_v = z^-d C_v(z) M(z) G(z), G the closed current loop from the
    held torque set-point to the sampled angle, held over N_v fast periods and sampled every
    N_v: x_{k+N} = A^N x_k + (sum_{j<N} A^j) B T (exact for a held input)."""
    s = drive.sampling
    n_v = round(s.velocity_period / s.current_period)
    a, b, c = current_loop_state_space(ad, bd, c_meas, drive)
    a_n = np.linalg.matrix_power(a, n_v)
    b_n = sum(np.linalg.matrix_power(a, j) for j in range(n_v)) @ b
    omega = np.asarray(omega, dtype=float)
    z = np.exp(1j * omega * s.velocity_period)
    g = np.empty(z.shape, dtype=complex)
    eye = np.eye(a.shape[0])
    for lo in range(0, z.size, 200):
        zz = z[lo:lo + 200]
        x = np.linalg.solve(zz[:, None, None] * eye[None] - a_n[None],
                            np.broadcast_to(b_n, (zz.size, *b_n.shape)))
        g[lo:lo + 200] = (c @ x)[:, 0, 0]
    vel = drive.velocity_loop
    return (z ** -s.computation_delay * pi_z(vel.kp, vel.ti, s.velocity_period,
                                             s.integral_rule, z)
            * speed_z(s.velocity_period, s.speed_filter, z) * g)
