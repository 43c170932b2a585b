"""The starter axis of ``servotune init``: it loads with load_axis and gives the values its
comments document, its structure against the closed forms of its springs and masses."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from servotune.axis import load_axis
from servotune.report import OutputExistsError
from servotune.template import axis_name_for, template_structure, template_toml, write_template

LEAD = 10e-3  # [m], the template's direct-drive ball screw
RATIO = LEAD / (2 * math.pi)


@pytest.fixture(scope="module")
def axis(tmp_path_factory):
    folder = tmp_path_factory.mktemp("starter")
    files = write_template(folder, name="starter")
    assert [f.name for f in files] == ["axis.toml", "structure.npz"]
    return load_axis(folder)


def test_the_documented_structure(axis):
    s = axis.structure
    assert s.dofs == ("motor.rotor", "motor.stator", "pad1.x", "pad2.x", "encoder.x", "wp.x")
    # masses of the docstring: rotor 0.012 and stator 0.03 kg m^2, slide 800 kg in two halves,
    # encoder head 2 kg, work piece 300 kg
    assert_allclose(np.diag(s.mass), [0.012, 0.03, 400.0, 400.0, 2.0, 300.0], rtol=0)
    assert_allclose(s.damping_ratio, 0.03, rtol=0)  # modal_damping = 0.03


def test_the_structure_is_the_springs_in_series(axis):
    # rotor held: the work piece hangs on screw (3e8), slide body (2e9) and table (1.5e8) in
    # series; its static compliance is the sum of theirs (K^-1 of the held model)
    held = axis.structure.locked(["motor.rotor"])
    i = int(held.index("wp.x"))
    compliance = np.linalg.inv(held.stiffness)[i, i]
    assert_allclose(compliance, 1 / 3e8 + 1 / 2e9 + 1 / 1.5e8, rtol=1e-10)
    # the stator on its bracket: one mode at sqrt(2e5 / 0.03) with the rest held
    stator = axis.structure.locked([d for d in axis.structure.dofs if d != "motor.stator"])
    assert_allclose(stator.natural_frequencies(), [math.sqrt(2e5 / 0.03)], rtol=1e-12)
    # free: one rigid-body mode, the axis travel, rotor angle = slide travel / r
    model = axis.structure
    assert model.natural_frequencies()[0] == 0.0
    travel = model.mode_shapes()[:, 0]
    assert_allclose(travel[model.index("motor.rotor")] * RATIO, travel[model.index("wp.x")],
                    rtol=1e-9)


def test_the_documented_drive_friction_cutting_and_requirements(axis):
    d = axis.drive
    assert (d.motor.torque_constant, d.motor.back_emf_constant) == (1.2, 1.2)
    assert (d.motor.resistance, d.motor.inductance) == (0.4, 3.0e-3)
    assert (d.limits.torque_peak, d.limits.torque_continuous) == (36.0, 12.0)
    assert_allclose(d.limits.speed_max, 3000.0 * 2 * math.pi / 60.0, rtol=1e-12)  # 3000 rpm
    assert_allclose(d.ratio, RATIO, rtol=1e-15)
    assert (d.current_loop.kp, d.current_loop.ti) == (15.0, 2.0e-3)
    assert (d.velocity_loop.kp, d.velocity_loop.ti) == (3.7, 12.0e-3)
    assert_allclose(d.kv, 1000.0 / 60.0, rtol=1e-12)  # Kv = 1 (m/min)/mm
    assert d.feedback == "linear" and d.encoder == "encoder.x"
    s = d.sampling
    assert (s.current_period, s.velocity_period, s.position_period) == (125e-6, 125e-6, 1e-3)
    f = axis.friction
    assert f.pads == ("pad1.x", "pad2.x") and f.viscous == 5578.0
    lugre = f.lugre
    assert (lugre.fc, lugre.fs, lugre.vs, lugre.delta) == (2198.0, 6013.0, 0.01, 1.0)
    assert (lugre.sigma0, lugre.sigma1, lugre.sigma2) == (5.9e9, 1.6e7, 5578.0)
    c = axis.cutting
    assert (c.setup.teeth, c.setup.kt, c.setup.kn) == (4, 2.0e9, 0.6e9)
    assert (c.setup.radial_immersion, c.setup.milling, c.direction) == (0.5, "down", "x")
    assert c.speed_rpm == (3000.0, 12000.0)
    r = axis.requirements
    assert (r.ms_velocity_max, r.ms_position_max, r.depth_required) == (2.0, 1.5, 2.0e-3)
    assert_allclose(r.band, (2 * math.pi * 5.0, 2 * math.pi * 300.0), rtol=1e-15)
    assert axis.tuning.free == ("c", "kv", "kp", "ti", "notch")
    assert dict(axis.tuning.bounds) == {"kv": (1.0, 300.0), "ti": (1.0e-3, 0.2)}


def test_the_defaults_the_comments_promise(axis):
    op = axis.operation
    # rapid speed from speed_max_rpm and the transmission: 3000 rpm x 10 mm = 0.5 m/s
    assert_allclose(op.rapid_speed, 3000.0 / 60.0 * LEAD, rtol=1e-12)
    # feed speeds from [cutting]: f_z N n / 60 at both ends of the speed range
    assert_allclose(op.feed_speeds, [1e-4 * 4 * n / 60.0 for n in (3000.0, 12000.0)],
                    rtol=1e-12)
    assert op.acceleration == 2.0


def test_template_structure_is_symmetric_and_positive_semidefinite():
    m, k, dofs = template_structure()
    assert len(dofs) == m.shape[0] == k.shape[0] == 6
    assert_allclose(k, k.T, rtol=0, atol=0)
    eig = np.linalg.eigvalsh(k)
    assert eig[0] > -1e-6 * eig[-1] and abs(eig[0]) < 1e-6 * eig[-1]  # one rigid-body mode


def test_write_template_refuses_to_overwrite_and_writes_nothing_then(tmp_path):
    write_template(tmp_path, name="first")
    before = (tmp_path / "axis.toml").read_text()
    (tmp_path / "structure.npz").unlink()
    with pytest.raises(OutputExistsError, match=r"axis\.toml exists"):
        write_template(tmp_path, name="second")
    assert not (tmp_path / "structure.npz").exists()  # nothing written
    assert (tmp_path / "axis.toml").read_text() == before
    write_template(tmp_path, force=True, name="second")
    assert load_axis(tmp_path).name == "second"


@pytest.mark.parametrize("name", ["x axis", "a/b", "", "ä"])
def test_template_toml_refuses_names_toml_or_folders_cannot_carry(name):
    with pytest.raises(ValueError, match=r"letters, digits and _ \. - only"):
        template_toml(name)


@pytest.mark.parametrize("folder, name", [("projects/X axis (rev 2)", "X_axis_rev_2"),
                                          ("mill-3.x", "mill-3.x"), ("__", "my_axis"),
                                          ("a  +  b", "a_b")])
def test_axis_name_for_keeps_letters_digits_and_separators(folder, name):
    assert axis_name_for(folder) == name
