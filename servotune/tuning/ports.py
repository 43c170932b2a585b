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

from dataclasses import dataclass

import numpy as np

from .. import frequency
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


DRIVE_PARTS = ("forward", "winding", "measurement", "position")


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
    drive: dict | None     # DRIVE_PARTS -> (K,) complex
    zfix: np.ndarray  # (M, K) complex, contact impedance without C (axis total)

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
            for name in DRIVE_PARTS:
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
        if problem.drive is not None:
            self.drive = {name: cx() for name in DRIVE_PARTS}
        self.zfix = cx()
        self.extra = [symbol[next(rows)] for _ in range(n_extra)]
        if next(rows, None) is not None:
            raise ValueError("port data rows do not match the problem")

    @staticmethod
    def size(problem: TuningProblem, n_extra: int = 0) -> int:
        _, vec = _port_vectors(problem)
        n = 1 + len(vec) ** 2 * 2 * (1 + len(problem.pads)) + 2 * len(problem.pads)
        return n + (2 * len(DRIVE_PARTS) if problem.drive is not None else 0) + 2 + n_extra

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
        self._tile = tile

    def pair(self, a: str, b: str) -> _Cx:
        return self._tile(self._data.pairs[(a, b)])

    def mode(self, a: str, b: str, i: int) -> tuple[_Cx, _Cx]:
        return (self._tile(self._data.alpha[(a, b)][:, i]),
                self._tile(self._data.lam[:, i]))


def port_data(problem: TuningProblem, omega: np.ndarray, exact_delays: bool = True) -> PortData:
    """The port data of a problem on a grid (see :class:`PortData`)."""
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
    if problem.drive is not None:
        parts = cascade_response(problem.drive, 1j * omega, exact_delays=exact_delays)
        drive = {"forward": parts.current_forward * parts.setpoint, "winding": parts.winding,
                 "measurement": parts.speed_measurement, "position": parts.position_delay}
        drive = {k: np.broadcast_to(v, omega.shape).astype(complex) for k, v in drive.items()}
    zfix = np.array([m.impedance(omega) for m in problem.regimes], dtype=complex)
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
    m = drive.motor
    parts = data.drive
    cv = design["kp"] * (1.0 + 1.0 / (s * design["ti"]))
    den = parts["winding"]
    a = parts["forward"] * cv
    a_v = a * parts["measurement"]
    b = m.torque_constant * m.back_emf_constant
    p_phi = rc("e", "e")
    p_fb = rc("f", "e")
    k_pos = parts["position"] * (design["kv"] / drive.ratio)
    out["loop_velocity"] = a_v * s * p_phi / (den + b * s * p_phi)
    out["loop_position"] = k_pos * a * p_fb / (den + (a_v + b) * s * p_phi)
    torque = -(a * k_pos * rc("f", "wp") + (a_v + b) * s * rc("e", "wp")) / (
        den + a * k_pos * p_fb + (a_v + b) * s * p_phi)
    out["compliance"] = h_ww + rc("wp", "e") * torque
    return out


def grid(lo: float, hi: float, n: int) -> np.ndarray:
    """A log-spaced grid [rad/s]."""
    return np.geomspace(lo, hi, n)


class ResponseModel:
    """The port-coupled responses of a problem on a fixed frequency grid, for many designs.

    The structure's port receptances, their pad eigen-decompositions and the contact impedances
    of the models are computed once; each call then costs a few vectorised complex operations.
    Results have one row per regime model of the problem (``problem.regimes``).

    Parameters
    ----------
    problem : TuningProblem
        Structure, pads, drive and regime models.
    omega : array_like
        Angular frequencies [rad/s] of the grid.
    exact_delays : bool
        The digital drive's delays as exact exponentials (True) or their Pade
        approximations (see :func:`servotune.drive.cascade_response`).

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

    def __init__(self, problem: TuningProblem, omega, exact_delays: bool = True):
        self.problem = problem
        self.data = port_data(problem, np.asarray(omega, dtype=float), exact_delays)
        self._numeric = _NumericPorts(self.data)

    @property
    def omega(self) -> np.ndarray:
        return self.data.omega

    def __call__(self, design: Design) -> dict:
        """``{"omega", "compliance", "loop_velocity", "loop_position"}``; the responses as
        complex arrays of shape (models, frequencies)."""
        res = responses(self.problem, self._numeric, design.to_dict())
        return {"omega": self.data.omega, **{k: v.value() for k, v in res.items()}}


def evaluate(problem: TuningProblem, design: Design, omega=None,
             exact_delays: bool = True) -> dict:
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
    exact_delays : bool
        The digital drive's delays as exact exponentials (True) or their Pade
        approximations.

    Returns
    -------
    dict
        ``omega`` [rad/s] and the complex responses of shape (models, frequencies):
        ``compliance`` (work-piece x/F [m/N]) and, with a drive, ``loop_velocity`` (the
        velocity loop's transfer with the position loop open) and ``loop_position`` (the
        position loop's with the velocity loop closed).
    """
    req = problem.requirements
    if omega is None:
        omega = np.unique(np.concatenate([grid(*req.band, 2000), grid(*req.loop_band, 2000)]))
    return ResponseModel(problem, omega, exact_delays)(design)
