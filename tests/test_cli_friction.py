"""``servotune friction`` and ``servotune friction fit``, called in-process."""

import json
import math

import numpy as np
import pytest

from servotune.cli import main
from servotune.friction import lugre
from servotune.friction.lugre import BIANCHI2014


def test_friction_json_has_the_equivalent_damping(tmp_path, capsys):
    assert main(["friction", "--amplitude", "2e-6", "--frequency-hz", "20", "--json",
                 "--out", str(tmp_path)]) == 0
    result = json.loads(capsys.readouterr().out)
    w = 2 * math.pi * 20.0
    a, fs, s0 = 2e-6, 6013.0, 5.9e9
    # the corrected Eq 9 written out (Bianchi et al. 2014, sec 4.2, area 4 Fs (A - Fs/sigma0))
    assert result["ceq_stiction"] == pytest.approx(4 * fs * (a - fs / s0) / (math.pi * w * a * a),
                                                   rel=1e-12)
    assert result["ceq_stiction_max"] == pytest.approx(s0 / (math.pi * w), rel=1e-12)
    assert result["ceq_lugre"] > result["ceq_stiction"] > 0.0
    assert 0.0 < result["keq_lugre"] < s0
    assert [row["amplitude"] for row in result["table"]] == [1e-6, 2e-6, 5e-6]
    folder = tmp_path / "friction_bianchi2014"
    assert result["folder"] == str(folder)
    for name in ("stribeck.png", "hysteresis.png", "equivalent_damping.png"):
        assert (folder / name).stat().st_size > 10_000
    assert json.loads((folder / "results.json").read_text()) == result


def test_friction_text_output(tmp_path, capsys):
    assert main(["friction", "--params", "canudas1995", "--no-plots", "--out",
                 str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "canudas1995" in out and "Ceq" in out
    assert not list((tmp_path / "friction_canudas1995").glob("*.png"))


def test_friction_with_micro_damping(tmp_path, capsys):
    # large strokes at 20 Hz (v up to 0.63 m/s >> vs, v_d): Coulomb plus viscous (the
    # classical describing function of a Coulomb slider, 4 Fc / (pi w A), plus sigma2)
    assert main(["friction", "--amplitude", "5e-3", "--sigma1-decay-speed", "1e-3", "--json",
                 "--no-plots", "--out", str(tmp_path)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["parameters"]["sigma1_decay_speed"] == 1e-3
    w = 2 * math.pi * 20.0
    coulomb = 4 * BIANCHI2014.fc / (math.pi * w * 5e-3) + BIANCHI2014.sigma2
    assert result["ceq_lugre"] == pytest.approx(coulomb, rel=0.03)
    assert main(["friction", "--sigma1-decay-speed", "1e-3", "--no-plots", "--out",
                 str(tmp_path)]) == 0
    assert "sigma1 decay speed = 0.001 m/s" in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["friction", "--amplitude=-1e-6"], "--amplitude"),
    (["friction", "--frequency-hz", "0"], "--frequency-hz"),
    (["friction", "--sigma1-decay-speed", "0"], "--sigma1-decay-speed"),
])
def test_friction_bad_input(argv, message, tmp_path, capsys):
    assert main([*argv, "--no-plots", "--out", str(tmp_path)]) == 2
    assert message in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def write_csv(path, header, columns):
    rows = "\n".join(",".join(f"{x:.12g}" for x in row) for row in zip(*columns, strict=True))
    path.write_text(header + "\n" + rows + "\n")


def test_fit_steady_state_from_csv(tmp_path, capsys):
    rng = np.random.default_rng(42)
    speeds = np.geomspace(2e-4, 0.5, 25)
    v = np.concatenate([-speeds, speeds])
    f = lugre.steady_state_friction(BIANCHI2014, v) + rng.normal(0.0, 60.0, v.size)
    data = tmp_path / "stribeck.csv"
    write_csv(data, "v_m_per_s,f_n", [v, f])
    assert main(["friction", "fit", str(data), "--fix", "delta=1", "--json",
                 "--out", str(tmp_path)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["fixed"] == {"delta": 1.0}
    for name, value in result["estimates"].items():
        assert abs(value - getattr(BIANCHI2014, name)) < 4 * result["standard_errors"][name]
    assert (tmp_path / "friction_fit_stribeck" / "fit_stribeck.png").stat().st_size > 10_000


def test_fit_presliding_from_csv(tmp_path, capsys):
    rng = np.random.default_rng(43)
    t = np.linspace(0.0, 3.7, 600)
    x = 10e-6 * np.sin(2 * math.pi * t / 3.7)
    f = lugre.simulate_lugre(BIANCHI2014, t, displacement=x).force + rng.normal(0, 60, t.size)
    data = tmp_path / "presliding.csv"
    write_csv(data, "t_s,x_um,f_n", [t, x * 1e6, f])
    assert main(["friction", "fit", str(data), "--no-plots", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "sigma0" in out and "sigma1" in out
    assert main(["friction", "fit", str(data), "--json", "--out", str(tmp_path)]) == 0
    result = json.loads(capsys.readouterr().out)
    s0, se = result["estimates"]["sigma0"], result["standard_errors"]["sigma0"]
    assert abs(s0 - BIANCHI2014.sigma0) < 4 * se
    assert (tmp_path / "friction_fit_presliding" / "fit_presliding.png").exists()
    # --json given before the sub-subcommand counts too
    assert main(["friction", "--json", "fit", str(data), "--no-plots", "--out",
                 str(tmp_path)]) == 0
    assert json.loads(capsys.readouterr().out)["estimates"]["sigma0"] == s0


def test_fit_refuses_unreadable_and_ill_posed_data(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("speed,torque\n1,2\n")
    assert main(["friction", "fit", str(bad), "--no-plots", "--out", str(tmp_path)]) == 1
    assert "v_m_per_s,f_n" in capsys.readouterr().err
    one_sided = tmp_path / "one_sided.csv"
    v = np.geomspace(1e-4, 0.5, 30)
    write_csv(one_sided, "v_m_per_s,f_n", [v, lugre.steady_state_friction(BIANCHI2014, v)])
    assert main(["friction", "fit", str(one_sided), "--no-plots", "--out", str(tmp_path)]) == 1
    assert "one sign" in capsys.readouterr().err
    assert main(["friction", "fit", str(one_sided), "--fix", "delta", "--no-plots", "--out",
                 str(tmp_path)]) == 1
    assert "NAME=VALUE" in capsys.readouterr().err
