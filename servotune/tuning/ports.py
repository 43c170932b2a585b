"""Frequency responses at the ports of the structure, in real arithmetic for casadi.

The structure's receptance between its ports (work piece, pads, motor, encoder) comes from the
modal sum once per frequency grid; the guide-way contact of each regime model couples through
the eigen-decomposition of the pad block, and the drive closes around scalar port receptances
(see the package docstring for the equations). Each complex quantity is a (real, imaginary)
pair of numpy arrays or casadi expressions, so the same code evaluates numerically and builds
the NLP. Everything that does not depend on the design (the structure's receptances, the
contact impedance Z_0 of each model, the fixed parts of the cascade with the digital drive's
delays) is *data*: one column per (frequency, model).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import frequency
from ..digital import cascade
from ..drive import cascade_response
from .problem import Design, TuningProblem

__all__ = ["ResponseModel", "evaluate"]


class _Cx:
    """A complex number as a (real, imaginary) pair of arrays or casadi expressions."""

    __slots__ = ("im", "re")

    def __init__(self, re, im=0.0):
        self.re, self.im = re, im

    @staticmethod
    def of(z):
        z = np.asarray(z)
        return _Cx(z.real.copy(), z.imag.copy())

    def _c(self, other):
        return other if isinstance(other, _Cx) else _Cx(other, 0.0)

    def __add__(self, o):
        o = self._c(o)
        return _Cx(self.re + o.re, self.im + o.im)

    __radd__ = __add__

    def __sub__(self, o):
        o = self._c(o)
        return _Cx(self.re - o.re, self.im - o.im)

    def __rsub__(self, o):
        return self._c(o) - self

    def __neg__(self):
        return _Cx(-self.re, -self.im)

    def __mul__(self, o):
        o = self._c(o)
        return _Cx(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)

    __rmul__ = __mul__

    def __truediv__(self, o):
        o = self._c(o)
        den = o.re * o.re + o.im * o.im
        return _Cx((self.re * o.re + self.im * o.im) / den, (self.im * o.re - self.re * o.im) / den)

    def __rtruediv__(self, o):
        return self._c(o) / self

    def abs2(self):
        return self.re * self.re + self.im * self.im

    def value(self) -> np.ndarray:
        return np.asarray(self.re) + 1j * np.asarray(self.im)


DRIVE_PARTS = ("forward", "winding")
#: The digital drive's parts at a frequency w (design-independent; see :func:`sampled_parts`).
SAMPLED_PARTS = ("h0", "k_ci", "k_ct", "dv_m", "dv", "qv", "hold_v", "hold_p", "dp", "half")
#: Per model and frequency: the zero-order hold's aliases of the sampled current, angle and
#: position per voltage, and the corrections of the lifts beyond their first term.
CORRECTIONS = ("a_i", "a_phi", "a_x", "d_vphi", "d_vx", "d_px")


def notch_response(design, omega, half=None, period: float = 0.0):
    """The tuned current set-point notch's response (a :class:`_Cx`) for numeric or symbolic
    design values ``notch_frequency`` w0 [rad/s], ``notch_width`` (2 zeta_p) and
    ``notch_depth`` (zeta_z = zeta_p depth).

    Continuous (``half`` None): ``(w0^2 - w^2 + 2j zeta_z w0 w) / (w0^2 - w^2 + 2j zeta_p w0
    w)``. Digital, as the drive computes it (Tustin prewarped to w0, in the current
    controller's cycle T, :func:`servotune.digital.discrete_filter`): s = (w0 / k) (z - 1) /
    (z + 1) with k = tan(w0 T / 2), and at z = exp(j w T), (z - 1)/(z + 1) = j tan(w T / 2);
    with ``half = exp(j w T / 2) = c + j s`` and both sides times (k c)^2 / w0^2::

        F = (k^2 c^2 - s^2 + 2j zeta_z k s c) / (k^2 c^2 - s^2 + 2j zeta_p k s c)

    which stays finite at the Nyquist frequency (c = 0: F = 1).
    """
    w0 = design["notch_frequency"]
    zp = 0.5 * design["notch_width"]
    zz = zp * design["notch_depth"]
    if half is None:
        re = w0 * w0 - omega * omega
        return _Cx(re, 2.0 * zz * w0 * omega) / _Cx(re, 2.0 * zp * w0 * omega)
    k = _tan(0.5 * w0 * period)
    c, s = half.re, half.im
    re = k * k * c * c - s * s
    return _Cx(re, 2.0 * zz * k * s * c) / _Cx(re, 2.0 * zp * k * s * c)


def lowpass_response(design, omega, zeta: float, half=None, period: float = 0.0):
    """The tuned current set-point low-pass' response (a :class:`_Cx`) for a numeric or
    symbolic corner ``lowpass_frequency`` w0 [rad/s] and damping ratio ``zeta``.

    Continuous (``half`` None): ``w0^2 / (w0^2 - w^2 + 2j zeta w0 w)``. Digital, as the drive
    computes it (Tustin prewarped to w0 in the current controller's cycle T, as
    :func:`notch_response`): with k = tan(w0 T / 2) and ``half = exp(j w T / 2) = c + j s``::

        F = k^2 c^2 / (k^2 c^2 - s^2 + 2j zeta k s c)

    which is 0 at the Nyquist frequency (c = 0), as Tustin's low-pass is.
    """
    w0 = design["lowpass_frequency"]
    if half is None:
        return _Cx(w0 * w0, 0.0 * omega) / _Cx(w0 * w0 - omega * omega, 2.0 * zeta * w0 * omega)
    k = _tan(0.5 * w0 * period)
    c, s = half.re, half.im
    num = k * k * c * c
    return _Cx(num, 0.0 * s) / _Cx(num - s * s, 2.0 * zeta * k * s * c)


def _filters(problem, design, omega, half=None, period: float = 0.0):
    """The product of the tuned set-point filters' responses (notch, low-pass), or None."""
    out = None
    if problem.notch is not None:
        out = notch_response(design, omega, half, period)
    if problem.lowpass is not None and design.get("lowpass_frequency") is not None:
        f = lowpass_response(design, omega, problem.lowpass.damping_ratio, half, period)
        out = f if out is None else out * f
    return out


def _tan(x):
    """tan of a number or a casadi expression."""
    return x.tan() if hasattr(x, "tan") else np.tan(x)


def is_sampled(problem: TuningProblem) -> bool:
    """Whether the problem's drive is digital (a sampled-data loop)."""
    return problem.drive is not None and not problem.drive.digital.is_continuous


def sampled_parts(drive, omega: np.ndarray) -> dict:
    """The digital drive's parts at angular frequencies ``omega`` (complex arrays).

    ``h0`` the zero-order hold's fundamental over the current period; ``k_ci``, ``k_ct`` the
    current controller's voltage per sampled current and per held torque set-point (from
    :func:`servotune.digital.digital_controller`); ``dv_m = z_v^-d M(z_v)`` (delay and speed
    measurement: backward difference and filter), ``dv = z_v^-d`` and ``qv`` the integral factor
    of the velocity PI, ``C_v = Kp (1 + qv / Ti)``; ``hold_v``, ``hold_p`` the fundamentals
    ``B_N(w)/N`` of the velocity and position controllers' holds; ``dp = z_p^-d``, set to 0
    above the position controller's Nyquist frequency (there the position loop's rows are
    void: its response repeats); ``half = exp(j w T / 2)`` (T the current period) for the
    tuned notch (:func:`notch_response`).
    """
    from ..digital import digital_controller
    from ..digital.sampled import _box, hold_fundamental

    s = drive.sampling
    ctl = digital_controller(drive)
    n_v, n_p = s.multiples()
    t, tv, tp = s.current_period, s.velocity_period, s.position_period
    d = s.computation_delay
    z = np.exp(1j * omega * t)
    zv = np.exp(1j * omega * tv)
    zp = np.exp(1j * omega * tp)
    m = (1.0 - 1.0 / zv) / tv
    if s.speed_filter > 0.0:
        a = math.exp(-tv / s.speed_filter)
        m = m * (1.0 - a) / (1.0 - a / zv)
    qv = tv / (zv - 1.0) if s.integral_rule == "forward_euler" else \
        0.5 * tv * (zv + 1.0) / (zv - 1.0)
    dp = np.where(omega < math.pi / tp * (1.0 - 1e-9), zp ** (-d), 0.0)
    return {"h0": hold_fundamental(omega, t), "k_ci": ctl.response("current", "current", z),
            "k_ct": ctl.response("current", "torque_set", z), "dv_m": zv ** (-d) * m,
            "dv": zv ** (-d), "qv": qv, "hold_v": _box(omega, t, n_v) / n_v,
            "hold_p": _box(omega, tv, n_p) / n_p, "dp": dp, "half": np.exp(0.5j * omega * t)}


_AXES: dict = {}


def _reference_axes(problem: TuningProblem, reference: Design) -> list:
    """The sampled-data axes of every regime model at ``reference`` (a few kept: the tuning
    asks for the same ones at every grid)."""
    from ..digital import SampledAxis

    key = (id(problem), reference)
    kept = _AXES.get(key)
    if kept is not None and kept[0] is problem:
        return kept[1]
    drive = problem.drive_for(reference)
    axes = [SampledAxis(problem.structure, drive,
                        model.contact(reference.c) if problem.pads else None, problem.pads)
            for model in problem.regimes]
    if len(_AXES) >= 8:
        _AXES.pop(next(iter(_AXES)))
    _AXES[key] = (problem, axes)
    return axes


def sampled_corrections(problem: TuningProblem, omega: np.ndarray, reference: Design,
                        pairs: dict, alpha: dict, lam: np.ndarray, zfix: np.ndarray,
                        parts: dict) -> np.ndarray:
    """The per-model corrections of the port model of a digital drive, exact at ``reference``.

    The port model evaluates the zero-order-hold plant by its first term, ``h0 P(jw)``, and
    each lift by its first term, ``(B_N(w)/N) G(w)``; the corrections are what the exact
    sampled-data model (:class:`servotune.digital.SampledAxis`) adds at ``reference``: the
    hold's aliases (which do not depend on the design: checked to 1e-8 relative on the bundled
    axis over C x 3) and the lifts' other terms (which do, a little: the position loop's
    sensitivity moves by 1e-5 at most when they are dropped altogether). So the port model
    equals the exact one at the reference design and stays within those amounts elsewhere;
    :func:`servotune.tuning.verify.verify` checks the design on the exact model.

    Returns
    -------
    numpy.ndarray
        Complex, shape (models, len(CORRECTIONS), K).
    """
    drive = problem.drive_for(reference)
    axes = _reference_axes(problem, reference)
    out = np.zeros((len(problem.regimes), len(CORRECTIONS), omega.size), dtype=complex)
    numeric = _NumericPorts(PortData(omega, pairs, alpha, lam, len(problem.pads),
                                     {k: v for k, v in parts.items()}, zfix, None, True))
    plant = {k: v.value() for k, v in _plant_parts(
        problem, numeric, reference.c if problem.pads else 0.0).items()}
    below = omega < math.pi / drive.sampling.position_period * (1.0 - 1e-9)
    for m, sa in enumerate(axes):
        g = sa.zoh_response(omega)
        h0 = parts["h0"]
        out[m, 0] = g[0] - h0 * plant["i_u"][m]
        out[m, 1] = g[1] - h0 * plant["phi_u"][m]
        out[m, 2] = g[2] - h0 * plant["x_u"][m]
        if sa.n_v > 1:
            cur = sa._current(omega)
            vel = sa._velocity(omega)
            out[m, 3] = vel.g_vphi - parts["hold_v"] * cur.phi_t
            out[m, 4] = vel.g_vx - parts["hold_v"] * cur.x_t
        if below.any():
            pos, vel = sa._position(omega[below], with_velocity=True)
            out[m, 5, below] = pos.g_px - parts["hold_p"][below] * vel.x_omega
    return out


def _port_vectors(problem: TuningProblem) -> tuple[list[str], dict]:
    """The structure DOFs at the ports and the port vectors wp, e (torque), f (feedback)."""
    drive = problem.drive
    dofs = [problem.force, *problem.pads]
    if drive is not None:
        m = drive.motor
        dofs += [m.rotor] + ([m.stator] if m.stator else [])
        if drive.feedback == "linear":
            dofs.append(drive.encoder)
    dofs = list(dict.fromkeys(dofs))
    idx = {d: i for i, d in enumerate(dofs)}
    vec = {}
    wp = np.zeros(len(dofs))
    wp[idx[problem.force]] = 1.0
    vec["wp"] = wp
    if drive is not None:
        e = np.zeros(len(dofs))
        e[idx[drive.motor.rotor]] = 1.0
        if drive.motor.stator:
            e[idx[drive.motor.stator]] = -1.0
        vec["e"] = e
        if drive.feedback == "linear":
            f = np.zeros(len(dofs))
            f[idx[drive.encoder]] = 1.0
        else:
            f = drive.ratio * e
        vec["f"] = f
    return dofs, vec


@dataclass(frozen=True)
class PortData:
    """Port receptances of the structure on a frequency grid, prepared for the contact
    coupling, with the fixed parts of the drive and the contact impedance of every model.

    ``rows(extra)`` lays them out as real rows with one column per (frequency, model): model
    m's columns are ``m K ... (m + 1) K - 1``; ``extra`` (one row of constants per model)
    carries per-model parameters of the constraints.
    """

    omega: np.ndarray
    pairs: dict       # (a, b) -> R_ab (K,) complex
    alpha: dict       # (a, b) -> (K, n_pads) complex
    lam: np.ndarray   # (K, n_pads)
    n_pads: int
    drive: dict | None     # DRIVE_PARTS or SAMPLED_PARTS -> (K,) complex
    zfix: np.ndarray  # (M, K) complex, contact impedance without C (axis total)
    corrections: np.ndarray | None = None  # (M, len(CORRECTIONS), K) complex (sampled drive)
    sampled: bool = False

    @property
    def n_models(self) -> int:
        return self.zfix.shape[0]

    def common_rows(self) -> np.ndarray:
        out = [self.omega]
        for key, value in self.pairs.items():
            out += [value.real, value.imag]
            for i in range(self.n_pads):
                out += [self.alpha[key][:, i].real, self.alpha[key][:, i].imag]
        for i in range(self.n_pads):
            out += [self.lam[:, i].real, self.lam[:, i].imag]
        if self.drive is not None:
            for name in (SAMPLED_PARTS if self.sampled else DRIVE_PARTS):
                out += [self.drive[name].real, self.drive[name].imag]
        return np.array(out)

    def rows(self, extra: np.ndarray | None = None, models=None) -> np.ndarray:
        """All data as real rows (n_rows, K M), in the order :class:`SymbolicPorts` reads;
        ``models`` selects the models (default all)."""
        common = self.common_rows()
        k = self.omega.size
        blocks = []
        for m in (range(self.n_models) if models is None else models):
            block = [common, self.zfix[m].real[None], self.zfix[m].imag[None]]
            if self.sampled:
                block += [self.corrections[m].real, self.corrections[m].imag]
            if extra is not None and extra.shape[1]:
                block.append(np.repeat(extra[m][:, None], k, axis=1))
            blocks.append(np.vstack(block))
        return np.hstack(blocks)


class SymbolicPorts:
    """The data of ONE (frequency, model) column as symbols, so the responses become a casadi
    function of (design, data) that is mapped over the grid and the models."""

    def __init__(self, problem: TuningProblem, symbol, n_extra: int = 0):
        _, vec = _port_vectors(problem)
        self.n_pads = len(problem.pads)
        rows = iter(range(symbol.shape[0]))

        def cx():
            return _Cx(symbol[next(rows)], symbol[next(rows)])

        self.omega = symbol[next(rows)]
        self.pairs, self.modes = {}, {}
        for a in vec:
            for b in vec:
                self.pairs[(a, b)] = cx()
                self.modes[(a, b)] = [cx() for _ in range(self.n_pads)]
        self.lam = [cx() for _ in range(self.n_pads)]
        self.drive = None
        self.sampled = is_sampled(problem)
        if problem.drive is not None:
            self.drive = {name: cx() for name in (SAMPLED_PARTS if self.sampled
                                                  else DRIVE_PARTS)}
        self.zfix = cx()
        self.corrections = None
        if self.sampled:
            re = [symbol[next(rows)] for _ in CORRECTIONS]
            im = [symbol[next(rows)] for _ in CORRECTIONS]
            self.corrections = {k: _Cx(a, b) for k, a, b in zip(CORRECTIONS, re, im,
                                                                 strict=True)}
        self.extra = [symbol[next(rows)] for _ in range(n_extra)]
        if next(rows, None) is not None:
            raise ValueError("port data rows do not match the problem")

    @staticmethod
    def size(problem: TuningProblem, n_extra: int = 0) -> int:
        _, vec = _port_vectors(problem)
        n = 1 + len(vec) ** 2 * 2 * (1 + len(problem.pads)) + 2 * len(problem.pads)
        if problem.drive is not None:
            n += 2 * (len(SAMPLED_PARTS) + len(CORRECTIONS) if is_sampled(problem)
                      else len(DRIVE_PARTS))
        return n + 2 + n_extra

    def pair(self, a: str, b: str) -> _Cx:
        return self.pairs[(a, b)]

    def mode(self, a: str, b: str, i: int) -> tuple[_Cx, _Cx]:
        return self.modes[(a, b)][i], self.lam[i]


class _NumericPorts:
    """The same interface over numeric :class:`PortData` for all models at once (arrays of
    shape (M, K))."""

    def __init__(self, data: PortData):
        m = data.n_models
        self.n_pads = data.n_pads

        def tile(z):
            return _Cx.of(np.broadcast_to(z, (m, z.shape[-1])))

        self.omega = np.broadcast_to(data.omega, (m, data.omega.size))
        self._data = data
        self.zfix = _Cx.of(data.zfix)
        self.drive = None if data.drive is None else {k: tile(v) for k, v in data.drive.items()}
        self.sampled = data.sampled
        self.corrections = None
        if data.sampled and data.corrections is not None:
            self.corrections = {k: _Cx.of(data.corrections[:, i])
                                for i, k in enumerate(CORRECTIONS)}
        self._tile = tile

    def pair(self, a: str, b: str) -> _Cx:
        return self._tile(self._data.pairs[(a, b)])

    def mode(self, a: str, b: str, i: int) -> tuple[_Cx, _Cx]:
        return (self._tile(self._data.alpha[(a, b)][:, i]),
                self._tile(self._data.lam[:, i]))


def port_data(problem: TuningProblem, omega: np.ndarray,
              reference: Design | None = None) -> PortData:
    """The port data of a problem on a grid (see :class:`PortData`); with a digital drive the
    corrections are exact at ``reference`` (default the initial design)."""
    omega = np.asarray(omega, dtype=float)
    dofs, vec = _port_vectors(problem)
    rec = frequency.modal_receptance(problem.structure, omega, dofs, dofs)  # (p, p, K)
    rec = np.moveaxis(rec, -1, 0)  # (K, p, p)
    n_p = len(problem.pads)
    pad_idx = [dofs.index(p) for p in problem.pads]
    names = list(vec)
    pairs, alpha = {}, {}
    if n_p:
        r_pp = rec[:, pad_idx][:, :, pad_idx]
        lam, u = np.linalg.eig(r_pp)
        u_inv = np.linalg.inv(u)
    else:
        lam = np.zeros((omega.size, 0))
    rec_b = {b: rec @ vec[b] for b in names}  # (K, p)
    for a in names:
        for b in names:
            pairs[(a, b)] = rec_b[b] @ vec[a]
            if n_p:
                left = np.einsum("kp,kpq->kq", (vec[a] @ rec)[:, pad_idx], u)
                right = np.einsum("kqp,kp->kq", u_inv, rec_b[b][:, pad_idx])
                alpha[(a, b)] = left * right
    drive = None
    zfix = np.array([m.impedance(omega) for m in problem.regimes], dtype=complex)
    if is_sampled(problem):
        drive = {k: np.broadcast_to(v, omega.shape).astype(complex)
                 for k, v in sampled_parts(problem.drive, omega).items()}
        ref = problem.initial_design() if reference is None else reference
        corr = sampled_corrections(problem, omega, ref, pairs, alpha, lam, zfix, drive)
        return PortData(omega, pairs, alpha, lam, n_p, drive, zfix, corr, True)
    if problem.drive is not None:
        parts = cascade_response(problem.drive, 1j * omega)
        drive = {"forward": parts.current_forward * parts.setpoint, "winding": parts.winding}
        drive = {k: np.broadcast_to(v, omega.shape).astype(complex) for k, v in drive.items()}
    return PortData(omega, pairs, alpha, lam, n_p, drive, zfix)


def responses(problem: TuningProblem, data, design) -> dict:
    """Compliance and loop transfer functions as :class:`_Cx`, for numeric or symbolic design
    values (a mapping with keys c, kv, kp, ti) and numeric (:class:`_NumericPorts`) or symbolic
    (:class:`SymbolicPorts`) data.

    Keys: ``compliance`` (x/F at the work piece), ``loop_velocity`` (L_v with the position loop
    open), ``loop_position`` (L_p with the velocity loop closed).
    """
    s = _Cx(0.0 * data.omega, data.omega)
    weights = []  # z / (1 + z lambda_i), shared by every port pair
    if data.n_pads:
        z = (data.zfix + s * design["c"]) / data.n_pads
        weights = [z / (1.0 + z * data.mode("wp", "wp", i)[1]) for i in range(data.n_pads)]

    def rc(a, b):
        out = data.pair(a, b)
        for i, w in enumerate(weights):
            out = out - w * data.mode(a, b, i)[0]
        return out

    h_ww = rc("wp", "wp")
    out = {"compliance": h_ww}
    drive = problem.drive
    if drive is None:
        return out
    if data.sampled:
        return _sampled_responses(problem, data, design, s, rc)
    m = drive.motor
    parts = data.drive
    cv = design["kp"] * (1.0 + 1.0 / (s * design["ti"]))
    den = parts["winding"]
    a = parts["forward"] * cv
    filters = _filters(problem, design, data.omega)
    if filters is not None:
        a = a * filters
    b = m.torque_constant * m.back_emf_constant
    p_phi = rc("e", "e")
    p_fb = rc("f", "e")
    k_pos = design["kv"] / drive.ratio
    out["loop_velocity"] = a * s * p_phi / (den + b * s * p_phi)
    out["loop_position"] = k_pos * a * p_fb / (den + (a + b) * s * p_phi)
    torque = -(a * k_pos * rc("f", "wp") + (a + b) * s * rc("e", "wp")) / (
        den + a * k_pos * p_fb + (a + b) * s * p_phi)
    out["compliance"] = h_ww + rc("wp", "e") * torque
    return out


def _coupling(data, c):
    """The port coupling rc(a, b) of the contact with viscous C."""
    s = _Cx(0.0 * data.omega, data.omega)
    weights = []
    if data.n_pads:
        z = (data.zfix + s * c) / data.n_pads
        weights = [z / (1.0 + z * data.mode("wp", "wp", i)[1]) for i in range(data.n_pads)]

    def rc(a, b):
        out = data.pair(a, b)
        for i, w in enumerate(weights):
            out = out - w * data.mode(a, b, i)[0]
        return out

    return s, rc


def _plant_parts(problem: TuningProblem, data, c, s=None, rc=None) -> dict:
    """The continuous axis driven by its voltage, at the ports: current, angle and position
    per voltage (``i_u``, ``phi_u``, ``x_u``), their responses to the work-piece force with the
    voltage at zero (``i_f``, ``phi_f``, ``x_f``), and the work-piece displacement per force
    and per voltage (``y_f``, ``y_u``). With the winding ``W = s L + R + kt ke s P_phi``::

        i = (u - ke s R_c[e, wp] F) / W,   phi = kt P_phi i + R_c[e, wp] F, ...
    """
    if rc is None:
        s, rc = _coupling(data, c)
    m = problem.drive.motor
    kt, ke = m.torque_constant, m.back_emf_constant
    b = kt * ke
    p_phi, p_fb = rc("e", "e"), rc("f", "e")
    p_ew, p_fw, p_we = rc("e", "wp"), rc("f", "wp"), rc("wp", "e")
    w = s * m.inductance + m.resistance + b * s * p_phi
    out = {"i_u": 1.0 / w, "phi_u": kt * p_phi / w, "x_u": kt * p_fb / w,
           "i_f": -ke * s * p_ew / w, "phi_f": p_ew * (s * m.inductance + m.resistance) / w,
           "x_f": p_fw - b * s * p_fb * p_ew / w, "y_f": rc("wp", "wp") - b * s * p_we * p_ew / w,
           "y_u": kt * p_we / w}
    return out


def _sampled_responses(problem: TuningProblem, data, design, s, rc) -> dict:
    """The sampled-data responses (:mod:`servotune.digital.cascade`) from the port model, the
    digital drive's parts and the per-model corrections."""
    plant = _plant_parts(problem, data, None, s, rc)
    parts, corr = data.drive, data.corrections
    h0 = parts["h0"]
    k_ct = parts["k_ct"]
    filters = _filters(problem, design, data.omega, parts["half"],
                       problem.drive.sampling.current_period)
    if filters is not None:
        k_ct = k_ct * filters
    cur = cascade.current_level(h0 * plant["i_u"] + corr["a_i"],
                                h0 * plant["phi_u"] + corr["a_phi"],
                                h0 * plant["x_u"] + corr["a_x"], parts["k_ci"], k_ct)
    cv = design["kp"] * (1.0 + parts["qv"] / design["ti"])
    k_vphi = -(parts["dv_m"] * cv)
    k_vomega = parts["dv"] * cv
    vel = cascade.velocity_level(parts["hold_v"] * cur.phi_t + corr["d_vphi"],
                                 parts["hold_v"] * cur.x_t + corr["d_vx"], k_vphi, k_vomega)
    k_px = -(parts["dp"] * (design["kv"] / problem.drive.ratio))
    pos = cascade.position_level(parts["hold_p"] * vel.x_omega + corr["d_px"], k_px)
    h = cascade.fundamental(cur, vel, pos, k_ci=parts["k_ci"], k_vphi=k_vphi,
                            k_vomega=k_vomega, k_px=k_px, i_f=plant["i_f"],
                            phi_f=plant["phi_f"], x_f=plant["x_f"], y_f=plant["y_f"],
                            y_u=plant["y_u"], h0=h0, hold_v=parts["hold_v"],
                            hold_p=parts["hold_p"])
    return {"compliance": h, "loop_velocity": vel.l_v, "loop_position": pos.l_p}


def grid(lo: float, hi: float, n: int) -> np.ndarray:
    """A log-spaced grid [rad/s]."""
    return np.geomspace(lo, hi, n)


class ResponseModel:
    """The port-coupled responses of a problem on a fixed frequency grid, for many designs.

    The structure's port receptances, their pad eigen-decompositions and the contact impedances
    of the models are computed once; each call then costs a few vectorised complex operations.
    Results have one row per regime model of the problem (``problem.regimes``). With a digital
    drive the sampled-data model's corrections (:func:`sampled_corrections`) are made exact at
    each design called with (``exact=True``, the default) or kept from ``reference``.

    Parameters
    ----------
    problem : TuningProblem
        Structure, pads, drive and regime models.
    omega : array_like
        Angular frequencies [rad/s] of the grid.
    reference : Design, optional
        The design at which a digital drive's corrections are exact (default the initial one).

    Examples
    --------
    The paper's Fig 5 system at Copt: the peak is g(alpha)/K at the fixed point (Eq 7).

    >>> import numpy as np
    >>> from servotune.structure import ModalModel
    >>> s = ModalModel([[5000.0, 0], [0, 1500.0]], [[16e6, -16e6], [-16e6, 16e6]],
    ...                ["pad1.x", "wp.x"], damping_ratio=0.0)
    >>> model = ResponseModel(TuningProblem(s, ["pad1.x"], c=4.912e5), [111.81])
    >>> round(float(abs(model(Design(c=4.912e5))["compliance"][0, 0])) * 16e6, 3)
    5.813
    """

    def __init__(self, problem: TuningProblem, omega, reference: Design | None = None):
        self.problem = problem
        self.reference = problem.initial_design() if reference is None else reference
        self.data = port_data(problem, np.asarray(omega, dtype=float), self.reference)
        self._numeric = _NumericPorts(self.data)

    @property
    def omega(self) -> np.ndarray:
        return self.data.omega

    def at(self, design: Design) -> ResponseModel:
        """Return the model with a digital drive's corrections exact at ``design``.

        Parameters
        ----------
        design : Design
            The design.

        Returns
        -------
        ResponseModel
            Itself when the corrections already are (or the drive is continuous), else a copy
            with them recomputed.
        """
        if not self.data.sampled or design == self.reference:
            return self
        out = object.__new__(ResponseModel)
        d = self.data
        corr = sampled_corrections(self.problem, d.omega, design, d.pairs, d.alpha, d.lam,
                                   d.zfix, d.drive)
        out.problem, out.reference = self.problem, design
        out.data = PortData(d.omega, d.pairs, d.alpha, d.lam, d.n_pads, d.drive, d.zfix, corr,
                            True)
        out._numeric = _NumericPorts(out.data)
        return out

    def __call__(self, design: Design, exact: bool = True) -> dict:
        """``{"omega", "compliance", "loop_velocity", "loop_position"}``; the responses as
        complex arrays of shape (models, frequencies). ``exact``: a digital drive's
        corrections at ``design`` (else at the reference)."""
        model = self.at(design) if exact else self
        res = responses(self.problem, model._numeric, design.to_dict())
        return {"omega": self.data.omega, **{k: v.value() for k, v in res.items()}}


def evaluate(problem: TuningProblem, design: Design, omega=None) -> dict:
    """Return the port-coupled responses of a design on a frequency grid (numpy).

    Parameters
    ----------
    problem : TuningProblem
        Structure, pads, drive, regime models and requirements.
    design : Design
        The design values (C, and Kv, Kp, Ti with a drive).
    omega : array_like, optional
        Angular frequencies [rad/s]; default the union of 2000 log-spaced points over
        ``problem.requirements.band`` and 2000 over ``problem.requirements.loop_band``.

    Returns
    -------
    dict
        ``omega`` [rad/s] and the complex responses of shape (models, frequencies):
        ``compliance`` (work-piece x/F [m/N]) and, with a drive, ``loop_velocity`` (the
        velocity loop's transfer with the position loop open) and ``loop_position`` (the
        position loop's with the velocity loop closed); a digital drive's as the sampled-data
        system (each loop at its controller's rate; the position loop 0 above its Nyquist
        frequency).
    """
    req = problem.requirements
    if omega is None:
        omega = np.unique(np.concatenate([grid(*req.band, 2000), grid(*req.loop_band, 2000)]))
    return ResponseModel(problem, omega, design)(design)
