"""casadi tuning against closed forms, brute force, and an independent verification."""

import math

import numpy as np
import pytest
from axis_fixtures import PADS, small_axis, small_drive
from numpy.testing import assert_allclose

from servotune import twomass
from servotune.frequency import compliance as plant_compliance
from servotune.plant import Contact, build_plant, loop_transfer
from servotune.structure import ModalModel
from servotune.tuning import (
    ChatterTarget,
    Design,
    Requirements,
    RequirementsNotMetError,
    ResponseModel,
    TuningProblem,
    evaluate,
    tune,
)


def two_mass(m1=5000.0, k=16e6, alpha=0.3):
    structure = ModalModel(np.diag([m1, alpha * m1]), [[k, -k], [-k, k]], ["pad1.x", "wp.x"],
                           damping_ratio=0.0)
    system = twomass.TwoMassSystem(m1, k, alpha)
    w_f1, w_f2 = twomass.fixed_points(system)
    return structure, system, Requirements(band=(w_f1, 4 * w_f2))


@pytest.mark.parametrize("alpha", [0.15, 0.3, 0.7])
def test_two_mass_copt_is_the_closed_form(alpha):
    structure, system, req = two_mass(alpha=alpha)
    problem = TuningProblem(structure, ["pad1.x"], c=1e5, free=("c",), requirements=req,
                            bounds={"c": (1e3, 1e8)})
    result = tune(problem, starts=2, tolerance=1e-10)
    assert result.success, result.reasons
    assert_allclose(result.design.c, twomass.optimal_damping(system), rtol=1e-4)
    assert_allclose(result.after.peak_compliance, twomass.g_alpha(alpha) / system.k, rtol=1e-6)


def _direct(ss, omega):
    """Balanced direct evaluation of a SISO state space (python-control's own evaluation loses
    digits on these badly scaled systems)."""
    import scipy.linalg as sl

    a, t = sl.matrix_balance(ss.A, permute=False, separate=True)
    b, c = ss.B / t[0][:, None], ss.C * t[0][None, :]
    return np.array([(c @ np.linalg.solve(1j * w * np.eye(a.shape[0]) - a, b))[0, 0]
                     + ss.D[0, 0] for w in omega])


@pytest.mark.parametrize("digital", [False, True])
def test_port_responses_equal_the_state_space_plant(digital):
    # every regime model's contact in the port model against the closed loop: continuous, the
    # python-control state space (build_plant, loop_transfer); digital, the sampled-data
    # model (servotune.digital.SampledAxis: the plant's zero-order hold by expm, the lifts
    # summed over every term), which the port model's corrections make it equal at the design
    from servotune.digital import SampledAxis
    from servotune.drive import Sampling
    from servotune.friction import LuGreParameters
    from servotune.regimes import RegimeModel

    structure = small_axis()
    drive = small_drive(sampling=Sampling(speed_filter=2e-4) if digital else None)
    p = LuGreParameters(fc=300.0, fs=600.0, vs=0.01, delta=1.0, sigma0=1e9, sigma1=2e6,
                        sigma2=2e3, sigma1_decay_speed=1e-3)
    models = (RegimeModel("standing", "presliding", p),
              RegimeModel("standing", "describing", p, amplitude=2e-7, frequency=300.0),
              RegimeModel("feeding 30 mm/s", "sliding", p, speed=0.03),
              RegimeModel("viscous", "viscous"))
    problem = TuningProblem(structure, PADS, c=8e4, drive=drive, free=("c", "kv", "kp", "ti"),
                            regimes=models)
    design = Design(c=2.2e5, kv=30.0, kp=5.0, ti=4e-3)
    omega = 2 * np.pi * np.geomspace(0.5, 2000.0, 200)
    got = evaluate(problem, design, omega)
    d = problem.drive_for(design)
    for m, model in enumerate(models):
        contact = model.contact(design.c)
        if digital:
            ref = SampledAxis(structure, d, contact, PADS)
            h = ref.compliance(omega)[0]
            # above the position controller's Nyquist frequency the port model leaves the
            # position loop out (its rows repeat there; its share of the compliance is small)
            slow = omega < ref.nyquist("position")
            assert_allclose(got["compliance"][m][slow], h[slow], rtol=1e-8,
                            atol=1e-8 * np.abs(h).max())
            assert_allclose(got["compliance"][m], h, rtol=1e-4, atol=1e-8 * np.abs(h).max())
            for loop in ("velocity", "position"):
                # each loop up to its controller's Nyquist frequency; the position loop's rows
                # are zero above it in the port model
                below = omega < ref.nyquist(loop)
                lr = ref.loop_response(loop, omega[below])
                assert_allclose(got[f"loop_{loop}"][m][below], lr, rtol=1e-8,
                                atol=1e-8 * np.abs(lr).max())
            assert np.all(got["loop_position"][m][omega >= ref.nyquist("position")] == 0)
            continue
        plant = build_plant(structure, d, contact, PADS)
        assert_allclose(got["compliance"][m], plant_compliance(plant, omega), rtol=1e-8)
        for loop in ("velocity", "position"):
            ref = loop_transfer(structure, d, contact, PADS, loop)
            assert_allclose(got[f"loop_{loop}"][m], _direct(ref, omega), rtol=1e-8)


def test_frozen_corrections_of_the_digital_drive_stay_close_away_from_their_design():
    # the port model with its sampled-data corrections from another design (as the optimiser
    # uses them between exchange rounds) against the exact model: the hold's aliases do not
    # depend on the design, the lifts' further terms only a little
    from servotune.drive import Sampling
    from servotune.tuning import ResponseModel

    structure = small_axis()
    problem = TuningProblem(structure, PADS, c=8e4, drive=small_drive(sampling=Sampling()),
                            free=("c", "kv", "kp", "ti"))
    omega = 2 * np.pi * np.geomspace(0.5, 450.0, 300)
    reference = Design(c=8e4, kv=20.0, kp=3.0, ti=6e-3)
    design = Design(c=2.4e5, kv=35.0, kp=5.0, ti=4e-3)
    model = ResponseModel(problem, omega, reference)
    frozen, exact = model(design, exact=False), model(design)
    for name in ("loop_velocity", "loop_position"):
        s_frozen, s_exact = 1 / (1 + frozen[name]), 1 / (1 + exact[name])
        assert np.abs(s_frozen - s_exact).max() <= 1e-3 * np.abs(s_exact).max()
    h0, h1 = frozen["compliance"], exact["compliance"]
    assert np.abs(h0 - h1).max() <= 1e-3 * np.abs(h1).max()


def brute_force(problem, kp_values, c_values, omega_band, omega_loop):
    """Dense search of the same objective and constraints over (Kp, C), fixed Kv and Ti."""
    x0 = problem.initial_design()
    band, loop = ResponseModel(problem, omega_band), ResponseModel(problem, omega_loop)
    best = (math.inf, None)
    for kp in kp_values:
        for c in c_values:
            d = Design(c=c, kv=x0.kv, kp=kp, ti=x0.ti)
            loops = loop(d)
            if all(np.abs(1 + loops[f"loop_{k}"][0]).min()
                   >= 1 / problem.requirements.ms_limit(k) for k in ("velocity", "position")):
                value = np.abs(band(d)["compliance"][0]).max()
                if value < best[0]:
                    best = (value, d)
    return best


def test_casadi_is_at_least_as_good_as_brute_force():
    structure, drive = small_axis(), small_drive()
    # the brute force knows only the Ms limits: the loop-quality rows are switched off
    req = Requirements(ms_velocity_max=1.5, ms_position_max=1.4, bandwidth_ratio_min=0,
                       current_bandwidth_ratio_min=0, ti_bandwidth_min=0, ti_bandwidth_max=0)
    problem = TuningProblem(structure, PADS, c=5e4, drive=drive, free=("c", "kp"),
                            requirements=req, bounds={"c": (1e3, 2e6), "kp": (0.3, 30.0)})
    result = tune(problem, starts=3)
    assert result.success, result.reasons
    omega_band = np.geomspace(*req.band, 600)
    omega_loop = np.geomspace(*req.loop_band, 600)
    value, design = brute_force(problem, np.geomspace(0.3, 30.0, 41), np.geomspace(1e3, 2e6, 41),
                                omega_band, omega_loop)
    assert design is not None
    tuned = np.abs(ResponseModel(problem, omega_band)(result.design)["compliance"][0]).max()
    assert tuned <= value * (1 + 1e-6)
    # and the brute-force optimum lies next to the casadi one (same basin, not a lucky grid)
    assert abs(math.log(design.c / result.design.c)) < math.log(2e6 / 1e3) / 40 * 1.5


def test_constraints_hold_on_a_grid_the_optimiser_never_saw():
    structure, drive = small_axis(), small_drive()
    req = Requirements(ms_velocity_max=1.6, ms_position_max=1.3, kv_min=10.0)
    problem = TuningProblem(structure, PADS, c=5e4, drive=drive,
                            free=("c", "kv", "kp", "ti"), requirements=req)
    result = tune(problem, starts=2)
    assert result.success, result.reasons
    # verification used python-control on its own dense grids; check once more here on a grid
    # shifted from every grid the optimiser built
    omega = np.geomspace(req.loop_band[0] * 1.0007, req.loop_band[1], 20011)
    d = problem.drive_for(result.design)
    for loop in ("velocity", "position"):
        lt = loop_transfer(structure, d, Contact.viscous(result.design.c), PADS, loop)
        s = 1 / (1 + np.array([complex(lt(1j * w)) for w in omega[::5]]))
        assert np.abs(s).max() <= req.ms_limit(loop) * (1 + 1e-3)
    assert result.design.kv >= 10.0 * (1 - 1e-9)
    assert result.after.peak_compliance < result.before.peak_compliance


def test_unreachable_requirement_names_the_binding_constraint():
    structure, drive = small_axis(), small_drive()
    req = Requirements(ms_velocity_max=1.01, ms_position_max=1.5)
    kp0 = drive.velocity_loop.kp
    problem = TuningProblem(structure, PADS, c=5e4, drive=drive, free=("kp",), requirements=req,
                            bounds={"kp": (kp0, 2 * kp0)})
    with pytest.raises(RequirementsNotMetError, match="Ms velocity loop"):
        tune(problem, starts=1)


@pytest.mark.parametrize("kwargs, message", [
    (dict(free=("c", "gain")), "unknown design variables"),
    (dict(free=("kv",), drive=None), "need a drive"),
    (dict(bounds={"c": (1e6, 1e7)}), "bounds of c"),
    (dict(weights=(0.0, 1.0)), "ChatterTarget"),
])
def test_bad_problems_are_refused(kwargs, message):
    base = dict(structure=small_axis(), pads=PADS, c=5e4, drive=small_drive(), free=("c",))
    base.update(kwargs)
    with pytest.raises(ValueError, match=message):
        TuningProblem(**base)


def test_requirements_margins_tighten_ms():
    req = Requirements(ms_velocity_max=3.0, phase_margin_min_deg=45.0, gain_margin_min_db=6.0)
    # PM 45 deg needs Ms <= 1/(2 sin 22.5 deg) = 1.307; GM 6 dB needs Ms <= 2
    assert req.ms_limit("velocity") == pytest.approx(1.0 / (2 * math.sin(math.radians(22.5))))


def _numpy_rows(problem, loop_model, d, gates, current_bw):
    """The NLP's loop rows restated in numpy from the module docstring of tuning.nlp (the
    gated rows with their logistic gates), for every model: (rows, models, frequencies)."""
    from servotune.tuning.nlp import GATE_SHARPNESS

    def sig(y):
        return 1.0 / (1.0 + np.exp(-GATE_SHARPNESS * y))

    req = problem.requirements
    res = loop_model(d)
    lv, lp = res["loop_velocity"], res["loop_position"]
    lw = np.log(loop_model.omega)[None, :]
    lv2 = np.abs(lv) ** 2
    tv2 = lv2 / np.abs(1 + lv) ** 2
    on_h, e_h, on_lo, e_lo, _, _, on_i, e_i = (gates[:, k][:, None] for k in range(8))
    return np.array([
        np.abs(1 + lv) ** 2 * req.ms_limit("velocity") ** 2,
        np.abs(1 + lp) ** 2 * req.ms_limit("position") ** 2,
        (tv2 - 0.5) / (tv2 + 0.5) + sig(lw - e_h - np.log(d.kv)) + 2 * (1 - on_h),
        (tv2 - 0.5) / (tv2 + 0.5) + sig(lw - e_lo + np.log(d.ti)) + 2 * (1 - on_lo),
        # (the upper bound of Ti x bandwidth is judged on the design, not a row)
        (0.5 - tv2) / (0.5 + tv2) + sig(e_i - lw) + sig(lw - e_i - np.log(1.25))
        + 2 * (1 - on_i)])


@pytest.mark.parametrize("active", ["objective and peak", "chatter", "Ms loops", "gated loops",
                                    "kv_min and thrust"])
def test_hessian_given_to_ipopt_matches_finite_differences_of_the_port_model(active):
    # The Hessian of the Lagrangian IPOPT receives is assembled from per-frequency kernel
    # Hessians (chain rule through the log variables, the epigraphs, the tracking term, the
    # thrust and kv_min rows); check it against central differences of the same Lagrangian
    # evaluated with numpy (ResponseModel and the rows restated above), one constraint group at
    # a time so each is seen at its own scale, with two regime models.
    from servotune.friction import LuGreParameters
    from servotune.regimes import Operation, RegimeModel
    from servotune.thrust import ThrustBudget
    from servotune.tuning.nlp import Kernels, Solver, gate_parameters

    structure, drive = small_axis(), small_drive()
    req = Requirements(ms_velocity_max=1.6, ms_position_max=1.4, kv_min=5.0)
    p = LuGreParameters(fc=300.0, fs=600.0, vs=0.01, delta=1.0, sigma0=1e9, sigma1=2e6,
                        sigma2=2e3)
    models = (RegimeModel("standing", "presliding", p),
              RegimeModel("feeding 30 mm/s", "sliding", p, speed=0.03))
    budget = ThrustBudget(4e4, 1.5e4, 0.2, 1100.0, p,
                          Operation(feed_speeds=(0.03,), rapid_speed=0.5, acceleration=2.0))
    problem = TuningProblem(structure, PADS, c=5e4, drive=drive, free=("c", "kv", "kp", "ti"),
                            requirements=req, weights=(0.6, 0.4), regimes=models,
                            thrust=budget, chatter=ChatterTarget(kt=6e8, mu=0.5))
    x0 = problem.initial_design()
    band_model = ResponseModel(problem, np.geomspace(*req.band, 7))
    loop_model = ResponseModel(problem, np.geomspace(2 * np.pi * 20, 2 * np.pi * 2000, 9))
    h0 = float(np.abs(band_model(x0)["compliance"]).max())
    s0 = 1e-7
    current_bw = 2 * np.pi * 700.0
    gates = gate_parameters(problem, np.array([1.3, 1.1]), current_bw)
    solver = Solver(problem, Kernels(problem, h0, s0), 7, 9)
    params = solver.parameters(band_model.data.rows(models=[0, 1]),
                               loop_model.data.rows(gates))
    groups = np.array(solver.groups)
    rng = np.random.default_rng(7)
    lam_g = rng.uniform(0.2, 1.0, groups.size)
    lam_f = 0.8 if active == "objective and peak" else 0.0
    keep = {"objective and peak": ["compliance peak", "worst peak"], "chatter": ["chatter"],
            "Ms loops": ["Ms velocity loop", "Ms position loop"],
            "gated loops": ["loop hierarchy", "Ti bandwidth min",
                            "current loop above"],
            "kv_min and thrust": ["kv_min", "thrust: rapid traverse",
                                  "thrust: feeding 30 mm/s"]}[active]
    lam_g[~np.isin(groups, keep)] = 0.0
    assert set(keep) <= set(groups)

    def lagrangian(x):
        d = Design(**{v: getattr(x0, v) * math.exp(x[i]) for i, v in enumerate(problem.free)})
        t, tm, q = x[4], x[5:7], x[7]
        h = band_model(d)["compliance"]
        rows = _numpy_rows(problem, loop_model, d, gates, current_bw)
        thrust = [(fixed + d.c * speed) / usable
                  for fixed, speed, usable, _ in budget.linear_form() if speed > 0]
        g = np.concatenate([
            (np.abs(h) ** 2 / h0**2 - tm[:, None] ** 2).ravel(),
            (0.5 * h.real / s0 + q).ravel(),
            t - tm,
            # the gated rows (after the two Ms rows) in the moving models only
            *[(r if i < 2 else r[list(problem.moving_models)]).ravel()
              for i, r in enumerate(rows)],
            thrust, [d.kv / req.kv_min]])
        c_lo, span = problem.c_cost
        f = (0.6 * (t + problem.mean_weight * tm.mean()) + 0.4 * q
             + problem.tracking_weight * x0.kv / d.kv + problem.c_cost_weight * (d.c - c_lo) / span)
        return lam_f * f + lam_g @ g

    x = np.array([0.3, -0.2, 0.1, 0.4, 0.9, 0.8, 0.85, 0.0])
    step = 1e-4
    n = x.size
    fd = np.zeros((n, n))
    for i in range(n):
        for j in range(n):
            ei, ej = np.eye(n)[i] * step, np.eye(n)[j] * step
            fd[i, j] = (lagrangian(x + ei + ej) - lagrangian(x + ei - ej)
                        - lagrangian(x - ei + ej) + lagrangian(x - ei - ej)) / (4 * step**2)
    upper = np.array(solver.hessian(x, params, lam_f, lam_g))
    exact = upper + upper.T - np.diag(np.diag(upper))
    # central differences: truncation ~ step^2 = 1e-8 relative, round-off ~ 1e-16/step^2
    assert_allclose(exact, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
    assert np.abs(fd).max() > 0


def test_a_solver_with_unused_grid_slots_finds_the_same_optimum_as_one_of_exact_size():
    # One solver serves every round of the grid exchange: grids smaller than its capacity are
    # padded and the padded constraints switched off by a mask. The reference is the NLP built
    # for exactly the grid's size: same design, objective and active constraints.
    from servotune.tuning.nlp import Kernels, Solver, gate_parameters
    from servotune.tuning.solve import _scale_factors

    structure, drive = small_axis(), small_drive()
    req = Requirements(ms_velocity_max=1.6, ms_position_max=1.3, kv_min=10.0)
    problem = TuningProblem(structure, PADS, c=5e4, drive=drive,
                            free=("c", "kv", "kp", "ti"), requirements=req)
    x0 = problem.initial_design()
    kernels = Kernels(problem, *_scale_factors(problem, x0))
    band = ResponseModel(problem, np.geomspace(*req.band, 40))
    loop = ResponseModel(problem, np.geomspace(*req.loop_band, 50))
    gates = gate_parameters(problem, np.ones(len(problem.regimes)), None)
    band_rows = band.data.rows(models=list(problem.cutting_models))
    loop_rows = loop.data.rows(gates)
    exact = Solver(problem, kernels, 40, 50).solve(x0, band_rows, loop_rows)
    padded_solver = Solver(problem, kernels, 40 + 13, 50 + 29)
    padded = padded_solver.solve(x0, band_rows, loop_rows)
    assert exact.converged and padded.converged
    assert padded.objective == pytest.approx(exact.objective, rel=1e-8)
    for v in problem.free:
        assert getattr(padded.design, v) == pytest.approx(getattr(exact.design, v), rel=1e-6)
    # the unused slots have no key and carry no multiplier
    keys = padded_solver.row_keys(band.omega, loop.omega)
    unused = [i for i, k in enumerate(keys) if k is None]
    assert len(unused) == 13 * len(problem.cutting_models) * len(kernels.band_rows) \
        + 29 * len(problem.regimes) * len(kernels.loop_rows)
    assert np.abs(padded.multipliers[1][unused]).max() < 1e-8


def test_an_iteration_limit_per_solve_stops_ipopt_there():
    from servotune.tuning.nlp import Kernels, Solver, gate_parameters
    from servotune.tuning.solve import _scale_factors

    structure, drive = small_axis(), small_drive()
    problem = TuningProblem(structure, PADS, c=5e4, drive=drive, free=("c", "kv", "kp", "ti"),
                            requirements=Requirements())
    x0 = problem.initial_design()
    kernels = Kernels(problem, *_scale_factors(problem, x0))
    band = ResponseModel(problem, np.geomspace(*problem.requirements.band, 30))
    loop = ResponseModel(problem, np.geomspace(*problem.requirements.loop_band, 30))
    rows = (band.data.rows(models=list(problem.cutting_models)),
            loop.data.rows(gate_parameters(problem, np.ones(len(problem.regimes)), None)))
    solver = Solver(problem, kernels, 30, 30)
    full = solver.solve(x0, *rows)
    assert full.converged and full.stats["iter_count"] > 5
    cut = solver.solve(x0, *rows, max_iter=3)
    assert not cut.converged and cut.stats["iter_count"] == 3
    again = solver.solve(x0, *rows)          # the limit holds for one solve only
    assert again.converged and again.stats["iter_count"] == full.stats["iter_count"]
