"""The friction-law interface and registry: discovery, the linear contacts built from any law,
the axis file, and the compiled kernel of a law (never stale)."""

import importlib
import sys

import control
import numpy as np
import pytest
from axis_fixtures import PADS, small_axis, small_drive
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp

from servotune.friction import LuGreParameters
from servotune.friction.guideway import GuideWayFriction
from servotune.friction.law import FrictionLaw, friction_law, friction_law_names
from servotune.plant import Contact, contact_kinds, friction_contact
from servotune.simulate import NonlinearAxis, axis_system, simulate, sine_sweep

# A law in its own module: a Maxwell element (spring k in series with a damper k/c) written as a
# "nonlinear" law whose remainder is r = c z (linear, so that the simulation has a closed-form
# reference). CONSTANT is the relaxation rate c [1/s], hard-coded in the compiled remainder.
TOY = '''
from dataclasses import dataclass

import control
import numba
import numpy as np

from servotune.friction.law import FrictionLaw
from servotune.structure.model import signal_name


@numba.njit(cache=True)
def toy_remainder(component, v, z, p):
    return CONSTANT * z, 0.0, CONSTANT


@dataclass(frozen=True)
class ToyMaxwell(FrictionLaw):
    k: float
    name = "toymaxwell"
    nonlinear = True

    @classmethod
    def from_table(cls, value):
        return cls(float(value["k"]))

    def presliding(self):
        return self.k, 0.0

    def with_viscous(self, c):
        if c:
            raise ValueError("the toy law has no viscous part")
        return self

    def pad_block(self, pad, n_pads, speed=0.0):
        v, r, f, force, z = (signal_name(pad, s) for s in ("v_", "r_", "f_", "F_", "z_"))
        k = self.k / n_pads
        return control.ss([[0.0]], [[1.0, -1.0, 0.0]], [[-k], [k], [1.0]], [[0.0] * 3] * 3,
                          inputs=[v, r, "one"], outputs=[f, force, z], states=[z],
                          name=f"friction_{signal_name(pad)}")

    def remainder(self):
        return toy_remainder

    def remainder_parameters(self, speed=0.0):
        return [0.0]

    def remainder_states(self, pad):
        return (signal_name(pad, "z_"),)

    def spring_states(self, pad, n_pads):
        return ((signal_name(pad, "z_"), self.k / n_pads),)

    def error_scales(self):
        return 1e-3, (1e-6,)

    def newton_tolerance(self, step):
        return 1e-14

    def friction_force(self, v, z):
        return self.k * np.asarray(z)

    def periodic_force(self, velocity, period, share=1.0):
        # dz/dt = v - CONSTANT z, F = k z: the periodic response harmonic by harmonic
        v = np.fft.rfft(np.asarray(velocity, dtype=float))
        omega = 2 * np.pi * np.arange(v.size) / period
        return share * self.k * np.fft.irfft(v / (1j * omega + CONSTANT), n=len(velocity))
'''


@pytest.fixture
def toy_law(tmp_path, monkeypatch):
    """A law in a package of its own, installed for the test: the module and a dist-info with
    its entry point in a folder on sys.path (as pip would install it)."""
    from servotune.friction import law as law_module

    folder = tmp_path / "site"
    info = folder / "toy_maxwell-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: toy-maxwell\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[servotune.friction_laws]\n"
                                           "toymaxwell = toymaxwell:ToyMaxwell\n")
    monkeypatch.syspath_prepend(str(folder))
    monkeypatch.setenv("SERVOTUNE_KERNEL_DIR", str(tmp_path / "kernels"))
    module = "toymaxwell"

    def write(constant):
        (folder / "toymaxwell.py").write_text(TOY.replace("CONSTANT", repr(constant)))
        importlib.invalidate_caches()
        if module in sys.modules:
            return importlib.reload(sys.modules[module])
        return None

    write(50.0)
    yield write
    sys.modules.pop(module, None)
    law_module._REGISTRY.pop("toymaxwell", None)
    law_module._LOADED.pop("toymaxwell", None)


def test_the_bundled_laws_are_discovered():
    assert {"lugre", "viscous"} <= set(friction_law_names())
    assert issubclass(friction_law("LuGre"), FrictionLaw)
    with pytest.raises(ValueError, match=r"unknown friction law 'glue'.*lugre"):
        friction_law("glue")


def test_two_laws_of_one_name_are_refused():
    with pytest.raises(TypeError, match="two friction laws are named 'lugre'"):
        type("Impostor", (FrictionLaw,), {"name": "lugre"})


def test_a_new_package_is_a_new_law_for_the_contacts_and_the_axis_file(toy_law, tmp_path):
    # nothing but the module and its entry point: the registry, the contacts and the loader
    # find it
    toy = friction_law("toymaxwell")
    law = toy.from_table({"k": 2.0e8})
    friction = GuideWayFriction(PADS, law=law, viscous=10.0)
    assert friction.lugre is None
    stiction = friction_contact(friction, "stiction")
    assert (stiction.stiffness, stiction.damping) == (2.0e8, 0.0)
    assert friction_contact(friction, "viscous").damping == 10.0
    # no closed form given: the interface linearises the law's own model about steady
    # sliding (dz/dt = v - c z, F = k z with c = 50 1/s: F/v = k / (s + c))
    sliding = friction_contact(friction, "sliding", v0=0.01)
    for w in (1.0, 50.0, 3000.0):
        assert complex(control.evalfr(sliding.system, 1j * w)) == pytest.approx(
            2.0e8 / (1j * w + 50.0), rel=1e-9)
    assert set(contact_kinds()) >= {"locked", "stiction", "viscous", "equivalent", "sliding",
                                    "free"}


def test_the_lugre_contacts_are_the_lugre_linearisations():
    p = LuGreParameters.named("bianchi2014")
    friction = GuideWayFriction(PADS, p)
    assert friction.law.name == "lugre"
    assert friction_contact(friction, "stiction") == Contact(
        "stiction", stiffness=p.sigma0, damping=p.sigma1 + p.sigma2,
        note=friction_contact(friction, "stiction").note)
    with pytest.raises(ValueError, match="not both"):
        GuideWayFriction(PADS, LuGreParameters.named("canudas1995"), law=friction.law)


def _maxwell_reference(law, rate, scenario):
    """The axis with the toy law as a linear system (r = rate z folded into A), by LSODA."""
    sysm = axis_system(small_axis(), small_drive(), law, PADS, 0.0, inputs=["f_wp_x", "one"])
    a = sysm.system.A + sysm.system.B[:, 2:] @ (rate * sysm.remainder_state)
    b = sysm.system.B[:, 0]
    force = scenario.forces["wp.x"]
    sol = solve_ivp(lambda t, x: a @ x + b * float(force(t)), (0.0, scenario.duration),
                    np.zeros(a.shape[0]), method="LSODA", rtol=1e-10, atol=1e-16,
                    t_eval=np.linspace(0.0, scenario.duration, 41))
    return sysm.system.C[sysm.outputs.index("wp_x")] @ sol.y


def test_the_kernel_follows_a_changed_law_never_stale(toy_law):
    # the compiled remainder is a constant of the kernel: after the law's source changes, the
    # simulation must use the new one (a kernel compiled and cached for the old source would
    # silently give the old result)
    scenario = sine_sweep(50.0, 30.0, 30.0, 0.04)
    results = {}
    for rate in (50.0, 5000.0):
        if rate != 50.0:
            toy_law(rate)
        law = friction_law("toymaxwell")(2.0e8)
        axis = NonlinearAxis(small_axis(), small_drive(), PADS, law)
        run = simulate(axis, scenario, record_step=1e-3)
        results[rate] = run.signals["wp_x"]
        reference = _maxwell_reference(law, rate, scenario)
        assert_allclose(run.signals["wp_x"], reference, atol=1e-4 * np.abs(reference).max())
    # the two laws differ visibly, so the check above could tell them apart
    assert np.abs(results[50.0] - results[5000.0]).max() > 0.05 * np.abs(results[50.0]).max()


def test_lugre_periodic_force_is_the_stribeck_curve_while_sliding_and_shares_linearly():
    # steady sliding: dz/dt = 0, so F = sgn(v) g(v) + sigma2 v (Canudas de Wit et al. 1995,
    # Eq 6), written out here; a pad's share of the law carries that share of the force
    from servotune.simulate import LuGreFriction

    p = LuGreParameters.named("bianchi2014")
    law = LuGreFriction(p)
    for v in (-0.03, 0.004):
        g = p.fc + (p.fs - p.fc) * np.exp(-(abs(v) / p.vs) ** p.delta)
        assert_allclose(law.periodic_force(np.full(16, v), 0.01, share=0.25),
                        0.25 * (np.sign(v) * g + p.sigma2 * v), rtol=1e-9)
    t = np.arange(64) / 64 * 0.02
    v = 2e-3 * np.cos(2 * np.pi * 50 * t)
    assert_allclose(law.periodic_force(v, 0.02, share=0.25), 0.25 * law.periodic_force(v, 0.02),
                    rtol=1e-9, atol=1e-9 * p.fs)


@pytest.mark.parametrize("amplitude", [2e-7, 2e-6, 2e-5])
def test_first_harmonic_of_the_periodic_force_is_the_lugre_describing_function(amplitude):
    # two methods: the interface's describing function (first harmonic of periodic_force, the
    # orbit from the harmonic-balance hook) against the LuGre cycle of
    # servotune.friction.describing_function (its own graded integration, Eq 8-10)
    from servotune.friction import describing_function
    from servotune.simulate import LuGreFriction

    p = LuGreParameters.named("bianchi2014")
    omega = 2 * np.pi * 57.0
    ceq, keq = FrictionLaw.describing_function(LuGreFriction(p), amplitude, omega, 1024)
    ceq_ref, keq_ref = describing_function(p, amplitude, omega)
    assert_allclose(ceq, ceq_ref, rtol=2e-3)
    assert_allclose(keq, keq_ref, rtol=2e-3, atol=2e-3 * p.sigma0)


def test_a_registered_contact_kind_reaches_the_analyses_and_the_command_line():
    import argparse

    from servotune import contact_kinds as registry
    from servotune.analysis import axis_contact, compliance_curve
    from servotune.axis import load_axis
    from servotune.cli._common import CliError, add_contact_options, check_contact_args

    def spring_only(friction, speed=None, **_):
        return Contact("spring_only", stiffness=friction.law.presliding()[0],
                       note=f"presliding spring alone (speed {speed})")

    kind = registry.ContactKind("spring_only", "the presliding spring without its damper",
                                spring_only, optional=("speed",))
    registry.register_contact_kind(kind)
    try:
        axis = load_axis("models/paper_x_axis").with_continuous_drive()
        contact = axis_contact(axis, "spring_only", speed=0.01)
        assert contact.stiffness == axis.friction.lugre.sigma0 and contact.damping == 0.0
        # the plant takes it as any spring contact: the same compliance as the stiction
        # contact with its damper removed
        reference = Contact("stiction", stiffness=axis.friction.lugre.sigma0)
        omega = 2 * np.pi * np.array([20.0, 57.0, 300.0])
        assert_allclose(compliance_curve(axis, contact, omega=omega).values,
                        compliance_curve(axis, reference, omega=omega).values, rtol=1e-12)
        with pytest.raises(ValueError, match="amplitude is a parameter of the 'equivalent'"):
            axis_contact(axis, "spring_only", amplitude=1e-6)
        parser = argparse.ArgumentParser()
        add_contact_options(parser)
        args = parser.parse_args(["--contact", "spring_only", "--speed", "0.01"])
        check_contact_args(args)
        with pytest.raises(CliError, match="--c sets the viscous damping"):
            check_contact_args(parser.parse_args(["--contact", "spring_only", "--c", "5"]))
    finally:
        registry._CONTACT_KINDS.pop("spring_only", None)


def test_kernels_of_older_sources_are_removed_after_a_day(toy_law, tmp_path):
    import os
    import time

    from servotune.simulate.integrator import chunk_kernel

    folder = tmp_path / "kernels"
    (folder / "__pycache__").mkdir(parents=True)
    old = folder / "_kernel_toymaxwell_toy_remainder_0123456789abcdef.py"
    recent = folder / "_kernel_toymaxwell_toy_remainder_fedcba9876543210.py"
    cached = folder / "__pycache__" / f"{old.stem}.integrate_chunk-1.py311.nbi"
    for f in (old, recent, cached):
        f.write_text("# a kernel of an older source\n")
    two_days = time.time() - 2 * 86400
    os.utime(old, (two_days, two_days))
    kernel = chunk_kernel(friction_law("toymaxwell")(1.0e8).remainder())
    assert kernel.py_func.__name__ == "integrate_chunk"
    assert not old.exists() and not cached.exists()
    assert recent.exists()                      # younger: maybe in use by a running process
    assert len(list(folder.glob("_kernel_toymaxwell_toy_remainder_*.py"))) == 2


def test_the_lugre_law_gives_harmonic_balance_the_exact_jacobian_of_its_periodic_force():
    # reference: central differences of the law's own periodic force
    from servotune.friction.laws.lugre import LuGreFriction

    law = LuGreFriction(LuGreParameters.named("bianchi2014"))
    t = np.arange(64) / 64.0
    v = 0.02 * np.sin(2 * np.pi * t) + 0.005
    force, jac = law.periodic_force_jacobian(v, 0.02, share=0.25)
    np.testing.assert_allclose(force, law.periodic_force(v, 0.02, share=0.25), rtol=1e-12)
    h = 1e-9
    for j in (0, 17, 40):
        e = np.zeros_like(v)
        e[j] = h
        fd = (law.periodic_force(v + e, 0.02, 0.25)
              - law.periodic_force(v - e, 0.02, 0.25)) / (2 * h)
        np.testing.assert_allclose(jac[:, j], fd, rtol=1e-4, atol=1e-6 * np.abs(fd).max())
