"""Solving the tuning problem: the stages, each a function with a typed result.

1. :func:`stable_starts`: the given first designs that keep every model stable, the initial
   design if every regime model is stable with it, else the initial design with a softer
   velocity loop; then seeded log-uniform draws within the bounds that keep every model
   stable. A model that no candidate stabilises (e.g. feeding
   below the Stribeck speed, where the friction slope is negative) is excluded from the
   optimisation and reported.
2. The starts solved in turn on the initial grid, until two reach the same stable optimum;
   the best is kept.
3. Grid exchange: the constraints evaluated on fine grids; the frequencies where they are
   worst (peaks of the compliance, minima of |1 + L|, the edges of the gated hierarchy rows)
   are added to the grids and the problem re-solved warm, until grid and truth agree (the
   position-loop bandwidth ratio of the hierarchy gates is updated with it).
4. :func:`servotune.tuning.verify.verify` and :func:`requirement_checks`: the independent
   check of the design in every model. When it fails only on Ti w_b above its rule (judged on
   the design, not a row of the NLP: :mod:`servotune.tuning.requirements.integral_time`), Ti
   is lowered to the rule (:func:`repair`) and the problem re-solved from there with Ti capped
   at that value and exchanged again (up to :data:`TI_RULE_ROUNDS` times); the re-solve is
   kept only when its check holds, and ``notes`` says where Ti was capped.

When no start reaches a usable optimum, the dense check of the initial design tells the two
failures apart: if the initial design meets every requirement, the requirements are feasible
and the optimiser merely found no better design, so the initial design is returned with that
reason in ``notes``; otherwise the requirements are infeasible within the bounds
(:class:`RequirementsNotMetError`, naming the binding constraint) or, when only the objective
did not settle, :class:`TuningDidNotConvergeError`.

The optimisation problem itself is stated in :mod:`servotune.tuning.nlp`.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .. import frequency
from ..blas import one_thread
from ..digital import SampledAxis
from ..drive import current_loop_bandwidth
from ..plant import build_plant
from ..units import HZ_PER_RAD_S
from .nlp import Kernels, Solution, Solver, gate_parameters
from .ports import ResponseModel, grid, is_sampled, port_data
from .problem import (
    LOWPASS_VARIABLES,
    NOTCH_VARIABLES,
    Design,
    NoStableStartError,
    RequirementsNotMetError,
    TuningDidNotConvergeError,
    TuningProblem,
)
from .verify import Performance, RequirementCheck, requirement_checks, verify

#: The tuned set-point filters' variables (the closed-loop matrices' form holds at fixed ones).
FILTER_VARIABLES = NOTCH_VARIABLES + LOWPASS_VARIABLES

__all__ = ["TuningResult", "TuningStatistics", "Prediction", "StartSet", "StartsOutcome",
           "HeldModel", "held_models",
           "ExchangeOutcome", "ClosedLoopMatrices", "stable_starts", "model_stability",
           "solve_starts", "repair",
           "exchange_grids", "predict", "tune"]

#: Softer velocity loops tried when the initial design leaves a model unstable.
SOFTENING = (0.7, 0.5, 0.35, 0.25, 0.18, 0.125, 0.09)
#: Points of the fine grids on which the exchange looks for the worst frequencies (each found
#: one is then placed by a parabola and evaluated exactly).
FINE_POINTS = 2500


@dataclass(frozen=True)
class TuningResult:
    """Outcome of :func:`tune`.

    Attributes
    ----------
    problem : TuningProblem
        The problem solved (without the models excluded at the start), with the bounds as
        given: when Ti was capped by its bandwidth rule (see :func:`tune`), ``notes`` says so
        and ``active`` names the cap when Ti sits at it.
    initial, design : Design
    before, after : Performance
        Verified with python-control in every model (``after`` None if not verified).
    predicted : Prediction or None
        The optimiser's own values (port model) at the optimum (None for a design checked
        without optimising it).
    success : bool
        True only if every requirement check holds on the design AND the solver converged
        (or, when no start reached a usable optimum, the initial design, which meets every
        requirement, is kept: said in ``notes``).
    reasons : tuple of str
        Why not, when ``success`` is False.
    active : tuple of str
        Constraints and bounds active at the optimum, by name.
    checks : tuple of RequirementCheck
        Every requirement judged on the dense check of the design.
    excluded : tuple of (RegimeModel, str)
        Models left out of the optimisation, and why: no stable design was found for them.
    stats : TuningStatistics
        Solver statistics: starts, iterations, exchange rounds, grid size, time [s].
    """

    problem: TuningProblem
    initial: Design
    design: Design
    before: Performance
    after: Performance | None
    predicted: Prediction | None
    success: bool
    reasons: tuple[str, ...]
    active: tuple[str, ...]
    stats: TuningStatistics
    checks: tuple[RequirementCheck, ...] = ()
    excluded: tuple = ()
    start: Design | None = None
    notes: tuple[str, ...] = ()
    """Remarks on how the design was reached (e.g. the initial design kept because the
    optimiser found no better one)."""
    held: tuple = ()
    """The cutting models the free variables cannot move (:class:`HeldModel`), held at their
    value by the lexicographic objective."""


# ----------------------------------------------------------------------- 1. starting points
def model_stability(problem: TuningProblem, design: Design) -> list[bool]:
    """Return the closed-loop stability of a design in each regime model (state-space poles).

    The criterion is :func:`servotune.frequency.is_stable` on the closed-loop state matrix of
    each model, taken from :class:`ClosedLoopMatrices` (exact multi-affine form) when the
    problem's drive has that form, else from :func:`~servotune.plant.build_plant`.

    Parameters
    ----------
    problem : TuningProblem
        The problem (structure, drive, regime models).
    design : Design
        The design.

    Returns
    -------
    list of bool
        One per regime model: True when every closed-loop pole lies in the left half plane.
    """
    if problem.drive is None:
        return [True] * len(problem.regimes)
    if is_sampled(problem):
        drive = problem.drive_for(design)
        return [SampledAxis(problem.structure, drive,
                            model.contact(design.c) if problem.pads else None,
                            problem.pads).is_stable() for model in problem.regimes]
    matrices = ClosedLoopMatrices.of(problem)
    if matrices.exact and all(getattr(design, v) == getattr(matrices.initial, v)
                              for v in FILTER_VARIABLES):
        # (the form holds at the initial set-point filters; other filters are built)
        return [frequency.is_stable_matrix(a) for a in matrices(design)]
    return [frequency.is_stable(matrices.build(model, design)) for model in problem.regimes]


class ClosedLoopMatrices:
    """The closed-loop state matrix of each regime model as a function of the design.

    With the cascade of :mod:`servotune.drive` (position P, velocity PI, the current loop
    fixed) and a contact viscous in C, the matrix is multi-affine in the design::

        A(d) = A_0 + c A_1 + Kv A_2 + Kp A_3 + (Kp / Ti) A_4 + Kp Kv A_5

    The six matrices of each model are solved for from the plants built at six designs around
    the initial one (C raised, Kv, Kp and Ti each doubled in turn, and Kv and Kp together: a
    well-conditioned 6 x 6 system in the variables relative to the initial design), and the
    form is checked at a seventh design against the built plant, entry by entry to 1e-9 of
    that entry's size over the designs (plus 1e-14 of the largest entry: the rounding of
    cancellations). A design then costs a sum of six matrices instead of an interconnection
    of the plant's blocks. When the check fails (a drive whose matrices depend otherwise on
    the design), ``exact`` is False and each design is built.

    Parameters
    ----------
    problem : TuningProblem
        A problem with a drive.
    """

    _KEPT: ClassVar[dict[int, tuple[object, ClosedLoopMatrices]]] = {}

    def __init__(self, problem: TuningProblem):
        self.problem = problem
        x0 = problem.initial_design()
        self._x0, self._c_ref = x0, x0.c if x0.c > 0 else 1.0
        fit = [x0,
               dataclasses.replace(x0, c=x0.c + self._c_ref),
               dataclasses.replace(x0, kv=2 * x0.kv),
               dataclasses.replace(x0, kp=2 * x0.kp),
               dataclasses.replace(x0, ti=2 * x0.ti),
               dataclasses.replace(x0, kv=2 * x0.kv, kp=2 * x0.kp)]
        check = dataclasses.replace(x0, c=x0.c + 0.5 * self._c_ref, kv=0.6 * x0.kv,
                                    kp=2.5 * x0.kp, ti=0.7 * x0.ti)
        m = np.array([self._monomials(d) for d in fit])
        self.coefficients, self.exact = [], True
        for model in problem.regimes:
            built = np.array([self.build(model, d).A for d in fit])
            coef = np.linalg.solve(m, built.reshape(len(fit), -1))
            a = self.build(model, check).A
            # each entry to 1e-9 of its size, with a floor of 1e-14 of the matrix's largest
            # entry (entries that are rounding of a cancellation, ~1e-16 of it, carry no form)
            tol = 1e-9 * np.abs(built).max(axis=0).ravel() + 1e-14 * np.abs(built).max()
            if a.shape != built.shape[1:] or not np.all(
                    np.abs(self._monomials(check) @ coef - a.ravel()) <= tol):
                self.exact = False
                break
            self.coefficients.append(coef.reshape((len(fit), *a.shape)))

    @classmethod
    def of(cls, problem: TuningProblem) -> ClosedLoopMatrices:
        """Return the matrices of ``problem``, made once per problem object (a few are kept).

        Parameters
        ----------
        problem : TuningProblem
            A problem with a drive.

        Returns
        -------
        ClosedLoopMatrices
        """
        kept = cls._KEPT.get(id(problem))
        if kept is not None and kept[0] is problem:
            return kept[1]
        out = cls(problem)
        if len(cls._KEPT) >= 4:
            cls._KEPT.pop(next(iter(cls._KEPT)))
        cls._KEPT[id(problem)] = (problem, out)
        return out

    @property
    def initial(self) -> Design:
        """The design the matrices were fitted around (the problem's initial one).

        Returns
        -------
        Design
        """
        return self._x0

    def _monomials(self, d: Design) -> np.ndarray:
        x0 = self._x0
        c, kv, kp, ti = d.c / self._c_ref, d.kv / x0.kv, d.kp / x0.kp, d.ti / x0.ti
        return np.array([1.0, c, kv, kp, kp / ti, kp * kv])

    def build(self, model, design: Design):
        """Return the closed-loop plant of one regime model with a design (built).

        Parameters
        ----------
        model : RegimeModel
            The regime model.
        design : Design
            The design.

        Returns
        -------
        control.StateSpace
            :func:`~servotune.plant.build_plant` of the model's contact and the design's drive.
        """
        p = self.problem
        return build_plant(p.structure, p.drive_for(design), model.contact(design.c), p.pads)

    def __call__(self, design: Design) -> list[np.ndarray]:
        """Return the closed-loop state matrix of every regime model with ``design``.

        Parameters
        ----------
        design : Design
            The design.

        Returns
        -------
        list of numpy.ndarray
            One matrix per regime model (built plants' matrices when not ``exact``).
        """
        if not self.exact:
            return [self.build(m, design).A for m in self.problem.regimes]
        mono = self._monomials(design)
        return [np.tensordot(mono, coef, axes=1) for coef in self.coefficients]


@dataclass(frozen=True)
class StartSet:
    """Stable starting points and the models no candidate could stabilise."""

    designs: tuple[Design, ...]
    excluded: tuple[int, ...]
    initial_stable: tuple[bool, ...]


def stable_starts(problem: TuningProblem, starts: int, seed: int = 0,
                  max_draws: int | None = None, spread: float = 3.0,
                  first=()) -> StartSet:
    """Return starting points that keep every (kept) regime model stable.

    The frequency constraints of the NLP keep a design stable only along continuous paths
    from a stable one, so every start must be stable in every model it is optimised for. The
    draws are log-uniform within a factor ``spread`` of the first stable design (the initial
    one or its softened version), clipped to the bounds: far draws mostly land where the
    problem has other, worse optima or none.

    Parameters
    ----------
    problem : TuningProblem
        The problem.
    starts : int
        Number of starting points wanted.
    seed : int
        Seed of the draws.
    max_draws : int, optional
        Largest number of random draws (default 20 per start).
    spread : float
        Draws lie within this factor of the first stable design.
    first : sequence of Design
        Designs tried before the initial one (e.g. the previous round's), clipped to the
        bounds; the stable ones come first among the starts.

    Returns
    -------
    StartSet
        The starts, the models no candidate stabilised and the initial design's stability.
    """
    x0 = problem.initial_design()
    s0 = model_stability(problem, x0)
    given = []
    for d in first:
        d = dataclasses.replace(d, **{v: float(np.clip(getattr(d, v), *problem.bounds[v]))
                                      for v in problem.free})
        stable = model_stability(problem, d)
        if all(stable):
            given.append(d)
    candidates = [(x0, s0)]
    if not all(s0) and problem.drive is not None and "kp" in problem.free:
        lo = problem.bounds["kp"][0]
        for f in SOFTENING:
            d = dataclasses.replace(x0, kp=max(x0.kp * f, lo))
            candidates.append((d, model_stability(problem, d)))
            if all(candidates[-1][1]):
                break
    rng = np.random.default_rng(seed)
    max_draws = 20 * max(starts, 1) if max_draws is None else max_draws
    draws = []

    def draw(centre=None):
        centre = centre or x0
        values = {}
        for v in problem.free:
            lo, hi = problem.bounds[v]
            mid = getattr(centre, v)
            values[v] = float(np.clip(mid * math.exp(rng.uniform(-1, 1) * math.log(spread)),
                                      lo, hi))
        d = dataclasses.replace(x0, **values)
        return d, model_stability(problem, d)

    stable_any = np.any([s for _, s in candidates], axis=0)
    n_draw = 0
    while not stable_any.all() and n_draw < min(max_draws, 10):
        n_draw += 1
        draws.append(draw())
        stable_any |= np.array(draws[-1][1])
    excluded = tuple(int(i) for i in np.nonzero(~stable_any)[0])
    keep = [i for i in range(len(problem.regimes)) if i not in excluded]

    def ok(s):
        return all(s[i] for i in keep)

    chosen = given + [d for d, s in candidates if ok(s)][:1]
    chosen += [d for d, s in draws if ok(s)]
    centre = chosen[0] if chosen else None
    while len(chosen) < max(starts, 1) and n_draw < max_draws:
        n_draw += 1
        d, s = draw(centre)
        if ok(s):
            chosen.append(d)
    return StartSet(tuple(chosen[:max(starts, 1)]), excluded, tuple(s0))


# ----------------------------------------------------------------------- grids and data
@dataclass
class _Grids:
    """The optimiser's band and loop grids with their data and per-model gate parameters."""

    problem: TuningProblem
    band: np.ndarray
    loop: np.ndarray
    gates: np.ndarray
    reference: Design

    def __post_init__(self):
        self.refresh()

    def refresh(self):
        cut = list(self.problem.cutting_models)
        self.band_model = ResponseModel(self.problem, self.band, self.reference)
        self.loop_model = ResponseModel(self.problem, self.loop, self.reference)
        self.band_rows = self.band_model.data.rows(models=cut)
        self.loop_rows = self.loop_model.data.rows(self.gates)


def _moved_multipliers(old: Solver, old_grids: _Grids, new: Solver, new_grids: _Grids,
                       lam_g: np.ndarray) -> np.ndarray:
    """Constraint multipliers carried to new grids (rows of new frequencies start at zero)."""
    index = {}
    for i, key in enumerate(old.row_keys(old_grids.band, old_grids.loop)):
        if key is not None:
            index.setdefault(key, i)
    out = np.zeros(len(new.rows))
    for j, key in enumerate(new.row_keys(new_grids.band, new_grids.loop)):
        i = index.get(key) if key is not None else None
        if i is not None:
            out[j] = lam_g[i]
    return out


def _scale_factors(problem: TuningProblem, design: Design) -> tuple[float, float]:
    """Peak and -min Re(mu G) of a design over the cutting models, for scaling."""
    model = ResponseModel(problem, grid(*problem.requirements.band, 1500), design)
    h = model(design)["compliance"][list(problem.cutting_models)]
    mu = problem.chatter.mu if problem.chatter is not None else 1.0
    return float(np.abs(h).max()), float(max(-(mu * h.real).min(), 1e-30))


def _bandwidth(omega: np.ndarray, loop: np.ndarray) -> float:
    """First -3 dB crossing of |L/(1+L)| relative to its low-frequency value."""
    t = np.abs(loop / (1.0 + loop))
    below = np.nonzero(t < t[0] / math.sqrt(2.0))[0]
    return float(omega[below[0]]) if below.size else float(omega[-1])


def _gamma(problem: TuningProblem, design: Design, model: ResponseModel) -> np.ndarray:
    """Position-loop bandwidth over Kv of each model, from the port model."""
    if problem.drive is None:
        return np.ones(len(problem.regimes))
    lp = model(design, exact=False)["loop_position"]
    return np.array([max(_bandwidth(model.omega, lp[m]) / design.kv, 1e-3)
                     for m in range(lp.shape[0])])


# ----------------------------------------------------------------------- 2-4. solving
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


@dataclass
class _Fine:
    """The constraint kernels evaluated on fine grids (numerically, by casadi)."""

    problem: TuningProblem
    kernels: Kernels
    band: np.ndarray
    loop: np.ndarray
    reference: Design

    def __post_init__(self):
        cut = list(self.problem.cutting_models)
        self.band_rows = port_data(self.problem, self.band, self.reference).rows(models=cut)
        self.loop_data = port_data(self.problem, self.loop, self.reference)

    def evaluate(self, solver: Solver, design: Design, gates: np.ndarray):
        u = solver.values(design)
        band = self.kernels.evaluate("band", u, self.band_rows)
        loop = None
        if self.kernels.loop is not None:
            loop = self.kernels.evaluate("loop", u, self.loop_data.rows(gates))
        return band, loop


def _exchange_points(problem, kernels, fine: _Fine, solver: Solver, grids: _Grids,
                     design: Design):
    """Frequencies where the constraints are worst (found on the fine grids, placed between
    their points by a parabola and evaluated exactly there), and the largest relative amount
    by which they are worse than on the optimiser's grids."""
    n_cut, n_models = len(problem.cutting_models), len(problem.regimes)
    fb, fl = fine.evaluate(solver, design, grids.gates)
    u = solver.values(design)
    gb = kernels.evaluate("band", u, grids.band_rows)
    kb, kg = fine.band.size, grids.band.size
    band_cands = {}
    for r, row in enumerate(kernels.band_rows):
        for m in range(n_cut):
            vals = fb[r, m * kb:(m + 1) * kb]
            band_cands[(r, m)] = _local_extrema(fine.band, vals, row == "compliance peak", 4)
    add_band = sorted({w for ws in band_cands.values() for w in ws})
    worst = 0.0
    if add_band:
        exact = port_data(problem, np.array(add_band), grids.reference).rows(
            models=list(problem.cutting_models))
        ev = kernels.evaluate("band", u, exact)
        ka = len(add_band)
        for r, row in enumerate(kernels.band_rows):
            for m in range(n_cut):
                e_vals, g_vals = ev[r, m * ka:(m + 1) * ka], gb[r, m * kg:(m + 1) * kg]
                if row == "compliance peak":
                    worst = max(worst, math.sqrt(max(e_vals.max(), 0) / g_vals.max()) - 1)
                elif g_vals.min() < 0:
                    worst = max(worst, e_vals.min() / g_vals.min() - 1)
    add_loop = []
    if fl is not None:
        kl = fine.loop.size
        cands = set()
        for r in range(len(kernels.loop_rows)):
            lo = kernels.loop_lower[r]
            for m in range(n_models):
                vals = fl[r, m * kl:(m + 1) * kl] - lo
                if vals.min() < 0.0 or not kernels.loop_moving_only[r]:
                    cands.update(_local_extrema(fine.loop, vals, False,
                                                3 if vals.min() < 0 else 1))
        add_loop = sorted(cands)
        if add_loop:
            exact = port_data(problem, np.array(add_loop), grids.reference).rows(grids.gates)
            ev = kernels.evaluate("loop", u, exact)
            for r in range(len(kernels.loop_rows)):
                lo = kernels.loop_lower[r]
                worst = max(worst, -(ev[r] - lo).min() / max(lo, 1.0))
    return add_band, add_loop, worst


#: Frequencies per model the exchange solver has room for beyond the initial grids (when a
#: round needs more, a larger solver is built).
EXCHANGE_ROOM = (24, 48)
#: A later start stops after this many times the iterations the first converged start took.
START_ITERATION_FACTOR = 2.0


@dataclass(frozen=True)
class TuningStatistics:
    """How a design was reached: the solver's statistics.

    Attributes
    ----------
    starts : int
        Starting points tried.
    polished : int
        Starts that reached a stable optimum.
    iterations : int
        IPOPT iterations, all solves.
    exchange_rounds : int
        Grid-exchange rounds.
    grid_points : int
        Frequencies of the final band and loop grids (per model).
    models : int
        Regime models optimised for.
    return_status : str or None
        IPOPT's status of the solve that gave the design.
    current_loop_bandwidth_hz : float or None
        Bandwidth of the current loop [Hz] (an edge: the hierarchy's gate), None without drive.
    time_s : float
        Wall time of :func:`tune` [s].
    """

    starts: int
    polished: int
    iterations: int
    exchange_rounds: int
    grid_points: int
    models: int
    return_status: str | None
    current_loop_bandwidth_hz: float | None
    time_s: float

    def to_dict(self) -> dict:
        """Return the statistics as a JSON-ready dict.

        Returns
        -------
        dict
            The fields by name (SI, snake_case keys).
        """
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Prediction:
    """The optimiser's own values (port model, fine grid) at the design.

    Attributes
    ----------
    peak_compliance : float
        Worst compliance peak over the cutting models [m/N].
    peak_compliance_models : tuple of float
        The peak in each cutting model [m/N].
    b_crit : float or None
        Limiting depth of cut of the worst model [m] (None without a chatter target).
    """

    peak_compliance: float
    peak_compliance_models: tuple[float, ...]
    b_crit: float | None = None

    def to_dict(self) -> dict:
        """Return the prediction as a JSON-ready dict.

        Returns
        -------
        dict
            ``peak_compliance`` [m/N], ``peak_compliance_models`` and, with a chatter target,
            ``b_crit`` [m].
        """
        out = {"peak_compliance": self.peak_compliance,
               "peak_compliance_models": list(self.peak_compliance_models)}
        if self.b_crit is not None:
            out["b_crit"] = self.b_crit
        return out


@dataclass(frozen=True)
class StartsOutcome:
    """Stage 2: the starts solved on the initial grids.

    ``best`` is the stable optimum with the lowest objective (None when no start reached
    one), ``runs`` every solve in order, ``polished`` the number of stable optima."""

    runs: tuple[Solution, ...]
    best: Solution | None
    polished: int
    iterations: int
    solver: Solver


@dataclass(frozen=True)
class ExchangeOutcome:
    """Stage 3: the design after the grid exchange.

    ``failed`` when a round's constraints at the added frequencies could not be met (the
    design is then the last feasible one on the previous grids); ``worst`` is the largest
    relative amount by which a constraint is worse between the grid points than on them."""

    design: Design
    best: Solution
    solver: Solver
    grids: _Grids
    rounds: int
    worst: float
    failed: bool
    iterations: int


def solve_starts(problem: TuningProblem, kernels: Kernels, grids: _Grids,
                 designs: tuple[Design, ...], callback=None) -> StartsOutcome:
    """Stage 2: solve from each start on the initial grids, in turn, until two reach the
    same stable optimum.

    A start that has not converged in ``START_ITERATION_FACTOR`` times the iterations the
    first converged start took is left (the solves that lead somewhere take about as many).

    Parameters
    ----------
    problem : TuningProblem
        The problem.
    kernels : Kernels
        Its per-frequency kernels.
    grids : _Grids
        The initial grids with their data.
    designs : tuple of Design
        Stable starting points (:func:`stable_starts`).
    callback : casadi.Callback, optional
        Interruption callback.

    Returns
    -------
    StartsOutcome
        The solves, the best stable optimum and the solver.
    """
    solver = Solver(problem, kernels, grids.band.size, grids.loop.size, max_iter=300,
                    callback=callback)
    runs, best, polished, iterations, limit = [], None, 0, 0, None
    for d in designs:
        sol = solver.solve(d, grids.band_rows, grids.loop_rows, max_iter=limit)
        iterations += sol.stats["iter_count"]
        runs.append(sol)
        if limit is None and sol.converged:
            limit = max(60, int(START_ITERATION_FACTOR * sol.stats["iter_count"]))
        if not sol.converged or not all(model_stability(problem, sol.design)):
            continue
        polished += 1
        if best is not None and _same_optimum(sol, best, problem.free):
            break
        if best is None or sol.objective < best.objective:
            best = sol
    return StartsOutcome(tuple(runs), best, polished, iterations, solver)


def exchange_grids(problem: TuningProblem, kernels: Kernels, grids: _Grids, gamma: np.ndarray,
                   start: Solution, start_solver: Solver, current_bw: float | None,
                   max_exchange: int = 30, tolerance: float = 1e-6,
                   callback=None) -> ExchangeOutcome:
    """Stage 3: refine the grids where the constraints are worst and re-solve, warm, until
    grid and truth agree within ``tolerance`` (relative).

    Each round evaluates the constraints on fine grids, adds the frequencies where they are
    worst (:func:`_exchange_points`), updates the position-loop bandwidth ratio ``gamma`` of
    the hierarchy gates, and re-solves from the last design with the multipliers carried
    over; when the warm solve fails, smaller trust regions around the design are tried.

    Parameters
    ----------
    problem, kernels : TuningProblem, Kernels
        The problem and its per-frequency kernels.
    grids : _Grids
        The grids of the start phase.
    gamma : numpy.ndarray
        Position-loop bandwidth over Kv of each model at the reference start.
    start : Solution
        The best optimum of the start phase.
    start_solver : Solver
        The solver that found it (its rows name the multipliers).
    current_bw : float or None
        Current-loop bandwidth [rad/s].
    max_exchange : int
        Largest number of rounds.
    tolerance : float
        Relative agreement between grid and true extrema that ends the exchange.
    callback : casadi.Callback, optional
        Interruption callback.

    Returns
    -------
    ExchangeOutcome
        The design on the refined grids and how it was reached.
    """
    req = problem.requirements
    fine = _Fine(problem, kernels, grid(*req.band, FINE_POINTS), grid(*req.loop_band, FINE_POINTS),
                 grids.reference)
    fine_loop_model = ResponseModel(problem, grid(*req.loop_band, 3000), grids.reference)
    solver, warm = start_solver, None
    design, best, rounds, worst, failed, iterations = start.design, start, 0, math.inf, False, 0
    for rounds in range(1, max_exchange + 1):  # noqa: B007
        # the ratio of the position loop's bandwidth to Kv, relaxed (a plain update overshoots:
        # Kv and the ratio move against each other)
        gamma = np.sqrt(gamma * _gamma(problem, design, fine_loop_model))
        new_gates = gate_parameters(problem, gamma, current_bw)
        gates_moved = not np.allclose(new_gates, grids.gates, rtol=0, atol=0.02)
        add_band, add_loop, worst = _exchange_points(problem, kernels, fine, solver, grids,
                                                     design)
        if worst <= tolerance and not gates_moved:
            break
        old_solver, old_grids = solver, grids
        grids = _Grids(problem, np.unique(np.concatenate([grids.band, add_band])),
                       np.unique(np.concatenate([grids.loop, add_loop])), new_gates,
                       grids.reference)
        if warm is None or grids.band.size > warm.n_band or grids.loop.size > warm.n_loop:
            warm = Solver(problem, kernels, grids.band.size + EXCHANGE_ROOM[0],
                          grids.loop.size + EXCHANGE_ROOM[1], warm=True, callback=callback)
        solver = warm
        lam = _moved_multipliers(old_solver, old_grids, solver, grids, best.multipliers[1])
        lam_x = best.multipliers[0]
        accepted = False
        for region in (None, 0.5, 0.1, 0.02):
            sol = solver.solve(design, grids.band_rows, grids.loop_rows, region,
                               multipliers=(lam_x, lam))
            iterations += sol.stats["iter_count"]
            if sol.converged and all(model_stability(problem, sol.design)):
                design, best, accepted = sol.design, sol, True
                break
        if not accepted:
            failed = True
            break
    return ExchangeOutcome(design, best, solver, grids, rounds, worst, failed, iterations)


def predict(problem: TuningProblem, design: Design,
            reference: Design | None = None) -> Prediction:
    """The optimiser's port model at ``design`` on a fine band grid (6000 frequencies).

    Parameters
    ----------
    problem : TuningProblem
        The problem.
    design : Design
        The design.
    reference : Design, optional
        Where a digital drive's corrections were made exact (the tuning's reference start;
        default ``design`` itself).

    Returns
    -------
    Prediction
        Peaks per cutting model and the limiting depth of cut.
    """
    # the optimiser's own values: the corrections of a digital drive as it used them
    ref = design if reference is None else reference
    h = ResponseModel(problem, grid(*problem.requirements.band, 6000),
                      ref)(design, exact=False)["compliance"]
    cut = list(problem.cutting_models)
    b_crit = None
    if problem.chatter is not None:
        b_crit = problem.chatter.b_crit(float((problem.chatter.mu * h[cut].real).min()))
    return Prediction(float(np.abs(h[cut]).max()),
                      tuple(float(np.abs(h[m]).max()) for m in cut), b_crit)


def _statistics(starts: int, polished: int, iterations: int, rounds: int, grids: _Grids,
                problem: TuningProblem, status, current_bw, t_start: float) -> TuningStatistics:
    return TuningStatistics(
        starts=starts, polished=polished, iterations=int(iterations), exchange_rounds=rounds,
        grid_points=int(grids.band.size + grids.loop.size), models=len(problem.regimes),
        return_status=status,
        current_loop_bandwidth_hz=None if current_bw is None else current_bw * HZ_PER_RAD_S,
        time_s=time.perf_counter() - t_start)


def _kept_models(problem: TuningProblem, start_set: StartSet):
    """The problem without the models no start stabilises, and those models with why."""
    excluded = tuple((problem.regimes[i], _exclusion_reason(problem.regimes[i]))
                     for i in start_set.excluded)
    if start_set.excluded:
        kept = tuple(m for i, m in enumerate(problem.regimes) if i not in start_set.excluded)
        if not any(m.cutting for m in kept):
            raise NoStableStartError(
                "no design was found that keeps any cutting regime stable: "
                + "; ".join(f"{m.name}: {r}" for m, r in excluded))
        problem = dataclasses.replace(problem, regimes=kept)
    if not start_set.designs:
        raise NoStableStartError(
            "no stable starting design: the initial design leaves "
            + ", ".join(m.name for m, s in zip(problem.regimes, start_set.initial_stable,
                                                  strict=False) if not s)
            + " unstable and neither a softer velocity loop nor random designs within the "
              "bounds stabilise every model; lower the velocity-loop gain kp, widen the bounds "
              "or check the model")
    return problem, excluded


#: A cutting model whose peak moves less than this (relative) per unit of log of every free
#: variable is held (see :func:`held_models`).
HOLD_SENSITIVITY = 1e-3
#: A held model may end this much (relative) above its value at the reference start.
HOLD_SLACK = 2e-3


@dataclass(frozen=True)
class HeldModel:
    """A cutting model the free variables cannot move, held at its value.

    Attributes
    ----------
    model : RegimeModel
        The model.
    peak : float
        Its compliance peak at the reference start [m/N].
    sensitivity : float
        The largest ``|d log peak / d log x|`` over the free variables x.
    reason : str
        Why (the numbers and what sets the peak).
    """

    model: object
    peak: float
    sensitivity: float
    reason: str

    def to_dict(self) -> dict:
        """Return the held model JSON-ready.

        Returns
        -------
        dict
            ``model``, ``regime``, ``peak_m_per_n``, ``sensitivity``, ``reason``.
        """
        return {"model": self.model.name, "regime": self.model.regime,
                "peak_m_per_n": self.peak, "sensitivity": self.sensitivity,
                "reason": self.reason}


def held_models(problem: TuningProblem, design: Design, step: float = 0.1,
                n_points: int = 800) -> tuple[HeldModel, ...]:
    """Return the cutting models whose compliance peak the free variables cannot move.

    Each free variable is moved by a factor ``exp(+-step)`` from ``design``; a model whose peak
    (on ``n_points`` log-spaced frequencies over the band, the port model with a digital
    drive's corrections exact at ``design``)
    changes by less than :data:`HOLD_SENSITIVITY` times ``step`` for every variable is held.
    When every cutting model would be held, none is (the worst peak then sets the objective as
    before).

    Parameters
    ----------
    problem : TuningProblem
        The problem.
    design : Design
        Where the sensitivities are taken (the reference start).
    step : float
        The log step.
    n_points : int
        Band frequencies.

    Returns
    -------
    tuple of HeldModel
    """
    if problem.weights[0] <= 0:
        return ()
    cut = list(problem.cutting_models)
    omega = grid(*problem.requirements.band, n_points)
    model = ResponseModel(problem, omega, design)

    def peaks(d):
        # a digital drive's corrections as at the reference (they move by 1e-5 at most:
        # far below what decides here)
        return np.abs(model(d, exact=False)["compliance"][cut]).max(axis=1)

    base = peaks(design)
    sens = np.zeros(len(cut))
    # the peaks between the grid's points (a lightly damped mode falls between them): a held
    # model is capped at its value, so its peak must be the true one
    for v in problem.free:
        lo, hi = (dataclasses.replace(design, **{v: float(np.clip(
            getattr(design, v) * math.exp(s), *problem.bounds[v]))}) for s in (-step, step))
        if lo == hi:
            continue
        span = math.log(getattr(hi, v) / getattr(lo, v))
        sens = np.maximum(sens, np.abs(np.log(peaks(hi) / peaks(lo))) / span)
    held = [i for i in range(len(cut)) if sens[i] < HOLD_SENSITIVITY]
    if len(held) == len(cut):
        return ()
    base = base.copy()
    for i in held:
        base[i] = _refined_peak(problem, design, cut[i], omega,
                                np.abs(model(design, exact=False)["compliance"][cut[i]]))
    out = []
    for i in held:
        m = problem.regimes[cut[i]]
        what = ("the guide ways stick: the presliding contact (sigma0) holds the pads, so "
                "the drive and the viscous C in parallel barely reach the work-piece mode"
                if m.kind in ("presliding", "describing") else
                "the design variables barely reach the mode that sets it")
        out.append(HeldModel(m, float(base[i]), float(sens[i]),
                             f"{m.name}: its peak {base[i]:.4g} m/N moves by at most "
                             f"{100 * sens[i] * step:.2g} % when any free variable changes by "
                             f"{100 * (math.exp(step) - 1):.0f} % ({what}); held there"))
    return tuple(out)


def _refined_peak(problem: TuningProblem, design: Design, index: int, omega: np.ndarray,
                  mag: np.ndarray, rounds: int = 4, n: int = 41) -> float:
    """The compliance peak of model ``index`` refined between the grid's points: each
    local maximum of ``mag`` on ``omega`` within 0.5 % of the grid's largest is zoomed on
    (``rounds`` times ``n`` points across its neighbours), the largest found returned."""
    top = float(mag.max())
    inner = np.nonzero((mag[1:-1] >= mag[:-2]) & (mag[1:-1] >= mag[2:])
                       & (mag[1:-1] >= 0.005 * top))[0] + 1
    candidates = sorted(inner, key=lambda i: -mag[i])[:4] or [int(np.argmax(mag))]
    one = dataclasses.replace(problem, regimes=(problem.regimes[index],), held=(),
                              held_caps=())
    best = top
    for i in candidates:
        lo, hi = omega[max(i - 1, 0)], omega[min(i + 1, omega.size - 1)]
        for _ in range(rounds):
            w = np.linspace(lo, hi, n)
            m = np.abs(ResponseModel(one, w, design)(design, exact=False)["compliance"][0])
            j = int(np.argmax(m))
            best = max(best, float(m[j]))
            lo, hi = w[max(j - 1, 0)], w[min(j + 1, n - 1)]
    return best


@one_thread
def tune(problem: TuningProblem, starts: int = 4, seed: int = 0, max_exchange: int = 30,
         tolerance: float = 1e-6, callback=None, first=()) -> TuningResult:
    """Optimise the free design variables with casadi/IPOPT, then verify with python-control.

    The stages: :func:`stable_starts`, :func:`solve_starts`, :func:`exchange_grids`,
    :func:`predict`, then :func:`~servotune.tuning.verify.verify` and
    :func:`~servotune.tuning.verify.requirement_checks` of the design in every model. The
    problem they solve is written out in :mod:`servotune.tuning.nlp`.

    Parameters
    ----------
    problem : TuningProblem
        Structure, drive, regime models, requirements, bounds and weights.
    starts : int
        Number of starting points (the initial design, or a softened one when it leaves a model
        unstable, plus seeded stable draws within the bounds). Tuning problems of feed axes
        have several local optima; more starts make finding the best more likely.
    seed : int
        Seed of the starting points.
    max_exchange : int
        Largest number of grid-exchange rounds.
    tolerance : float
        Relative agreement between grid and true extrema that ends the exchange.
    callback : casadi.Callback, optional
        IPOPT's iteration callback (e.g. to honour an interruption).
    first : sequence of Design
        Designs to start from before the initial one (:func:`stable_starts`).

    Returns
    -------
    TuningResult
        ``success`` only when every requirement check holds and IPOPT converged. When no
        start reaches a usable optimum but the initial design meets every requirement, the
        initial design, with the reason in ``notes`` ("the optimiser found no better design").
        When the optimum fails only on Ti times the velocity bandwidth above
        ``ti_bandwidth_max`` (a rule the NLP does not carry), the design re-optimised with Ti
        capped at the rule, with the cap in ``notes`` (and in ``active`` when Ti sits at it).

    Raises
    ------
    NoStableStartError
        When no candidate keeps the models stable.
    RequirementsNotMetError
        "requirements infeasible" (IPOPT found the constraints locally infeasible) or
        "requirements not met" (the optimiser stopped otherwise): no start reaches a feasible
        design and the initial design does not meet the requirements either; the message names
        the binding constraint.
    TuningDidNotConvergeError
        "the optimiser found no better design": the frequency constraints were met but the
        objective did not settle, and the initial design does not meet every requirement.

    See Also
    --------
    servotune.design.tune_axis : the design job (regimes, tuning, verdict) around this.
    servotune.tuning.verify.verify : the independent check of a design.
    """
    t_start = time.perf_counter()
    req = problem.requirements
    x0 = problem.initial_design()
    current_bw = (current_loop_bandwidth(problem.drive) if problem.drive is not None else None)
    # 1. stable starts (models no start stabilises are left out and reported)
    start_set = stable_starts(problem, starts, seed, first=first)
    problem, excluded = _kept_models(problem, start_set)
    before = verify(problem, x0)
    reference = start_set.designs[0]
    # the lexicographic objective: the models no free variable moves are held at their value
    held = held_models(problem, reference)
    if held:
        index = {id(m): i for i, m in enumerate(problem.regimes)}
        problem = dataclasses.replace(
            problem, held=tuple(index[id(h.model)] for h in held),
            held_caps=tuple(h.peak * (1.0 + HOLD_SLACK) for h in held))
    h0, s0 = _scale_factors(problem, reference)
    kernels = Kernels(problem, h0, s0)
    gamma = _gamma(problem, reference,
                   ResponseModel(problem, grid(*req.loop_band, 3000), reference))
    grids = _Grids(problem, grid(*req.band, problem.n_grid), grid(*req.loop_band, problem.n_grid),
                   gate_parameters(problem, gamma, current_bw), reference)
    # 2. the starts on the initial grids
    phase = solve_starts(problem, kernels, grids, start_set.designs, callback)
    n_starts = len(start_set.designs)
    if phase.best is None:
        why = _no_optimum(phase.solver, phase.runs, n_starts)
        checks0 = requirement_checks(problem, x0, before, current_bw)
        if not (before.stable and all(c.holds for c in checks0)):
            _raise_infeasible(why, checks0)
        status = phase.runs[-1].stats["return_status"] if phase.runs else None
        return TuningResult(
            problem=problem, initial=x0, design=x0, before=before, after=before,
            predicted=predict(problem, x0), success=True, reasons=(), active=(),
            checks=checks0, excluded=excluded, start=reference, held=held,
            notes=(f"the optimiser found no better design than the initial one ({why}); the "
                   "initial design is kept: it meets every requirement in the dense check. "
                   "More starts (--starts) or other bounds may find a better one",),
            stats=_statistics(n_starts, 0, phase.iterations, 0, grids, problem, status,
                              current_bw, t_start))
    # 3. grid exchange (and the position-loop bandwidth ratio of the gates)
    ex = exchange_grids(problem, kernels, grids, gamma, phase.best, phase.solver, current_bw,
                        max_exchange, tolerance, callback)
    if ex.failed:
        ex = _repaired_exchange(problem, kernels, gamma, ex, current_bw, max_exchange,
                                tolerance, callback)
    # 4. the optimiser's prediction and the independent check
    judged = _judge(problem, ex, reference, tolerance, current_bw)
    notes, iterations = (), phase.iterations + ex.iterations
    if _only_above_ti_rule(judged):
        # the rule Ti w_b <= ti_bandwidth_max is not a row of the NLP: Ti lowered to it and
        # the problem re-solved with Ti capped there
        capped = _ti_capped(judged, kernels, gamma, reference, current_bw, max_exchange,
                            tolerance, callback)
        iterations += capped.iterations
        if capped.judged is not None:
            judged, notes = capped.judged, (capped.note,)
    ex = judged.outcome
    active = _active(problem, ex.design, ex.solver, ex.best)
    cap = judged.problem.bounds["ti"][1] if "ti" in problem.free else None
    if cap is not None and cap < problem.bounds["ti"][1] and ex.design.ti >= cap * (1 - 1e-4):
        active.append(_ti_cap_text(problem, cap))
    return TuningResult(
        problem=problem, initial=x0, design=ex.design, before=before, after=judged.after,
        predicted=judged.prediction, success=not judged.reasons, reasons=judged.reasons,
        active=tuple(active), checks=judged.checks, excluded=excluded, start=reference,
        held=held, notes=notes,
        stats=_statistics(n_starts, phase.polished, iterations, ex.rounds, ex.grids, problem,
                          ex.best.stats["return_status"], current_bw, t_start))


@dataclass(frozen=True)
class _Judged:
    """An exchange's outcome with the optimiser's prediction, the independent check of its
    design and the reasons it fails (empty when it succeeds); ``problem`` is the problem it
    was solved in (its bound of Ti may be capped by :func:`_ti_capped`)."""

    problem: TuningProblem
    outcome: ExchangeOutcome
    prediction: Prediction
    after: Performance
    checks: tuple[RequirementCheck, ...]
    reasons: tuple[str, ...]


def _judge(problem: TuningProblem, ex: ExchangeOutcome, reference: Design, tolerance: float,
           current_bw: float | None) -> _Judged:
    """Stage 4: the optimiser's prediction and the independent check of the exchange's
    design, and the reasons it fails."""
    pred = predict(problem, ex.design, reference)
    reasons = []
    if ex.failed:
        reasons.append("the optimiser could not satisfy the constraints at frequencies added by "
                       f"the grid exchange (round {ex.rounds}); the design is the last feasible "
                       "one on the previous grid")
    elif ex.worst > max(tolerance, 1e-4):
        reasons.append(f"the frequency grid did not converge (true extrema {ex.worst:.2g} "
                       f"beyond the grid after {ex.rounds} exchange rounds)")
    after = verify(problem, ex.design)
    checks = requirement_checks(problem, ex.design, after, current_bw)
    reasons += [f"verification: {c.text}" for c in checks if not c.holds]
    if after.stable and abs(after.peak_compliance / pred.peak_compliance - 1) > 0.01:
        reasons.append(
            f"verification: the state-space compliance peak {after.peak_compliance:.4g} m/N "
            f"differs from the optimiser's {pred.peak_compliance:.4g} m/N by more than 1%")
    return _Judged(problem, ex, pred, after, checks, tuple(reasons))


def _above_ti_rule(check: RequirementCheck) -> bool:
    """A failed check of Ti w_b above its rule (the upper bound, not a row of the NLP)."""
    return (not check.holds and check.requirement.startswith("Ti") and check.value is not None
            and check.limit is not None and check.value > check.limit)


def _only_above_ti_rule(judged: _Judged) -> bool:
    """The design is stable and fails only on Ti w_b above its rule."""
    failed = [c for c in judged.checks if not c.holds]
    return (judged.after.stable and bool(failed) and len(failed) == len(judged.reasons)
            and all(_above_ti_rule(c) for c in failed))


def _ti_cap_text(problem: TuningProblem, cap: float) -> str:
    """How Ti's cap is reported among the active constraints."""
    return (f"Ti capped at {cap:.4g} s by the rule Ti x w_b <= ti_bandwidth_max "
            f"({problem.requirements.ti_bandwidth_max:g})")


#: Largest number of rounds of Ti lowered to its bandwidth rule and the problem re-solved
#: (the bandwidth moves with Kp when Ti changes).
TI_RULE_ROUNDS = 2


@dataclass(frozen=True)
class _TiCapped:
    """The outcome of :func:`_ti_capped`: the judged re-solve (None when it did not
    succeed), the note that says so, and the IPOPT iterations it took."""

    judged: _Judged | None
    note: str
    iterations: int


def _ti_capped(judged: _Judged, kernels: Kernels, gamma: np.ndarray, reference: Design,
               current_bw: float | None, max_exchange: int, tolerance: float,
               callback) -> _TiCapped:
    """When the design fails only on Ti w_b above its rule: what an engineer does, Ti lowered
    to the rule (:func:`repair`) and the problem re-solved from there with Ti at most that
    value (its upper bound capped), on the refined grids and exchanged again; up to
    :data:`TI_RULE_ROUNDS` times. The re-solve counts only when it converges, is stable and
    its dense check holds; else the given outcome stands."""
    problem = judged.problem
    lo, hi = problem.bounds["ti"]
    x0, first_ti = problem.initial_design(), judged.outcome.design.ti
    last, iterations = judged, 0
    for _ in range(TI_RULE_ROUNDS):
        start = repair(problem, last.outcome.design, current_bw)
        if start is None or not x0.ti <= start.ti < hi:
            # (the cap may not fall below the initial Ti: the problem must hold its start)
            break
        capped = dataclasses.replace(problem, bounds={**problem.bounds, "ti": (lo, start.ti)})
        ex = last.outcome
        solver = Solver(capped, kernels, ex.grids.band.size, ex.grids.loop.size, max_iter=300,
                        callback=callback)
        sol = solver.solve(start, ex.grids.band_rows, ex.grids.loop_rows)
        iterations += sol.stats["iter_count"]
        if not (sol.converged and all(model_stability(capped, sol.design))):
            break
        again = exchange_grids(capped, kernels, ex.grids, gamma, sol, solver, current_bw,
                               max_exchange, tolerance, callback)
        iterations += again.iterations
        if again.failed:
            break
        last = _judge(capped, again, reference, tolerance, current_bw)
        if not last.reasons:
            req = problem.requirements
            note = (f"{_ti_cap_text(problem, start.ti)}: the optimum without the cap had Ti "
                    f"{first_ti:.4g} s, above the rule (checked on the design, not a constraint "
                    f"of the optimiser), so Ti was lowered to the rule with 10 % to spare and "
                    f"the design re-optimised with Ti at most there; the bounds of Ti as given "
                    f"({lo:.4g}, {hi:.4g}) s. Ti x w_b now "
                    + ", ".join(f"{c.value:.3g}" for c in last.checks
                                if c.requirement.startswith("Ti") and c.value is not None)
                    + f" (within [{req.ti_bandwidth_min:g}, {req.ti_bandwidth_max:g}])")
            return _TiCapped(last, note, iterations)
        if not _only_above_ti_rule(last):
            break
    return _TiCapped(None, "", iterations)


#: Largest number of repair steps of a design the exchange could not make feasible.
REPAIR_STEPS = 12


def repair(problem: TuningProblem, design: Design, current_bw: float | None):
    """Return a design near ``design`` that meets every requirement in the dense check, or
    None: the moves a commissioning engineer makes, one step per failed check (Ms of the
    velocity loop or instability: Kp x 0.8; Ti below its bandwidth rule: Ti raised to it with
    10 % to spare; Ti above it: Ti lowered to it with 10 % to spare; the loop hierarchy or the
    position loop's Ms: Kv x 0.7), within the bounds and the free variables, up to
    :data:`REPAIR_STEPS` times.

    Parameters
    ----------
    problem : TuningProblem
        The problem.
    design : Design
        Where to start (e.g. the exchange's last design).
    current_bw : float or None
        Current-loop bandwidth [rad/s].

    Returns
    -------
    Design or None
        The repaired design, or None when the steps do not reach one.
    """
    d = design
    for _ in range(REPAIR_STEPS):
        perf = verify(problem, d)
        failed = [c for c in requirement_checks(problem, d, perf, current_bw) if not c.holds]
        if perf.stable and not failed:
            return d
        change = {}
        if not perf.stable or any(c.requirement == "Ms velocity loop" for c in failed):
            change["kp"] = d.kp * 0.8
        raised, lowered = [], []
        for c in failed:
            if c.requirement.startswith("Ti") and c.value is not None and c.limit:
                # Ti w_b against the rule: Ti moved to it with 10 % to spare (w_b barely moves
                # with Ti); raised when one model is below, else lowered to the strictest
                if c.value < c.limit:
                    raised.append(d.ti * c.limit / c.value * 1.1)
                else:
                    lowered.append(d.ti * c.limit / c.value / 1.1)
            elif c.requirement in ("loop hierarchy", "Ms position loop"):
                change["kv"] = d.kv * 0.7
        if raised or lowered:
            change["ti"] = max(raised) if raised else min(lowered)
        change = {v: float(np.clip(x, *problem.bounds[v])) for v, x in change.items()
                  if v in problem.free}
        if not change or all(change[v] == getattr(d, v) for v in change):
            return None
        d = dataclasses.replace(d, **change)
    return None


def _repaired_exchange(problem, kernels, gamma, ex: ExchangeOutcome, current_bw,
                       max_exchange, tolerance, callback) -> ExchangeOutcome:
    """When the exchange could not make its design feasible at the frequencies it added: the
    design repaired (:func:`repair`), solved again on the refined grids and exchanged from
    there; the failed outcome stands when that does not succeed."""
    start = repair(problem, ex.design, current_bw)
    if start is None:
        return ex
    sol = ex.solver.solve(start, ex.grids.band_rows, ex.grids.loop_rows)
    if not (sol.converged and all(model_stability(problem, sol.design))):
        return ex
    again = exchange_grids(problem, kernels, ex.grids, gamma, sol, ex.solver, current_bw,
                           max_exchange, tolerance, callback)
    if again.failed:
        return ex
    return dataclasses.replace(again, iterations=again.iterations + ex.iterations
                               + sol.stats["iter_count"])


def _exclusion_reason(model) -> str:
    slope = model.slope()
    if slope is not None and slope < 0:
        return (f"unstable for every design tried: the sliding friction falls with speed there "
                f"(slope {slope:.3g} N s/m below the Stribeck speed) and feeds a self-excited "
                "oscillation (of the pads on their contact stiffness, or stick-slip of the "
                "slide); feed faster, or add viscous damping")
    return "unstable for every design tried"


def _same_optimum(a: Solution, b: Solution, free) -> bool:
    """Two optima agree: objectives to 1e-6 and every free variable to 1e-3 (relative)."""
    fa, fb = a.objective, b.objective
    return (abs(fa - fb) <= 1e-6 * max(abs(fa), abs(fb), 1e-300) and all(
        abs(math.log(getattr(a.design, v) / getattr(b.design, v))) <= 1e-3 for v in free))


@dataclass(frozen=True)
class _NoOptimum:
    """Why no start reached a usable optimum: ``kind`` "unstable" (the optima that meet the
    frequency constraints all have an unstable loop), "objective" (the constraints were met,
    only the objective's bound did not settle) or "constraint" (``constraint`` was violated
    by ``violation``, relative to its limit, at the best start)."""

    kind: str
    n_starts: int
    status: str
    constraint: str = ""
    violation: float = 0.0

    def __str__(self) -> str:
        if self.kind == "unstable":
            return (f"the optima of all {self.n_starts} starts that meet the frequency "
                    "constraints have an unstable loop")
        if self.kind == "objective":
            return (f"IPOPT did not converge from any of {self.n_starts} starts ({self.status}); "
                    "the frequency constraints were met, only the objective did not settle")
        return (f"'{self.constraint}' still violated at the best of {self.n_starts} starts "
                f"(IPOPT: {self.status})")


#: IPOPT's return statuses that say the constraints are (locally) infeasible; any other
#: stop of a start that violates a constraint proves nothing about feasibility.
LOCALLY_INFEASIBLE = ("Infeasible_Problem_Detected", "Restoration_Failed")

#: What an axis file changes to relax each kind of constraint (by the start of its name).
FIXES = (
    ("thrust", "a stronger motor ([drive.motor] torque_continuous, torque_peak, torque_speed), "
               "a lower rapid speed or acceleration ([operation] rapid_speed, acceleration), "
               "a smaller reserve ([requirements] thrust_margin) or less guide-way friction "
               "([friction]; the floor of C is the guide ways' own sigma2, [tuning] c)"),
    ("Ms", "the margins ([requirements] ms_velocity_max, ms_position_max, "
           "phase_margin_min_deg, gain_margin_min_db), or a faster drive ([drive.sampling] "
           "periods and computation_delay) and fewer set-point filters ([drive.filters])"),
    ("loop hierarchy", "[requirements] bandwidth_ratio_min, or the bounds of Kv ([tuning] kv)"),
    ("current loop", "[requirements] current_bandwidth_ratio_min, or a faster current loop "
                     "([drive.current_loop] kp, ti; [drive.sampling] current_period)"),
    ("Ti", "[requirements] ti_bandwidth_min, ti_bandwidth_max, or the bounds of Ti ([tuning] "
           "ti)"),
    ("kv_min", "the least Kv ([requirements] kv_min) or the bounds of Kv ([tuning] kv)"),
)


def _fixes(constraint: str) -> str:
    """The axis fields that relax a constraint, or the generic advice."""
    for prefix, text in FIXES:
        if constraint.startswith(prefix):
            return text
    return "relax it or widen the bounds of the free variables"


def _no_optimum(solver: Solver, runs, n_starts) -> _NoOptimum:
    """Why none of the runs gave a usable optimum."""
    feasible = [r for r in runs if r.converged]
    if feasible:
        return _NoOptimum("unstable", len(feasible), feasible[0].stats["return_status"])
    worst_run = min(runs, key=lambda r: max(solver.violations(r.g).values(), default=0.0))
    viol = solver.violations(worst_run.g)
    worst = max(viol, key=viol.get) if viol else "compliance peak"
    status = worst_run.stats["return_status"]
    if worst in ("compliance peak", "chatter", "worst peak") or viol[worst] <= 1e-6:
        return _NoOptimum("objective", n_starts, status)
    return _NoOptimum("constraint", n_starts, status, worst, viol[worst])


def _raise_infeasible(why: _NoOptimum, initial_checks):
    """The error when no start gave a usable optimum and the initial design does not meet the
    requirements either."""
    failed = [c.text for c in initial_checks if not c.holds]
    initial = ("the initial design does not meet the requirements: " + "; ".join(failed[:3])
               + (" ..." if len(failed) > 3 else "")) if failed else \
        "the initial design leaves a regime model unstable"
    if why.kind == "objective":
        raise TuningDidNotConvergeError(
            f"the optimiser found no better design: {why}, and {initial}; add starts "
            "(--starts) or narrow the bounds")
    if why.kind == "unstable":
        raise RequirementsNotMetError(
            "requirements infeasible within the bounds: the binding constraint is closed-loop "
            f"stability ({why}), and {initial}; relax the Ms limits, narrow the bounds towards "
            "the initial design or add starts")
    if why.status in LOCALLY_INFEASIBLE:
        raise RequirementsNotMetError(
            f"requirements infeasible within the bounds: the binding constraint is "
            f"'{why.constraint}' ({why}), and {initial}; to fix: {_fixes(why.constraint)}")
    # the optimiser stopped (an iteration limit, a failed line search): no design found, but
    # none shown not to exist either
    raise RequirementsNotMetError(
        f"requirements not met: no start reached a design that meets them within the bounds "
        f"(the constraint still violated is '{why.constraint}': {why}; the optimiser stopped "
        f"without showing that no such design exists), and {initial}; to fix: "
        f"{_fixes(why.constraint)}, or try more starts (--starts)")


def _active(problem: TuningProblem, design: Design, solver: Solver, best: Solution) -> list:
    out = []
    for v in problem.free:
        lo, hi = problem.bounds[v]
        val = getattr(design, v)
        if val <= lo * (1 + 1e-4):  # IPOPT stops a little inside its bounds
            out.append(f"{v} at its lower bound {lo:.4g}")
        if val >= hi * (1 - 1e-4):
            out.append(f"{v} at its upper bound {hi:.4g}")
    if len(best.g) == len(solver.groups):
        out += solver.active(best.g)
    return out
