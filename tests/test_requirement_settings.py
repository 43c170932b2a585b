"""A requirement of another package declares its settings (servotune.requirements.Setting): the
axis file's [requirements] accepts and validates them, `servotune init` lists them, the report's
inputs table shows their values and the requirement reads them. The worked example is
examples/plugins/following_error, installed here as pip would (a folder on sys.path with its
dist-info and entry point)."""

import importlib
import math
import re
import shutil
import sys
from pathlib import Path

import pytest

from servotune.friction import law as law_registry
from servotune.plugins import REQUIREMENTS_GROUP
from servotune.requirements import Requirements, Setting
from servotune.tuning import constraint

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "plugins" / "following_error"


@pytest.fixture
def following_error(tmp_path, monkeypatch):
    """The example installed; its class. The registries are as before afterwards."""
    saved = [dict(law_registry._REGISTRY), dict(constraint._REGISTRY), dict(constraint._LOADED),
             dict(constraint._ORIGIN)]
    folder = tmp_path / "site"
    info = folder / "following_error-0.1.dist-info"
    info.mkdir(parents=True)
    shutil.copy(EXAMPLE / "following_error.py", folder / "following_error.py")
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: following-error\n"
                                   "Version: 0.1\n")
    project = (EXAMPLE / "pyproject.toml").read_text()
    point = re.search(r"following_error = \"([^\"]+)\"", project).group(1)
    (info / "entry_points.txt").write_text(f"[{REQUIREMENTS_GROUP}]\n"
                                           f"following_error = {point}\n")
    monkeypatch.syspath_prepend(str(folder))
    importlib.invalidate_caches()
    yield lambda: importlib.import_module("following_error").FollowingError
    sys.modules.pop("following_error", None)
    for registry, before in zip((law_registry._REGISTRY, constraint._REGISTRY,
                                 constraint._LOADED, constraint._ORIGIN), saved, strict=True):
        registry.clear()
        registry.update(before)


def axis_with(tmp_path, lines: str) -> Path:
    folder = tmp_path / "axis"
    shutil.copytree(ROOT / "models" / "paper_x_axis", folder)
    text = (folder / "axis.toml").read_text()
    if "[requirements]" in text:
        text = text.replace("[requirements]", "[requirements]\n" + lines, 1)
    else:
        text += "\n[requirements]\n" + lines
    (folder / "axis.toml").write_text(text)
    return folder


def test_a_declared_setting_is_read_validated_and_reaches_the_requirement(following_error,
                                                                         tmp_path):
    from servotune.axis import load_axis
    from servotune.design import tuning_problem

    cls = following_error()
    assert "following_error_max_m" in constraint.declared_settings()
    axis = load_axis(axis_with(tmp_path, "following_error_max_m = 2.0e-4\n"))
    assert dict(axis.requirements.settings) == {"following_error_max_m": 2.0e-4}
    problem = tuning_problem(axis)
    assert cls.applies(problem)
    assert cls.setting(problem, "following_error_max_m") == 2.0e-4
    # the row the tuner imposes: Kv e_max / v_max >= 1 at the highest feed speed (40 mm/s)
    (name, row, low, high), = cls.design_rows(problem, lambda var: {"kv": 250.0}[var])
    assert name == "following_error" and (low, high) == (1.0, math.inf)
    assert row == pytest.approx(250.0 * 2.0e-4 / 0.04)
    # the check: e = v / Kv against the setting
    from servotune.tuning import Design

    check, = cls.design_checks(problem, Design(c=1e4, kv=100.0, kp=5.0, ti=0.03))
    assert check.value == pytest.approx(0.04 / 100.0) and not check.holds
    check, = cls.design_checks(problem, Design(c=1e4, kv=300.0, kp=5.0, ti=0.03))
    assert check.holds


def test_a_setting_out_of_its_declared_range_is_refused_naming_key_range_and_owner(
        following_error, tmp_path):
    from servotune.axis import AxisFormatError, load_axis

    following_error()
    with pytest.raises(AxisFormatError) as err:
        load_axis(axis_with(tmp_path, "following_error_max_m = 0.2\n"))   # 200 mm: a unit slip
    text = str(err.value)
    for part in ("[requirements] following_error_max_m", "outside [1e-07, 0.01] m",
                 "'following_error'", "axis.toml"):
        assert part in text, text


def test_without_the_plugin_the_key_is_unknown_and_the_message_lists_the_known(tmp_path):
    from servotune.axis import AxisFormatError, load_axis

    with pytest.raises(AxisFormatError, match=r"unknown keys \['following_error_max_m'\]"):
        load_axis(axis_with(tmp_path, "following_error_max_m = 2.0e-4\n"))


def test_init_lists_the_declared_settings_and_the_report_shows_their_values(following_error,
                                                                           tmp_path):
    from servotune.summary import setting_rows
    from servotune.template import write_template

    following_error()
    files = write_template(tmp_path / "starter")
    text = files[0].read_text()
    line = next(x for x in text.splitlines() if x.startswith("# following_error_max_m"))
    assert "[m]" in line and "in [1e-07, 0.01]" in line and "'following_error'" in line
    # the starter axis with the line uncommented loads
    from servotune.axis import load_axis

    files[0].write_text(text.replace(line, "following_error_max_m = 5e-4"))
    axis = load_axis(tmp_path / "starter")
    assert axis.requirements.value(constraint.declared_settings()[
        "following_error_max_m"][0]) == 5e-4
    rows = setting_rows(axis.requirements)
    assert rows == [("requirement following_error", "following_error_max_m = 0.0005 m",
                     rows[0][2])]
    assert "in [1e-07, 0.01] m" in rows[0][2]
    assert setting_rows(Requirements())[0][1] == "following_error_max_m = off (not given)"


def test_a_setting_is_declared_with_its_range_and_refused_when_malformed():
    with pytest.raises(ValueError, match="lower-case identifier"):
        Setting("Bad-Name", "m", None, 0.0, 1.0, "x")
    with pytest.raises(ValueError, match="outside"):
        Setting("x_m", "m", 2.0, 0.0, 1.0, "x")
    with pytest.raises(ValueError, match="must be a number"):
        Setting("x_m", "m", None, 0.0, 1.0, "x").parse("0.5")
    assert Requirements(settings={"b": 2, "a": 1.0}).settings == (("a", 1.0), ("b", 2.0))
    hash(Requirements(settings={"a": 1.0}))          # still hashable (a frozen value)


def test_a_requirement_declaring_a_builtin_field_or_a_duplicate_is_refused():
    class Clash(constraint.Requirement):
        settings = (Setting("kv_min", "1/s", None, 0.0, 1.0, "x"),
                    Setting("a_m", "m", None, 0.0, 1.0, "x"),
                    Setting("a_m", "m", None, 0.0, 1.0, "x"))

    problems = " ".join(constraint.requirement_problems(Clash))
    assert "['a_m', 'kv_min']" in problems
