"""Identification recovers known parameters from synthetic noisy data within its standard
errors, and refuses data that cannot determine them."""

import dataclasses
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from servotune.friction import identify, lugre
from servotune.friction.identify import IdentificationError
from servotune.friction.lugre import BIANCHI2014

NOISE = 60.0  # N, 1 % of Fs


def stribeck_data(rng, n_side=25, v_min=2e-4, v_max=0.5, p=BIANCHI2014):
    """Fig 7 style: constant-velocity tests over -0.5..0.5 m/s, Gaussian force noise."""
    speeds = np.geomspace(v_min, v_max, n_side)
    v = np.concatenate([-speeds[::-1], speeds])
    f = lugre.steady_state_friction(p, v) + rng.normal(0.0, NOISE, v.size)
    return v, f


def test_steady_state_fit_recovers_the_paper_parameters():
    rng = np.random.default_rng(2014)
    v, f = stribeck_data(rng)
    fit = identify.fit_steady_state(v, f)
    truth = np.array([getattr(BIANCHI2014, n) for n in fit.names])
    z = (fit.values - truth) / fit.standard_errors
    assert np.all(np.abs(z) < 4.0), dict(zip(fit.names, z, strict=True))
    assert_allclose(fit.rms, NOISE, rtol=0.25)
    assert_allclose(fit.residuals, f - lugre.steady_state_friction(fit.parameters, v), atol=1e-6)


def test_steady_state_standard_errors_match_the_scatter_of_repeated_fits():
    # Monte Carlo: the spread of estimates over noise realisations is what the covariance says
    rng = np.random.default_rng(11)
    estimates, errors = [], []
    for _ in range(40):
        v, f = stribeck_data(rng)
        fit = identify.fit_steady_state(v, f)
        estimates.append(fit.values)
        errors.append(fit.standard_errors)
    spread = np.std(estimates, axis=0, ddof=1)
    predicted = np.mean(errors, axis=0)
    # 40 samples: the sample standard deviation is within about +-25 % (2 sigma) of the truth
    assert_allclose(spread / predicted, 1.0, atol=0.35)
    truth = np.array([getattr(BIANCHI2014, n) for n in identify.STEADY_NAMES])
    assert np.all(np.abs(np.mean(estimates, axis=0) - truth) < 3 * predicted / math.sqrt(40))


def test_steady_state_fit_with_fixed_delta():
    rng = np.random.default_rng(5)
    v, f = stribeck_data(rng)
    fit = identify.fit_steady_state(v, f, fixed={"delta": 1.0})
    assert fit.names == ("fc", "fs", "vs", "sigma2")
    assert fit.parameters.delta == 1.0
    value, se = fit.estimate("vs")
    assert abs(value - BIANCHI2014.vs) < 4 * se
    with pytest.raises(ValueError, match="cannot fix"):
        identify.fit_steady_state(v, f, fixed={"sigma0": 1.0})


@pytest.mark.parametrize("case, match", [
    ("few", "points cannot determine"),
    ("one_sided", "one sign"),
    ("narrow", "decade"),
    ("zero", "v = 0"),
    ("fast_only", "Stribeck|determine"),
])
def test_steady_state_refuses_ill_posed_data(case, match):
    rng = np.random.default_rng(3)
    if case == "few":
        v, f = stribeck_data(rng, n_side=5)
    elif case == "one_sided":
        v, f = stribeck_data(rng)
        v, f = np.abs(v), np.abs(f)
    elif case == "narrow":
        v, f = stribeck_data(rng, v_min=0.1, v_max=0.5)
    elif case == "zero":
        v, f = stribeck_data(rng)
        v[3] = 0.0
    else:  # all speeds far above vs: the Stribeck dip is not in the data
        v, f = stribeck_data(rng, v_min=0.08, v_max=2.0)
    with pytest.raises(IdentificationError, match=match):
        identify.fit_steady_state(v, f)


def presliding_record(rng, p=BIANCHI2014):
    """Fig 2 / Fig 8 style: 10 um sinusoid with a 3.7 s period, force noise 1 % of Fs."""
    t = np.linspace(0.0, 7.4, 1500)
    x = 10e-6 * np.sin(2 * math.pi * t / 3.7) + 2e-6 * np.sin(2 * math.pi * t / 0.9)
    force = lugre.simulate_lugre(p, t, displacement=x).force + rng.normal(0.0, NOISE, t.size)
    return t, x, force


def test_presliding_fit_recovers_sigma0_and_sigma1():
    rng = np.random.default_rng(8)
    t, x, f = presliding_record(rng)
    start = dataclasses.replace(BIANCHI2014, sigma0=1e8, sigma1=0.0)  # wrong on purpose
    fit = identify.fit_presliding(t, x, f, start)
    for name in ("sigma0", "sigma1"):
        value, se = fit.estimate(name)
        assert abs(value - getattr(BIANCHI2014, name)) < 4 * se, (name, value, se)
        assert se < 0.2 * value
    assert_allclose(fit.rms, NOISE, rtol=0.15)
    assert fit.parameters.fs == BIANCHI2014.fs


@pytest.mark.parametrize("case, match", [
    ("still", "no presliding motion"),
    ("monotone", "never reverses"),
    ("short", "too few"),
])
def test_presliding_refuses_ill_posed_data(case, match):
    t = np.linspace(0.0, 1.0, 200)
    x = {"still": np.zeros_like(t), "monotone": 1e-3 * t,
         "short": 1e-6 * np.sin(20 * t)}[case]
    f = np.zeros_like(t)
    if case == "short":
        t, x, f = t[:10], x[:10], f[:10]
    with pytest.raises(IdentificationError, match=match):
        identify.fit_presliding(t, x, f, BIANCHI2014)


def test_csv_reading_accepts_si_and_edge_units(tmp_path):
    steady = tmp_path / "stribeck.csv"
    steady.write_text("v_mm_per_s,f_n\n-100,-2800\n100,2800\n")
    data = identify.read_friction_csv(steady)
    assert data.kind == "steady_state"
    assert_allclose(data.velocity, [-0.1, 0.1])
    hist = tmp_path / "presliding.csv"
    hist.write_text("# comment line\nt_s,x_um,f_n\n0,0,0\n0.1,2,100\n")
    data = identify.read_friction_csv(hist)
    assert data.kind == "presliding"
    assert_allclose(data.displacement, [0.0, 2e-6])
    bad = tmp_path / "bad.csv"
    bad.write_text("speed,torque\n1,2\n")
    with pytest.raises(ValueError, match="v_m_per_s,f_n"):
        identify.read_friction_csv(bad)
    nan = tmp_path / "nan.csv"
    nan.write_text("v_m_per_s,f_n\n1,abc\n")
    with pytest.raises(ValueError,
                       match=r"nan\.csv, line 2: column 'f_n' holds 'abc', not a number"):
        identify.read_friction_csv(nan)
