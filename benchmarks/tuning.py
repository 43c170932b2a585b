"""Tuning the bundled axis: casadi/IPOPT against scipy on the same objective and constraints.

Case: ``models/paper_x_axis`` with the free variables of its ``[tuning]`` (C, Kv, Kp, Ti) and
every regime model the axis works in (standing: presliding and the describing function at the
process amplitude; feeding at each feed speed: LuGre linearised about sliding), set up as
``servotune tune`` sets it up (``servotune.design.tuning_problem`` with the axis' settings: the
digital drive as the sampled-data system it is, the thrust budget). The problem is the NLP of
:mod:`servotune.tuning.nlp`::

    minimise    max_m t_m + mean_weight mean_m t_m + HELD_WEIGHT mean_k t_k
                + tracking_weight Kv0/Kv + c_cost_weight (C - C_lo)/C_span
                (t = peak |h| / h0; m the movable cutting models, k the held ones)
    subject to  t_k <= cap_k / h0 for every held model k;
                Ms of the velocity and of the position loop in every model (the Ms disk),
                the loop hierarchy (velocity-loop bandwidth >= N x the position loop's), the
                integral time's lower bound (Ti x velocity bandwidth >= r_min) and the current
                loop above the velocity loop, in every moving model, as the NLP's smooth gates;
                the thrust budget (C v within the motor's usable thrust at each case); Kv >= Kv_min;
                closed-loop stability in every model; bounds.

The held models are those :func:`servotune.tuning.solve.held_models` finds at casadi's
reference start (cutting models no free variable moves, e.g. the standing regime whose pads
stick), with their caps, as ``tune`` sets them in the problem it returns; the scipy methods
take them from there. The upper bound of Ti x bandwidth is not a row of the NLP (casadi's
:mod:`servotune.tuning.requirements.integral_time` judges it on the design only), so it is
not one here either: the common evaluator below checks it for every method.

All methods work in the same log-scaled variables ``u = log(x / x0)`` within the same bounds.

* ``casadi``: :func:`servotune.tuning.tune` as shipped (IPOPT, exact derivatives, grid exchange,
  several starts; its time includes its own verification, :func:`servotune.tuning.verify`, of
  the initial and the final design in every regime model).
* ``scipy_de``: ``scipy.optimize.differential_evolution`` with
  ``constraints=NonlinearConstraint(...)`` (Lampinen's feasibility rules: no penalty weight),
  default polish (trust-constr); its budget is checked once per generation and the polish
  runs after it, so its run can exceed the budget.
* ``scipy_nm``: ``scipy.optimize.minimize(method="Nelder-Mead")`` with bounds, from the same
  starting points as casadi (:func:`servotune.tuning.solve.stable_starts`: the initial design, or
  a softer velocity loop when the initial one is unstable, plus the same seeded stable draws),
  restarted from its own result until it stops improving (the budget is checked between
  runs); constraints by an exact (L1) penalty ``f + rho * sum(max(0, 1 - g_i))`` with
  rho = 10, unstable designs get +inf.
* ``scipy_slsqp``: ``scipy.optimize.minimize(method="SLSQP")``, gradients by finite
  differences (scipy's default), with the bounds and the constraints as inequality
  constraints, from the same starting points as Nelder-Mead, each restarted from its run's best
  feasible design until that improves by less than 1e-8 relative (the budget is checked
  between runs). The objective's maxima over frequencies and over the movable models are
  written in epigraph form (:class:`Epigraph`: extra variables t_m >= |h_m(w_i)| / h0 at every
  band frequency of each cutting model, T >= t_m of each movable one; the objective is then
  smooth in the variables);
  the Ms, gate, thrust and Kv rows are the other methods' (each the smallest value over the
  grid); stability is the same check, entered as its continuous margin (the smallest
  -Re p / |p| over the monodromy exponents, rigid-body ones left out: > 0 when stable) since a
  +1/-1 flag has no finite-difference gradient.

The scipy methods evaluate exactly the functions casadi optimises. The responses are those of
:class:`servotune.tuning.ResponseModel`, the port model of the NLP evaluated numerically (the
same code builds casadi's kernels): the structure's port receptances coupled with each model's
contact, and, for the digital drive, the sampled-data loop (:mod:`servotune.digital.cascade`:
the zero-order hold of the voltage, the controllers' difference equations at their own rates,
the velocity and position loops lifted) with its per-model corrections (the hold's aliases and
the lifts' higher terms, :func:`servotune.tuning.ports.sampled_corrections`) computed once at
casadi's reference start and frozen there (``ResponseModel(problem, omega, reference)`` called
with ``exact=False``), as casadi freezes them at that start for its whole run. They are taken on
ONE fixed log grid over the loop band (``--grid`` points; the compliance on its part inside the
objective band), so a design costs one call; the gated rows are those of the NLP (the same gate
constants, :func:`servotune.tuning.nlp.gate_parameters`), with the ratio of the position loop's
bandwidth to Kv taken from the design itself (casadi updates it between its exchange rounds);
h0 and s0 are the NLP's scale factors at casadi's reference start. How far the frozen
corrections are from the exact ones at casadi's final design is reported.

Stability is decided by the tuner's own check, :func:`servotune.tuning.solve.model_stability`:
for the digital drive the sampled-data closed loop of each model
(:class:`servotune.digital.SampledAxis`: the plant discretised under the zero-order hold, the
controllers' difference equations, the monodromy matrix over the position period; stable when
every multiplier lies inside the unit circle, with the rounding allowance of
``require_stable``). casadi keeps stability by continuity from stable starts and runs that
check on its starts and on every converged solution; the scipy methods have no such
continuity (differential evolution draws designs anywhere within the bounds), so they run it on
every design they evaluate: one eigenvalue problem of the monodromy matrix per model. Its share
of each scipy method's time is reported, and the speedup without it
(``speedup_without_stability_checks``) beside the speedup.

Every final design is judged by ONE common evaluator: :func:`servotune.tuning.verify` (each
model's closed loop built anew, for the digital drive the exact sampled-data system,
:class:`servotune.digital.SampledAxis`, with no frozen corrections; its stability, compliance
and loops on dense grids none of the methods used) and
:func:`servotune.tuning.requirement_checks` (every requirement in every model, as the design job
judges it), plus the objective formula on the verified peaks.

Speedup at equal objective: each method records when its best feasible design on its own grid
improves; the time scipy needs to reach casadi's objective (casadi's design evaluated on
scipy's grid by the same formula, within ``--match`` relative) is compared with the time of
the whole casadi run. The top-level ``speedup`` is against the FASTEST scipy method that gets
there (``speedup_against``); a method that never gets there within its budget does not count
(``methods_not_reaching_casadi_objective``; its own entry gives a lower bound, its run time /
casadi time), and only when none gets there is the top-level figure the smallest such lower
bound (``speedup_is_lower_bound``). The design with which a scipy method
first gets there is judged by the common evaluator as well (``design_at_casadi_objective``,
after the run, untimed): a fixed grid can miss an Ms peak between its points, which casadi's
grid exchange finds.

BLAS and OpenMP are held to one thread for all methods (the matrices are small).

Usage: ``python benchmarks/tuning.py [--json] [--methods de,nm,slsqp] [--de-budget S]
[--nm-budget S] [--slsqp-budget S] [--grid N]``
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

import casadi  # noqa: E402
import numpy as np  # noqa: E402
import scipy  # noqa: E402
from scipy.optimize import NonlinearConstraint, differential_evolution, minimize  # noqa: E402
from scipy.special import expit  # noqa: E402

from servotune.axis import load_axis  # noqa: E402
from servotune.design import tuning_problem  # noqa: E402
from servotune.digital import SampledAxis  # noqa: E402
from servotune.drive import current_loop_bandwidth  # noqa: E402
from servotune.tuning import Design, ResponseModel, requirement_checks, tune, verify  # noqa: E402
from servotune.tuning import solve as tuning_solve  # noqa: E402
from servotune.tuning.nlp import GATE_SHARPNESS, HELD_WEIGHT, gate_parameters  # noqa: E402
from servotune.tuning.ports import is_sampled  # noqa: E402
from servotune.tuning.solve import model_stability  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RHO = 10.0
STABILITY_SCALE = 100.0  # SLSQP: the stability margin's row (-Re p / |p|) scaled to order 1


class Stability:
    """Closed-loop stability of a design in every regime model by the tuner's own check
    (:func:`servotune.tuning.solve.model_stability`: the sampled-data loop's monodromy
    multipliers for a digital drive), with the number of checks and the time they took."""

    def __init__(self, problem):
        self.problem = problem
        self.calls = 0
        self.time_s = 0.0
        self.margin = 0.0

    def stable(self, d: Design) -> bool:
        """The check's verdict; :attr:`margin` is then set to a continuous measure of it for a
        gradient-based method (see :meth:`_margin`)."""
        t0 = time.perf_counter()
        try:
            p = self.problem
            if not is_sampled(p):
                ok = all(model_stability(p, d))
                self.margin = 1.0 if ok else -1.0
                return ok
            # model_stability's own path for the sampled drive, its multipliers kept
            drive = p.drive_for(d)
            axes = [SampledAxis(p.structure, drive, m.contact(d.c) if p.pads else None, p.pads)
                    for m in p.regimes]
            ok = all(a.is_stable() for a in axes)
            self.margin = self._margin(axes)
            return ok
        finally:
            self.calls += 1
            self.time_s += time.perf_counter() - t0

    @staticmethod
    def _margin(axes) -> float:
        """The smallest -Re p / |p| over the monodromy exponents p of every model (p = log of
        a multiplier / the frame), those below 1e-3 1/s (a rigid-body travel at rounding) and
        of zero multipliers left out: > 0 when stable, continuous in the design."""
        worst = math.inf
        for a in axes:
            p = a._stability[1]
            p = p[np.isfinite(p.real) & (np.abs(p) > 1e-3)]
            if p.size:
                worst = min(worst, float((-p.real / np.abs(p)).min()))
        return worst if math.isfinite(worst) else 1.0

    def restart(self):
        self.calls, self.time_s = 0, 0.0


def _gate(y):
    return expit(GATE_SHARPNESS * y)


class GridObjective:
    """The tuning objective and constraints of a problem on one fixed grid (numpy)."""

    def __init__(self, problem, n_grid: int, stability: Stability, reference: Design,
                 current_bandwidth):
        req = problem.requirements
        lo, hi = min(req.band[0], req.loop_band[0]), max(req.band[1], req.loop_band[1])
        self.problem = problem
        # casadi's port model: a digital drive's corrections exact at its reference start and
        # kept there (called with exact=False below)
        self.model = ResponseModel(problem, np.geomspace(lo, hi, n_grid), reference)
        w = self.model.omega
        self.in_band = (w >= req.band[0]) & (w <= req.band[1])
        self.in_loop = (w >= req.loop_band[0]) & (w <= req.loop_band[1])
        self.log_w_loop = np.log(w[self.in_loop])
        self.cut = list(problem.cutting_models)
        # the lexicographic objective: held cutting models (capped, weighted last) and the
        # movable ones (their worst peak and mean), as the NLP of the problem tune() returns
        self.held = [self.cut.index(m) for m in problem.held if m in self.cut]
        self.movable = [i for i in range(len(self.cut)) if i not in self.held]
        self.caps = [problem.held_caps[list(problem.held).index(self.cut[i])] for i in self.held]
        self.x0 = problem.initial_design()
        self.free = problem.free
        self.lower = np.array([math.log(problem.bounds[v][0] / getattr(self.x0, v))
                               for v in self.free])
        self.upper = np.array([math.log(problem.bounds[v][1] / getattr(self.x0, v))
                               for v in self.free])
        self.ms = [req.ms_limit("velocity"), req.ms_limit("position")]
        self.kv_min = req.kv_min if "kv" in self.free else 0.0
        self.thrust = ([(f, v, u) for f, v, u, _ in problem.thrust.linear_form() if v > 0]
                       if problem.thrust is not None and "c" in self.free else [])
        self.current_bandwidth = current_bandwidth
        self.stability = stability
        self.mu = problem.chatter.mu if problem.chatter is not None else 1.0
        # the NLP's scale factors (peak and -min Re(mu G) of the reference start)
        self.h0, self.s0 = tuning_solve._scale_factors(problem, reference)
        self._cache = {}
        self._responses = {}
        self.evaluations = 0
        self.t0 = time.perf_counter()
        # (elapsed s, best feasible objective so far, stability s so far, its u)
        self.history = []

    def design(self, u) -> Design:
        return replace(self.x0, **{v: float(getattr(self.x0, v) * math.exp(u[i]))
                                   for i, v in enumerate(self.free)})

    def u_of(self, d: Design) -> np.ndarray:
        return np.array([math.log(getattr(d, v) / getattr(self.x0, v)) for v in self.free])

    def objective_of(self, d: Design, peaks, min_re) -> float:
        """The NLP's objective from the cutting models' peaks [m/N] and min Re(mu G) [m/N]."""
        p = self.problem
        w_peak, w_chatter = p.weights
        f = 0.0
        if w_peak:
            t = np.asarray(peaks) / self.h0
            t_mov = t[self.movable]
            f += w_peak * (float(t_mov.max()) + p.mean_weight * float(t_mov.mean()))
            if self.held:
                f += w_peak * HELD_WEIGHT * float(t[self.held].mean())
        if w_chatter:
            f += w_chatter * float(-min_re) / self.s0
        if "kv" in self.free and p.tracking_weight:
            f += p.tracking_weight * self.x0.kv / d.kv
        if p.c_cost is not None:
            c_lo, span = p.c_cost
            f += p.c_cost_weight * (d.c - c_lo) / span
        return f

    def gate_rows(self, d: Design, lv: np.ndarray, lp: np.ndarray) -> list[float]:
        """Smallest value of each gated row of the NLP over the loop grid, every model."""
        p, req = self.problem, self.problem.requirements
        w = self.model.omega[self.in_loop]
        gamma = np.array([max(tuning_solve._bandwidth(w, lp[m]) / d.kv, 1e-3)
                          for m in range(lp.shape[0])])
        gates = gate_parameters(p, gamma, self.current_bandwidth)
        lw, off, out = self.log_w_loop, 2.0, []
        for m in range(lv.shape[0]):
            on_h, edge_h, on_lo, edge_lo, _, _, on_i, edge_i = gates[m]
            tv2 = np.abs(lv[m]) ** 2 / np.abs(1.0 + lv[m]) ** 2
            up, down = (tv2 - 0.5) / (tv2 + 0.5), (0.5 - tv2) / (0.5 + tv2)
            if req.bandwidth_ratio_min > 0:
                out.append(up + _gate(lw - (edge_h + math.log(d.kv))) + off * (1 - on_h))
            if req.ti_bandwidth_min > 0:   # (the upper bound is no row of the NLP)
                out.append(up + _gate(lw - (edge_lo - math.log(d.ti))) + off * (1 - on_lo))
            if req.current_bandwidth_ratio_min > 0:
                out.append(down + _gate(edge_i - lw) + _gate(lw - edge_i - math.log(1.25))
                           + off * (1 - on_i))
        return [float(r.min()) for r in out]

    def values(self, u):
        """(objective, constraint values g (feasible when all >= 1), stable)."""
        key = tuple(float(x) for x in u)
        if key in self._cache:
            return self._cache[key]
        self.evaluations += 1
        d = self.design(u)
        res = self.model(d, exact=False)
        h = res["compliance"][self.cut][:, self.in_band]
        peaks = np.abs(h).max(axis=1)
        f = self.objective_of(d, peaks, float((self.mu * h.real).min()))
        lv = res["loop_velocity"][:, self.in_loop]
        lp = res["loop_position"][:, self.in_loop]
        g = [limit * float(np.abs(1.0 + loop).min())
             for limit, loop in zip(self.ms, (lv, lp), strict=True)]
        g += [cap / peaks[i] for i, cap in zip(self.held, self.caps, strict=True)]
        g += [1.0 + v for v in self.gate_rows(d, lv, lp)]
        g += [2.0 - (fixed + d.c * speed) / usable for fixed, speed, usable in self.thrust]
        if self.kv_min > 0:
            g.append(d.kv / self.kv_min)
        stable = self.stability.stable(d)
        out = (f, np.array(g), stable)
        if len(self._cache) > 64:
            self._cache.clear()
            self._responses.clear()
        self._cache[key] = out
        # the per-frequency terms behind the objective's maxima (the epigraph rows)
        self._responses[key] = (np.abs(h) / self.h0, (self.mu * h.real).min(axis=0) / self.s0,
                                self.stability.margin)
        if stable and np.all(out[1] >= 1.0) and (not self.history or f < self.history[-1][1]):
            self.history.append((time.perf_counter() - self.t0, f, self.stability.time_s,
                                 np.array(u, dtype=float)))
        return out

    def restart_clock(self):
        self.t0 = time.perf_counter()
        self.history = []
        self.evaluations = 0
        self.stability.restart()

    def reached(self, target: float, rtol: float) -> tuple[float, float, np.ndarray] | None:
        """(elapsed s, of which in stability checks s, the design's u) when the best feasible
        objective first came within ``rtol`` of ``target``, or None."""
        for t, f, t_stab, u in self.history:
            if f <= target * (1.0 + rtol):
                return t, t_stab, u
        return None

    def time_to_reach(self, target: float, rtol: float) -> float | None:
        hit = self.reached(target, rtol)
        return None if hit is None else hit[0]

    # scipy interfaces ------------------------------------------------------------------
    def objective(self, u) -> float:
        return self.values(u)[0]

    def constraints(self, u) -> np.ndarray:
        _, g, stable = self.values(u)
        return np.append(g, 1.0 if stable else -1.0)

    def penalised(self, u) -> float:
        f, g, stable = self.values(u)
        if not stable:
            return math.inf
        return f + RHO * float(np.maximum(0.0, 1.0 - g).sum())

    def responses(self, u) -> tuple[np.ndarray, np.ndarray, float]:
        """(|h| / h0 of each cutting model on the objective band, min over the cutting models of
        Re(mu h) / s0 on the band, the stability margin of :class:`Stability`) at ``u``: the
        terms whose maxima make the objective."""
        self.values(u)
        return self._responses[tuple(float(x) for x in u)]


class Epigraph:
    """The objective's maxima over frequencies (and over the movable models) in epigraph form
    for a gradient-based method: variables z = (u, t_1..t_M, T, r) with t_m >= |h_m(w_i)| / h0
    at every band frequency of cutting model m, T >= t_m of every movable model, and, with a
    chatter weight, r >= -Re(mu h(w_i)) / s0; minimise the NLP's objective with T, t and r in
    place of the maxima (the held models' caps become t_k <= cap_k / h0). The other rows are
    those of :meth:`GridObjective.constraints` (the same callables as the other scipy methods:
    the Ms, gate, thrust and Kv rows), shifted to >= 0, and the same stability check as its
    continuous margin (:meth:`Stability._margin`, x STABILITY_SCALE) in place of the +1/-1
    entry, which gives a finite-difference gradient nothing to follow."""

    def __init__(self, grid: GridObjective):
        self.grid = grid
        p = grid.problem
        self.n = len(grid.free)
        self.m = len(grid.cut)
        self.w_peak, self.w_chatter = (float(w) for w in p.weights)
        # the rows of GridObjective.values' g that the epigraph replaces: the held caps
        self.n_ms = len(grid.ms)
        self.n_caps = len(grid.held)

    def split(self, z):
        z = np.asarray(z, dtype=float)
        n, m = self.n, self.m
        return z[:n], z[n:n + m], z[n + m], z[n + m + 1]

    def start(self, u) -> np.ndarray:
        """The epigraph variables at their smallest feasible values for the design ``u``."""
        a, re_min, _ = self.grid.responses(u)
        t = a.max(axis=1)
        return np.concatenate([u, t, [t[self.grid.movable].max(), max(-re_min.min(), 0.0)]])

    def bounds(self) -> list[tuple[float, float]]:
        return (list(zip(self.grid.lower, self.grid.upper, strict=True))
                + [(0.0, None)] * (self.m + 1) + [(None, None)])

    def objective(self, z) -> float:
        u, t, big_t, r = self.split(z)
        g, p = self.grid, self.grid.problem
        d = g.design(u)
        f = 0.0
        if self.w_peak:
            f += self.w_peak * (big_t + p.mean_weight * float(t[g.movable].mean()))
            if g.held:
                f += self.w_peak * HELD_WEIGHT * float(t[g.held].mean())
        if self.w_chatter:
            f += self.w_chatter * r
        if "kv" in g.free and p.tracking_weight:
            f += p.tracking_weight * g.x0.kv / d.kv
        if p.c_cost is not None:
            c_lo, span = p.c_cost
            f += p.c_cost_weight * (d.c - c_lo) / span
        return float(f)

    def constraints(self, z) -> np.ndarray:
        u, t, big_t, r = self.split(z)
        g = self.grid
        a, re_min, margin = g.responses(u)
        rows = [(t[:, None] - a).ravel(), big_t - t[g.movable]]
        if self.w_chatter:
            rows.append(r + re_min)
        if g.held:
            rows.append(np.array([cap / g.h0 - t[i]
                                  for i, cap in zip(g.held, g.caps, strict=True)]))
        other = g.constraints(u)[:-1] - 1.0
        keep = np.ones(len(other), dtype=bool)
        keep[self.n_ms:self.n_ms + self.n_caps] = False   # the caps, as rows on t above
        rows.append(other[keep])
        # stability: the same check, as its continuous margin in place of the +1/-1 entry
        rows.append([STABILITY_SCALE * margin])
        return np.concatenate(rows)


def corrections_deviation(grid: GridObjective, design: Design) -> dict:
    """How far the port model with the corrections frozen at the reference is from the one
    with them exact at ``design``, on the scipy grid: the largest difference of each response
    relative to its largest magnitude (the compliance in the objective band, the loops in the
    loop band), and the objective by the same formula."""
    if not grid.model.data.sampled:
        return {}
    frozen, exact = grid.model(design, exact=False), grid.model(design)
    parts = {"compliance": grid.in_band, "loop_velocity": grid.in_loop,
             "loop_position": grid.in_loop}
    out = {}
    for key, sel in parts.items():
        a, b = frozen[key][:, sel], exact[key][:, sel]
        out[key] = float(np.nanmax(np.abs(a - b)) / np.nanmax(np.abs(b)))
    h = exact["compliance"][grid.cut][:, grid.in_band]
    out["objective_exact_corrections"] = grid.objective_of(
        design, np.abs(h).max(axis=1), float((grid.mu * h.real).min()))
    return out


def common_evaluation(grid: GridObjective, design: Design) -> dict:
    """The independent evaluator: :func:`servotune.tuning.verify` in every regime model, every
    requirement check, and the objective formula on the verified peaks."""
    problem = grid.problem
    perf = verify(problem, design)
    checks = requirement_checks(problem, design, perf, grid.current_bandwidth)
    failed = [c.text for c in checks if not c.holds]
    out = {"design": design.to_dict(), "stable": perf.stable, "feasible": not failed,
           "failed_checks": failed}
    if not perf.stable:
        return out
    models = [perf.models[m] for m in grid.cut]
    peaks = [mp.peak_compliance for mp in models]
    min_re = 0.0
    if problem.chatter is not None and problem.weights[1]:
        # b_crit = -1 / (2 Kt min Re(mu G)) in each model: the worst model's min Re(mu G)
        min_re = min(-1.0 / (2.0 * problem.chatter.kt * mp.b_crit) for mp in models)
    out.update(objective=grid.objective_of(design, peaks, min_re),
               peak_compliance=max(peaks),
               peak_compliance_models={mp.model.name: mp.peak_compliance for mp in models},
               worst_model=perf.worst_model.model.name if perf.worst_model else None,
               peak_frequency_hz=perf.peak_frequency / (2 * math.pi))
    if grid.held:   # the NLP's caps of the held models (not a requirement check)
        out["held_peaks_within_caps"] = all(
            peaks[i] <= cap for i, cap in zip(grid.held, grid.caps, strict=True))
    ms_v = [mp.velocity.ms for mp in perf.models if mp.velocity is not None]
    ms_p = [mp.position.ms for mp in perf.models if mp.position is not None]
    if ms_v:
        out.update(ms_velocity=max(ms_v), ms_position=max(ms_p),
                   ms_velocity_violation=max(ms_v) - problem.requirements.ms_limit("velocity"),
                   ms_position_violation=max(ms_p) - problem.requirements.ms_limit("position"))
    return out


def run_de(grid: GridObjective, budget: float, seed: int, popsize: int):
    grid.restart_clock()
    state = {"stopped": False}

    def callback(intermediate_result):
        if time.perf_counter() - grid.t0 > budget:
            state["stopped"] = True
            return True
        return False

    n_g = len(grid.constraints(np.zeros(len(grid.free))))
    res = differential_evolution(
        grid.objective, list(zip(grid.lower, grid.upper, strict=True)),
        constraints=NonlinearConstraint(grid.constraints, np.ones(n_g), np.full(n_g, np.inf)),
        seed=seed, popsize=popsize, maxiter=100000, tol=1e-8, atol=0.0, polish=True,
        callback=callback)
    return res.x, time.perf_counter() - grid.t0, {
        "message": str(res.message), "generations": int(res.nit), "evaluations": grid.evaluations,
        "stability_checks": grid.stability.calls, "stability_checks_s": grid.stability.time_s,
        "stopped_by_budget": state["stopped"], "polish": "trust-constr (scipy default)"}


def run_nm(grid: GridObjective, starts, budget: float):
    grid.restart_clock()
    best, restarts = None, 0
    bounds = list(zip(grid.lower, grid.upper, strict=True))
    for d in starts:
        u = grid.u_of(d)
        f = grid.penalised(u)
        for _ in range(20):
            if time.perf_counter() - grid.t0 > budget:
                break
            res = minimize(grid.penalised, u, method="Nelder-Mead", bounds=bounds,
                           options={"xatol": 1e-9, "fatol": 1e-12, "maxfev": 20000,
                                    "adaptive": True})
            restarts += 1
            improved = res.fun < f - 1e-12
            u, f = res.x, min(f, res.fun)
            if not improved:
                break
        if best is None or f < best[1]:
            best = (u, f)
    return best[0], time.perf_counter() - grid.t0, {
        "evaluations": grid.evaluations, "nelder_mead_runs": restarts,
        "stability_checks": grid.stability.calls, "stability_checks_s": grid.stability.time_s,
        "penalty": f"exact L1, rho = {RHO}", "stopped_by_budget":
            time.perf_counter() - grid.t0 > budget}


def run_slsqp(grid: GridObjective, starts, budget: float):
    """SLSQP (finite-difference gradients) on the epigraph form, from each start in turn,
    restarted from its run's best feasible design until that improves by less than 1e-8
    relative (the budget checked between runs);
    the best feasible design on the grid is kept (a run's end point may be infeasible)."""
    grid.restart_clock()
    epi = Epigraph(grid)
    runs, messages = 0, []
    for d in starts:
        u, f = grid.u_of(d), math.inf
        for _ in range(20):
            if time.perf_counter() - grid.t0 > budget:
                break
            n_before = len(grid.history)
            res = minimize(epi.objective, epi.start(u), method="SLSQP", bounds=epi.bounds(),
                           constraints=[{"type": "ineq", "fun": epi.constraints}],
                           options={"ftol": 1e-10, "maxiter": 200})
            runs += 1
            messages.append(str(res.message))
            # the run's best feasible (stable) design on the grid: its end point may be neither
            # (a restart counts when it gains more than 1e-8 relative: a start stuck away
            # from the optimum gains ~1e-9 per run, the last steps near it ~1e-6)
            found = grid.history[n_before:]
            if not found or found[-1][1] >= f - 1e-8 * abs(found[-1][1]):
                if found and found[-1][1] < f:
                    u, f = found[-1][3], found[-1][1]
                break
            u, f = found[-1][3], found[-1][1]
    best = grid.history[-1][3] if grid.history else grid.u_of(starts[0])
    return best, time.perf_counter() - grid.t0, {
        "evaluations": grid.evaluations, "slsqp_runs": runs, "messages": sorted(set(messages)),
        "stability_checks": grid.stability.calls, "stability_checks_s": grid.stability.time_s,
        "form": "epigraph: t_m >= |h_m(w_i)|/h0 per band frequency and cutting model, "
                "T >= t_m (movable); Ms, gate, thrust and Kv rows as the other scipy "
                "methods'; stability as its margin (min -Re p/|p| of the monodromy "
                "exponents) >= 0; finite-difference gradients",
        "stopped_by_budget": time.perf_counter() - grid.t0 > budget}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--axis", default=str(ROOT / "models" / "paper_x_axis"))
    parser.add_argument("--starts", type=int, default=4,
                        help="casadi, Nelder-Mead and SLSQP starts")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--grid", type=int, default=3000, help="scipy grid points")
    parser.add_argument("--de-budget", type=float, default=600.0, help="DE time budget [s]")
    parser.add_argument("--nm-budget", type=float, default=300.0, help="NM time budget [s]")
    parser.add_argument("--slsqp-budget", type=float, default=300.0,
                        help="SLSQP time budget [s]")
    parser.add_argument("--popsize", type=int, default=15)
    parser.add_argument("--match", type=float, default=1e-4,
                        help="relative tolerance of 'equal objective'")
    parser.add_argument("--methods", default="de,nm,slsqp",
                        help="scipy methods, comma-separated: de, nm, slsqp")
    args = parser.parse_args(argv)
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]

    load_start = os.getloadavg()[0]
    axis = load_axis(args.axis)
    settings = axis.tuning  # as `servotune tune` sets the problem up (tune_axis)
    problem = tuning_problem(axis, settings.free, settings.chatter_weight, settings.bounds)

    # casadi ---------------------------------------------------------------------------
    # the time tune() spends in its own verification (initial and final design) is measured
    # by wrapping the module's verify
    spent = {"verify_s": 0.0}

    def timed_verify(*a):
        t = time.perf_counter()
        try:
            return verify(*a)
        finally:
            spent["verify_s"] += time.perf_counter() - t

    tuning_solve.verify = timed_verify
    try:
        t0, c0 = time.perf_counter(), time.process_time()
        result = tune(problem, starts=args.starts, seed=args.seed)
        t_casadi, cpu_casadi = time.perf_counter() - t0, time.process_time() - c0
    finally:
        tuning_solve.verify = verify
    # the problem tune() solved (without models it excluded at the start) and its reference
    # start (the scale of the objective)
    problem = result.problem
    current_bw = current_loop_bandwidth(problem.drive) if problem.drive is not None else None
    t0 = time.perf_counter()
    verify(problem, result.design)
    t_verify = time.perf_counter() - t0

    # scipy ----------------------------------------------------------------------------
    # casadi's reference start: its objective's scale and where its port model's sampled-data
    # corrections are exact (and kept)
    reference = result.start or result.initial
    t0 = time.perf_counter()
    grid = GridObjective(problem, args.grid, Stability(problem), reference, current_bw)
    t_setup = time.perf_counter() - t0
    casadi_on_grid = grid.values(grid.u_of(result.design))
    target = casadi_on_grid[0]
    frozen_deviation = corrections_deviation(grid, result.design)

    evaluations = {"casadi": common_evaluation(grid, result.design)}
    evaluations["casadi"].update(time_s=t_casadi, cpu_s=cpu_casadi,
                                 time_in_own_verification_s=spent["verify_s"],
                                 time_optimisation_s=t_casadi - spent["verify_s"],
                                 success=result.success,
                                 reasons=list(result.reasons), stats=result.stats.to_dict(),
                                 objective_on_scipy_grid=target,
                                 feasible_on_scipy_grid=bool(casadi_on_grid[2] and np.all(
                                     casadi_on_grid[1] >= 1 - 1e-9)))
    runs = {}
    if "de" in methods:
        c0 = time.process_time()
        u, t, info = run_de(grid, args.de_budget, args.seed, args.popsize)
        runs["scipy_de"] = (u, t, time.process_time() - c0, info, list(grid.history))
    if "nm" in methods:
        c0 = time.process_time()
        starts = tuning_solve.stable_starts(problem, args.starts, args.seed).designs
        u, t, info = run_nm(grid, starts, args.nm_budget)
        runs["scipy_nm"] = (u, t, time.process_time() - c0, info, list(grid.history))
    if "slsqp" in methods:
        c0 = time.process_time()
        starts = tuning_solve.stable_starts(problem, args.starts, args.seed).designs
        u, t, info = run_slsqp(grid, starts, args.slsqp_budget)
        runs["scipy_slsqp"] = (u, t, time.process_time() - c0, info, list(grid.history))
    for name, (u, t, cpu, info, history) in runs.items():
        f, g, stable = grid.values(u)
        grid.history = history
        reach = {f"time_to_casadi_objective_rtol_{r:g}_s": grid.time_to_reach(target, r)
                 for r in sorted({args.match, 1e-2, 1e-3})}
        ev = common_evaluation(grid, grid.design(u))
        ev.update(time_s=t, cpu_s=cpu, setup_s=t_setup, objective_on_scipy_grid=f,
                  feasible_on_scipy_grid=bool(stable and np.all(g >= 1 - 1e-9)), **info, **reach)
        hit = grid.reached(target, args.match)
        t_equal = None if hit is None else hit[0]
        ev["speedup"] = (t_equal / t_casadi) if t_equal is not None else None
        ev["speedup_lower_bound"] = None if t_equal is not None else t / t_casadi
        t_opt = t_casadi - spent["verify_s"]
        ev["speedup_optimisation_only"] = (t_equal / t_opt) if t_equal is not None else None
        ev["speedup_optimisation_only_lower_bound"] = None if t_equal is not None else t / t_opt
        # the same with the scipy method's time in stability checks taken out
        t_plain = (hit[0] - hit[1]) if hit is not None else t - info["stability_checks_s"]
        ev["time_to_casadi_objective_without_stability_checks_s"] = (
            None if hit is None else t_plain)
        ev["speedup_without_stability_checks"] = (t_plain / t_casadi) if hit is not None else None
        ev["speedup_without_stability_checks_lower_bound"] = (
            None if hit is not None else t_plain / t_casadi)
        ev["stability_share_of_time"] = info["stability_checks_s"] / t if t > 0 else None
        ev["best_feasible_history"] = [[round(a, 3), b] for a, b, _, _ in history]
        # the design that reached casadi's objective, judged by the common evaluator (after
        # the run, untimed): a fixed grid can miss a peak between its points
        if hit is not None:
            at = common_evaluation(grid, grid.design(hit[2]))
            ev["design_at_casadi_objective"] = {k: at.get(k) for k in (
                "design", "stable", "feasible", "failed_checks", "objective")}
        evaluations[name] = ev

    # against the fastest scipy method that reaches casadi's objective; one that never does
    # does not count (listed), and only when none does is the speedup the smallest lower bound
    scipy_runs = {k: ev for k, ev in evaluations.items() if k != "casadi"}
    reaching = {k: ev["speedup"] for k, ev in scipy_runs.items() if ev["speedup"] is not None}
    not_reaching = [k for k in scipy_runs if k not in reaching]
    if reaching:
        against = min(reaching, key=reaching.get)
        speedup, lower_bound = reaching[against], False
    elif scipy_runs:
        against = min(scipy_runs, key=lambda k: scipy_runs[k]["speedup_lower_bound"])
        speedup, lower_bound = scipy_runs[against]["speedup_lower_bound"], True
    else:
        against, speedup, lower_bound = None, None, False
    out = {
        "case": f"{axis.name}: free {','.join(problem.free)}, {len(problem.regimes)} regime "
                f"models, objective worst movable peak/h0 + {problem.mean_weight} mean movable "
                f"peak/h0 + {HELD_WEIGHT:g} mean held peak/h0 (held capped) + "
                f"{problem.tracking_weight} Kv0/Kv + {problem.c_cost_weight} C cost, Ms velocity "
                f"<= {problem.requirements.ms_limit('velocity'):.4f}, Ms position <= "
                f"{problem.requirements.ms_limit('position'):.4f}, loop hierarchy, Ti (lower "
                "bound), current loop, thrust, stable in every model",
        "regime_models": [m.name for m in problem.regimes],
        "held_models": [{"model": problem.regimes[grid.cut[i]].name, "cap_m_per_n": cap}
                        for i, cap in zip(grid.held, grid.caps, strict=True)],
        "excluded_models": [m.name for m, _ in result.excluded],
        "initial_design": result.initial.to_dict(),
        "reference_start": None if result.start is None else result.start.to_dict(),
        "scale_h0_m_per_n": grid.h0,
        "time_casadi_s": t_casadi,
        "time_one_verification_s": t_verify,
        "baseline": "the fastest of the scipy methods run (differential_evolution, "
                    "Nelder-Mead, SLSQP in epigraph form with finite-difference gradients) "
                    "to reach casadi's objective within match_rtol, on the same objective "
                    "and constraints (one fixed grid)",
        "model": ("port model (ResponseModel) with the digital drive's sampled-data corrections "
                  "frozen at casadi's reference start, as casadi; stability by "
                  "servotune.tuning.solve.model_stability (SampledAxis monodromy) on every "
                  "design" if is_sampled(problem) else
                  "port model (ResponseModel) of the continuous drive; stability by "
                  "servotune.tuning.solve.model_stability on every design"),
        "drive_sampled": is_sampled(problem),
        "scipy_grid_points": args.grid,
        "match_rtol": args.match,
        "frozen_corrections_deviation_at_casadi_design": frozen_deviation,
        "speedup": speedup,
        "speedup_against": against,
        "speedup_is_lower_bound": lower_bound,
        "methods_not_reaching_casadi_objective": not_reaching,
        "methods": evaluations,
        "load_average_1min": [load_start, os.getloadavg()[0]],
        "versions": {"scipy": scipy.__version__, "casadi": casadi.__version__,
                     "numpy": np.__version__},
    }
    if args.json:
        print(json.dumps(out, indent=2, default=float))
    else:
        print(out["case"])
        print(f"{'method':10} {'time [s]':>9} {'objective':>11} {'Ms vel':>7} {'Ms pos':>7} "
              f"{'feasible':>8}  design (c, kv, kp, ti)")
        for name, ev in evaluations.items():
            d = ev["design"]
            print(f"{name:10} {ev['time_s']:9.2f} {ev.get('objective', math.nan):11.7f} "
                  f"{ev.get('ms_velocity', math.nan):7.4f} {ev.get('ms_position', math.nan):7.4f}"
                  f" {ev.get('feasible', False)!s:>8}  {d['c']:.4g}, {d['kv']:.4g}, "
                  f"{d['kp']:.4g}, {d['ti']:.4g}")
        for name, ev in evaluations.items():
            if name == "casadi":
                continue
            t_eq = ev[f"time_to_casadi_objective_rtol_{args.match:g}_s"]
            if t_eq is not None:
                at = ev["design_at_casadi_objective"]
                print(f"  {name}: reaches casadi's objective (rtol {args.match:g}) after "
                      f"{t_eq:.1f} s: speedup {ev['speedup']:.1f} x (that design "
                      f"{'passes' if at['feasible'] else 'fails'} the common check)")
            else:
                print(f"  {name}: does not reach casadi's objective (rtol {args.match:g}) "
                      f"within {ev['time_s']:.0f} s: speedup > {ev['speedup_lower_bound']:.1f} x")
        for name, ev in evaluations.items():
            if name != "casadi":
                print(f"  {name}: {ev['stability_checks']} stability checks took "
                      f"{ev['stability_checks_s']:.1f} s of its {ev['time_s']:.1f} s")
        print(f"  casadi: {t_casadi:.2f} s in all, of which {spent['verify_s']:.2f} s in its "
              f"own verification (2 designs, every regime model); load average "
              f"{load_start:.1f} -> {os.getloadavg()[0]:.1f}")
    return out


if __name__ == "__main__":
    main()
