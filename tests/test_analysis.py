"""Linear analyses of the bundled axis against the paper's Table 3, and the bode/compliance
commands."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from servotune import analysis
from servotune.axis import load_axis
from servotune.cli import main
from servotune.plant import Contact
from servotune.units import HZ_PER_RAD_S

MODELS = Path(__file__).resolve().parents[1] / "models"


@pytest.fixture(scope="module")
def axis():
    # the paper's model: the drive in continuous time (sec 3)
    return load_axis(MODELS / "paper_x_axis").with_continuous_drive()


def test_bundled_drive_reproduces_table3_resonances(axis):
    # Table 3: LuGre at standstill resonates at 57 Hz (pads stuck), viscous-only at 32 Hz,
    # both with a work-piece oscillation of about 6e-5 mm/N = 6e-8 m/N
    omega = analysis.default_omega(5.0, 300.0, 3000)
    locked = analysis.compliance_curve(axis, Contact.locked(), omega=omega)
    viscous = analysis.compliance_curve(axis, analysis.axis_contact(axis, "viscous"),
                                        omega=omega)
    assert locked.peak_frequency * HZ_PER_RAD_S == pytest.approx(57.0, abs=1.0)
    assert viscous.peak_frequency * HZ_PER_RAD_S == pytest.approx(32.0, abs=1.5)
    for curve in (locked, viscous):
        assert 4e-8 < curve.peak_compliance < 9e-8


def test_stiction_linearisation_is_close_to_locked_pads(axis):
    # sigma0 = 5.9e9 N/m against the structure: the pads are nearly held
    omega = analysis.default_omega(40.0, 80.0, 800)
    locked = analysis.compliance_curve(axis, Contact.locked(), omega=omega)
    stiction = analysis.compliance_curve(axis, analysis.axis_contact(axis, "stiction"),
                                         omega=omega)
    assert stiction.peak_frequency == pytest.approx(locked.peak_frequency, rel=0.03)


def test_fig9_large_damping_tends_to_locked_pads(axis):
    # no control: C -> infinity is the structure with the pads held (its own receptance)
    omega = analysis.default_omega(20.0, 200.0, 400)
    big = analysis.uncontrolled_compliance(axis, [1e11], omega)[0]
    held = axis.structure.locked(list(axis.pads)).receptance(omega, ["wp.x"], ["wp.x"])[:, 0, 0]
    assert_allclose(big.values, held, rtol=2e-3)


def test_loops_of_the_bundled_drive_are_stable_with_margins(axis):
    loops = analysis.loop_report(axis, analysis.axis_contact(axis, "viscous"),
                                 omega=analysis.default_omega(0.1, 3000.0, 4000))
    # the position loop crosses over near Kv/(2 pi) for a fast velocity loop
    assert loops.position.crossover == pytest.approx(axis.drive.kv, rel=0.05)
    assert loops.velocity.phase_margin_deg > 30 and loops.velocity.ms < 2.0
    assert 1.0 < loops.position.ms < 3.0


def test_bode_command_json(tmp_path, capsys):
    assert main(["bode", str(MODELS / "paper_x_axis"), "--continuous", "--out", str(tmp_path),
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    for loop in ("velocity_loop", "position_loop"):
        for key in ("phase_margin_deg", "gain_margin_db", "ms", "bandwidth_hz"):
            assert key in out[loop]
    assert out["kv_m_per_min_per_mm"] == pytest.approx(1.0)
    assert Path(out["figures"][0]).stat().st_size > 10_000


def test_compliance_command_json_and_contacts(tmp_path, capsys):
    assert main(["compliance", str(MODELS / "paper_x_axis"), "--contact", "locked",
                 "--continuous", "--out", str(tmp_path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["peak_frequency_hz"] == pytest.approx(57.0, abs=1.0)
    assert len(out["fig9"]) == 5 and out["peak_compliance"] > 0
    # the describing-function contact needs its amplitude and frequency
    assert main(["compliance", str(MODELS / "paper_x_axis"), "--contact", "equivalent",
                 "--continuous", "--out", str(tmp_path), "--force"]) == 1
    assert "amplitude" in capsys.readouterr().err
    assert main(["compliance", str(MODELS / "paper_x_axis"), "--contact", "equivalent",
                 "--amplitude", "2e-6", "--frequency-hz", "57", "--out", str(tmp_path),
                 "--continuous", "--force", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert "describing function" in out["contact_note"]


def test_two_mass_compliance_without_drive(tmp_path, capsys):
    # the Fig 5 model has no drive: the compliance is the uncontrolled one with C = Copt
    assert main(["compliance", str(MODELS / "two_mass_fig5"), "--out", str(tmp_path),
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    g = (1 - 0.3 + math.sqrt(1 + 0.3**2)) / 0.3  # g(alpha), Eq 7
    assert out["controlled"] is False
    assert out["peak_compliance"] == pytest.approx(g / 16e6, rel=1e-3)
    assert np.isfinite(out["peak_frequency_hz"])


def test_the_bundled_gains_are_unstable_with_the_digital_drive_and_the_error_says_so(tmp_path,
                                                                                   capsys):
    # the paper's velocity loop (kp = 35 N m s/rad, crossover ~540 Hz in continuous time) loses
    # more phase to a 125 us drive's 250 us of loop delay (2 pi 540 Hz x 250 us = 49 deg) than
    # its margin of 57 deg minus what the sampled current loop costs: unstable
    assert main(["bode", str(MODELS / "paper_x_axis"), "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "unstable" in err and "--continuous" in err and "[drive.sampling]" in err


def test_a_compliance_peak_at_the_band_edge_is_flagged(tmp_path, capsys):
    # the starter axis resonates near 112 Hz (standing, locked pads): over 5-300 Hz the peak
    # is that resonance; over 150-300 Hz the largest value is at 150 Hz, the band's edge, and
    # the command says so instead of reporting it as a peak
    from servotune.cli import main
    from servotune.template import write_template

    write_template(tmp_path / "ax")
    assert main(["compliance", str(tmp_path / "ax"), "--contact", "locked", "--json",
                 "--no-plots", "--out", str(tmp_path / "o")]) == 0
    inside = json.loads(capsys.readouterr().out)
    assert 100.0 < inside["peak_frequency_hz"] < 125.0 and inside["peak_at_edge"] is False
    text = (tmp_path / "ax" / "axis.toml").read_text()
    (tmp_path / "ax" / "axis.toml").write_text(text.replace("band_hz = [5.0, 300.0]",
                                                            "band_hz = [150.0, 300.0]"))
    assert main(["compliance", str(tmp_path / "ax"), "--contact", "locked", "--no-plots",
                 "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert "AT THE BAND EDGE (150-300 Hz)" in out
