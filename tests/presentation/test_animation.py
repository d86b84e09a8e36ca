"""Tests of scoutsim.presentation.animation and the `scoutsim plot` / `scoutsim animate` subcommands."""

import numpy as np
import pytest
from PIL import Image

import scoutsim
from scoutsim.cli import main
from scoutsim.presentation.animation import animate, frame_times, save_animation


@pytest.fixture(scope="module")
def result():
    return scoutsim.simulate(duration=1.0, model="II", friction_coefficient=0.8)


@pytest.fixture(scope="module")
def saved(result, tmp_path_factory):
    return result.save(tmp_path_factory.mktemp("run") / "result.npz")


def test_frame_times(result):
    t = frame_times(result, fps=20, t0=0.2, t1=0.5)
    assert len(t) == int(round((0.5 - 0.2) * 20)) + 1 == 7
    np.testing.assert_allclose(t, 0.2 + np.arange(7) / 20)
    assert len(frame_times(result, fps=10)) == 11  # whole run: 0 .. 1 s
    assert len(frame_times(result, fps=7, t0=0.0, t1=0.5)) == 4  # floor(3.5) + 1


def test_gif_frame_count(result, tmp_path):
    p = save_animation(result, tmp_path / "a.gif", fps=20, t0=0.3, t1=0.55)
    with Image.open(p) as im:
        assert im.format == "GIF"
        assert im.n_frames == len(frame_times(result, 20, 0.3, 0.55)) == 6
        assert im.size == (640, 320)


def test_animation_artists(result):
    anim = animate(result, fps=10, t0=0.5, t1=0.6)
    fig = anim._fig
    ax = fig.get_axes()[0]
    assert "[m]" in ax.get_xlabel() and "[m]" in ax.get_ylabel()
    artists = anim._func(1)
    stamp = [a for a in artists if hasattr(a, "get_text") and "t =" in str(a.get_text())]
    assert stamp and "0.600 s" in stamp[0].get_text()
    anim._draw_was_started = True  # drawn by hand: no "deleted without rendering" warning


def test_bad_inputs(result, tmp_path, monkeypatch):
    with pytest.raises(ValueError, match="suffix"):
        save_animation(result, tmp_path / "a.avi")
    with pytest.raises(ValueError, match="t1 > t0"):
        frame_times(result, 10, 0.5, 0.5)
    with pytest.raises(ValueError, match="covers"):
        frame_times(result, 10, 0.5, 3.0)
    with pytest.raises(ValueError, match="fps"):
        frame_times(result, 0)
    import scoutsim.presentation.animation as A

    monkeypatch.setattr(A.shutil, "which", lambda name: None)
    with pytest.raises(RuntimeError, match="ffmpeg"):
        save_animation(result, tmp_path / "a.mp4", t0=0.0, t1=0.1)


def test_cli_animate_writes_gif(saved, tmp_path, capsys):
    out = tmp_path / "run.gif"
    code = main(
        ["animate", str(saved), "--out", str(out), "--fps", "10", "--t0", "0.2", "--t1", "0.5"]
    )
    assert code == 0 and "wrote" in capsys.readouterr().out
    with Image.open(out) as im:
        assert im.n_frames == 4


def test_cli_plot_result_and_log(saved, result, tmp_path, capsys, monkeypatch):
    from scoutsim.validation import save_log, to_log

    out = tmp_path / "run.pdf"
    assert main(["plot", str(saved), "--out", str(out), "--t0", "0.1", "--t1", "0.9"]) == 0
    assert out.read_bytes().startswith(b"%PDF")
    log = save_log(to_log(result), tmp_path / "log.csv.gz")
    monkeypatch.chdir(tmp_path)
    assert main(["plot", str(log)]) == 0  # default: log.png in the current directory
    assert (tmp_path / "log.png").read_bytes().startswith(b"\x89PNG")
    capsys.readouterr()


@pytest.mark.parametrize(
    "argv, message",
    [
        (["plot", "missing.npz"], "not found"),
        (["plot", "{npz}", "--out", "x.jpg"], "suffix"),
        (["plot", "{npz}", "--t0", "0.5", "--t1", "0.2"], "t1 > t0"),
        (["plot", "{npz}", "--t0", "100", "--t1", "200"], "must overlap the run"),
        (["plot", "{txt}"], "neither a saved run"),
        (["animate", "{npz}", "--out", "x.avi"], "suffix"),
        (["animate", "{txt}", "--out", "x.gif"], "not a saved run"),
        (["animate", "{npz}", "--out", "x.gif", "--t0", "0.5", "--t1", "5"], "covers"),
        (["animate", "{bad_npz}", "--out", "x.gif"], "cannot read result"),
    ],
)
def test_cli_bad_inputs_exit_2(argv, message, saved, tmp_path, capsys):
    txt = tmp_path / "notes.txt"
    txt.write_text("hello\n")
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    argv = [a.format(npz=saved, txt=txt, bad_npz=bad) for a in argv]
    argv = [str(tmp_path / a) if a in ("x.jpg", "x.avi", "x.gif") else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err


def test_result_without_robot_in_provenance_is_drawn_with_the_default_robot(result):
    """A result whose provenance does not name the robot (e.g. one assembled by hand or
    saved without it) is drawn with the default Scout II (RobotParameters()): the torso is
    a rectangle of the default torso length x height, and every frame matches the frame of
    the same run whose provenance names the (default) robot it simulated."""
    import dataclasses

    from scoutsim.parameters import RobotParameters

    provenance = {k: v for k, v in result.provenance.items() if k != "robot"}
    bare = dataclasses.replace(result, provenance=provenance, _cache={})
    assert "robot" not in bare.provenance and "robot" in result.provenance
    robot = RobotParameters()
    with_robot = animate(result, fps=10, t0=0.2, t1=0.4)
    without = animate(bare, fps=10, t0=0.2, t1=0.4)
    for i in range(len(without.frame_times)):
        corners = without._func(i)[0].get_xy()[:4]
        sides = np.hypot(*np.diff(np.vstack([corners, corners[:1]]), axis=0).T)
        np.testing.assert_allclose(sides, [robot.torso_length, robot.torso_height] * 2, rtol=1e-12)
        np.testing.assert_array_equal(corners, with_robot._func(i)[0].get_xy()[:4])
    for anim in (with_robot, without):
        anim._draw_was_started = True  # drawn by hand: no "deleted without rendering" warning


def test_leg_colour_is_the_controller_state_and_toe_marker_the_simulated_contact(result):
    """Contact and controller state are two things: at a sample where the controller still
    says flight but the simulated toe is on the ground, the leg is drawn in the flight
    colour and its toe filled; in the air the toe is open. Both have a legend."""
    from matplotlib.colors import to_rgba

    from scoutsim.names import ContactMode, LegState
    from scoutsim.presentation.animation import LEG_STATE_COLORS, TOE_MARKERS

    leg = 0
    state, contact = result.leg_state(leg), result.contact_mode(leg)
    late = np.flatnonzero((state == LegState.FLIGHT) & (contact != ContactMode.FLIGHT))
    air = np.flatnonzero(contact == ContactMode.FLIGHT)
    assert late.size and air.size, "the run has a touchdown the controller detects later"
    for k in (late[0], air[0]):
        t = result.t[k]
        anim = animate(result, fps=1000, t0=t, t1=min(t + 0.0005, result.t[-1]))
        anim._func(0)
        legs, toes = anim.artists["legs"], anim.artists["toes"]
        assert to_rgba(legs[leg].get_color()) == to_rgba(LEG_STATE_COLORS[state[k]])
        on_ground = contact[k] != ContactMode.FLIGHT
        assert (to_rgba(toes[leg].get_markerfacecolor()) == to_rgba("k")) == on_ground
        sliding = contact[k] == ContactMode.SLIDE
        assert toes[leg].get_marker() == (TOE_MARKERS["sliding"][0] if sliding else "o")
        status = anim.artists["status"].get_text()
        assert ("in air" in status.splitlines()[1]) == (not on_ground)
        titles = [lg.get_title().get_text() for lg in anim._fig.legends]
        assert titles == ["leg colour: controller state", "toe: simulated contact"]
        anim._draw_was_started = True
