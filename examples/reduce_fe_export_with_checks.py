"""From an FE export to a checked reduced model: ports by node number, reduction, checks.

The goal: take the matrices of a structure as an FE program exports them (MatrixMarket M and K,
a DOF map of node numbers and direction labels, node coordinates), name the few DOFs the axis
needs from their node numbers or positions (a ports file), reduce by Craig-Bampton, and let
the reduction check say whether the reduced model is right over the band of interest.

The data: a symmetric structure made here, a round table on a hub with six identical radial
ribs (each rib 60 masses on springs), written to files as an export would be. The ports are
the hub (``wp.z``, by node number) and the tip of the first rib (``tip.z``, by position). With
both held, five ribs are fixed-free chains, so each of their frequencies is a fixed-interface
frequency five times (closed form below), which the reduction must keep; in the full model
five ways of the ribs swinging against each other leave the hub still and keep the first rib
frequency exactly.

Two reductions are checked over 5-150 Hz: six fixed-interface modes (up to 67 Hz: the check
fails and names the frequency to keep), and every mode up to 600 Hz (the check passes).
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse as sp

import servotune as st
from servotune.structure import craig_bampton, reduction_check

N_RIBS, N_PER_RIB = 6, 60
M_RIB, K_RIB = 1.0, 6.43e7          # kg per rib mass, N/m per rib spring
M_HUB, K_HUB = 50.0, 1e8            # the hub and its support
RADIUS = 0.5                        # m, length of a rib
BAND_HZ = (5.0, 150.0)


def rib_frequencies_hz(count: int) -> np.ndarray:
    """Fixed-free chain of one rib: f_j = sqrt(k/m) sin((2j-1) pi / (2 (2n+1))) / pi."""
    j = np.arange(1, count + 1)
    return np.sqrt(K_RIB / M_RIB) * np.sin((2 * j - 1) * np.pi / (2 * (2 * N_PER_RIB + 1))) \
        / math.pi


def write_export(folder: Path) -> None:
    """M.mtx, K.mtx, dofs.csv (node, dof), nodes.csv (node, x, y, z) and ports.csv."""
    n = 1 + N_RIBS * N_PER_RIB
    nodes = [1] + [1000 * (a + 1) + j for a in range(N_RIBS) for j in range(N_PER_RIB)]
    rows, cols, vals = [], [], []

    def spring(i, j, value):
        rows.extend([i, j, i, j])
        cols.extend([i, j, j, i])
        vals.extend([value, value, -value, -value])

    for a in range(N_RIBS):
        first = 1 + a * N_PER_RIB
        spring(0, first, K_RIB)
        for j in range(N_PER_RIB - 1):
            spring(first + j, first + j + 1, K_RIB)
    k = sp.coo_array((vals, (rows, cols)), shape=(n, n)).tocsr() \
        + sp.diags_array(np.r_[K_HUB, np.zeros(n - 1)])
    m = sp.diags_array(np.r_[M_HUB, np.full(n - 1, M_RIB)])
    scipy.io.mmwrite(folder / "M.mtx", sp.coo_array(m), symmetry="symmetric")
    scipy.io.mmwrite(folder / "K.mtx", sp.coo_array(k.tocsr()), symmetry="symmetric")
    (folder / "dofs.csv").write_text(
        "index,node,dof\n" + "".join(f"{i + 1},{node},UZ\n" for i, node in enumerate(nodes)))
    lines = ["node,x,y,z", "1,0,0,0"]
    for a in range(N_RIBS):
        phi = 2 * math.pi * a / N_RIBS
        for j in range(N_PER_RIB):
            r = RADIUS * (j + 1) / N_PER_RIB
            lines.append(f"{1000 * (a + 1) + j},{r * math.cos(phi):.6f},{r * math.sin(phi):.6f},0")
    (folder / "nodes.csv").write_text("\n".join(lines) + "\n")
    # the hub by its node number, a rib tip by its position (the nearest node is taken)
    (folder / "ports.csv").write_text("port,node,x,y,z,direction\n"
                                      "wp.z,1,,,,UZ\n"
                                      f"tip.z,,{RADIUS},0,0,UZ\n")


def main(folder: Path | None = None) -> dict:
    """Write the export, read it with its ports, reduce it twice and check both reductions."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) if folder is None else Path(folder)
        write_export(folder)
        data = st.read_structure(folder / "M.mtx", folder / "K.mtx", folder / "dofs.csv",
                                 ports=folder / "ports.csv", coordinates=folder / "nodes.csv")
    ports = ["wp.z", "tip.z"]
    boundary = data.index(ports)
    band = tuple(2 * math.pi * f for f in BAND_HZ)
    results = {"ports_rows": boundary.tolist(), "n_dofs_full": data.n}
    for label, kwargs in (("few", {"n_modes": 6}), ("enough", {"f_max_hz": 600.0})):
        model = craig_bampton(data.mass, data.stiffness, boundary, boundary_names=ports,
                              **kwargs)
        check = reduction_check(data.mass, data.stiffness, boundary, model, band)
        print(f"-- {label}: {model.n - len(ports)} fixed-interface modes")
        print(check)
        results[label] = {"passed": check.passed, "failures": list(check.failures),
                          "fixed_interface_hz": list(model.reduction.fixed_interface_hz),
                          "full_frequencies_hz": check.full_frequencies_hz.tolist(),
                          "max_frequency_error": check.max_frequency_error,
                          "max_compliance_error": check.max_compliance_error,
                          "coverage_message": check.coverage.message}
    return results


if __name__ == "__main__":
    main()
