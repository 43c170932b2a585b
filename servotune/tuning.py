"""Tuning of guide-way damping and servo gains with casadi (the only casadi user).

The design variables are the guide-way damping C (axis total, shared by the pads), the position
gain Kv and the velocity PI (Kp, Ti); the user chooses which are free. Objectives are the peak
work-piece compliance over a band and the chatter margin; constraints are the sensitivity peaks
Ms of the velocity and position loops (gain and phase margins enter through the Ms disk:
Ms <= 1/(2 sin(PM/2)) guarantees PM, Ms <= GM/(GM - 1) guarantees GM), a minimum Kv, and bounds.

Frequency responses in real arithmetic
--------------------------------------
casadi has no complex numbers, and rebuilding the closed loop for every trial design would be
slow, so the responses are written at the *ports* of the structure (work piece, pads, motor,
encoder). With R(jw) the structure's receptance between the ports (modal sum, computed once),
viscous pads z = (k + j w C)/n couple in closed form,

    R_c = R - z R_:p (I + z R_pp)^-1 R_p:  =  R - z sum_i a_i b_i^T / (1 + z lambda_i),

with the eigen-decomposition R_pp = U diag(lambda) U^-1 done once per frequency. The drive then
closes around the scalar port receptances (torque port e = rotor - stator, feedback port f):

    P_phi = e^T R_c e,  P_fb = f^T R_c e,  a = C_i F C_v,  b = kt ke,  den = j w L + R + C_i
    L_v   = a j w P_phi / (den + b j w P_phi)                        (position loop open)
    L_p   = (Kv/r) a P_fb / (den + (a + b) j w P_phi)                (velocity loop closed)
    T/F   = -(a (Kv/r) R_c[f, wp] + (a + b) j w R_c[e, wp]) / (den + a (Kv/r) P_fb
            + (a + b) j w P_phi)
    x/F   = R_c[wp, wp] + R_c[wp, e] T/F

Each complex quantity is carried as a (real, imaginary) pair of casadi expressions vectorised
over the frequency grid, so IPOPT gets exact derivatives. Peak and Ms constraints are semi-
infinite; they are imposed on a grid that is refined by exchange: after each solve the true
extrema are located on a fine grid, refined by bounded scalar search and added to the grid,
until the grid and the true values agree.

After solving, :func:`verify` checks the design independently with python-control on the
interconnected state-space plant (closed-loop poles, margins, Ms on a dense grid the optimiser
never saw, compliance peak, chatter limit). A design that fails verification is returned with
``success = False`` and the reasons, never as a success.

References
----------
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 4.1 (optimal guide-way damping), sec 5.2.
J. A. E. Andersson et al., "CasADi: a software framework for nonlinear optimization and
optimal control", Math. Prog. Comp. 11 (2019) 1-36.
R. Hettich, K. O. Kortanek, "Semi-infinite programming: theory, methods, and applications",
SIAM Review 35 (1993) 380-429 (exchange methods).
K. J. Astrom, R. M. Murray, Feedback Systems, 2nd ed. (2021), sec 13.3 (Ms and margins).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import casadi as ca
import numpy as np

from . import frequency
from .drive import Drive, PIController
from .plant import Contact, UnstableLoopError, build_plant, loop_transfer
from .structure.model import ModalModel

__all__ = [
    "Requirements",
    "ChatterTarget",
    "Design",
    "TuningProblem",
    "Performance",
    "TuningResult",
    "RequirementsNotMetError",
    "ResponseModel",
    "evaluate",
    "verify",
    "tune",
]

VARIABLES = ("c", "kv", "kp", "ti")
HZ = 1.0 / (2.0 * math.pi)


class RequirementsNotMetError(ValueError):
    """The requirements cannot be met within the bounds (names the binding constraint)."""


@dataclass(frozen=True)
class Requirements:
    """Robustness and performance requirements (SI; margins at the edges in deg and dB).

    Parameters
    ----------
    ms_velocity_max, ms_position_max : float
        Largest allowed sensitivity peak of the velocity and the position loop (> 1).
    phase_margin_min_deg, gain_margin_min_db : float, optional
        Smallest allowed margins; enforced through the Ms disk (each tightens the Ms limit).
    kv_min : float
        Smallest allowed position gain Kv [1/s].
    band : (float, float)
        Frequency band [rad/s] of the compliance-peak objective.
    loop_band : (float, float)
        Frequency range [rad/s] on which the loop constraints are imposed.
    """

    ms_velocity_max: float = 2.0
    ms_position_max: float = 1.5
    phase_margin_min_deg: float | None = None
    gain_margin_min_db: float | None = None
    kv_min: float = 0.0
    band: tuple[float, float] = (2 * math.pi * 5.0, 2 * math.pi * 300.0)
    loop_band: tuple[float, float] = (2 * math.pi * 0.1, 2 * math.pi * 3000.0)

    def __post_init__(self) -> None:
        for name in ("ms_velocity_max", "ms_position_max"):
            value = float(getattr(self, name))
            if not value > 1.0 or not math.isfinite(value):
                raise ValueError(f"Requirements.{name} must be finite and > 1, got {value!r}")
        if self.phase_margin_min_deg is not None and not 0 < self.phase_margin_min_deg < 90:
            raise ValueError("Requirements.phase_margin_min_deg must lie in (0, 90) deg")
        if self.gain_margin_min_db is not None and not self.gain_margin_min_db > 0:
            raise ValueError("Requirements.gain_margin_min_db must be > 0 dB")
        if not self.kv_min >= 0:
            raise ValueError("Requirements.kv_min must be >= 0 1/s")
        for name in ("band", "loop_band"):
            lo, hi = (float(v) for v in getattr(self, name))
            if not 0 < lo < hi < math.inf:
                raise ValueError(f"Requirements.{name} must be (low, high) with 0 < low < high "
                                 f"rad/s, got {getattr(self, name)!r}")
            object.__setattr__(self, name, (lo, hi))

    def ms_limit(self, loop: str) -> float:
        """The Ms limit of a loop including what the margin requirements imply."""
        limit = self.ms_velocity_max if loop == "velocity" else self.ms_position_max
        if self.phase_margin_min_deg is not None:
            limit = min(limit, 1.0 / (2.0 * math.sin(math.radians(self.phase_margin_min_deg) / 2)))
        if self.gain_margin_min_db is not None:
            gm = 10.0 ** (self.gain_margin_min_db / 20.0)
            limit = min(limit, gm / (gm - 1.0))
        return limit


@dataclass(frozen=True)
class ChatterTarget:
    """Chatter-limit objective in the oriented one-direction zero-order form.

    With only the feed direction flexible, the oriented FRF is ``Phi = mu G`` (G the work-piece
    compliance, mu the directional factor of the milling set-up) and the limiting depth is
    ``b_lim = -1 / (2 Kt Re Phi)`` at the chatter frequency; the absolute limit is
    ``b_crit = -1 / (2 Kt min_w Re Phi)`` (Tlusty; Altintas and Budak 1995; see
    :mod:`servotune.chatter.zoa`).

    Parameters
    ----------
    kt : float
        Tangential cutting coefficient [N/m^2] (> 0).
    mu : float
        Directional factor mu = D_xx/Kt [-] (non-zero; may be negative).
    required_depth : float, optional
        Required axial depth [m]; the margin is b_crit / required_depth.

    Examples
    --------
    A single mode of stiffness k and damping zeta has min Re G = -1/(4 k zeta (1 + zeta)), so
    Tlusty's b_crit = 2 k zeta (1 + zeta) / (Kt mu):

    >>> k, zeta, target = 1e7, 0.02, ChatterTarget(kt=6e8, mu=0.5)
    >>> b = target.b_crit(target.mu * -1.0 / (4 * k * zeta * (1 + zeta)))
    >>> round(b / (2 * k * zeta * (1 + zeta) / (6e8 * 0.5)), 12)
    1.0
    """

    kt: float
    mu: float
    required_depth: float | None = None

    def __post_init__(self) -> None:
        if not (self.kt > 0 and math.isfinite(self.kt)):
            raise ValueError(f"ChatterTarget.kt must be finite and > 0 N/m^2, got {self.kt!r}")
        if not (math.isfinite(self.mu) and self.mu != 0):
            raise ValueError(f"ChatterTarget.mu must be finite and non-zero, got {self.mu!r}")
        if self.required_depth is not None and not self.required_depth > 0:
            raise ValueError("ChatterTarget.required_depth must be > 0 m")

    @classmethod
    def from_setup(cls, setup, direction: str = "x", required_depth: float | None = None):
        """From a :class:`~servotune.chatter.MillingSetup` (flexible direction ``x`` or ``y``)."""
        from .chatter import directional_factor

        return cls(setup.kt, directional_factor(setup, direction), required_depth)

    def b_crit(self, min_real: float) -> float:
        """b_crit [m] from the most negative real part of the ORIENTED FRF mu G [m/N]."""
        return math.inf if min_real >= 0 else -1.0 / (2.0 * self.kt * min_real)

    def margin(self, b_crit: float) -> float | None:
        """b_crit over the required depth (None without a requirement)."""
        return None if self.required_depth is None else b_crit / self.required_depth


@dataclass(frozen=True)
class Design:
    """Values of the design variables (SI): C [N s/m] (axis total), Kv [1/s], Kp [N m s/rad],
    Ti [s]. Variables without a drive may be None."""

    c: float
    kv: float | None = None
    kp: float | None = None
    ti: float | None = None

    def to_dict(self) -> dict:
        return {"c": self.c, "kv": self.kv, "kp": self.kp, "ti": self.ti}


@dataclass(frozen=True)
class TuningProblem:
    """A tuning problem on a structure with viscous guide-way pads and, optionally, a drive.

    Parameters
    ----------
    structure : ModalModel
    pads : sequence of str
        Pad DOFs where the guide-way damping C acts (shared equally).
    c : float
        Initial guide-way damping C [N s/m] (axis total).
    drive : Drive, optional
        Initial drive (its Kv, velocity Kp and Ti are the initial gains).
    free : sequence of str
        Which of ``("c", "kv", "kp", "ti")`` the optimiser may change.
    bounds : dict, optional
        ``{name: (low, high)}`` in SI; defaults: a factor 100 either way of the initial value.
    requirements : Requirements
    chatter : ChatterTarget, optional
    weights : (float, float)
        Weights of (compliance peak / initial peak, initial b_crit / b_crit) in the objective.
    tracking_weight : float
        Weight of Kv0/Kv in the objective when Kv is free: the compliance barely depends on
        Kv, so without it Kv would be left anywhere the constraints allow; with it Kv goes as
        high as the position-loop Ms allows (tracking accuracy grows with Kv).
    contact_stiffness : float
        Fixed total contact stiffness at the pads [N/m] (0 for purely viscous pads).
    force : str
        Work-piece DOF where the cutting force acts and the compliance is taken.
    n_grid : int
        Initial number of grid frequencies (the exchange refinement adds more).
    """

    structure: ModalModel
    pads: tuple[str, ...]
    c: float
    drive: Drive | None = None
    free: tuple[str, ...] = ("c",)
    bounds: dict = field(default_factory=dict)
    requirements: Requirements = field(default_factory=Requirements)
    chatter: ChatterTarget | None = None
    weights: tuple[float, float] = (1.0, 0.0)
    tracking_weight: float = 0.05
    contact_stiffness: float = 0.0
    force: str = "wp.x"
    n_grid: int = 60

    def __post_init__(self) -> None:
        pads = tuple(self.pads)
        self.structure.index(list(pads) + [self.force])
        object.__setattr__(self, "pads", pads)
        free = tuple(dict.fromkeys(self.free))
        unknown = [v for v in free if v not in VARIABLES]
        if unknown:
            raise ValueError(f"unknown design variables {unknown}; choose from {VARIABLES}")
        if self.drive is None and set(free) - {"c"}:
            raise ValueError(f"free variables {sorted(set(free) - {'c'})} need a drive")
        if "c" in free and not pads:
            raise ValueError("tuning C needs the pad DOFs (pads=...)")
        if not free:
            raise ValueError("no free design variables")
        object.__setattr__(self, "free", free)
        if not (self.c >= 0 and math.isfinite(self.c)):
            raise ValueError(f"the initial damping c must be finite and >= 0, got {self.c!r}")
        if "c" in free and self.c <= 0:
            raise ValueError("a free damping C needs a positive initial value")
        w_peak, w_chatter = (float(w) for w in self.weights)
        if w_peak < 0 or w_chatter < 0 or w_peak + w_chatter == 0:
            raise ValueError("weights must be >= 0 and not both zero")
        if not (self.tracking_weight >= 0 and math.isfinite(self.tracking_weight)):
            raise ValueError("tracking_weight must be finite and >= 0")
        if w_chatter > 0 and self.chatter is None:
            raise ValueError("a chatter weight needs a ChatterTarget (chatter=...)")
        design = self.initial_design()
        checked = {}
        for name in VARIABLES:
            value = getattr(design, name)
            lo, hi = self.bounds.get(name, (value / 100.0, value * 100.0) if value else (0, 0))
            if name in free and not (0 < lo <= value <= hi < math.inf):
                raise ValueError(f"bounds of {name} must satisfy 0 < low <= initial <= high, got "
                                 f"({lo!r}, {hi!r}) with initial {value!r}")
            checked[name] = (float(lo), float(hi))
        object.__setattr__(self, "bounds", checked)

    def initial_design(self) -> Design:
        d = self.drive
        if d is None:
            return Design(c=float(self.c))
        return Design(c=float(self.c), kv=d.kv, kp=d.velocity_loop.kp, ti=d.velocity_loop.ti)

    def drive_for(self, design: Design) -> Drive | None:
        """The drive with a design's gains."""
        if self.drive is None:
            return None
        return replace(self.drive, kv=design.kv,
                       velocity_loop=PIController(kp=design.kp, ti=design.ti))


# --------------------------------------------------------------------------------------------
# complex arithmetic on (re, im) pairs of numpy arrays or casadi expressions
class _Cx:
    __slots__ = ("re", "im")

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
    """Structure receptances at the ports on a frequency grid, prepared for C coupling."""

    omega: np.ndarray
    pairs: dict  # (a, b) -> R_ab (K,) complex
    alpha: dict  # (a, b) -> (K, n_pads) complex
    lam: np.ndarray  # (K, n_pads)
    n_pads: int


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
    return _PortData(omega, pairs, alpha, lam, n_p)


def _responses(problem: TuningProblem, data: _PortData, design) -> dict:
    """Compliance, loop transfer functions as _Cx over the grid, for numeric or symbolic
    design values (a mapping with keys c, kv, kp, ti)."""
    s = _Cx(np.zeros_like(data.omega), data.omega)
    z = None
    if data.n_pads:
        z = (problem.contact_stiffness + s * design["c"]) / data.n_pads

    def rc(a, b):
        out = _Cx.of(data.pairs[(a, b)])
        if z is not None:
            for i in range(data.n_pads):
                out = out - z * _Cx.of(data.alpha[(a, b)][:, i]) / (
                    1.0 + z * _Cx.of(data.lam[:, i]))
        return out

    h_ww = rc("wp", "wp")
    out = {"compliance": h_ww}
    drive = problem.drive
    if drive is None:
        return out
    m = drive.motor
    ci = _Cx.of(np.asarray(drive.current_loop.transfer_function()(1j * data.omega)))
    filt = _Cx.of(np.asarray(drive.torque_filter()(1j * data.omega)).reshape(-1))
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
@dataclass(frozen=True)
class Performance:
    """What a design achieves (SI): compliance peak [m/N] at [rad/s], b_crit [m], the Ms and
    margins of both loops (None without a drive)."""

    peak_compliance: float
    peak_frequency: float
    b_crit: float | None = None
    min_real: float | None = None
    velocity: frequency.LoopAnalysis | None = None
    position: frequency.LoopAnalysis | None = None
    stable: bool = True

    def to_dict(self) -> dict:
        return {
            "peak_compliance": self.peak_compliance,
            "peak_frequency_hz": self.peak_frequency * HZ,
            "b_crit_m": self.b_crit,
            "stable": self.stable,
            "velocity_loop": self.velocity.to_dict() if self.velocity else None,
            "position_loop": self.position.to_dict() if self.position else None,
        }


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


def verify(problem: TuningProblem, design: Design) -> Performance:
    """Performance of a design from the interconnected python-control plant, on dense grids
    that the optimiser never uses.

    Raises
    ------
    UnstableLoopError
        If the closed loop is unstable.
    """
    req = problem.requirements
    drive = problem.drive_for(design)
    contact = _contact(problem, design)
    plant = build_plant(problem.structure, drive, contact, problem.pads)
    # a log grid offset by a third of a step from any grid the optimiser builds
    n = 6001
    ratio = (req.band[1] / req.band[0]) ** (1.0 / (n - 1))
    omega = req.band[0] * ratio ** (np.arange(n) + 1.0 / 3.0)
    omega = omega[omega <= req.band[1]]
    from .structure.model import signal_name

    h = frequency.compliance(plant, omega, force=signal_name(problem.force, "f_"),
                             output=signal_name(problem.force))
    peak, w_peak = frequency.peak(omega, h)
    b_crit = min_real = None
    if problem.chatter is not None:
        from .chatter import critical_depth

        oriented = problem.chatter.mu * h.real
        b_crit = critical_depth(oriented, problem.chatter.kt, omega)
        min_real = -1.0 / (2.0 * problem.chatter.kt * b_crit)
    velocity = position = None
    if drive is not None:
        loop_omega = np.geomspace(req.loop_band[0], req.loop_band[1], 8001)
        velocity = frequency.analyse_loop(
            loop_transfer(problem.structure, drive, contact, problem.pads, "velocity"),
            loop_omega)
        position = frequency.analyse_loop(
            loop_transfer(problem.structure, drive, contact, problem.pads, "position"),
            loop_omega)
    return Performance(peak, w_peak, b_crit, min_real, velocity, position, True)


# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TuningResult:
    """Outcome of :func:`tune`.

    Attributes
    ----------
    design, initial : Design
    before, after : Performance
        Verified with python-control (``after`` is None if the design could not be verified).
    predicted : dict
        The optimiser's own values (port model) at the optimum.
    success : bool
        True only if the solver converged AND verification confirmed the constraints.
    reasons : tuple of str
        Why not, when ``success`` is False.
    active : tuple of str
        Constraints and bounds active at the optimum.
    stats : dict
        Solver statistics: starts, iterations, exchange rounds, grid size, time [s].
    """

    problem: TuningProblem
    initial: Design
    design: Design
    before: Performance
    after: Performance | None
    predicted: dict
    success: bool
    reasons: tuple[str, ...]
    active: tuple[str, ...]
    stats: dict

    def objective(self, performance: Performance, design: Design) -> float:
        """The optimiser's objective for a verified performance of a design."""
        w_peak, w_chatter = self.problem.weights
        value = w_peak * performance.peak_compliance / self.before.peak_compliance
        if w_chatter:
            value += w_chatter * self.before.b_crit / performance.b_crit
        if "kv" in self.problem.free:
            value += self.problem.tracking_weight * self.initial.kv / design.kv
        return value


def _scale_factors(problem: TuningProblem, design: Design):
    """Initial peak and initial -min Re G (for scaling) from a fine port-model evaluation."""
    res = evaluate(problem, design, _grid(*problem.requirements.band, 4000))
    h = res["compliance"]
    mu = problem.chatter.mu if problem.chatter is not None else 1.0
    return float(np.abs(h).max()), float(max(-(mu * h.real).min(), 1e-30))


class _Solver:
    """The casadi NLP on a given grid, rebuilt when the grid changes."""

    def __init__(self, problem: TuningProblem, band_grid, loop_grid, h0, s0):
        self.problem = problem
        req = problem.requirements
        x0 = problem.initial_design()
        self.free = problem.free
        self.scale = {v: getattr(x0, v) for v in self.free}
        p = ca.MX.sym("p", len(self.free))
        values = {v: getattr(x0, v) for v in VARIABLES}
        for i, v in enumerate(self.free):
            values[v] = self.scale[v] * ca.exp(p[i])
        t = ca.MX.sym("t")  # scaled compliance peak
        q = ca.MX.sym("q")  # scaled -min Re G
        w_peak, w_chatter = problem.weights
        g, lbg, ubg, self.groups = [], [], [], []

        def add(expr, lo, hi, group):
            g.append(expr)
            n = expr.shape[0]
            lbg.extend([lo] * n)
            ubg.extend([hi] * n)
            self.groups.extend([group] * n)

        band = _port_data(problem, band_grid)
        resp = _responses(problem, band, values)
        h = resp["compliance"]
        if w_peak > 0:
            add(h.abs2() / h0**2 - t * t, -ca.inf, 0.0, "compliance peak")
        if w_chatter > 0:
            add(problem.chatter.mu * h.re / s0 + q, 0.0, ca.inf, "chatter")
        if problem.drive is not None:
            loops = _responses(problem, _port_data(problem, loop_grid), values)
            for loop in ("velocity", "position"):
                ms = req.ms_limit(loop)
                add((1.0 + loops[f"loop_{loop}"]).abs2() * ms**2, 1.0, ca.inf, f"Ms {loop} loop")
            if "kv" in self.free and req.kv_min > 0:
                add(values["kv"] - req.kv_min, 0.0, ca.inf, "kv_min")
        objective = (w_peak * t if w_peak > 0 else 0) + (w_chatter * q if w_chatter > 0 else 0)
        if "kv" in self.free and problem.tracking_weight > 0:
            objective = objective + problem.tracking_weight * x0.kv / values["kv"]
        x = ca.vertcat(p, t, q)
        self.nlp = {"x": x, "f": objective, "g": ca.vertcat(*g)}
        self.lbg, self.ubg = np.array(lbg), np.array(ubg)
        self.solver = ca.nlpsol("tune", "ipopt", self.nlp, {
            "ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
            "ipopt.tol": 1e-10, "ipopt.acceptable_tol": 1e-8, "ipopt.max_iter": 500,
            "ipopt.mu_strategy": "adaptive", "ipopt.hessian_approximation": "limited-memory"})
        # limited-memory Hessian: with a handful of variables and hundreds of frequency
        # constraints, building the exact Hessian of the Lagrangian costs more than it saves
        lo = [math.log(problem.bounds[v][0] / self.scale[v]) for v in self.free]
        hi = [math.log(problem.bounds[v][1] / self.scale[v]) for v in self.free]
        self.lbx = np.array(lo + [0.0, -ca.inf])
        self.ubx = np.array(hi + [ca.inf, ca.inf])
        self.w_peak, self.w_chatter = w_peak, w_chatter

    def solve(self, design: Design, t0: float, q0: float, region: float | None = None):
        """Solve from ``design``; ``region`` limits each log-variable to +-region around it
        (a trust region that keeps the step continuous, see :func:`tune`)."""
        p0 = [math.log(getattr(design, v) / self.scale[v]) for v in self.free]
        lbx, ubx = self.lbx.copy(), self.ubx.copy()
        if region is not None:
            n = len(p0)
            lbx[:n] = np.maximum(lbx[:n], np.array(p0) - region)
            ubx[:n] = np.minimum(ubx[:n], np.array(p0) + region)
        sol = self.solver(x0=np.array(p0 + [t0, q0]), lbx=lbx, ubx=ubx,
                          lbg=self.lbg, ubg=self.ubg)
        stats = self.solver.stats()
        x = np.array(sol["x"]).ravel()
        values = {v: float(self.scale[v] * math.exp(x[i])) for i, v in enumerate(self.free)}
        new = replace(design, **values)
        g = np.array(sol["g"]).ravel()
        return new, float(x[-2]), float(x[-1]), float(sol["f"]), stats, g

    def violations(self, g: np.ndarray) -> dict:
        out = {}
        for gi, lo, hi, group in zip(g, self.lbg, self.ubg, self.groups, strict=True):
            v = max(lo - gi, gi - hi, 0.0)
            out[group] = max(out.get(group, 0.0), v)
        return out


def _stable(problem: TuningProblem, design: Design) -> bool:
    """Closed-loop stability of a design from the poles of the interconnected plant."""
    drive = problem.drive_for(design)
    if drive is None:
        return True
    plant = build_plant(problem.structure, drive, _contact(problem, design), problem.pads)
    try:
        frequency.require_stable(plant)
    except UnstableLoopError:
        return False
    return True


def _contact(problem: TuningProblem, design: Design) -> Contact:
    if not problem.pads:
        return Contact.free()
    if problem.contact_stiffness:
        return Contact("equivalent", stiffness=problem.contact_stiffness, damping=design.c,
                       note="tuned pads")
    return Contact.viscous(design.c)


def _converged(stats) -> bool:
    return bool(stats["success"]) or stats["return_status"] in (
        "Solve_Succeeded", "Solved_To_Acceptable_Level")


def _local_extrema(omega, values, maximise: bool, count: int) -> list[float]:
    """The ``count`` largest local maxima (or smallest minima) of ``values`` on a fine grid,
    each placed between grid points by a parabola in log omega."""
    v = values if maximise else -values
    inner = np.nonzero((v[1:-1] >= v[:-2]) & (v[1:-1] >= v[2:]))[0] + 1
    cand = np.unique(np.concatenate([inner, [int(np.argmax(v))]]))
    cand = cand[np.argsort(-v[cand])][:count]
    out = []
    for i in cand:
        if 0 < i < omega.size - 1:
            x = np.log(omega[i - 1:i + 2])
            a2, a1, _ = np.polyfit(x - x[1], v[i - 1:i + 2], 2)
            if a2 < 0 and abs(a1 / (2 * a2)) <= x[2] - x[0]:
                out.append(float(omega[i] * math.exp(-a1 / (2 * a2))))
                continue
        out.append(float(omega[i]))
    return out


def _exchange_points(problem: TuningProblem, design: Design, models: dict):
    """True extrema of a design's responses and how far the optimiser's grid misses them.

    ``models`` holds :class:`ResponseModel` s on the fine band and loop grids and on the
    optimiser's current grids. Candidates are located on the fine grids, placed between grid
    points by a parabola, and evaluated exactly there.
    """
    fine_band, fine_loop = models["fine_band"](design), None
    grid_band = models["band"](design)
    checks = []  # (kind, omega)
    if problem.weights[0] > 0:
        checks += [("peak", w) for w in _local_extrema(
            fine_band["omega"], np.abs(fine_band["compliance"]), True, 4)]
    mu = problem.chatter.mu if problem.chatter is not None else 1.0
    if problem.weights[1] > 0:
        checks += [("real", w) for w in _local_extrema(
            fine_band["omega"], mu * fine_band["compliance"].real, False, 4)]
    if problem.drive is not None:
        fine_loop = models["fine_loop"](design)
        for key in ("loop_velocity", "loop_position"):
            checks += [(key, w) for w in _local_extrema(
                fine_loop["omega"], np.abs(1 + fine_loop[key]), False, 3)]
    exact = ResponseModel(problem, [w for _, w in checks])(design)
    worst, added_band, added_loop = 0.0, [], []
    for kind in ("peak", "real", "loop_velocity", "loop_position"):
        sel = [i for i, (k, _) in enumerate(checks) if k == kind]
        if not sel:
            continue
        ws = [checks[i][1] for i in sel]
        if kind == "peak":
            worst = max(worst, np.abs(exact["compliance"][sel]).max()
                        / np.abs(grid_band["compliance"]).max() - 1)
            added_band += ws
        elif kind == "real":
            worst = max(worst, (mu * exact["compliance"].real[sel]).min()
                        / (mu * grid_band["compliance"].real).min() - 1)
            added_band += ws
        else:
            grid_loop = models["loop"](design)
            worst = max(worst, np.abs(1 + grid_loop[kind]).min()
                        / np.abs(1 + exact[kind][sel]).min() - 1)
            added_loop += ws
    return added_band, added_loop, worst


def tune(problem: TuningProblem, starts: int = 4, seed: int = 0, max_exchange: int = 30,
         tolerance: float = 1e-6) -> TuningResult:
    """Optimise the free design variables with casadi/IPOPT, then verify with python-control.

    Parameters
    ----------
    problem : TuningProblem
    starts : int
        Number of starting points: the initial design plus seeded log-uniform draws within the
        bounds; unstable draws are skipped (the frequency constraints keep a design stable only
        along continuous paths from a stable one, so every start must be stable), and every
        optimum is checked for closed-loop stability before it is accepted.
    seed : int
        Seed of the starting points.
    max_exchange : int
        Largest number of grid-exchange rounds.
    tolerance : float
        Relative agreement between grid and true extrema that ends the exchange.

    Returns
    -------
    TuningResult
        ``success`` only when IPOPT converged and the verification holds.

    Raises
    ------
    RequirementsNotMetError
        When no start reaches a feasible design; the message names the binding constraint.
    UnstableLoopError
        When the initial design is unstable (tuning needs a stable start).
    """
    t_start = time.perf_counter()
    req = problem.requirements
    x0 = problem.initial_design()
    before = verify(problem, x0)  # raises UnstableLoopError for an unstable initial design
    h0, s0 = _scale_factors(problem, x0)
    band_grid = _grid(*req.band, problem.n_grid)
    loop_grid = _grid(*req.loop_band, problem.n_grid)
    rng = np.random.default_rng(seed)
    designs, draws = [x0], 0
    while len(designs) < max(starts, 1) and draws < 20 * starts:
        draws += 1
        values = {v: float(math.exp(rng.uniform(*np.log(problem.bounds[v]))))
                  for v in problem.free}
        candidate = replace(x0, **values)
        if _stable(problem, candidate):
            designs.append(candidate)

    solver = _Solver(problem, band_grid, loop_grid, h0, s0)
    best, runs, iterations = None, [], 0
    for d in designs:
        new, _, _, f, stats, g = solver.solve(d, 1.0, 1.0)
        iterations += stats["iter_count"]
        ok = _converged(stats) and _stable(problem, new)
        runs.append((f, new, stats, g))
        if ok and (best is None or f < best[0]):
            best = (f, new, stats, g)
    if best is None:
        f, new, stats, g = min(runs, key=lambda r: max(solver.violations(r[3]).values()))
        viol = solver.violations(g)
        worst = max(viol, key=viol.get)
        raise RequirementsNotMetError(
            f"the requirements cannot be met within the bounds: the binding constraint is "
            f"'{worst}' (violated by {viol[worst]:.3g} in scaled units at the best of "
            f"{len(designs)} starts; IPOPT: {stats['return_status']}); relax it or widen the "
            "bounds of the free variables")

    design = best[1]
    models = {"fine_band": ResponseModel(problem, _grid(*req.band, 6000)),
              "fine_loop": ResponseModel(problem, _grid(*req.loop_band, 6000))}
    rounds, worst_rel, exchange_failed = 0, math.inf, False
    for rounds in range(1, max_exchange + 1):  # noqa: B007
        models["band"] = ResponseModel(problem, band_grid)
        models["loop"] = ResponseModel(problem, loop_grid)
        added_band, added_loop, worst_rel = _exchange_points(problem, design, models)
        if worst_rel <= tolerance:
            break
        band_grid = np.unique(np.concatenate([band_grid, added_band]))
        loop_grid = np.unique(np.concatenate([loop_grid, added_loop]))
        solver = _Solver(problem, band_grid, loop_grid, h0, s0)
        # the new grid points may cut off the current design; re-solve from it, shrinking a
        # trust region until the step stays on the stable side (frequency constraints alone
        # cannot tell a stable design from an unstable one far away)
        accepted = False
        for region in (None, 0.5, 0.1, 0.02):
            new, _, _, f, stats, g = solver.solve(design, 1.0, 1.0, region)
            iterations += stats["iter_count"]
            if _converged(stats) and _stable(problem, new):
                design, best, accepted = new, (f, new, stats, g), True
                break
        if not accepted:
            exchange_failed = True
            break
    g = best[3]
    active = []
    for v in problem.free:
        lo, hi = problem.bounds[v]
        val = getattr(design, v)
        if val <= lo * (1 + 1e-6):
            active.append(f"{v} at its lower bound {lo:.4g}")
        if val >= hi * (1 - 1e-6):
            active.append(f"{v} at its upper bound {hi:.4g}")
    if len(g) == len(solver.groups):
        for group in sorted(set(solver.groups)):
            if group.startswith("Ms") or group == "kv_min":
                sel = [i for i, gg in enumerate(solver.groups) if gg == group]
                lo = solver.lbg[sel]
                if np.any(np.abs(g[sel] - lo) <= 1e-5 * np.maximum(1, np.abs(lo))):
                    active.append(group)
    predicted = models["fine_band"](design)
    pred = {"peak_compliance": float(np.abs(predicted["compliance"]).max())}
    if problem.chatter is not None:
        pred["b_crit"] = problem.chatter.b_crit(
            float((problem.chatter.mu * predicted["compliance"].real).min()))

    reasons = []
    if exchange_failed:
        reasons.append("the optimiser could not satisfy the constraints at frequencies added by "
                       f"the grid exchange (round {rounds}); the design is the last feasible one "
                       "on the previous grid")
    elif worst_rel > max(tolerance, 1e-4):
        reasons.append(f"the frequency grid did not converge (true extrema {worst_rel:.2g} "
                       f"beyond the grid after {rounds} exchange rounds)")
    after = None
    try:
        after = verify(problem, design)
    except UnstableLoopError as exc:
        reasons.append(f"verification: {exc}")
    if after is not None:
        if abs(after.peak_compliance / pred["peak_compliance"] - 1) > 0.01:
            reasons.append(
                f"verification: the state-space compliance peak {after.peak_compliance:.4g} m/N "
                f"differs from the optimiser's {pred['peak_compliance']:.4g} m/N by more than 1%")
        for loop, analysis in (("velocity", after.velocity), ("position", after.position)):
            if analysis is not None and analysis.ms > req.ms_limit(loop) * 1.005:
                reasons.append(f"verification: Ms of the {loop} loop is {analysis.ms:.4f}, above "
                               f"the limit {req.ms_limit(loop):.4f}")
    return TuningResult(
        problem=problem, initial=x0, design=design, before=before, after=after,
        predicted=pred, success=not reasons, reasons=tuple(reasons), active=tuple(active),
        stats={"starts": len(designs), "iterations": int(iterations), "exchange_rounds": rounds,
               "grid_points": int(band_grid.size + loop_grid.size),
               "return_status": best[2]["return_status"],
               "time_s": time.perf_counter() - t_start})
