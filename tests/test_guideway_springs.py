"""An FE export that keeps its guide-way springs (the slide held to the ground at its pads):
without them named, the tuning says where the structure is held and the field that fixes it;
with them named ([structure] guideway_springs), the springs come out of the stiffness and the
friction model takes their place -- here giving back the bundled axis exactly."""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from servotune.axis import AxisFormatError, load_axis
from servotune.cli import main

PAPER = Path(__file__).resolve().parents[1] / "models" / "paper_x_axis"
SPRINGS = {"pad1.x": 2.0e8, "pad2.x": 2.0e8, "pad3.x": 3.0e8, "pad4.x": 3.0e8}   # N/m


def grounded(folder: Path, named: bool, springs=SPRINGS) -> Path:
    """The bundled axis whose structure holds its pads to the ground by springs, as an FE
    export with its guide-way spring elements; with ``named`` the axis file names them."""
    shutil.copytree(PAPER, folder)
    data = dict(np.load(folder / "structure.npz"))
    dofs = [str(d) for d in data["dofs"]]
    k = data["stiffness"].copy()
    for dof, value in SPRINGS.items():
        i = dofs.index(dof)
        k[i, i] += value
    np.savez(folder / "structure.npz", mass=data["mass"], stiffness=k, dofs=data["dofs"])
    if named:
        table = ", ".join(f'"{d}" = {v!r}' for d, v in springs.items())
        text = (folder / "axis.toml").read_text().replace(
            'file = "structure.npz"', f'file = "structure.npz"\nguideway_springs = {{ {table} }}',
            1)
        (folder / "axis.toml").write_text(text)
    return folder


def test_named_springs_come_out_and_give_back_the_free_slide(tmp_path):
    axis = load_axis(grounded(tmp_path / "named", named=True))
    paper = load_axis(PAPER)
    np.testing.assert_allclose(axis.structure.stiffness, paper.structure.stiffness,
                               rtol=0, atol=1e-9 * np.abs(paper.structure.stiffness).max())
    np.testing.assert_allclose(axis.structure.natural_frequencies(),
                               paper.structure.natural_frequencies(), rtol=1e-6, atol=1e-6)


def test_an_unnamed_grounded_slide_is_refused_naming_where_it_is_held_and_the_fix(tmp_path,
                                                                                  capsys):
    folder = grounded(tmp_path / "held", named=False)
    code = main(["tune", str(folder), "--no-simulation", "--json", "--out", str(tmp_path / "o")])
    out = json.loads(capsys.readouterr().out)
    assert code == 1
    text = out["error"]
    for part in ("no rigid-body travel", "guideway_springs", "pad1.x", "friction model"):
        assert part in text, text
    # the holding forces are the springs: 1e9 N per m of common travel in all
    from servotune.thrust import holding_forces

    held = dict(holding_forces(load_axis(folder).structure, list(SPRINGS)))
    for dof, value in SPRINGS.items():
        assert held[dof] == pytest.approx(value, rel=1e-6)


def test_a_spring_beyond_the_model_s_stiffness_or_an_unknown_dof_is_refused(tmp_path):
    with pytest.raises(AxisFormatError, match=r"guideway_springs\.pad1\.x.*more than the "
                                              r"stiffness"):
        load_axis(grounded(tmp_path / "a", named=True,
                           springs={"pad1.x": 1e15}))
    with pytest.raises(AxisFormatError, match=r"guideway_springs\.pad9\.x.*unknown DOF"):
        load_axis(grounded(tmp_path / "b", named=True, springs={"pad9.x": 1e8}))
    with pytest.raises(AxisFormatError, match=r"guideway_springs\.pad1\.x.*N/m"):
        load_axis(grounded(tmp_path / "c", named=True, springs={"pad1.x": -1.0}))


def test_a_loop_that_does_nothing_is_named_so_and_has_no_bandwidth():
    """A velocity loop whose actuator barely moves what it measures (|L| <= 6e-5 as a
    grounded export gives): its closed-loop gain stays about |L|, it is inert, its
    bandwidth is not a number and its JSON says why; a working loop is not."""
    from servotune.frequency import analyse_response

    w = np.geomspace(1.0, 1e4, 2000)
    weak = 6e-5 * (1 + 10 / (1j * w)) / (1 + 1j * w / 100)       # a PI on a held structure
    a = analyse_response(w, weak, weak[0])
    assert a.inert and np.isnan(a.bandwidth)
    assert a.closed_loop_gain_max == pytest.approx(np.abs(weak / (1 + weak)).max())
    assert a.closed_loop_gain_max < 1e-3
    d = a.to_dict()
    assert d["inert"] and "does nothing" in d["note"]
    working = analyse_response(w, 100.0 / (1j * w), 100.0 / (1j * 0.01))
    assert not working.inert and working.bandwidth == pytest.approx(100.0, rel=1e-2)
    assert "note" not in working.to_dict()
