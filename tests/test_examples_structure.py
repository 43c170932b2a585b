"""The structure examples run and give what independent references say (closed forms)."""

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_reduce_fe_export_with_checks(tmp_path):
    example = load("reduce_fe_export_with_checks")
    r = example.main(tmp_path)
    # the ports: node 1 (the hub, first row) and the node nearest the first rib's tip, 1059
    assert r["ports_rows"] == [0, example.N_PER_RIB]
    rib = example.rib_frequencies_hz(3)
    # too few modes: the check fails, names the band, what was reached and the fix
    few = r["few"]
    assert few["passed"] is False
    for text in ("5-150 Hz", "225 Hz", "f_max_hz = 225"):
        assert text in few["coverage_message"]
    # enough: five free ribs give each fixed-free chain frequency five times (closed form)
    enough = r["enough"]
    assert enough["passed"] is True, enough["failures"]
    f = np.array(enough["fixed_interface_hz"])
    for value in rib:
        assert np.sum(np.isclose(f, value, rtol=1e-9)) == 5
    # in the full model the ribs swinging against each other keep the first frequency exactly
    full = np.array(enough["full_frequencies_hz"])
    assert np.sum(np.isclose(full, rib[0], rtol=1e-9)) == 5
    assert enough["max_frequency_error"] < 1e-3
    assert enough["max_compliance_error"] < 0.05
    assert math.isfinite(enough["max_compliance_error"])


def test_example_data_are_written_as_an_export(tmp_path):
    example = load("reduce_fe_export_with_checks")
    example.write_export(tmp_path)
    header = (tmp_path / "dofs.csv").read_text().splitlines()[:2]
    assert header == ["index,node,dof", "1,1,UZ"]
    with pytest.raises(ValueError, match="nearest node"):
        import servotune as st

        (tmp_path / "ports.csv").write_text("port,node,x,y,z,direction\nwp.z,,2.0,0,0,UZ\n")
        st.read_structure(tmp_path / "M.mtx", tmp_path / "K.mtx", tmp_path / "dofs.csv",
                          ports=tmp_path / "ports.csv", coordinates=tmp_path / "nodes.csv")
