"""Craig-Bampton reduction of a 3D solid model of a slide: servotune against plain scipy.

The model is a ribbed cast-iron slide, 1.6 m x 1.0 m x 0.25 m: a base plate (the lower 40 % of
the height) with longitudinal and transverse ribs every sixth element, meshed with 8-node
hexahedra (trilinear, 2x2x2 Gauss; element matrices derived and assembled here with numpy, all
elements being the same brick). The boundary is the translation of the four pad points under
the corners and of the work-piece point on top (15 DOFs); 25 fixed-interface modes are kept, so
the reduced model has 40 DOFs.

Methods, each timed in a fresh process (peak resident memory from ``getrusage``):

* ``servotune``: :func:`servotune.structure.craig_bampton_basis` as shipped (one sparse
  factorisation of K_ii for the constraint modes and the shift-invert Lanczos of ``eigsh``
  from a random start for 26 modes, then a Sturm count at the middle of the gap between the
  25th and the 26th that checks no mode was missed: a factorisation of K_ii - s M_ii after
  the factors of K_ii are freed; SuperLU unless ``pypardiso`` is installed);
* ``scipy`` (the baseline): the same work written plainly with scipy, as a careful user
  writes it: ``splu(K_ii)`` with the column ordering and pivoting servotune's own
  factorisation uses (``permc_spec="MMD_AT_PLUS_A"``, ``diag_pivot_thresh=0``, symmetric
  mode: the right choice for a symmetric positive-definite K_ii), the constraint modes from it
  and ``eigsh(K_ii, 26, M_ii, sigma=0, OPinv=..., tol=1e-8)`` (the accuracy servotune asks of
  ARPACK; its eigenvalues are Ritz values, accurate far beyond the eigenvectors' 1e-8, and the
  free-free frequencies of the two reduced models are compared below); then the same Sturm
  count as servotune's: ``del`` of the first factors, K_ii - s M_ii put in the first
  factorisation's column order (``q = argsort(perm_c)``, ``A[q][:, q]``: the order SuperLU
  factorised K_ii in) and ``splu`` of it with ``permc_spec="NATURAL"`` and the same pivoting
  options, so no second ordering is computed; the negative entries of ``U.diagonal()``, the
  permutations checked equal. servotune reads diag(U) from SuperLU's storage in place rather
  than through scipy's ``U`` (a copy of the factors), and retries the count at a nearby shift
  when SuperLU pivots off the diagonal: the baseline stops with an error there instead;
* ``scipy_nocheck``: the baseline without the Sturm count (25 modes, no check that none was
  missed; the same ``tol``), for reference: servotune does more work than it;
* ``scipy_defaults``: ``scipy_nocheck`` with ``splu``'s default ordering (COLAMD), for
  reference only (not a fair baseline: it fills in far more);
* ``dense`` (a second baseline, where it fits): dense Cholesky for the constraint modes and
  ``scipy.linalg.eigh(K_ii, M_ii, subset_by_index=...)``;
* ``check``: :func:`servotune.structure.reduction_check` of the servotune model against the
  full model over 5-300 Hz (reported apart: it is a second job, not part of the reduction).

Usage: ``python benchmarks/craig_bampton.py [--json] [--sizes N ...] [--dense-max N]
[--methods M ...] [--repeat N]``; the top-level ``speedup`` is scipy's time over servotune's at
the largest size (``speedup_no_check``: the same against ``scipy_nocheck``); with ``--repeat``
the methods take turns N times and each one's fastest run counts (all times are listed).
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


def scipy_reduction(m, k, boundary, n_modes, ordering: bool = True, check: bool = True,
                    tol: float = 1e-8):
    """The plain scipy baseline: splu (with servotune's ordering and pivoting unless
    ``ordering`` is False) and eigsh at servotune's tolerance (``tol``); with ``check`` one mode
    more and a Sturm count in the gap above the last kept mode (the check servotune makes), its
    factorisation in the first one's column order."""
    import scipy.sparse.linalg as sla

    n = m.shape[0]
    interior = np.setdiff1d(np.arange(n), boundary)
    m, k = m.tocsr(), k.tocsr()
    k_ii = k[interior][:, interior].tocsc()
    m_ii = m[interior][:, interior].tocsc()
    k_ib = k[interior][:, boundary].toarray()
    m_ib = m[interior][:, boundary].toarray()
    options = {"permc_spec": "MMD_AT_PLUS_A", "diag_pivot_thresh": 0.0,
               "options": {"SymmetricMode": True}}
    lu = sla.splu(k_ii, **options) if ordering else sla.splu(k_ii)
    psi = -lu.solve(k_ib)
    op = sla.LinearOperator(k_ii.shape, matvec=lu.solve, dtype=float)
    w2, phi = sla.eigsh(k_ii, k=n_modes + (1 if check else 0), M=m_ii, sigma=0.0, OPinv=op,
                        tol=tol)
    order = np.argsort(w2)
    w2, phi = w2[order], phi[:, order]
    if check:
        # Sturm count: the negative pivots of K_ii - s M_ii = L D L^T (Sylvester) are the
        # modes below s, s between the last kept mode and the next
        # in the order K_ii was factorised in: SuperLU factorised K_ii[q][:, q], no new ordering
        q = np.argsort(lu.perm_c)
        del lu, op
        s = 0.5 * (w2[n_modes - 1] + w2[n_modes])
        a = (k_ii - s * m_ii).tocsc()
        a = a[q][:, q].tocsc()
        lu = sla.splu(a, **{**options, "permc_spec": "NATURAL"})
        del a
        if not np.array_equal(lu.perm_r, lu.perm_c):
            raise RuntimeError("SuperLU pivoted off the diagonal: no Sturm count")
        below = int(np.sum(lu.U.diagonal() < 0))
        del lu
        if below != n_modes:
            raise RuntimeError(f"{below} fixed-interface modes below {s:.6g}, "
                               f"{n_modes} found")
        w2, phi = w2[:n_modes], phi[:, :n_modes]
    mbb = m[boundary][:, boundary].toarray() + m_ib.T @ psi + psi.T @ m_ib + psi.T @ (m_ii @ psi)
    mbm = (m_ib.T + (m_ii @ psi).T) @ phi
    mr = np.block([[mbb, mbm], [mbm.T, np.eye(n_modes)]])
    kr = scipy.linalg.block_diag(k[boundary][:, boundary].toarray() + k_ib.T @ psi,
                                 np.diag(w2))
    return mr, kr


def run_case(n_target: int, method: str) -> dict:
    """One reduction in this process; returns timings, memory and the reduced frequencies."""
    from servotune.structure import ModalModel, reduction_check
    from servotune.structure.reduction import craig_bampton_basis
    from servotune.structure.solvers import pardiso_available

    if pardiso_available():  # load MKL before the clock starts
        import pypardiso  # noqa: F401
    scipy.linalg.eigh(np.eye(3) * 2.0, np.eye(3), subset_by_index=[0, 1])  # load LAPACK
    t0 = time.perf_counter()
    m, k, xyz, volume = slide_model(n_target)
    t_model = time.perf_counter() - t0
    boundary = boundary_dofs(xyz)
    rss_model = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    extra = {}
    cpu0 = resource.getrusage(resource.RUSAGE_SELF)
    t0 = time.perf_counter()
    if method == "dense":
        mr, kr = dense_reduction(m, k, boundary, N_MODES)
        solver = "lapack"
    elif method == "scipy":
        mr, kr = scipy_reduction(m, k, boundary, N_MODES)
        solver = ("superlu (MMD_AT_PLUS_A, diag_pivot_thresh 0, symmetric mode), eigsh tol 1e-8, "
                  "Sturm count in the same order")
    elif method == "scipy_nocheck":
        mr, kr = scipy_reduction(m, k, boundary, N_MODES, check=False)
        solver = ("superlu (MMD_AT_PLUS_A, diag_pivot_thresh 0, symmetric mode), eigsh tol 1e-8, "
                  "no check")
    elif method == "scipy_defaults":
        mr, kr = scipy_reduction(m, k, boundary, N_MODES, ordering=False, check=False)
        solver = "superlu (scipy defaults), no check"
    else:
        solver = "pardiso" if pardiso_available() else "superlu"
        basis = craig_bampton_basis(m, k, boundary, n_modes=N_MODES)
        mr, kr = basis.mass, basis.stiffness
        extra = {"fixed_interface_method": basis.method, "restarts": basis.restarts}
    t_reduce = time.perf_counter() - t0
    cpu1 = resource.getrusage(resource.RUSAGE_SELF)
    cpu_reduce = cpu1.ru_utime + cpu1.ru_stime - cpu0.ru_utime - cpu0.ru_stime
    rss_reduce = cpu1.ru_maxrss / 1e6
    if method == "check":
        names = [f"{i // 3}.{'xyz'[i % 3]}" for i in boundary]
        model = ModalModel(mr, kr, names + [f"mode.{j + 1}" for j in range(N_MODES)],
                           reduction=basis.info)
        coords = {str(i // 3): xyz[i // 3] for i in boundary}
        t0 = time.perf_counter()
        check = reduction_check(m, k, boundary, model, (2 * math.pi * 5, 2 * math.pi * 300),
                                coordinates=coords)
        extra.update({"time_check_s": time.perf_counter() - t0,
                      "check_reference_modes": check.reference_modes,
                      "check_max_frequency_error": check.max_frequency_error,
                      "check_max_compliance_error": check.max_compliance_error,
                      "check_failures": list(check.failures)})
    w2 = scipy.linalg.eigh(kr, mr, eigvals_only=True)
    free = np.sqrt(np.clip(w2, 0, None)) / (2 * math.pi)
    u = np.tile([1.0, 0.0, 0.0], m.shape[0] // 3)  # rigid translation in X: u^T M u = rho V
    mass_check = float(u @ (m @ u))
    return {"n_dof": int(m.shape[0]), "nnz": int(k.nnz), "method": method, "solver": solver,
            "load_average_1min": os.getloadavg()[0],
            "n_reduced": int(mr.shape[0]), "time_model_s": t_model, "time_reduce_s": t_reduce,
            "cpu_reduce_s": cpu_reduce,
            "peak_rss_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6,
            "peak_rss_reduce_gb": rss_reduce,
            "rss_after_model_gb": rss_model,
            "mass_error": abs(mass_check - RHO * volume) / (RHO * volume),
            "free_free_hz": free[6:12].tolist(), **extra}


def _in_subprocess(n_target: int, method: str, timeout: float) -> dict:
    cmd = [sys.executable, __file__, "--case", str(n_target), method]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=True)
    except subprocess.TimeoutExpired:
        return {"n_target": n_target, "method": method, "error": f"timeout after {timeout} s"}
    except subprocess.CalledProcessError as exc:
        return {"n_target": n_target, "method": method, "error": exc.stderr.strip()[-300:]}
    return json.loads(out.stdout)


def _compare(rows, base, ours="servotune"):
    out = []
    for r in rows:
        if r["method"] != base:
            continue
        s = next((x for x in rows if x["method"] == ours and x["n_dof"] == r["n_dof"]), None)
        if s:
            out.append({"n_dof": r["n_dof"], "baseline": base,
                        "speedup": r["time_reduce_s"] / s["time_reduce_s"],
                        "memory_ratio": s["peak_rss_reduce_gb"] / r["peak_rss_reduce_gb"],
                        "max_rel_diff_free_free_hz": float(np.max(
                            np.abs(np.array(s["free_free_hz"]) - r["free_free_hz"])
                            / np.array(r["free_free_hz"])))})
    return out


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--sizes", type=int, nargs="+", default=[4000, 50000])
    parser.add_argument("--dense-max", type=int, default=8000,
                        help="largest size for the dense baseline (default 8000)")
    parser.add_argument("--no-check", action="store_true",
                        help="skip the run with the reduction check")
    parser.add_argument("--timeout", type=float, default=900.0, help="per case [s]")
    parser.add_argument("--methods", nargs="+", default=None,
                        help="the methods to run (default: all that fit)")
    parser.add_argument("--repeat", type=int, default=1,
                        help="runs of each case, the methods taking turns; the fastest counts "
                             "(default 1: on a shared machine use 3 or more)")
    parser.add_argument("--case", nargs=2, metavar=("N", "METHOD"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.case:
        print(json.dumps(run_case(int(args.case[0]), args.case[1])))
        return {}
    rows = []
    for n in args.sizes:
        methods = (["servotune", "scipy", "scipy_nocheck", "scipy_defaults"]
                   + (["dense"] if n <= args.dense_max else [])
                   + ([] if args.no_check else ["check"]))
        if args.methods:
            methods = [x for x in methods if x in args.methods]
        runs = {method: [] for method in methods}
        for _ in range(max(1, args.repeat)):
            for method in methods:
                runs[method].append(_in_subprocess(n, method, args.timeout))
        for method in methods:
            done = [r for r in runs[method] if "error" not in r]
            row = min(done, key=lambda r: r["time_reduce_s"]) if done else runs[method][0]
            if len(done) > 1:
                row = {**row, "times_reduce_s": [r["time_reduce_s"] for r in done],
                       "peak_rss_reduce_gb_runs": [r["peak_rss_reduce_gb"] for r in done]}
            rows.append(row)
            if not args.json:
                if "error" in row:
                    print(f"{n:>8d} {method:9s} {row['error']}", flush=True)
                else:
                    more = f"  check {row['time_check_s']:.1f} s" if "time_check_s" in row \
                        else ""
                    print(f"{row['n_dof']:>8d} {method:9s} reduce {row['time_reduce_s']:8.2f} s"
                          f" (CPU {row['cpu_reduce_s']:.1f} s)"
                          f"  peak RSS {row['peak_rss_reduce_gb']:5.2f} GB"
                          f"  (model {row['time_model_s']:.1f} s){more}", flush=True)
    ok = [r for r in rows if "error" not in r]
    result = {"n_modes": N_MODES, "n_boundary": 15, "cores": os.cpu_count(),
              "load_average_1min_at_end": os.getloadavg()[0], "cases": rows,
              "baseline": "scipy (splu with servotune's ordering and pivoting + eigsh at "
                          "servotune's tol 1e-8, same modes, the same Sturm count as "
                          "servotune's check in the first factorisation's order)"}
    result["against_scipy"] = _compare(ok, "scipy")
    result["against_scipy_nocheck"] = _compare(ok, "scipy_nocheck")
    result["against_scipy_defaults"] = _compare(ok, "scipy_defaults")
    result["against_dense"] = _compare(ok, "dense")
    largest = result["against_scipy"][-1] if result["against_scipy"] else None
    result["speedup"] = None if largest is None else largest["speedup"]
    result["memory_ratio"] = None if largest is None else largest["memory_ratio"]
    result["speedup_n_dof"] = None if largest is None else largest["n_dof"]
    plain = result["against_scipy_nocheck"][-1] if result["against_scipy_nocheck"] else None
    result["speedup_no_check"] = None if plain is None else plain["speedup"]
    result["memory_ratio_no_check"] = None if plain is None else plain["memory_ratio"]
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for key in ("against_scipy", "against_scipy_nocheck", "against_scipy_defaults",
                    "against_dense"):
            for s in result[key]:
                print(f"{s['n_dof']} DOF, servotune vs {s['baseline']}: speedup "
                      f"{s['speedup']:.2f}x, memory {s['memory_ratio']:.2f} of the baseline "
                      f"(free-free frequencies agree to {s['max_rel_diff_free_free_hz']:.1e})")
    return result


if __name__ == "__main__":
    main()
