"""Two-mass layouts of sec 4.1 against closed forms, the paper's numbers and python-control."""

import math

import control
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from servotune import twomass
from servotune.twomass import TwoMassSystem

FIG5 = dict(m1=5000.0, k=16e6, alpha=0.3)  # the paper's table beside Fig 5


def state_space(system: TwoMassSystem, c: float) -> control.StateSpace:
    """The two masses assembled from their equations of motion, independently of the module.

    States [x1, x2, v1, v2], input f2, output x2.
    """
    m1, m2, k = system.m1, system.m2, system.k
    if system.layout == "B":  # ground --C-- M1 --K-- M2
        kk = np.array([[k, -k], [-k, k]])
        cc = np.array([[c, 0.0], [0.0, 0.0]])
    else:  # ground --K-- M2 --C-- M1
        kk = np.array([[0.0, 0.0], [0.0, k]])
        cc = np.array([[c, -c], [-c, c]])
    minv = np.diag([1.0 / m1, 1.0 / m2])
    a = np.block([[np.zeros((2, 2)), np.eye(2)], [-minv @ kk, -minv @ cc]])
    b = np.array([[0.0], [0.0], [0.0], [1.0 / m2]])
    cmat = np.array([[0.0, 1.0, 0.0, 0.0]])
    return control.ss(a, b, cmat, 0.0)


@pytest.mark.parametrize("layout", ["A", "B"])
@pytest.mark.parametrize("c", [1e2, 4.912e3, 4.912e5, 3e7])
def test_compliance_equals_python_control_state_space(layout, c):
    system = TwoMassSystem(**FIG5, layout=layout)
    omega = 2 * np.pi * np.linspace(0.5, 40.0, 300)
    reference = state_space(system, c)(1j * omega)
    assert_allclose(twomass.two_mass_compliance(system, omega, c), reference, rtol=1e-9)


@pytest.mark.parametrize("layout", ["A", "B"])
def test_fixed_points_do_not_depend_on_damping(layout):
    system = TwoMassSystem(**FIG5, layout=layout)
    c = np.geomspace(1e2, 1e9, 29)[:, None]
    for w in twomass.fixed_points(system):
        mag = np.abs(twomass.two_mass_compliance(system, w, c))
        assert_allclose(mag, np.broadcast_to(mag[0], mag.shape), rtol=1e-10)


def test_fixed_points_are_not_fixed_elsewhere():
    # the property above is specific to the fixed points: between them |H| moves with C
    system = TwoMassSystem(**FIG5)
    w = np.mean(twomass.fixed_points(system))
    mag = np.abs(twomass.two_mass_compliance(system, w, np.array([1e3, 1e6])))
    assert abs(mag[0] / mag[1] - 1.0) > 0.1


def test_paper_fig5_copt():
    # Fig 5 draws C = 4.912e3 ... 4.912e7 N s/m; 4.912e5 is the optimum (paper sec 4.1)
    assert_allclose(twomass.optimal_damping(TwoMassSystem(**FIG5)), 4.912e5, rtol=1e-4)


def test_fig5_resonance_decreases_with_damping():
    # paper sec 4.1: "the resonance frequency decreases as C is augmented"
    system = TwoMassSystem(**FIG5)
    c_opt = twomass.optimal_damping(system)
    peaks = [twomass.peak_compliance(system, c_opt * 10.0**k)[1] for k in (-2, -1, 1, 2)]
    assert np.all(np.diff(peaks) < 0)
    w_c0, w_cinf = twomass.limit_resonances(system)
    assert_allclose([peaks[0], peaks[-1]], [w_c0, w_cinf], rtol=2e-3)


@pytest.mark.parametrize("alpha", [0.05, 0.1, 0.3, 0.6, 0.9])
def test_copt_is_the_numeric_minimax_damping(alpha):
    system = TwoMassSystem(m1=5000.0, k=16e6, alpha=alpha)
    c_num, peak_num = twomass.minimax_damping(system)
    assert_allclose(c_num, twomass.optimal_damping(system), rtol=1e-5)
    assert_allclose(peak_num, twomass.g_alpha(alpha) / system.k, rtol=1e-9)


def test_lanchester_copt_is_the_numeric_minimax_damping():
    # layout A, an interpretation: the closed form is Den Hartog's Lanchester damper
    for alpha in (0.1, 0.3, 1.0, 3.0):
        system = TwoMassSystem(m1=5000.0, k=16e6, alpha=alpha, layout="A")
        c_num, peak_num = twomass.minimax_damping(system)
        assert_allclose(c_num, twomass.optimal_damping(system), rtol=1e-5)
        assert_allclose(peak_num, twomass.optimal_peak(system), rtol=1e-9)


def test_above_alpha_one_first_fixed_point_dominates():
    system = TwoMassSystem(m1=5000.0, k=16e6, alpha=3.0)
    with pytest.warns(UserWarning, match="first fixed point"):
        twomass.analyse_two_mass(system)
    w1 = twomass.fixed_points(system)[0]
    h1 = abs(complex(twomass.two_mass_compliance(system, w1, 1.0)))
    assert h1 > twomass.optimal_peak(system)
    _, peak = twomass.minimax_damping(system)
    assert peak >= h1 * (1 - 1e-12)


@settings(max_examples=40, deadline=None)
@given(alpha=st.floats(0.02, 0.95), m1=st.floats(10.0, 1e5), k=st.floats(1e4, 1e10))
def test_optimal_peak_is_the_frf_peak_at_copt(alpha, m1, k):
    # g(alpha)/K (Eq 7) against the numerically found maximum of |H| at Copt; at alpha = 1 the
    # two fixed points are equally high and the peak location is ambiguous
    system = TwoMassSystem(m1=m1, k=k, alpha=alpha)
    peak, w_peak = twomass.peak_compliance(system, twomass.optimal_damping(system))
    assert_allclose(peak * k, twomass.g_alpha(alpha), rtol=1e-8)
    assert_allclose(w_peak, twomass.fixed_points(system)[1], rtol=1e-3)


def test_limit_resonances_are_the_undamped_eigenfrequencies():
    system = TwoMassSystem(**FIG5)
    m1, m2, k = system.m1, system.m2, system.k
    free = np.sqrt(np.linalg.eigvals(np.array([[k / m1, -k / m1], [-k / m2, k / m2]])).max())
    assert_allclose(twomass.limit_resonances(system), [free, math.sqrt(k / m2)], rtol=1e-12)


def test_analysis_to_dict_is_in_si_with_hz_edges():
    d = twomass.analyse_two_mass(TwoMassSystem(**FIG5)).to_dict()
    assert_allclose(d["fixed_points_hz"], np.array(d["fixed_points"]) / (2 * np.pi))
    assert_allclose(d["peak_compliance"] * FIG5["k"], twomass.g_alpha(0.3))


@pytest.mark.parametrize("field, value", [
    ("alpha", 0.0), ("alpha", -0.3), ("m1", 0.0), ("m1", -1.0), ("k", 0.0),
    ("k", float("nan")), ("alpha", float("inf")), ("m1", float("nan"))])
def test_invalid_parameters_are_refused_by_name(field, value):
    kwargs = dict(FIG5, **{field: value})
    with pytest.raises(ValueError, match=field):
        TwoMassSystem(**kwargs)


def test_invalid_layout_and_damping():
    with pytest.raises(ValueError, match="layout"):
        TwoMassSystem(**FIG5, layout="C")
    system = TwoMassSystem(**FIG5)
    with pytest.raises(ValueError, match="damping"):
        twomass.two_mass_compliance(system, 10.0, -1.0)
    with pytest.raises(ValueError, match="damping"):
        twomass.two_mass_compliance(system, 10.0, float("nan"))
    with pytest.raises(ValueError, match="alpha"):
        twomass.g_alpha(0.0)
