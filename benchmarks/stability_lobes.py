"""Stability lobes: vectorised zero-order lobes and semi-discretisation against plain loops.

Case: the milling benchmark of Insperger and Stepan (2 teeth, Kt = 6e8 N/m^2, Kn = 2e8 N/m^2,
f_n = 922 Hz, zeta = 0.011, modal mass 0.03993 kg, down-milling).

1. Zero-order lobes for 10,000 spindle speeds and 20 lobes (full slot):
   servotune.chatter.stability_lobes (lobes as parametric curves, all segments sampled on the
   speed grid at once) against a loop over the speeds that, at each speed, finds the
   frequencies satisfying the phase condition on the same oriented FRF (given ready-made, not
   timed): numpy over the 2,301 frequencies of each eigenvalue (lobe number, crossings), a
   Python loop over the few crossings. Its cost is the lobe number at every (speed, frequency,
   eigenvalue), 46 M values, not the Python loop: vectorising the crossings and both
   eigenvalues, or whole blocks of 64-1,024 speeds, gave the same results in 0.80-1.06 s
   against this loop's 0.85 s (10,000 speeds, best of 2 each, same process), so the plain
   loop is kept.
2. Semi-discretisation on a 200 x 200 (speed, depth) grid, 40 intervals per period, a/D = 0.05,
   5,000-25,000 rpm, 0-10 mm: servotune.chatter.stability_map (batched matrix exponentials and
   monodromy for all grid points) against a loop over the grid points that, per grid point,
   stacks the 40 augmented interval matrices as one (40, k, k) array and calls
   scipy.linalg.expm once on the stack (scipy >= 1.9), then builds and multiplies the dense
   (n + m) x (n + m) interval maps one by one and takes np.linalg.eigvals of the monodromy
   matrix. The loop is timed on a sub-grid (12 x 12 by default, one run) and compared per grid
   point with servotune's spectral radius and stable / unstable verdict (also timed against
   the vectorised code on the same sub-grid). This is the top-level ``speedup``.
3. The rule behind the default intervals: the error of b_lim with m = 40, 80, 160 where a
   tooth period spans 2.3, 4.3 and 8.3 periods of the mode (near lobe minima), against the
   converged limit, and the constant K in error = K (T f / m)^2.
4. Accuracy of servotune.chatter.sdm_lobes at its defaults (intervals chosen per speed and
   refined until the estimated error of b_lim is below 1 %; 200 speeds over the default range)
   for a/D = 1, 0.1 and 0.05: b_lim at 16 of the speeds against a converged reference (m = 452
   and 640 intervals, extrapolated at second order), beside the former fixed 40 intervals.
5. Convergence of the semi-discretisation: b_lim at the critical speeds of a/D = 1 and
   a/D = 0.05 as the number of intervals per period grows, with the cost per grid point.

BLAS and OpenMP are held to one thread (before numpy is imported) for both methods: the
matrices are small, and on a shared machine multi-threaded BLAS on 4 x 4 matrices mostly waits
for its threads (scipy.linalg.expm of a 4 x 4 matrix was measured 10-50 times slower).

Usage: ``python benchmarks/stability_lobes.py [--json] [--repeat N] [--subgrid K]``
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import scipy.linalg  # noqa: E402
from _timing import best_time  # noqa: E402

from servotune import chatter  # noqa: E402

WN = 2 * math.pi * 922.0
ZETA = 0.011
SYSTEM = chatter.modal_compliance([chatter.Mode(WN, ZETA, 0.03993 * WN**2)])


def setup(ae):
    return chatter.MillingSetup(teeth=2, kt=6e8, kn=2e8, radial_immersion=ae, milling="down")



# --- baselines --------------------------------------------------------------------------------

def zoa_speed_loop(omega, phi, kt, teeth, speeds, lobes):
    """Baseline: at every speed, the frequencies where w T - theta(w) = 2 pi k, k < lobes."""
    re = phi.real
    with np.errstate(divide="ignore"):
        inv_depth = np.where(re < 0.0, -2.0 * kt * re, 0.0)          # 1 / b_lim
        theta = math.pi + 2.0 * np.arctan(np.divide(phi.imag, re, out=np.zeros_like(re),
                                                    where=re != 0.0))
    valid = re < 0.0
    out = np.full(speeds.size, np.inf)
    for i, n in enumerate(speeds):
        period = 60.0 / (teeth * n)
        for e in range(phi.shape[1]):
            x = (omega * period - theta[:, e]) / (2.0 * math.pi)          # lobe number
            k = np.floor(x)
            cross = np.flatnonzero((k[1:] != k[:-1]) & valid[1:, e] & valid[:-1, e])
            for j in cross:
                target = max(k[j], k[j + 1])
                if not 0 <= target < lobes:
                    continue
                t = (target - x[j]) / (x[j + 1] - x[j])
                inv = inv_depth[j, e] + t * (inv_depth[j + 1, e] - inv_depth[j, e])
                out[i] = min(out[i], 1.0 / inv)
    return out


def sdm_point_loop(model, h, period, depth):
    """Baseline: one grid point; the m interval matrices in one (m, k, k) stack through one
    scipy.linalg.expm call, then the dense interval maps multiplied one by one."""
    a, bf, c = model.a, model.b, model.c
    n, r = bf.shape
    m = h.shape[0]
    dt = period / m
    size = n + m * r
    bh = depth * h                                          # (m, r, r)
    aug = np.zeros((m, n + 2 * r, n + 2 * r))
    aug[:, :n, :n] = a - bf @ bh @ c
    aug[:, :n, n:n + r] = bf
    aug[:, n:n + r, n + r:] = np.eye(r)
    e = scipy.linalg.expm(aug * dt)                         # all m intervals at once
    phi = np.eye(size)
    for i in range(m):
        g1, g2 = e[i, :n, n:n + r], e[i, :n, n + r:] / dt
        z = np.zeros((size, size))
        z[:n, :n] = e[i, :n, :n]
        z[:n, n + (m - 1) * r:] += (g1 - g2) @ bh[i]          # q_(i-m)
        z[:n, n + (m - 2) * r:n + (m - 1) * r] += g2 @ bh[i]  # q_(i-m+1)
        z[n:n + r, :n] = c                                    # q_i enters the history
        z[n + r:, n:n + (m - 1) * r] = np.eye((m - 1) * r)    # shift
        phi = z @ phi
    return float(np.max(np.abs(np.linalg.eigvals(phi))))


# --- the runs -----------------------------------------------------------------------------------

def bench_zoa(repeat):
    s = setup(1.0)
    speeds = np.linspace(2000.0, 40000.0, 10_000)
    t_vec, result = best_time(lambda: chatter.stability_lobes(SYSTEM, s, speeds, lobes=20),
                              repeat)
    # the baseline gets the frequency response and oriented FRF ready-made (not timed)
    omega = chatter.frequency_grid(SYSTEM, omega_max=1.1 * 2 * math.pi * 2 * speeds[-1] / 60)
    _, g = chatter.compliance_matrix(SYSTEM, omega)
    phi = chatter.oriented_frf(g, s)
    t_loop, loop = best_time(lambda: zoa_speed_loop(omega, phi, s.kt, s.teeth, speeds, 20), 1)
    finite = np.isfinite(loop) & np.isfinite(result.depth_limit)
    return {
        "speeds": speeds.size, "lobes": 20, "frequencies": omega.size,
        "vectorised_s": t_vec, "speed_loop_s": t_loop, "speedup": t_loop / t_vec,
        "target_s": 0.05, "meets_target": t_vec < 0.05,
        "max_relative_difference": float(np.max(np.abs(result.depth_limit[finite]
                                                       / loop[finite] - 1.0))),
        "speeds_compared": int(finite.sum()),
        "b_crit_m": result.b_crit, "critical_speed_rpm": result.critical_speed_rpm,
    }


def bench_sdm(repeat, sub):
    s = setup(0.05)
    speeds = np.linspace(5000.0, 25000.0, 200)
    depths = np.linspace(0.0, 10e-3, 200)
    m = 40
    t_vec, grid = best_time(lambda: chatter.stability_map(SYSTEM, s, speeds, depths,
                                                          intervals=m), repeat)
    model = chatter.cutting_state_space(SYSTEM)
    dirs = list(model.directions)
    h = chatter.periodic_directional_matrix(s, m)[:, dirs][:, :, dirs]
    pick_s = np.linspace(0, speeds.size - 1, sub).astype(int)
    pick_d = np.linspace(0, depths.size - 1, sub).astype(int)

    def loop():
        return np.array([[sdm_point_loop(model, h, 60.0 / (s.teeth * speeds[i]), depths[j])
                          for j in pick_d] for i in pick_s])

    t_loop, rho_loop = best_time(loop, 1)
    t_vec_sub, _ = best_time(lambda: chatter.stability_map(
        SYSTEM, s, speeds[pick_s], depths[pick_d], intervals=m), repeat)
    per_vec = t_vec / (speeds.size * depths.size)
    per_loop = t_loop / (sub * sub)
    return {
        "grid": [speeds.size, depths.size], "intervals": m, "radial_immersion": 0.05,
        "vectorised_s": t_vec, "vectorised_per_point_s": per_vec,
        "loop_subgrid": [sub, sub], "loop_subgrid_s": t_loop, "loop_per_point_s": per_loop,
        "loop_full_grid_estimate_s": per_loop * speeds.size * depths.size,
        "speedup": per_loop / per_vec,
        "vectorised_same_subgrid_s": t_vec_sub,
        "speedup_same_subgrid": t_loop / t_vec_sub,
        "max_abs_difference_spectral_radius": float(np.max(np.abs(
            grid.spectral_radius[np.ix_(pick_s, pick_d)] - rho_loop))),
        "stability_equal_on_subgrid": bool(np.array_equal(
            grid.stable[np.ix_(pick_s, pick_d)], rho_loop < 1.0)),
        "stability_differing_points": int(np.count_nonzero(
            grid.stable[np.ix_(pick_s, pick_d)] != (rho_loop < 1.0))),
        "stable_fraction": float(grid.stable.mean()),
    }


def converged_limits(s, speeds, depth_max):
    """b_lim with m = 452 and 640, extrapolated at second order."""
    from servotune.chatter.sdm import _limit_depths

    model = chatter.cutting_state_space(SYSTEM)
    period = 60.0 / (s.teeth * np.asarray(speeds))
    b = [_limit_depths(model, chatter.periodic_directional_matrix(s, m)[:, :1, :1], period,
                       depth_max, 16, 1e-7) for m in (452, 640)]
    with np.errstate(invalid="ignore"):
        return np.where(np.isfinite(b[1]), b[1] + (b[1] - b[0]) / ((640 / 452) ** 2 - 1), b[1])


def interval_rule_study():
    """Error of b_lim against the converged limit for m = 40, 80, 160 at speeds where a tooth
    period spans T f = 2.3, 4.3, 8.3 periods of the mode (near lobe minima), and the constant K
    of error = K (T f / m)^2 (the basis of INTERVALS_PER_MODE_PERIOD)."""
    rows = []
    for ae in (1.0, 0.1, 0.05):
        s = setup(ae)
        tf = np.array([8.3, 4.3, 2.3])  # ascending speeds
        speeds = 60.0 / (s.teeth * tf / 922.0)
        depth_max = 10.0 * chatter.absolute_stability_limit(SYSTEM, s)[0]
        ref = converged_limits(s, speeds, depth_max)
        for m in (40, 80, 160):
            b = chatter.sdm_lobes(SYSTEM, s, speeds, depth_max, intervals=m,
                                  tol=1e-6).depth_limit
            for k in range(speeds.size):
                if not (np.isfinite(ref[k]) and np.isfinite(b[k])):
                    continue
                err = b[k] / ref[k] - 1.0
                rows.append({"radial_immersion": ae, "speed_rpm": float(speeds[k]),
                             "periods_of_mode_per_tooth_period": float(tf[k]), "intervals": m,
                             "error": float(err),
                             "k_constant": float(abs(err) / (tf[k] / m) ** 2)})
    return rows


def accuracy_at_defaults():
    rows = []
    for ae in (1.0, 0.1, 0.05):
        s = setup(ae)
        t0 = time.perf_counter()
        r = chatter.sdm_lobes(SYSTEM, s)
        elapsed = time.perf_counter() - t0
        pick = np.linspace(0, r.speed_rpm.size - 1, 16).astype(int)
        speeds = r.speed_rpm[pick]
        ref = converged_limits(s, speeds, r.depth_ceiling)
        t0 = time.perf_counter()
        fixed = chatter.sdm_lobes(SYSTEM, s, r.speed_rpm, r.depth_ceiling, intervals=40)
        elapsed_fixed = time.perf_counter() - t0
        finite = np.isfinite(ref) & np.isfinite(r.depth_limit[pick])
        err = r.depth_limit[pick][finite] / ref[finite] - 1.0
        err_fixed = fixed.depth_limit[pick][finite] / ref[finite] - 1.0
        values, counts = np.unique(r.intervals_by_speed, return_counts=True)
        rows.append({
            "radial_immersion": ae, "speed_range_rpm": [float(r.speed_rpm[0]),
                                                        float(r.speed_rpm[-1])],
            "speeds": int(r.speed_rpm.size), "time_default_s": elapsed,
            "time_fixed_40_s": elapsed_fixed, "compared_speeds": int(finite.sum()),
            "max_abs_error_default": float(np.abs(err).max()),
            "max_error_estimate_default": r.max_error_estimate,
            "max_abs_error_fixed_40": float(np.abs(err_fixed).max()),
            "intervals_used": {str(int(v)): int(c) for v, c in zip(values, counts,
                                                                    strict=True)},
            "b_crit_default_m": r.b_crit, "b_crit_fixed_40_m": fixed.b_crit,
        })
    return rows


def convergence():
    rows = []
    for ae, speeds, top in ((1.0, (15000.0, 17000.0), 2e-3), (0.05, (17900.0, 18400.0), 3e-3)):
        s = setup(ae)
        ref = chatter.sdm_lobes(SYSTEM, s, np.linspace(*speeds, 11), top, intervals=40)
        n = ref.critical_speed_rpm
        for m in (10, 20, 40, 80, 160):
            t0 = time.perf_counter()
            r = chatter.sdm_lobes(SYSTEM, s, [n, n * (1 + 1e-9)], top, intervals=m, tol=1e-6)
            elapsed = time.perf_counter() - t0
            t0 = time.perf_counter()
            chatter.stability_map(SYSTEM, s, [n, n + 1.0], np.linspace(0, top, 50), intervals=m)
            per_point = (time.perf_counter() - t0) / 100
            rows.append({"radial_immersion": ae, "speed_rpm": n, "intervals": m,
                         "b_lim_m": float(r.depth_limit[0]), "limit_search_s": elapsed,
                         "per_grid_point_s": per_point})
    for ae in (1.0, 0.05):
        sel = [r for r in rows if r["radial_immersion"] == ae]
        b = [r["b_lim_m"] for r in sel]
        for i, r in enumerate(sel):
            finite = i > 0 and math.isfinite(b[i - 1]) and math.isfinite(b[i])
            r["change_from_previous"] = b[i] / b[i - 1] - 1.0 if finite else None
            if 0 < i < len(sel) - 1 and all(math.isfinite(v) for v in b[i - 1:i + 2]):
                r["observed_order"] = math.log2(abs(b[i - 1] - b[i]) / abs(b[i] - b[i + 1]))
    return rows


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--repeat", type=int, default=5, help="repeats of the fast runs (best kept)")
    p.add_argument("--subgrid", type=int, default=12,
                   help="the semi-discretisation loop runs on SUBGRID x SUBGRID points")
    args = p.parse_args(argv)
    sdm = bench_sdm(max(1, args.repeat // 2), args.subgrid)
    zoa = bench_zoa(args.repeat)
    accuracy = accuracy_at_defaults()
    result = {"baseline": "semi-discretisation map: a plain loop over the grid points "
                          "(one scipy.linalg.expm call per grid point on the stack of its 40 "
                          "interval matrices, dense products, eigvals), 40 intervals",
              "speedup": sdm["speedup"], "speedup_zero_order_lobes": zoa["speedup"],
              "max_abs_error_sdm_lobes_at_defaults": max(
                  r["max_abs_error_default"] for r in accuracy),
              "blas_threads": os.environ["OPENBLAS_NUM_THREADS"],
              "zoa": zoa, "sdm": sdm, "sdm_accuracy_at_defaults": accuracy,
              "sdm_interval_rule": interval_rule_study(),
              "sdm_convergence": convergence()}
    if args.json:
        print(json.dumps(result, indent=2))
        return result
    z, s = result["zoa"], result["sdm"]
    print(f"zero-order: {z['speeds']} speeds x {z['lobes']} lobes: "
          f"{1e3 * z['vectorised_s']:.1f} ms (target 50 ms), loop over speeds "
          f"{1e3 * z['speed_loop_s']:.0f} ms, "
          f"speedup {z['speedup']:.0f}x, max rel. difference {z['max_relative_difference']:.1e}")
    print(f"semi-discretisation {s['grid'][0]} x {s['grid'][1]}, m = {s['intervals']}: "
          f"{s['vectorised_s']:.2f} s ({1e6 * s['vectorised_per_point_s']:.0f} us/point); loop "
          f"{1e6 * s['loop_per_point_s']:.0f} us/point on {s['loop_subgrid'][0]}^2 points "
          f"(full grid ~{s['loop_full_grid_estimate_s']:.0f} s); speedup {s['speedup']:.1f}x "
          f"(same sub-grid {s['speedup_same_subgrid']:.1f}x); max |d rho| "
          f"{s['max_abs_difference_spectral_radius']:.1e}, stable/unstable verdicts differ at "
          f"{s['stability_differing_points']} points")
    print("sdm_lobes at its defaults against a converged reference (16 speeds):")
    for r in result["sdm_accuracy_at_defaults"]:
        print(f"  a/D = {r['radial_immersion']:<4g} {r['speeds']} speeds "
              f"{r['speed_range_rpm'][0]:.0f}-{r['speed_range_rpm'][1]:.0f} rpm: "
              f"{r['time_default_s']:.1f} s, max error {100 * r['max_abs_error_default']:.2f} % "
              f"(estimated {100 * r['max_error_estimate_default']:.2f} %); fixed m = 40: "
              f"{r['time_fixed_40_s']:.1f} s, max error {100 * r['max_abs_error_fixed_40']:.1f} %")
    print("convergence of b_lim at the critical speed:")
    for r in result["sdm_convergence"]:
        change = r["change_from_previous"]
        print(f"  a/D = {r['radial_immersion']:<4g} n = {r['speed_rpm']:8.1f} rpm  m = "
              f"{r['intervals']:3d}  b_lim = {1e3 * r['b_lim_m']:.5f} mm  "
              + ("" if change is None else f"change {100 * change:+.3f} %  ")
              + ("" if "observed_order" not in r else f"order {r['observed_order']:.2f}  ")
              + f"{1e6 * r['per_grid_point_s']:.0f} us/point")
    return result


if __name__ == "__main__":
    main()
