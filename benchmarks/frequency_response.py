"""Closed-loop work-piece compliance of the bundled axis at 2,000 frequencies.

Two servotune methods against python-control's ``frequency_response`` on the same SISO system
(f_wp_x -> wp_x) of the interconnected plant (``build_plant`` with the axis' viscous-only pads
and its drive):

* ``port_compliance``: the structure's receptance at its ports from the modal sum, closed with
  the contacts and the cascade by one small batched linear solve (never forms the closed loop);
* ``fast_frequency_response``: the closed-loop state space, balanced, in modal form
  C V diag(1/(jw - lambda)) V^-1 B, checked a posteriori against direct solves.

All are compared with a balanced direct solve of (jw I - A) x = B, the accuracy reference.

Usage: ``python benchmarks/frequency_response.py [--json] [--repeat N] [--axis PATH]``
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import control
import numpy as np
import scipy.linalg
from _timing import best_time

from servotune import analysis
from servotune.axis import load_axis
from servotune.frequency import fast_frequency_response, port_compliance

ROOT = Path(__file__).resolve().parents[1]



def reference(sys, omega):
    """Balanced direct solve, one frequency at a time (the accuracy reference)."""
    a, t = scipy.linalg.matrix_balance(sys.A, permute=False, separate=True)
    b, c = sys.B / t[0][:, None], sys.C * t[0][None, :]
    eye = np.eye(a.shape[0])
    return np.array([(c @ np.linalg.solve(1j * w * eye - a, b))[0, 0] + sys.D[0, 0]
                     for w in omega])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--axis", default=str(ROOT / "models" / "paper_x_axis"))
    args = parser.parse_args(argv)

    axis = load_axis(args.axis)
    plant = analysis.axis_plant(axis, analysis.axis_contact(axis, "viscous"))
    sub = plant[plant.output_labels.index("wp_x"), plant.input_labels.index("f_wp_x")]
    omega = 2 * math.pi * np.geomspace(1.0, 1000.0, 2000)

    contact = analysis.axis_contact(axis, "viscous")
    t_ports, ports = best_time(
        lambda: port_compliance(axis.structure, omega, axis.drive, contact, axis.pads)[0],
        args.repeat)
    t_fast, fast = best_time(
        lambda: fast_frequency_response(sub, omega).complex.reshape(-1), args.repeat)
    t_pc, pc = best_time(
        lambda: control.frequency_response(sub, omega).complex.reshape(-1), args.repeat)
    ref = reference(sub, omega)
    result = {
        "case": f"{axis.name}: closed-loop f_wp_x -> wp_x, {sub.nstates} states, "
                f"{omega.size} frequencies",
        "time_servotune_ports_s": t_ports,
        "time_servotune_modal_state_space_s": t_fast,
        "time_python_control_s": t_pc,
        "speedup": t_pc / t_ports,
        "speedup_modal_state_space": t_pc / t_fast,
        "max_rel_diff_servotune_vs_python_control": float(np.abs(ports / pc - 1).max()),
        "max_rel_err_servotune_ports_vs_reference": float(np.abs(ports / ref - 1).max()),
        "max_rel_err_servotune_modal_vs_reference": float(np.abs(fast / ref - 1).max()),
        "max_rel_err_python_control_vs_reference": float(np.abs(pc / ref - 1).max()),
        "control_version": control.__version__,
    }
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
    return result


if __name__ == "__main__":
    main()
