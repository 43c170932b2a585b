"""Property-based tests (hypothesis) of the axis loader and of the command line's validators.

* Any TOML, made from the starter axis by replacing a value with anything TOML can hold,
  deleting a key or a section, or adding an unknown key, either loads or raises the project's
  own ``AxisFormatError`` naming the field (never another exception).
* The numeric flag types accept exactly the finite numbers in their range, and refuse
  everything else with a message giving the range.
* A results folder name made from any subject stays inside ``--out``; any nested result
  becomes strict JSON.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import tomllib
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from servotune.axis import AxisFormatError, load_axis
from servotune.cli._common import RunOutput, number, safe_name, to_jsonable
from servotune.template import template_structure, template_toml

TEMPLATE = tomllib.loads(template_toml("prop"))
FOLDER = Path(tempfile.mkdtemp(prefix="servotune-axis-properties-"))
_m, _k, _dofs = template_structure()
np.savez(FOLDER / "structure.npz", mass=_m, stiffness=_k, dofs=np.array(_dofs))


def _leaves(table, path=()):
    for key, value in table.items():
        if isinstance(value, dict) and value and key != "lugre":
            yield from _leaves(value, (*path, key))
        else:
            yield (*path, key)


LEAVES = sorted(_leaves(TEMPLATE))
SECTIONS = sorted({leaf[:-1] for leaf in LEAVES if len(leaf) > 1})

toml_scalars = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.text(max_size=12),
    st.booleans(),
    st.sampled_from([0, 1, -1, 1e300, -1e300, 1e-300, 2.0, 0.5]),
)
toml_values = st.one_of(toml_scalars, st.lists(toml_scalars, max_size=4),
                        st.dictionaries(st.sampled_from(["a", "fc", "x"]), toml_scalars,
                                        max_size=2))


def _set(data, path, value):
    table = data
    for key in path[:-1]:
        table = table[key]
    if value is _DELETE:
        del table[path[-1]]
    else:
        table[path[-1]] = value


_DELETE = object()


def _copy(data):
    return json.loads(json.dumps(data))


def _load(data) -> None:
    (FOLDER / "axis.toml").write_text(tomli_w.dumps(data))
    load_axis(FOLDER)


def _names_the_field(message: str, path) -> bool:
    words = [path[-1], f"[{'.'.join(path[:-1])}]" if len(path) > 1 else f"[{path[0]}]"]
    return any(w in message for w in words)


# Cases the loader once got wrong (a traceback, or the wrong name in the message), kept as
# explicit examples.
FIXED_GAPS = [
    (("drive", "motor", "rotor"), [], "a list as a DOF name ends in TypeError (unhashable)"),
    (("drive", "motor", "stator"), ["x"], "a list as a DOF name ends in TypeError"),
    (("drive", "position_loop", "kv_m_per_min_per_mm"), math.inf,
     "the error names Drive.kv, not the field kv_m_per_min_per_mm"),
    (("cutting", "feed_per_tooth"), 0.0078125,
     "a feed from [cutting] (6.25 m/s) above the rapid speed named only speed_max_rpm"),
    (("drive", "transmission", "ratio"), 1e-6,
     "a rapid speed (top speed x ratio) below the feed named only speed_max_rpm"),
    (("drive", "motor", "speed_max_rpm"), 1.0, "the same, from the motor's top speed"),
]


@pytest.mark.parametrize("path, value", [(path, value) for path, value, _ in FIXED_GAPS])
def test_earlier_gaps_of_the_loader_name_the_field(path, value):
    data = _copy(TEMPLATE)
    _set(data, path, value)
    with pytest.raises(AxisFormatError) as info:
        _load(data)
    assert _names_the_field(str(info.value), path)


def test_the_starter_itself_loads():
    _load(_copy(TEMPLATE))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(LEAVES), value=toml_values)
@example(path=("cutting", "kt"), value=-1.0)
@example(path=("drive", "motor", "resistance"), value=math.nan)
@example(path=("structure", "modal_damping"), value=[0.03, "x"])
@example(path=("friction", "pads"), value=[])
def test_any_value_anywhere_loads_or_names_the_field(path, value):
    data = _copy(TEMPLATE)
    _set(data, path, value)
    try:
        _load(data)
    except AxisFormatError as exc:
        assert "axis.toml" in str(exc) or "structure" in str(exc)
        assert _names_the_field(str(exc), path), (path, value, str(exc))


@settings(max_examples=100, deadline=None)
@given(path=st.sampled_from(LEAVES))
def test_a_missing_key_loads_with_its_default_or_is_named(path):
    data = _copy(TEMPLATE)
    _set(data, path, _DELETE)
    try:
        _load(data)
    except AxisFormatError as exc:
        assert _names_the_field(str(exc), path), (path, str(exc))


@settings(max_examples=60, deadline=None)
@given(section=st.sampled_from(SECTIONS), key=st.text(
    alphabet="abcdefghijklmnopqrstuvwxyz_", min_size=1, max_size=10))
def test_an_unknown_key_is_refused_by_name(section, key):
    data = _copy(TEMPLATE)
    table = data
    for name in section:
        table = table[name]
    assume(key not in table)
    table[key] = 1.0
    with pytest.raises(AxisFormatError, match=key):
        _load(data)


def test_unknown_axis_keys_are_refused():
    data = _copy(TEMPLATE)
    data["axis"]["descripton"] = "misspelt"
    with pytest.raises(AxisFormatError, match="descripton"):
        _load(data)


@settings(max_examples=40, deadline=None)
@given(section=st.sampled_from(sorted({s[0] for s in SECTIONS} | {"axis", "cutting"})))
def test_a_missing_section_loads_or_names_it(section):
    data = _copy(TEMPLATE)
    del data[section]
    try:
        _load(data)
    except AxisFormatError as exc:
        assert f"[{section}]" in str(exc), str(exc)


# --------------------------------------------------------------------------- CLI validators

bounds = st.tuples(st.floats(-1e6, 1e6), st.floats(0, 1e6)).map(lambda t: (t[0], t[0] + t[1]))


@given(limits=bounds, text=st.one_of(st.text(max_size=8), st.floats().map(repr),
                                     st.integers(-10**6, 10**6).map(str)),
       low_open=st.booleans(), high_open=st.booleans())
def test_a_number_flag_takes_exactly_the_finite_numbers_in_range(limits, text, low_open,
                                                                  high_open):
    low, high = limits
    parse = number(low, high, low_open=low_open, high_open=high_open)
    try:
        expected = float(text)
    except ValueError:
        expected = None
    ok = expected is not None and math.isfinite(expected) and (
        expected > low if low_open else expected >= low) and (
        expected < high if high_open else expected <= high)
    if ok:
        assert parse(text) == expected
    else:
        with pytest.raises(argparse.ArgumentTypeError, match="give a number in"):
            parse(text)


@given(text=st.text(max_size=8), low=st.integers(-5, 5), span=st.integers(0, 10))
def test_a_whole_number_flag_refuses_fractions_and_out_of_range(text, low, span):
    parse = number(low, low + span, integer=True)
    try:
        value = int(text)
    except ValueError:
        value = None
    if value is not None and low <= value <= low + span:
        assert parse(text) == value
    else:
        with pytest.raises(argparse.ArgumentTypeError, match=f"from {low} to {low + span}"):
            parse(text)


@given(name=st.text(max_size=40))
def test_a_results_folder_stays_inside_out(name):
    safe = safe_name(name)
    assert safe and "/" not in safe and "\\" not in safe and ".." not in safe
    assert not safe.startswith(".")
    out = Path("/tmp/out")
    assert (out / f"bode_{safe}").resolve().parent == out.resolve()


@settings(deadline=None)
@given(name=st.text(max_size=20))
def test_the_run_folder_of_any_subject_is_a_child_of_out(name):
    out = Path(tempfile.mkdtemp(prefix="servotune-out-"))
    run = RunOutput(out, "modes", name)
    assert run.path.parent == out


json_leaves = st.one_of(st.floats(), st.integers(-10**9, 10**9), st.text(max_size=5),
                        st.none(), st.booleans())
nested = st.recursive(json_leaves, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=5), inner, max_size=4)),
    max_leaves=20)


@given(obj=nested)
def test_any_result_becomes_strict_json(obj):
    text = json.dumps(to_jsonable({"result": obj}), allow_nan=False)
    assert json.loads(text)["result"] is not None or obj is None or (
        isinstance(obj, float) and not math.isfinite(obj))

