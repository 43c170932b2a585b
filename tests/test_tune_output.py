"""What ``servotune tune`` prints: the verdict first (its label agrees with the exit status
and with the --json run's), then the design and the report's path, then the details."""

import json
from pathlib import Path

from servotune.cli import main

MODELS = Path(__file__).resolve().parents[1] / "models"


def test_the_verdict_comes_first_and_agrees_with_the_exit_status(tmp_path, capsys):
    code = main(["tune", str(MODELS / "two_mass_fig5"), "--out", str(tmp_path / "text")])
    lines = capsys.readouterr().out.splitlines()
    assert main(["tune", str(MODELS / "two_mass_fig5"), "--out", str(tmp_path / "json"),
                 "--json"]) == code
    result = json.loads(capsys.readouterr().out)
    label = "VERIFIED" if code == 0 else "NOT VERIFIED"
    assert result["verified"] is (code == 0)
    from servotune.axis import load_axis

    axis = load_axis(MODELS / "two_mass_fig5")
    assert result["friction_law"] == (axis.friction.law.name if axis.friction else None)
    first = lines[0]
    assert first.startswith(f"two_mass_fig5: {label}")
    details = lines.index("Details")
    top = lines[:details]
    assert any(line.startswith("  design: C ") for line in top)
    report = [line for line in top if line.startswith("  report: ")]
    assert report and report[0].endswith("report.html")
    assert Path(report[0].split("report: ")[1]).is_file()
    # the tables come after the verdict, and the last lines repeat it and the report
    assert any("Design" in line for line in lines[details:])
    assert lines[-1] == report[0]
    assert any(line.startswith(f"two_mass_fig5: {label}") for line in lines[-4:])
