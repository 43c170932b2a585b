"""One rule for every reported peak or resonance (servotune.peaks): a largest value at the first
or last frequency of the band is flagged and is no resonance; default bands hold the modes that
move the work piece.

References: the closed forms of a single-DOF oscillator (natural frequency sqrt(k/m); the
receptance of viscous damping zeta peaks at wn sqrt(1 - 2 zeta^2) with 1/(2 k zeta
sqrt(1 - zeta^2))) and of a two-DOF chain (the roots of its characteristic quadratic and the
mode shapes from its second row); for the starter axis of ``servotune init``, the eigenvalue
problem of its own mass and stiffness matrices (scipy.linalg.eigh), built here from the files.
"""

import json
import math
import tomllib

import numpy as np
import pytest
import scipy.linalg

from servotune.cli import main
from servotune.peaks import (
    BAND_MARGIN,
    band_peak,
    chosen_band,
    extreme_edge,
    mode_band,
    structure_peak,
)
from servotune.structure.model import ModalModel
from servotune.units import HZ_PER_RAD_S

TWO_PI = 2 * math.pi
M, K, ZETA = 300.0, 1.5e8, 0.03            # a work piece on its fixture
WN = math.sqrt(K / M)                       # 707.1 rad/s, 112.5 Hz
W_PEAK = WN * math.sqrt(1 - 2 * ZETA**2)    # where |X/F| of viscous damping peaks
H_PEAK = 1 / (2 * K * ZETA * math.sqrt(1 - ZETA**2))


@pytest.fixture(scope="module")
def sdof():
    return ModalModel([[M]], [[K]], ["wp.x"], damping_ratio=ZETA)


# -- the rule on sampled curves ----------------------------------------------------------------

@pytest.mark.parametrize(("values", "minimum", "edge"), [
    ([1.0, 2.0, 3.0], False, "high"), ([3.0, 2.0, 1.0], False, "low"),
    ([1.0, 3.0, 2.0], False, None), ([1.0, 3.0, 2.0], True, "low"),
    ([2.0, -1.0, 0.5], True, None), ([1.0, 2.0, np.nan], False, None),
])
def test_the_edge_of_an_extreme(values, minimum, edge):
    # the last finite sample before NaN (a sampled loop's Nyquist) is not the band's edge
    assert extreme_edge(values, minimum=minimum) == edge


def test_a_band_below_the_mode_flags_the_upper_edge_and_reports_no_resonance():
    w = np.linspace(0.1 * WN, 0.9 * WN, 801)
    h = 1 / (K - M * w**2 + 2j * ZETA * math.sqrt(K * M) * w)
    found = band_peak(w, h, unit="m/N")
    assert found.edge == "high" and found.resonance is None and found.peak is None
    assert found.largest_frequency == w[-1] and found.largest == pytest.approx(abs(h[-1]))
    data = found.to_dict("compliance_m_per_n")
    assert data["peak_at_band_edge"] == "high" and data["resonance_hz"] is None
    assert data["peak_compliance_m_per_n"] is None
    text = found.describe(widen_high="widen the band (--f-end-hz)")
    assert "upper edge" in text and "no resonance found inside" in text
    assert "still rises there" in text and "--f-end-hz" in text


def test_a_band_holding_the_mode_reports_the_closed_form_resonance():
    w = np.linspace(0.5 * WN, 1.5 * WN, 1001)
    h = 1 / (K - M * w**2 + 2j * ZETA * math.sqrt(K * M) * w)
    found = band_peak(w, np.abs(h))
    assert found.edge is None
    assert abs(found.resonance - W_PEAK) <= w[1] - w[0]      # within one grid step
    assert found.peak == pytest.approx(H_PEAK, rel=1e-3)     # the parabola's vertex


def test_the_minimum_of_re_g_of_chatter_at_the_grid_edge():
    # a single mode: Re of its compliance is most negative at wn sqrt(1 + 2 zeta) (Tlusty);
    # a grid that stops below that has its minimum at the upper edge, one across it inside
    from servotune.analysis import chatter_minimum_edge
    from servotune.chatter import MillingSetup, Mode, modal_compliance

    mode = Mode(WN, ZETA, K)
    setup = MillingSetup(teeth=2, kt=6e8, kn=2e8)
    w_c = WN * math.sqrt(1 + 2 * ZETA)
    system = modal_compliance([mode])
    short = np.linspace(1.001 * WN, 0.99 * w_c, 200)
    assert chatter_minimum_edge(system, setup, omega=short) == "high"
    assert chatter_minimum_edge(system, setup, omega=np.linspace(WN, 1.2 * w_c, 400)) is None


def test_a_sensitivity_peak_beyond_the_grid_is_flagged():
    # L = wc^2 / (s (s + 2 zeta wc)): |S| = |1/(1 + L)| peaks near wc for a small zeta; a grid
    # that ends at wc / 2 has its largest |S| at the upper edge
    from servotune import analysis
    from servotune.plant import Contact

    wc, z = 100.0, 0.1

    def report(omega):
        s = 1j * omega
        loop = wc**2 / (s * (s + 2 * z * wc))
        return analysis.LoopReport(Contact.locked(), omega, None, None, loop, loop)

    assert report(np.geomspace(1.0, wc / 2, 300)).ms_edge("velocity") == "high"
    assert report(np.geomspace(1.0, 10 * wc, 600)).ms_edge("position") is None


# -- a structure: the single-DOF oscillator -----------------------------------------------------

def test_structure_below_and_above_the_mode_flags_the_edges(sdof):
    below = structure_peak(sdof, "wp.x", (0.2 * WN, 0.8 * WN))
    assert below.edge == "high" and below.resonance is None
    assert below.largest_frequency == pytest.approx(0.8 * WN, rel=1e-12)
    above = structure_peak(sdof, "wp.x", (1.5 * WN, 4 * WN))
    assert above.edge == "low" and above.resonance is None and not above.rigid_body
    assert "--f-start-hz" in above.describe(widen_low="widen the band (--f-start-hz)")


def test_structure_resonance_inside_the_band_is_the_closed_form(sdof):
    n = 2000
    band = (0.3 * WN, 3 * WN)
    found = structure_peak(sdof, "wp.x", band, n=n)
    step = (band[1] / band[0]) ** (1 / (n - 1)) - 1               # relative grid step
    assert found.edge is None
    assert abs(found.resonance / W_PEAK - 1) <= step
    assert found.peak == pytest.approx(H_PEAK, rel=1e-6)


def test_a_rigid_body_mode_is_named_and_no_band_is_asked_for():
    # a free slide (4 x 300 kg) carries the work piece: a rigid-body mode and one at
    # sqrt(k (1/m1 + 1/m2)); below that the compliance rises towards 0 Hz without bound
    chain = ModalModel(np.diag([4 * M, M]), [[K, -K], [-K, K]], ["slide.x", "wp.x"],
                       damping_ratio=ZETA)
    w_flex = math.sqrt(K * (1 / (4 * M) + 1 / M))
    assert chain.natural_frequencies()[1] == pytest.approx(w_flex, rel=1e-12)
    found = structure_peak(chain, "wp.x", (TWO_PI * 5, 0.8 * w_flex))
    assert found.edge == "low" and found.rigid_body and found.resonance is None
    text = found.describe()
    assert "rigid-body mode (0 Hz)" in text and "no band can hold it" in text
    assert "widen" not in text


# -- the default band: the requirement band widened for the work-piece modes --------------------

def test_the_default_band_holds_the_mode(sdof):
    band = (TWO_PI * 5, TWO_PI * 50)                  # a requirement band below the mode
    result = mode_band(band, [sdof], "wp.x")
    assert result.modes == pytest.approx((WN,), rel=1e-12)
    assert result.widened and result.band[0] == band[0]
    assert result.band[1] == pytest.approx(BAND_MARGIN * WN, rel=1e-12)
    assert "widened" in result.note() and "112.5" in result.note()
    found = structure_peak(sdof, "wp.x", result.band)
    assert found.edge is None and found.resonance == pytest.approx(W_PEAK, rel=1e-6)
    # a band that holds the mode with the margin is kept
    kept = mode_band((TWO_PI * 5, TWO_PI * 300), [sdof], "wp.x")
    assert not kept.widened and kept.band == pytest.approx((TWO_PI * 5, TWO_PI * 300))


def test_the_default_band_of_a_two_dof_chain():
    # ground -k1- m1 -k2- m2 (the work piece): m1 m2 w^4 - (m1 k2 + m2 (k1 + k2)) w^2 + k1 k2
    # = 0; the mode shape from the second row, x1 = (k2 - m2 w^2) / k2 x2, mass-normalised;
    # the share of the static compliance at m2 is phi2^2 / w^2 over the sum
    m1, m2, k1, k2 = 800.0, 300.0, 4e8, 1.5e8
    b, c = m1 * k2 + m2 * (k1 + k2), k1 * k2
    w2 = np.array([(b - math.sqrt(b * b - 4 * m1 * m2 * c)) / (2 * m1 * m2),
                   (b + math.sqrt(b * b - 4 * m1 * m2 * c)) / (2 * m1 * m2)])
    ratio = (k2 - m2 * w2) / k2
    phi2 = 1 / np.sqrt(m1 * ratio**2 + m2)
    share = phi2**2 / w2 / np.sum(phi2**2 / w2)
    expected = np.sqrt(w2[share >= 0.05])
    model = ModalModel(np.diag([m1, m2]), [[k1 + k2, -k2], [-k2, k2]], ["slide.x", "wp.x"])
    result = mode_band((TWO_PI * 5, TWO_PI * 60), [model], "wp.x")
    assert result.modes == pytest.approx(tuple(expected), rel=1e-9)
    assert result.band[1] == pytest.approx(BAND_MARGIN * expected.max(), rel=1e-9)


def test_a_band_given_by_the_user_replaces_the_default(sdof):
    default = mode_band((TWO_PI * 5, TWO_PI * 300), [sdof], "wp.x")
    assert chosen_band(default) == (default.band, default.note())
    band, note = chosen_band(default, None, 100.0)
    assert band == pytest.approx((TWO_PI * 5, TWO_PI * 100)) and "as given" in note
    with pytest.raises(ValueError, match="start < end"):
        chosen_band(default, 400.0)


# -- the commands on the starter axis of `servotune init` ---------------------------------------

@pytest.fixture(scope="module")
def starter(tmp_path_factory):
    folder = tmp_path_factory.mktemp("init") / "myaxis"
    assert main(["init", str(folder), "--json"]) == 0
    return folder


@pytest.fixture(scope="module")
def starter_mode_hz(starter) -> dict:
    """The work-piece mode of the starter axis from its own matrices: pads locked, and pads on
    the presliding bristle springs sigma0 (axis total, shared by the pads)."""
    data = np.load(starter / "structure.npz")
    mass, stiffness, dofs = data["mass"], data["stiffness"], [str(d) for d in data["dofs"]]
    toml = tomllib.loads((starter / "axis.toml").read_text())
    pads = [dofs.index(p) for p in toml["friction"]["pads"]]
    wp = dofs.index("wp.x")

    def wp_mode(m, k, i_wp):
        w2, phi = scipy.linalg.eigh(k, m)
        share = np.where(w2 > 1e-6 * w2.max(), phi[i_wp] ** 2 / np.maximum(w2, 1e-300), 0.0)
        return math.sqrt(w2[int(np.argmax(share))]) * HZ_PER_RAD_S

    keep = [i for i in range(len(dofs)) if i not in pads]
    locked = wp_mode(mass[np.ix_(keep, keep)], stiffness[np.ix_(keep, keep)], keep.index(wp))
    k_bristle = stiffness.copy()
    for p in pads:
        k_bristle[p, p] += toml["friction"]["lugre"]["sigma0"] / len(pads)
    w2, phi = scipy.linalg.eigh(stiffness, mass)
    return {"locked": locked, "presliding": wp_mode(mass, k_bristle, wp),
            "rigid_moves_wp": bool(abs(w2[0]) < 1e-6 * w2.max() and abs(phi[wp, 0]) > 1e-6)}


def run_json(capsys, argv) -> dict:
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_compliance_default_band_finds_the_mode(starter, starter_mode_hz, tmp_path, capsys):
    # closed loop, pads locked: the work piece on its fixture; the drive holds the slide, the
    # pads are locked, so the resonance lies within 1 % of the structure's mode
    out = run_json(capsys, ["compliance", str(starter), "--contact", "locked", "--no-plots",
                            "--out", str(tmp_path)])
    assert out["peak_at_band_edge"] is None
    assert out["resonance_hz"] == pytest.approx(starter_mode_hz["locked"], rel=0.01)
    assert out["peak_frequency_hz"] == out["resonance_hz"]
    lo, hi = out["default_band"]["band_hz"]
    assert lo <= starter_mode_hz["locked"] / BAND_MARGIN
    assert hi >= starter_mode_hz["locked"] * BAND_MARGIN
    # the paper's Fig 9 curves have no control: the rigid-body mode of the free axis makes
    # the lightly damped ones largest at the band's lower edge, and says so
    assert starter_mode_hz["rigid_moves_wp"]
    light = out["fig9"][0]
    assert light["c"] == 5e3 and light["peak_at_band_edge"] == "low"
    assert light["rigid_body_mode"] is True and light["resonance_hz"] is None


def test_compliance_band_below_the_mode_flags_the_upper_edge(starter, starter_mode_hz,
                                                              tmp_path, capsys):
    argv = ["compliance", str(starter), "--contact", "locked", "--f-start-hz", "10",
            "--f-end-hz", "100", "--no-plots", "--out", str(tmp_path)]
    assert 100.0 < starter_mode_hz["locked"]
    out = run_json(capsys, argv)
    assert out["peak_at_band_edge"] == "high" and out["resonance_hz"] is None
    assert out["peak_compliance"] is None and out["largest_at_hz"] == pytest.approx(100.0)
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "upper edge 100 Hz" in text and "no resonance found inside 10-100 Hz" in text
    assert "widen the band (--f-end-hz)" in text
    assert "rigid-body mode (0 Hz)" in text and "no band can hold it" in text   # Fig 9, C=5e3


def test_nlcompliance_band_edge_and_default_band(starter, starter_mode_hz, tmp_path, capsys):
    # at 268 N peak to peak the pads stay in presliding: the resonance lies between the
    # structure's mode with the pads on the bristle springs alone (the softest they can be)
    # and with the pads locked (the bristle dampers, sigma1 w = 1.1e10 N/m at 112 Hz, nearly
    # lock them), less the 0.1 % of the damped peak and 0.5 % for the drive
    below = run_json(capsys, ["nlcompliance", str(starter), "--force-pp", "268",
                              "--f-start-hz", "10", "--f-end-hz", "100", "--no-plots",
                              "--out", str(tmp_path / "below")])
    curve = below["curves"][0]
    assert curve["peak_at_band_edge"] == "high" and curve["resonance_hz"] is None
    assert curve["peak_compliance_m_per_n"] is None
    assert curve["largest_at_hz"] == pytest.approx(100.0, rel=1e-6)
    assert below["linear_references"]["presliding"]["peak_at_band_edge"] == "high"
    assert below["describing_function"][0]["resonance_hz"] is None
    out = run_json(capsys, ["nlcompliance", str(starter), "--force-pp", "268", "--no-plots",
                            "--out", str(tmp_path / "default")])
    curve = out["curves"][0]
    assert curve["peak_at_band_edge"] is None
    assert (0.995 * starter_mode_hz["presliding"] < curve["resonance_hz"]
            < 1.005 * starter_mode_hz["locked"])
    assert curve["peak_compliance_m_per_n"] == curve["largest_compliance_m_per_n"]
    lo, hi = out["band_hz"]
    assert lo < starter_mode_hz["presliding"] / BAND_MARGIN
    assert hi > starter_mode_hz["presliding"] * BAND_MARGIN
    assert any(n.startswith(f"band {lo:.4g}-{hi:.4g} Hz") for n in out["notes"])


def test_modes_flags_the_rigid_body_mode_and_finds_the_locked_mode(starter, starter_mode_hz,
                                                                   tmp_path, capsys):
    free = run_json(capsys, ["modes", str(starter), "--out", str(tmp_path)])
    assert free["wp_x_rigid_body_mode"] is True and free["wp_x_peak_compliance"] is None
    held = run_json(capsys, ["modes", str(starter), "--pads", "locked", "--out", str(tmp_path)])
    assert held["wp_x_peak_at_band_edge"] is None
    # the damped peak of a 3 % mode lies 0.09 % below it; the other modes move it less
    assert held["wp_x_peak_hz"] == pytest.approx(starter_mode_hz["locked"], rel=0.005)
