"""The drive's measured speed plant (``servotune identify --kind speed-plant``).

References, best first:

* the velocity loop closed on a speed plant (``velocity_loop_response``: the winding, the
  zero-order hold as an alias sum, the controllers' difference equations) against the model's
  own loop (``SampledAxis.loop_response``: the plant discretised by the matrix exponential,
  stability from the monodromy multipliers; ``loop_transfer`` for the continuous drive): two
  independent computations of one loop, within the alias sum's truncation (1e-5);
* the Nyquist count against closed forms (``k / (s + 1)^3``) and against the model's
  multipliers;
* the done-when test of issue #30: the model's speed plant written as UFF 58 and CSV, read back
  by ``servotune identify --kind speed-plant --axis``, gives the margins of
  ``servotune bode --contact stiction``. The tolerance is the grid's: the margins are
  interpolated between lines, so the same model loop on the measurement's lines (the
  ``model`` entry of the JSON) and on ``bode``'s 8001 log-spaced points differs by the
  grid's share; the measured margins must lie within twice that (plus 1e-5 relative for the
  aliases above the last line, seen through the inertia line). A plant 25 % off gives
  margins far outside it.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from servotune.analysis import axis_contact
from servotune.axis import load_axis
from servotune.cli import main
from servotune.closed_loop import closed_loop
from servotune.measured import MeasuredFrf, compare_speed_plant, model_speed_plant
from servotune.measured.frf import read_frf_csv, read_frf_uff
from servotune.measured.speed_plant import encircled_poles, velocity_loop_response

MODELS = Path(__file__).resolve().parents[1] / "models"
#: the measurement's lines: 0 to 4 kHz (the velocity controller's Nyquist frequency at
#: 125 us) every 0.5 Hz, as a drive's measuring function records them
F_HZ = np.arange(0.0, 4000.0 + 1e-9, 0.5)
#: the axes: the paper's with its continuous drive, and one with a stable digital drive
CASES = {"paper_x_axis": ["--continuous"], "weak_motor_axis": []}
KEYS = ("gain_margin_db", "phase_margin_deg", "ms", "bandwidth_hz", "crossover_hz",
        "phase_crossover_hz")


def axis_of(name: str, continuous: bool = False):
    axis = load_axis(MODELS / name)
    return axis.with_continuous_drive() if continuous else axis


def speed_plant(name: str, scale: float = 1.0) -> np.ndarray:
    """The model's speed plant on F_HZ, times ``scale``."""
    axis = axis_of(name)
    return scale * model_speed_plant(axis.structure, axis.require_drive(), 2 * np.pi * F_HZ,
                                     axis_contact(axis, "stiction"), axis.pads)


def write_uff(path: Path, values: np.ndarray) -> Path:
    """One dataset 58: angular velocity (type 11 about +RZ) over moment (type 13 about +RZ)."""
    import pyuff

    uff = pyuff.UFF(str(path))
    uff.write_sets([pyuff.prepare_58(
        binary=0, func_type=4, rsp_node=1, rsp_dir=6, ref_node=1, ref_dir=6, data=values,
        x=F_HZ, id1="speed plant", rsp_ent_name="motor", ref_ent_name="motor",
        abscissa_spacing=1, abscissa_spec_data_type=18, ordinate_spec_data_type=11,
        orddenom_spec_data_type=13)], mode="overwrite")
    return path


def write_csv(path: Path, values: np.ndarray) -> Path:
    """Magnitude in rpm/N m and phase in degrees, as a drive's export may give them."""
    rpm = np.abs(values) * 60 / (2 * np.pi)
    lines = [f"{f:.10g},{m:.17g},{p:.17g}" for f, m, p in
             zip(F_HZ, rpm, np.rad2deg(np.angle(values)), strict=True)]
    path.write_text("# quantity: speed per torque\n# units: rpm/N m\nf_hz,mag,phase_deg\n"
                    + "\n".join(lines) + "\n")
    return path


def run_json(argv, capsys) -> dict:
    assert main([*argv, "--json", "--no-plots", "--quiet"]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("name, slower", [("paper_x_axis", False), ("weak_motor_axis", False),
                                          ("weak_motor_axis", True)])
def test_the_loop_on_the_model_plant_is_the_model_loop(name, slower):
    """``slower``: the speed controller every 250 us (two current periods: the lifted loop)
    with a 0.2 ms speed filter."""
    axis = axis_of(name, continuous=bool(CASES[name]))
    drive, contact = axis.require_drive(), axis_contact(axis, "stiction")
    top = 3900.0
    if slower:
        drive = dataclasses.replace(drive, sampling=dataclasses.replace(
            drive.sampling, velocity_period=250e-6, speed_filter=2e-4))
        top = 1950.0
    omega = 2 * np.pi * np.geomspace(0.5, top, 400)

    def plant(w):
        return model_speed_plant(axis.structure, drive, w, contact, axis.pads)

    mine = velocity_loop_response(drive, plant, omega)
    theirs = closed_loop(axis.structure, drive, contact, axis.pads).loop_response("velocity",
                                                                                  omega)
    np.testing.assert_allclose(mine, theirs, rtol=1e-5)


@pytest.mark.parametrize("k, unstable", [(7.0, 0), (10.0, 2)])
def test_the_nyquist_count_of_a_third_order_loop(k, unstable):
    # 1 + k/(s+1)^3 = 0: s = -1 + k^(1/3) exp(j pi (2m+1)/3), two in the right half plane
    # when k^(1/3) cos 60 deg > 1, i.e. k > 8
    w = np.geomspace(1e-3, 1e3, 20001)
    assert encircled_poles(k / (1j * w + 1) ** 3) == unstable


def test_the_unstable_digital_paper_axis_is_unstable_on_its_measured_plant():
    """The paper's velocity PI (Kp 35 N m s/rad) with the sampled drive: the model's
    multipliers say unstable (two growing pairs); the Nyquist count on the measured plant
    finds the same four poles."""
    axis = axis_of("paper_x_axis")
    contact = axis_contact(axis, "stiction")
    frf = MeasuredFrf(2 * np.pi * F_HZ, speed_plant("paper_x_axis"), "speed_per_torque",
                      "model", "model.csv")
    c = compare_speed_plant(frf, axis.structure, axis.require_drive(), contact, axis.pads)
    assert c.model_loop is None and "unstable" in c.model_unstable
    assert c.measured_unstable_poles == 4
    assert c.velocity_loop()["stable"] is False


def test_the_speed_plant_reads_back_from_uff_and_csv(tmp_path):
    values = speed_plant("weak_motor_axis")
    uff = read_frf_uff(write_uff(tmp_path / "plant.uff", values))[0]
    csv = read_frf_csv(write_csv(tmp_path / "plant.csv", values))
    for frf in (uff, csv):
        assert frf.quantity == "speed_per_torque" and frf.unit == "rad/s/N m"
        np.testing.assert_allclose(frf.omega, 2 * np.pi * F_HZ, rtol=1e-12)
        np.testing.assert_allclose(frf.values, values, rtol=1e-9, atol=1e-12 * abs(values).max())


@pytest.fixture(scope="module")
def bode(tmp_path_factory):
    """``servotune bode NAME --contact stiction`` of each axis: its velocity loop."""
    out = {}
    for name, extra in CASES.items():
        folder = tmp_path_factory.mktemp("bode")
        argv = ["bode", str(MODELS / name), "--contact", "stiction", *extra, "--json",
                "--no-plots", "--quiet", "--out", str(folder)]
        import contextlib
        import io

        buffer = io.StringIO()
        with contextlib.redirect_stdout(buffer):
            assert main(argv) == 0
        out[name] = json.loads(buffer.getvalue())["velocity_loop"]
    return out


def tolerance(key: str, model_on_lines: dict, reference: dict) -> float:
    """The grid's share of a margin (twice it), plus 1e-5 relative for the aliases above the
    last line."""
    a, b = model_on_lines[key], reference[key]
    if a is None or b is None:
        return 0.0
    return 2 * abs(a - b) + 1e-5 * abs(b)


def agree(measured: dict, model: dict, reference: dict) -> None:
    for key in KEYS:
        m, r = measured[key], reference[key]
        assert (m is None) == (r is None), (key, m, r)
        if m is not None:
            tol = tolerance(key, model, reference)
            assert abs(m - r) <= tol, f"{key}: measured {m}, bode {r}, tolerance {tol}"


@pytest.mark.parametrize("name, fmt", [("paper_x_axis", "uff"), ("weak_motor_axis", "uff"),
                                       ("weak_motor_axis", "csv")])
def test_a_measured_speed_plant_gives_the_margins_of_its_model(name, fmt, bode, tmp_path,
                                                                capsys):
    writer = write_uff if fmt == "uff" else write_csv
    path = writer(tmp_path / f"plant.{fmt}", speed_plant(name))
    out = run_json(["identify", str(path), "--kind", "speed-plant", "--axis",
                    str(MODELS / name), *CASES[name], "--out", str(tmp_path / "out")], capsys)
    assert out["kind"] == "speed-plant" and out["quantity"] == "speed_per_torque"
    assert out["frf_error"] < 1e-6
    loop = out["velocity_loop"]
    assert loop["drive"] == ("continuous" if CASES[name] else "sampled")
    assert loop["stable"] is True and loop["model"]["stable"] is True
    assert {k: loop[k] for k in KEYS} == {k: loop["measured"][k] for k in KEYS}
    agree(loop["measured"], loop["model"], bode[name])
    # the grid's share is what the tolerance says it is: small against the margins
    assert abs(loop["phase_margin_deg"] - bode[name]["phase_margin_deg"]) < 0.01
    assert abs(loop["ms"] / bode[name]["ms"] - 1) < 1e-3


def test_a_plant_a_quarter_off_gives_other_margins(bode, tmp_path, capsys):
    """The same plant 25 % larger (a torque constant 25 % above the drive's): the gain margin
    falls by 20 log10 1.25 = 1.94 dB, far outside the grid's tolerance."""
    name = "weak_motor_axis"
    path = write_uff(tmp_path / "plant.uff", speed_plant(name, scale=1.25))
    out = run_json(["identify", str(path), "--kind", "speed-plant", "--axis",
                    str(MODELS / name), "--out", str(tmp_path / "out")], capsys)
    assert out["frf_error"] == pytest.approx(0.2, rel=1e-6)   # |1.25 P - P| / |1.25 P|
    loop, reference = out["velocity_loop"], bode[name]
    for key in ("gain_margin_db", "crossover_hz", "ms"):
        tol = tolerance(key, loop["model"], reference)
        assert abs(loop["measured"][key] - reference[key]) > 10 * tol, key
    assert loop["difference"]["gain_margin_db"] == pytest.approx(-20 * math.log10(1.25),
                                                                 abs=0.01)


def test_the_command_writes_its_figure_and_text(tmp_path, capsys):
    path = write_uff(tmp_path / "plant.uff", speed_plant("weak_motor_axis"))
    assert main(["identify", str(path), "--kind", "speed-plant", "--axis",
                 str(MODELS / "weak_motor_axis"), "--quiet", "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "the loop on the measurement: stable" in text and "the model" in text
    assert (tmp_path / "identify_plant" / "speed_plant.png").is_file()


@pytest.mark.parametrize("argv, words", [
    (["--kind", "closed-loop"], "is a speed per torque, the drive's speed plant: give --kind "
                                "speed-plant"),
    (["--kind", "speed-plant"], "give --axis AXIS"),
    (["--kind", "speed-plant", "--axis", str(MODELS / "weak_motor_axis"), "--dof", "wp.x"],
     "--dof: not with --kind speed-plant"),
    ([], "is a speed per torque, the drive's speed plant: give --kind speed-plant"),
])
def test_what_the_speed_plant_does_not_take_is_a_usage_error(argv, words, tmp_path, capsys):
    path = write_csv(tmp_path / "plant.csv", np.linspace(1, 2, F_HZ.size) / (1j * F_HZ + 1))
    assert main(["identify", str(path), *argv, "--out", str(tmp_path / "out")]) == 2
    assert words in capsys.readouterr().err


def test_a_measurement_that_stops_short_of_the_nyquist_frequency_is_flagged():
    """Lines up to 2 kHz only (the controller's Nyquist frequency is 4 kHz): the phase
    crossover at 921 Hz is still on the lines and its margin the model's; the contour is closed
    at 4 kHz through the inertia line, and the output says what the lines do not show."""
    axis = axis_of("weak_motor_axis")
    keep = F_HZ <= 2000.0
    frf = MeasuredFrf(2 * np.pi * F_HZ[keep], speed_plant("weak_motor_axis")[keep],
                      "speed_per_torque", "short", "short.csv")
    c = compare_speed_plant(frf, axis.structure, axis.require_drive(),
                            axis_contact(axis, "stiction"), axis.pads)
    assert any("ends at 2000 Hz, below the velocity controller's Nyquist frequency 4000 Hz"
               in w for w in c.warnings)
    assert c.measured_unstable_poles == 0
    assert c.measured_loop.gain_margin_db == pytest.approx(c.model_loop.gain_margin_db,
                                                           abs=1e-4)


@pytest.mark.parametrize("content, words", [
    ("# quantity: receptance\nf_hz,re,im\n1,1e-6,0\n2,1e-6,0\n",
     "plant.csv, line 1: the file states a receptance, but a speed_per_torque was asked for"),
    ("f_hz,re,im\n1,1,0\n2,1,0\n3,-1,0\n",
     "plant.csv: the measured speed plant does not fall as an inertia 1/(j w J)"),
])
def test_a_file_that_is_no_speed_plant_is_a_clear_error(content, words, tmp_path, capsys):
    path = tmp_path / "plant.csv"
    path.write_text(content)
    assert main(["identify", str(path), "--kind", "speed-plant", "--axis",
                 str(MODELS / "weak_motor_axis"), "--no-plots",
                 "--out", str(tmp_path / "out")]) == 1
    assert words in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
