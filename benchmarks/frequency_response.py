"""Frequency responses of the bundled axis: servotune against python-control's frequency_response.

1. Closed-loop work-piece compliance f_wp_x -> wp_x at 2,000 frequencies (1 Hz - 1 kHz) of the
   interconnected plant (``build_plant`` with the axis' viscous-only pads and its drive):

   * ``port_compliance`` (the ``speedup``): the structure's receptance at its ports from the
     modal sum, closed with the contacts and the cascade by one small batched solve per
     frequency (never forms the closed loop);
   * ``fast_frequency_response``: the closed-loop state space in (block) modal form, checked a
     posteriori against direct solves (Hessenberg form) at a few dozen frequencies;
   * baseline: ``control.frequency_response`` on the same SISO system (SLICOT TB05AD through
     slycot: a Hessenberg form, then O(n^2) per frequency).

2. The loop transfer functions of ``loop_report`` (velocity and position loop, 8,001
   frequencies, 0.1 Hz - 3 kHz) by ``fast_frequency_response`` at the default rtol (1e-10) and
   at the 1e-7 of ``analyse_loop``, against ``control.frequency_response``. The open velocity
   loop has an integrator and the free axis' rigid body at s = 0, which defeats the plain
   modal form.

Accuracy: the compliance against a balanced direct solve at every frequency, the loops
against LU solves refined with a residual in extended precision (numpy's long double) at 41
frequencies. Times are the best of ``--repeat`` calls; the first call in this process (which
also loads the compiled kernels from numba's cache) is given beside them. BLAS and OpenMP are
held to one thread for every method (before numpy is imported): the matrices are small, and
on a shared machine threaded BLAS mostly waits for its threads.

Usage: ``python benchmarks/frequency_response.py [--json] [--repeat N] [--axis PATH]``
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import control  # noqa: E402
import numpy as np  # noqa: E402
import scipy.linalg  # noqa: E402
from _timing import best_time  # noqa: E402

from servotune import analysis  # noqa: E402
from servotune.axis import load_axis  # noqa: E402
from servotune.frequency import fast_frequency_response, port_compliance  # noqa: E402
from servotune.plant import loop_transfer  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def reference(sys, omega):
    """Balanced direct solve, one frequency at a time (the accuracy reference)."""
    a, t = scipy.linalg.matrix_balance(sys.A, permute=False, separate=True)
    b, c = sys.B / t[0][:, None], sys.C * t[0][None, :]
    eye = np.eye(a.shape[0])
    return np.array([(c @ np.linalg.solve(1j * w * eye - a, b))[0, 0] + sys.D[0, 0]
                     for w in omega])


def refined_reference(sys, omega):
    """LU solves with two steps of iterative refinement, the residual in long double."""
    a, t = scipy.linalg.matrix_balance(sys.A, permute=False, separate=True)
    b, c = sys.B[:, 0] / t[0], sys.C[0] * t[0]
    out = []
    for w in omega:
        m = 1j * w * np.eye(a.shape[0]) - a
        x = np.linalg.solve(m, b)
        ml = m.astype(np.clongdouble)
        for _ in range(2):
            r = b.astype(np.clongdouble) - ml @ x.astype(np.clongdouble)
            x = x + np.linalg.solve(m, r.astype(complex))
        out.append(complex(c.astype(np.clongdouble) @ x.astype(np.clongdouble)) + sys.D[0, 0])
    return np.array(out)


def first_and_best(fn, repeat):
    t0 = time.perf_counter()
    fn()
    first = time.perf_counter() - t0
    best, out = best_time(fn, repeat)
    return first, best, out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--repeat", type=int, default=20)
    parser.add_argument("--axis", default=str(ROOT / "models" / "paper_x_axis"))
    args = parser.parse_args(argv)

    axis = load_axis(args.axis)
    contact = analysis.axis_contact(axis, "viscous")
    plant = analysis.axis_plant(axis, contact)
    sub = plant[plant.output_labels.index("wp_x"), plant.input_labels.index("f_wp_x")]
    omega = 2 * math.pi * np.geomspace(1.0, 1000.0, 2000)

    first_ports, t_ports, ports = first_and_best(
        lambda: port_compliance(axis.structure, omega, axis.drive, contact, axis.pads)[0],
        args.repeat)
    first_fast, t_fast, fast = first_and_best(
        lambda: fast_frequency_response(sub, omega).complex.reshape(-1), args.repeat)
    t_pc, pc = best_time(
        lambda: control.frequency_response(sub, omega).complex.reshape(-1), args.repeat)
    ref = reference(sub, omega)
    result = {
        "case": f"{axis.name}: closed-loop f_wp_x -> wp_x, {sub.nstates} states, "
                f"{omega.size} frequencies",
        "baseline": f"control.frequency_response (python-control {control.__version__})",
        "time_servotune_ports_s": t_ports,
        "time_servotune_ports_first_call_s": first_ports,
        "time_servotune_modal_state_space_s": t_fast,
        "time_servotune_modal_state_space_first_call_s": first_fast,
        "time_python_control_s": t_pc,
        "speedup": t_pc / t_ports,
        "speedup_modal_state_space": t_pc / t_fast,
        "max_rel_err_servotune_ports_vs_reference": float(np.abs(ports / ref - 1).max()),
        "max_rel_err_servotune_modal_vs_reference": float(np.abs(fast / ref - 1).max()),
        "max_rel_err_python_control_vs_reference": float(np.abs(pc / ref - 1).max()),
        "loops": {},
    }
    w_loop = analysis.default_omega(0.1, 3000.0, 8001)
    idx = np.linspace(0, w_loop.size - 1, 41).astype(int)
    for loop in ("velocity", "position"):
        lt = loop_transfer(axis.structure, axis.drive, contact, axis.pads, loop)
        ref_l = refined_reference(lt, w_loop[idx])
        row = {"states": lt.nstates, "frequencies": int(w_loop.size)}
        t_pc_l, pc_l = best_time(
            lambda lt=lt: control.frequency_response(lt, w_loop).complex.reshape(-1),
            max(2, args.repeat // 4))
        row["time_python_control_s"] = t_pc_l
        row["max_rel_err_python_control"] = float(np.abs(pc_l[idx] / ref_l - 1).max())
        for rtol in (1e-7, 1e-10):
            t_l, got = best_time(
                lambda lt=lt, rtol=rtol: fast_frequency_response(
                    lt, w_loop, rtol=rtol).complex.reshape(-1), args.repeat)
            key = f"rtol_{rtol:g}"
            row[f"time_servotune_{key}_s"] = t_l
            row[f"speedup_{key}"] = t_pc_l / t_l
            row[f"max_rel_err_servotune_{key}"] = float(np.abs(got[idx] / ref_l - 1).max())
        result["loops"][loop] = row
        result[f"speedup_{loop}_loop_default_rtol"] = row["speedup_rtol_1e-10"]
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(result["case"])
        print(f"  servotune port_compliance         : {t_ports * 1e3:8.2f} ms "
              f"(speedup {result['speedup']:.1f} x)")
        print(f"  servotune fast_frequency_response : {t_fast * 1e3:8.2f} ms "
              f"(speedup {result['speedup_modal_state_space']:.1f} x)")
        print(f"  python-control frequency_response : {t_pc * 1e3:8.2f} ms")
        print(f"  relative errors against a balanced direct solve: ports "
              f"{result['max_rel_err_servotune_ports_vs_reference']:.1e}, modal "
              f"{result['max_rel_err_servotune_modal_vs_reference']:.1e}, python-control "
              f"{result['max_rel_err_python_control_vs_reference']:.1e}")
        for loop, row in result["loops"].items():
            print(f"  {loop} loop, {row['frequencies']} frequencies: python-control "
                  f"{row['time_python_control_s'] * 1e3:.1f} ms (error "
                  f"{row['max_rel_err_python_control']:.1e}); servotune rtol 1e-7 "
                  f"{row['time_servotune_rtol_1e-07_s'] * 1e3:.1f} ms (error "
                  f"{row['max_rel_err_servotune_rtol_1e-07']:.1e}), default rtol "
                  f"{row['time_servotune_rtol_1e-10_s'] * 1e3:.1f} ms (error "
                  f"{row['max_rel_err_servotune_rtol_1e-10']:.1e})")
    return result


if __name__ == "__main__":
    main()
