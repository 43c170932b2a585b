"""Milling set-up and directional matrices against quadrature of the force model and closed
forms."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from servotune.chatter import (
    MillingSetup,
    directional_factor,
    directional_matrix,
    periodic_directional_matrix,
)


def h_instantaneous(setup, phi0):
    """H (..., 2, 2) at tooth-0 angles phi0, summed over the teeth straight from the force
    projections (Insperger et al. 2003, Eq 4-7), written independently of the module."""
    phi0 = np.asarray(phi0, dtype=float)
    out = np.zeros((*phi0.shape, 2, 2))
    for j in range(setup.teeth):
        phi = (phi0 + 2 * math.pi * j / setup.teeth) % (2 * math.pi)
        g = (setup.entry_angle < phi) & (phi < setup.exit_angle)
        s, c = np.sin(phi), np.cos(phi)
        # dynamic chip thickness dh = s dx + c dy; forces on the tool per unit depth
        fx_per_dh = -setup.kt * c - setup.kn * s
        fy_per_dh = setup.kt * s - setup.kn * c
        out[..., 0, 0] -= g * fx_per_dh * s   # F = -b H dq
        out[..., 0, 1] -= g * fx_per_dh * c
        out[..., 1, 0] -= g * fy_per_dh * s
        out[..., 1, 1] -= g * fy_per_dh * c
    return out


SETUPS = [MillingSetup(2, 6e8, 2e8, ae, mode) for ae in (1.0, 0.5, 0.1, 0.05)
          for mode in ("down", "up")] + [MillingSetup(5, 2e9, 7e8, 0.3, "up")]


@pytest.mark.parametrize("setup", SETUPS, ids=lambda s: f"N{s.teeth}-{s.radial_immersion}-"
                                                        f"{s.milling}")
def test_directional_matrix_is_the_mean_of_the_force_model(setup):
    # midpoint rule over one tooth period; H jumps by ~K_t at entry/exit, so with 2e5 points
    # the error is ~K_t / 2e5
    n = 200000
    phi0 = (np.arange(n) + 0.5) * (2 * math.pi / setup.teeth) / n
    mean = h_instantaneous(setup, phi0).mean(axis=0)
    assert_allclose(directional_matrix(setup), mean, atol=2e-5 * setup.kt)


@pytest.mark.parametrize("setup", SETUPS[:4], ids=lambda s: f"{s.radial_immersion}")
def test_interval_averages_match_quadrature(setup):
    m = 12
    h = periodic_directional_matrix(setup, m)
    dphi = 2 * math.pi / setup.teeth / m
    for i in (0, 5, 11):
        sub = (i + (np.arange(40000) + 0.5) / 40000) * dphi
        ref = h_instantaneous(setup, sub).mean(axis=0)
        assert_allclose(h[i], ref, atol=1e-4 * setup.kt)
    assert_allclose(h.mean(axis=0), directional_matrix(setup), rtol=1e-12, atol=1e-6)


def test_full_slot_closed_form():
    # Altintas (2012) Eq 3.59 at phi = 0 .. pi: alpha = [[-Kr pi, -pi], [pi, -Kr pi]]
    s = MillingSetup(teeth=4, kt=1.5e9, kn=4.5e8)
    expected = s.teeth / 4 * np.array([[s.kn, s.kt], [-s.kt, s.kn]])
    assert_allclose(directional_matrix(s), expected, rtol=1e-12)
    assert directional_factor(s, "x") == pytest.approx(s.teeth * s.kr_ratio / 4)
    assert directional_factor(s, "y") == pytest.approx(s.teeth * s.kr_ratio / 4)


def test_half_immersion_angles_and_mirror():
    down = MillingSetup(2, 6e8, 2e8, 0.5, "down")
    up = MillingSetup(2, 6e8, 2e8, 0.5, "up")
    assert (down.entry_angle, down.exit_angle) == pytest.approx((math.pi / 2, math.pi))
    assert (up.entry_angle, up.exit_angle) == pytest.approx((0.0, math.pi / 2))
    # the direct terms of up and down milling differ only by the sign of the Kt part
    d, u = directional_matrix(down), directional_matrix(up)
    assert d[0, 0] + u[0, 0] == pytest.approx(2 * 2 * 2e8 / (2 * math.pi) * math.pi / 4)


def test_from_ratio():
    s = MillingSetup.from_ratio(teeth=3, kt=1e9, kr=0.3, radial_immersion=0.2, milling="up")
    assert s.kn == pytest.approx(3e8) and s.kr_ratio == pytest.approx(0.3)
    assert s.to_dict()["exit_angle_deg"] == pytest.approx(math.degrees(math.acos(0.6)))


@pytest.mark.parametrize("kwargs, words", [
    (dict(radial_immersion=0.0), "radial_immersion"),
    (dict(radial_immersion=1.2), "(0, 1]"),
    (dict(radial_immersion=-0.3), "radial_immersion"),
    (dict(kt=-6e8), "kt"),
    (dict(kn=-2e8), "kn"),
    (dict(kt=float("nan")), "kt"),
    (dict(teeth=0), "teeth"),
    (dict(teeth=2.5), "teeth"),
    (dict(milling="side"), "milling"),
    (dict(helix_angle=2.0), "helix_angle"),
])
def test_bad_set_up_is_refused_by_name(kwargs, words):
    args = dict(teeth=2, kt=6e8, kn=2e8, radial_immersion=1.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=words.replace("(", r"\(").replace("]", r"\]")):
        MillingSetup(**args)


def test_bad_ratio_and_intervals_and_direction():
    with pytest.raises(ValueError, match="kr"):
        MillingSetup.from_ratio(2, 6e8, -0.3)
    with pytest.raises(ValueError, match="intervals"):
        periodic_directional_matrix(SETUPS[0], 0)
    with pytest.raises(ValueError, match="direction"):
        directional_factor(SETUPS[0], "z")
