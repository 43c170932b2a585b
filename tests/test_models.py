"""The bundled models meet their calibration targets (Bianchi et al. 2014, Table 3), the
reduction of the paper axis agrees with its full model, and ``servotune modes`` reports them."""

import importlib.util
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from numpy.testing import assert_allclose

from servotune.axis import load_axis
from servotune.cli import main

MODELS = Path(__file__).resolve().parents[1] / "models"
TWO_PI = 2 * math.pi


@pytest.fixture(scope="module")
def axis():
    return load_axis(MODELS / "paper_x_axis")


@pytest.fixture(scope="module")
def build():
    spec = importlib.util.spec_from_file_location("paper_build",
                                                  MODELS / "paper_x_axis" / "build.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    yield module
    del sys.modules[spec.name]


def wp_x_mode(model):
    """Frequency [Hz] of the mode with the largest share of work-piece X motion."""
    share = model.participation("wp.x")
    return model.natural_frequencies()[int(share.argmax())] / TWO_PI, share.max()


def test_paper_axis_has_the_papers_layout(axis):
    s = axis.structure
    assert s.n == 41  # as the paper's reduced model
    assert s.dofs[:10] == ("pad1.x", "pad2.x", "pad3.x", "pad4.x", "wp.x", "wp.y", "wp.z",
                           "motor.rotor", "motor.stator", "encoder.x")
    omega = s.natural_frequencies()
    assert omega[0] == 0.0 and omega[1] > 0  # one rigid-body mode: the axis travel
    assert_allclose(s.modal_damping_ratios()[1:], 0.03, rtol=1e-9)


def test_pads_locked_work_piece_mode_is_at_57_hz(axis):
    # Table 3, LuGre at standstill: 57 Hz
    locked = axis.configuration(pads="locked")
    f, share = wp_x_mode(locked)
    assert abs(f - 57.0) < 0.5 and share > 0.9


def test_rotor_held_axis_mode_is_at_32_hz(axis):
    # Table 3, viscous rows: 32 Hz
    held = axis.configuration(pads="free", motor="locked")
    f, share = wp_x_mode(held)
    assert abs(f - 32.0) < 0.5 and share > 0.5


def test_peak_compliances_are_of_the_papers_order(axis):
    # Table 3: about 6e-5 mm/N = 6e-8 m/N. Pads locked the model is calibrated to it; with
    # the rotor held rigidly (no servo damping) the peak is higher, as README.md explains.
    locked = axis.configuration(pads="locked")
    held = axis.configuration(motor="locked")
    band = (TWO_PI * 5.0, TWO_PI * 300.0)
    w_l, peak_l = locked.compliance_peak("wp.x", *band)
    w_h, peak_h = held.compliance_peak("wp.x", *band)
    assert_allclose(peak_l, 6e-8, rtol=0.05)
    assert 2e-8 < peak_h < 2e-7
    assert abs(w_l / TWO_PI - 57.0) < 1.0 and abs(w_h / TWO_PI - 32.0) < 1.0
    # second method: python-control's frequency response of the state-space model
    for model, w, peak in ((locked, w_l, peak_l), (held, w_h, peak_h)):
        sys = model.to_state_space(inputs=["wp.x"], outputs=["wp.x"])
        assert_allclose(abs(sys(1j * w)), peak, rtol=1e-8)
        grid = np.linspace(band[0], band[1], 3000)
        assert np.abs(sys(1j * grid)).max() <= peak * (1 + 1e-9)


def test_reduced_model_matches_the_full_model(axis, build):
    # Craig-Bampton check on the bundled model: the 57 Hz mode of the full 591-DOF model with
    # the pads locked is reproduced from above within 0.1 %
    mass, stiffness, dofs, _ = build.build_full(build.Calibration())
    keep = [i for i, d in enumerate(dofs) if d not in build.PADS]
    sub = np.ix_(keep, keep)
    lam = scipy.linalg.eigh(mass.toarray()[sub], stiffness.toarray()[sub], eigvals_only=True)
    full = np.sort(1 / np.sqrt(lam[::-1][:15])) / TWO_PI
    reduced = axis.configuration(pads="locked").natural_frequencies()[:15] / TWO_PI
    f57 = wp_x_mode(axis.configuration(pads="locked"))[0]
    j = int(np.argmin(abs(reduced - f57)))
    assert reduced[j] >= full[j] * (1 - 1e-9)
    assert_allclose(reduced[j], full[j], rtol=1e-3)
    assert_allclose(reduced[:5], full[:5], rtol=1e-3)


def test_build_script_reproduces_the_bundled_files(tmp_path, build, axis):
    result = build.main(["--out", str(tmp_path)])
    rebuilt = load_axis(tmp_path)
    assert rebuilt.structure.dofs == axis.structure.dofs
    assert_allclose(rebuilt.structure.natural_frequencies(), axis.structure.natural_frequencies(),
                    rtol=1e-7, atol=1e-6)
    stored = json.loads((MODELS / "paper_x_axis" / "calibration.json").read_text())
    assert_allclose(result["measured"]["pads_locked"]["wp_x_mode_hz"],
                    stored["measured"]["pads_locked"]["wp_x_mode_hz"], rtol=1e-6)
    bundled = (MODELS / "paper_x_axis" / "axis.toml").read_text()
    assert (tmp_path / "axis.toml").read_text() == bundled
    # the transmission ratio is lead / (2 pi) / belt ratio
    assert_allclose(rebuilt.drive["transmission"]["ratio"], 0.020 / TWO_PI / 2.0, rtol=1e-6)


def test_modes_command_reports_the_57_hz_mode(capsys):
    assert main(["modes", str(MODELS / "paper_x_axis"), "--pads", "locked", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    f = np.array(result["frequencies_hz"])
    share = np.array(result["wp_x_participation"])
    assert len(f) == len(share) == 37
    assert_allclose(share.sum(), 1.0, rtol=1e-12)
    assert abs(f[share.argmax()] - 57.0) < 0.5 and abs(result["wp_x_mode_hz"] - 57.0) < 0.5
    assert_allclose(result["wp_x_peak_compliance"], 6e-8, rtol=0.05)
    assert result["rigid_body_modes"] == 0


def test_modes_command_free_axis_and_text(capsys):
    assert main(["modes", str(MODELS / "paper_x_axis"), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["rigid_body_modes"] == 1 and result["frequencies_hz"][0] == 0.0
    assert result["wp_x_participation"][0] == 0.0 and result["damping_ratios"][0] is None
    assert result["wp_x_peak_compliance"] is None
    assert main(["modes", str(MODELS / "two_mass_fig5"), "--pads", "locked"]) == 0
    out = capsys.readouterr().out
    assert "16.44" in out and "work piece X" in out  # sqrt(K/M2) / 2 pi


def test_modes_command_errors(tmp_path, capsys):
    assert main(["modes", str(tmp_path)]) == 1
    assert "no axis description here" in capsys.readouterr().err
    assert main(["modes", str(MODELS / "two_mass_fig5"), "--motor", "locked"]) == 1
    assert "[drive.motor] rotor is missing" in capsys.readouterr().err
