"""More FE export formats: Nastran OUTPUT4 (through pyyeti's reader), Harwell-Boeing files as
scipy writes them, and ports named from node numbers and directions of an export."""

import json

import numpy as np
import pytest
import scipy.io
import scipy.linalg
import scipy.sparse as sp
from numpy.testing import assert_allclose

from servotune.structure import (
    MatrixFileError,
    Port,
    PortError,
    name_ports,
    read_coordinates,
    read_harwell_boeing,
    read_matrix,
    read_op4,
    read_ports,
    read_structure,
)


@pytest.fixture
def pair():
    rng = np.random.default_rng(3)
    a = sp.random_array((9, 9), density=0.3, rng=rng).toarray()
    mass = a @ a.T + 9 * np.eye(9)
    b = sp.random_array((9, 9), density=0.3, rng=rng).toarray() * 1e6
    stiffness = b + b.T + np.diag(np.full(9, 8e6))
    return mass, stiffness


# -- Nastran OUTPUT4 ---------------------------------------------------------------------------
def test_op4_written_by_hand_in_the_ascii_format(tmp_path):
    # the OUTPUT4 ASCII layout: a header (ncol, nrow, form, type, name, format), then per
    # column its number, the first row and the count of values, the values; a last record with
    # column ncol + 1 ends the matrix (form 6 = symmetric, type 2 = real double)
    text = "\n".join([
        "       2       2       6       2KAA     1P,3E23.16",
        "       1       1       2",
        " 4.0000000000000000E+00-1.5000000000000000E+00",
        "       2       1       2",
        "-1.5000000000000000E+00 3.0000000000000000E+00",
        "       3       1       1",
        " 0.0000000000000000E+00",
    ]) + "\n"
    (tmp_path / "k.op4").write_text(text)
    assert_allclose(read_matrix(tmp_path / "k.op4", "KAA").toarray(), [[4, -1.5], [-1.5, 3]])


@pytest.mark.parametrize("binary", [False, True])
@pytest.mark.parametrize("sparse", [False, True])
def test_op4_round_trip_with_both_matrices_in_one_file(tmp_path, pair, binary, sparse):
    op4 = pytest.importorskip("pyyeti.nastran.op4")
    mass, stiffness = pair
    matrices = [sp.csr_array(mass), sp.csr_array(stiffness)] if sparse else [mass, stiffness]
    op4.write(str(tmp_path / "fe.op4"), ["MGG", "KGG"], matrices, binary=binary)
    data = read_structure(tmp_path / "fe.op4")
    assert_allclose(data.mass.toarray(), mass, rtol=1e-15)
    assert_allclose(data.stiffness.toarray(), stiffness, rtol=1e-15)
    assert sorted(read_op4(tmp_path / "fe.op4")) == ["kgg", "mgg"]


def test_bad_op4_files_are_clear_errors(tmp_path, pair):
    (tmp_path / "bad.op4").write_text("this is not an op4 file\n")
    with pytest.raises(MatrixFileError, match="Nastran OUTPUT4"):
        read_matrix(tmp_path / "bad.op4")
    op4 = pytest.importorskip("pyyeti.nastran.op4")
    op4.write(str(tmp_path / "only.op4"), ["PHG"], [pair[0]], binary=False)
    with pytest.raises(MatrixFileError, match=r"holds \['PHG'\]"):
        read_structure(tmp_path / "only.op4")


# -- Harwell-Boeing as scipy writes it ---------------------------------------------------------
@pytest.mark.parametrize("n", [30, 147, 1074])
def test_harwell_boeing_written_by_scipy_with_negative_values(tmp_path, n):
    # scipy's hb_write declares E25.16 but writes 24-character fields: with negative values the
    # fields do not line up with the declared widths
    rng = np.random.default_rng(n)
    a = sp.random_array((n, n), density=min(1.0, 8.0 / n), rng=rng)
    a = (-(a + a.T) - 1e3 * sp.eye_array(n)).tocsc()
    scipy.io.hb_write(tmp_path / "k.rua", a)
    header = (tmp_path / "k.rua").read_text().splitlines()[3]
    assert "E25.16" in header
    assert_allclose(read_harwell_boeing(tmp_path / "k.rua").toarray(), a.toarray(), rtol=0,
                    atol=0)


# -- ports named from node numbers and directions ------------------------------------------------
DOFS = ["101.ux", "101.uy", "101.uz", "205.ux", "205.uy", "205.uz", "205.rotx", "9001.rotx"]


def test_ports_by_node_number_and_direction_spellings():
    ports = [Port("wp.x", "UX", node=205), Port("pad1.x", "1", node="101"),
             Port("motor.rotor", "rotx", node="9001.0")]
    names = name_ports(DOFS, ports)
    assert names == ("pad1.x", "101.uy", "101.uz", "wp.x", "205.uy", "205.uz", "205.rotx",
                     "motor.rotor")


def test_ports_by_position_take_the_nearest_node_within_tolerance():
    coords = {"101": (0.2, 0.15, 0.0), "205": (0.8, 0.5, 0.25), "9001": (0.0, 0.0, 0.3)}
    names = name_ports(DOFS, [Port("wp.x", "x", position=(0.8005, 0.5, 0.25))], coords,
                       tolerance=1e-3)
    assert names[3] == "wp.x"
    with pytest.raises(PortError, match=r"nearest node .* is 205 at 0.01 m, farther than"):
        name_ports(DOFS, [Port("wp.x", "x", position=(0.81, 0.5, 0.25))], coords)
    with pytest.raises(PortError, match="give the node coordinates"):
        name_ports(DOFS, [Port("wp.x", "x", position=(0.8, 0.5, 0.25))])


@pytest.mark.parametrize("ports, message", [
    ([Port("wp.x", "x", node=999)], r"node 999 is not in the DOF map .* 101, 205, 9001"),
    ([Port("wp.x", "rz", node=205)], r"node 205 has no rz DOF .* ux, uy, uz, rotx"),
    ([Port("a.x", "x", node=205), Port("b.x", "ux", node=205)], "are the same DOF"),
    ([Port("a.x", "x", node=205), Port("a.x", "y", node=205)], "given twice"),
    ([Port("101.uy", "x", node=205)], "also names of other DOFs"),
])
def test_bad_ports_are_clear_errors(ports, message):
    with pytest.raises(PortError, match=message):
        name_ports(DOFS, ports)


@pytest.mark.parametrize("kwargs, message", [
    ({"name": "", "direction": "x", "node": 1}, "needs a name"),
    ({"name": "mode.1", "direction": "x", "node": 1}, "reserved"),
    ({"name": "p", "direction": "sideways", "node": 1}, "unknown direction"),
    ({"name": "p", "direction": "x"}, "either a node"),
    ({"name": "p", "direction": "x", "position": (0, 0, float("nan"))}, "3 finite"),
])
def test_bad_port_definitions(kwargs, message):
    with pytest.raises(PortError, match=message):
        Port(**kwargs)


def test_read_structure_names_ports_from_files(tmp_path, pair):
    mass, stiffness = pair
    scipy.io.mmwrite(tmp_path / "M.mtx", sp.coo_array(mass))
    scipy.io.mmwrite(tmp_path / "K.mtx", sp.coo_array(stiffness))
    nodes = [11, 11, 11, 12, 12, 12, 13, 13, 13]
    labels = ["UX", "UY", "UZ"] * 3
    (tmp_path / "dofs.csv").write_text(
        "index,node,dof\n" + "".join(f"{i + 1},{n},{d}\n"
                                     for i, (n, d) in enumerate(zip(nodes, labels, strict=True))))
    (tmp_path / "nodes.csv").write_text("node,x,y,z\n11,0,0,0\n12,1,0,0\n13,1,1,0.5\n")
    (tmp_path / "ports.csv").write_text("port,node,x,y,z,direction\n"
                                        "pad1.x,11,,,,UX\n"
                                        "wp.x,,1.0,1.0,0.5,UX\n"
                                        "wp.z,13,,,,UZ\n")
    data = read_structure(tmp_path / "M.mtx", tmp_path / "K.mtx", tmp_path / "dofs.csv",
                          ports=tmp_path / "ports.csv", coordinates=tmp_path / "nodes.csv")
    assert data.dofs[0] == "pad1.x" and data.dofs[6] == "wp.x" and data.dofs[8] == "wp.z"
    assert data.dofs[1] == "11.uy"
    assert_allclose(data.index(["wp.x"]), [6])
    assert set(read_coordinates(tmp_path / "nodes.csv")) == {"11", "12", "13"}
    (tmp_path / "bad.csv").write_text("port,node,direction\nwp.x,77,UX\n")
    with pytest.raises(MatrixFileError, match="node 77 is not in the DOF map"):
        read_structure(tmp_path / "M.mtx", tmp_path / "K.mtx", tmp_path / "dofs.csv",
                       ports=tmp_path / "bad.csv")


def test_ports_file_format_errors(tmp_path):
    (tmp_path / "p.csv").write_text("name,where\nwp.x,205\n")
    with pytest.raises(PortError, match="needs the columns port, direction and node"):
        read_ports(tmp_path / "p.csv")
    (tmp_path / "q.csv").write_text("port,node,x,y,z,direction\nwp.x,,a,b,c,x\n")
    with pytest.raises(PortError, match=r"line 2: port 'wp\.x' has neither"):
        read_ports(tmp_path / "q.csv")


def test_op4_matrices_by_their_names(tmp_path, pair, capsys):
    """Nastran's modal-space names (MHH/KHH) are read by default; other names are given in
    axis.toml ([structure] mass_name / stiffness_name) or to servotune check
    (--mass-name / --stiffness-name); a missing name says how to give it."""
    op4 = pytest.importorskip("pyyeti.nastran.op4")
    mass, stiffness = pair
    op4.write(str(tmp_path / "h.op4"), ["MHH", "KHH"], [mass, stiffness], binary=False)
    data = read_structure(tmp_path / "h.op4")
    assert_allclose(data.stiffness.toarray(), stiffness, rtol=1e-15)
    op4.write(str(tmp_path / "x.op4"), ["MXX", "KXX"], [mass, stiffness], binary=False)
    with pytest.raises(MatrixFileError, match=r"holds \['KXX', 'MXX'\].*--mass-name"):
        read_structure(tmp_path / "x.op4")
    data = read_structure(tmp_path / "x.op4", mass_name="MXX", stiffness_name="KXX")
    assert_allclose(data.mass.toarray(), mass, rtol=1e-15)
    from servotune.cli import main

    assert main(["check", str(tmp_path / "x.op4"), "--mass-name", "MXX", "--stiffness-name",
                 "KXX", "--json", "--out", str(tmp_path / "out")]) in (0, 1)
    out = json.loads(capsys.readouterr().out)
    w2 = scipy.linalg.eigh(stiffness, mass, eigvals_only=True)
    f_ref = np.sqrt(np.clip(w2, 0.0, None)) / (2 * np.pi)
    f_ref = f_ref[f_ref > 1e-6 * f_ref.max()]
    assert_allclose(np.sort(out["free_free_frequencies_hz"])[-len(f_ref):], f_ref, rtol=1e-8)
