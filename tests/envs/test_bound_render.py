"""Rendering and vectorising scoutsim/Bound-v0 (scoutsim/envs/bound.py with
scoutsim/presentation/frames.py): Gymnasium's render_mode conventions (check_env with and
without it, the error for an unknown mode, render_fps the policy rate), a frame drawing the
robot where the model puts it (toes from the model's evaluation agreeing with the leg
kinematics, filled on the ground and hollow in flight), the vector environments built from
the id, and an environment that pickles and goes on bit for bit."""

import math
import pickle

import numpy as np
import pytest

gymnasium = pytest.importorskip(
    "gymnasium", reason="the learning environment needs gymnasium (pip install 'scoutsim[rl]')"
)

from gymnasium.utils.env_checker import check_env  # noqa: E402

import scoutsim.envs  # noqa: E402,F401
from scoutsim.envs.bound import BoundEnv  # noqa: E402
from scoutsim.names import ContactMode  # noqa: E402
from scoutsim.presentation.frames import GROUND_MARGIN_M, VIEW_HALF_WIDTH_M, RobotPose, draw_pose  # noqa: E402
from scoutsim.presentation.style import LEG_STATE_LINE_COLORS  # noqa: E402
from scoutsim.state import state_index  # noqa: E402

ID = "scoutsim/Bound-v0"
#: the set-point action that runs the controller as it is (Table I by default): the
#: normalised action 0, the controller's own set-points
TABLE_I_SETPOINTS = np.zeros(4, dtype=np.float32)


def _pixel(frame, x_view, x, y):
    """The (row, column) of world point (x, y) [m] in a frame whose view is centred on
    x_view [m] (frames.py's view: VIEW_HALF_WIDTH_M either side, the bottom edge
    GROUND_MARGIN_M below the ground)."""
    h, w = frame.shape[:2]
    scale = w / (2.0 * VIEW_HALF_WIDTH_M)
    y_top = -GROUND_MARGIN_M + h / scale
    return int((y_top - y) * scale), int((x - (x_view - VIEW_HALF_WIDTH_M)) * scale)


@pytest.mark.parametrize("render_mode", [None, "rgb_array"])
@pytest.mark.parametrize("action_type", ["torque", "setpoints"])
def test_check_env_passes_with_and_without_render_mode(render_mode, action_type):
    env = gymnasium.make(ID, model="I", action_type=action_type, render_mode=render_mode)
    check_env(env.unwrapped)
    assert env.unwrapped.render_mode == render_mode


def test_render_follows_gymnasium_conventions():
    # the mode is checked at construction and the error names the allowed ones
    with pytest.raises(ValueError, match="rgb_array"):
        BoundEnv(render_mode="depth_array")
    with pytest.raises(ValueError, match="render_width"):
        BoundEnv(render_mode="rgb_array", render_width=3)
    # no mode: render returns None
    env = BoundEnv(model="ideal")
    env.reset(seed=0)
    assert env.render() is None
    # render_fps is the policy rate: one frame per step plays in real time
    assert BoundEnv.metadata["render_modes"] == ["rgb_array"]
    assert BoundEnv(model="ideal").metadata["render_fps"] == pytest.approx(1 / 0.01)
    assert BoundEnv(model="ideal", policy_period=0.004).metadata["render_fps"] == pytest.approx(
        1 / 0.004
    )
    # an (H, W, 3) uint8 frame, of the size asked for
    env = gymnasium.make(
        ID, model="ideal", render_mode="rgb_array", render_width=200, render_height=100
    )
    with pytest.raises(gymnasium.error.ResetNeeded):
        env.unwrapped.render()
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (100, 200, 3) and frame.dtype == np.uint8


def test_toes_drawn_where_the_leg_kinematics_put_them_filled_on_the_ground():
    """The engine's toe positions (the model's evaluation) agree with the hip plus the leg
    along its world angle, hip + l (sin(theta + phi), -cos(theta + phi)), a toe in stance is
    on the ground, and the frame draws each toe there: a filled disc in contact, a ring in
    flight (its centre left as the background)."""
    env = gymnasium.make(
        ID, model="ideal", action_type="setpoints", render_mode="rgb_array"
    ).unwrapped
    env.reset(seed=0)
    robot, seen = env.robot, set()
    for _ in range(40):  # 0.4 s: both legs land and lift off
        env.step(TABLE_I_SETPOINTS)
        eng, frame = env.engine, env.render()
        s = eng.s
        theta = s[state_index("theta")]
        for leg, name in enumerate(("back", "front")):
            hx = eng.x + robot.hip_offset(leg) * math.cos(theta)
            hy = eng.height + robot.hip_offset(leg) * math.sin(theta)
            g = theta + s[state_index(f"phi_{name}")]
            length = s[state_index(f"leg_length_{name}")]
            tx, ty = eng.toe_position(leg)
            assert (tx, ty) == pytest.approx(
                (hx + length * math.sin(g), hy - length * math.cos(g)), abs=1e-9
            )
            on_ground = eng.contact_mode(leg) != ContactMode.FLIGHT
            if on_ground:
                assert ty == pytest.approx(0.0, abs=1e-9)
            row, col = _pixel(frame, eng.x, tx, ty)
            centre = frame[row, col]
            assert np.array_equal(centre, [0, 0, 0]) == on_ground
            seen.add(on_ground)
    assert seen == {True, False}


def test_the_view_follows_the_robot_and_legs_show_the_controller_leg_state():
    env = gymnasium.make(
        ID, model="ideal", action_type="setpoints", render_mode="rgb_array"
    ).unwrapped
    env.reset(seed=0)
    first = env.render()
    states = set()
    for _ in range(60):
        env.step(TABLE_I_SETPOINTS)
        frame = env.render()
        eng = env.engine
        # the torso's COM is drawn (grey) at the centre column of every frame
        row, col = _pixel(frame, eng.x, eng.x, eng.height)
        assert col == frame.shape[1] // 2
        # each leg's midpoint has its leg state's colour
        for leg in (0, 1):
            c, s = math.cos(eng.pitch), math.sin(eng.pitch)
            hip = np.array([eng.x, eng.height]) + env.robot.hip_offset(leg) * np.array([c, s])
            mid = 0.5 * (hip + np.array(eng.toe_position(leg)))
            r, k = _pixel(frame, eng.x, *mid)
            from matplotlib.colors import to_rgb

            want = np.round(255 * np.array(to_rgb(LEG_STATE_LINE_COLORS[eng.ls[leg]])))
            assert np.array_equal(frame[r, k], want)
            states.add(int(eng.ls[leg]))
    assert len(states) >= 2
    # it moved on: the ground's ticks have scrolled
    assert eng.x > 0.5 and not np.array_equal(first, frame)


def test_draw_pose_puts_the_robot_at_its_pose_and_survives_a_state_that_is_not_finite():
    pose = RobotPose(
        x=2.0,
        height=0.3,
        pitch=0.0,
        hip_offsets=(-0.25, 0.25),
        torso_length=0.55,
        torso_height=0.1,
        toes=((1.75, 0.0), (2.3, 0.05)),
        contact=(True, False),
    )
    frame = draw_pose(pose, 300, 150)
    # the torso box is grey at its centre, white above it
    assert np.array_equal(frame[_pixel(frame, 2.0, 2.0, 0.3)], [191, 191, 191])
    assert np.array_equal(frame[_pixel(frame, 2.0, 2.0, 0.45)], [255, 255, 255])
    # a pitched pose turns the box: the nose's corner region is filled only when it rises
    up = draw_pose(RobotPose(**{**pose.__dict__, "pitch": 0.3}), 300, 150)
    nose_above = _pixel(frame, 2.0, 2.2, 0.38)
    assert np.array_equal(up[nose_above], [191, 191, 191])
    assert np.array_equal(frame[nose_above], [255, 255, 255])
    blank = draw_pose(RobotPose(**{**pose.__dict__, "height": math.nan}), 300, 150)
    assert blank.shape == (150, 300, 3)
    assert not np.any(np.all(blank == 191, axis=2))  # no torso drawn
    with pytest.raises(ValueError, match="width"):
        draw_pose(pose, 8, 150)


@pytest.mark.parametrize("render_mode", [None, "rgb_array"])
def test_sync_and_async_vector_envs_from_the_id_step_and_render(render_mode):
    for mode in ("sync", "async"):
        envs = gymnasium.make_vec(
            ID,
            num_envs=2,
            vectorization_mode=mode,
            model="ideal",
            action_type="setpoints",
            start="random",
            render_mode=render_mode,
        )
        try:
            obs, _ = envs.reset(seed=3)
            for _ in range(3):
                obs, reward, terminated, truncated, info = envs.step(
                    np.tile(TABLE_I_SETPOINTS, (2, 1))
                )
            assert obs.shape[0] == 2 and not (terminated.any() or truncated.any())
            assert not info["numerical_failure"].any()
            frames = envs.render()
            if render_mode is None:
                assert frames is None or all(f is None for f in frames)
            else:
                assert len(frames) == 2 and frames[0].shape == (240, 480, 3)
                assert not np.array_equal(frames[0], frames[1])  # two random starts
        finally:
            envs.close()


def test_async_vector_env_of_made_envs_renders():
    envs = gymnasium.vector.AsyncVectorEnv(
        [lambda: gymnasium.make(ID, model="ideal", render_mode="rgb_array")] * 2
    )
    try:
        envs.reset(seed=1)
        envs.step(np.zeros((2, 2)))
        frames = envs.render()
        assert len(frames) == 2 and all(f.dtype == np.uint8 for f in frames)
    finally:
        envs.close()


@pytest.mark.parametrize("action_type", ["torque", "setpoints"])
def test_an_env_pickled_mid_episode_goes_on_bit_for_bit(action_type):
    env = BoundEnv(model="II", action_type=action_type, render_mode="rgb_array")
    env.reset(seed=4)
    action = TABLE_I_SETPOINTS if action_type == "setpoints" else np.array([3.0, -2.0])
    for _ in range(3):
        env.step(action)
    copy = pickle.loads(pickle.dumps(env))
    for _ in range(3):
        a, b = env.step(action), copy.step(action)
        assert np.array_equal(a[0], b[0]) and a[1:4] == b[1:4]
    assert np.array_equal(env.render(), copy.render())
