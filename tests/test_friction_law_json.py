"""Every command whose results rest on a friction law names it (``friction_law`` in its JSON):
the bundled axis' LuGre, the same axis with the GMS law, and none where no axis is given."""

import json
import re
import shutil
from pathlib import Path

import pytest

from servotune.cli import main

PAPER = Path(__file__).resolve().parents[1] / "models" / "paper_x_axis"


def gms_axis(folder: Path) -> Path:
    from test_friction_gms import P

    shutil.copytree(PAPER, folder)
    text = re.sub(r"variation = \{[^}]*\}[^\n]*\n(\s+#[^\n]*\n)*", "",
                  (folder / "axis.toml").read_text())
    start, end = text.index("[friction.lugre]"), text.index("[drive]")
    table = "\n".join(f"{k} = {v!r}" for k, v in (
        ("stiffness", list(P.stiffness)), ("fractions", list(P.fractions)),
        ("damping", list(P.damping)), ("fc", P.fc), ("fs", P.fs), ("vs", P.vs),
        ("delta", P.delta), ("sigma2", P.sigma2), ("attraction", P.attraction)))
    (folder / "axis.toml").write_text(text[:start] + "[friction.gms]\n" + table + "\n\n"
                                      + text[end:])
    return folder


def run(capsys, argv):
    code = main([*argv, "--json"])
    out = json.loads(capsys.readouterr().out)
    return code, out


@pytest.mark.parametrize("command", [["compliance", "--continuous", "--no-plots"], ["modes"],
                                     ["bode", "--continuous", "--no-plots"],
                                     ["lobes", "--continuous", "--no-plots"]])
def test_the_law_is_named(tmp_path, capsys, command):
    name, *flags = command
    code, out = run(capsys, [name, str(PAPER), *flags, "--out", str(tmp_path / "a")])
    assert code == 0 and out["friction_law"] == "lugre"
    written = json.loads(next((tmp_path / "a").glob("*/results.json")).read_text())
    assert written["friction_law"] == "lugre"
    if name in ("compliance", "modes"):
        code, out = run(capsys, [name, str(gms_axis(tmp_path / "g")), *flags, "--out",
                                 str(tmp_path / "b")])
        assert code == 0 and out["friction_law"] == "gms"


def test_no_law_without_an_axis(tmp_path, capsys):
    code, out = run(capsys, ["lobes", "--mode", "922", "0.02", "1e7", "--no-plots", "--out",
                             str(tmp_path)])
    assert code == 0 and out["friction_law"] is None
