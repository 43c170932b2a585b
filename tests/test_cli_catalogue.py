"""A catalogue of bad inputs across every command: each ends in a clear error.

For each case: the exit status (2 for a flag argparse refuses, 1 for anything else), a message
on standard error that names what was wrong (the field, the flag, the file), no traceback, no
"internal error", and nothing written (every file under the test's folder, the current folder
included, is the same before and after).

A case is a small fixture: a function that prepares files in the test's folder and returns the
command line. Cases that the code does not handle yet are marked xfail (strict) with the reason,
so that they stay visible and turn into failures the day they are fixed.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from servotune.cli import main
from servotune.template import template_toml, write_template

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "models" / "paper_x_axis"


# --------------------------------------------------------------------------- fixtures

@pytest.fixture(scope="module")
def starter(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("starter") / "cat"
    write_template(folder, name="cat")
    return folder


def axis(tmp, starter, change=None, drop=()) -> str:
    """A copy of the starter axis in ``tmp/axis`` with ``change(text)`` applied to axis.toml
    and the sections in ``drop`` removed."""
    folder = tmp / "axis"
    shutil.copytree(starter, folder)
    text = template_toml("cat")
    for section in drop:
        text = _drop(text, section)
    if change is not None:
        new = change(text)
        assert new != text, "the fixture changed nothing"
        text = new
    (folder / "axis.toml").write_text(text)
    return str(folder)


def _drop(text: str, section: str) -> str:
    """Remove ``[section]`` and its sub-tables from a TOML text."""
    out, skipping = [], False
    for line in text.splitlines(keepends=True):
        header = re.match(r"\[([a-z_.]+)\]", line)
        if header:
            name = header.group(1)
            skipping = name == section or name.startswith(section + ".")
        if not skipping:
            out.append(line)
    result = "".join(out)
    assert result != text, f"no [{section}] in the template"
    return result


def sub(old: str, new: str):
    """A change of axis.toml: replace ``old`` (which must be there) by ``new``."""
    def change(text: str) -> str:
        assert old in text, old
        return text.replace(old, new)
    return change


def npz(tmp, name="m.npz", **arrays) -> str:
    path = tmp / name
    np.savez(path, **arrays)
    return str(path)


def text_file(tmp, name, content) -> str:
    path = tmp / name
    path.write_text(content)
    return str(path)


def spring_mass(n=3, scale=1.0):
    m = np.eye(n) * 10.0 * scale
    k = 2e6 * np.eye(n) - 1e6 * np.eye(n, k=1) - 1e6 * np.eye(n, k=-1)
    return m, k


def mtx(tmp, name, matrix) -> str:
    from scipy.io import mmwrite

    path = tmp / name
    mmwrite(str(path), matrix)
    return str(path)


def stribeck_csv(tmp, name="stribeck.csv", rows=None, header="v_m_per_s,f_n") -> str:
    if rows is None:
        v = np.concatenate([-np.geomspace(1e-4, 0.5, 20), np.geomspace(1e-4, 0.5, 20)])
        rows = [(x, 2000.0 * np.sign(x) + 5000.0 * x) for x in v]
    body = "\n".join(",".join(f"{c:.9g}" if isinstance(c, float) else str(c) for c in r)
                     for r in rows)
    return text_file(tmp, name, header + "\n" + body + "\n")


def frf_csv(tmp, content) -> str:
    return text_file(tmp, "frf.csv", content)


MODE = ["--mode", "922", "0.011", "1.34e6"]


def xfail(reason):
    return pytest.mark.xfail(reason=reason, strict=True)


# --------------------------------------------------------------------------- the catalogue
# (id, fixture: (tmp, starter) -> argv, exit status, words that must be in the message)

CASES = [
    # ---- axis files (read by `modes`, the quickest command that loads an axis)
    ("axis-missing-toml", lambda t, s: ["modes", str(t)], 1, "no axis description"),
    ("axis-missing-folder", lambda t, s: ["modes", str(t / "nowhere")], 1, "nowhere"),
    ("axis-invalid-toml", lambda t, s: ["modes", axis(t, s, sub("[axis]", "[axis"))], 1,
     "not valid TOML"),
    ("axis-duplicate-key", lambda t, s: ["modes", axis(t, s, sub(
        "teeth = 4", "teeth = 4\nteeth = 5"))], 1, "not valid TOML"),
    ("axis-unknown-section", lambda t, s: ["modes", axis(t, s, sub("[axis]", "[axes]"))], 1,
     "axes"),
    ("axis-no-name", lambda t, s: ["modes", axis(t, s, sub('name = "cat"', 'nom = "cat"'))], 1,
     "[axis] name"),
    ("axis-empty-name", lambda t, s: ["modes", axis(t, s, sub('name = "cat"', 'name = ""'))], 1,
     "[axis] name"),
    ("axis-no-structure", lambda t, s: ["modes", axis(t, s, drop=["structure"])], 1,
     "[structure]"),
    ("axis-structure-file-missing", lambda t, s: ["modes", axis(t, s, sub(
        'file = "structure.npz"', 'file = "missing.npz"'))], 1, "missing.npz"),
    ("axis-structure-npz-empty", lambda t, s: ["modes", _structure_bytes(t, s, b"")], 1,
     "axis.toml: [structure] file: cannot read "),
    ("axis-structure-npz-cut-short", lambda t, s: ["modes", _structure_bytes(
        t, s, (s / "structure.npz").read_bytes()[:300])], 1,
     "[structure] file: cannot read"),
    ("axis-structure-npz-not-square", lambda t, s: ["modes", _structure_arrays(
        t, s, mass=lambda m: m[:, :-1])], 1,
     "axis.toml: [structure] file: "),
    ("axis-structure-file-is-a-folder", lambda t, s: ["modes", axis(t, s, sub(
        'file = "structure.npz"', 'file = "."'))], 1, "is a folder, not a file"),
    ("axis-structure-file-a-number", lambda t, s: ["modes", axis(t, s, sub(
        'file = "structure.npz"', 'file = 5'))], 1,
     "[structure] file: got 5; give a file name in quotes"),
    ("axis-reduce-boundary-a-string", lambda t, s: ["modes", _fe_axis(
        t, s, 'boundary = "wp.x"\nn_modes = 0')], 1,
     '[structure] reduce.boundary: got \'wp.x\'; give a list of DOF names'),
    ("axis-reduce-f-max-text", lambda t, s: ["modes", _fe_axis(
        t, s, 'boundary = ["pad1.x", "pad2.x", "wp.x", "motor.rotor", "motor.stator"]\n'
              'f_max_hz = "500"')], 1, "[structure] reduce.f_max_hz: got '500'"),
    ("axis-reduce-n-modes-negative", lambda t, s: ["modes", _fe_axis(
        t, s, 'boundary = ["pad1.x", "pad2.x", "wp.x", "motor.rotor", "motor.stator"]\n'
              'n_modes = -1')], 1, "[structure] reduce.n_modes: got -1; give a whole number"),
    ("axis-reduce-n-modes-beyond-the-interior", lambda t, s: ["modes", _fe_axis(
        t, s, 'boundary = ["pad1.x", "pad2.x", "wp.x", "motor.rotor", "motor.stator"]\n'
              'n_modes = 100')], 1, "[structure] reduce.n_modes: 100 fixed-interface modes "
     "asked, but the structure has"),
    ("axis-reduce-two-cutoffs", lambda t, s: ["modes", _fe_axis(
        t, s, 'boundary = ["pad1.x", "pad2.x", "wp.x", "motor.rotor", "motor.stator"]\n'
              'n_modes = 1\nf_max_hz = 500.0')], 1,
     "[structure] reduce: both n_modes and f_max_hz are given; give one of them"),
    ("axis-misspelt-key", lambda t, s: ["modes", axis(t, s, sub(
        "torque_constant = 1.2", "torque_konstant = 1.2"))], 1, "torque_konstant"),
    ("axis-negative-torque-constant", lambda t, s: ["modes", axis(t, s, sub(
        "torque_constant = 1.2", "torque_constant = -1.2"))], 1, "torque_constant"),
    ("axis-text-for-number", lambda t, s: ["modes", axis(t, s, sub(
        "resistance = 0.4", 'resistance = "0.4 ohm"'))], 1, "resistance"),
    ("axis-nan", lambda t, s: ["modes", axis(t, s, sub(
        "resistance = 0.4", "resistance = nan"))], 1, "resistance"),
    ("axis-inf", lambda t, s: ["modes", axis(t, s, sub(
        "inductance = 3.0e-3", "inductance = inf"))], 1, "inductance"),
    ("axis-unknown-pad-dof", lambda t, s: ["modes", axis(t, s, sub(
        'pads = ["pad1.x", "pad2.x"]', 'pads = ["pad1.x", "pad7.x"]'))], 1, "pad7.x"),
    ("axis-unknown-rotor-dof", lambda t, s: ["modes", axis(t, s, sub(
        'rotor = "motor.rotor"', 'rotor = "spindle"'))], 1, "spindle"),
    ("axis-unknown-lugre-set", lambda t, s: ["modes", axis(t, s, lambda text: re.sub(
        r"\[friction\.lugre\].*?(?=\[drive\])", "", text, flags=re.S).replace(
        'pads = ["pad1.x", "pad2.x"]', 'pads = ["pad1.x", "pad2.x"]\nlugre = "teflon"'))], 1,
     "lugre"),
    ("axis-lugre-energy", lambda t, s: ["modes", axis(t, s, sub(
        "sigma1 = 1.6e7 ", "sigma1 = -1.6e7 "))], 1, "sigma1"),
    ("axis-lugre-fc-above-fs", lambda t, s: ["modes", axis(t, s, sub(
        "fc = 2198.0 ", "fc = 7000.0 "))], 1, "fc"),
    ("axis-negative-modal-damping", lambda t, s: ["modes", axis(t, s, sub(
        "modal_damping = 0.03", "modal_damping = -0.03"))], 1, "modal_damping"),
    ("axis-two-kv", lambda t, s: ["modes", axis(t, s, sub(
        "kv_m_per_min_per_mm = 1.0 ", "kv = 16.7\nkv_m_per_min_per_mm = 1.0 "))], 1, "kv"),
    ("axis-immersion", lambda t, s: ["modes", axis(t, s, sub(
        "radial_immersion = 0.5", "radial_immersion = 50.0"))], 1, "radial_immersion"),
    ("axis-zero-teeth", lambda t, s: ["modes", axis(t, s, sub("teeth = 4", "teeth = 0"))], 1,
     "teeth"),
    ("axis-milling-mode", lambda t, s: ["modes", axis(t, s, sub(
        'milling = "down"', 'milling = "sideways"'))], 1, "milling"),
    ("axis-speed-range-reversed", lambda t, s: ["modes", axis(t, s, sub(
        "speed_rpm = [3000.0, 12000.0]", "speed_rpm = [12000.0, 3000.0]"))], 1, "speed_rpm"),
    ("axis-band-reversed", lambda t, s: ["modes", axis(t, s, sub(
        "band_hz = [5.0, 300.0]", "band_hz = [300.0, 5.0]"))], 1, "band"),
    ("axis-ms-below-one", lambda t, s: ["modes", axis(t, s, sub(
        "ms_position_max = 1.5", "ms_position_max = 0.9"))], 1, "ms_position_max"),
    ("axis-chatter-weight", lambda t, s: ["modes", axis(t, s, sub(
        "chatter_weight = 0.0", "chatter_weight = 2.0"))], 1, "chatter_weight"),
    ("axis-free-unknown", lambda t, s: ["modes", axis(t, s, sub(
        'free = ["c", "kv", "kp", "ti", "notch"]', 'free = ["zz"]'))], 1, "free"),
    ("axis-unknown-subtable", lambda t, s: ["modes", axis(t, s, lambda x: x
                                                          + "\n[friction.extra]\nx = 1\n")],
     1, "extra"),
    ("axis-motor-key-names-section", lambda t, s: ["modes", axis(t, s, sub(
        "torque_constant = 1.2", "torque_konstant = 1.2"))], 1,
     "[drive.motor]: unknown key 'torque_konstant' (did you mean 'torque_constant'?)"),
    ("axis-motor-key-missing", lambda t, s: ["modes", axis(t, s, sub(
        "inductance = 3.0e-3", ""))], 1, "[drive.motor]: missing ['inductance']"),
    ("axis-sampling-unknown-key", lambda t, s: ["modes", axis(t, s, sub(
        "speed_filter = 0.0", "speed_filtre = 0.0"))], 1, "[drive.sampling]: unknown keys"),
    ("axis-current-period-zero", lambda t, s: ["modes", axis(t, s, sub(
        "current_period = 125.0e-6", "current_period = 0.0"))], 1,
     "[drive.sampling] current_period: got 0.0, but a sample period must be > 0"),
    ("axis-velocity-period-zero", lambda t, s: ["modes", axis(t, s, sub(
        "velocity_period = 125.0e-6", "velocity_period = 0"))], 1,
     "velocity_period: got 0, but a sample period must be > 0"),
    ("axis-position-period-negative", lambda t, s: ["modes", axis(t, s, sub(
        "position_period = 1.0e-3", "position_period = -1.0e-3"))], 1,
     "or continuous = true"),
    ("axis-position-period-in-ms", lambda t, s: ["modes", axis(t, s, sub(
        "position_period = 1.0e-3", "position_period = 1.0"))], 1,
     "position_period: 1.0 is outside the plausible range"),
    ("axis-computation-delay-in-seconds", lambda t, s: ["modes", axis(t, s, sub(
        "computation_delay = 1.0", "computation_delay = 125.0e-6"))], 1,
     "computation_delay: got 0.000125; it counts sample periods, not seconds"),
    ("axis-velocity-period-slower-than-position", lambda t, s: ["modes", axis(t, s, sub(
        "velocity_period = 125.0e-6", "velocity_period = 4.0e-3"))], 1,
     "position_period (0.001 s) is shorter than velocity_period (0.004 s): the position "
     "controller runs inside the speed controller's cycle"),
    ("axis-periods-not-multiples", lambda t, s: ["modes", axis(t, s, sub(
        "position_period = 1.0e-3", "position_period = 1.1e-3"))], 1,
     "is not a whole multiple of velocity_period"),
    ("axis-computation-delay-fraction", lambda t, s: ["modes", axis(t, s, sub(
        "computation_delay = 1.0", "computation_delay = 1.5"))], 1,
     "give the whole number of periods"),
    ("axis-computation-delay-negative", lambda t, s: ["modes", axis(t, s, sub(
        "computation_delay = 1.0", "computation_delay = -1.0"))], 1, "computation_delay"),
    ("axis-speed-filter-huge", lambda t, s: ["modes", axis(t, s, sub(
        "speed_filter = 0.0", "speed_filter = 2.0"))], 1,
     "speed_filter: 2.0 is outside the plausible range [0, 0.05] s"),
    ("axis-speed-filter-negative", lambda t, s: ["modes", axis(t, s, sub(
        "speed_filter = 0.0", "speed_filter = -1.0e-3"))], 1, "speed_filter"),
    # unit and exponent slips that used to load (each named with its field and the fix)
    ("axis-lugre-vs-in-mm-per-s", lambda t, s: ["modes", axis(t, s, sub(
        "vs = 0.01 ", "vs = 10.0 "))], 1,
     "[friction.lugre] vs: 10 m/s is outside the plausible range [1e-07, 1] m/s of guide-way "
     "friction; check the value and its unit (m/s, axis totals), e.g. 0.01 m/s, not mm/s"),
    ("axis-lugre-sigma2-exponent", lambda t, s: ["modes", axis(t, s, sub(
        "sigma2 = 5578.0 ", "sigma2 = 5.578e12 "))], 1,
     "[friction.lugre] sigma2: 5.578e+12 N s/m is outside the plausible range"),
    ("axis-lugre-fs-exponent", lambda t, s: ["modes", axis(t, s, sub(
        "fs = 6013.0 ", "fs = 6.0e12 "))], 1, "[friction.lugre] fs: 6e+12 N is outside"),
    ("axis-lugre-misspelt-key", lambda t, s: ["modes", axis(t, s, sub(
        "sigma2 = 5578.0 ", "sigma2 = 5578.0\nsigma3 = 1.0 "))], 1,
     "[friction.lugre]: unknown key 'sigma3'; check the spelling; give a named set"),
    ("axis-viscous-negative-said-once", lambda t, s: ["modes", axis(t, s, sub(
        "viscous = 5578.0", "viscous = -5578.0"))], 1,
     "axis.toml: [friction] viscous: -5578.0 is outside the plausible range [0, 1e+10] N s/m;"
     " check the value and its unit\n"),
    ("axis-pads-twice", lambda t, s: ["modes", axis(t, s, sub(
        'pads = ["pad1.x", "pad2.x"]', 'pads = ["pad1.x", "pad1.x"]'))], 1,
     "[friction] pads: ['pad1.x', 'pad1.x'] names a DOF twice; list each pad's relative-X DOF "
     "once"),
    ("axis-stator-is-rotor", lambda t, s: ["compliance", axis(t, s, sub(
        'stator = "motor.stator"', 'stator = "motor.rotor"'))], 1,
     "[drive.motor] stator: the same DOF as rotor ('motor.rotor'): the torque acts between "
     "the two, so it would cancel"),
    ("axis-inductance-in-mh", lambda t, s: ["bode", axis(t, s, sub(
        "inductance = 3.0e-3", "inductance = 3.0"))], 1,
     "[drive.motor] inductance: L / R = 3 H / 0.4 ohm = 7.5 s: an electrical time constant "
     "above 1 s no servo motor has (data sheets give 1 to 50 ms); check the units: inductance "
     "in H (3 mH = 3.0e-3)"),
    ("axis-ratio-lead-in-m-per-rad", lambda t, s: ["compliance", axis(t, s, sub(
        "ratio = 0.0015915494309189536", "ratio = 1.5915494309189536"))], 1,
     "[drive.transmission] ratio: speed_max_rpm x ratio = 500 m/s at the slide, past any "
     "machine tool (20 m/s); give the ratio in m/rad: lead / (2 pi) / belt ratio"),
    ("axis-current-ti-in-ms", lambda t, s: ["bode", axis(t, s, sub(
        "ti = 2.0e-3 ", "ti = 2.0 "))], 1,
     "[drive.current_loop] ti: 2.0 is outside the plausible range [1e-07, 1] s"),
    ("axis-velocity-ti-in-ms", lambda t, s: ["bode", axis(t, s, sub(
        "ti = 12.0e-3 ", "ti = 12.0 "))], 1,
     "[drive.velocity_loop] ti: 12.0 is outside the plausible range [1e-07, 10] s"),
    ("axis-velocity-loop-key-names-section", lambda t, s: ["modes", axis(t, s, sub(
        "kp = 3.7 ", "kp = 3.7\ntn = 0.01 "))], 1,
     "[drive.velocity_loop]: unknown keys ['tn']"),
    ("axis-feedforward-in-percent", lambda t, s: ["bode", axis(t, s, sub(
        "# [drive.feedforward]", "[drive.feedforward]\nvelocity = 100.0"))], 1,
     "[drive.feedforward] velocity: 100.0 is outside the plausible range [0, 2]"),
    ("axis-lowpass-negative", lambda t, s: ["bode", axis(t, s, sub(
        "# [drive.filters]", "[drive.filters]\nlowpass_hz = -800.0"))], 1,
     "[drive.filters] lowpass_hz: got -800.0; give a positive value"),
    ("axis-lowpass-above-nyquist", lambda t, s: ["modes", axis(t, s, sub(
        "# [drive.filters]", "[drive.filters]\nlowpass_hz = 8000.0"))], 1,
     "[drive.filters] lowpass_hz: 8000 Hz is at or above half the current controller's "
     "sample rate (4000 Hz, [drive.sampling] current_period = 0.000125 s)"),
    ("axis-notch-above-nyquist", lambda t, s: ["modes", axis(t, s, sub(
        "# [drive.filters]", "[drive.filters]\nnotch_hz = 5000.0"))], 1,
     "[drive.filters] notch_hz: 5000 Hz is at or above half the current controller's sample "
     "rate (4000 Hz"),
    ("axis-kv-min-above-the-tuning-bound", lambda t, s: ["modes", axis(t, s, sub(
        "# kv_min_m_per_min_per_mm = 1.0", "kv_min_m_per_min_per_mm = 100.0"))], 1,
     "[requirements] kv_min: the least Kv 1667 1/s (100 (m/min)/mm) is above the largest Kv "
     "the tuning may choose, [tuning] kv = 300 1/s; lower kv_min"),
    ("axis-c-bound-below-the-guide-ways-own", lambda t, s: ["modes", axis(t, s, sub(
        "# c = [5578.0, 1.0e8]", "c = [1.0, 1.0e8]"))], 1,
     "[tuning] c: the lower bound 1 N s/m is below the guide ways' own viscous friction "
     "sigma2 = 5578 N s/m ([friction.lugre])"),
    ("axis-lugre-delta-implausible", lambda t, s: ["modes", axis(t, s, sub(
        "delta = 1.0 ", "delta = 50.0 "))], 1,
     "[friction.lugre] delta: 50 is outside the plausible range [0, 10] (an exponent) of "
     "guide-way friction"),
    ("axis-phase-margin-in-radians", lambda t, s: ["modes", axis(t, s, sub(
        "phase_margin_min_deg = 40.0", "phase_margin_min_deg = 0.7"))], 1,
     "[requirements] phase_margin_min_deg: 0.7 deg is no phase margin a design asks for, but "
     "0.7 rad = 40.1 deg is; give degrees, e.g. 40"),
    ("axis-immersion-underflow", lambda t, s: ["tune", axis(t, s, sub(
        "radial_immersion = 0.5", "radial_immersion = 2.4e-197"))], 1,
     "[cutting] radial_immersion"),
    pytest.param("axis-kt-1e300", lambda t, s: ["lobes", axis(t, s, sub(
        "kt = 2.0e9", "kt = 1.0e300"))], 1, "kt"),
    pytest.param("axis-mass-1e300", lambda t, s: ["modes", _heavy(t, s)], 1, "mass",
                 ),
    pytest.param("axis-resistance-1e300", lambda t, s: ["bode", axis(t, s, sub(
        "resistance = 0.4", "resistance = 1.0e300"))], 1, "resistance",
                 ),

    # ---- sections a command needs
    ("lobes-without-cutting", lambda t, s: ["lobes", axis(t, s, drop=["cutting"])], 1,
     "[cutting]"),
    ("bode-without-drive", lambda t, s: ["bode", axis(t, s, drop=["drive"])], 1, "[drive]"),
    ("table3-without-friction", lambda t, s: ["table3", axis(t, s, drop=["friction"])], 1,
     "[friction]"),
    ("table3-without-drive", lambda t, s: ["table3", axis(t, s, drop=["drive"])], 1, "[drive]"),
    ("modes-locked-pads-without-friction", lambda t, s: [
        "modes", axis(t, s, drop=["friction"]), "--pads", "locked"], 1, "[friction]"),
    ("compliance-stiction-without-friction", lambda t, s: [
        "compliance", axis(t, s, drop=["friction"]), "--contact", "stiction"], 1,
     "[friction]"),
    ("tune-without-friction", lambda t, s: [
        "tune", axis(t, s, drop=["friction"]), "--no-simulation"], 1, "[friction]"),
    pytest.param("tune-without-drive", lambda t, s: [
        "tune", axis(t, s, drop=["drive"]), "--no-simulation"], 1, "[drive]",
                 ),

    # ---- measured FRFs (`identify`)
    ("identify-csv-text-for-number", lambda t, s: ["identify", frf_csv(
        t, "f_hz,re,im\n10,1e-6,0\n20,fast,0\n")], 1, "frf.csv, line 3: column 're'"),
    ("identify-missing-file", lambda t, s: ["identify", str(t / "hammer.uff")], 1,
     "hammer.uff: no such file"),
    ("identify-uff-without-frf", lambda t, s: ["identify", text_file(
        t, "nodes.unv", "    -1\n   164\n         1  SI\n    -1\n")], 1,
     "no dataset 58"),
    ("identify-band-reversed", lambda t, s: ["identify", frf_csv(
        t, "f_hz,re,im\n10,1e-6,0\n20,1e-6,0\n"), "--band-hz", "300", "20"], 2,
     "--band-hz 300 20"),
    ("identify-dof-without-axis", lambda t, s: ["identify", frf_csv(
        t, "f_hz,re,im\n10,1e-6,0\n20,1e-6,0\n"), "--dof", "wp.y"], 2, "--dof wp.y"),
    ("identify-axis-without-friction", lambda t, s: ["identify", frf_csv(
        t, "f_hz,re,im\n10,1e-6,0\n20,1e-6,0\n"), "--axis", axis(t, s, drop=["friction"])],
     1, "[friction]"),
    ("identify-axis-unknown-dof", lambda t, s: ["identify", frf_csv(
        t, "f_hz,re,im\n10,1e-6,0\n20,1e-6,0\n"), "--axis", axis(t, s), "--dof", "wp.q"],
     1, "--dof wp.q: unknown DOF 'wp.q'"),

    # ---- structure files (`check`)
    ("check-missing-file", lambda t, s: ["check", str(t / "M.mtx"), str(t / "K.mtx")], 1,
     "M.mtx"),
    ("check-unknown-suffix", lambda t, s: ["check", text_file(t, "M.txt", "1"),
                                           text_file(t, "K.txt", "1")], 1, ".txt"),
    ("check-mtx-without-stiffness", lambda t, s: ["check", mtx(t, "M.mtx", np.eye(2))], 1,
     "stiffness"),
    ("check-corrupt-mtx", lambda t, s: ["check", text_file(t, "M.mtx", "%%MatrixMarket junk\n"),
                                        mtx(t, "K.mtx", np.eye(2))], 1, "M.mtx"),
    ("check-sizes-differ", lambda t, s: ["check", mtx(t, "M.mtx", np.eye(2)),
                                         mtx(t, "K.mtx", np.eye(3))], 1, "K.mtx"),
    ("check-not-square", lambda t, s: ["check", mtx(t, "M.mtx", np.ones((2, 3))),
                                       mtx(t, "K.mtx", np.eye(2))], 1, "M.mtx"),
    ("check-npz-without-stiffness", lambda t, s: ["check", npz(t, mass=np.eye(2))], 1,
     "stiffness"),
    ("check-three-files", lambda t, s: ["check", *[mtx(t, f"{n}.mtx", np.eye(2))
                                                   for n in "MKX"]], 2, "at most two"),
    ("check-dof-map-length", lambda t, s: [
        "check", mtx(t, "M.mtx", spring_mass()[0]), mtx(t, "K.mtx", spring_mass()[1]),
        "--dof-map", text_file(t, "dofs.csv", "name\na.x\nb.x\n")], 1, "dofs.csv"),
    ("check-unknown-boundary", lambda t, s: [
        "check", mtx(t, "M.mtx", spring_mass()[0]), mtx(t, "K.mtx", spring_mass()[1]),
        "--dof-map", text_file(t, "dofs.csv", "name\na.x\nb.x\nc.x\n"), "--boundary", "z.x"],
     1, "z.x"),
    ("check-modes-and-cutoff", lambda t, s: [
        "check", mtx(t, "M.mtx", spring_mass()[0]), mtx(t, "K.mtx", spring_mass()[1]),
        "--boundary", "0", "--n-modes", "2", "--f-max-hz", "100"], 2, "--f-max-hz"),
    ("check-nan-in-matrix", lambda t, s: ["check", npz(t, mass=np.array([[np.nan, 0], [0, 1.]]),
                                                       stiffness=np.eye(2))], 1, "NaN"),
    ("check-axis-folder-with-dof-map", lambda t, s: ["check", str(PAPER), "--dof-map",
                                                     text_file(t, "dofs.csv", "name\na.x\n")],
     2, "--dof-map sets how matrix files are read or reduced; " + str(PAPER)
     + " is an axis folder, whose [structure] says that"),
    ("check-axis-folder-with-reduction", lambda t, s: ["check", str(PAPER), "--boundary",
                                                       "wp.x", "--n-modes", "3"], 2,
     "--boundary, --n-modes set how matrix files are read or reduced"),
    ("check-f-max-zero", lambda t, s: ["check", str(PAPER), "--f-max-hz", "0"], 2,
     "--f-max-hz"),
    ("check-n-modes-negative", lambda t, s: ["check", str(PAPER), "--n-modes", "-1"], 2,
     "--n-modes"),

    # ---- CSV files
    ("fit-wrong-header", lambda t, s: ["friction", "fit", stribeck_csv(
        t, header="speed,torque")], 1, "v_m_per_s,f_n"),
    ("fit-non-number", lambda t, s: ["friction", "fit", stribeck_csv(
        t, rows=[("0.1", "abc")] * 20)], 1, "f_n"),
    ("fit-too-few-points", lambda t, s: ["friction", "fit", stribeck_csv(
        t, rows=[(0.001, 3000.0), (-0.002, -2800.0)])], 1, "at least"),
    ("fit-one-sign", lambda t, s: ["friction", "fit", stribeck_csv(
        t, rows=[(float(v), 2000.0 + 5000.0 * v) for v in np.geomspace(1e-4, 0.5, 30)])], 1,
     "one sign"),
    ("fit-empty-file", lambda t, s: ["friction", "fit", text_file(t, "empty.csv", "")], 1,
     "empty.csv"),
    ("fit-missing-file", lambda t, s: ["friction", "fit", str(t / "nothing.csv")], 1,
     "nothing.csv"),
    ("fit-fix-unknown-name", lambda t, s: ["friction", "fit", stribeck_csv(t), "--fix",
                                           "mu=0.1"], 1, "mu"),
    ("fit-fix-nan", lambda t, s: ["friction", "fit", stribeck_csv(t), "--fix", "delta=nan"],
     1, "finite"),
    ("fit-fix-negative-vs", lambda t, s: ["friction", "fit", stribeck_csv(t), "--fix",
                                          "vs=-1"], 1,
     "--fix 'vs=-1': vs must be in [1e-07, 1] m/s; give the value in SI units"),
    ("fit-fix-zero-delta", lambda t, s: ["friction", "fit", stribeck_csv(t), "--fix",
                                         "delta=0"], 1,
     "--fix 'delta=0': delta must be in (0, 10]"),
    ("fit-speeds-in-mm-per-s", lambda t, s: ["friction", "fit", stribeck_csv(
        t, rows=[(sg * v, sg * (2000.0 + 5.0 * v)) for sg in (1.0, -1.0)
                 for v in (1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0)])], 1,
     "stribeck.csv: column v_m_per_s reaches 1000 m/s, past any guide way (10 m/s); give the "
     "speeds in m/s"),
    ("fit-with-the-damping-flags", lambda t, s: ["friction", "--amplitude", "1e-6",
                                                 "--frequency-hz", "50", "fit",
                                                 stribeck_csv(t)], 2,
     "--amplitude, --frequency-hz set the equivalent damping of 'servotune friction', not the "
     "fit: drop them"),
    ("fit-fix-without-value", lambda t, s: ["friction", "fit", stribeck_csv(t), "--fix",
                                            "delta"], 1, "NAME=VALUE"),
    ("frf-missing-file", lambda t, s: ["lobes", "--frf", str(t / "frf.csv")], 1, "frf.csv"),
    ("frf-wrong-header", lambda t, s: ["lobes", "--frf", frf_csv(
        t, "f,re,im\n1,2,3\n2,3,4\n3,4,5\n4,5,6\n")], 1, "f_hz"),
    ("frf-nan", lambda t, s: ["lobes", "--frf", frf_csv(
        t, "f_hz,re_xx_m_per_n,im_xx_m_per_n\n100,nan,1e-7\n200,1e-7,-1e-7\n"
           "300,1e-8,-1e-8\n")], 1, "frf.csv"),
    ("frf-rows-out-of-order", lambda t, s: ["lobes", "--frf", frf_csv(
        t, "f_hz,re_xx_m_per_n,im_xx_m_per_n\n300,1e-8,-1e-8\n100,1e-7,-1e-7\n"
           "200,1e-7,-2e-7\n")], 1,
     "frf.csv: column f_hz: data row 2 has 100 Hz after 300 Hz; the frequencies must be > 0 "
     "Hz and increase from row to row: sort the rows by f_hz"),
    ("frf-repeated-frequency", lambda t, s: ["lobes", "--frf", frf_csv(
        t, "f_hz,re_xx_m_per_n,im_xx_m_per_n\n100,1e-7,-1e-7\n100,1e-7,-1e-7\n"
           "200,1e-7,-2e-7\n")], 1, "column f_hz: data row 2 has 100 Hz after 100 Hz"),
    ("frf-negative-frequency", lambda t, s: ["lobes", "--frf", frf_csv(
        t, "f_hz,re_xx_m_per_n,im_xx_m_per_n\n-100,1e-7,-1e-7\n200,1e-7,-2e-7\n"
           "300,1e-8,-1e-8\n")], 1, "column f_hz: data row 1 has -100 Hz"),
    ("coordinates-bad-csv", lambda t, s: ["check", str(PAPER), "--coordinates", text_file(
        t, "xyz.csv", "node,x\n1,abc\n")], 1, "xyz.csv"),

    # ---- flags
    ("modes-count-negative", lambda t, s: ["modes", str(PAPER), "--count", "-3"], 2,
     "--count"),
    ("modes-count-zero", lambda t, s: ["modes", str(PAPER), "--count", "0"], 2, "--count"),
    ("modes-pads-unknown", lambda t, s: ["modes", str(PAPER), "--pads", "glued"], 2, "--pads"),
    ("modes-no-plots", lambda t, s: ["modes", str(PAPER), "--no-plots"], 2,
     "--no-plots: servotune modes writes no figures"),
    ("check-no-plots", lambda t, s: ["check", str(PAPER), "--no-plots"], 2,
     "--no-plots: servotune check writes no figures"),
    ("table3-no-plots", lambda t, s: ["table3", str(PAPER), "--no-plots"], 2,
     "--no-plots: servotune table3 writes no figures"),
    ("init-no-plots", lambda t, s: ["init", str(t / "new"), "--no-plots"], 2,
     "--no-plots: servotune init writes no figures"),
    ("twomass-alpha-negative", lambda t, s: ["twomass", "--alpha", "-1"], 2, "--alpha"),
    ("twomass-k-zero", lambda t, s: ["twomass", "--k", "0"], 2, "--k"),
    ("twomass-m1-nan", lambda t, s: ["twomass", "--m1", "nan"], 2, "--m1"),
    ("twomass-m1-inf", lambda t, s: ["twomass", "--m1", "inf"], 2, "--m1"),
    ("twomass-m1-text", lambda t, s: ["twomass", "--m1", "heavy"], 2, "--m1"),
    ("twomass-layout", lambda t, s: ["twomass", "--layout", "C"], 2, "--layout"),
    ("friction-amplitude", lambda t, s: ["friction", "--amplitude=-1e-6"], 2, "--amplitude"),
    ("friction-frequency", lambda t, s: ["friction", "--frequency-hz", "0"], 2,
     "--frequency-hz"),
    ("friction-params", lambda t, s: ["friction", "--params", "teflon"], 2, "--params"),
    ("lobes-teeth", lambda t, s: ["lobes", *MODE, "--teeth", "0"], 2, "--teeth"),
    ("lobes-immersion", lambda t, s: ["lobes", *MODE, "--immersion", "1.5"], 2, "--immersion"),
    ("lobes-speeds", lambda t, s: ["lobes", *MODE, "--speeds", "1"], 2, "--speeds"),
    ("lobes-mode-stiffness", lambda t, s: ["lobes", "--mode", "922", "0.02", "-5"], 2,
     "K_N_PER_M"),
    ("lobes-mode-text", lambda t, s: ["lobes", "--mode", "922", "abc", "1e6"], 2, "ZETA"),
    ("lobes-speed-range", lambda t, s: ["lobes", *MODE, "--speed-rpm", "9000", "5000"], 1,
     "--speed-rpm"),
    ("lobes-intervals", lambda t, s: ["lobes", *MODE, "--intervals", "2"], 2, "--intervals"),
    ("lobes-kt-in-n-per-mm2", lambda t, s: ["lobes", *MODE, "--kt", "2000"], 2,
     "argument --kt: '2000' is not accepted: give a number in [100000, 1e+11] N/m^2"),
    ("bode-abbreviated-flag", lambda t, s: ["bode", str(PAPER), "--freq", "10"], 2,
     "unrecognized arguments: --freq 10"),
    ("modes-axis-is-the-npz", lambda t, s: ["modes", str(Path(axis(t, s)) / "structure.npz")],
     1, "structure.npz: not an axis description (not a text file); give the axis folder"),
    ("modes-axis-is-a-text-file", lambda t, s: ["modes", text_file(t, "notes.txt", "hello")],
     1, "notes.txt: not valid TOML (Expected '=' after a key in a key/value pair (at end of "
        "document)); give the axis folder (the one holding axis.toml)"),
    ("lobes-intervals-without-sdm", lambda t, s: ["lobes", *MODE, "--intervals", "8"], 2,
     "--intervals sets the semi-discretisation: add --method sdm, or drop it"),
    ("lobes-depth-max-without-sdm", lambda t, s: ["lobes", *MODE, "--depth-max-mm", "3"], 2,
     "--depth-max-mm sets the semi-discretisation"),
    ("lobes-no-compliance", lambda t, s: ["lobes"], 2, "give the compliance"),
    ("lobes-two-sources", lambda t, s: ["lobes", str(PAPER), *MODE], 2, "one source"),
    ("table3-workers", lambda t, s: ["table3", "--workers", "0"], 2, "--workers"),
    ("table3-duration-zero", lambda t, s: ["table3", "--duration", "0"], 2, "--duration"),
    ("table3-duration-negative", lambda t, s: ["table3", "--duration", "-5"], 2, "--duration"),
    ("table3-sweep-reversed", lambda t, s: ["table3", "--f-start-hz", "100", "--f-end-hz",
                                            "10"], 1, "--f-start-hz"),
    ("nlcompliance-force-zero", lambda t, s: ["nlcompliance", str(PAPER), "--force-pp", "0"],
     2, "--force-pp"),
    ("nlcompliance-no-force", lambda t, s: ["nlcompliance", str(PAPER)], 2, "--force-pp"),
    ("nlcompliance-speed-negative", lambda t, s: [
        "nlcompliance", str(PAPER), "--force-pp", "50", "--speed", "-0.03"], 2, "--speed"),
    ("nlcompliance-harmonics-zero", lambda t, s: [
        "nlcompliance", str(PAPER), "--force-pp", "50", "--harmonics", "0"], 2, "--harmonics"),
    ("nlcompliance-band-reversed", lambda t, s: [
        "nlcompliance", str(PAPER), "--force-pp", "50", "--f-start-hz", "100", "--f-end-hz",
        "10"], 1, "--f-start-hz"),
    ("nlcompliance-unstable-digital-drive", lambda t, s: [
        "nlcompliance", str(PAPER), "--force-pp", "50"], 1, "try --continuous"),
    ("nlcompliance-without-friction", lambda t, s: [
        "nlcompliance", axis(t, s, drop=["friction", "operation"]), "--force-pp", "50"], 1,
     "[friction]"),
    ("compliance-c-negative", lambda t, s: ["compliance", str(PAPER), "--c", "-5"], 2, "--c"),
    ("compliance-amplitude-huge", lambda t, s: ["compliance", str(PAPER), "--amplitude", "1"],
     2, "--amplitude"),
    ("compliance-equivalent-needs-amplitude", lambda t, s: [
        "compliance", str(PAPER), "--contact", "equivalent"], 1,
     "--contact equivalent needs --amplitude and --frequency-hz"),
    ("compliance-equivalent-needs-frequency", lambda t, s: [
        "compliance", str(PAPER), "--contact", "equivalent", "--amplitude", "2e-6"], 1,
     "--contact equivalent needs --frequency-hz"),
    ("compliance-sliding-needs-speed", lambda t, s: [
        "compliance", str(PAPER), "--contact", "sliding"], 1,
     "--contact sliding needs a non-zero --speed"),
    ("compliance-sliding-speed-zero", lambda t, s: [
        "compliance", str(PAPER), "--contact", "sliding", "--speed", "0"], 1,
     "non-zero --speed"),
    ("compliance-amplitude-without-equivalent", lambda t, s: [
        "compliance", str(PAPER), "--contact", "locked", "--amplitude", "2e-6"], 1,
     "--amplitude sets the vibration of --contact equivalent"),
    ("compliance-frequency-without-equivalent", lambda t, s: [
        "compliance", str(PAPER), "--frequency-hz", "50"], 1,
     "it has no meaning with --contact viscous"),
    ("compliance-speed-without-sliding", lambda t, s: [
        "compliance", str(PAPER), "--contact", "equivalent", "--amplitude", "2e-6",
        "--frequency-hz", "50", "--speed", "0.03"], 1,
     "--speed sets the sliding speed of --contact sliding"),
    ("compliance-speed-huge", lambda t, s: ["compliance", str(PAPER), "--contact", "sliding",
                                            "--speed", "30"], 2, "[-10, 10] m/s"),
    ("compliance-c-without-viscous", lambda t, s: [
        "compliance", str(PAPER), "--contact", "locked", "--c", "1e5"], 1, "--c"),
    ("compliance-amplitude-negative-exponent", lambda t, s: [
        "compliance", str(PAPER), "--contact", "equivalent", "--amplitude", "-1e-6",
        "--frequency-hz", "50"], 2,
     "argument --amplitude: expected one argument (-1e-6 reads as a flag: write "
     "--amplitude=-1e-6 for a negative number)"),
    ("bode-contact-unknown", lambda t, s: ["bode", str(PAPER), "--contact", "glue"], 2,
     "--contact"),
    pytest.param("tune-starts-zero", lambda t, s: ["tune", str(PAPER), "--starts", "0"], 2,
                 "--starts"),
    pytest.param("tune-starts-negative", lambda t, s: ["tune", str(PAPER), "--starts", "-5"], 2,
                 "--starts"),
    ("tune-spread-samples-without-a-study", lambda t, s: [
        "tune", str(PAPER), "--spread-samples", "3", "--no-simulation"], 2,
     "--spread-samples counts the worst samples of --spread-from STUDY; give --spread-from "
     "too, or drop --spread-samples"),
    ("tune-free-unknown", lambda t, s: ["tune", str(PAPER), "--free", "xyz"], 2, "--free"),
    ("study-missing-file", lambda t, s: ["study", str(t / "s.toml")], 1, "no study file"),
    ("study-not-toml", lambda t, s: ["study", text_file(t, "s.toml", "[study\n")], 1,
     "not valid TOML"),
    ("study-unknown-key", lambda t, s: ["study", text_file(
        t, "s.toml", f'[study]\naxes = ["{s}"]\nsampels = 3\n')], 1, "sampels"),
    ("study-axis-missing", lambda t, s: ["study", text_file(
        t, "s.toml", '[study]\naxes = ["nowhere"]\n')], 1, "no axis.toml"),
    ("study-bad-distribution", lambda t, s: ["study", text_file(
        t, "s.toml", f'[study]\naxes = ["{s}"]\n[vary."friction.lugre.fc"]\n'
                     'distribution = "gauss"\n')], 1, "'gauss'"),
    ("study-bad-scheduler", lambda t, s: ["study", str(t / "s.toml"), "--scheduler",
                                          "localhost:8786"], 2, "tcp://"),
    ("study-workers-zero", lambda t, s: ["study", str(t / "s.toml"), "--workers", "0"], 2,
     "--workers"),
    ("study-design-inline", lambda t, s: ["study", text_file(
        t, "s.toml", f'[study]\naxes = ["{s}"]\ncompute = ["compliance"]\n'
                     'design = {c = 5578.0, kv = 25.0, kp = 5.0, ti = 0.01}\n')], 1,
     "[study] design: got {'c': 5578.0, 'kv': 25.0, 'kp': 5.0, 'ti': 0.01}; name the "
     "results.json that servotune tune wrote"),
    ("study-design-negative-c", lambda t, s: ["study", text_file(
        t, "s.toml", f'[study]\naxes = ["{s}"]\ncompute = ["compliance"]\n'
                     f'design = "{design_file(t, c=-1.0)}"\n')], 1,
     "results.json: design.c is -1.0; give a finite number > 0"),
    ("verify-missing-file", lambda t, s: ["verify", str(t / "results.json")], 1,
     "results.json"),
    ("verify-not-json", lambda t, s: ["verify", text_file(t, "r.json", "{not json")], 1,
     "not valid JSON"),
    ("verify-no-design", lambda t, s: ["verify", text_file(t, "r.json", json.dumps(
        {"axis": str(PAPER)}))], 1, "'design'"),
    ("verify-negative-c", lambda t, s: ["verify", design_file(t, c=-1.0)], 1, "design.c"),
    ("verify-misspelt-design-key", lambda t, s: ["verify", design_file(t, kv=None, kvv=25.0)],
     1, "design has an unknown key 'kvv' (did you mean 'kv'?)"),
    ("verify-design-without-kp-ti", lambda t, s: ["verify", design_file(t, kp=None, ti=None)],
     1, "design has no 'kp', 'ti'; the design must hold c [N s/m], kv [1/s]"),
    ("verify-design-only-c", lambda t, s: ["verify", design_file(t, kv=None, kp=None,
                                                                 ti=None)], 1, "'kv'"),
    ("verify-design-text", lambda t, s: ["verify", design_file(t, kv="25")], 1,
     'design.kv is "25"; give a number in 1/s'),
    ("verify-design-null", lambda t, s: ["verify", design_file(t, kp="null")], 1,
     "design.kp is null"),
    ("verify-design-nan", lambda t, s: ["verify", design_file(t, kp="NaN")], 1,
     "design.kp is nan; give a finite number > 0"),
    ("verify-design-infinite-c", lambda t, s: ["verify", design_file(t, c="Infinity")], 1,
     "design.c is inf"),
    ("verify-design-negative-ti", lambda t, s: ["verify", design_file(t, ti=-0.01)], 1,
     "design.ti is -0.01"),
    ("verify-design-zero-kv", lambda t, s: ["verify", design_file(t, kv=0)], 1,
     "design.kv is 0"),
    ("verify-design-boolean", lambda t, s: ["verify", design_file(t, kp=True)], 1,
     "design.kp is true"),
    ("verify-design-kv-unit-slip", lambda t, s: ["verify", design_file(t, kv=1.5e6)], 1,
     "design.kv is 1500000.0, above the plausible 10000 1/s"),
    ("verify-design-not-object", lambda t, s: ["verify", text_file(t, "r.json", json.dumps(
        {"axis": str(PAPER), "design": [1, 2]}))], 1, "'design' must be an object"),
    ("verify-axis-not-text", lambda t, s: ["verify", design_file(t, axis=5)], 1,
     "'axis' must be the path of the axis folder"),
    ("verify-axis-missing", lambda t, s: ["verify", design_file(t, axis="nowhere")], 1,
     "the axis folder 'nowhere' does not exist"),
    ("verify-a-folder", lambda t, s: ["verify", _folder(t, "ax")], 1,
     "is a folder; verify wants the results.json that servotune tune writes"),
    ("verify-an-axis-folder", lambda t, s: ["verify", str(PAPER)], 1,
     "(an axis folder: run servotune tune"),
    ("verify-a-results-folder", lambda t, s: ["verify", _results_folder(t)], 1,
     "tune_ax/results.json"),
    ("verify-force-negative", lambda t, s: ["verify", design_file(t), "--force-pp", "-1"], 2,
     "argument --force-pp: '-1' is not accepted: give a number in (0, 1e+06] N"),
    ("verify-force-huge", lambda t, s: ["verify", design_file(t), "--force-pp", "1e9"], 2,
     "--force-pp"),
    ("verify-force-text", lambda t, s: ["verify", design_file(t), "--force-pp", "much"], 2,
     "'much' is not a number"),
    ("verify-speed-zero", lambda t, s: ["verify", design_file(t), "--speed", "0"], 2,
     "argument --speed: '0' is not accepted: give a number in (0, 10] m/s"),
    ("verify-speed-huge", lambda t, s: ["verify", design_file(t), "--speed", "50"], 2,
     "--speed"),
    ("verify-f-start-nan", lambda t, s: ["verify", design_file(t), "--f-start-hz", "nan",
                                         "--f-end-hz", "100"], 2, "--f-start-hz"),
    ("verify-f-end-huge", lambda t, s: ["verify", design_file(t), "--f-start-hz", "10",
                                        "--f-end-hz", "1e6"], 2,
     "argument --f-end-hz: '1e6' is not accepted: give a number in (0, 100000] Hz"),
    ("verify-f-start-alone", lambda t, s: ["verify", design_file(t), "--f-start-hz", "10"],
     2, "give both --f-start-hz and --f-end-hz"),
    ("verify-band-reversed", lambda t, s: ["verify", design_file(t), "--f-start-hz", "100",
                                           "--f-end-hz", "10"], 1,
     "--f-start-hz 100 must be below --f-end-hz 10"),
    ("unknown-command", lambda t, s: ["tuning", str(PAPER)], 2, "invalid choice"),
    ("no-command", lambda t, s: [], 2, "COMMAND"),

    # ---- output folders
    ("out-is-a-file", lambda t, s: ["twomass", "--out", text_file(t, "o.txt", "x")], 1,
     "o.txt is a file"),
    ("out-under-a-file", lambda t, s: ["bode", str(PAPER), "--out", str(Path(text_file(
        t, "o.txt", "x")) / "sub")], 1, "o.txt is a file"),
    ("out-foreign-file", lambda t, s: ["modes", str(PAPER), "--out", _foreign(
        t, "modes_paper_x_axis")], 1, "notes.txt"),
    ("out-run-folder-is-a-file", lambda t, s: ["friction", "--out", _blocked(
        t, "friction_bianchi2014")], 1, "friction_bianchi2014"),
    ("out-empty", lambda t, s: ["modes", str(PAPER), "--out", ""], 2,
     "argument --out: '' is empty: give the folder for the results"),
    ("init-into-a-file", lambda t, s: ["init", text_file(t, "axis.toml", "x")], 1,
     "is a file"),
    ("init-under-a-file", lambda t, s: ["init", str(Path(text_file(t, "f", "x")) / "a")], 1,
     "is a file"),
    ("init-existing-axis", lambda t, s: ["init", _copy(t, s)], 1, "--force"),
]


def design_file(tmp, axis=str(PAPER), **change) -> str:
    """A results file of servotune tune (axis and design) with design keys changed: None drops
    a key, the strings "NaN", "Infinity" and "null" are written as those JSON words."""
    design = {"c": 5578.0, "kv": 25.5, "kp": 5.85, "ti": 0.0267}
    design.update(change)
    design = {k: v for k, v in design.items() if v is not None}
    text = json.dumps({"axis": axis, "design": design})
    for word in ("NaN", "Infinity", "null"):
        text = text.replace(f'"{word}"', word)
    return text_file(tmp, "results.json", text)


def _folder(tmp, name) -> str:
    (tmp / name).mkdir()
    return str(tmp / name)


def _results_folder(tmp) -> str:
    folder = tmp / "out" / "tune_ax"
    folder.mkdir(parents=True)
    design_file(folder)
    return str(folder)


def _heavy(tmp, starter) -> str:
    folder = Path(axis(tmp, starter, sub("modal_damping = 0.03", "modal_damping = 0.02")))
    data = np.load(folder / "structure.npz")
    np.savez(folder / "structure.npz", mass=data["mass"] * 1e300, stiffness=data["stiffness"],
             dofs=data["dofs"])
    return str(folder)


def _structure_bytes(tmp, starter, data: bytes) -> str:
    folder = Path(axis(tmp, starter, sub("modal_damping = 0.03", "modal_damping = 0.02")))
    (folder / "structure.npz").write_bytes(data)
    return str(folder)


def _structure_arrays(tmp, starter, **change) -> str:
    folder = Path(axis(tmp, starter, sub("modal_damping = 0.03", "modal_damping = 0.02")))
    data = dict(np.load(folder / "structure.npz"))
    np.savez(folder / "structure.npz", **{k: change[k](v) if k in change else v
                                          for k, v in data.items()})
    return str(folder)


def _fe_axis(tmp, starter, reduce: str) -> str:
    """The starter axis as FE matrices (M.mtx, K.mtx, dofs.csv) with [structure.reduce]."""
    from scipy.io import mmwrite

    folder = Path(axis(tmp, starter, lambda text: text.replace(
        'file = "structure.npz"', 'mass = "M.mtx"\nstiffness = "K.mtx"\ndof_map = "dofs.csv"'
    ).replace("[friction]", f"[structure.reduce]\n{reduce}\n\n[friction]", 1)))
    data = np.load(folder / "structure.npz")
    mmwrite(str(folder / "M.mtx"), data["mass"])
    mmwrite(str(folder / "K.mtx"), data["stiffness"])
    (folder / "dofs.csv").write_text("name\n" + "\n".join(data["dofs"]) + "\n")
    return str(folder)


def _foreign(tmp, name) -> str:
    (tmp / "out" / name).mkdir(parents=True)
    (tmp / "out" / name / "notes.txt").write_text("mine")
    return str(tmp / "out")


def _blocked(tmp, name) -> str:
    (tmp / "out").mkdir()
    (tmp / "out" / name).write_text("in the way")
    return str(tmp / "out")


def _copy(tmp, starter) -> str:
    shutil.copytree(starter, tmp / "mine")
    return str(tmp / "mine")


def _files(folder: Path) -> dict:
    return {p: p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _case_id(case):
    return case.values[0] if hasattr(case, "values") else case[0]


def test_the_catalogue_is_large_and_covers_every_command():
    from servotune.cli import COMMANDS

    assert len(CASES) >= 60
    names = {_case_id(c) for c in CASES}
    assert len(names) == len(CASES)
    first_words = set()
    for case in CASES:
        fixture = case.values[1] if hasattr(case, "values") else case[1]
        code = fixture.__code__.co_consts
        first_words |= {c for c in code if isinstance(c, str) and c in COMMANDS}
    assert first_words >= set(COMMANDS)


@pytest.mark.parametrize("case_id, fixture, status, words", CASES,
                         ids=[_case_id(c) for c in CASES])
def test_bad_input_is_a_clear_error_and_writes_nothing(case_id, fixture, status, words,
                                                       starter, tmp_path, monkeypatch, capsys):
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)  # a default ./out would land here and be seen
    argv = fixture(tmp_path, starter)
    if argv and argv[0] not in ("init",) and "--out" not in argv and argv[0] in (
            "twomass", "modes", "check", "friction", "bode", "compliance", "lobes", "table3"):
        argv = [*argv, "--out", str(tmp_path / "out")]
    before = _files(tmp_path)
    code = main(argv)
    err = capsys.readouterr().err
    assert code == status, err
    assert words in err, err
    assert "Traceback" not in err and "internal error" not in err, err
    assert _files(tmp_path) == before
