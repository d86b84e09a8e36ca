"""``scoutsim assumptions`` (scoutsim.cli.assumptions): the command writes its table, JSON
and figure, prints the Markdown table with a verdict for every case, and refuses a bad
basin grid or reference with exit code 2."""

import csv
import json

from scoutsim.cli import main


def test_assumptions_quick_writes_the_table_json_and_figure(tmp_path, capsys):
    out = tmp_path / "assume"
    code = main(
        [
            "assumptions",
            "--quick",
            "--basin-grid",
            "0x0",
            "--workers",
            "1",
            "--no-progress",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    rows = list(csv.DictReader(open(out / "assumptions.csv")))
    cases = [r["case"] for r in rows]
    assert cases[:5] == ["ideal", "ideal+line", "I", "II", "II+effects"]
    assert "-belt" in cases and "-gear-inertia" in cases
    by = {r["case"]: r for r in rows}
    assert by["-gear-inertia"]["status"] == "not_switchable"
    assert by["-battery-sag"]["status"] == "absent"
    # the reference's percents are 0 where it bounds
    assert float(by["II+effects"]["pct_mean_speed_m_s"]) == 0.0
    data = json.loads((out / "assumptions.json").read_text())
    assert data["reference"] == "II+effects" and len(data["rows"]) == len(rows)
    # --quick shortens the runs; the basin grid given (none) is kept
    assert data["settings"]["duration_s"] == 5.0 and data["settings"]["basin_speeds_m_s"] == []
    assert (out / "assumptions.png").stat().st_size > 0
    printed = capsys.readouterr().out
    assert "| case | verdict |" in printed and "not switchable" in printed


def test_assumptions_refuses_a_bad_basin_grid_and_reference(tmp_path, capsys):
    assert main(["assumptions", "--basin-grid", "2by1", "--out", str(tmp_path)]) == 2
    assert "--basin-grid" in capsys.readouterr().err
    code = main(
        [
            "assumptions",
            "--reference",
            "III",
            "--duration",
            "0.5",
            "--basin-grid",
            "0x0",
            "--workers",
            "1",
            "--no-progress",
            "--no-plots",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 2
    assert "reference 'III'" in capsys.readouterr().err
