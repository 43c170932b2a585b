"""The reduction check (reduced against full model) and the band coverage, both ways: on the
symmetric star (repeated eigenvalues, closed form) and on a beam frame, with the full model's
compliance checked against a direct dense solution."""

import math
import sys

import numpy as np
import pytest
import scipy.sparse as sp
from numpy.testing import assert_allclose
from structure_star import arm_frequencies, star

import servotune.structure.reduction as reduction
from servotune.structure import (
    ModalModel,
    craig_bampton,
    lowest_modes,
    mode_coverage,
    reduction_check,
)

TWO_PI = 2 * math.pi
BAND = (TWO_PI * 5.0, TWO_PI * 60.0)  # the star's 10, 30 and 50 Hz arm modes lie in it
check_module = sys.modules["servotune.structure.reduction_check"]


@pytest.fixture(scope="module")
def star_model():
    return star()


def reduce_star(mass, stiffness, dofs, **kwargs):
    return craig_bampton(mass, stiffness, [0], boundary_names=["hub.x"], **kwargs)


def test_reduced_star_keeps_every_copy_and_passes(star_model):
    mass, stiffness, dofs = star_model
    model = reduce_star(mass, stiffness, dofs, f_max_hz=100.0)
    info = model.reduction
    # closed form: every fixed-interface mode below 100 Hz, 8 copies each of 10 ... 90 Hz
    assert_allclose(np.array(info.fixed_interface_hz),
                    np.repeat(arm_frequencies(count=5), 8) / TWO_PI, rtol=1e-10)
    assert info.complete_below_hz >= 100.0
    check = reduction_check(mass, stiffness, [0], model, BAND)
    assert check.passed, check.failures
    assert check.coverage.covered and check.n_missing_modes == 0
    # 7 of every 8 arm combinations leave the hub still: they keep the arm frequencies exactly
    for f in arm_frequencies(count=3) / TWO_PI:
        assert np.sum(np.isclose(check.full_frequencies_hz, f, rtol=1e-9)) == 7
    assert check.max_frequency_error < 1e-3  # the in-phase modes, approximated from above
    assert "result: passed" in str(check)


def test_reduction_check_catches_lost_copies(star_model, monkeypatch):
    mass, stiffness, dofs = star_model

    def old_solver(k, m, **kwargs):  # the former behaviour: all-ones start, no check
        kwargs.update(v0=np.ones(k.shape[0]), verify="none")
        return lowest_modes(k, m, **kwargs)

    monkeypatch.setattr(reduction, "lowest_modes", old_solver)
    old = reduce_star(mass, stiffness, dofs, n_modes=40)
    monkeypatch.undo()
    # the old model misses copies: fewer fixed-interface modes at 10 Hz than the 8 arms
    f = np.array(old.reduction.fixed_interface_hz)
    assert np.sum(np.isclose(f, arm_frequencies(count=1)[0] / TWO_PI, rtol=1e-8)) < 8
    check = reduction_check(mass, stiffness, [0], old, BAND)
    assert not check.passed
    assert check.max_frequency_error > 0.5  # the reduced modes come out far too high
    assert any("off by more than 1 %" in msg for msg in check.failures)
    # and the same reduction as shipped keeps them all and passes
    new = reduce_star(mass, stiffness, dofs, n_modes=40)
    assert reduction_check(mass, stiffness, [0], new, BAND).passed


def frame(n_elements=12):
    from servotune.structure import StructureBuilder

    b = StructureBuilder()
    for name, p in {"base": (0, 0, 0), "top": (0, 0, 1.2), "tip": (0.8, 0, 1.2)}.items():
        b.add_node(name, p)
    section = dict(e=2.1e11, area=2e-3, iy=4e-7, iz=6e-7, torsion=6e-7, rho=7850.0,
                   n_elements=n_elements)
    b.add_beam("base", "top", **section)
    b.add_beam("top", "tip", **section)
    b.add_mass("tip", 40.0, (0.5, 0.5, 0.5))
    for c in ("x", "y", "z", "rx", "ry", "rz"):  # clamped base, as stiff springs
        b.add_spring({f"base.{c}": 1.0}, 1e12)
    return b


@pytest.fixture(scope="module")
def frame_model():
    b = frame()
    mass, stiffness, dofs = b.assemble()
    ports = ["tip.x", "tip.y", "tip.z"]
    return mass, stiffness, dofs, [dofs.index(p) for p in ports], ports, b


def test_full_model_reference_compliance_is_the_direct_solution(frame_model):
    mass, stiffness, _dofs, boundary, _ports, _ = frame_model
    hi = TWO_PI * 200.0
    lam, pb, rem, _ = check_module._full_reference(stiffness.tocsc(), mass.tocsc(),
                                                   np.array(boundary), hi, 2.0, -1.0, "auto")
    omega = np.geomspace(TWO_PI * 5, hi, 60)
    eta = 0.06
    got = check_module._driving_points(lam, pb, eta, omega, rem, -1.0)
    k, m = stiffness.toarray(), mass.toarray()
    direct = np.array([np.abs(np.diag(np.linalg.inv(k * (1 + 1j * eta) - w * w * m)
                                      [np.ix_(boundary, boundary)])) for w in omega])
    assert_allclose(got, direct, rtol=2e-3)  # series remainder: r^4/(1-r) of the remainder


def test_compliance_and_coverage_fail_with_too_few_modes_and_pass_with_enough(frame_model):
    mass, stiffness, _dofs, boundary, ports, b = frame_model
    band = (TWO_PI * 5.0, TWO_PI * 200.0)
    few = craig_bampton(mass, stiffness, boundary, n_modes=1, boundary_names=ports)
    bad = reduction_check(mass, stiffness, boundary, few, band, coordinates=b.nodes)
    assert not bad.passed and not bad.coverage.covered
    assert bad.max_compliance_error > 0.05 or bad.n_missing_modes > 0
    assert "5-200 Hz" in bad.coverage.message and "f_max_hz = 300" in bad.coverage.message
    enough = craig_bampton(mass, stiffness, boundary, f_max_hz=800.0, boundary_names=ports)
    good = reduction_check(mass, stiffness, boundary, enough, band, coordinates=b.nodes)
    assert good.passed, good.failures
    assert good.max_compliance_error < 0.05 and good.max_frequency_error < 0.01
    assert good.directions == ("X", "Y", "Z", "RX", "RY", "RZ")
    # the JSON form holds only finite numbers or None
    d = good.to_dict()
    assert d["passed"] is True and d["band_coverage"]["covered"] is True


def test_mode_coverage_both_ways():
    def model(f_hz):
        w2 = (TWO_PI * np.asarray(f_hz)) ** 2
        n = 1 + len(w2)
        k = np.diag(np.r_[1e6, w2])
        return ModalModel(np.eye(n), k, ["wp.x"] + [f"mode.{j + 1}" for j in range(len(w2))])

    band = (TWO_PI * 5.0, TWO_PI * 300.0)
    short = mode_coverage(model([16.0, 120.0, 310.0]), band)
    assert not short.covered and short.reached_hz == pytest.approx(310.0)
    for text in ("5-300 Hz", "310 Hz", "450 Hz", "f_max_hz = 450"):
        assert text in short.message
    assert mode_coverage(model([16.0, 120.0, 460.0]), band).covered
    assert mode_coverage(model([16.0, 120.0, 460.0]), band, margin=2.0).covered is False
    # a model without modal DOFs is not a reduced one: nothing was left out
    plain = mode_coverage(ModalModel([[1.0]], [[1e6]], ["wp.x"]), band)
    assert plain.covered and not plain.reduced


def test_reduction_information_survives_locking_and_added_elements(star_model):
    mass, stiffness, dofs = star_model
    model = reduce_star(mass, stiffness, dofs, n_modes=8)
    assert model.locked(["mode.8"]).reduction == model.reduction
    assert model.with_added(damping={"hub.x": 10.0}).reduction == model.reduction
    assert model.with_damping(0.05).reduction == model.reduction
    # counts: 8 kept out of the 1600 interior modes; the next one is known
    assert model.reduction.next_hz == pytest.approx(arm_frequencies(count=2)[1] / TWO_PI,
                                                    rel=1e-9)


def test_reduced_model_must_match_the_boundary(star_model):
    mass, stiffness, dofs = star_model
    model = reduce_star(mass, stiffness, dofs, n_modes=8)
    with pytest.raises(ValueError, match="boundary"):
        reduction_check(mass, stiffness, [0, 1], model, BAND)
    with pytest.raises(ValueError, match="band"):
        reduction_check(mass, stiffness, [0], model, (10.0, 5.0))
    bad = sp.eye_array(3)
    with pytest.raises(ValueError, match="square and alike"):
        reduction_check(bad, stiffness, [0], model, BAND)
