"""Frequency responses of the bundled axis: servotune against python-control's frequency_response.

Sections 1 and 2 use the bundled axis with its drive in continuous time
(``Axis.with_continuous_drive()``: the paper's continuous cascade, no sampling). They measure
the continuous machinery (the port coupling of ``port_compliance``, ``build_plant`` and
``loop_transfer``, ``fast_frequency_response``), which takes continuous drives only; the axis'
own digital drive is the sampled-data system of section 3.

1. Closed-loop work-piece compliance f_wp_x -> wp_x at 2,000 frequencies (1 Hz - 1 kHz) of the
   interconnected plant (``build_plant`` with the axis' viscous-only pads and the continuous
   drive):

   * ``port_compliance`` (the ``speedup``): the structure's receptance at its ports from the
     modal sum, closed with the contacts and the cascade by one small batched solve per
     frequency (never forms the closed loop);
   * ``fast_frequency_response``: the closed-loop state space in (block) modal form, checked a
     posteriori against direct solves (Hessenberg form) at a few dozen frequencies;
   * baseline: ``control.frequency_response`` on the same SISO system (SLICOT TB05AD through
     slycot: a Hessenberg form, then O(n^2) per frequency).

2. The loop transfer functions of the continuous drive (``loop_transfer``: velocity and
   position loop, 8,001 frequencies, 0.1 Hz - 3 kHz) by ``fast_frequency_response`` at the
   default rtol (1e-10) and at the 1e-7 of ``analyse_loop``, against
   ``control.frequency_response``. The open velocity loop has an integrator and the free axis'
   rigid body at s = 0, which defeats the plain modal form.

3. The loops of the axis' own digital drive (``[drive.sampling]``), as ``loop_report`` takes
   them: :meth:`servotune.digital.SampledAxis.loop_response` (the velocity loop at the velocity
   controller's rate with the position loop open, the position loop at the position
   controller's rate with the velocity loop closed; 8,001 frequencies from 0.1 Hz up to 3 kHz
   or the loop's Nyquist frequency), against the same sampled-data loops written plainly with
   python-control: the open plant (voltage to the sampled current, motor angle and position;
   ``build_open_plant``) discretised by ``control.c2d(..., "zoh")``, the controllers'
   difference equations (the state spaces of ``digital_controller``) joined to it by
   ``control.interconnect``, the loop broken at the velocity controller's output, or at the
   position controller's with the inner loops lifted over the position period (A^N and
   sum A^j B: python-control has no lifting), then ``control.frequency_response``. Both are
   timed from the same inputs (structure, drive, contact, pads): building included. The drive's
   gains are those of the axis with the velocity-loop Kp softened by the tuner's factors
   (``servotune.tuning.solve.SOFTENING``) until the sampled-data loop is stable (the axis' own
   Kp is not, with the digital drive). Needs a velocity controller at the current controller's
   rate (as the bundled axis has); skipped otherwise. Reported apart, not in ``speedup``.

   The sampled-data compliance (:meth:`servotune.digital.SampledAxis.compliance`) is not
   compared: python-control evaluates continuous or discrete LTI systems, and the fundamental of
   a continuous output under held, multi-rate control (the hold's aliases through the plant,
   the lifted position loop) is not one; written with python-control it would be the algebra
   of :mod:`servotune.digital.cascade` itself, not a plain use of the library. The plain way to
   that curve is a stepped sine in the time domain (the kind of baseline of
   ``harmonic_balance.py``).

Accuracy: the compliance against a balanced direct solve at every frequency, the continuous
loops against LU solves refined with a residual in extended precision (numpy's long double) at
41 frequencies, the digital loops of the two methods against each other. Times are the best of
``--repeat`` calls; the first call in this process (which also loads the compiled kernels from
numba's cache) is given beside them. BLAS and OpenMP are held to one thread for every method
(before numpy is imported): the matrices are small, and on a shared machine threaded BLAS
mostly waits for its threads.

Usage: ``python benchmarks/frequency_response.py [--json] [--repeat N] [--axis PATH]``
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
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
from servotune.digital import MEASURED, SampledAxis, digital_controller  # noqa: E402
from servotune.frequency import fast_frequency_response, port_compliance  # noqa: E402
from servotune.plant import build_open_plant, loop_transfer  # noqa: E402
from servotune.tuning.solve import SOFTENING  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def reference(sys, omega):
    """Balanced direct solve, one frequency at a time (the accuracy reference)."""
    a, t = scipy.linalg.matrix_balance(sys.A, permute=False, separate=True)
    b, c = sys.B / t[0][:, None], sys.C * t[0][None, :]
    eye = np.eye(a.shape[0])
    return np.array([(c @ np.linalg.solve(1j * w * eye - a, b))[0, 0] + sys.D[0, 0]
                     for w in omega])


def refined_reference(sys, omega, z=None):
    """LU solves with two steps of iterative refinement, the residual in long double (at the
    points ``z`` instead of ``j omega`` for a discrete system)."""
    a, t = scipy.linalg.matrix_balance(sys.A, permute=False, separate=True)
    b, c = sys.B[:, 0] / t[0], sys.C[0] * t[0]
    out = []
    for s in (1j * np.asarray(omega) if z is None else z):
        m = s * np.eye(a.shape[0]) - a
        x = np.linalg.solve(m, b)
        ml = m.astype(np.clongdouble)
        for _ in range(2):
            r = b.astype(np.clongdouble) - ml @ x.astype(np.clongdouble)
            x = x + np.linalg.solve(m, r.astype(complex))
        out.append(complex(c.astype(np.clongdouble) @ x.astype(np.clongdouble)) + sys.D[0, 0])
    return np.array(out)


def python_control_digital_loop(structure, drive, contact, pads, loop):
    """A loop of the sampled-data axis written plainly with python-control (section 3): the
    open plant discretised under the zero-order hold, the controllers' state spaces joined by
    ``interconnect``, the position loop lifted over its period; the discrete L (its sample
    time the loop's period)."""
    ctl = digital_controller(drive)
    t = ctl.period
    full = build_open_plant(structure, drive, contact, pads)
    rows = [list(full.output_labels).index(m) for m in MEASURED]
    col = list(full.input_labels).index("voltage")
    plant = control.c2d(control.ss(full.A, full.B[:, [col]], full.C[rows], np.zeros((3, 1))),
                        t, method="zoh")
    plant = control.ss(plant.A, plant.B, plant.C, plant.D, t, inputs=["voltage"],
                       outputs=list(MEASURED))
    cur = ctl.level("current").system
    current = control.ss(cur.A, cur.B, cur.C, cur.D, t, inputs=list(cur.input_labels),
                         outputs=["voltage"])
    inner = control.interconnect([plant, current], inplist=["torque_set"],
                                 outlist=["motor_angle", "x_fb"], inputs=["torque_set"],
                                 outputs=["motor_angle", "x_fb"], dt=t, check_unused=False)
    vel = ctl.level("velocity").system
    velocity = control.ss(vel.A, vel.B, vel.C, vel.D, t, inputs=list(vel.input_labels),
                          outputs=["torque_cmd"])
    if loop == "velocity":
        # broken at the velocity controller's output: L = -(torque back per torque injected)
        opened = control.interconnect([inner, velocity], inplist=["torque_set"],
                                      outlist=["torque_cmd"], inputs=["torque_set"],
                                      outputs=["torque_cmd"], dt=t, check_unused=False)
        return -opened
    closed = control.interconnect(
        [inner, control.ss([], [], [], [[1.0]], t, inputs="torque_cmd", outputs="torque_set"),
         velocity], inplist=["omega_cmd"], outlist=["x_fb"], inputs=["omega_cmd"],
        outputs=["x_fb"], dt=t, check_unused=False)
    # lifted over the position period: the speed command held, the position sampled
    m = ctl.level("position").every
    a, b = np.asarray(closed.A), np.asarray(closed.B)
    powers = [np.eye(a.shape[0])]
    for _ in range(m - 1):
        powers.append(a @ powers[-1])
    lifted = control.ss(powers[-1] @ a, sum(pw @ b for pw in powers), closed.C, closed.D, t * m)
    pos = ctl.level("position").system
    i_fb = list(pos.input_labels).index("x_fb")
    k = control.ss(pos.A, pos.B[:, [i_fb]], pos.C, pos.D[:, [i_fb]], t * m)   # per x_fb
    return -(k * lifted)


def stable_digital_drive(axis, contact):
    """The axis' digital drive with its velocity-loop Kp softened, as the tuner softens it
    (``SOFTENING``), until the sampled-data loop is stable; (drive, factor)."""
    drive = axis.drive
    for factor in (1.0, *SOFTENING):
        d = dataclasses.replace(drive, velocity_loop=dataclasses.replace(
            drive.velocity_loop, kp=drive.velocity_loop.kp * factor))
        if SampledAxis(axis.structure, d, contact, axis.pads).is_stable():
            return d, factor
    raise RuntimeError("no softened velocity loop is stable with the digital drive")


def digital_loops(axis, contact, repeat):
    """Section 3: the digital drive's loops, SampledAxis against plain python-control."""
    drive, factor = stable_digital_drive(axis, contact)
    sa = SampledAxis(axis.structure, drive, contact, axis.pads)
    out = {"velocity_kp_factor": factor, "velocity_kp": drive.velocity_loop.kp,
           "periods_s": {"current": drive.sampling.current_period,
                         "velocity": drive.sampling.velocity_period,
                         "position": drive.sampling.position_period}}
    for loop in ("velocity", "position"):
        top = min(2 * math.pi * 3000.0, sa.nyquist(loop) * (1.0 - 1e-6))
        w = np.geomspace(2 * math.pi * 0.1, top, 8001)
        first, t_st, ours = first_and_best(
            lambda w=w, loop=loop: SampledAxis(
                axis.structure, drive, contact, axis.pads).loop_response(loop, w), repeat)
        t_pc, pc = best_time(lambda w=w, loop=loop: control.frequency_response(
            python_control_digital_loop(axis.structure, drive, contact, axis.pads, loop),
            w).complex.reshape(-1), max(2, repeat // 4))
        sys = python_control_digital_loop(axis.structure, drive, contact, axis.pads, loop)
        idx = np.linspace(0, w.size - 1, 41).astype(int)
        ref = refined_reference(sys, w[idx], z=np.exp(1j * w[idx] * sys.dt))
        out[loop] = {"frequencies": int(w.size), "top_hz": top / (2 * math.pi),
                     "states_python_control": sys.nstates,
                     "time_servotune_s": t_st, "time_servotune_first_call_s": first,
                     "time_python_control_s": t_pc, "speedup": t_pc / t_st,
                     "max_rel_err_servotune": float(np.abs(ours[idx] / ref - 1).max()),
                     "max_rel_err_python_control": float(np.abs(pc[idx] / ref - 1).max())}
    return out


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

    own = load_axis(args.axis)
    # sections 1 and 2: the continuous machinery, on the axis with its continuous drive
    axis = own.with_continuous_drive()
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
        "case": f"{axis.name} with its continuous drive: closed-loop f_wp_x -> wp_x, "
                f"{sub.nstates} states, {omega.size} frequencies",
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
    # section 3: the axis' own digital drive
    s = own.drive.sampling if own.drive is not None else None
    if s is None or s.is_continuous:
        result["digital_loops"] = {"skipped": "the axis' drive is continuous"}
    elif s.velocity_period != s.current_period:
        result["digital_loops"] = {"skipped": "the velocity controller is slower than the "
                                              "current controller (no plain baseline here)"}
    else:
        result["digital_loops"] = digital_loops(own, contact, args.repeat)
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
        dig = result["digital_loops"]
        if "skipped" in dig:
            print(f"  digital drive's loops: skipped ({dig['skipped']})")
        for loop in ("velocity", "position"):
            if loop in dig:
                row = dig[loop]
                print(f"  digital drive, {loop} loop, {row['frequencies']} frequencies up to "
                      f"{row['top_hz']:.0f} Hz: SampledAxis {row['time_servotune_s'] * 1e3:.1f} "
                      f"ms, python-control {row['time_python_control_s'] * 1e3:.1f} ms "
                      f"(speedup {row['speedup']:.1f} x); errors {row['max_rel_err_servotune']:.1e}"
                      f" / {row['max_rel_err_python_control']:.1e}")
    return result


if __name__ == "__main__":
    main()
