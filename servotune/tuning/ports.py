"""Frequency responses at the ports of the structure, in real arithmetic for casadi.

The structure's receptance between its ports (work piece, pads, motor, encoder) comes from the
modal sum once per frequency grid; viscous pads couple in closed form through the eigen-
decomposition of the pad block, and the drive closes around scalar port receptances (see the
package docstring for the equations). Each complex quantity is a (real, imaginary) pair of numpy
arrays or casadi expressions, so the same code evaluates numerically and builds the NLP.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import frequency
from .problem import Design, TuningProblem

__all__ = ["ResponseModel", "evaluate"]

class _Cx:
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


@dataclass(frozen=True)
class _PortData:
    """Structure receptances at the ports on a frequency grid, prepared for C coupling, with
    the fixed parts of the drive (current PI, set-point filters) at the same frequencies."""

    omega: np.ndarray
    pairs: dict  # (a, b) -> R_ab (K,) complex
    alpha: dict  # (a, b) -> (K, n_pads) complex
    lam: np.ndarray  # (K, n_pads)
    n_pads: int
    current: np.ndarray | None = None  # current PI C_i(jw) (K,) complex
    filt: np.ndarray | None = None  # set-point filters F(jw) (K,) complex

    def pair(self, a: str, b: str) -> _Cx:
        return _Cx.of(self.pairs[(a, b)])

    def mode(self, a: str, b: str, i: int) -> tuple[_Cx, _Cx]:
        """(alpha_i, lambda_i) of pad eigen-direction i."""
        return _Cx.of(self.alpha[(a, b)][:, i]), _Cx.of(self.lam[:, i])

    def drive_parts(self) -> tuple[_Cx, _Cx]:
        return _Cx.of(self.current), _Cx.of(self.filt)

    def rows(self) -> np.ndarray:
        """All data as real rows (n_rows, K), in the order :class:`_SymbolicPorts` reads."""
        out = [self.omega]
        for key, value in self.pairs.items():
            out += [value.real, value.imag]
            for i in range(self.n_pads):
                out += [self.alpha[key][:, i].real, self.alpha[key][:, i].imag]
        for i in range(self.n_pads):
            out += [self.lam[:, i].real, self.lam[:, i].imag]
        if self.current is not None:
            out += [self.current.real, self.current.imag, self.filt.real, self.filt.imag]
        return np.array(out)


class _SymbolicPorts:
    """The port data of ONE frequency as symbols (a column of :meth:`_PortData.rows`), so the
    responses become a casadi function of (design, data) that is mapped over the grid."""

    def __init__(self, problem: TuningProblem, symbol):
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
        self.current = self.filt = None
        if problem.drive is not None:
            self.current, self.filt = cx(), cx()
        if next(rows, None) is not None:
            raise ValueError("port data rows do not match the problem")

    @staticmethod
    def size(problem: TuningProblem) -> int:
        _, vec = _port_vectors(problem)
        n = 1 + len(vec) ** 2 * 2 * (1 + len(problem.pads)) + 2 * len(problem.pads)
        return n + (4 if problem.drive is not None else 0)

    def pair(self, a: str, b: str) -> _Cx:
        return self.pairs[(a, b)]

    def mode(self, a: str, b: str, i: int) -> tuple[_Cx, _Cx]:
        return self.modes[(a, b)][i], self.lam[i]

    def drive_parts(self) -> tuple[_Cx, _Cx]:
        return self.current, self.filt


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


def _port_data(problem: TuningProblem, omega: np.ndarray) -> _PortData:
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
    current = filt = None
    if problem.drive is not None:
        drive = problem.drive
        current = np.asarray(drive.current_loop.transfer_function()(1j * omega)).reshape(-1)
        filt = np.asarray(drive.torque_filter()(1j * omega)).reshape(-1)
        current = np.broadcast_to(current, omega.shape).astype(complex)
        filt = np.broadcast_to(filt, omega.shape).astype(complex)
    return _PortData(omega, pairs, alpha, lam, n_p, current, filt)


def _responses(problem: TuningProblem, data, design) -> dict:
    """Compliance, loop transfer functions as _Cx over the grid, for numeric or symbolic
    design values (a mapping with keys c, kv, kp, ti) and numeric (:class:`_PortData`) or
    symbolic (:class:`_SymbolicPorts`) port data."""
    s = _Cx(0.0 * data.omega, data.omega)
    weights = []  # z / (1 + z lambda_i), shared by every port pair
    if data.n_pads:
        z = (problem.contact_stiffness + s * design["c"]) / data.n_pads
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
    ci, filt = data.drive_parts()
    cv = design["kp"] * (1.0 + 1.0 / (s * design["ti"]))
    den = s * m.inductance + m.resistance + ci
    a = ci * filt * cv
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


# --------------------------------------------------------------------------------------------


def _grid(lo: float, hi: float, n: int) -> np.ndarray:
    return np.geomspace(lo, hi, n)


class ResponseModel:
    """The port-coupled responses of a problem on a fixed frequency grid, for many designs.

    The structure's port receptances and their pad eigen-decompositions are computed once;
    each call then costs a few vectorised complex operations.

    Examples
    --------
    >>> import numpy as np
    >>> from servotune.structure import ModalModel
    >>> s = ModalModel([[5000.0, 0], [0, 1500.0]], [[16e6, -16e6], [-16e6, 16e6]],
    ...                ["pad1.x", "wp.x"], damping_ratio=0.0)
    >>> model = ResponseModel(TuningProblem(s, ["pad1.x"], c=4.912e5), [111.81])
    >>> round(float(abs(model(Design(c=4.912e5))["compliance"][0])) * 16e6, 3)  # g(0.3), Eq 7
    5.813
    """

    def __init__(self, problem: TuningProblem, omega):
        self.problem = problem
        self.data = _port_data(problem, np.asarray(omega, dtype=float))

    @property
    def omega(self) -> np.ndarray:
        return self.data.omega

    def __call__(self, design: Design) -> dict:
        """``{"omega", "compliance", "loop_velocity", "loop_position"}`` as complex arrays."""
        res = _responses(self.problem, self.data, design.to_dict())
        return {"omega": self.data.omega, **{k: v.value() for k, v in res.items()}}


def evaluate(problem: TuningProblem, design: Design, omega=None) -> dict:
    """The port-coupled responses of a design on a grid (numpy), as complex arrays."""
    req = problem.requirements
    if omega is None:
        omega = np.unique(np.concatenate([_grid(*req.band, 2000), _grid(*req.loop_band, 2000)]))
    return ResponseModel(problem, omega)(design)
