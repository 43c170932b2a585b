"""Axis descriptions: loading the bundled models, the FE-matrix path with reduction, and
errors that name file, field and fix."""

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp
from numpy.testing import assert_allclose

from servotune.axis import Axis, AxisFormatError, load_axis

MODELS = Path(__file__).resolve().parents[1] / "models"


def test_two_mass_axis_is_the_papers_fig5_system():
    axis = load_axis(MODELS / "two_mass_fig5")
    assert isinstance(axis, Axis) and axis.name == "two_mass_fig5"
    s = axis.structure
    assert s.dofs == ("pad1.x", "wp.x")
    m1, m2, k = 5000.0, 1500.0, 16e6
    # free: a rigid-body mode and sqrt(K (M1 + M2) / (M1 M2)); slide held: sqrt(K / M2)
    assert_allclose(s.natural_frequencies(), [0.0, math.sqrt(k * (m1 + m2) / (m1 * m2))],
                    atol=1e-9)
    locked = axis.configuration(pads="locked")
    assert_allclose(locked.natural_frequencies(), [math.sqrt(k / m2)])
    assert_allclose(s.damping, 0.0, atol=0)  # the only damping is the guide-way C
    assert axis.friction["viscous"] == 4.912e5 and axis.pads == ("pad1.x",)


def test_paper_axis_tables_are_read_only():
    axis = load_axis(MODELS / "paper_x_axis" / "axis.toml")
    assert axis.path == (MODELS / "paper_x_axis").resolve()
    assert axis.structure.n == 41
    assert axis.friction["pads"] == ("pad1.x", "pad2.x", "pad3.x", "pad4.x")
    assert axis.drive["motor"]["rotor"] == "motor.rotor"
    with pytest.raises(TypeError):
        axis.drive["motor"]["torque_constant"] = 3.0
    with pytest.raises(TypeError):
        axis.requirements["band_hz"] = (1.0, 2.0)
    assert axis.motor_rotor == "motor.rotor"


def write_fe_axis(folder, extra=""):
    """A 20-mass chain in MatrixMarket files with a DOF map, reduced on loading."""
    n, k, m = 20, 1e7, 10.0
    main = np.full(n, 2 * k)
    main[-1] = k
    stiffness = sp.diags_array([main, -k * np.ones(n - 1), -k * np.ones(n - 1)], offsets=[0, 1, -1])
    scipy.io.mmwrite(folder / "M.mtx", sp.coo_array(sp.eye_array(n) * m), symmetry="symmetric")
    scipy.io.mmwrite(folder / "K.mtx", sp.coo_array(stiffness), symmetry="symmetric")
    names = [f"c{i}.x" for i in range(n - 1)] + ["wp.x"]
    (folder / "dofs.csv").write_text("name\n" + "\n".join(names) + "\n")
    (folder / "axis.toml").write_text(
        '[axis]\nname = "chain"\n\n[structure]\nmass = "M.mtx"\nstiffness = "K.mtx"\n'
        'dof_map = "dofs.csv"\nmodal_damping = 0.02\n'
        'reduce = { boundary = ["wp.x", "c0.x"], n_modes = 6 }\n' + extra)
    return n, k, m


def test_fe_matrices_are_reduced_on_loading(tmp_path):
    n, k, m = write_fe_axis(tmp_path, '\n[friction]\npads = ["c0.x"]\nviscous = 100.0\n')
    axis = load_axis(tmp_path)
    s = axis.structure
    assert s.dofs[:3] == ("wp.x", "c0.x", "mode.1") and s.n == 8
    # the grounded chain: the lowest frequency converges to the closed form from above
    exact = 2 * math.sqrt(k / m) * math.sin(math.pi / (2 * (2 * n + 1)))
    w1 = s.natural_frequencies()[0]
    assert exact <= w1 < exact * 1.001
    assert_allclose(s.modal_damping_ratios(), 0.02, rtol=1e-9)
    assert axis.cutting == {} and axis.friction["viscous"] == 100.0


@pytest.mark.parametrize("toml, message", [
    ('[axis]\nname = "x"\n', r"\[structure\]: missing"),
    ('[structure]\nfile = "s.npz"\n', r"\[axis\]: missing"),
    ('[axis]\nname = "x"\n[structure]\nfile = "nope.npz"\n', "nope.npz does not exist"),
    ('[axis]\nname = "x"\n[structure]\nfiles = "s.npz"\n', r"unknown keys \['files'\]"),
    ('[axis]\nname = "x"\n[structure]\nfile = "s.npz"\n[spindle]\nrpm = 1\n',
     r"unknown \['spindle'\]"),
    ('[axis]\nname = "x"\n[structure]\n', "no matrices are named"),
    ('[axis]\nname = "x"\n[structure]\nfile = "s.npz"\n[friction]\npads = ["pad9.x"]\n',
     r"\[friction\] pads: unknown DOF 'pad9.x'"),
    ('[axis]\nname = "x"\n[structure]\nfile = "s.npz"\nmodal_damping = "3%"\n',
     "modal_damping"),
    ('[axis]\nname = "x"\n[structure]\nfile = "s.npz"\n[drive]\nencoder = "linear"\n',
     "encoder.x"),
    ("[axis\n", "not valid TOML"),
])
def test_errors_name_file_field_and_fix(tmp_path, toml, message):
    np.savez(tmp_path / "s.npz", mass=np.eye(2), stiffness=np.diag([1e6, 1e6]),
             dofs=np.array(["pad1.x", "wp.x"]))
    (tmp_path / "axis.toml").write_text(toml)
    with pytest.raises(AxisFormatError, match=message) as info:
        load_axis(tmp_path)
    assert "axis.toml" in str(info.value)


def test_missing_folder_and_bad_reduce_boundary(tmp_path):
    with pytest.raises(AxisFormatError, match="no axis description here"):
        load_axis(tmp_path / "nothing")
    write_fe_axis(tmp_path)
    text = (tmp_path / "axis.toml").read_text().replace('"c0.x"]', '"c99.x"]')
    (tmp_path / "axis.toml").write_text(text)
    with pytest.raises(AxisFormatError, match=r"reduce.boundary.*c99.x"):
        load_axis(tmp_path)


def test_configuration_needs_pads_and_valid_words(tmp_path):
    write_fe_axis(tmp_path)
    axis = load_axis(tmp_path)
    with pytest.raises(AxisFormatError, match=r"\[friction\] pads is missing"):
        axis.configuration(pads="locked")
    with pytest.raises(ValueError, match="'locked' or 'free'"):
        axis.configuration(pads="stuck")
    with pytest.raises(AxisFormatError, match=r"\[drive.motor\] rotor is missing"):
        axis.configuration(motor="locked")
