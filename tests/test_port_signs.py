"""A sign on a port's direction: ``-UX`` names the negative of the export's DOF.

References: D M D and D K D with D = diag(+-1) built by hand (q_export = D q); the eigenvalues
of a congruence with an orthogonal D are those of the original; end to end, an export with one
DOF reversed (``export_structure(flip=...)`` of ``test_exported_axis``) read with that port's
direction given with a minus sign is the unreversed export, and its transmission checks "ok".
"""

import dataclasses
import json

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp
from test_exported_axis import ENCODER, RATIO, ROTOR, write_axis

import servotune as st
from servotune.axis import AxisFormatError, structure_matrices
from servotune.cli import main
from servotune.model_checks import axis_model_checks
from servotune.structure import (
    MatrixFileError,
    Port,
    PortError,
    apply_signs,
    name_ports,
    port_signs,
    read_structure,
    signed_direction,
    write_npz,
)

DOFS = ("7.ux", "7.uy", "9.rotx", "120.ux", "mode.1")
COORDS = {"7": (0.0, 0.0, 0.0), "9": (-0.8, 0.0, 0.06), "120": (0.0, 0.25, 0.05)}


def spd(n, seed):
    """A seeded symmetric positive definite matrix with off-diagonal coupling everywhere."""
    a = np.random.default_rng(seed).standard_normal((n, n))
    return a @ a.T + n * np.eye(n)


# -- spelling ------------------------------------------------------------------------------------
@pytest.mark.parametrize("text, sign, direction", [
    ("-x", -1, "x"), ("-UX", -1, "x"), ("-ROTX", -1, "rx"), ("-1", -1, "x"), (-4, -1, "rx"),
    ("+x", 1, "x"), ("UX", 1, "x"), (" -uy ", -1, "y"), ("-T3", -1, "z"),
])
def test_a_direction_may_carry_a_sign(text, sign, direction):
    assert signed_direction(text) == (sign, direction)
    port = Port("p.x", text, node=7)
    assert (port.sign, port.direction) == (sign, direction)


def test_a_port_keeps_its_sign_when_varied_and_by_its_field():
    port = Port("encoder.x", "-UX", node=120)
    assert (port.direction, port.sign, port.node) == ("x", -1, "120")
    assert dataclasses.replace(port, node=121).sign == -1  # the stored direction has no sign
    assert Port("encoder.x", "x", node=120, sign=-1).sign == -1
    assert Port("encoder.x", "-x", node=120, sign=-1).sign == 1  # the signs multiply
    assert Port("encoder.x", "UX", node=120).sign == 1  # existing constructions unchanged


@pytest.mark.parametrize("text", ["--x", "-foo", "-", "+-x", "-mode", "x-"])
def test_a_sign_on_what_is_not_a_direction_is_refused_naming_the_port(text):
    with pytest.raises(PortError, match=r"port 'encoder.x': unknown direction .*use x, y, z, "
                                        r"rx, ry, rz .*-UX, -ROTX, -1"):
        Port("encoder.x", text, node=120)


@pytest.mark.parametrize("sign", [0, 2, -2, True, "-"])
def test_a_sign_field_other_than_plus_or_minus_one_is_refused(sign):
    with pytest.raises(PortError, match=r"port 'encoder.x': sign .*give \+1 or -1"):
        Port("encoder.x", "x", node=120, sign=sign)


# -- signs per row, congruence -------------------------------------------------------------------
def test_port_signs_are_minus_one_on_the_rows_of_signed_ports_only():
    ports = [Port("wp.x", "x", node=7), Port("motor.rotor", "-ROTX", node=9),
             Port("encoder.x", "-1", position=(0.0, 0.25, 0.0505))]  # nearest node: 120
    assert port_signs(DOFS, ports, COORDS).tolist() == [1.0, 1.0, -1.0, -1.0, 1.0]
    # the names are as without the signs
    assert name_ports(DOFS, ports, COORDS) == ("wp.x", "7.uy", "motor.rotor", "encoder.x",
                                               "mode.1")


@pytest.mark.parametrize("kind", ["dense", "csr_array", "csc_matrix", "coo_array"])
def test_apply_signs_is_d_m_d_and_keeps_a_sparse_matrix_sparse(kind):
    m = spd(5, 1)
    m[0, 4] = m[4, 0] = 0.0  # a structural zero stays one
    signs = [1, 1, -1, -1, 1]
    d = np.diag([1.0, 1.0, -1.0, -1.0, 1.0])  # by hand
    given = {"dense": m, "csr_array": sp.csr_array(m), "csc_matrix": sp.csc_matrix(m),
             "coo_array": sp.coo_array(m)}[kind]
    out = apply_signs(given, signs)
    if kind == "dense":
        assert isinstance(out, np.ndarray)
        np.testing.assert_array_equal(out, d @ m @ d)  # times +-1: exact
    else:
        assert sp.issparse(out) and out.format == given.format and type(out) is type(given)
        assert out.nnz == given.nnz
        np.testing.assert_array_equal(out.toarray(), d @ m @ d)
    np.testing.assert_array_equal(given if kind == "dense" else given.toarray(), m)  # no copy
    assert apply_signs(given, np.ones(5)) is given  # nothing reversed: the same matrix


@pytest.mark.parametrize("signs", [[1, -1], [1, 0, -1, 1, 1], [[1] * 5]])
def test_apply_signs_refuses_signs_that_do_not_fit(signs):
    with pytest.raises(ValueError, match="signs"):
        apply_signs(np.eye(5), signs)


def _npz(tmp_path, dense):
    m, k = spd(len(DOFS), 2), spd(len(DOFS), 3) * 1e6
    path = write_npz(tmp_path / "s.npz", m if dense else sp.csr_array(m),
                     k if dense else sp.csr_array(k), DOFS)
    return path, m, k


@pytest.mark.parametrize("dense", [True, False], ids=["dense", "sparse"])
def test_read_structure_with_signed_ports_gives_d_m_d_and_d_k_d(tmp_path, dense):
    path, m, k = _npz(tmp_path, dense)
    plain = [Port("wp.x", "x", node=7), Port("motor.rotor", "ROTX", node=9),
             Port("encoder.x", "UX", node=120)]
    signed = [Port("wp.x", "x", node=7), Port("motor.rotor", "-ROTX", node=9),
              Port("encoder.x", "-UX", node=120)]
    a = read_structure(path, ports=plain)
    b = read_structure(path, ports=signed)
    assert a.dofs == b.dofs == ("wp.x", "7.uy", "motor.rotor", "encoder.x", "mode.1")
    d = np.diag([1.0, 1.0, -1.0, -1.0, 1.0])
    for name, reference in (("mass", m), ("stiffness", k)):
        got = getattr(b, name)
        assert sp.issparse(got)
        np.testing.assert_array_equal(got.toarray(), d @ getattr(a, name).toarray() @ d)
        np.testing.assert_array_equal(getattr(a, name).toarray(), reference)
    # (b) a congruence with an orthogonal D: the same eigenvalues, M still positive definite
    w_a = scipy.linalg.eigh(a.stiffness.toarray(), a.mass.toarray(), eigvals_only=True)
    w_b = scipy.linalg.eigh(b.stiffness.toarray(), b.mass.toarray(), eigvals_only=True)
    np.testing.assert_allclose(w_b, w_a, rtol=1e-12)
    np.testing.assert_allclose(np.linalg.eigvalsh(b.mass.toarray()),
                               np.linalg.eigvalsh(a.mass.toarray()), rtol=1e-12)


def test_read_structure_with_a_signed_ports_csv_and_a_bad_one(tmp_path):
    path, m, _ = _npz(tmp_path, dense=False)
    ports = tmp_path / "ports.csv"
    ports.write_text("port,node,direction\nencoder.x,120,-1\n")
    data = read_structure(path, ports=ports)
    assert data.mass[3, 3] == m[3, 3] and data.mass[3, 0] == -m[3, 0]
    ports.write_text("port,node,direction\nencoder.x,120,--x\n")
    with pytest.raises(MatrixFileError, match=r"ports.csv.*port 'encoder.x': unknown direction "
                                              r"'--x'.*-UX"):
        read_structure(path, ports=ports)


# -- an exported axis end to end -----------------------------------------------------------------
ENCODER_LINE = f'"encoder.x" = {{ node = {ENCODER}, direction = "1" }}'
ROTOR_LINE = f'"motor.rotor" = {{ node = {ROTOR}, direction = "ROTX" }}'


def _edit(folder, old, new):
    toml = folder / "axis.toml"
    text = toml.read_text()
    assert text.count(old) == 1
    toml.write_text(text.replace(old, new))


def _ports_csv(folder, encoder_direction):
    """The axis' ports moved to ports.csv (as tests/test_exported_axis.py's CSV test does)."""
    (folder / "ports.csv").write_text(
        "port,node,x,y,z,direction\npad1.x,101,,,,UX\npad2.x,105,,,,x\n"
        f"encoder.x,{ENCODER},,,,{encoder_direction}\nwp.x,,0.0,0.0,0.8,x\n"
        f"motor.rotor,{ROTOR},,,,ROTX\nmotor.stator,9002,,,,rx\n")
    text = (folder / "axis.toml").read_text()
    start, end = text.index("[structure.ports]"), text.index("\n[friction]")
    (folder / "axis.toml").write_text(
        text[:start].replace('coordinates = "nodes.csv"',
                             'coordinates = "nodes.csv"\nports = "ports.csv"') + text[end:])


CASES = {
    "encoder-table": (ENCODER, lambda f: _edit(f, ENCODER_LINE, ENCODER_LINE.replace(
        '"1"', '"-UX"'))),
    "rotor-table": (ROTOR, lambda f: _edit(f, ROTOR_LINE, ROTOR_LINE.replace('"ROTX"',
                                                                             '"-ROTX"'))),
    "encoder-csv": (ENCODER, lambda f: _ports_csv(f, "-1")),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_flipped_export_with_a_minus_sign_on_its_port_is_the_unflipped_export(tmp_path,
                                                                                   case):
    node, sign_it = CASES[case]
    write_axis(tmp_path / "reference")
    folder = tmp_path / "flipped"
    write_axis(folder, flip=node)
    # without the sign the check names the flip and the fix in axis.toml's own words
    checks = axis_model_checks(st.load_axis(folder))
    assert checks.transmission.status == "flipped"
    dof = checks.transmission.flipped
    assert f'[structure.ports] "{dof}" = {{ node = <node>, direction = "-' in checks.errors[0]
    assert f"{dof} is node {node}" in checks.errors[0]
    sign_it(folder)
    axis, reference = st.load_axis(folder), st.load_axis(tmp_path / "reference")
    checks = axis_model_checks(axis).require()
    assert checks.transmission.status == "ok"
    assert checks.transmission.structure_ratio == pytest.approx(
        axis_model_checks(reference).transmission.structure_ratio, rel=1e-12)
    assert checks.transmission.structure_ratio == pytest.approx(RATIO, rel=1e-6)
    # the matrices as read are the unflipped export's, exactly (two sign changes)
    a, b = structure_matrices(axis), structure_matrices(reference)
    assert a.dofs == b.dofs
    np.testing.assert_array_equal(a.mass.toarray(), b.mass.toarray())
    np.testing.assert_array_equal(a.stiffness.toarray(), b.stiffness.toarray())
    # ... and so the reduced structure: the static motion of every DOF with the motor turned
    held = ["pad1.x", "pad2.x", "motor.rotor", "motor.stator"]
    np.testing.assert_allclose(axis.structure.locked(held).stiffness,
                               reference.structure.locked(held).stiffness, rtol=1e-12,
                               atol=1e-12 * np.abs(reference.structure.stiffness).max())


@pytest.mark.parametrize("node, line", [(ENCODER, ENCODER_LINE), (ROTOR, ROTOR_LINE)])
def test_the_line_the_flipped_message_gives_is_the_fix(tmp_path, node, line):
    folder = tmp_path / "ax"
    write_axis(folder, flip=node)
    checks = axis_model_checks(st.load_axis(folder))
    dof = checks.transmission.flipped
    fix = dict(checks.port_fixes)[dof]
    assert f"in axis.toml write {fix}" in checks.errors[0]
    assert fix == line.replace('"1"', '"-1"').replace('"ROTX"', '"-ROTX"')
    _edit(folder, line, fix)  # the advice, verbatim
    assert axis_model_checks(st.load_axis(folder)).transmission.status == "ok"
    # and on the corrected axis with the export corrected too, it says to take the sign away
    write_axis(folder)
    _edit(folder, line, fix)
    checks = axis_model_checks(st.load_axis(folder))
    assert checks.transmission.status == "flipped"
    assert dict(checks.port_fixes)[dof] == line


def test_servotune_check_of_the_flipped_export_with_its_sign_passes(tmp_path, capsys):
    folder = tmp_path / "ax"
    write_axis(folder, flip=ENCODER)
    _edit(folder, ENCODER_LINE, ENCODER_LINE.replace('"1"', '"-1"'))
    assert main(["check", str(folder), "--json", "--out", str(tmp_path / "o")]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["transmission"]["status"] == "ok" and out["passed"] is True


@pytest.mark.parametrize("direction", ["--x", "-foo"])
def test_a_bad_signed_direction_in_axis_toml_names_file_port_and_spellings(tmp_path,
                                                                           direction):
    folder = tmp_path / "ax"
    write_axis(folder)
    _edit(folder, ENCODER_LINE, ENCODER_LINE.replace('"1"', f'"{direction}"'))
    with pytest.raises(AxisFormatError) as info:
        st.load_axis(folder)
    text = str(info.value)
    assert text.startswith(f'{folder / "axis.toml"}: [structure.ports] "encoder.x"')
    assert f"unknown direction '{direction}'" in text and 'direction = "-UX"' in text
