"""Every command reads a robot file whose legs differ ([back, front] values) and whose torso
COM is off centre, and runs every model with it; what cannot be done with such a robot
(one hip unit identified for two different ones) is refused with a message naming the
fields."""

from __future__ import annotations

import json

import pytest

from scoutsim.cli import main
from scoutsim.result.simulation_result import SimulationResult

ROBOT_FILE = """\
[robot]
com_offset = 0.015
leg_mass = [1.0, 0.9]
leg_inertia = [0.0052, 0.0045]
leg_com_distance = { value = [16, 15], unit = "cm" }

[transmission]
joint_stiction = [0.021, 0.025]

[motor]
current_limit = [12.0, 12.5]
"""


@pytest.fixture(scope="module")
def robot_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("robot") / "unequal.toml"
    path.write_text(ROBOT_FILE)
    return str(path)


@pytest.mark.parametrize("model", ["II", "I", "ideal", "passive"])
def test_run_every_model(robot_file, tmp_path, capsys, model):
    code = main(
        [
            "run",
            "--robot",
            robot_file,
            "--model",
            model,
            "--duration",
            "1",
            "--out",
            str(tmp_path / "out"),
            "--json",
        ]
    )
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    # (the passive robot with massive legs folds: nothing holds its legs)
    assert summary["outcome"] == ("fell" if model == "passive" else "completed")
    robot = SimulationResult.load(tmp_path / "out").provenance["robot"]
    assert tuple(robot["leg_mass"]) == (1.0, 0.9) and robot["com_offset"] == 0.015
    assert tuple(robot["leg_com_distance"]) == pytest.approx((0.16, 0.15), rel=1e-15)


def test_run_from_standing(robot_file, tmp_path):
    assert (
        main(
            [
                "run",
                "--robot",
                robot_file,
                "--start",
                "standing",
                "--duration",
                "1.5",
                "--out",
                str(tmp_path / "out"),
                "--quiet",
            ]
        )
        == 0
    )


@pytest.mark.parametrize(
    "command",
    [
        [
            "sweep",
            "--grid",
            "controller.touchdown_angle_front_deg=20:21:2",
            "--workers",
            "1",
            "--no-progress",
        ],
        [
            "basin",
            "--model",
            "II",
            "--speeds",
            "1.3",
            "--pitch-rates",
            "0",
            "--workers",
            "1",
            "--no-plots",
            "--no-progress",
        ],
        [
            "tune",
            "--objective",
            "speed",
            "--target",
            "1.3",
            "--budget",
            "4",
            "--param",
            "controller.touchdown_angle_front_deg=19:22",
        ],
    ],
    ids=["sweep", "basin", "tune"],
)
def test_studies(robot_file, tmp_path, command):
    assert (
        main(
            [
                *command,
                "--robot",
                robot_file,
                "--duration",
                "1.5",
                "--out",
                str(tmp_path / "out"),
                "--quiet",
            ]
        )
        == 0
    )


def test_orbit_rig_and_the_refused_fit(robot_file, tmp_path, capsys):
    assert main(["orbit", "--robot", robot_file, "--duration", "6", "--json", "--no-progress"]) == 0
    orbit = json.loads(capsys.readouterr().out)
    assert orbit["spectral_radius"] < 1.0
    log = tmp_path / "rig"
    assert (
        main(["rig", "free-swing", "--robot", robot_file, "--duration", "1", "--out", str(log)])
        == 0
    )
    logs = sorted(log.glob("*.csv*"))
    assert logs
    capsys.readouterr()
    code = main(
        [
            "identify",
            str(logs[0]),
            "--robot",
            robot_file,
            "--starts",
            "1",
            "--local",
            "1",
            "--out",
            str(tmp_path / "fit"),
            "--quiet",
        ]
    )
    assert code != 0
    err = capsys.readouterr().err
    assert "joint_stiction" in err and "one hip unit" in err


@pytest.mark.parametrize(
    "command",
    [
        ["orbit", "--sensitivity", "robot.current_limit"],
        ["sweep", "--grid", "robot.current_limit=11:13:2", "--duration", "0.5", "--out", "o"],
        ["continue", "--vary", "robot.current_limit=11:13", "--out", "o"],
        ["tune", "--param", "robot.current_limit=11:13", "--objective", "cot", "--out", "o"],
        ["uncertainty", "--param", "robot.current_limit=11:13", "--samples", "2", "--out", "o"],
    ],
    ids=["orbit", "sweep", "continue", "tune", "uncertainty"],
)
def test_a_field_whose_legs_differ_is_named_by_leg(robot_file, tmp_path, capsys, command):
    """The robot's current limits differ (12 / 12.5 A): one value for both would silently
    make them equal, so a study refuses it before it runs, naming the two legs' names."""
    command = [str(tmp_path / a) if a == "o" else a for a in command]
    code = main([*command, "--robot", robot_file, "--quiet"])
    assert code == 2
    err = capsys.readouterr().err
    assert "'robot.current_limit.back'" in err and "'robot.current_limit.front'" in err


def test_a_sweep_over_one_legs_value_keeps_the_other(robot_file, tmp_path):
    out = tmp_path / "sweep"
    args = ["sweep", "--grid", "robot.current_limit.front=11:13:2", "--duration", "0.5"]
    assert main([*args, "--robot", robot_file, "--out", str(out), "--quiet"]) == 0
    import pandas as pd

    table = pd.read_csv(out / "sweep.csv")
    assert list(table["robot.current_limit.front"]) == [11.0, 13.0]
    assert set(table["outcome"]) <= {"completed", "fell"}


def test_a_tuning_of_one_legs_value_writes_a_robot_file_that_runs(robot_file, tmp_path):
    """Tuning the front current limit of this robot: the best value is the front entry of
    the robot's pair in best.toml (the back one kept), and the file runs as the robot."""
    import tomllib

    out = tmp_path / "tune"
    args = ["tune", "--param", "robot.current_limit.front=11:13", "--objective", "cot"]
    args += ["--budget", "6", "--duration", "1.5", "--workers", "1", "--out", str(out)]
    assert main([*args, "--robot", robot_file, "--quiet"]) == 0
    best = json.loads((out / "best.json").read_text())["parameters"]
    written = tomllib.loads((out / "best.toml").read_text())["motor"]["current_limit"]
    assert written["value"] == [12.0, best["robot.current_limit.front"]]
    run = tmp_path / "run"
    toml = str(out / "best.toml")
    assert main(["run", "--controller", toml, "--robot", toml, "--duration", "0.3",
                 "--no-plots", "--out", str(run), "--quiet"]) == 0  # fmt: skip
