"""What the design job takes from a friction law (servotune.friction.law): the law with the
design's viscous damping, its steady sliding friction and slope (closed forms against the
interface's numeric fallback from the law's own periodic orbit), and the regime models, the
thrust budget and the verdict's nonlinear axis built from any law, not LuGre alone."""

import dataclasses
import math
from pathlib import Path

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from servotune.friction import LuGreParameters
from servotune.friction.law import FrictionLaw
from servotune.friction.laws.gms import BIANCHI2014_GMS, GMSFriction
from servotune.friction.laws.lugre import LuGreFriction
from servotune.friction.laws.viscous import ViscousFriction
from servotune.regimes import Operation, RegimeModel, as_law, regime_models
from servotune.thrust import ThrustBudget

LUGRE = LuGreParameters.named("bianchi2014")
GMS = GMSFriction(BIANCHI2014_GMS)


def stribeck(fc, fs, vs, delta, v):
    """The Stribeck curve written out here (Bianchi et al. 2014, Eq 3)."""
    return fc + (fs - fc) * math.exp(-((abs(v) / vs) ** delta))


@pytest.mark.parametrize("law", [LuGreFriction(LUGRE), GMS, ViscousFriction(5578.0)],
                         ids=["lugre", "gms", "viscous"])
def test_with_viscous_replaces_the_viscous_part_and_nothing_else(law):
    c = 12345.0
    other = law.with_viscous(c)
    assert type(other) is type(law)
    assert other.viscous_part == c
    k0, d0 = law.presliding()
    k1, d1 = other.presliding()
    assert k1 == k0
    assert d1 == pytest.approx(d0 - law.viscous_part + c, rel=1e-12)
    # the steady sliding friction moves by (c - old) v, nothing else
    v = 0.03
    assert other.steady_force(v) - law.steady_force(v) == pytest.approx(
        (c - law.viscous_part) * v, rel=1e-9)


@pytest.mark.parametrize("v", [0.002, 0.01, 0.04, -0.03])
def test_lugre_steady_friction_is_the_stribeck_curve(v):
    law = LuGreFriction(LUGRE)
    p = LUGRE
    expect = math.copysign(stribeck(p.fc, p.fs, p.vs, p.delta, v), v) + p.sigma2 * v
    assert law.steady_force(v) == pytest.approx(expect, rel=1e-12)
    h = 1e-7
    slope = (stribeck(p.fc, p.fs, p.vs, p.delta, abs(v) + h)
             - stribeck(p.fc, p.fs, p.vs, p.delta, abs(v) - h)) / (2 * h) + p.sigma2
    assert law.steady_slope(v) == pytest.approx(slope, rel=1e-6)


@pytest.mark.parametrize("v", [0.004, 0.01, 0.04])
def test_gms_steady_friction_closed_form_is_its_own_periodic_orbit(v):
    """The closed form (every element slipping at its share of the Stribeck curve) against the
    interface's fallback: the law's periodic orbit under a constant velocity."""
    numeric = FrictionLaw.steady_force(GMS, v)
    assert GMS.steady_force(v) == pytest.approx(numeric, rel=1e-4)
    p = BIANCHI2014_GMS
    assert GMS.steady_force(v) == pytest.approx(
        stribeck(p.fc, p.fs, p.vs, p.delta, v) + p.sigma2 * v, rel=1e-12)
    assert GMS.steady_slope(v) == pytest.approx(FrictionLaw.steady_slope(GMS, v), rel=2e-3)


def test_the_steady_friction_needs_a_moving_axis():
    with pytest.raises(ValueError, match="non-zero speed"):
        FrictionLaw.steady_force(GMS, 0.0)


def test_a_multi_state_sliding_impedance_is_the_frequency_response_of_the_law():
    """RegimeModel's impedance of GMS' four-state sliding linearisation against python-control's
    own frequency response of the same system (a second evaluation)."""
    model = RegimeModel("feeding 30 mm/s", "sliding", GMS, speed=0.03)
    omega = np.geomspace(10.0, 1e5, 40)
    base = GMS.with_viscous(0.0).sliding_system(0.03)
    g = np.array([complex(control.evalfr(base, 1j * w)) for w in omega])
    assert_allclose(model.impedance(omega), 1j * omega * g, rtol=1e-9)


def test_lugre_parameters_and_the_lugre_law_give_the_same_models():
    op = Operation(feed_speeds=(0.03,), rapid_speed=0.3, acceleration=2.0)
    by_params = regime_models(LUGRE, op, 1e-6, 2 * math.pi * 60.0)
    by_law = regime_models(LuGreFriction(LUGRE), op, 1e-6, 2 * math.pi * 60.0)
    assert by_params == by_law
    omega = np.geomspace(10.0, 1e4, 25)
    for a, b in zip(by_params, by_law, strict=True):
        assert isinstance(a.friction, LuGreFriction)
        assert_allclose(a.impedance(omega), b.impedance(omega), rtol=0)


def test_a_gms_axis_has_the_regime_models_of_its_own_law():
    op = Operation(feed_speeds=(0.03,), rapid_speed=0.3, acceleration=2.0)
    models = regime_models(GMS, op, 1e-6, 2 * math.pi * 60.0)
    assert [m.kind for m in models] == ["presliding", "describing", "sliding"]
    assert all(m.friction is GMS for m in models)
    presliding, describing, sliding = models
    # presliding: the sum of the element springs and dampers, with the design's C beside them
    contact = presliding.contact(1000.0)
    assert contact.stiffness == pytest.approx(sum(BIANCHI2014_GMS.stiffness))
    assert contact.damping == pytest.approx(sum(BIANCHI2014_GMS.damping) + 1000.0)
    # the describing function of the law without its viscous part
    ceq, keq = GMS.with_viscous(0.0).describing_function(1e-6, 2 * math.pi * 60.0)
    assert describing.to_dict()["ceq_without_c"] == pytest.approx(ceq)
    assert describing.to_dict()["keq"] == pytest.approx(keq)
    # sliding: the level is the Stribeck curve, the slope its derivative (no viscous part)
    p = BIANCHI2014_GMS
    assert sliding.to_dict()["friction_level_n"] == pytest.approx(
        stribeck(p.fc, p.fs, p.vs, p.delta, 0.03))
    assert sliding.slope() == pytest.approx(GMS.steady_slope(0.03) - p.sigma2)
    assert sliding.to_dict()["friction_law"] == "gms"


def test_a_spread_of_lugre_parameters_on_another_law_is_refused_naming_the_fix():
    op = Operation(feed_speeds=(0.03,))
    with pytest.raises(ValueError, match=r"'gms'.*friction_spread"):
        regime_models(GMS, op, spread={"fs": 0.1})


def test_the_thrust_budget_takes_the_law_s_own_sliding_friction():
    """A traverse at 0.2 m/s: the friction in the budget is the law's steady friction without
    its viscous part (GMS: the Stribeck curve), the viscous force is the design's C v."""
    op = Operation(feed_speeds=(), rapid_speed=0.2, acceleration=1.0)
    budget = ThrustBudget(4e4, 1.2e4, 0.2, 500.0, GMS, op)
    case = next(c for c in budget.cases(8000.0) if c.name == "rapid traverse")
    terms = dict(case.terms)
    p = BIANCHI2014_GMS
    assert terms["friction g(v)"] == pytest.approx(stribeck(p.fc, p.fs, p.vs, p.delta, 0.2))
    assert terms["viscous C v"] == pytest.approx(8000.0 * 0.2)
    # LuGre parameters are the LuGre law
    lugre = ThrustBudget(4e4, 1.2e4, 0.2, 500.0, LUGRE, op)
    assert isinstance(lugre.friction, LuGreFriction)
    assert lugre.c_max() == ThrustBudget(4e4, 1.2e4, 0.2, 500.0, LuGreFriction(LUGRE),
                                         op).c_max()


def test_as_law_refuses_what_is_not_friction():
    assert as_law(None) is None
    assert as_law(GMS) is GMS
    assert as_law(LUGRE) == LuGreFriction(LUGRE)
    with pytest.raises(ValueError, match="FrictionLaw or LuGreParameters"):
        as_law({"fc": 1.0})


def test_the_verdict_s_nonlinear_axis_carries_the_axis_law_with_the_design_c():
    """design_axis: the pads of the simulated axis have the axis' own law (GMS here), its
    viscous part the design's C -- not a LuGre stand-in."""
    from servotune.axis import load_axis
    from servotune.design import tuning_problem
    from servotune.friction.guideway import GuideWayFriction
    from servotune.verdict import design_axis

    base = load_axis(Path(__file__).resolve().parents[1] / "models" / "paper_x_axis")
    axis = dataclasses.replace(base, friction=GuideWayFriction(base.pads, law=GMS))
    problem = tuning_problem(axis)
    assert {m.friction.name for m in problem.regimes} == {"gms"}
    design = dataclasses.replace(problem.initial_design(), c=9000.0)
    nl = design_axis(axis, problem, design)
    assert isinstance(nl.friction, GMSFriction)
    assert nl.friction.viscous_part == 9000.0
    assert nl.friction.params.stiffness == BIANCHI2014_GMS.stiffness


@pytest.mark.parametrize("law", [LuGreFriction(LUGRE),
                                 LuGreFriction(dataclasses.replace(LUGRE,
                                                                   sigma1_decay_speed=None)),
                                 GMS, ViscousFriction(5578.0)],
                         ids=["lugre-decaying-sigma1", "lugre", "gms", "viscous"])
@pytest.mark.parametrize("v", [0.006, 0.03])
def test_the_sliding_linearisation_fallback_is_each_law_s_closed_form(law, v):
    """The interface's default sliding linearisation (the law's simulation model, its
    remainders' tangents at the steady state found by integration) against each law's closed
    form (LuGre: Canudas de Wit et al. 1995 linearised; GMS: every element slipping)."""
    closed = law.sliding_system(v)
    numeric = FrictionLaw.sliding_system(law, v)
    omega = np.geomspace(1.0, 1e6, 30)
    g_closed = np.array([complex(control.evalfr(closed, 1j * w)) for w in omega])
    g_numeric = np.array([complex(control.evalfr(numeric, 1j * w)) for w in omega])
    scale = np.abs(g_closed).max()
    assert_allclose(g_numeric, g_closed, rtol=1e-6, atol=1e-7 * scale)


def test_tune_designs_an_axis_with_another_law_and_its_verdict_takes_that_law(tmp_path, capsys):
    """servotune tune on the bundled axis with the viscous law in place of LuGre: the regime
    models, the thrust budget, the verdict's simulations and harmonic balance all take the
    axis' own law (named in the JSON), and the verdict says so; no LuGre stand-in."""
    import json
    import re
    import shutil

    from servotune.cli import main

    paper = Path(__file__).resolve().parents[1] / "models" / "paper_x_axis"
    folder = tmp_path / "axis"
    shutil.copytree(paper, folder)
    text = re.sub(r"variation = \{[^}]*\}[^\n]*\n(\s+#[^\n]*\n)*", "",
                  (folder / "axis.toml").read_text())
    text = re.sub(r"\nviscous = [^\n]*", "", text)      # [friction.viscous] is the law's table
    start, end = text.index("[friction.lugre]"), text.index("[drive]")
    (folder / "axis.toml").write_text(text[:start] + "[friction.viscous]\nc = 5578.0\n\n"
                                      + text[end:])
    code = main(["tune", str(folder), "--out", str(tmp_path / "out"), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code in (0, 1), out
    assert out["friction_law"] == "viscous"
    assert {m["friction_law"] for m in out["regime_models"]} == {"viscous"}
    verdict = out["verdict"]
    assert verdict["coverage"]["friction_law"] == "viscous"
    assert any("the viscous friction law at every pad" in line for line in verdict["checked"])
    # the viscous law's regime models: standing the pads are the damper C alone (no spring)
    standing = next(m for m in out["regime_models"] if m["model"] == "presliding")
    assert standing["regime"] == "standing"
    assert out["design"]["c"] >= 5578.0 - 1e-9      # the guide ways' own damping is the floor


class _Counted:
    """A law whose periodic force is counted (no exact Jacobian: harmonic balance takes
    finite differences)."""

    def __init__(self, law):
        self.law, self.calls = law, 0
        self.name = law.name

    def periodic_force(self, velocity, period, share=1.0):
        self.calls += 1
        return self.law.periodic_force(velocity, period, share)


def test_broyden_updates_find_the_same_periodic_response_with_fewer_law_evaluations():
    """Harmonic balance of the small axis with GMS pads: the friction Jacobian taken afresh by
    finite differences at every point (secant_updates = 0) and carried on by Broyden updates
    give the same curve -- the solutions are those of the residual -- for far fewer
    evaluations of the law."""
    from axis_fixtures import PADS, small_axis, small_drive

    from servotune.harmonic import HarmonicSettings, nonlinear_compliance
    from servotune.simulate.setup import AxisSetup

    gms = GMS.with_viscous(2000.0)
    setup = AxisSetup("small", small_axis(), small_drive(velocity_feedforward=1.0),
                      tuple(PADS), None, 2000.0, law=gms)
    band = (2 * math.pi * 30.0, 2 * math.pi * 120.0)
    curves, calls = {}, {}
    for k in (0, 8):
        law = _Counted(gms)
        out = nonlinear_compliance(setup, [300.0], band=band, law=law,
                                   settings=HarmonicSettings(harmonics=5, secant_updates=k),
                                   references=False, describing=False)
        curves[k], calls[k] = out.curves[0], law.calls
    assert curves[8].peak == pytest.approx(curves[0].peak, rel=1e-5)
    assert curves[8].resonance == pytest.approx(curves[0].resonance, rel=1e-4)
    assert calls[8] < 0.4 * calls[0]


def test_secant_updates_must_be_a_count():
    from servotune.harmonic import HarmonicSettings

    with pytest.raises(ValueError, match="secant_updates"):
        HarmonicSettings(secant_updates=-1)


def _axis_with_law(folder: Path, law: str) -> Path:
    """The bundled axis with [friction.gms] (the GMS set matched to the paper's) or
    [friction.viscous] (its sigma2) in place of LuGre."""
    import re
    import shutil

    paper = Path(__file__).resolve().parents[1] / "models" / "paper_x_axis"
    shutil.copytree(paper, folder)
    text = re.sub(r"variation = \{[^}]*\}[^\n]*\n(\s+#[^\n]*\n)*", "",
                  (folder / "axis.toml").read_text())
    text = re.sub(r"\nviscous = [^\n]*", "", text)
    start, end = text.index("[friction.lugre]"), text.index("[drive]")
    table = {"gms": "", "viscous": "[friction.viscous]\nc = 5578.0\n\n"}[law]
    text = text[:start] + table + text[end:]
    if law == "gms":
        text = text.replace('pads = ["pad1.x"', 'gms = "bianchi2014"\npads = ["pad1.x"', 1)
    (folder / "axis.toml").write_text(text)
    return folder


@pytest.mark.parametrize("law", ["gms", "viscous"])
@pytest.mark.parametrize("command", [["compliance", "--continuous", "--no-plots"],
                                     ["bode", "--continuous", "--no-plots"], ["modes"],
                                     ["lobes", "--continuous", "--no-plots"]])
def test_every_linear_command_runs_with_every_shipped_law(tmp_path, capsys, law, command):
    import json

    from servotune.cli import main

    folder = _axis_with_law(tmp_path / "axis", law)
    name, *flags = command
    code = main([name, str(folder), *flags, "--json", "--out", str(tmp_path / "out")])
    out = json.loads(capsys.readouterr().out)
    assert code == 0, out
    assert out["friction_law"] == law


def test_harmonic_balance_of_the_viscous_law_is_the_linear_compliance(tmp_path, capsys):
    """nlcompliance with the viscous law: the friction is linear, so the periodic response
    is the viscous reference's compliance (a second method: the linear closed loop)."""
    import json

    from servotune.cli import main

    folder = _axis_with_law(tmp_path / "axis", "viscous")
    code = main(["nlcompliance", str(folder), "--force-pp", "268", "--harmonics", "3",
                 "--f-start-hz", "20", "--f-end-hz", "80", "--continuous", "--no-plots",
                 "--json", "--out", str(tmp_path / "out")])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["friction_law"] == "viscous"
    curve, reference = out["curves"][0], out["linear_references"]["viscous"]
    # the same peak (the reference on 901 points, the balance's peak refined)
    assert curve["peak_compliance_m_per_n"] == pytest.approx(
        reference["peak_compliance_m_per_n"], rel=2e-3)
    assert curve["resonance_hz"] == pytest.approx(reference["resonance_hz"], rel=5e-3)


def test_a_law_without_a_steady_friction_says_what_it_lacks():
    class Bare(FrictionLaw):
        """A law with neither steady_force nor periodic_force (not registered: no name)."""

    with pytest.raises(ValueError, match="neither steady_force nor periodic_force"):
        Bare().steady_force(0.01)
