"""Zero-order stability lobes against Tlusty's closed form, the characteristic equation solved
independently speed by speed, and the other input forms."""

import math

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy import optimize

from servotune.chatter import (
    MillingSetup,
    Mode,
    absolute_stability_limit,
    chatter_margin,
    compliance_matrix,
    critical_depth,
    directional_factor,
    directional_matrix,
    modal_compliance,
    oriented_frf,
    read_frf_csv,
    stability_lobes,
    system_response,
)

# Insperger and Stepan's milling benchmark (Insperger & Stepan 2004, IJNME 61, sec 5)
WN = 2 * math.pi * 922.0
ZETA = 0.011
K_IS = 0.03993 * WN**2
BENCH = modal_compliance([Mode(WN, ZETA, K_IS)])
SLOT = MillingSetup(teeth=2, kt=6e8, kn=2e8, radial_immersion=1.0)


def coupled_system():
    """Two modes with oblique mode shapes: a 2 x 2 compliance with cross terms."""
    shapes = [(math.cos(0.4), math.sin(0.4)), (-math.sin(0.9), math.cos(0.9))]
    modes = [(2 * math.pi * 700.0, 0.03, 2.0e7), (2 * math.pi * 1100.0, 0.02, 3.5e7)]
    n = 2 * len(modes)
    a, b, c = np.zeros((n, n)), np.zeros((n, 2)), np.zeros((2, n))
    for i, ((wn, z, k), v) in enumerate(zip(modes, shapes, strict=True)):
        a[2 * i, 2 * i + 1] = 1.0
        a[2 * i + 1, 2 * i] = -wn**2
        a[2 * i + 1, 2 * i + 1] = -2 * z * wn
        b[2 * i + 1] = np.array(v) * wn**2 / k
        c[:, 2 * i] = v
    return control.ss(a, b, c, np.zeros((2, 2)))


@pytest.mark.parametrize("wn, zeta, k", [(WN, ZETA, K_IS), (2 * math.pi * 60.0, 0.03, 8e7),
                                         (2 * math.pi * 2500.0, 0.002, 3e6)])
@pytest.mark.parametrize("direction", ["x", "y"])
def test_tlusty_single_mode_identity(wn, zeta, k, direction):
    # b_crit K_t mu = 2 k zeta (1 + zeta), at w_n sqrt(1 + 2 zeta) (Tlusty & Polacek 1963)
    setup = MillingSetup(teeth=3, kt=8e8, kn=3e8, radial_immersion=1.0)
    mu = directional_factor(setup, direction)
    assert mu > 0
    system = modal_compliance([Mode(wn, zeta, k, direction)])
    b, wc = absolute_stability_limit(system, setup, direction=direction)
    assert_allclose(b * setup.kt * mu, 2 * k * zeta * (1 + zeta), rtol=1e-9)
    assert_allclose(wc, wn * math.sqrt(1 + 2 * zeta), rtol=1e-6)


def test_negative_directional_factor_chatters_below_resonance():
    # down-milling a/D = 0.5 has mu_x < 0: the limit is set by the positive real part of G,
    # largest at w_n sqrt(1 - 2 zeta): b_crit K_t |mu| = 2 k zeta (1 - zeta)
    setup = MillingSetup(teeth=2, kt=6e8, kn=2e8, radial_immersion=0.5)
    mu = directional_factor(setup, "x")
    assert mu < 0
    b, wc = absolute_stability_limit(BENCH, setup)
    assert_allclose(b * setup.kt * abs(mu), 2 * K_IS * ZETA * (1 - ZETA), rtol=1e-9)
    assert_allclose(wc, WN * math.sqrt(1 - 2 * ZETA), rtol=1e-6)


def test_lobe_minima_speeds_closed_form():
    # each lobe minimum: w_c T = theta + 2 pi k, theta = pi + 2 atan(sqrt(1 + 2 zeta))
    result = stability_lobes(BENCH, SLOT, np.linspace(6000, 40000, 4001))
    root = math.sqrt(1 + 2 * ZETA)
    theta = math.pi + 2 * math.atan(root)
    n_k = 60 * WN * root / (2 * (theta + 2 * math.pi * np.arange(6)))
    assert_allclose(result.critical_speed_rpm, n_k[0], rtol=1e-6)
    # the envelope touches b_crit at every lobe minimum in the range, within the grid step
    for n in n_k[(n_k > 6000) & (n_k < 40000)]:
        i = np.argmin(abs(result.speed_rpm - n))
        assert result.depth_limit[i] == pytest.approx(result.b_crit, rel=2e-3)
    assert np.all(result.depth_limit >= result.b_crit * (1 - 1e-9))


def limit_by_characteristic_equation(system, setup, speed_rpm, omega):
    """b_lim at one speed from det[I + b (1 - exp(-i w T)) G D] = 0 directly.

    The determinant is det(M) b^2 + tr(M) b + 1 with M = (1 - exp(-i w T)) G D; its roots are
    b = 2 / (-tr M -/+ sqrt(tr(M)^2 - 4 det M)). Chatter at depth b needs a real positive root:
    find the frequencies where a root's imaginary part vanishes and keep the least real root.
    """
    t = 60.0 / (setup.teeth * speed_rpm)
    d = directional_matrix(setup)

    def roots(w):
        w = np.atleast_1d(w)
        g = np.moveaxis(system(1j * w, squeeze=False), -1, 0)
        m = (1 - np.exp(-1j * w * t))[:, None, None] * (g @ d)
        tr = m[:, 0, 0] + m[:, 1, 1]
        det = m[:, 0, 0] * m[:, 1, 1] - m[:, 0, 1] * m[:, 1, 0]
        root = np.sqrt(tr * tr - 4 * det)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.stack([2 / (-tr - root), 2 / (-tr + root)])

    best = np.inf
    values = roots(omega).imag
    for branch in range(2):
        v = values[branch]
        for i in np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0):
            try:
                w0 = optimize.brentq(lambda w, br=branch: roots(w)[br, 0].imag, omega[i],
                                     omega[i + 1], xtol=1e-13 * omega[i])
            except ValueError:  # the root is infinite inside (det M = 0 in 1-D): no crossing
                continue
            r = roots(w0)[branch, 0]
            if r.real > 0 and abs(r.imag) < 1e-6 * abs(r):   # not a jump of the square root
                best = min(best, r.real)
    return best


@pytest.mark.parametrize("system, setup", [
    (BENCH, SLOT),
    (coupled_system(), MillingSetup(teeth=4, kt=1.2e9, kn=4e8, radial_immersion=0.4)),
    (coupled_system(), MillingSetup(teeth=3, kt=1.2e9, kn=4e8, radial_immersion=0.7,
                                    milling="up")),
])
def test_envelope_solves_the_characteristic_equation(system, setup):
    rng = np.random.default_rng(7)
    _, wc = absolute_stability_limit(system, setup)
    lo, hi = 60 * wc / (setup.teeth * 8 * math.pi), 60 * wc / (setup.teeth * 1.2 * math.pi)
    speeds = np.linspace(lo, hi, 3001)
    result = stability_lobes(system, setup, speeds)
    omega = np.linspace(0.3 * wc, 2.5 * wc, 8000)
    for i in rng.choice(speeds.size, 6, replace=False):
        reference = limit_by_characteristic_equation(system, setup, speeds[i], omega)
        assert math.isfinite(reference)
        # the envelope interpolates between lobe points on the frequency grid
        assert_allclose(result.depth_limit[i], reference, rtol=3e-3)


def test_oriented_frf_are_the_eigenvalues():
    _, g = compliance_matrix(coupled_system(), np.linspace(2000, 9000, 20001))
    setup = MillingSetup(teeth=4, kt=1.2e9, kn=4e8, radial_immersion=0.4)
    phi = oriented_frf(g, setup)
    ref = np.linalg.eigvals(g @ directional_matrix(setup) / setup.kt)
    assert_allclose(np.sort_complex(phi), np.sort_complex(ref), rtol=1e-10, atol=1e-16)
    # the branches are continuous: on this fine grid no step exceeds 1 % of the largest value
    # (a swap of branches would jump by the distance between the eigenvalues, ~|Phi|)
    assert np.max(np.abs(np.diff(phi, axis=0))) < 0.01 * np.max(np.abs(phi))


def test_system_response_equals_python_control():
    sys = coupled_system()
    w = np.geomspace(100, 20000, 300)
    assert_allclose(system_response(sys, w), sys(1j * w, squeeze=False), rtol=1e-10)


def test_lobe_depth_scales_with_teeth():
    # D is proportional to N and n = 60 w / (N (theta + 2 pi k)): doubling N halves b and n
    speeds = np.linspace(8000, 30000, 2001)
    two = stability_lobes(BENCH, SLOT, speeds)
    four = stability_lobes(BENCH, MillingSetup(teeth=4, kt=6e8, kn=2e8), speeds / 2)
    assert_allclose(four.depth_limit, two.depth_limit / 2, rtol=1e-9)
    assert_allclose(four.critical_speed_rpm, two.critical_speed_rpm / 2, rtol=1e-9)
    assert_allclose(four.b_crit, two.b_crit / 2, rtol=1e-12)


def test_measured_forms_agree_with_the_system(tmp_path):
    w, g = compliance_matrix(BENCH, np.linspace(0.8 * WN, 1.2 * WN, 4001))
    reference, _ = absolute_stability_limit(BENCH, SLOT)
    frd = control.frd(np.moveaxis(g, 0, -1), w)
    b_frd, _ = absolute_stability_limit(frd, SLOT)
    b_siso, _ = absolute_stability_limit((w, g[:, 0, 0]), SLOT)
    # parabolic refinement on a grid of step 1e-4 w_n (the peak of Re G is ~2 zeta w_n wide)
    assert_allclose([b_frd, b_siso], reference, rtol=1e-5)
    path = tmp_path / "frf.csv"
    rows = np.column_stack([w / (2 * math.pi), g[:, 0, 0].real, g[:, 0, 0].imag])
    np.savetxt(path, rows, delimiter=",", header="f_hz,re_xx_m_per_n,im_xx_m_per_n",
               comments="")
    b_csv, _ = absolute_stability_limit(read_frf_csv(path), SLOT)
    assert_allclose(b_csv, reference, rtol=1e-5)
    speeds = np.linspace(14000, 18000, 201)
    assert_allclose(stability_lobes(read_frf_csv(path), SLOT, speeds).depth_limit,
                    stability_lobes(BENCH, SLOT, speeds).depth_limit, rtol=3e-3)


def test_csv_with_all_terms(tmp_path):
    sys = coupled_system()
    w, g = compliance_matrix(sys, np.linspace(1000, 12000, 3000))
    cols, names = [w / (2 * math.pi)], ["f_hz"]
    for (i, j), term in zip([(0, 0), (0, 1), (1, 0), (1, 1)], ["xx", "xy", "yx", "yy"],
                            strict=True):
        cols += [g[:, i, j].real, g[:, i, j].imag]
        names += [f"re_{term}_m_per_n", f"im_{term}_m_per_n"]
    path = tmp_path / "frf.csv"
    np.savetxt(path, np.column_stack(cols), delimiter=",", header=",".join(names), comments="")
    frd = read_frf_csv(path)
    assert_allclose(frd.omega, w, rtol=1e-12)
    setup = MillingSetup(teeth=4, kt=1.2e9, kn=4e8, radial_immersion=0.4)
    assert_allclose(absolute_stability_limit(frd, setup)[0],
                    absolute_stability_limit(sys, setup)[0], rtol=1e-4)


def test_chatter_margin_forms():
    b_crit, _ = absolute_stability_limit(BENCH, SLOT)
    assert chatter_margin(BENCH, SLOT, 1e-4) == pytest.approx(b_crit / 1e-4, rel=1e-12)
    # a window around a lobe minimum: the worst speed is the minimum itself
    assert chatter_margin(BENCH, SLOT, 1e-4, (15000, 17000)) == pytest.approx(b_crit / 1e-4)
    # a window in the stable pocket: the margin is the lowest envelope value there
    pocket = chatter_margin(BENCH, SLOT, 1e-4, (19000, 23000))
    lobes = stability_lobes(BENCH, SLOT, np.linspace(19000, 23000, 2001))
    assert pocket == pytest.approx(lobes.depth_limit.min() / 1e-4, rel=1e-12)
    assert pocket > 3 * b_crit / 1e-4


def test_critical_depth_parabola():
    # exact on a parabola, never above the grid minimum
    w = np.array([1.0, 2.0, 4.0])
    y = -5.0 + 0.5 * (w - 2.3) ** 2
    assert critical_depth(y, 2.0, w) == pytest.approx(-1 / (2 * 2.0 * -5.0), rel=1e-12)
    assert critical_depth(y, 2.0) == pytest.approx(-1 / (2 * 2.0 * y.min()))


@pytest.mark.parametrize("make, words", [
    (lambda: critical_depth(np.array([1e-7, 2e-7]), 6e8), "no negative real part"),
    (lambda: absolute_stability_limit(  # a real positive compliance: a spring, no chatter
        (np.array([1.0, 2.0, 3.0]), np.full(3, 1e-6 + 0j)), SLOT), "no negative real part"),
    (lambda: absolute_stability_limit(control.ss([[0.0, 1.0], [-4.0, 0.1]], [[0.0], [1.0]],
                                                 [[1.0, 0.0]], 0.0), SLOT), "pole"),
    (lambda: absolute_stability_limit(control.ss(-np.eye(3), np.ones((3, 3)), np.ones((3, 3)),
                                                 0.0), SLOT), "SISO or 2 x 2"),
    (lambda: absolute_stability_limit((np.array([3.0, 2.0, 1.0]), np.ones(3)), SLOT),
     "increasing"),
    (lambda: absolute_stability_limit((np.array([1.0, 2.0, 3.0]), np.ones(4)), SLOT), "shape"),
    (lambda: absolute_stability_limit(BENCH, SLOT, direction="z"), "direction"),
    (lambda: stability_lobes(BENCH, SLOT, [3000.0, 2000.0]), "increasing"),
    (lambda: stability_lobes(BENCH, SLOT, [1.0, 2.0]), "lobes"),
    (lambda: chatter_margin(BENCH, SLOT, -1e-3), "required depth"),
    (lambda: absolute_stability_limit(BENCH, "slot"), "MillingSetup"),
    (lambda: absolute_stability_limit([1, 2, 3], SLOT), "python-control"),
])
def test_bad_input_is_a_clear_error(make, words):
    with pytest.raises(ValueError, match=words):
        make()


@pytest.mark.parametrize("header, words", [
    ("f_hz,re_xx_m_per_n", "both re_xx"),
    ("f_hz,re_xy_m_per_n,im_xy_m_per_n", "direct term"),
    ("freq,re_xx_m_per_n,im_xx_m_per_n", "unknown columns"),
    ("f_hz,re_xx_m_per_n,im_xx_m_per_n,re_xy_m_per_n,im_xy_m_per_n", "cross terms"),
])
def test_bad_csv_is_refused(tmp_path, header, words):
    path = tmp_path / "bad.csv"
    n = header.count(",") + 1
    path.write_text(header + "\n" + "\n".join(",".join(["1e-6"] * n) for _ in range(5)))
    with pytest.raises(ValueError, match=words):
        read_frf_csv(path)


def test_envelope_does_not_depend_on_the_lobe_chunks(monkeypatch):
    import servotune.chatter.zoa as zoa

    speeds = np.linspace(3000, 40000, 3000)
    whole = stability_lobes(BENCH, SLOT, speeds, lobes=20)
    monkeypatch.setattr(zoa, "_POINTS_PER_CHUNK", 20_000)  # one or two lobes per chunk
    chunked = stability_lobes(BENCH, SLOT, speeds, lobes=20)
    assert_allclose(chunked.depth_limit, whole.depth_limit, rtol=0, atol=0)


def test_transfer_function_input():
    # the single mode as a transfer function (1/m) / (s^2 + 2 zeta wn s + wn^2)
    tf = control.tf([1 / 0.03993], [1, 2 * ZETA * WN, WN**2])
    b_tf, w_tf = absolute_stability_limit(tf, SLOT)
    b_ss, w_ss = absolute_stability_limit(BENCH, SLOT)
    assert_allclose([b_tf, w_tf], [b_ss, w_ss], rtol=1e-8)
