"""An exported axis end to end: FE matrices with node numbers, ports named in ``axis.toml`` from
node numbers and positions, reduced on loading, checked and tuned by ``servotune tune``.

The structure is built here and written as an FE program exports it: MatrixMarket M and K in
symmetric storage, a DOF map ``index,node,dof`` (``UX``, ``UY``, ``ROTX``) and node coordinates
``node,x,y,z``. A 650 kg table (five nodes in X and Y, the pads at its ends), a work-piece column
on its centre (four nodes, the work piece at the top), a linear-encoder head, a ball-screw shaft
coupled to the motor rotor and a stator on a torsional mount. References: the dense
eigen-solution of the full matrices, the exact static condensation of Craig-Bampton, the
screw's r = lead / (2 pi) and the Ritz upper bound of a reduced model's frequencies.
"""

import dataclasses
import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.linalg
import scipy.sparse as sp
from axis_fixtures import PADS, small_axis, small_drive

import servotune as st
from servotune.axis import AxisFormatError, structure_matrices
from servotune.cli import main
from servotune.closed_loop import closed_loop
from servotune.plant import Contact
from servotune.tuning import RequirementsNotMetError, TuningProblem, tune
from servotune.tuning.nlp import Solver

RATIO = 10e-3 / (2 * math.pi)  # 10 mm lead [m/rad]
TABLE = (101, 102, 103, 104, 105)
COLUMN = (301, 302, 303, 304)
ENCODER, SCREW, ROTOR, STATOR = 120, 201, 9001, 9002
BOUNDARY = ["pad1.x", "pad2.x", "wp.x", "motor.rotor", "motor.stator", "encoder.x"]
#: the export's rows of the ports (what axis.toml names them from)
PORT_ROWS = {"pad1.x": (101, "UX"), "pad2.x": (105, "UX"), "wp.x": (304, "UX"),
             "motor.rotor": (ROTOR, "ROTX"), "motor.stator": (STATOR, "ROTX"),
             "encoder.x": (ENCODER, "UX")}
BAND_HZ = (5.0, 300.0)
TWO_PI = 2 * math.pi


def export_structure(folder: Path, flip: int | None = None):
    """Write M.mtx, K.mtx, dofs.csv and nodes.csv; ``flip`` reverses the direction of that
    node's first DOF (its row and column of M and K times -1), as a sign slip in an export does.
    Returns the dense M, K and the rows (node, label)."""
    rows, mass = [], []

    def dof(node, label, m):
        rows.append((node, label))
        mass.append(m)
        return len(rows) - 1

    rot, sta, scr = dof(ROTOR, "ROTX", 3e-3), dof(STATOR, "ROTX", 0.03), dof(SCREW, "ROTX", 2e-3)
    tx = {n: dof(n, "UX", 130.0) for n in TABLE}
    ty = {n: dof(n, "UY", 130.0) for n in TABLE}
    enc = dof(ENCODER, "UX", 2.0)
    cx = {n: dof(n, "UX", 120.0 if n == COLUMN[-1] else 30.0) for n in COLUMN}
    springs = [({sta: 1.0}, 1.0e6),                      # motor mount [N m/rad]
               ({rot: 1.0, scr: -1.0}, 4.0e5),           # disc coupling [N m/rad]
               ({scr: RATIO, tx[103]: -1.0}, 5.0e8),     # nut on r theta - x [N/m]
               ({ty[101]: 1.0}, 6.0e8), ({ty[105]: 1.0}, 6.0e8),  # guide ways across
               ({enc: 1.0, tx[103]: -1.0}, 5.0e8)]       # encoder-head bracket
    for a, b in itertools.pairwise(TABLE):
        springs += [({tx[a]: 1.0, tx[b]: -1.0}, 2.0e9), ({ty[a]: 1.0, ty[b]: -1.0}, 1.0e9)]
    below = tx[103]
    for n in COLUMN:
        springs.append(({cx[n]: 1.0, below: -1.0}, 8.0e8))
        below = cx[n]
    n = len(rows)
    m, k = np.diag(mass), np.zeros((n, n))
    for coefficients, value in springs:
        v = np.zeros(n)
        for i, c in coefficients.items():
            v[i] += c
        k += value * np.outer(v, v)
    if flip is not None:
        t = np.ones(n)
        t[next(i for i, (node, _) in enumerate(rows) if node == flip)] = -1.0
        m, k = t[:, None] * m * t, t[:, None] * k * t
    scipy.io.mmwrite(folder / "M.mtx", sp.coo_array(m), symmetry="symmetric")
    scipy.io.mmwrite(folder / "K.mtx", sp.coo_array(k), symmetry="symmetric")
    (folder / "dofs.csv").write_text("index,node,dof\n" + "".join(
        f"{i + 1},{node},{label}\n" for i, (node, label) in enumerate(rows)))
    xyz = {ROTOR: (-0.80, 0.0, 0.06), STATOR: (-0.85, 0.0, 0.06), SCREW: (-0.60, 0.0, 0.06),
           ENCODER: (0.0, 0.25, 0.05)}
    xyz.update({node: (-0.45 + 0.225 * j, 0.0, 0.15) for j, node in enumerate(TABLE)})
    xyz.update({node: (0.0, 0.0, 0.35 + 0.15 * j) for j, node in enumerate(COLUMN)})
    (folder / "nodes.csv").write_text("node,x,y,z\n" + "".join(
        f"{node},{x},{y},{z}\n" for node, (x, y, z) in xyz.items()))
    return m, k, rows


STRUCTURE = """\
[axis]
name = "exported_axis"

[structure]
mass = "M.mtx"
stiffness = "K.mtx"
dof_map = "dofs.csv"
coordinates = "nodes.csv"
modal_damping = 0.03
reduce = {{ boundary = {boundary}, {reduce} }}

[structure.ports]
"pad1.x" = {{ node = 101, direction = "x" }}
"pad2.x" = {{ node = 105, direction = "UX" }}
"encoder.x" = {{ node = {encoder}, direction = "1" }}
"wp.x" = {{ position = [0.0, 0.0, 0.8], direction = "x" }}
"motor.rotor" = {{ node = {rotor}, direction = "ROTX" }}
"motor.stator" = {{ node = {stator}, direction = "rx" }}
"""

# friction and drive as in examples/data/table_axis/axis.toml; Kv = 0.1 1/s held (free = c):
# the position loop's gain kv / omega stays below 1 from 0.1 Hz up (no gain crossover)
REST = """
[friction]
pads = ["pad1.x", "pad2.x"]

[friction.lugre]
fc = 600.0
fs = 1500.0
vs = 0.005
delta = 1.0
sigma0 = 1.4e9
sigma1 = 4.0e6
sigma2 = 2000.0
sigma1_decay_speed = 1.0e-3

[drive]
encoder = "linear"

[drive.motor]
rotor = "motor.rotor"
stator = "motor.stator"
torque_constant = 1.2
back_emf_constant = 1.2
resistance = 0.6
inductance = 6.0e-3
torque_peak = 36.0
torque_continuous = 12.0
speed_max_rpm = 3000.0

[drive.transmission]
ratio = 1.591549e-3

[drive.current_loop]
kp = 30.0
ti = 10.0e-3

[drive.velocity_loop]
kp = 2.0
ti = 20.0e-3

[drive.position_loop]
kv = {kv}

[cutting]
teeth = 3
kt = 1.5e9
kn = 0.45e9
radial_immersion = 0.5
milling = "down"
speed_rpm = [2000.0, 12000.0]

[operation]
acceleration = 2.0

[tuning]
free = ["c"]

[requirements]
ms_velocity_max = 2.0
ms_position_max = 1.5
band_hz = [5.0, 300.0]
depth_required = 1.0e-3
"""


def write_axis(folder: Path, reduce: str = "f_max_hz = 1000.0", flip: int | None = None,
               kv: float = 0.1, structure: str | None = None):
    """An exported axis in ``folder``; returns (M, K, rows) of the full export."""
    folder.mkdir(parents=True, exist_ok=True)
    full = export_structure(folder, flip)
    text = structure if structure is not None else STRUCTURE.format(
        boundary=json.dumps(BOUNDARY), reduce=reduce, encoder=ENCODER, rotor=ROTOR,
        stator=STATOR)
    (folder / "axis.toml").write_text(text + REST.format(kv=kv))
    return full


def dense_frequencies_hz(m, k):
    return np.sqrt(np.clip(scipy.linalg.eigh(k, m, eigvals_only=True), 0.0, None)) / TWO_PI


def row(rows, name):
    return rows.index(PORT_ROWS[name])


def tune_json(folder: Path, out: Path, capsys, *extra):
    code = main(["tune", str(folder), "--json", "--no-simulation", "--no-plots", "--starts",
                 "1", "--workers", "1", "--out", str(out), *extra])
    captured = capsys.readouterr()
    return code, json.loads(captured.out), captured.err


# -- loading: ports, reduction -------------------------------------------------------------------
def test_ports_name_the_export_rows_and_the_reduction_matches_the_full_model(tmp_path):
    m, k, rows = write_axis(tmp_path / "ax")
    axis = st.load_axis(tmp_path / "ax")
    model = axis.structure
    assert list(model.dofs[:len(BOUNDARY)]) == BOUNDARY
    # each port names the export's row of its node and direction (wp.x by position: node 304)
    data = structure_matrices(axis)
    assert [data.dofs.index(p) for p in BOUNDARY] == [row(rows, p) for p in BOUNDARY]
    assert "102.ux" in data.dofs and "101.uy" in data.dofs  # other rows keep their names
    # the ports are the rows they name: Craig-Bampton keeps the static condensation exact, so
    # the static compliance at wp.x with the pads and the motor held is the full model's
    held = ["pad1.x", "pad2.x", "motor.rotor", "motor.stator"]
    free = [i for i in range(len(rows)) if i not in {row(rows, h) for h in held}]
    full = np.linalg.inv(k[np.ix_(free, free)])[free.index(row(rows, "wp.x"))]
    reduced = model.locked(held)
    j = reduced.dofs.index("wp.x")
    compliance = np.linalg.inv(reduced.stiffness)[j]
    assert compliance[j] == pytest.approx(full[free.index(row(rows, "wp.x"))], rel=1e-9)
    assert compliance[reduced.dofs.index("encoder.x")] == pytest.approx(
        full[free.index(row(rows, "encoder.x"))], rel=1e-9)
    # every mode of the band from the reduced model (modes to 1000 Hz kept, 3.3 x the band's
    # top) agrees with the dense eigen-solution of the full matrices to 0.05 %
    f_full = dense_frequencies_hz(m, k)
    f_red = np.sort(model.natural_frequencies()) / TWO_PI
    in_band = f_full[(f_full > BAND_HZ[0]) & (f_full < BAND_HZ[1])]
    assert in_band.size >= 3
    assert f_full[0] < 1e-3 and f_red[0] < 1e-3  # the slide with the free motor: rigid
    np.testing.assert_allclose(f_red[1:1 + in_band.size], in_band, rtol=5e-4)


def test_a_reduction_with_too_few_modes_is_a_ritz_upper_bound(tmp_path):
    m, k, _ = write_axis(tmp_path / "ax", reduce="n_modes = 1")
    model = st.load_axis(tmp_path / "ax").structure
    f_full = dense_frequencies_hz(m, k)
    f_red = np.sort(model.natural_frequencies()) / TWO_PI
    assert model.n == len(BOUNDARY) + 1
    # Rayleigh-Ritz: the j-th frequency of a reduced model is at or above the full one's; one
    # fixed-interface mode leaves the band's modes more than 1 % too high
    assert np.all(f_red[1:] >= f_full[1:model.n] * (1 - 1e-9))
    assert np.max(f_red[1:4] / f_full[1:4] - 1) > 0.01


# -- tune and bode end to end ---------------------------------------------------------------------
def test_tune_writes_results_with_reasons_and_warns_about_the_band(tmp_path, capsys):
    m, k, rows = write_axis(tmp_path / "ax", reduce="n_modes = 1")
    code, out, err = tune_json(tmp_path / "ax", tmp_path / "out", capsys)
    assert code == 3, err  # the linear checks hold; the nonlinear verification was skipped
    written = json.loads((tmp_path / "out" / "tune_exported_axis" / "results.json").read_text())
    assert written["reasons"] == out["reasons"] and written["reasons"]
    assert any("--no-simulation" in r for r in written["reasons"])
    # the position loop has no gain crossover: null figures with their reason beside them
    position = written["loops_after"]["position_loop"]
    for key in ("phase_margin_deg", "crossover_hz"):
        assert position[key] is None
        assert "no gain crossover" in position[f"{key}_reason"]
    # ... as the loop itself says: |L| < 1 already at the lowest analysed frequency (0.1 Hz),
    # and |L| ~ kv / omega there (the velocity loop closed follows its command)
    axis = st.load_axis(tmp_path / "ax")
    d = dataclasses.replace(axis.drive, kv=written["design"]["kv"])
    w_low = TWO_PI * 0.1
    gain = abs(complex(closed_loop(axis.structure, d, Contact.viscous(written["design"]["c"]),
                                   axis.pads).loop_response("position", [w_low])[0]))
    assert gain < 1.0 and gain == pytest.approx(0.1 / w_low, rel=0.05)
    # the band warning names the band, the frequency reached and the fix; the kept mode is the
    # lowest fixed-interface mode of the full matrices (boundary held)
    b = [row(rows, p) for p in BOUNDARY]
    inner = [i for i in range(len(rows)) if i not in b]
    f_fixed = dense_frequencies_hz(m[np.ix_(inner, inner)], k[np.ix_(inner, inner)])
    (warning,) = written["warnings"]
    assert "5-300 Hz" in warning and f"{f_fixed[0]:.4g} Hz" in warning
    assert "f_max_hz = 450" in warning
    assert "WARNING: band coverage" in err
    assert written["model_checks"]["transmission"]["structure_ratio"] == pytest.approx(
        RATIO, rel=1e-6)


def test_tune_with_enough_modes_gives_no_warning(tmp_path, capsys):
    write_axis(tmp_path / "ax", reduce="f_max_hz = 1000.0")
    code, out, err = tune_json(tmp_path / "ax", tmp_path / "out", capsys)
    assert code in (1, 3), err
    assert out["warnings"] == [] and "WARNING" not in err
    assert out["model_checks"]["band_coverage"]["covered"] is True


@pytest.mark.parametrize("command", ["tune", "bode"])
@pytest.mark.parametrize("node, dof", [(ENCODER, "encoder.x"), (ROTOR, "motor.rotor")])
def test_a_flipped_direction_is_refused_naming_the_dof(tmp_path, capsys, command, node, dof):
    write_axis(tmp_path / "ax", flip=node)
    out = tmp_path / "out"
    argv = [command, str(tmp_path / "ax"), "--out", str(out), "--no-plots"]
    assert main(argv + (["--no-simulation"] if command == "tune" else [])) == 1
    err = capsys.readouterr().err
    assert "flipped" in err and f"reverse {dof}" in err and "not the gains" in err
    assert f"{dof} is node {node}" in err  # where the export has it
    assert not out.exists()  # refused before any work


def test_a_transmission_ratio_off_is_refused(tmp_path, capsys):
    write_axis(tmp_path / "ax")
    toml = tmp_path / "ax" / "axis.toml"
    toml.write_text(toml.read_text().replace("ratio = 1.591549e-3", "ratio = 1.0e-2"))
    assert main(["bode", str(tmp_path / "ax"), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert "[drive.transmission] ratio" in err and "encoder.x" in err


# -- bad [structure] values -----------------------------------------------------------------------
def _ports(**changes):
    lines = {"pad1.x": '{ node = 101, direction = "x" }',
             "pad2.x": '{ node = 105, direction = "UX" }',
             "encoder.x": '{ node = 120, direction = "x" }',
             "wp.x": '{ position = [0.0, 0.0, 0.8], direction = "x" }',
             "motor.rotor": '{ node = 9001, direction = "ROTX" }',
             "motor.stator": '{ node = 9002, direction = "rx" }'}
    lines.update(changes)
    return "\n".join(f'"{k}" = {v}' for k, v in lines.items() if v is not None)


def _structure(extra="", ports=None, coordinates='coordinates = "nodes.csv"'):
    return (f'[axis]\nname = "exported_axis"\n\n[structure]\nmass = "M.mtx"\n'
            f'stiffness = "K.mtx"\ndof_map = "dofs.csv"\n{coordinates}\n{extra}\n'
            f"[structure.ports]\n{ports if ports is not None else _ports()}\n")


BAD = [
    ("unknown-port-key", _structure(ports=_ports(**{"pad1.x": '{ node = 101, dir = "x" }'})),
     r'\[structure.ports\] "pad1.x": unknown keys \[\'dir\'\]'),
    ("node-not-in-export",
     _structure(ports=_ports(**{"pad1.x": '{ node = 777, direction = "x" }'})),
     r"node 777 is not in the DOF map"),
    ("direction-not-at-node", _structure(ports=_ports(**{"encoder.x": '{ node = 120, '
                                                         'direction = "y" }'})),
     r"node 120 has no y DOF .*it has ux"),
    ("unknown-direction", _structure(ports=_ports(**{"pad1.x": '{ node = 101, '
                                                     'direction = "sideways" }'})),
     r'"pad1.x".*unknown direction'),
    ("node-and-position", _structure(ports=_ports(**{"pad1.x": '{ node = 101, position = '
                                                     '[0, 0, 0], direction = "x" }'})),
     r"either a node number or a position"),
    ("position-not-3", _structure(ports=_ports(**{"wp.x": '{ position = [0.0, 0.8], '
                                                  'direction = "x" }'})),
     r'"wp.x" position: got \[0.0, 0.8\]; give three coordinates'),
    ("position-far", _structure(ports=_ports(**{"wp.x": '{ position = [0.0, 0.0, 0.9], '
                                                'direction = "x" }'})),
     r"farther than the tolerance"),
    ("position-without-coordinates", _structure(coordinates=""),
     r"\[structure\] coordinates: missing: ports \['wp.x'\] are given by position"),
    ("coordinates-missing-file", _structure(coordinates='coordinates = "gone.csv"'),
     r"\[structure\] coordinates: .*gone.csv does not exist"),
    ("ports-not-a-table", _structure().split("[structure.ports]")[0] + "ports = 3\n",
     r"\[structure\] ports: got 3"),
    ("ports-file-missing", _structure().split("[structure.ports]")[0] + 'ports = "p.csv"\n',
     r"\[structure\] ports: .*p.csv does not exist"),
    ("two-ports-one-dof", _structure(ports=_ports(**{"pad2.x": '{ node = 101, '
                                                     'direction = "x" }'})),
     r"are the same DOF"),
    ("coordinates-without-ports", '[axis]\nname = "a"\n\n[structure]\nmass = "M.mtx"\n'
     'stiffness = "K.mtx"\ndof_map = "dofs.csv"\ncoordinates = "nodes.csv"\n',
     r"\[structure\] coordinates: given without ports"),
    ("tolerance-unit-slip", _structure(extra="port_tolerance = 50.0"),
     r"\[structure\] port_tolerance: 50.0 is outside the plausible range"),
    ("unknown-structure-key", _structure(extra='node_map = "n.csv"'),
     r"\[structure\]: unknown keys \['node_map'\]"),
]


@pytest.mark.parametrize("name, text, message", BAD, ids=[b[0] for b in BAD])
def test_bad_port_settings_name_file_field_and_fix(tmp_path, name, text, message):
    folder = tmp_path / "ax"
    folder.mkdir()
    export_structure(folder)
    (folder / "axis.toml").write_text(text)
    with pytest.raises(AxisFormatError, match=message) as info:
        st.load_axis(folder)
    text = str(info.value)
    assert text.startswith(str(folder / "axis.toml") + ": [structure")
    assert "; " in text.split(": [structure", 1)[1]  # problem; fix


def test_ports_from_a_csv_file_are_the_same_as_from_the_table(tmp_path):
    write_axis(tmp_path / "table")
    folder = tmp_path / "csv"
    write_axis(folder)
    (folder / "ports.csv").write_text(
        "port,node,x,y,z,direction\npad1.x,101,,,,UX\npad2.x,105,,,,x\nencoder.x,120,,,,1\n"
        "wp.x,,0.0,0.0,0.8,x\nmotor.rotor,9001,,,,ROTX\nmotor.stator,9002,,,,rx\n")
    text = (folder / "axis.toml").read_text()
    start, end = text.index("[structure.ports]"), text.index("\n[friction]")
    (folder / "axis.toml").write_text(
        text[:start].replace('coordinates = "nodes.csv"',
                             'coordinates = "nodes.csv"\nports = "ports.csv"') + text[end:])
    a, b = st.load_axis(tmp_path / "table").structure, st.load_axis(folder).structure
    assert a.dofs == b.dofs
    np.testing.assert_array_equal(a.stiffness, b.stiffness)


# -- the tuner: "no better design" against "requirements infeasible" ------------------------------
def _not_converging(monkeypatch):
    """IPOPT that never reports convergence (its iterates unchanged), as at an iteration
    limit."""
    solve = Solver.solve

    def stalled(self, *args, **kwargs):
        sol = solve(self, *args, **kwargs)
        return dataclasses.replace(sol, stats={**sol.stats, "success": False,
                                               "return_status": "Maximum_Iterations_Exceeded"})

    monkeypatch.setattr(Solver, "solve", stalled)


def test_no_better_design_returns_the_initial_one_with_the_reason(monkeypatch):
    problem = TuningProblem(small_axis(), PADS, c=5e4, drive=small_drive(), free=("c",))
    _not_converging(monkeypatch)
    result = tune(problem, starts=2)
    assert result.design == result.initial and result.after is result.before
    # it is kept because it meets every requirement in the dense check
    assert result.success and result.checks and all(c.holds for c in result.checks)
    (note,) = result.notes
    assert "found no better design" in note and "Maximum_Iterations_Exceeded" in note


def test_requirements_the_initial_design_misses_are_infeasible(monkeypatch):
    from servotune.requirements import Requirements

    drive = small_drive()
    kp0 = drive.velocity_loop.kp
    problem = TuningProblem(small_axis(), PADS, c=5e4, drive=drive, free=("kp",),
                            requirements=Requirements(ms_velocity_max=1.01, ms_position_max=1.5),
                            bounds={"kp": (kp0, 2 * kp0)})
    _not_converging(monkeypatch)
    with pytest.raises(RequirementsNotMetError, match="requirements not met") as info:
        tune(problem, starts=1)
    assert "'Ms velocity loop'" in str(info.value)
    assert "the initial design does not meet the requirements" in str(info.value)
    # the optimiser stopped at its iteration limit: that shows no infeasibility, and it says so
    assert "without showing that no such design exists" in str(info.value)
    assert "infeasible" not in str(info.value)


def test_requirements_ipopt_finds_locally_infeasible_are_called_so(monkeypatch):
    from servotune.requirements import Requirements

    drive = small_drive()
    kp0 = drive.velocity_loop.kp
    problem = TuningProblem(small_axis(), PADS, c=5e4, drive=drive, free=("kp",),
                            requirements=Requirements(ms_velocity_max=1.01, ms_position_max=1.5),
                            bounds={"kp": (kp0, 2 * kp0)})
    solve = Solver.solve

    def infeasible(self, *args, **kwargs):
        sol = solve(self, *args, **kwargs)
        return dataclasses.replace(sol, stats={**sol.stats, "success": False,
                                               "return_status": "Infeasible_Problem_Detected"})

    monkeypatch.setattr(Solver, "solve", infeasible)
    with pytest.raises(RequirementsNotMetError, match="requirements infeasible within the "
                       "bounds") as info:
        tune(problem, starts=1)
    assert "'Ms velocity loop'" in str(info.value)


def test_tune_prints_the_reason_when_it_keeps_the_initial_design(tmp_path, capsys,
                                                                  monkeypatch):
    write_axis(tmp_path / "ax", kv=10.0)
    _not_converging(monkeypatch)
    code = main(["tune", str(tmp_path / "ax"), "--no-simulation", "--no-plots", "--starts", "1",
                 "--workers", "1", "--out", str(tmp_path / "out")])
    text = capsys.readouterr().out
    written = json.loads((tmp_path / "out" / "tune_exported_axis" / "results.json").read_text())
    # the initial design meets the requirements: it is kept, with the reason printed
    assert code == 3 and written["success"], written["reasons"]
    assert "note: the optimiser found no better design" in text
    assert any("found no better design" in n for n in written["notes"])
    assert written["design"] == written["initial_design"]


def test_check_of_an_exported_axis_compares_the_reduction_with_the_full_export(tmp_path,
                                                                             capsys):
    # `check AXIS` reads the full matrices with their ports named (as the axis does) and
    # compares the reduced model with them: with modes up to 1 kHz the 5-300 Hz band passes
    from servotune.cli import main

    write_axis(tmp_path / "ax", reduce="f_max_hz = 1000.0")
    assert main(["check", str(tmp_path / "ax"), "--json", "--out", str(tmp_path / "o")]) == 0
    out = json.loads(capsys.readouterr().out)
    check = out["reduction_check"]
    assert check["passed"] is True and check["n_missing_modes"] == 0
    assert check["max_frequency_error"] < check["frequency_tolerance"]


def test_a_model_that_does_not_cover_the_band_verifies_nothing(tmp_path, capsys):
    """One fixed-interface mode kept, far below the band's top: whatever the simulations find,
    the verdict is NOT VERIFIED with the coverage named (the claims rest on a model that
    leaves out the modes of the band)."""
    write_axis(tmp_path / "ax", reduce="n_modes = 1")
    code = main(["tune", str(tmp_path / "ax"), "--json", "--no-plots", "--starts", "1",
                 "--workers", "1", "--out", str(tmp_path / "out")])
    out = json.loads(capsys.readouterr().out)
    assert code == 1 and out["verified"] is False
    assert any("does not cover the band" in r for r in out["verdict"]["reasons"])
