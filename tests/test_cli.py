"""The command line, called in-process through ``main([...])``."""

import json

import numpy as np
import pytest

from servotune import twomass
from servotune.cli import main


def test_twomass_json_has_the_keys_and_values(tmp_path, capsys):
    assert main(["twomass", "--m1", "5000", "--k", "16e6", "--alpha", "0.3",
                 "--out", str(tmp_path), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    for key in ("fixed_points_hz", "c_opt", "peak_compliance", "peak_frequency_hz",
                "resonance_c0_hz", "resonance_cinf_hz"):
        assert key in result
    np.testing.assert_allclose(result["c_opt"], 4.912e5, rtol=1e-4)
    np.testing.assert_allclose(result["peak_compliance"], twomass.g_alpha(0.3) / 16e6)
    assert len(result["fixed_points_hz"]) == 2
    for name in ("fig5_compliance_layout_B.png", "fig4_g_alpha.png"):
        assert (tmp_path / name).stat().st_size > 10_000


def test_twomass_text_and_layout_a(tmp_path, capsys):
    assert main(["twomass", "--layout", "A", "--no-plots", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "Copt" in out and "layout A" in out
    assert not any(tmp_path.iterdir())


def test_existing_figures_are_not_overwritten(tmp_path, capsys):
    target = tmp_path / "fig4_g_alpha.png"
    target.write_bytes(b"keep me")
    assert main(["twomass", "--out", str(tmp_path)]) == 1
    assert "--force" in capsys.readouterr().err
    assert target.read_bytes() == b"keep me"
    assert not (tmp_path / "fig5_compliance_layout_B.png").exists()
    assert main(["twomass", "--out", str(tmp_path), "--force"]) == 0
    assert target.read_bytes() != b"keep me"


@pytest.mark.parametrize("argv", [["twomass", "--alpha", "-1"], ["twomass", "--k", "0"]])
def test_bad_input_is_a_clear_error(argv, capsys, tmp_path):
    assert main([*argv, "--out", str(tmp_path)]) == 1
    assert "must be a positive" in capsys.readouterr().err
