"""Modal identification from measured FRFs (servotune.measured, ``servotune identify``).

The reference is independent of the method: FRFs synthesised here from a 3-DOF M, K, C
(receptance H = (K - w^2 M + j w C)^-1) and the eigen-solution of its state matrix by
scipy.linalg.eig: natural frequencies |lambda|, damping ratios -Re(lambda)/|lambda| and the
residues of the receptance, (C v)(w^H B)/(w^H v) with the right and left eigenvectors v, w.
The FRFs are written to CSV and to UFF dataset 58 (pyuff's writer) and read back.

Tolerances: 0.5 % on the frequencies and 10 % on the damping ratios, with and without 1 %
complex noise (seeded); the residues within 2 % without noise and 10 % with it.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.linalg

from servotune.cli import main
from servotune.measured import FrfFileError, identify_modes, read_frfs
from servotune.measured.frf import read_frf_csv, read_frf_uff

# a 3-DOF chain, proportional damping plus a local damper at DOF 1 (complex modes)
M = np.diag([2.0, 1.5, 1.0])
K = 1e6 * np.array([[3.0, -1.5, 0.0], [-1.5, 2.5, -1.0], [0.0, -1.0, 1.2]])
C = 2e-5 * K + 5.0 * M + np.diag([40.0, 0.0, 0.0])
F_HZ = np.arange(0.0, 500.0 + 1e-9, 0.25)
FORCE_DOF = 0


def receptance(response: int) -> np.ndarray:
    """H[response, FORCE_DOF] at F_HZ, by solving (K - w^2 M + j w C) x = e."""
    w = 2 * np.pi * F_HZ
    force = np.eye(3)[:, FORCE_DOF]
    return np.array([np.linalg.solve(K - wi**2 * M + 1j * wi * C, force)[response] for wi in w])


def eigen_solution(response: int):
    """Natural frequencies [Hz], damping ratios and receptance residues from the state matrix."""
    n = M.shape[0]
    minv = np.linalg.inv(M)
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ K, -minv @ C]])
    b = np.concatenate([np.zeros(n), minv[:, FORCE_DOF]])
    c = np.concatenate([np.eye(n)[response], np.zeros(n)])
    lam, left, right = scipy.linalg.eig(a, left=True, right=True)
    keep = np.flatnonzero(lam.imag > 0)
    keep = keep[np.argsort(lam[keep].imag)]
    residues = np.array([(c @ right[:, k]) * (left[:, k].conj() @ b)
                         / (left[:, k].conj() @ right[:, k]) for k in keep])
    lam = lam[keep]
    return np.abs(lam) / (2 * np.pi), -lam.real / np.abs(lam), residues


def noisy(h: np.ndarray, level: float, seed: int) -> np.ndarray:
    """h with complex Gaussian noise of RMS ``level`` times |h| at each line."""
    if level == 0:
        return h
    rng = np.random.default_rng(seed)
    e = (rng.standard_normal(h.size) + 1j * rng.standard_normal(h.size)) / np.sqrt(2)
    return h + level * np.abs(h) * e


def write_csv(path, h, header="# quantity: receptance\n# units: m/N\n"):
    lines = [f"{f:.10g},{v.real:.17g},{v.imag:.17g}" for f, v in zip(F_HZ, h, strict=True)]
    path.write_text(header + "f_hz,re,im\n" + "\n".join(lines) + "\n")
    return path


def write_uff(path, responses, dataset_type=58, func_type=4):
    import pyuff

    sets = []
    for node, h in responses:
        sets.append(pyuff.prepare_58(
            binary=0, func_type=func_type, rsp_node=node, rsp_dir=1, ref_node=FORCE_DOF + 1,
            ref_dir=1, data=h, x=F_HZ, id1="hammer test", rsp_ent_name="wp", ref_ent_name="wp",
            abscissa_spacing=1, abscissa_spec_data_type=18, ordinate_spec_data_type=8,
            orddenom_spec_data_type=13))
    if dataset_type == 15:
        sets = [pyuff.prepare_15(node_nums=[1, 2], def_cs=[0, 0], disp_cs=[0, 0], color=[1, 1],
                                 x=[0.0, 1.0], y=[0.0, 0.0], z=[0.0, 0.0])]
    pyuff.UFF(str(path)).write_sets(sets, "overwrite")
    return path


def check_modes(fit, response: int, noise: float, frf_index: int = 0):
    f_ref, zeta_ref, residues_ref = eigen_solution(response)
    f = np.array([m.frequency / (2 * np.pi) for m in fit.modes])
    zeta = np.array([m.damping_ratio for m in fit.modes])
    residues = np.array([m.residues[frf_index] for m in fit.modes])
    assert f.size == 3, f
    np.testing.assert_allclose(f, f_ref, rtol=0.005)
    np.testing.assert_allclose(zeta, zeta_ref, rtol=0.10)
    tolerance = 0.02 if noise == 0 else 0.10
    assert np.all(np.abs(residues - residues_ref) <= tolerance * np.abs(residues_ref)), (
        residues, residues_ref)


@pytest.mark.parametrize("noise", [0.0, 0.01])
@pytest.mark.parametrize("response", [0, 2])
@pytest.mark.parametrize("fmt", ["csv", "uff"])
def test_modes_of_a_three_dof_system_match_its_eigen_solution(fmt, response, noise, tmp_path):
    h = noisy(receptance(response), noise, seed=11 + response)
    path = (write_csv(tmp_path / "h.csv", h) if fmt == "csv"
            else write_uff(tmp_path / "h.uff", [(response + 1, h)]))
    fit = identify_modes(read_frfs([path]))
    check_modes(fit, response, noise)
    # the synthesised FRF reproduces the measurement to about the noise
    assert fit.frf_error < (1e-3 if noise == 0 else 2 * noise)


def test_csv_and_uff_give_the_same_modes(tmp_path):
    h = noisy(receptance(0), 0.01, seed=3)
    from_csv = identify_modes([read_frf_csv(write_csv(tmp_path / "h.csv", h))])
    from_uff = identify_modes(read_frf_uff(write_uff(tmp_path / "h.uff", [(1, h)])))
    # UFF ASCII keeps 12 significant digits: the same poles to far better than the tolerances
    for a, b in zip(from_csv.modes, from_uff.modes, strict=True):
        assert a.frequency == pytest.approx(b.frequency, rel=1e-6)
        assert a.damping_ratio == pytest.approx(b.damping_ratio, rel=1e-4)
        assert abs(a.residues[0] - b.residues[0]) <= 1e-4 * abs(b.residues[0])
    assert len(from_csv.modes) == len(from_uff.modes) == 3


def test_several_frfs_one_fit_with_residues_per_frf(tmp_path):
    h0, h2 = noisy(receptance(0), 0.01, 5), noisy(receptance(2), 0.01, 6)
    files = [write_csv(tmp_path / "drive.csv", h0), write_csv(tmp_path / "far.csv", h2)]
    fit = identify_modes(read_frfs(files))
    check_modes(fit, 0, 0.01, frf_index=0)
    check_modes(fit, 2, 0.01, frf_index=1)
    # one UFF file with both records gives the same poles
    both = read_frfs([write_uff(tmp_path / "both.uff", [(1, h0), (3, h2)])])
    assert [f.name for f in both] == ["both.uff #1 (1:+X/1:+X)", "both.uff #2 (3:+X/1:+X)"]
    again = identify_modes(both)
    np.testing.assert_allclose([m.frequency for m in again.modes],
                               [m.frequency for m in fit.modes], rtol=1e-6)


def test_magnitude_phase_and_units_are_read_to_si(tmp_path):
    h = receptance(1)
    lines = [f"{f:.10g},{abs(v) * 1e6:.17g},{np.rad2deg(np.angle(v)):.17g}"
             for f, v in zip(F_HZ, h, strict=True)]
    path = tmp_path / "polar.csv"
    path.write_text("# quantity = receptance\n# units = um/N\nf_hz,mag,phase_deg\n"
                    + "\n".join(lines) + "\n")
    frf = read_frf_csv(path)
    np.testing.assert_allclose(frf.values, h, rtol=1e-12)
    np.testing.assert_allclose(frf.omega, 2 * np.pi * F_HZ)
    assert frf.quantity == "receptance" and frf.defaults == ()
    plain = tmp_path / "plain.csv"
    plain.write_text("f_hz,re,im\n1,1,0\n2,1,0\n")
    assert "a receptance in m/N (no '# quantity:'" in read_frf_csv(plain).defaults[0]


def test_modes_hz_picks_the_nearest_poles(tmp_path):
    h = noisy(receptance(0), 0.01, seed=9)
    fit = identify_modes(read_frfs([write_csv(tmp_path / "h.csv", h)]),
                         frequencies=[2 * np.pi * 260.0, 2 * np.pi * 90.0])
    f_ref, _, _ = eigen_solution(0)
    got = [m.frequency / (2 * np.pi) for m in fit.modes]
    np.testing.assert_allclose(got, [f_ref[0], f_ref[2]], rtol=0.005)
    assert [m.requested / (2 * np.pi) for m in fit.modes] == pytest.approx([90.0, 260.0])
    assert fit.chosen_by == "frequency"


def test_the_command_writes_json_and_figures(tmp_path, capsys):
    path = write_csv(tmp_path / "hammer.csv", noisy(receptance(0), 0.01, seed=1))
    code = main(["identify", str(path), "--band-hz", "20", "400", "--max-order", "30",
                 "--json", "--out", str(tmp_path / "out")])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    f_ref, zeta_ref, _ = eigen_solution(0)
    assert [m["frequency_hz"] for m in out["modes"]] == pytest.approx(f_ref, rel=0.005)
    assert [m["damping_ratio"] for m in out["modes"]] == pytest.approx(zeta_ref, rel=0.1)
    assert all(len(m["residue"]) == 2 for m in out["modes"])
    assert out["frf_error"] < 0.02 and out["files"] == [str(path)]
    assert out["band_hz"] == pytest.approx([20.0, 400.0])
    folder = tmp_path / "out" / "identify_hammer"
    assert {p.name for p in folder.iterdir()} >= {"results.json", "frf_fit.png",
                                                   "stabilisation.png"}
    assert "--kind" in out["not_done"] and "updated_axis" not in out


@pytest.mark.parametrize("content, words", [
    ("f_hz,re,im\n10,1e-6,0\n20,fast,0\n", "line 3: column 're' holds 'fast', not a number"),
    ("f_hz,real,imag\n10,1e-6,0\n20,1e-6,0\n", "needs the columns re,im or mag,phase_deg"),
    ("f_hz,re,im\n10,1e-6,0\n5,1e-6,0\n", "line 3: f_hz 5 does not increase"),
    ("# units: furlongs/N\nf_hz,re,im\n10,1e-6,0\n20,1e-6,0\n", "line 1: units 'furlongs/N'"),
])
def test_a_malformed_csv_is_a_clear_error_naming_the_file(content, words, tmp_path, capsys):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    with pytest.raises(FrfFileError, match=r"bad\.csv"):
        read_frf_csv(path)
    assert main(["identify", str(path), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert str(path) in err and words in err, err
    assert not (tmp_path / "out").exists()


def test_a_uff_file_without_frfs_is_a_clear_error(tmp_path, capsys):
    nodes = write_uff(tmp_path / "nodes.uff", [], dataset_type=15)
    assert main(["identify", str(nodes), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert str(nodes) in err and "dataset(s) 15 (nodes), no dataset 58" in err, err
    timed = write_uff(tmp_path / "time.uff", [(1, receptance(0))], func_type=1)
    with pytest.raises(FrfFileError, match=r"time.uff: no dataset 58 holds a frequency "
                                           r"response function .*records: 1 \(time response\)"):
        read_frf_uff(timed)


def test_frfs_on_different_lines_are_refused(tmp_path):
    a = write_csv(tmp_path / "a.csv", receptance(0))
    b = tmp_path / "b.csv"
    b.write_text("f_hz,re,im\n" + "\n".join(f"{f},{1e-6},0" for f in F_HZ[::2]) + "\n")
    with pytest.raises(ValueError, match="different frequency lines"):
        identify_modes(read_frfs([a, b]))


@pytest.mark.parametrize("quantity, power", [("mobility", 1), ("accelerance", 2)])
def test_mobility_and_accelerance_give_the_receptance_residues(quantity, power, tmp_path):
    # (j w)^power H: the same poles, and LSFD reports the residues of the receptance
    jw = 2j * np.pi * F_HZ
    h = noisy(jw**power * receptance(0), 0.01, seed=21)
    path = write_csv(tmp_path / "h.csv", h, header=f"# quantity: {quantity}\n")
    frf = read_frf_csv(path)
    assert frf.quantity == quantity and "units" in frf.defaults[0]
    fit = identify_modes([frf])
    check_modes(fit, 0, 0.01)
    assert fit.frf_error < 0.02


def test_the_rule_keeps_poles_stable_over_orders_and_drops_drifting_ones():
    from servotune.measured.ema import (
        PoleEstimates,
        SelectionRule,
        choose_poles,
        stabilisation_diagram,
    )

    def pole(f_hz, zeta):
        w = 2 * np.pi * f_hz
        return complex(-zeta * w, w * np.sqrt(1 - zeta**2))

    orders = tuple(range(2, 22, 2))
    poles = tuple(np.array([
        pole(100.0 * (1 + 1e-4 * k), 0.02),        # stable: 0.01 % steps
        pole(200.0, 0.02 * 1.2**k),                # damping drifts 20 % per order
        pole(300.0 * (1 + 0.05 * k), 0.02),        # frequency drifts 5 % per order
        pole(150.0, -0.01),                        # unstable pole: damping out of range
    ]) for k in range(len(orders)))
    diagram = stabilisation_diagram(PoleEstimates(orders, poles, (2 * np.pi, 2 * np.pi * 900)),
                                    SelectionRule())
    at = {round(f): diagram.status[(diagram.order == 20) & (np.isclose(
        diagram.frequency / (2 * np.pi), f, rtol=0.5e-3))] for f in (100.09, 200.0, 150.0)}
    assert at[100].tolist() == [2] and at[200].tolist() == [1] and at[150].tolist() == [-1]
    chosen, _ = choose_poles(diagram)
    assert len(chosen) == 1 and diagram.frequency[chosen[0]] / (2 * np.pi) == pytest.approx(
        100.0, rel=2e-3)
    assert diagram.run[chosen[0]] >= 5
