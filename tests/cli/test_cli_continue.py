"""``scoutsim continue``: the passive family's branch table and figure, the controlled
robot's family through a few values, and the refusals of bad input."""

import json

import pandas as pd
import pytest

from scoutsim.analysis.gait_family import FAMILY_COLUMNS
from scoutsim.cli import main


def test_passive_family_writes_the_table_and_figure(tmp_path, capsys):
    out = tmp_path / "passive"
    code = main(["continue", "--passive", "--vary", "pitch_rate_deg=100:120", "--out", str(out),
                 "--json", "--no-progress"])  # fmt: skip
    assert code == 0
    s = json.loads(capsys.readouterr().out)
    assert s["method"] == "pseudo-arclength" and s["stopped"] == "range"
    assert s["bifurcations"] == []  # (the crossings below 100 deg/s: test_passive_family.py)
    csv = pd.read_csv(out / "family.csv")
    parquet = pd.read_parquet(out / "family.parquet")
    assert list(csv.columns) == ["pitch_rate_deg", *FAMILY_COLUMNS]
    assert list(parquet.columns) == list(csv.columns) and len(parquet) == len(csv)
    assert csv["pitch_rate_deg"].iloc[0] == pytest.approx(100.0)
    assert csv["pitch_rate_deg"].iloc[-1] == pytest.approx(120.0)
    assert (out / "family.png").stat().st_size > 10_000
    assert not csv["stable"].any()  # the passive bound is unstable throughout


def test_controlled_family_follows_the_orbit_through_the_values(tmp_path, capsys):
    """Model II under Table I at three front touchdown angles: an orbit at each (a cycle of
    one or more strides: the sampled loop locks into such cycles), the stride period
    growing with the angle, every row stable."""
    out = tmp_path / "controlled"
    code = main(["continue", "--vary", "controller.touchdown_angle_front_deg=22:23",
                 "--points", "3", "--out", str(out), "--json", "--no-progress"])  # fmt: skip
    assert code == 0
    s = json.loads(capsys.readouterr().out)
    assert s["method"] == "natural-parameter" and s["orbits"] == 3 and s["stable"] == 3
    df = pd.read_parquet(out / "family.parquet")
    assert list(df["controller.touchdown_angle_front_deg"]) == [22.0, 22.5, 23.0]
    assert (df["status"] == "ok").all() and (df["strides"] >= 1).all()
    assert (df["period_s"] / df["strides"]).is_monotonic_increasing
    assert (df["spectral_radius"] < 1.0).all()
    # the world touchdown angle is the commanded one plus the pitch: it follows the command
    assert df["touchdown_angle_front_deg"].is_monotonic_increasing


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--vary", "pitch_rate_deg=0"], "NAME=LO:HI"),
        (["--vary", "pitch_rate_deg=5:1", "--passive"], "HI must exceed LO"),
        (["--vary", "robot.leg_stiffness=1000:2000", "--passive"], "pitch_rate_deg"),
        (["--vary", "controller.touchdown_angle_fornt_deg=20:22"], "did you mean"),
    ],
)
def test_bad_input_is_a_usage_error_naming_the_field(tmp_path, capsys, argv, message):
    code = main(["continue", *argv, "--out", str(tmp_path / "x"), "--no-progress"])
    assert code == 2
    assert message in capsys.readouterr().err


def test_a_factory_that_raises_is_a_usage_error_naming_it(tmp_path, capsys, monkeypatch):
    """A MODULE:FACTORY whose code raises (here: a factory with another signature than
    FACTORY(robot, params)) is reported with how it was called, not as a traceback."""
    (tmp_path / "wrong_factory.py").write_text("def make(robot, gain):\n    return 1.0 + gain\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    code = main(["continue", "--controller", "wrong_factory:make", "--vary",
                 "robot.belt_stiffness=400:600", "--out", str(tmp_path / "x"),
                 "--no-progress"])  # fmt: skip
    assert code == 2
    err = capsys.readouterr().err
    assert "wrong_factory:make" in err and "make(robot, params)" in err and "TypeError" in err


def test_a_controller_without_its_state_is_refused_by_name(tmp_path, capsys, monkeypatch):
    """A family restarts strides from section states: a Python controller that cannot give
    and take its own state is a usage error saying what to add."""
    (tmp_path / "stateless.py").write_text(
        "import numpy as np\n\n\nclass Hold:\n    def command(self, t, sensors):\n"
        "        return np.zeros(2)\n\n\ndef make(robot, params):\n    return Hold()\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    code = main(["continue", "--controller", "stateless:make", "--vary",
                 "robot.belt_stiffness=400:600", "--out", str(tmp_path / "x"),
                 "--no-progress"])  # fmt: skip
    assert code == 2
    assert "get_state()" in capsys.readouterr().err
