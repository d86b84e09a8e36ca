"""`scoutsim tune` on the command line: its files, the controller file it writes read back
by `scoutsim run --controller FILE`, Ctrl-C and the run again, and its error messages."""

import csv
import json
import math
import sys

import pytest

from scoutsim import SimulationResult
from scoutsim.cli import main

pytest.importorskip("cmaes")

TUNE = [
    "tune",
    "--objective",
    "speed",
    "--target",
    "1.3",
    "--param",
    "controller.touchdown_angle_front_deg=18:26",
    "--param",
    "controller.touchdown_angle_back_deg=16:24",
    "--budget",
    "8",
    "--population",
    "4",
    "--duration",
    "3",
    "--workers",
    "1",
    "--no-progress",
]


def test_tune_writes_its_files_and_run_reads_the_controller_file(tmp_path, capsys):
    out = tmp_path / "tune"
    assert main(TUNE + ["--out", str(out)]) == 0
    printed = capsys.readouterr().out
    for name in (
        "tune.csv",
        "tune.parquet",
        "convergence.png",
        "best.toml",
        "best.json",
        "manifest.json",
        "evaluations.jsonl",
        "optimizer.pkl",
    ):
        assert (out / name).exists(), name
    assert json.loads((out / "manifest.json").read_text())["status"] == "complete"
    rows = list(csv.DictReader(open(out / "tune.csv")))
    assert len(rows) == 8
    best = json.loads((out / "best.json").read_text())
    assert f"run it: scoutsim run --controller {out}/best.toml" in printed

    run_out = tmp_path / "run"
    assert (
        main(
            [
                "run",
                "--controller",
                str(out / "best.toml"),
                "--duration",
                "3",
                "--out",
                str(run_out),
                "--no-progress",
                "--no-energy",
            ]
        )
        == 0
    )
    r = SimulationResult.load(run_out)
    c = r.provenance["controller"]
    deg = best["parameters"]
    assert math.degrees(c["touchdown_angle_front"]) == pytest.approx(
        deg["controller.touchdown_angle_front_deg"], rel=1e-15
    )
    assert c["touchdown_angle_back"] == best["parameters_si"]["controller.touchdown_angle_back"]
    summary = json.loads((run_out / "summary.json").read_text())
    assert summary["outcome"] == best["metrics"]["outcome"]
    assert summary["n_steady_strides"] == best["metrics"]["n_steady_strides"]


def test_ctrl_c_keeps_the_evaluations_and_the_same_command_goes_on(tmp_path, monkeypatch, capsys):
    from scoutsim.analysis import tune as T

    whole = tmp_path / "whole"
    assert main(TUNE + ["--out", str(whole)]) == 0
    real, calls = T.tune_task, []

    def cut(task):
        calls.append(1)
        if len(calls) == 6:
            raise KeyboardInterrupt
        return real(task)

    monkeypatch.setattr(T, "tune_task", cut)
    cut_dir = tmp_path / "cut"
    assert main(TUNE + ["--out", str(cut_dir)]) == 130
    err = capsys.readouterr().err
    assert "5 evaluations are done" in err and "run the same command again" in err
    monkeypatch.setattr(T, "tune_task", real)
    assert main(TUNE + ["--out", str(cut_dir)]) == 0
    assert "(5 resumed" in capsys.readouterr().out
    assert (cut_dir / "tune.csv").read_bytes() == (whole / "tune.csv").read_bytes()


@pytest.mark.parametrize(
    "argv, words",
    [
        (["--param", "controller.touchdown_angle_frnt_deg"], ["touchdown_angle_frnt_deg"]),
        (["--param", "controller.touchdown_angle_front_deg=30:20"], ["LOW must be below HIGH"]),
        (["--param", "robot.leg_stiffness"], ["robot.leg_stiffness", "needs a range"]),
        (
            ["--param", "robot.leg_stiffness=-5:3000"],
            ["robot.leg_stiffness=-5:3000", "allowed values"],
        ),
        ([], ["--param"]),
        (
            ["--param", "controller.touchdown_angle_front_deg", "--refine", "-1"],
            ["refine = -1 is not allowed"],
        ),
    ],
)
def test_bad_params_exit_2_naming_them(tmp_path, capsys, argv, words):
    code = main(["tune", "--target", "1.3", "--out", str(tmp_path)] + argv)
    assert code == 2
    err = capsys.readouterr().err
    for w in words:
        assert w in err


def test_speed_needs_a_target(tmp_path, capsys):
    assert (
        main(["tune", "--param", "controller.touchdown_angle_front_deg", "--out", str(tmp_path)])
        == 2
    )
    assert "--target" in capsys.readouterr().err


def test_without_the_optimiser_library_tune_says_what_to_install(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "cmaes", None)
    assert main(TUNE + ["--out", str(tmp_path)]) == 2
    assert "pip install cmaes" in capsys.readouterr().err


def test_run_with_a_missing_or_bad_controller_file_exits_2(tmp_path, capsys):
    assert (
        main(
            [
                "run",
                "--controller",
                str(tmp_path / "nope.toml"),
                "--duration",
                "0.1",
                "--out",
                str(tmp_path / "o"),
            ]
        )
        == 2
    )
    assert "nope.toml" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text(
        '[controller_law]\nname = "table-i"\n[controller]\n'
        'touchdown_angle_front = { value = 120, unit = "deg" }\n'
    )
    assert (
        main(["run", "--controller", str(bad), "--duration", "0.1", "--out", str(tmp_path / "o")])
        == 2
    )
    assert "touchdown_angle_front" in capsys.readouterr().err
