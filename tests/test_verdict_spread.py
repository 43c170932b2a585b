"""The nonlinear verdict over the friction spread (servotune.verdict, servotune.regimes)."""

from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from servotune.axis import AxisFormatError, axis_from_tables, load_axis
from servotune.friction.lugre import BIANCHI2014, BIANCHI2014_SPREAD
from servotune.regimes import FrictionSpread, friction_spread
from servotune.tuning import Design

MODELS = Path(__file__).resolve().parents[1] / "models"
#: The bundled axis' design as `servotune tune models/paper_x_axis --json` (4 starts) tunes it.
BUNDLED_DESIGN = Design(c=5578.0, kv=23.072682552939863, kp=4.640919453460411,
                        ti=0.026241089944609972)
#: The starter axis' design of tests/test_verdict_harmonic.py.
STARTER_DESIGN = Design(c=5578.0, kv=45.7, kp=3.03, ti=0.0105)


def starter_tables(tmp_path):
    from servotune.template import write_template

    if not (tmp_path / "axis.toml").exists():
        write_template(tmp_path)
    return tomllib.loads((tmp_path / "axis.toml").read_text())


# ------------------------------------------------------------------------- the spread's box
def test_the_box_has_every_combination_of_lows_and_highs():
    box = FrictionSpread.absolute(BIANCHI2014, BIANCHI2014_SPREAD)
    corners = box.corners()
    assert len(corners) == 8
    values = {(p.fs, p.sigma0, p.sigma1) for _, p in corners}
    expected = {(6013.0 + a * 258.0, 5.9e9 + b * 1.17e9, 1.6e7 + c * 1.3e6)
                for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)}
    assert len(values) == 8
    for got, want in zip(sorted(values), sorted(expected), strict=True):
        assert_allclose(got, want, rtol=1e-12)
    # the other parameters stay nominal
    assert all(p.fc == BIANCHI2014.fc and p.vs == BIANCHI2014.vs for _, p in corners)
    assert box.describe() == "fs +-258 N, sigma0 +-1.17e9 N/m, sigma1 +-1.3e6 N s/m"
    assert corners[0][0] == "fs -258 N, sigma0 -1.17e9 N/m, sigma1 -1.3e6 N s/m"


def test_a_relative_spread_and_a_corner_that_crosses_fc():
    box = FrictionSpread.relative(BIANCHI2014, {"fs": 0.7, "sigma0": 3.0})
    labels = dict(box.corners())
    low = labels["fs -70%, sigma0 / 3, fc lowered to fs"]
    assert low.fs == pytest.approx(0.3 * 6013.0) and low.fc == low.fs   # 1804 N < Fc 2198 N
    assert low.sigma0 == pytest.approx(5.9e9 / 3)
    assert labels["fs +70%, sigma0 x 3"].sigma0 == pytest.approx(3 * 5.9e9)
    d = box.to_dict()
    assert d["corners"] == 4 and d["parameters"]["sigma0"]["high"] == pytest.approx(1.77e10)


@pytest.mark.parametrize("variation", [{"sigma0": 6e9}, {"vs": 0.001}, {"fs": -1.0}])
def test_a_variation_outside_its_range_is_refused(variation):
    with pytest.raises(ValueError):
        FrictionSpread.absolute(BIANCHI2014, variation)


def test_the_tuning_spread_comes_before_the_identified_variation():
    assert friction_spread(BIANCHI2014) is None and friction_spread(None, {"fs": 0.1}) is None
    got = friction_spread(BIANCHI2014, {"sigma0": 3.0}, BIANCHI2014_SPREAD)
    assert list(got.deviations) == ["sigma0"] and got.source == "[tuning] friction_spread"
    assert friction_spread(BIANCHI2014, {}, BIANCHI2014_SPREAD).source == "[friction] variation"


# -------------------------------------------------------------------------- the axis file
def test_the_bundled_axis_states_the_papers_measured_variation():
    axis = load_axis(MODELS / "paper_x_axis")
    assert dict(axis.tuning.friction_variation) == dict(BIANCHI2014_SPREAD)
    line = [d for d in axis.defaults if "friction_spread" in d]
    assert line == ["[tuning] friction_spread absent: the identified variation of [friction], "
                    "fs +-258 N, sigma0 +-1.17e9 N/m, sigma1 +-1.3e6 N s/m: the nonlinear "
                    "verdict checks its 8 corners"]


def test_a_named_set_brings_its_variation_and_a_bad_one_is_refused(tmp_path):
    data = starter_tables(tmp_path)
    del data["friction"]["lugre"]                       # the named default, bianchi2014
    axis = axis_from_tables(data, tmp_path / "axis.toml")
    assert dict(axis.tuning.friction_variation) == dict(BIANCHI2014_SPREAD)
    assert any("named set bianchi2014" in d for d in axis.defaults)
    data["friction"]["variation"] = {"sigma0": 7e9}      # the low corner would be negative
    with pytest.raises(AxisFormatError, match=r"\[friction\] variation"):
        axis_from_tables(data, tmp_path / "axis.toml")
    # none given: the default says the verdict checks the nominal friction only
    plain = starter_tables(tmp_path)
    axis = axis_from_tables(plain, tmp_path / "axis.toml")
    assert not axis.tuning.friction_variation
    assert any("checks the nominal friction only" in d for d in axis.defaults)


# --------------------------------------------------- a corner that fails, the nominal holds
@pytest.fixture(scope="module")
def starter_with_a_stick_slip_corner(tmp_path_factory):
    # the starter axis with Fs known to +-3 kN: at Fs + 3 kN the Stribeck curve falls at
    # 20 mm/s by (Fs - Fc)/vs exp(-2) = 9.2e4 N s/m, 16 times the guide ways' viscous 5578
    from servotune.design import check_design
    from servotune.verdict import nonlinear_verdict

    folder = tmp_path_factory.mktemp("starter")
    data = starter_tables(folder)
    data["friction"]["variation"] = {"fs": 3000.0}
    axis = axis_from_tables(data, folder / "axis.toml")
    result = check_design(axis, STARTER_DESIGN, feed_speeds=[0.02])
    verdict = nonlinear_verdict(axis, result, forces=(268.0,), speeds=[0.02],
                                simulate_before=False)
    return axis, result, verdict


def test_a_corner_that_sticks_and_slips_fails_the_verdict_and_is_named(
        starter_with_a_stick_slip_corner):
    axis, result, verdict = starter_with_a_stick_slip_corner
    assert result.success and verdict.linear_holds
    assert not verdict.verified and verdict.headline.startswith("NOT VERIFIED")
    feeding = next(r for r in verdict.regimes if r.speed == 0.02)
    standing = next(r for r in verdict.regimes if r.speed == 0.0)
    assert standing.holds
    # the nominal friction holds the claim: no reason of the regime without a corner
    assert not [x for x in verdict.reasons if x.startswith(f"{feeding.name}: ")]
    corners = {c.label: c for c in feeding.corners}
    assert set(corners) == {"fs -3e3 N", "fs +3e3 N"}
    assert corners["fs -3e3 N"].holds
    bad = corners["fs +3e3 N"]
    assert not bad.holds and "stick-slip while feeding at 20 mm/s" in bad.reason
    assert any(x.startswith("feeding 20 mm/s, fs +3e3 N: stick-slip") for x in verdict.reasons)
    # the reference: the LuGre time simulation of that corner fed at 20 mm/s without force,
    # written out here; the slide stops in every cycle (its speed falls below a tenth of the
    # feed), while with the nominal friction it slides steadily
    from servotune.design import tuning_problem
    from servotune.simulate.scenario import constant_speed
    from servotune.simulate.simulator import simulate
    from servotune.verdict import design_axis

    problem = tuning_problem(axis)
    for fs, sticks in ((axis.friction.lugre.fs + 3000.0, True), (axis.friction.lugre.fs, False)):
        friction = dataclasses.replace(axis.friction.lugre, fs=fs)
        run = simulate(design_axis(axis, problem, STARTER_DESIGN, friction=friction),
                       constant_speed(0.02, 1.6))
        late = run.t > 1.1
        v = np.mean([run[f"v_{p.replace('.', '_')}"][late] for p in axis.pads], axis=0)
        assert bool(v.min() < 0.1 * 0.02) is sticks


def test_a_periodic_response_above_the_claim_at_a_corner_names_the_corner(tmp_path,
                                                                          monkeypatch):
    # harmonic balance the only witness at a corner: a peak above the claim there fails the
    # regime, in the words "<regime>, <corner>: harmonic balance peak ... above the claim"
    from servotune import verdict as v
    from servotune.design import check_design

    data = starter_tables(tmp_path)
    data["tuning"]["friction_spread"] = {"sigma0": 3.0}
    axis = axis_from_tables(data, tmp_path / "axis.toml")
    result = check_design(axis, STARTER_DESIGN)
    real = v.harmonic_scan
    stiff = 3.0 * axis.friction.lugre.sigma0

    def scan_high_at_the_stiff_corner(nl_axis, speed, forces_pp, band_hz):
        peaks = real(nl_axis, speed, forces_pp, band_hz)
        high = math.isclose(nl_axis.friction.params.sigma0, stiff, rel_tol=1e-9)
        return tuple(dataclasses.replace(p, peak=p.peak * (2.0 if high else 1.0))
                     for p in peaks)

    monkeypatch.setattr(v, "harmonic_scan", scan_high_at_the_stiff_corner)
    judged = v.nonlinear_verdict(axis, result, forces=(268.0,), speeds=[],
                                 simulate_before=False)
    (standing,) = judged.regimes
    assert not judged.verified and not standing.holds
    reason = next(x for x in judged.reasons if x.startswith("standing, sigma0 x 3: "))
    assert "harmonic balance peak" in reason and "above the claim" in reason
    assert {c.label: c.holds for c in standing.corners} == {"sigma0 / 3": True,
                                                            "sigma0 x 3": False}
    # the worst corner is the one simulated in time
    assert standing.worst_corner.label == "sigma0 x 3"
    assert standing.worst_corner.simulations


# ------------------------------------------------- the bundled axis at sigma0 x 3 and / 3
@pytest.fixture(scope="module")
def bundled_sigma0():
    from servotune.design import check_design
    from servotune.verdict import nonlinear_verdict

    axis = load_axis(MODELS / "paper_x_axis")
    result = check_design(axis, BUNDLED_DESIGN)
    box = FrictionSpread.relative(axis.friction.lugre, {"sigma0": 3.0})
    process = axis.operation.process_force_pp
    verdict = nonlinear_verdict(axis, result, forces=(process,), speeds=[],
                                simulate_before=False, spread=box)
    return axis, result, box, verdict


def test_the_linear_claim_at_each_corner_is_the_state_space_models_peak(bundled_sigma0):
    # the verdict closes each corner's contact over the drive's tabulated receptance; the
    # reference is python-control's closed loop (the state space of the sampled-data axis)
    from servotune import frequency
    from servotune.closed_loop import axis_compliance

    _, result, box, verdict = bundled_sigma0
    problem = result.problem
    drive = problem.drive_for(BUNDLED_DESIGN)
    omega = np.geomspace(*problem.requirements.band, 6001)
    (standing,) = verdict.regimes
    models = [m for m in problem.regimes if m.regime == "standing"]
    for corner in standing.corners:
        params = dict(box.corners())[corner.label]
        peaks = [frequency.peak(omega, axis_compliance(
            problem.structure, omega, drive,
            dataclasses.replace(m, friction=params).contact(BUNDLED_DESIGN.c),
            problem.pads)[0])[0] for m in models]
        assert corner.claimed_peak == pytest.approx(max(peaks), rel=1e-6)
    # the regime's claim is the worst over the nominal models and the corners
    assert standing.claimed_peak == pytest.approx(
        max([standing.claimed_peak_tuned] + [c.claimed_peak for c in standing.corners]))
    assert standing.claimed_peak_tuned == pytest.approx(result.after.peak_compliance)


def test_a_stepped_sine_at_sigma0_x_3_and_by_3_does_not_contradict_the_verdict(
        bundled_sigma0):
    # the reference: the LuGre time simulation at each corner's harmonic-balance resonance,
    # run to a steady fundamental (servotune.harmonic.stepped), written out here; it agrees
    # with the scanned peak within 1 % and, with the regime's claim, gives the same judgement
    from servotune.design import tuning_problem
    from servotune.harmonic.stepped import stepped_sine
    from servotune.simulate.setup import AxisSetup
    from servotune.verdict import design_axis

    axis, _, _, verdict = bundled_sigma0
    (standing,) = verdict.regimes
    problem = tuning_problem(axis)
    tol = axis.requirements.nonlinear_tolerance
    for corner in standing.corners:
        nl = design_axis(axis, problem, BUNDLED_DESIGN, friction=corner.friction)
        setup = AxisSetup("corner", nl.structure, nl.drive, tuple(nl.pads),
                          nl.friction.params, float(nl.friction.params.sigma2))
        peak = corner.harmonic_peak
        steady = stepped_sine(setup, peak.force_pp, [2 * math.pi * peak.resonance_hz])
        assert steady.compliance[0] == pytest.approx(peak.peak, rel=0.01), corner.label
        assert corner.holds == (steady.compliance[0] <= (1 + tol) * standing.claimed_peak)
    # sigma0 x 3 raises the standing peak well above the tuned claim (the nominal friction's):
    # the claim over the spread says so, and the verdict tells it
    stiff = next(c for c in standing.corners if c.label == "sigma0 x 3")
    assert stiff.claimed_peak > 1.3 * standing.claimed_peak_tuned
    assert "over the friction spread the claim is" in standing.explanation


def test_the_coverage_lists_what_was_run(bundled_sigma0):
    axis, _, _, verdict = bundled_sigma0
    process = axis.operation.process_force_pp
    cov = verdict.coverage
    assert cov["friction_spread"]["corners"] == 2
    assert cov["friction_spread"]["parameters"]["sigma0"]["low"] == pytest.approx(5.9e9 / 3)
    assert cov["forces_pp_n"] == [process] and cov["corner_forces_pp_n"] == [process]
    assert cov["force_multiples_of_process"] == [1.0, 1.0]
    assert cov["feeds_m_per_s"] == [] and cov["standing"] is True
    assert cov["regimes"] == ["standing"]
    (standing,) = verdict.regimes
    # every corner was scanned; the simulated corner is listed with its force
    assert all(c.harmonic for c in standing.corners)
    simulated = cov["simulated"]["standing"]
    assert simulated["nominal"] == [process]
    assert simulated["corners"] == {standing.worst_corner.label: [process]}
    assert verdict.coverage_text == ("over the friction spread (2 corners: sigma0 / 3 to x 3), "
                                     f"forces 1 x the process force ({process:.4g} N p-p), "
                                     "standing")
    assert verdict.coverage_text in verdict.headline
    assert verdict.to_dict()["coverage"] == cov
    # what is said checked and not checked is true of the run
    assert any(line.startswith("the friction spread") for line in verdict.checked)
    assert not any("the friction spread in the time simulation" in line
                   for line in verdict.not_checked)
    assert not any("only the peak torque" in line for line in verdict.not_checked)
