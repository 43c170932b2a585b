"""The tuning problem as a nonlinear program, written out in one place.

Variables (log-scaled, ``u_v = log(x_v / x_v0)`` for each free design variable x_v among C,
Kv, Kp, Ti), the epigraph variables of the objective, and the data of the frequency grids as
parameters (one column per frequency and regime model; see :mod:`servotune.tuning.ports`)::

    minimise    w_p (t + mu mean_m t_m + eps mean_k t_k) + w_c q + w_t Kv0 / Kv
                + w_C (C - C_lo) / C_span

    subject to  |h_m(w)|^2 / h0^2 <= t_m^2          every cutting model m, band frequency w
                t_m <= t                              every movable model m
                t_k <= cap_k / h0                     every held model k
                mu_d Re h_m(w) / s0 + q >= 0         (chatter: b_crit = 1 / (2 Kt s0 q))
                Ms_v^2 |1 + L_v,m(w)|^2 >= 1         every model m, loop frequency w
                Ms_p^2 |1 + L_p,m(w)|^2 >= 1
                |T_v,m(w)| >= 1/sqrt2   for w <= N gamma_m Kv      (loop hierarchy)
                |T_v,m(w)| >= 1/sqrt2   for w <= r_min / Ti            (Ti w_b >= r_min)
                |T_v,m(w)| <= 1/sqrt2   for w in [r_max/Ti, 1.25 r_max/Ti] (Ti w_b <= r_max)
                |T_v,m(w)| <= 1/sqrt2   for w in [w_i/N_i, 1.25 w_i/N_i] (current loop above)
                            (the last four in every moving model m: sliding or viscous pads)
                F_fix,j + C v_j <= (1 - margin) F_avail,j      every thrust case j
                Kv >= Kv_min,  bounds on every u_v

The models the free variables cannot move (found before the solve, see
:func:`servotune.tuning.solve.held_models`: a standing regime whose pads stick, for one) are
*held*: capped at their value instead of setting the worst peak, and weighted last (eps =
:data:`HELD_WEIGHT`): the objective is lexicographic over the regimes, first the worst peak of
the models the design can move, then their mean, then the held ones.

The rows after the epigraph rows are the registered requirements' (one module each in
:mod:`servotune.tuning.requirements`, see :mod:`servotune.tuning.constraint`): their loop rows
at every loop frequency and their rows in the design variables; the statement above is that of
the shipped ones.

h_m is the work-piece compliance, L_v and L_p the velocity loop (position loop open) and the
position loop (velocity loop closed), T = L/(1 + L), all with the guide ways of model m and the
digital drive's delays. The conditions "for w <= ..." depend on the design; they are imposed at
every grid frequency with a smooth gate: ``value + sigma(kappa log(w / w_edge)) >= 0`` with the
value normalised to (-1, 1) (e.g. (|T|^2 - 1/2)/(|T|^2 + 1/2)) and the logistic sigma switching
the condition off past the edge; the edges are placed ``GATE_SAFETY`` beyond the requirement so
that the gate's soft part does not eat into it. gamma_m, the ratio of the position loop's
bandwidth to Kv, is a parameter the solve updates from the current design between exchange
rounds (:mod:`servotune.tuning.solve`).

The Hessian of the Lagrangian is assembled from the per-frequency Hessians of the kernels
(mapped and summed over the columns with their multipliers) instead of casadi's generic
second-order sweep over the whole NLP, which costs several times more per iteration.

References
----------
J. A. E. Andersson et al., "CasADi: a software framework for nonlinear optimization and
optimal control", Math. Prog. Comp. 11 (2019) 1-36. A. Waechter, L. T. Biegler, "On the
implementation of an interior-point filter line-search algorithm for large-scale nonlinear
programming", Math. Prog. 106 (2006) 25-57 (IPOPT). P. Apkarian, D. Noll, "Nonsmooth H-infinity
synthesis", IEEE TAC 51 (2006) 71-86 (worst case over several models, as MATLAB's systune).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from .. import interrupt
from ._clib import cache_folder
from .constraint import LoopQuantities, requirements
from .gates import GATE_SAFETY, GATE_SHARPNESS
from .ports import SymbolicPorts, responses
from .problem import VARIABLES, Design, TuningProblem

__all__ = ["GATE_SHARPNESS", "GATE_SAFETY", "HELD_WEIGHT", "ColumnMap", "Kernels", "Solver",
           "Solution", "gate_parameters", "cache_folder"]

#: Weight of the held models' mean peak in the objective (relative to the worst movable one):
#: third in the lexicographic order, after the worst and the mean of the movable models.
HELD_WEIGHT = 1e-3


def gate_parameters(problem: TuningProblem, gamma: np.ndarray,
                    current_bandwidth: float | None) -> np.ndarray:
    """Return the per-model constants of the requirements' loop rows.

    Parameters
    ----------
    problem : TuningProblem
        The problem (its requirements and which models move).
    gamma : numpy.ndarray
        Position-loop bandwidth over Kv of each regime model (edges of the hierarchy gate).
    current_bandwidth : float or None
        Bandwidth of the current loop [rad/s] (None: no current-loop row).

    Returns
    -------
    numpy.ndarray
        One row per regime model: the constants of :meth:`Requirement.gate` of every loop
        requirement of the problem, in their order (e.g. whether the requirement applies to
        the model and the log of its edge).
    """
    gated = [c for c in requirements(problem) if c.gate_size]
    rows = []
    for m in range(len(problem.regimes)):
        row = []
        for c in gated:
            row.extend(float(x) for x in c.gate(problem, m, float(gamma[m]), current_bandwidth))
        rows.append(row)
    return np.array(rows, dtype=float).reshape(len(problem.regimes), -1)


class ColumnMap:
    """A per-frequency kernel ``f(u, d)`` evaluated at one ``u`` over any number of data
    columns, in chunks of ``chunk`` columns.

    The values are exchanged with casadi through buffers bound once (``Function.buffer``):
    converting a numpy array of thousands of columns to casadi's matrix type costs about 20
    times the evaluation itself, and building a map of the kernel costs about 5 us per
    column, so one map of ``chunk`` columns serves every size (the last chunk padded with
    copies of its last column). Casadi versions without buffers are called plainly (same
    values).

    Parameters
    ----------
    kernel : casadi.Function
        A function of (u, one data column) with one output column.
    chunk : int
        Columns per evaluation of the mapped kernel.
    """

    def __init__(self, kernel: ca.Function, chunk: int = 256):
        self.chunk = int(chunk)
        self.n_data, self.n_out = kernel.size1_in(1), kernel.size1_out(0)
        self.function = kernel.map(f"{kernel.name()}_{self.chunk}", "serial", self.chunk,
                                   [0], [])
        self._u = np.zeros(kernel.size1_in(0))
        self._data = np.zeros(self.n_data * self.chunk)
        self._out = np.zeros(self.n_out * self.chunk)
        self._run = None
        if hasattr(self.function, "buffer"):
            self._buffer, self._run = self.function.buffer()
            self._buffer.set_arg(0, memoryview(self._u))
            self._buffer.set_arg(1, memoryview(self._data))
            self._buffer.set_res(0, memoryview(self._out))

    def __call__(self, u: np.ndarray, data: np.ndarray) -> np.ndarray:
        """Return the kernel's output at ``u`` for every column of ``data``.

        Parameters
        ----------
        u : numpy.ndarray
            The scaled free variables.
        data : numpy.ndarray
            ``(n_data, n)``: one data column per frequency and model.

        Returns
        -------
        numpy.ndarray
            ``(n_out, n)``.
        """
        data = np.asarray(data, dtype=float)
        if data.ndim != 2 or data.shape[0] != self.n_data:
            raise ValueError(f"data of shape {data.shape} for a kernel of {self.n_data} data "
                             "rows")
        n = data.shape[1]
        out = np.empty((self.n_out, n))
        block = self._data.reshape(self.n_data, self.chunk, order="F")
        result = self._out.reshape(self.n_out, self.chunk, order="F")
        self._u[:] = u
        for start in range(0, n, self.chunk):
            k = min(self.chunk, n - start)
            block[:, :k] = data[:, start:start + k]
            block[:, k:] = data[:, start + k - 1:start + k]
            if self._run is None:
                result[:] = np.array(self.function(self._u, block))
            else:
                self._run()
                if self._buffer.ret() != 0:
                    raise RuntimeError(f"casadi could not evaluate {self.function.name()} "
                                       f"(return code {self._buffer.ret()})")
            out[:, start:start + k] = result[:, :k]
        return out


class Kernels:
    """The constraint functions at ONE frequency (one data column) as casadi functions of
    (u, data), u = log(x / x0) the scaled free variables, with the Hessians of their
    multiplier-weighted sums; the NLP maps them over the grid columns, :meth:`evaluate`
    evaluates them numerically."""

    def __init__(self, problem: TuningProblem, h0: float, s0: float):
        self._maps: dict[str, ColumnMap] = {}
        self.h0, self.s0 = h0, s0
        x0 = problem.initial_design()
        free = problem.free
        u = ca.SX.sym("u", len(free))
        values = {v: getattr(x0, v) or 0.0 for v in VARIABLES}
        for i, v in enumerate(free):
            values[v] = getattr(x0, v) * ca.exp(u[i])
        w_peak, w_chatter = problem.weights
        # band: compliance peak and chatter rows
        d_band = ca.SX.sym("d", SymbolicPorts.size(problem))
        h = responses(problem, SymbolicPorts(problem, d_band), values)["compliance"]
        band = []
        if w_peak > 0:
            band.append(h.abs2() / h0**2)
        if w_chatter > 0:
            band.append(problem.chatter.mu * h.re / s0)
        self.band, self.band_hessian = self._pair("band", u, d_band, ca.vertcat(*band))
        self.band_rows = (["compliance peak"] if w_peak > 0 else []) + (
            ["chatter"] if w_chatter > 0 else [])
        self.loop = self.loop_hessian = None
        self.loop_rows, self.loop_lower, self.loop_moving_only = [], [], []
        if problem.drive is not None:
            self._loop_kernels(problem, u, values)
        self._compile(len(free))

    def _compile(self, n_free: int) -> None:
        """The kernels compiled to C (one library: :mod:`servotune.tuning._clib`), with the
        forward derivatives in up to ``n_free`` directions the constraint Jacobian takes."""
        from ._clib import compile_functions

        names = ("band", "band_hessian", "loop", "loop_hessian")
        present = [n for n in names if getattr(self, n) is not None]
        compiled = compile_functions([getattr(self, n) for n in present],
                                     {"band": n_free, "loop": n_free})
        for name, f in zip(present, compiled, strict=True):
            setattr(self, name, f)

    def _loop_kernels(self, problem: TuningProblem, u, values) -> None:
        """The loop kernel of the requirements' rows and its Hessian."""
        # the loop rows: each requirement's, in their order (servotune.tuning.requirements)
        loop_requirements = [c for c in requirements(problem) if c.row_names(problem)]
        n_gate = sum(c.gate_size for c in requirements(problem))
        d_loop = ca.SX.sym("d", SymbolicPorts.size(problem, n_gate))
        ports = SymbolicPorts(problem, d_loop, n_gate)
        resp = responses(problem, ports, values)
        lv = resp["loop_velocity"]
        q = LoopQuantities(lv, resp["loop_position"], lv.abs2() / (1.0 + lv).abs2(),
                           ca.log(ports.omega), values["kv"], values["ti"])
        rows = []
        self.loop_lower, self.loop_moving_only = [], []
        offsets, at = {}, 0
        for c in requirements(problem):
            offsets[c.name] = at
            at += c.gate_size
        for c in loop_requirements:
            gate = ports.extra[offsets[c.name]:offsets[c.name] + c.gate_size]
            new = c.loop_rows(problem, q, gate)
            names = c.row_names(problem)
            if len(new) != len(names):
                raise ValueError(f"requirement {c.name!r} gave {len(new)} loop rows for "
                                 f"{len(names)} names")
            rows += new
            self.loop_rows += list(names)
            self.loop_lower += [float(c.lower)] * len(names)
            self.loop_moving_only += [bool(c.moving_only)] * len(names)
        self.loop, self.loop_hessian = self._pair("loop", u, d_loop, ca.vertcat(*rows))

    def evaluate(self, which: str, u: np.ndarray, data: np.ndarray) -> np.ndarray:
        """Return the band or loop kernel at ``u`` for every column of ``data`` (numerically).

        Parameters
        ----------
        which : {"band", "loop"}
            The kernel.
        u : numpy.ndarray
            The scaled free variables.
        data : numpy.ndarray
            One data column per frequency and model (:meth:`PortData.rows`).

        Returns
        -------
        numpy.ndarray
            One row per kernel output (``band_rows`` or ``loop_rows``), one column per
            data column.
        """
        kernel = self.band if which == "band" else self.loop
        if kernel is None:
            raise ValueError(f"this problem has no {which} kernel")
        if which not in self._maps:
            self._maps[which] = ColumnMap(kernel)
        return self._maps[which](u, data)

    @staticmethod
    def _pair(name, u, d, out):
        """The function and the Hessian in u of its outputs weighted by multipliers."""
        lam = ca.SX.sym("lam", out.numel())
        hessian = ca.hessian(ca.dot(lam, out), u)[0]
        return (ca.Function(name, [u, d], [out]),
                ca.Function(f"{name}_hessian", [u, d, lam], [ca.densify(hessian)]))


class _IterationLimit:
    """IPOPT's iteration callback: stops a solve after a per-solve number of iterations (so
    one solver serves solves with different limits), when Ctrl-C was pressed, or when
    ``inner`` (another casadi callback) asks to stop."""

    def __init__(self, inner=None):
        self.inner, self.limit, self.count, self.reached = inner, None, 0, False
        self.callback = interrupt.casadi_iteration_callback("iteration_limit", stop=self._stop)

    def start(self, limit: int | None) -> None:
        self.limit, self.count, self.reached = limit, 0, False

    def _stop(self) -> bool:
        self.count += 1
        if self.limit is not None and self.count > self.limit:
            self.reached = True
            return True
        return self.inner is not None and float(self.inner.eval([])[0]) != 0


@dataclass(frozen=True)
class Solution:
    """What one IPOPT solve returns."""

    design: Design
    objective: float
    stats: dict
    g: np.ndarray
    multipliers: tuple
    x: np.ndarray

    @property
    def converged(self) -> bool:
        return bool(self.stats["success"]) or self.stats["return_status"] in (
            "Solve_Succeeded", "Solved_To_Acceptable_Level")


class Solver:
    """The NLP for grids of up to ``n_band`` band frequencies (x the cutting models) and
    ``n_loop`` loop frequencies (x all models); the grids' data are its parameters.

    A grid may have fewer frequencies than the solver's capacity: the unused columns are
    switched off by a mask (a parameter too), their constraints then read ``-t_m^2 <= 0``,
    ``q >= 0`` and ``lo + 1 >= lo``, never active, so one solver serves every round of the grid
    exchange (building an IPOPT instance costs about 0.2 s). :meth:`parameters` lays a grid's
    data out for it.

    ``rows`` lists, for every constraint row, ``(group, model, column)`` with ``column`` the
    data column (frequency slot x model) or None; :meth:`row_keys` names each row by its
    frequency, so multipliers can follow a refined grid.

    Parameters
    ----------
    problem : TuningProblem
        The problem (its regime models, requirements, weights, thrust budget and bounds).
    kernels : Kernels
        The per-frequency constraint functions of ``problem``.
    n_band, n_loop : int
        Capacity of the band and loop grids (frequencies per model).
    warm : bool
        IPOPT's warm-start options (start from given multipliers, small barrier parameter).
    max_iter : int
        IPOPT's iteration limit; :meth:`solve` may set a lower one per solve.
    callback : casadi.Callback, optional
        Called at every IPOPT iteration; a non-zero return stops the solve (an interruption).
    """

    def __init__(self, problem: TuningProblem, kernels: Kernels, n_band: int, n_loop: int,
                 warm: bool = False, max_iter: int = 500, callback=None):
        self.problem, self.kernels = problem, kernels
        x0 = problem.initial_design()
        self.free = free = problem.free
        nf = len(free)
        self.scale = {v: getattr(x0, v) for v in free}
        cut = problem.cutting_models
        n_models = len(problem.regimes)
        w_peak, w_chatter = problem.weights
        self.n_band, self.n_loop = n_band, n_loop
        n_t = (1 + len(cut)) if w_peak > 0 else 0
        n_q = 1 if w_chatter > 0 else 0
        p = ca.MX.sym("p", nf)
        tt = ca.MX.sym("t", n_t)
        q = ca.MX.sym("q", n_q)
        self.n_t, self.n_q = n_t, n_q

        def design_value(v):
            return self.scale[v] * ca.exp(p[free.index(v)]) if v in free else getattr(x0, v)

        g, lbg, ubg, self.rows = [], [], [], []

        def add(expr, lo, hi, group, models=None, columns=None):
            n = expr.shape[0]
            g.append(expr)
            lbg.extend([lo] * n)
            ubg.extend([hi] * n)
            for i in range(n):
                self.rows.append((group, None if models is None else models[i],
                                  None if columns is None else columns[i]))

        n_rows_band = kernels.band.size1_in(1)
        data_band = ca.MX.sym("band", n_rows_band, n_band * len(cut))
        mask_band = ca.MX.sym("band_mask", n_band * len(cut))
        params = [ca.vec(data_band)]
        band = (kernels.band.map(n_band * len(cut))(p, data_band)
                * ca.repmat(mask_band.T, kernels.band.size1_out(0), 1))
        band_cols = list(range(n_band * len(cut)))
        band_models = [cut[j // n_band] for j in band_cols]
        weights_band = []  # (row of the kernel, group) for the Hessian
        row = 0
        if w_peak > 0:
            t_of_col = ca.vertcat(*[ca.repmat(tt[1 + i], n_band, 1) for i in range(len(cut))])
            add(band[row, :].T - t_of_col ** 2, -ca.inf, 0.0, "compliance peak", band_models,
                band_cols)
            weights_band.append("compliance peak")
            row += 1
        if w_chatter > 0:
            add(band[row, :].T + q[0], 0.0, ca.inf, "chatter", band_models, band_cols)
            weights_band.append("chatter")
        held = [cut.index(m) for m in problem.held if m in cut]
        movable = [i for i in range(len(cut)) if i not in held]
        self.held, self.movable = held, movable
        if w_peak > 0:
            # the worst peak over the models the design can move (the held ones are capped)
            add(tt[0] - tt[[1 + i for i in movable]], 0.0, ca.inf, "worst peak")
        data_loop = None
        if kernels.loop is not None:
            n_rows_loop = kernels.loop.size1_in(1)
            data_loop = ca.MX.sym("loop", n_rows_loop, n_loop * n_models)
            mask_loop = ca.MX.sym("loop_mask", n_loop * n_models)
            params.append(ca.vec(data_loop))
            loops = kernels.loop.map(n_loop * n_models)(p, data_loop)
            all_cols = list(range(n_loop * n_models))
            # rows of requirements on the moving models only are left out elsewhere (there
            # the kernel switches them off and they always hold)
            moving = set(problem.moving_models)
            moving_cols = [j for j in all_cols if j // n_loop in moving]
            for i, group in enumerate(kernels.loop_rows):
                lo = kernels.loop_lower[i]
                cols = moving_cols if kernels.loop_moving_only[i] else all_cols
                if not cols:
                    continue
                row = loops[i, cols].T * mask_loop[cols] + (1.0 - mask_loop[cols]) * (lo + 1.0)
                add(row, lo, ca.inf, group, [j // n_loop for j in cols], cols)
        # the requirements' rows in the design variables (thrust cases, kv_min, ...)
        rest_start = len(lbg)
        for requirement in requirements(problem):
            for name, expr, lo, hi in requirement.design_rows(problem, design_value):
                add(ca.vertcat(expr), lo, hi, name)
        objective = 0
        if w_peak > 0:
            t_mov = tt[[1 + i for i in movable]]
            objective = w_peak * (tt[0] + problem.mean_weight * ca.sum1(t_mov) / len(movable))
            if held:
                objective = objective + w_peak * HELD_WEIGHT * ca.sum1(
                    tt[[1 + i for i in held]]) / len(held)
        if w_chatter > 0:
            objective = objective + w_chatter * q[0]
        if "kv" in free and problem.tracking_weight > 0:
            objective = objective + problem.tracking_weight * x0.kv / design_value("kv")
        if problem.c_cost is not None:
            c_lo, span = problem.c_cost
            objective = objective + problem.c_cost_weight * (design_value("c") - c_lo) / span
        x = ca.vertcat(p, tt, q)
        params.append(mask_band)
        masks = [mask_band]
        if data_loop is not None:
            params.append(mask_loop)
            masks.append(mask_loop)
        self.nlp = {"x": x, "p": ca.vertcat(*params), "f": objective, "g": ca.vertcat(*g)}
        self.lbg, self.ubg = np.array(lbg), np.array(ubg)
        self.groups = [r[0] for r in self.rows]
        self.hessian = self._hessian(x, p, tt, objective, g, rest_start, data_band, data_loop,
                                     masks, weights_band, len(cut), n_models)
        self._limit = _IterationLimit(callback)
        options = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                   "ipopt.tol": 1e-10, "ipopt.acceptable_tol": 1e-8, "ipopt.max_iter": max_iter,
                   "ipopt.mu_strategy": "adaptive", "hess_lag": self.hessian,
                   "iteration_callback": self._limit.callback}
        if warm:
            options.update({"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-6,
                            "ipopt.warm_start_bound_push": 1e-9,
                            "ipopt.warm_start_mult_bound_push": 1e-9})
        self.solver = ca.nlpsol("tune", "ipopt", self.nlp, options)
        lo = [math.log(problem.bounds[v][0] / self.scale[v]) for v in free]
        hi = [math.log(problem.bounds[v][1] / self.scale[v]) for v in free]
        self.lbx = np.array([*lo, *([0.0] * n_t), *([-ca.inf] * n_q)])
        self.ubx = np.array([*hi, *([ca.inf] * n_t), *([ca.inf] * n_q)])
        if n_t:
            for i in held:
                cap = problem.held_caps[list(problem.held).index(cut[i])]
                self.ubx[nf + 1 + i] = cap / kernels.h0

    def _hessian(self, x, p, tt, objective, g, rest_start, data_band, data_loop, masks,
                 weights_band, n_cut, n_models):
        kernels = self.kernels
        nf = p.shape[0]
        lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", len(self.lbg))
        groups = np.array(self.groups)

        columns = np.array([-1 if c is None else c for _, _, c in self.rows])

        def weights(names, n_cols, mask):
            """Each group's multipliers (times the mask) spread over the data columns."""
            rows = []
            for name in names:
                idx = np.nonzero(groups == name)[0].tolist()
                if not idx:
                    rows.append(ca.MX.zeros(1, n_cols))
                    continue
                cols = columns[idx].tolist()
                if cols == list(range(n_cols)):
                    rows.append((lam_g[idx] * mask).T)
                    continue
                # the row covers some columns only: multipliers scattered, zero elsewhere
                spread = ca.MX.zeros(n_cols, 1)
                spread[cols] = lam_g[idx] * mask[cols]
                rows.append(spread.T)
            return ca.vertcat(*rows)

        n_band_cols = self.n_band * n_cut
        hess_p = kernels.band_hessian.map(f"band_hessian_{n_band_cols}", "serial", n_band_cols,
                                          [0], [0])(p, data_band,
                                                    weights(weights_band, n_band_cols,
                                                            masks[0]))
        if data_loop is not None:
            n_loop_cols = self.n_loop * n_models
            hess_p += kernels.loop_hessian.map(f"loop_hessian_{n_loop_cols}", "serial",
                                               n_loop_cols, [0], [0])(
                p, data_loop, weights(kernels.loop_rows, n_loop_cols, masks[1]))
        rest = lam_f * objective
        g_all = ca.vertcat(*g)
        for i in range(rest_start, len(self.lbg)):
            rest = rest + lam_g[i] * g_all[i]
        hess_rest = ca.hessian(rest, x)[0]
        n_x = x.shape[0]
        block = ca.MX(n_x, n_x)
        block[:nf, :nf] = hess_p
        if self.n_t:
            # d^2/dt_m^2 of (|h|^2/h0^2 - t_m^2) weighted: -2 sum of the model's multipliers
            peak = np.nonzero(groups == "compliance peak")[0]
            for i in range(n_cut):
                idx = peak[i * self.n_band:(i + 1) * self.n_band].tolist()
                j = nf + 1 + i
                block[j, j] = -2.0 * ca.sum1(lam_g[idx])
        hessian = block + hess_rest
        return ca.Function("hess_lag", [x, self.nlp["p"], lam_f, lam_g],
                           [ca.triu(ca.densify(hessian))],
                           ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])

    def values(self, design: Design) -> np.ndarray:
        """Return the scaled variables ``u = log(x / x0)`` of a design's free variables.

        Parameters
        ----------
        design : Design
            The design.

        Returns
        -------
        numpy.ndarray
            One value per free variable, in the order of ``problem.free``.
        """
        return np.array([math.log(getattr(design, v) / self.scale[v]) for v in self.free])

    def _padded(self, data: np.ndarray, n_models: int, capacity: int):
        """Widen a grid's data (model-major blocks of k <= capacity columns) to the capacity,
        unused slots holding copies of each block's last column; also return the mask."""
        rows, cols = data.shape
        k = cols // n_models
        if k * n_models != cols or not 0 < k <= capacity:
            raise ValueError(f"grid data of {cols} columns for {n_models} models does not fit "
                             f"a solver built for {capacity} frequencies per model")
        blocks = data.reshape(rows, n_models, k)
        out = np.empty((rows, n_models, capacity), dtype=float)
        out[:, :, :k] = blocks
        out[:, :, k:] = blocks[:, :, -1:]
        mask = np.zeros((n_models, capacity))
        mask[:, :k] = 1.0
        return out.reshape(rows, n_models * capacity), mask.ravel()

    def parameters(self, band_data: np.ndarray, loop_data=None) -> np.ndarray:
        """Return the NLP's parameter vector for the grids' data.

        Parameters
        ----------
        band_data : numpy.ndarray
            :meth:`PortData.rows` of the cutting models on the band grid (at most
            ``n_band`` frequencies per model).
        loop_data : numpy.ndarray, optional
            :meth:`PortData.rows` of all models with the gate parameters on the loop grid (at
            most ``n_loop`` frequencies per model); needed when the problem has a drive.

        Returns
        -------
        numpy.ndarray
            The data, widened to the capacity, followed by the masks of the used slots.

        Raises
        ------
        ValueError
            When a grid has more frequencies than the solver has room for.
        """
        band, band_mask = self._padded(np.asarray(band_data, dtype=float),
                                       len(self.problem.cutting_models), self.n_band)
        params, masks = [band.ravel(order="F")], [band_mask]
        if self.kernels.loop is not None:
            loop, loop_mask = self._padded(np.asarray(loop_data, dtype=float),
                                           len(self.problem.regimes), self.n_loop)
            params.append(loop.ravel(order="F"))
            masks.append(loop_mask)
        return np.concatenate(params + masks)

    def row_keys(self, band: np.ndarray, loop: np.ndarray) -> list:
        """Return a key per constraint row that survives a change of grids.

        Parameters
        ----------
        band, loop : numpy.ndarray
            The band and loop grids [rad/s] the solver is used with.

        Returns
        -------
        list
            ``(group, model, omega)`` for the rows of the grids, ``(group, model, None)`` for
            the rows without a frequency, None for an unused slot.
        """
        keys = []
        for group, model, column in self.rows:
            if column is None:
                keys.append((group, model, None))
                continue
            in_band = group in ("compliance peak", "chatter")
            omega, capacity = (band, self.n_band) if in_band else (loop, self.n_loop)
            slot = column % capacity
            keys.append((group, model, float(omega[slot])) if slot < omega.size else None)
        return keys

    def epigraph_start(self, design: Design, band_data: np.ndarray) -> np.ndarray:
        """Return the epigraph variables (t, t_m, q) that make the grid constraints hold.

        Parameters
        ----------
        design : Design
            The design the solve starts from.
        band_data : numpy.ndarray
            The band grid's data (as for :meth:`parameters`).

        Returns
        -------
        numpy.ndarray
            t (the worst peak), t_m per cutting model (both scaled by h0) and q (chatter).
        """
        band = self.kernels.evaluate("band", self.values(design), band_data)
        out = []
        row = 0
        if self.n_t:
            per_model = band[row].reshape(len(self.problem.cutting_models), -1)
            per = np.sqrt(np.maximum(per_model.max(axis=1), 0.0))
            nf = len(self.free)
            per = np.minimum(per, self.ubx[nf + 1:nf + 1 + per.size])
            out += [float(per[self.movable].max()), *per.tolist()]
            row += 1
        if self.n_q:
            out.append(float(-band[row].min()))
        return np.array(out)

    def solve(self, design: Design, band_data, loop_data, region: float | None = None,
              multipliers=None, max_iter: int | None = None) -> Solution:
        """Solve from ``design`` with the grids' data.

        Parameters
        ----------
        design : Design
            The starting design (its fixed variables are kept).
        band_data, loop_data : numpy.ndarray
            The grids' data (see :meth:`parameters`).
        region : float, optional
            Limits each log-variable to +-region around its start (a trust region).
        multipliers : tuple of numpy.ndarray, optional
            (lam_x, lam_g) to warm-start a solver built with ``warm=True``.
        max_iter : int, optional
            Stop after that many iterations (below the solver's own limit); the solution then
            reports "Maximum_Iterations_Exceeded".

        Returns
        -------
        Solution
            The design reached (clipped to the bounds), objective, IPOPT's statistics, the
            constraint values and the multipliers.

        Raises
        ------
        servotune.interrupt.Interrupted
            When an interruption (Ctrl-C) stopped IPOPT.
        """
        p0 = self.values(design)
        y0 = self.epigraph_start(design, band_data)
        lbx, ubx = self.lbx.copy(), self.ubx.copy()
        n = p0.size
        if region is not None:
            lbx[:n] = np.maximum(lbx[:n], p0 - region)
            ubx[:n] = np.minimum(ubx[:n], p0 + region)
        args = {"x0": np.concatenate([p0, y0]), "lbx": lbx, "ubx": ubx, "lbg": self.lbg,
                "ubg": self.ubg, "p": self.parameters(band_data, loop_data)}
        if multipliers is not None:
            args["lam_x0"], args["lam_g0"] = multipliers
        self._limit.start(max_iter)
        sol = self.solver(**args)
        # IPOPT turns Ctrl-C into a failed solve: end the tuning instead of going on
        interrupt.check("the tuning (IPOPT)")
        stats = self.solver.stats()
        if self._limit.reached:
            stats = {**stats, "return_status": "Maximum_Iterations_Exceeded", "success": False}
        x = np.array(sol["x"]).ravel()
        # IPOPT may end a hair outside a bound (its bound_relax_factor): clip to the bounds
        values = {v: float(np.clip(self.scale[v] * math.exp(x[i]), *self.problem.bounds[v]))
                  for i, v in enumerate(self.free)}
        new = Design(**{**design.to_dict(), **values})
        return Solution(new, float(sol["f"]), stats, np.array(sol["g"]).ravel(),
                        (np.array(sol["lam_x"]).ravel(), np.array(sol["lam_g"]).ravel()), x)

    def violations(self, g: np.ndarray) -> dict:
        """Return the largest violation of each constraint group (scaled units).

        Parameters
        ----------
        g : numpy.ndarray
            Constraint values of a solve (:attr:`Solution.g`).

        Returns
        -------
        dict
            Group name -> largest violation (0 when the group holds).
        """
        out = {}
        for gi, lo, hi, group in zip(g, self.lbg, self.ubg, self.groups, strict=True):
            v = max(lo - gi, gi - hi, 0.0)
            out[group] = max(out.get(group, 0.0), v)
        return out

    def active(self, g: np.ndarray, tol: float = 1e-5) -> list[str]:
        """Return the constraint groups with a row at its bound (the epigraphs aside).

        Parameters
        ----------
        g : numpy.ndarray
            Constraint values of a solve.
        tol : float
            Relative distance to a bound counted as "at" it.

        Returns
        -------
        list of str
            The active groups, in the order of the rows.
        """
        out = []
        for group in dict.fromkeys(self.groups):
            if group in ("compliance peak", "chatter", "worst peak"):
                continue
            sel = [i for i, gg in enumerate(self.groups) if gg == group]
            lo, hi = self.lbg[sel], self.ubg[sel]
            near = np.zeros(len(sel), dtype=bool)
            fin = np.isfinite(lo)
            near[fin] |= np.abs(g[sel][fin] - lo[fin]) <= tol * np.maximum(1, np.abs(lo[fin]))
            fin = np.isfinite(hi)
            near[fin] |= np.abs(g[sel][fin] - hi[fin]) <= tol * np.maximum(1, np.abs(hi[fin]))
            if near.any():
                out.append(group)
        return out
