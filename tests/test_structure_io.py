"""Matrix files: every reader round-trips, every bad file gives its clear error; the check
command."""

import json

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp
from numpy.testing import assert_allclose

from servotune.cli import main
from servotune.structure import (
    MatrixFileError,
    UnknownDofError,
    read_dof_map,
    read_harwell_boeing,
    read_matrix,
    read_structure,
    write_npz,
)


@pytest.fixture
def pair():
    """A random sparse SPD mass and SPD stiffness of 7 DOFs, and their names."""
    rng = np.random.default_rng(42)
    a = sp.random_array((7, 7), density=0.4, rng=rng).toarray()
    mass = a @ a.T + 7 * np.eye(7)
    b = sp.random_array((7, 7), density=0.3, rng=rng).toarray() * 1e6
    stiffness = b + b.T + np.diag(np.full(7, 5e6))
    return mass, stiffness, [f"n{i}.x" for i in range(7)]


def write_hb_symmetric(path, a, fmt_val="(3D24.16)", per_line=3, width=24, digits=16):
    """A Harwell-Boeing RSA file (lower triangle by columns), written as the format says:
    fixed-width Fortran fields, as Ansys HBMAT writes them."""
    low = sp.tril(sp.csc_array(a)).tocsc()
    low.sort_indices()
    ptr, ind, val = low.indptr + 1, low.indices + 1, low.data

    def lines(values, per, w, fmt):
        out = []
        for i in range(0, len(values), per):
            out.append("".join(fmt(v).rjust(w) for v in values[i:i + per]))
        return out

    p_lines = lines(ptr, 10, 8, str)
    i_lines = lines(ind, 10, 8, str)
    v_lines = lines(val, per_line, width, lambda v: f"{v:.{digits}E}".replace("E", "D"))
    total = len(p_lines) + len(i_lines) + len(v_lines)
    header = [
        f"{'stiffness (symmetric storage)':<72}{'KEY':<8}",
        f"{total:14d}{len(p_lines):14d}{len(i_lines):14d}{len(v_lines):14d}{0:14d}",
        f"{'RSA':<14}{a.shape[0]:14d}{a.shape[1]:14d}{low.nnz:14d}{0:14d}",
        f"{'(10I8)':<16}{'(10I8)':<16}{fmt_val:<20}{'':<20}",
    ]
    path.write_text("\n".join(header + p_lines + i_lines + v_lines) + "\n")


# -- round trips --------------------------------------------------------------------------------
def test_npz_round_trip_dense_and_sparse(tmp_path, pair):
    mass, stiffness, dofs = pair
    write_npz(tmp_path / "a.npz", mass, sp.csr_array(stiffness), dofs)
    data = read_structure(tmp_path / "a.npz")
    assert_allclose(data.mass.toarray(), mass, rtol=0, atol=0)
    assert_allclose(data.stiffness.toarray(), stiffness, rtol=0, atol=0)
    assert data.dofs == tuple(dofs)
    with pytest.raises(FileExistsError, match="force"):
        write_npz(tmp_path / "a.npz", mass, stiffness, dofs)


def test_npz_written_by_scipy_save_npz(tmp_path, pair):
    mass, stiffness, _ = pair
    sp.save_npz(tmp_path / "m.npz", sp.csr_matrix(mass))
    sp.save_npz(tmp_path / "k.npz", sp.csr_matrix(stiffness))
    data = read_structure(tmp_path / "m.npz", tmp_path / "k.npz")
    assert_allclose(data.stiffness.toarray(), stiffness)
    assert data.dofs[0] == "dof.1"


@pytest.mark.parametrize("symmetry", ["general", "symmetric"])
def test_matrix_market_round_trip(tmp_path, pair, symmetry):
    mass, stiffness, _ = pair
    scipy.io.mmwrite(tmp_path / "m.mtx", sp.coo_array(mass), symmetry=symmetry)
    scipy.io.mmwrite(tmp_path / "k.mtx", sp.coo_array(stiffness), symmetry=symmetry)
    (tmp_path / "k.mtx").rename(tmp_path / "k.mmf")  # the suffix of Ansys *EXPORT,...,MMF
    data = read_structure(tmp_path / "m.mtx", tmp_path / "k.mmf")
    assert_allclose(data.mass.toarray(), mass, rtol=1e-15)
    assert_allclose(data.stiffness.toarray(), stiffness, rtol=1e-15)


def test_matrix_market_symmetric_storage_as_ansys_writes_it(tmp_path):
    # one triangle in coordinate form: the reader must fill in the other one
    (tmp_path / "k.mtx").write_text(
        "%%MatrixMarket matrix coordinate real symmetric\n% exported\n3 3 5\n"
        "1 1 4.0\n2 1 -1.0\n2 2 4.0\n3 2 -2.5e+00\n3 3 5.0\n")
    assert_allclose(read_matrix(tmp_path / "k.mtx").toarray(),
                    [[4, -1, 0], [-1, 4, -2.5], [0, -2.5, 5]])


def test_harwell_boeing_symmetric_round_trip(tmp_path, pair):
    mass, stiffness, _ = pair
    write_hb_symmetric(tmp_path / "m.hb", mass)
    write_hb_symmetric(tmp_path / "k.rsa", stiffness, fmt_val="(1P,4E20.12)", per_line=4,
                       width=20, digits=12)
    data = read_structure(tmp_path / "m.hb", tmp_path / "k.rsa")
    assert_allclose(data.mass.toarray(), mass, rtol=1e-15)
    assert_allclose(data.stiffness.toarray(), stiffness, rtol=1e-11)  # 12 digits written


def test_harwell_boeing_fields_without_spaces(tmp_path):
    # fixed-width fields that touch each other: only the Fortran widths separate them
    text = "\n".join([
        f"{'tight':<72}{'K':<8}",
        f"{4:14d}{1:14d}{1:14d}{1:14d}{0:14d}",
        f"{'RSA':<14}{2:14d}{2:14d}{3:14d}{0:14d}",
        f"{'(3I2)':<16}{'(3I2)':<16}{'(3E10.3)':<20}",
        " 1 3 4",
        " 1 2 2",
        "-1.000E+01-2.500E+00 3.000E+01",
    ]) + "\n"
    (tmp_path / "t.hb").write_text(text)
    assert_allclose(read_harwell_boeing(tmp_path / "t.hb").toarray(), [[-10, -2.5], [-2.5, 30]])


def test_harwell_boeing_unsymmetric_written_by_scipy(tmp_path, pair):
    _, stiffness, _ = pair
    scipy.io.hb_write(tmp_path / "k.rua", sp.csc_array(stiffness))
    assert_allclose(read_matrix(tmp_path / "k.rua").toarray(), stiffness, rtol=1e-15)


@pytest.mark.parametrize("names", [("M", "K"), ("mass", "stiffness")])
def test_matlab_round_trip_sparse_and_dense(tmp_path, pair, names):
    mass, stiffness, _ = pair
    scipy.io.savemat(tmp_path / "fe.mat", {names[0]: sp.csc_array(mass), names[1]: stiffness})
    data = read_structure(tmp_path / "fe.mat")
    assert_allclose(data.mass.toarray(), mass)
    assert_allclose(data.stiffness.toarray(), stiffness)


@pytest.mark.parametrize("text, expected", [
    ("name\nslide.x\nwp.x\n", ("slide.x", "wp.x")),
    ("node,dof\n12,UX\n12,ROTZ\n", ("12.ux", "12.rotz")),
    ("index,name\n2,b\n1,a\n", ("a", "b")),  # ordered by the 1-based equation number
])
def test_dof_maps(tmp_path, text, expected):
    (tmp_path / "dofs.csv").write_text(text)
    assert read_dof_map(tmp_path / "dofs.csv") == expected


def test_dof_map_names_the_rows(tmp_path, pair):
    mass, stiffness, dofs = pair
    scipy.io.mmwrite(tmp_path / "m.mtx", sp.coo_array(mass))
    scipy.io.mmwrite(tmp_path / "k.mtx", sp.coo_array(stiffness))
    (tmp_path / "dofs.csv").write_text("name\n" + "\n".join(dofs) + "\n")
    data = read_structure(tmp_path / "m.mtx", tmp_path / "k.mtx", tmp_path / "dofs.csv")
    assert_allclose(data.index(["n3.x", "n0.x"]), [3, 0])
    with pytest.raises(UnknownDofError, match=r"unknown DOF names \['wp\.x'\]"):
        data.index(["wp.x"])
    model = data.to_modal_model(damping_ratio=0.0)
    assert model.dofs == tuple(dofs)


# -- bad files -----------------------------------------------------------------------------------
def test_non_square_matrix(tmp_path):
    scipy.io.mmwrite(tmp_path / "m.mtx", sp.coo_array(np.ones((3, 2))))
    scipy.io.mmwrite(tmp_path / "k.mtx", sp.coo_array(np.eye(3)))
    with pytest.raises(MatrixFileError, match=r"m\.mtx: the mass matrix is not square"):
        read_structure(tmp_path / "m.mtx", tmp_path / "k.mtx")


def test_mismatched_sizes(tmp_path):
    scipy.io.mmwrite(tmp_path / "m.mtx", sp.coo_array(np.eye(3)))
    scipy.io.mmwrite(tmp_path / "k.mtx", sp.coo_array(np.eye(4)))
    with pytest.raises(MatrixFileError, match="mass is 3x3 but stiffness is 4x4"):
        read_structure(tmp_path / "m.mtx", tmp_path / "k.mtx")


def test_asymmetry_beyond_tolerance(tmp_path, pair):
    mass, stiffness, _ = pair
    stiffness = stiffness.copy()
    stiffness[0, 1] += 1e-3 * np.abs(stiffness).max()
    scipy.io.mmwrite(tmp_path / "m.mtx", sp.coo_array(mass))
    scipy.io.mmwrite(tmp_path / "k.mtx", sp.coo_array(stiffness))
    with pytest.raises(MatrixFileError, match=r"k\.mtx: the stiffness matrix is not symmetric"):
        read_structure(tmp_path / "m.mtx", tmp_path / "k.mtx")
    # within a looser tolerance it is accepted and symmetrised
    data = read_structure(tmp_path / "m.mtx", tmp_path / "k.mtx", symmetry_tolerance=1e-2)
    assert_allclose(data.stiffness.toarray(), data.stiffness.toarray().T)


@pytest.mark.parametrize("n", [5, 3500])  # dense eigenvalues, and sparse LDL^T inertia
def test_indefinite_mass(tmp_path, n):
    diag = np.ones(n)
    diag[n // 2] = -1e-3
    sp.save_npz(tmp_path / "m.npz", sp.diags_array(diag).tocsr())
    sp.save_npz(tmp_path / "k.npz", sp.eye_array(n).tocsr())
    with pytest.raises(MatrixFileError, match="mass matrix is indefinite"):
        read_structure(tmp_path / "m.npz", tmp_path / "k.npz")


def test_semidefinite_lumped_mass_is_accepted(tmp_path):
    # lumped mass without rotary inertia: zero rows are not an error
    sp.save_npz(tmp_path / "m.npz", sp.diags_array([1.0, 0.0, 2.0, 0.0]).tocsr())
    sp.save_npz(tmp_path / "k.npz", sp.eye_array(4).tocsr())
    assert read_structure(tmp_path / "m.npz", tmp_path / "k.npz").n == 4


def test_dof_map_of_the_wrong_length(tmp_path, pair):
    mass, stiffness, _ = pair
    write_npz(tmp_path / "a.npz", mass, stiffness, [f"d{i}" for i in range(7)])
    (tmp_path / "dofs.csv").write_text("name\na\nb\n")
    with pytest.raises(MatrixFileError, match="names 2 DOFs but the matrices have 7"):
        read_structure(tmp_path / "a.npz", dof_map=tmp_path / "dofs.csv")


@pytest.mark.parametrize("name, content, message", [
    ("m.mtx", "this is not a matrix\n", "not a readable MatrixMarket file"),
    ("m.npz", "garbage", "not an .npz archive"),
    ("m.mat", "garbage", "cannot read as a MATLAB file"),
    ("m.hb", "too short\n", "not a Harwell-Boeing file"),
    ("m.xyz", "1 2 3", "unknown matrix file type"),
])
def test_unreadable_files(tmp_path, name, content, message):
    (tmp_path / name).write_text(content)
    with pytest.raises(MatrixFileError, match=message):
        read_matrix(tmp_path / name)


def test_missing_file_and_missing_variable(tmp_path, pair):
    with pytest.raises(MatrixFileError, match="no such file"):
        read_matrix(tmp_path / "nothing.mtx")
    scipy.io.savemat(tmp_path / "fe.mat", {"A": pair[0]})
    with pytest.raises(MatrixFileError, match="none of the variables"):
        read_structure(tmp_path / "fe.mat")
    with pytest.raises(MatrixFileError, match="give the stiffness file too"):
        scipy.io.mmwrite(tmp_path / "m.mtx", sp.coo_array(pair[0]))
        read_structure(tmp_path / "m.mtx")


def test_truncated_and_unsupported_harwell_boeing(tmp_path, pair):
    write_hb_symmetric(tmp_path / "k.hb", pair[1])
    lines = (tmp_path / "k.hb").read_text().splitlines()
    (tmp_path / "cut.hb").write_text("\n".join(lines[:-2]) + "\n")
    with pytest.raises(MatrixFileError, match="truncated"):
        read_matrix(tmp_path / "cut.hb")
    lines[2] = "CSA" + lines[2][3:]
    (tmp_path / "complex.hb").write_text("\n".join(lines) + "\n")
    with pytest.raises(MatrixFileError, match="'CSA' is not supported"):
        read_matrix(tmp_path / "complex.hb")


@pytest.mark.parametrize("text, message", [
    ("", "empty"), ("label\na\n", "needs a 'name' column"), ("name\na\na\n", "duplicate"),
    ("index,name\n1,a\n3,b\n", "number the rows"),
])
def test_bad_dof_maps(tmp_path, text, message):
    (tmp_path / "dofs.csv").write_text(text)
    with pytest.raises(MatrixFileError, match=message):
        read_dof_map(tmp_path / "dofs.csv")


# -- the check command ---------------------------------------------------------------------
def chain_files(tmp_path, n=30):
    k = 1e6
    main_diag = np.full(n, 2 * k)
    main_diag[-1] = k
    off = -k * np.ones(n - 1)
    stiffness = sp.diags_array([main_diag, off, off], offsets=[0, 1, -1])
    scipy.io.mmwrite(tmp_path / "m.mtx", sp.coo_array(sp.eye_array(n) * 2.0), symmetry="symmetric")
    scipy.io.mmwrite(tmp_path / "k.mtx", sp.coo_array(stiffness), symmetry="symmetric")
    (tmp_path / "dofs.csv").write_text("name\n" + "\n".join(f"m{i}.x" for i in range(n)) + "\n")
    return n, k


def test_check_command_reduces_and_reports(tmp_path, capsys):
    n, k = chain_files(tmp_path)
    argv = ["check", str(tmp_path / "m.mtx"), str(tmp_path / "k.mtx"), "--dof-map",
            str(tmp_path / "dofs.csv"), "--boundary", f"m{n - 1}.x", "--n-modes", "4"]
    # 4 fixed-interface modes reach 46.8 Hz (the 5th is at 58.4 Hz): not enough for the default
    # band 5-300 Hz, enough for 1-30 Hz with the margin 1.5 (45 Hz)
    assert main([*argv, "--json"]) == 1
    assert json.loads(capsys.readouterr().out)["band_coverage"]["covered"] is False
    argv += ["--band-hz", "1", "30"]
    assert main([*argv, "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    # fixed-interface modes: the chain held at both ends, f_j = sqrt(k/m) sin(j pi/(2n)) / pi
    j = np.arange(1, 5)
    assert_allclose(result["fixed_base_frequencies_hz"],
                    np.sqrt(k / 2.0) * np.sin(j * np.pi / (2 * n)) / np.pi, rtol=1e-9)
    assert result["n_boundary"] == 1 and result["passed"]
    assert main(argv) == 0
    assert "fixed [Hz]" in capsys.readouterr().out


def test_check_command_on_an_axis_and_on_bad_files(tmp_path, capsys):
    assert main(["check", "models/paper_x_axis"]) == 0
    assert "10 boundary DOFs, 31 modes" in capsys.readouterr().out
    (tmp_path / "m.mtx").write_text("nonsense\n")
    assert main(["check", str(tmp_path / "m.mtx"), str(tmp_path / "m.mtx")]) == 1
    assert "not a readable MatrixMarket file" in capsys.readouterr().err
    chain_files(tmp_path)
    assert main(["check", str(tmp_path / "m.mtx"), str(tmp_path / "k.mtx"), "--dof-map",
                 str(tmp_path / "dofs.csv"), "--boundary", "wp.x"]) == 1
    assert "unknown DOF names ['wp.x']" in capsys.readouterr().err
