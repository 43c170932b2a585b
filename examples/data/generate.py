"""Write the data files of the examples (synthetic "measurements" with known truth).

Run ``python examples/data/generate.py --force`` to rewrite them; the output is the same on every
run (seeded ``numpy.random.default_rng``, fixed print precision). ``tests/test_examples.py``
checks that the stored files are what this script writes.

Files (paths relative to ``examples/data``):

``table_axis/M.mtx``, ``table_axis/K.mtx``, ``table_axis/dofs.csv``
    FE mass and stiffness of a small table axis (a 650 kg table on two guide-way pads, driven by
    a 40 x 10 ball screw through a bellows coupling, with a work-piece column), built with
    :class:`servotune.structure.StructureBuilder` and written as MatrixMarket files in
    symmetric storage (one triangle, as Ansys ``*EXPORT,...,MMF`` writes), with a DOF map of
    ``name`` and 1-based ``index`` columns. The axis description is
    ``table_axis/axis.toml`` (hand-written, not generated).
``table_axis/stribeck.csv``
    Sliding friction of that axis measured at constant velocities (``v_m_per_s,f_n``): the
    steady-state LuGre curve of :data:`TABLE_AXIS_FRICTION` with Gaussian force noise of
    :data:`TABLE_AXIS_NOISE` newtons.
``stribeck_paper_axis.csv``
    The same kind of test on the paper's axis: the steady-state curve of the identified set of
    Bianchi et al. (2014) (:data:`servotune.friction.BIANCHI2014`) with noise
    :data:`PAPER_AXIS_NOISE` N, at the speeds of a Fig 7-like test (0.1 mm/s to 0.5 m/s).
``frf_two_mode.csv``
    A tool/work-piece compliance in the feed direction (``f_hz,re_xx_m_per_n,im_xx_m_per_n``),
    as an averaged impact test would give it: two modes (:data:`FRF_MODES`) with relative
    complex Gaussian noise, ``G (1 + e)`` with the real and imaginary parts of ``e`` of standard
    deviation :data:`FRF_NOISE`, every 1 Hz from 200 Hz to 2000 Hz.
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import sys
from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse

from servotune.friction import BIANCHI2014, LuGreParameters, steady_state_friction
from servotune.structure import StructureBuilder

__all__ = [
    "FRF_MODES",
    "FRF_NOISE",
    "PAPER_AXIS_NOISE",
    "TABLE_AXIS_BOUNDARY",
    "TABLE_AXIS_FRICTION",
    "TABLE_AXIS_NOISE",
    "build_table_axis",
    "files",
    "frf_rows",
    "stribeck_rows",
    "write_all",
]

HERE = Path(__file__).resolve().parent
TWO_PI = 2.0 * math.pi

# -- the table axis ---------------------------------------------------------------------------
STEEL = {"e": 2.1e11, "rho": 7850.0, "nu": 0.3}
CAST_IRON = {"e": 1.2e11, "rho": 7200.0, "nu": 0.26}
SCREW_LEAD = 0.010                 # 40 x 10 ball screw [m]
SCREW_ROOT_DIAMETER = 0.034        # [m]
SCREW_X = (-0.70, 0.50)            # screw ends along X [m]; the nut is at X = 0
SCREW_Z = 0.06                     # screw axis above the pad plane [m]
J_ROTOR = 3.0e-3                   # 12 N m servo motor, rotor + encoder disk [kg m^2]
J_STATOR = 0.03                    # motor housing about the shaft axis [kg m^2]
K_MOTOR_MOUNT = 1.0e6              # flange mount of the stator, torsion [N m/rad]
K_COUPLING = 4.0e4                 # bellows coupling rotor -> screw, torsion [N m/rad]
K_BEARING_AXIAL = 6.0e8            # fixed bearing set at the motor end [N/m]
K_BEARING_RADIAL = 4.0e8           # each end [N/m]
K_NUT_AXIAL = 5.0e8                # preloaded single nut [N/m]
K_NUT_RADIAL = 2.0e8
TABLE_X = (-0.45, 0.45)            # table casting, a box beam along X [m]
TABLE_Z = 0.15
TABLE_MASS = 650.0                 # table with its ribs and covers [kg]
PADS_X = (-0.45, 0.45)             # two plain pads under the table ends
K_PAD_Z, K_PAD_Y, K_PAD_TILT = 1.2e9, 6.0e8, 8.0e6
M_PAD = 4.0
COLUMN_Z = (0.30, 0.75)            # work-piece column (fixture) on the table centre [m]
WP_Z = 0.80
WP_MASS = 120.0                    # work piece [kg]
ENCODER_POS = (0.0, 0.25, 0.05)    # linear-scale reading head on the table side
K_LINK = 1.0e10                    # penalty stiffness of rigid attachments [N/m]

#: Boundary DOFs of the Craig-Bampton reduction named in ``table_axis/axis.toml``.
TABLE_AXIS_BOUNDARY = ("pad1.x", "pad2.x", "wp.x", "wp.y", "wp.z", "motor.rotor",
                       "motor.stator", "encoder.x")

#: The true axis-total friction of the table axis (steady-state parameters identified in the
#: example; sigma0 and sigma1 are those written in ``axis.toml``).
TABLE_AXIS_FRICTION = LuGreParameters(fc=650.0, fs=1450.0, vs=0.006, delta=1.0, sigma0=1.4e9,
                                      sigma1=4.0e6, sigma2=2600.0)
TABLE_AXIS_NOISE = 15.0            # [N], standard deviation of the force readings
PAPER_AXIS_NOISE = 60.0            # [N], 1 % of the paper's Fs

#: (f_n [Hz], zeta, modal stiffness [N/m]) of the two modes of ``frf_two_mode.csv``: the
#: dominant one is the flexible one (smallest k zeta (1 + zeta)).
FRF_MODES = ((620.0, 0.035, 2.0e7), (1350.0, 0.025, 6.0e7))
FRF_NOISE = 0.01
FRF_F_HZ = np.arange(200.0, 2000.0 + 0.5, 1.0)


def _box(b, h, t):
    """Area, both second moments and the Bredt torsion constant of a box b x h, wall t [m]."""
    area = b * h - (b - 2 * t) * (h - 2 * t)
    i_h = (b * h**3 - (b - 2 * t) * (h - 2 * t) ** 3) / 12
    i_b = (h * b**3 - (h - 2 * t) * (b - 2 * t) ** 3) / 12
    am = (b - t) * (h - t)
    return area, i_h, i_b, 4 * am**2 * t / (2 * (b + h - 2 * t))


def build_table_axis(refine: int = 1):
    """Sparse (CSR) mass and stiffness of the table axis and its DOF names; ``refine``
    multiplies the number of beam elements of the screw, the table and the column (1: the
    146-DOF model of ``table_axis``; the ports keep their names at every refinement)."""
    sb = StructureBuilder()
    pitch = SCREW_LEAD / TWO_PI
    for name in ("motor.rotor", "motor.stator"):
        sb.add_dof(name)
    sb.add_mass("motor.rotor", J_ROTOR)
    sb.add_mass("motor.stator", J_STATOR)
    sb.add_spring({"motor.stator": 1.0}, K_MOTOR_MOUNT)

    # ball screw, 8 elements; the coupling twists between rotor and screw end
    sb.add_node("screw.0", (SCREW_X[0], 0.0, SCREW_Z))
    sb.add_node("screw.1", (SCREW_X[1], 0.0, SCREW_Z))
    d = SCREW_ROOT_DIAMETER
    area, inertia = math.pi * d * d / 4, math.pi * d**4 / 64
    screw = sb.add_beam("screw.0", "screw.1", area=area, iy=inertia, iz=inertia,
                        torsion=2 * inertia, n_elements=8 * refine, **STEEL)
    sb.add_spring({"motor.rotor": 1.0, "screw.0.rx": -1.0}, K_COUPLING)
    sb.add_spring({"screw.0.x": 1.0}, K_BEARING_AXIAL)
    for end in (screw[0], screw[-1]):
        for c in "yz":
            sb.add_spring({f"{end}.{c}": 1.0}, K_BEARING_RADIAL)
    nut_on_screw = min(screw, key=lambda n: abs(sb.nodes[n][0]))

    # table: box beam 0.9 m long, 4 elements, density scaled to the table mass
    sb.add_node("table.0", (TABLE_X[0], 0.0, TABLE_Z))
    sb.add_node("table.1", (TABLE_X[1], 0.0, TABLE_Z))
    a_t, ih_t, ib_t, tor_t = _box(0.55, 0.25, 0.025)
    rho = TABLE_MASS / (a_t * (TABLE_X[1] - TABLE_X[0]))
    table = sb.add_beam("table.0", "table.1", e=CAST_IRON["e"], nu=CAST_IRON["nu"], rho=rho,
                        area=a_t, iy=ih_t, iz=ib_t, torsion=tor_t, n_elements=4 * refine)
    for k, x in enumerate(PADS_X, start=1):
        pad = f"pad{k}"
        sb.add_node(pad, (x, 0.0, 0.0))
        sb.add_mass(pad, M_PAD, (0.02, 0.02, 0.02))
        host = min(table, key=lambda n, x=x: abs(sb.nodes[n][0] - x))
        sb.add_rigid_link(host, pad, K_LINK)
        sb.add_spring({f"{pad}.z": 1.0}, K_PAD_Z)
        sb.add_spring({f"{pad}.y": 1.0}, K_PAD_Y)
        for c in ("rx", "ry", "rz"):
            sb.add_spring({f"{pad}.{c}": 1.0}, K_PAD_TILT)
    centre = min(table, key=lambda n: abs(sb.nodes[n][0]))

    sb.add_node("nut", (0.0, 0.0, SCREW_Z))
    sb.add_mass("nut", 8.0, (0.01, 0.01, 0.01))
    sb.add_rigid_link(centre, "nut", K_LINK)
    sb.add_spring({"nut.x": 1.0, f"{nut_on_screw}.x": -1.0, f"{nut_on_screw}.rx": -pitch},
                  K_NUT_AXIAL)
    for c in "yz":
        sb.add_spring({f"nut.{c}": 1.0, f"{nut_on_screw}.{c}": -1.0}, K_NUT_RADIAL)

    sb.add_node("encoder", ENCODER_POS)
    sb.add_mass("encoder", 0.5, (1e-4, 1e-4, 1e-4))
    sb.add_rigid_link(centre, "encoder", K_LINK)

    # work-piece column: steel box 0.22 x 0.22, wall 15 mm, 4 elements; work piece on top
    sb.add_node("column.0", (0.0, 0.0, COLUMN_Z[0]))
    sb.add_node("column.1", (0.0, 0.0, COLUMN_Z[1]))
    sb.add_rigid_link(centre, "column.0", K_LINK)
    a_c, ih_c, ib_c, tor_c = _box(0.22, 0.22, 0.015)
    sb.add_beam("column.0", "column.1", area=a_c, iy=ih_c, iz=ib_c, torsion=tor_c,
                n_elements=4 * refine, up=(1.0, 0.0, 0.0), **STEEL)
    sb.add_node("wp", (0.0, 0.0, WP_Z))
    sb.add_mass("wp", WP_MASS, (WP_MASS * 0.02, WP_MASS * 0.02, WP_MASS * 0.02))
    sb.add_rigid_link("column.1", "wp", K_LINK)
    mass, stiffness, dofs = sb.assemble()
    # symmetric storage needs exact symmetry; the assembly is symmetric to round-off
    return ((mass + mass.T) / 2).tocsr(), ((stiffness + stiffness.T) / 2).tocsr(), dofs


def _matrix_market(a) -> str:
    """A symmetric sparse matrix as MatrixMarket text (one triangle)."""
    buffer = io.BytesIO()
    scipy.io.mmwrite(buffer, scipy.sparse.coo_array(scipy.sparse.tril(a)), symmetry="symmetric",
                     precision=15, comment="generated by examples/data/generate.py; SI units")
    return buffer.getvalue().decode()


def _csv(header, rows) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    return out.getvalue()


def stribeck_rows(params: LuGreParameters, noise: float, speeds, seed: int):
    """(v, F) rows of a constant-velocity test over both directions with seeded force noise."""
    speeds = np.asarray(speeds, dtype=float)
    v = np.concatenate([-speeds[::-1], speeds])
    rng = np.random.default_rng(seed)
    force = steady_state_friction(params, v) + noise * rng.standard_normal(v.size)
    return [(f"{vi:.6e}", f"{fi:.3f}") for vi, fi in zip(v, force, strict=True)]


def frf_rows(seed: int = 4):
    """(f_hz, Re G_xx, Im G_xx) rows: two modes with relative complex noise (module docstring)."""
    w = TWO_PI * FRF_F_HZ
    g = np.zeros(w.size, dtype=complex)
    for f_n, zeta, k in FRF_MODES:
        r = w / (TWO_PI * f_n)
        g += (1.0 / k) / (1.0 - r**2 + 2j * zeta * r)
    rng = np.random.default_rng(seed)
    g = g * (1.0 + FRF_NOISE * (rng.standard_normal(w.size) + 1j * rng.standard_normal(w.size)))
    return [(f"{f:.1f}", f"{z.real:.6e}", f"{z.imag:.6e}") for f, z in
            zip(FRF_F_HZ, g, strict=True)]


def files() -> dict[str, str]:
    """Every generated file: path relative to ``examples/data`` -> text."""
    mass, stiffness, dofs = build_table_axis()
    return {
        "table_axis/M.mtx": _matrix_market(mass),
        "table_axis/K.mtx": _matrix_market(stiffness),
        "table_axis/dofs.csv": _csv(("index", "name"),
                                    [(i + 1, name) for i, name in enumerate(dofs)]),
        "table_axis/stribeck.csv": _csv(
            ("v_m_per_s", "f_n"),
            stribeck_rows(TABLE_AXIS_FRICTION, TABLE_AXIS_NOISE, np.geomspace(2e-4, 0.4, 16),
                          seed=1)),
        "stribeck_paper_axis.csv": _csv(
            ("v_m_per_s", "f_n"),
            stribeck_rows(BIANCHI2014, PAPER_AXIS_NOISE, np.geomspace(1e-4, 0.5, 20), seed=2)),
        "frf_two_mode.csv": _csv(("f_hz", "re_xx_m_per_n", "im_xx_m_per_n"), frf_rows()),
    }


def write_all(folder=HERE, force: bool = False) -> list[Path]:
    """Write every file under ``folder``; refuse to replace existing ones without ``force``."""
    folder = Path(folder)
    content = files()
    targets = [folder / name for name in content]
    existing = [str(p) for p in targets if p.exists()]
    if existing and not force:
        raise FileExistsError(f"{existing[0]} exists (and {len(existing) - 1} more); pass "
                              "--force to replace")
    for text, path in zip(content.values(), targets, strict=True):
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return targets


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE, help="folder (default: examples/data)")
    parser.add_argument("--force", action="store_true", help="replace existing files")
    args = parser.parse_args()
    try:
        for p in write_all(args.out, args.force):
            print(p)
    except FileExistsError as exc:
        sys.exit(str(exc))
