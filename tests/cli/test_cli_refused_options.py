"""An option a mode would ignore is refused, naming it, before anything runs
(scoutsim.cli._given).

``orbit --passive --model I`` used to print the passive model's orbit as if Model I had
been asked for; every such combination is now a usage error (exit 2) that names the
option, however the user spelled it (an abbreviation, ``--name=value``)."""

import pytest

from scoutsim.cli import build_parser, main
from scoutsim.cli._given import given_options


@pytest.mark.parametrize(
    "argv, option",
    [
        (["orbit", "--passive", "--model", "I"], "--model"),
        (["orbit", "--passive", "--mod", "I"], "--model"),  # argparse's abbreviation
        (["orbit", "--passive", "--friction=0.8"], "--friction"),
        (["orbit", "--passive", "--duration", "3"], "--duration"),
        (["orbit", "--passive", "--strides", "2"], "--strides"),
        (["orbit", "--passive", "--section", "plant"], "--section"),
        (["orbit", "--passive", "--workers", "2"], "--workers"),
        (["orbit", "--passive", "--scheduler", "tcp://h:8786"], "--scheduler"),
        (["orbit", "--speed", "1.2"], "--speed"),
        (["orbit", "--workers", "2"], "--workers"),  # (no --sensitivity to share out)
        (["orbit", "--apex-height", "0.3"], "--apex-height"),
        (["orbit", "--pitch-rate", "20"], "--pitch-rate"),
        (["continue", "--vary", "pitch_rate_deg=0:10", "--passive", "--points", "3"], "--points"),
        (["continue", "--vary", "pitch_rate_deg=0:10", "--passive", "--model", "I"], "--model"),
        (["continue", "--vary", "robot.leg_stiffness=3000:3100", "--speed", "1"], "--speed"),
        (["basin", "--floors", "0.8,1.0", "--friction", "0.6"], "--friction"),
        (
            ["tune", "--floors", "0.8", "--friction", "0.6", "--target", "1.2"]
            + ["--param", "controller.touchdown_angle_front_deg"],
            "--friction",
        ),
    ],
)
def test_an_option_the_mode_ignores_is_refused_by_name(argv, option, tmp_path, capsys):
    if argv[0] in ("continue", "basin", "tune"):
        argv = argv + ["--out", str(tmp_path / "out")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{option} is not allowed" in err
    assert not (tmp_path / "out").exists()  # refused before anything ran or was written


def test_given_options_are_the_typed_ones_however_spelled():
    given = given_options(
        build_parser(), ["orbit", "--passive", "--fric=0.9", "--jac", "fd", "--json"]
    )
    assert {"passive", "friction", "jacobian", "json"} <= given
    # the defaults of the options not typed are not among them
    assert not given & {"model", "duration", "speed", "apex_height", "workers", "robot"}


def test_the_passive_orbit_takes_its_own_options(capsys):
    # --speed, --apex-height and --jacobian belong to the passive orbit: accepted
    assert main(["orbit", "--passive", "--speed", "1.3", "--apex-height", "0.35", "--json"]) == 0
    assert '"period_s"' in capsys.readouterr().out
