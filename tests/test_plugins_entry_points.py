"""Plug-ins from other packages, found through their entry points (servotune.plugins).

Each test installs a distribution on the fly: a folder on sys.path holding the module and a
``<name>.dist-info`` with METADATA and entry_points.txt, which importlib.metadata discovers as it
discovers any installed package. The worked example is examples/plugins/dahl_friction (the Dahl
model), checked against its closed forms (Dahl 1968; Olsson et al. 1998, Eq 5-6)."""

import importlib
import math
import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp

from servotune.friction import law as law_registry
from servotune.friction.law import friction_law, friction_law_names, friction_laws
from servotune.plugins import FRICTION_LAWS_GROUP, REQUIREMENTS_GROUP, PluginError
from servotune.tuning import constraint

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "plugins" / "dahl_friction"
SIGMA0, FC = 5.9e9, 2198.0      # the paper's bristle stiffness and Coulomb force, axis totals


@pytest.fixture
def install(tmp_path, monkeypatch):
    """``install(dist, modules, entry_points)``: a distribution on sys.path for one test; the
    registries and the modules it added are as before afterwards."""
    saved = [dict(law_registry._REGISTRY), dict(law_registry._LOADED),
             dict(constraint._REGISTRY), dict(constraint._LOADED), dict(constraint._ORIGIN)]
    added = []

    def install(dist, modules, entry_points):
        folder = tmp_path / f"site_{dist}"
        folder.mkdir()
        for name, text in modules.items():
            (folder / f"{name}.py").write_text(text)
            added.append(name)
        info = folder / f"{dist}-0.1.dist-info"
        info.mkdir()
        (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 0.1\n")
        (info / "entry_points.txt").write_text("".join(
            f"[{group}]\n" + "".join(f"{k} = {v}\n" for k, v in points.items()) + "\n"
            for group, points in entry_points.items()))
        monkeypatch.syspath_prepend(str(folder))
        importlib.invalidate_caches()
        return folder

    yield install
    for name in added:
        sys.modules.pop(name, None)
    for registry, before in zip((law_registry._REGISTRY, law_registry._LOADED,
                                 constraint._REGISTRY, constraint._LOADED, constraint._ORIGIN),
                                saved, strict=True):
        registry.clear()
        registry.update(before)


@pytest.fixture
def dahl(install):
    """The example package installed as its pyproject.toml declares it; its law class."""
    project = tomllib.loads((EXAMPLE / "pyproject.toml").read_text())["project"]
    points = project["entry-points"]
    install(project["name"].replace("-", "_"),
            {"dahl_friction": (EXAMPLE / "dahl_friction.py").read_text()}, points)
    assert points == {FRICTION_LAWS_GROUP: {"dahl": "dahl_friction:DahlFriction"}}
    return friction_law("dahl")


def _law_module(class_body):
    return ("from servotune.friction.law import FrictionLaw\n\n\n"
            f"class Law(FrictionLaw):\n{class_body}")


# ---------------------------------------------------------------- (a) the Dahl example


def test_the_dahl_law_is_found_by_name_and_loaded_on_first_use(install):
    install("dahl_friction", {"dahl_friction": (EXAMPLE / "dahl_friction.py").read_text()},
            {FRICTION_LAWS_GROUP: {"dahl": "dahl_friction:DahlFriction"}})
    sys.modules.pop("dahl_friction", None)
    assert "dahl" in friction_law_names()
    assert "dahl_friction" not in sys.modules          # listed from the metadata alone
    cls = friction_law("Dahl")
    assert cls.__module__ == "dahl_friction" and cls.name == "dahl"
    assert set(friction_laws()) >= {"dahl", "gms", "lugre", "viscous"}


def test_the_dahl_law_in_an_axis_file_and_a_time_simulation(dahl, tmp_path):
    # the bundled axis with [friction.dahl] instead of [friction.lugre], moved sinusoidally
    # (20 um in 0.1 s: the pads slide and reverse); reference: the law's closed form
    # (dahl_step, exact on a monotone path) along the pad path the simulation recorded
    from servotune.axis import load_axis
    from servotune.simulate import NonlinearAxis, simulate, sinusoid
    from servotune.simulate.setup import axis_setup

    folder = tmp_path / "axis"
    shutil.copytree(ROOT / "models" / "paper_x_axis", folder)
    text = re.sub(r"variation = \{[^}]*\}[^\n]*\n(\s+#[^\n]*\n)*", "",
                  (folder / "axis.toml").read_text())
    start, end = text.index("[friction.lugre]"), text.index("[drive]")
    (folder / "axis.toml").write_text(text[:start] + f"[friction.dahl]\nsigma0 = {SIGMA0}\n"
                                      f"fc = {FC}\n\n" + text[end:])
    axis = load_axis(folder)
    assert axis.friction.law == dahl(SIGMA0, FC)
    assert axis.friction.lugre is None
    setup = axis_setup(axis.with_continuous_drive())
    law = axis.friction.law
    record = 2.5e-4
    run = simulate(NonlinearAxis(setup.structure, setup.drive, setup.pads, law),
                   sinusoid(20e-6, 0.1, 2), record_step=record)
    assert run.friction == "dahl"
    step = sys.modules[dahl.__module__].dahl_step
    n_pads = len(setup.pads)
    share = FC / n_pads
    for pad in setup.pads:
        name = pad.replace(".", "_")
        v, force = run.signals[f"v_{name}"], run.signals[f"F_{name}"]
        x = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * record)])
        z = [force[0] * n_pads / SIGMA0]
        for dx in np.diff(x):
            z.append(step(z[-1], dx, SIGMA0 / FC, 1.0))
        error = np.abs(force - SIGMA0 / n_pads * np.array(z))
        # the path between samples taken as the trapezoid: 1 % of the pad's sliding force
        assert error.max() < 0.01 * share
        assert np.abs(force).max() == pytest.approx(share, rel=1e-3)   # sliding: Fc


def _pad_motion(law, velocity, x_end, n=2001):
    """The state z along a path at constant velocity, integrated by LSODA from the law's own
    pieces: dz/dt = v - (c0 + c_v v + c_z z) - r(v, z), linear part about rest."""
    c0, cv, cz = law.linearisation(0.0)
    p = law.remainder_parameters(0.0)
    remainder = law.remainder()

    def rhs(t, z):
        return [velocity - (c0 + cv * velocity + cz * z[0])
                - remainder(0, velocity, z[0], p)[0]]

    t = np.linspace(0.0, x_end / velocity, n)
    sol = solve_ivp(rhs, (0.0, t[-1]), [0.0], method="LSODA", t_eval=t, rtol=1e-11,
                    atol=1e-9 * FC / SIGMA0)
    return velocity * t, sol.y[0]


@pytest.mark.parametrize("alpha", [1.0, 2.5])
@pytest.mark.parametrize("velocity", [0.02, -0.005])
def test_the_dahl_virgin_curve_and_sliding_force_are_the_closed_forms(dahl, velocity, alpha):
    # from rest, dF/dx = sigma0 (1 - F/Fc sgn(v))^alpha (Olsson et al. 1998, Eq 5) integrates
    # to F = Fc (1 - g) sgn(x), g = exp(-r |x|) for alpha = 1 and
    # g = (1 + (alpha - 1) r |x|)^(1/(1 - alpha)) above, r = sigma0 / Fc: the force tends to
    # the sliding force Fc sgn(v) (exponentially, or as a power for alpha > 1)
    law = dahl(SIGMA0, FC, alpha)
    r = SIGMA0 / FC
    x, z = _pad_motion(law, velocity, 10 / r * math.copysign(1.0, velocity))
    g = (np.exp(-r * np.abs(x)) if alpha == 1.0
         else (1.0 + (alpha - 1.0) * r * np.abs(x)) ** (1.0 / (1.0 - alpha)))
    closed = FC * (1.0 - g) * np.sign(velocity)
    assert_allclose(law.friction_force(velocity, z), closed, atol=1e-6 * FC)
    # steady sliding: at F = Fc sgn(v) the pad's rate v - w(v, z) is zero, whatever v
    c0, cv, cz = law.linearisation(velocity)
    p = law.remainder_parameters(velocity)
    z_ss = math.copysign(FC / SIGMA0, velocity)
    rate = velocity - (c0 + cv * velocity + cz * z_ss) - law.remainder()(0, velocity, z_ss, p)[0]
    assert rate == pytest.approx(0.0, abs=1e-12 * abs(velocity))
    # and the periodic orbit at a constant velocity is that sliding force, shared by the pads
    assert_allclose(law.periodic_force(np.full(32, velocity), 0.01, share=0.25),
                    0.25 * math.copysign(FC, velocity), rtol=1e-12)


@pytest.mark.parametrize("amplitude", [2e-8, 3e-7, 5e-6])
def test_the_dahl_describing_function_is_the_closed_form_loop(dahl, amplitude):
    # alpha = 1 under x = A sin(omega t): the branch from -A is F = Fc - (Fc + F_A)
    # exp(-sigma0 (x + A)/Fc) with F_A = Fc tanh(sigma0 A / Fc), so the loop dissipates
    # E = 4 Fc (A - tanh(sigma0 A / Fc) Fc / sigma0) per cycle, and Ceq = E / (pi omega A^2)
    law = dahl(SIGMA0, FC)
    omega = 2 * math.pi * 57.0
    ceq, keq = law.describing_function(amplitude, omega, 512)
    r = SIGMA0 / FC
    energy = 4 * FC * (amplitude - math.tanh(r * amplitude) / r)
    assert ceq == pytest.approx(energy / (math.pi * omega * amplitude**2), rel=1e-3)
    assert 0 < keq < SIGMA0


# ---------------------------------------------------------------- (b) a broken plug-in


def test_a_law_missing_a_required_method_is_refused_naming_its_entry_point(install):
    body = ('    name = "halfdone"\n'
            "    @classmethod\n    def from_table(cls, value):\n        return cls()\n"
            "    def presliding(self):\n        return 1.0, 0.0\n")
    install("halfdone_friction", {"halfdone_law": _law_module(body)},
            {FRICTION_LAWS_GROUP: {"halfdone": "halfdone_law:Law"}})
    assert "halfdone" in friction_law_names()
    with pytest.raises(PluginError) as err:
        friction_law("halfdone")
    text = str(err.value)
    for part in ("entry point 'halfdone'", "halfdone = halfdone_law:Law",
                 "halfdone_friction 0.1", "does not implement pad_block, friction_force"):
        assert part in text
    assert "halfdone" not in law_registry._REGISTRY            # never served by name
    assert friction_law("lugre").name == "lugre"               # the others unaffected


def test_a_nonlinear_law_without_its_remainder_and_a_misnamed_law_are_refused(install):
    body = ('    name = "{name}"\n    nonlinear = True\n'
            "    @classmethod\n    def from_table(cls, value):\n        return cls()\n"
            "    def presliding(self):\n        return 1.0, 0.0\n"
            "    def pad_block(self, pad, n_pads, speed=0.0):\n        pass\n"
            "    def friction_force(self, v, z):\n        return 0.0\n")
    install("partial_friction", {"nonlinear_law": _law_module(body.format(name="partial")),
                                 "misnamed_law": _law_module(body.format(name="other"))},
            {FRICTION_LAWS_GROUP: {"partial": "nonlinear_law:Law",
                                   "misnamed": "misnamed_law:Law"}})
    with pytest.raises(PluginError, match=r"'partial'.*does not implement with_viscous, remainder, "
                                          r"remainder_parameters.*required of a nonlinear law"):
        friction_law("partial")
    with pytest.raises(PluginError, match=r"'misnamed'.*is named 'other', not 'misnamed'"):
        friction_law("misnamed")


def test_a_requirement_that_checks_nothing_is_refused_when_the_tuning_asks(install):
    module = ("from servotune.tuning.constraint import Requirement\n\n\n"
              "class Unchecked(Requirement):\n    name = 'unchecked'\n"
              "    @classmethod\n    def design_rows(cls, problem, value):\n        return []\n")
    install("unchecked_requirement", {"unchecked_req": module},
            {REQUIREMENTS_GROUP: {"unchecked": "unchecked_req:Unchecked"}})
    with pytest.raises(PluginError, match=r"requirement plug-in of the entry point 'unchecked'"
                                          r".*unchecked_requirement 0\.1.*checks nothing"):
        constraint.requirements()


# ---------------------------------------------------------------- (c) a name clash


def test_two_plugins_of_one_name_are_an_error_naming_both(install):
    install("dahl_friction", {"dahl_friction": (EXAMPLE / "dahl_friction.py").read_text()},
            {FRICTION_LAWS_GROUP: {"dahl": "dahl_friction:DahlFriction"}})
    install("other_dahl", {"other_dahl": "raise RuntimeError('never imported')\n"},
            {FRICTION_LAWS_GROUP: {"dahl": "other_dahl:Dahl"}})
    for call in (friction_law_names, lambda: friction_law("lugre")):
        with pytest.raises(PluginError) as err:
            call()
        text = str(err.value)
        assert "two friction law plug-ins are named 'dahl'" in text
        assert "dahl = dahl_friction:DahlFriction" in text and "dahl_friction 0.1" in text
        assert "dahl = other_dahl:Dahl" in text and "other_dahl 0.1" in text


def test_a_requirement_named_like_a_shipped_one_is_an_error_naming_both(install):
    module = ("from servotune.tuning.constraint import Requirement\n\n\n"
              "class Again(Requirement):\n    name = 'kv_min'\n"
              "    @classmethod\n    def design_rows(cls, problem, value):\n        return []\n"
              "    @classmethod\n    def design_checks(cls, problem, design):\n"
              "        return []\n")
    install("kv_again", {"kv_again": module}, {REQUIREMENTS_GROUP: {"kv_again": "kv_again:Again"}})
    with pytest.raises(PluginError) as err:
        constraint.requirements()
    text = str(err.value)
    assert "entry point 'kv_again'" in text and "kv_again 0.1" in text
    assert "named 'kv_min'" in text
    assert "servotune.tuning.requirements.kv_min:KvMin" in text   # the other one, by its entry


# ---------------------------------------------------------------- (d) an import error


def test_a_plugin_that_fails_to_import_is_named_and_breaks_nothing_else(install):
    install("ghost_friction", {"ghost_law": "import servotune_no_such_module\n"},
            {FRICTION_LAWS_GROUP: {"ghost": "ghost_law:Ghost"}})
    assert "ghost" in friction_law_names()
    assert friction_law("lugre").name == "lugre"
    from servotune.axis import load_axis

    assert load_axis(ROOT / "models" / "paper_x_axis").friction.law.name == "lugre"
    with pytest.raises(PluginError) as err:
        friction_law("ghost")
    text = str(err.value)
    assert "entry point 'ghost' (ghost = ghost_law:Ghost in group servotune.friction_laws)" in text
    assert "ghost_friction 0.1" in text
    assert "ModuleNotFoundError: No module named 'servotune_no_such_module'" in text
    with pytest.raises(PluginError, match="ghost"):
        friction_laws()                   # all of them asked for: the broken one is named


# ---------------------------------------------------------------- installed with pip


def _offline_build_possible() -> str | None:
    """Why the example cannot be built offline here (None: it can): pip without build
    isolation needs a setuptools that builds wheels by itself (>= 70.1) or the wheel package."""
    try:
        import setuptools
    except ImportError:
        return "setuptools is not installed"
    version = tuple(int(p) for p in setuptools.__version__.split(".")[:2])
    if version >= (70, 1):
        return None
    try:
        import wheel  # noqa: F401
    except ImportError:
        return (f"setuptools {setuptools.__version__} needs the wheel package to build, and an "
                "isolated build would fetch it from a package index")
    return None


def test_the_example_installs_with_pip_offline(tmp_path):
    reason = _offline_build_possible()
    if reason is not None:
        pytest.skip(f"no offline build: {reason}")
    target, source = tmp_path / "site", tmp_path / "dahl_friction"
    shutil.copytree(EXAMPLE, source, ignore=shutil.ignore_patterns("__pycache__", "build",
                                                                   "*.egg-info"))
    pip = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                          "--no-build-isolation", "--no-index", "--target", str(target),
                          str(source)], capture_output=True, text=True, timeout=300)
    assert pip.returncode == 0, pip.stderr
    check = subprocess.run(
        [sys.executable, "-c", "from servotune.friction.law import friction_law; "
         "print(friction_law('dahl').__module__)"],
        capture_output=True, text=True, timeout=300,
        env={**os.environ, "PYTHONPATH": str(target)})
    assert check.stdout.strip() == "dahl_friction", check.stderr


# ---------------------------------------------------------------- an uninstalled source tree


def test_the_package_modules_are_imported_only_without_servotune_entry_points(monkeypatch):
    from servotune import plugins

    imported = []
    monkeypatch.setattr(plugins, "import_modules", imported.append)
    assert "lugre" in plugins.discover(FRICTION_LAWS_GROUP, law_registry.LAWS_PACKAGE)
    assert imported == []                         # installed: the entry points alone
    monkeypatch.setattr(plugins.importlib.metadata, "entry_points", lambda group: [])
    assert plugins.discover(REQUIREMENTS_GROUP, constraint.REQUIREMENTS_PACKAGE) == {}
    assert imported == ["servotune.tuning.requirements"]
