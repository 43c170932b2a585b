"""Craig-Bampton reduction of a 3D solid model of a slide: sparse against dense.

The model is a ribbed cast-iron slide, 1.6 m x 1.0 m x 0.25 m: a base plate (the lower 40 % of
the height) with longitudinal and transverse ribs every sixth element, meshed with 8-node
hexahedra (trilinear, 2x2x2 Gauss; element matrices derived and assembled here with numpy, all
elements being the same brick). The boundary is the translation of the four pad points under
the corners and of the work-piece point on top (15 DOFs); 25 fixed-interface modes are kept, so
the reduced model has 40 DOFs.

Methods, each timed in a fresh process (peak resident memory from ``getrusage``):

* ``sparse``: :func:`servotune.structure.craig_bampton` as shipped (one sparse Cholesky of K_ii
  for the constraint modes and the shift-invert Lanczos of ``eigsh``; PARDISO when
  ``pypardiso`` is installed, else SuperLU);
* ``superlu``: the same with scipy's SuperLU forced;
* ``dense`` (the baseline): dense Cholesky solve for the constraint modes and the dense
  generalised eigen-solution ``scipy.linalg.eigh(K_ii, M_ii, subset_by_index=...)``, which is
  how a reduction is written without sparse solvers. It runs only at sizes where it fits.

Usage: ``python benchmarks/craig_bampton.py [--json] [--sizes N ...] [--dense-max N]``.
Needs only numpy/scipy; ``pip install -e '.[bench]'`` adds pypardiso (the ``fast`` solver).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import time

import numpy as np
import scipy.linalg
import scipy.sparse as sp

LX, LY, LZ = 1.6, 1.0, 0.25
E, NU, RHO = 1.2e11, 0.26, 7200.0       # grey cast iron
N_MODES = 25
PADS = [(0.2, 0.15, 0.0), (1.4, 0.15, 0.0), (0.2, 0.85, 0.0), (1.4, 0.85, 0.0)]
WORK_PIECE = (0.8, 0.5, LZ)


def hex8(hx, hy, hz):
    """Stiffness and consistent mass of one hx x hy x hz brick (DOFs node-major, x y z)."""
    corners = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                        [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)
    lam = E * NU / ((1 + NU) * (1 - 2 * NU))
    mu = E / (2 * (1 + NU))
    d = np.zeros((6, 6))
    d[:3, :3] = lam
    d[range(3), range(3)] += 2 * mu
    d[range(3, 6), range(3, 6)] = mu
    half = np.array([hx, hy, hz]) / 2
    det = np.prod(half)
    ke, me = np.zeros((24, 24)), np.zeros((24, 24))
    gauss = np.array([-1.0, 1.0]) / math.sqrt(3.0)
    for xi in np.array(np.meshgrid(gauss, gauss, gauss)).reshape(3, -1).T:
        f = 1 + corners * xi                     # (8, 3) factors of the shape functions
        n = f.prod(axis=1) / 8
        dn = np.empty((8, 3))
        for k in range(3):
            dn[:, k] = corners[:, k] * np.prod(np.delete(f, k, axis=1), axis=1) / 8 / half[k]
        b = np.zeros((6, 24))
        for k in range(3):
            b[k, k::3] = dn[:, k]
        b[3, 0::3], b[3, 1::3] = dn[:, 1], dn[:, 0]
        b[4, 1::3], b[4, 2::3] = dn[:, 2], dn[:, 1]
        b[5, 0::3], b[5, 2::3] = dn[:, 2], dn[:, 0]
        ke += b.T @ d @ b * det
        nm = np.kron(n, np.eye(3))
        me += RHO * nm.T @ nm * det
    return ke, me


def slide_model(n_target: int):
    """Sparse M, K of the ribbed slide with about ``n_target`` DOFs, and node coordinates."""
    # element counts in the ratio of the part, refined until the DOF count is reached
    scale = 1.0
    while True:
        nx, ny, nz = (max(2, round(v * scale)) for v in (16, 10, 2.5))
        count = _node_count(nx, ny, nz) * 3
        if count >= n_target:
            break
        scale *= 1.02
    hx, hy, hz = LX / nx, LY / ny, LZ / nz
    ex, ey, ez = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz),
                                                 indexing="ij"))
    keep = _solid(ex, ey, ez, nx, ny, nz)
    ex, ey, ez = ex[keep], ey[keep], ez[keep]
    offsets = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                        [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]])
    grid_id = ((ex[:, None] + offsets[:, 0]) * (ny + 1) + ey[:, None] + offsets[:, 1]) \
        * (nz + 1) + ez[:, None] + offsets[:, 2]
    used, conn = np.unique(grid_id, return_inverse=True)
    conn = conn.reshape(-1, 8)
    ke, me = hex8(hx, hy, hz)
    dofs = (3 * conn[:, :, None] + np.arange(3)).reshape(-1, 24)
    rows = np.repeat(dofs, 24, axis=1).ravel()
    cols = np.tile(dofs, (1, 24)).ravel()
    n = 3 * used.size
    k = sp.coo_array((np.tile(ke.ravel(), len(conn)), (rows, cols)), shape=(n, n)).tocsr()
    m = sp.coo_array((np.tile(me.ravel(), len(conn)), (rows, cols)), shape=(n, n)).tocsr()
    i, rest = np.divmod(used, (ny + 1) * (nz + 1))
    j, kk = np.divmod(rest, nz + 1)
    xyz = np.column_stack([i * hx, j * hy, kk * hz])
    return m, k, xyz, len(conn) * hx * hy * hz


def _solid(ex, ey, ez, nx, ny, nz):
    base = ez < max(1, round(0.4 * nz))
    ribs = (ex % 6 == 0) | (ey % 6 == 0) | (ex == nx - 1) | (ey == ny - 1)
    return base | ribs


def _node_count(nx, ny, nz):
    ex, ey, ez = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz),
                                                 indexing="ij"))
    keep = _solid(ex, ey, ez, nx, ny, nz)
    nodes = set()
    for di in (0, 1):
        for dj in (0, 1):
            for dk in (0, 1):
                nodes.update((((ex[keep] + di) * (ny + 1) + ey[keep] + dj) * (nz + 1)
                              + ez[keep] + dk).tolist())
    return len(nodes)


def boundary_dofs(xyz):
    nodes = [int(np.argmin(((xyz - np.array(p)) ** 2).sum(axis=1)))
             for p in [*PADS, WORK_PIECE]]
    return (3 * np.array(nodes)[:, None] + np.arange(3)).ravel()


def dense_reduction(m, k, boundary, n_modes):
    """The baseline: Craig-Bampton with dense linear algebra."""
    n = m.shape[0]
    interior = np.setdiff1d(np.arange(n), boundary)
    md, kd = m.toarray(), k.toarray()
    k_ii, m_ii = kd[np.ix_(interior, interior)], md[np.ix_(interior, interior)]
    k_ib, m_ib = kd[np.ix_(interior, boundary)], md[np.ix_(interior, boundary)]
    psi = -scipy.linalg.cho_solve(scipy.linalg.cho_factor(k_ii), k_ib)
    w2, phi = scipy.linalg.eigh(k_ii, m_ii, subset_by_index=[0, n_modes - 1])
    mbb = md[np.ix_(boundary, boundary)] + m_ib.T @ psi + psi.T @ m_ib + psi.T @ m_ii @ psi
    mbm = (m_ib.T + psi.T @ m_ii) @ phi
    mr = np.block([[mbb, mbm], [mbm.T, np.eye(n_modes)]])
    kr = scipy.linalg.block_diag(kd[np.ix_(boundary, boundary)] + k_ib.T @ psi, np.diag(w2))
    return mr, kr


def run_case(n_target: int, method: str) -> dict:
    """One reduction in this process; returns timings, memory and the reduced frequencies."""
    from servotune.structure.reduction import _pardiso_available, craig_bampton_basis

    if _pardiso_available():  # load MKL before the clock starts
        import pypardiso  # noqa: F401
    scipy.linalg.eigh(np.eye(3) * 2.0, np.eye(3), subset_by_index=[0, 1])  # load LAPACK
    t0 = time.perf_counter()
    m, k, xyz, volume = slide_model(n_target)
    t_model = time.perf_counter() - t0
    boundary = boundary_dofs(xyz)
    rss_model = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    t0 = time.perf_counter()
    if method == "dense":
        mr, kr = dense_reduction(m, k, boundary, N_MODES)
        solver = "lapack"
    else:
        solver = "superlu" if method == "superlu" else (
            "pardiso" if _pardiso_available() else "superlu")
        basis = craig_bampton_basis(m, k, boundary, n_modes=N_MODES, solver=solver)
        mr, kr = basis.mass, basis.stiffness
    t_reduce = time.perf_counter() - t0
    w2 = scipy.linalg.eigh(kr, mr, eigvals_only=True)
    free = np.sqrt(np.clip(w2, 0, None)) / (2 * math.pi)
    u = np.tile([1.0, 0.0, 0.0], m.shape[0] // 3)  # rigid translation in X: u^T M u = rho V
    mass_check = float(u @ (m @ u))
    return {"n_dof": int(m.shape[0]), "nnz": int(k.nnz), "method": method, "solver": solver,
            "load_average_1min": os.getloadavg()[0],
            "n_reduced": int(mr.shape[0]), "time_model_s": t_model, "time_reduce_s": t_reduce,
            "peak_rss_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6,
            "rss_after_model_gb": rss_model,
            "mass_error": abs(mass_check - RHO * volume) / (RHO * volume),
            "free_free_hz": free[6:12].tolist()}


def _in_subprocess(n_target: int, method: str, timeout: float) -> dict:
    cmd = [sys.executable, __file__, "--case", str(n_target), method]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=True)
    except subprocess.TimeoutExpired:
        return {"n_target": n_target, "method": method, "error": f"timeout after {timeout} s"}
    except subprocess.CalledProcessError as exc:
        return {"n_target": n_target, "method": method, "error": exc.stderr.strip()[-300:]}
    return json.loads(out.stdout)


def _power_law(rows):
    """Exponent p and prefactor of time = c n^p fitted to (n, time) in log-log."""
    n = np.log([r["n_dof"] for r in rows])
    t = np.log([r["time_reduce_s"] for r in rows])
    p, c = np.polyfit(n, t, 1)
    return float(p), float(math.exp(c))


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--sizes", type=int, nargs="+",
                        default=[2000, 4000, 8000, 25000, 50000, 100000, 200000])
    parser.add_argument("--dense-max", type=int, default=8000,
                        help="largest size for the dense baseline (default 8000)")
    parser.add_argument("--superlu-max", type=int, default=50000,
                        help="largest size for the forced-SuperLU run (default 50000)")
    parser.add_argument("--timeout", type=float, default=600.0, help="per case [s]")
    parser.add_argument("--case", nargs=2, metavar=("N", "METHOD"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.case:
        print(json.dumps(run_case(int(args.case[0]), args.case[1])))
        return {}
    rows = []
    for n in args.sizes:
        methods = ["sparse"] + (["superlu"] if n <= args.superlu_max else []) \
            + (["dense"] if n <= args.dense_max else [])
        for method in methods:
            row = _in_subprocess(n, method, args.timeout)
            rows.append(row)
            if not args.json:
                if "error" in row:
                    print(f"{n:>8d} {method:8s} {row['error']}", flush=True)
                else:
                    print(f"{row['n_dof']:>8d} {method:8s} ({row['solver']:8s}) reduce "
                          f"{row['time_reduce_s']:8.2f} s  peak RSS {row['peak_rss_gb']:5.2f} GB"
                          f"  (model {row['time_model_s']:.1f} s)", flush=True)
    ok = [r for r in rows if "error" not in r]
    result = {"n_modes": N_MODES, "n_boundary": 15, "cores": os.cpu_count(),
              "load_average_1min_at_end": os.getloadavg()[0], "cases": rows}
    speedups = []
    for r in ok:
        if r["method"] != "dense":
            continue
        s = next((x for x in ok if x["method"] == "sparse" and x["n_dof"] == r["n_dof"]), None)
        if s:
            speedups.append({"n_dof": r["n_dof"],
                             "speedup": r["time_reduce_s"] / s["time_reduce_s"],
                             "max_rel_diff_free_free_hz": float(np.max(
                                 np.abs(np.array(s["free_free_hz"]) - r["free_free_hz"])
                                 / np.array(r["free_free_hz"])))})
    result["speedup_by_size"] = speedups
    result["speedup"] = speedups[-1]["speedup"] if speedups else None
    fits = {}
    for method in ("sparse", "superlu", "dense"):
        sub = [r for r in ok if r["method"] == method]
        if len(sub) >= 2:
            fits[method] = dict(zip(("exponent", "prefactor"), _power_law(sub), strict=True))
    result["scaling"] = fits
    largest = max((r for r in ok if r["method"] == "sparse"), key=lambda r: r["n_dof"],
                  default=None)
    if largest and "dense" in fits:
        f = fits["dense"]
        dense_est = f["prefactor"] * largest["n_dof"] ** f["exponent"]
        result["largest"] = {"n_dof": largest["n_dof"], "time_reduce_s": largest["time_reduce_s"],
                             "peak_rss_gb": largest["peak_rss_gb"],
                             "dense_time_extrapolated_s": dense_est,
                             "dense_memory_gb_estimate": 2 * 8 * largest["n_dof"] ** 2 / 1e9,
                             "speedup_extrapolated": dense_est / largest["time_reduce_s"]}
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for s in speedups:
            print(f"speedup sparse vs dense at {s['n_dof']} DOF: {s['speedup']:.1f}x "
                  f"(free-free frequencies agree to {s['max_rel_diff_free_free_hz']:.1e})")
        for method, f in fits.items():
            print(f"scaling {method:8s}: time ~ n^{f['exponent']:.2f}")
        if "largest" in result:
            g = result["largest"]
            print(f"largest: {g['n_dof']} DOF in {g['time_reduce_s']:.1f} s, peak RSS "
                  f"{g['peak_rss_gb']:.2f} GB; dense would need "
                  f"~{g['dense_memory_gb_estimate']:.0f}"
                  f" GB and ~{g['dense_time_extrapolated_s']:.0f} s (extrapolated): "
                  f"{g['speedup_extrapolated']:.0f}x")
    return result


if __name__ == "__main__":
    main()
