"""The Gymnasium environment scoutsim/Bound-v0 (scoutsim/envs/bound.py): the API contract
(check_env without a warning, the spaces as learning libraries expect them, vector API,
seeding, episode end) and that a policy step is the simulator's own physics (the same
motion, readings and energy balance as simulate())."""

import math
import subprocess
import sys
import warnings

import numpy as np
import pytest

gymnasium = pytest.importorskip(
    "gymnasium", reason="the learning environment needs gymnasium (pip install 'scoutsim[rl]')"
)

from gymnasium.utils.env_checker import check_env  # noqa: E402

import scoutsim  # noqa: E402
import scoutsim.envs  # noqa: E402,F401
from scoutsim._core.model import layout as L  # noqa: E402
from scoutsim.control.sensors import SensorChannel, SensorParameters  # noqa: E402
from scoutsim.envs.bound import BoundEnv  # noqa: E402

ID = "scoutsim/Bound-v0"
#: Table I's set-points (touchdown back / front, sweep back / front), from the paper
#: the set-point action that runs the controller as it is (Table I by default): the
#: normalised action 0, the controller's own set-points
TABLE_I_SETPOINTS = np.zeros(4, dtype=np.float32)
#: sensors with noise, bias, resolution and delay on several channels
NOISY = SensorParameters(
    pitch=SensorChannel(noise=math.radians(0.3), bias=math.radians(0.5), delay=2),
    hip_rate=SensorChannel(noise=0.05, delay=1),
    hip_angle=SensorChannel(resolution=1e-4),
    motor_current=SensorChannel(noise=0.1, delay=3),
)


def _pd_policy(obs):
    """A deterministic policy of the readings (so that noise in them changes the run):
    a PD servo of each hip towards 20 deg."""
    tau = (
        250.0 * (math.radians(20.0) - obs[L.SN_ANGLE_B : L.SN_ANGLE_B + 2])
        - 5.0 * obs[L.SN_RATE_B : L.SN_RATE_B + 2]
    )
    return np.clip(tau / 31.0, -1.0, 1.0).astype(np.float32)


def _episode(env, seed, n, policy):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for _ in range(n):
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        out += [
            obs,
            np.array(
                [reward, terminated, truncated, info["x_position"], info["electrical_energy"]]
            ),
        ]
        if terminated or truncated:
            break
    return np.concatenate(out)


@pytest.mark.parametrize("action_type", ["torque", "setpoints"])
@pytest.mark.parametrize("model", ["ideal", "I", "II"])
def test_check_env_passes_without_a_warning_for_each_model(model, action_type):
    env = gymnasium.make(ID, model=model, action_type=action_type)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any warning of the checker fails the test
        check_env(env.unwrapped)
        check_env(
            gymnasium.make(ID, model=model, action_type=action_type, start="flight").unwrapped
        )


@pytest.mark.parametrize("action_type", ["torque", "setpoints"])
def test_spaces_are_float32_boxes_normalised_actions_and_named_bounded_observations(action_type):
    from scoutsim.control.sensors import CHANNELS

    env = gymnasium.make(ID, action_type=action_type).unwrapped
    act, obs = env.action_space, env.observation_space
    assert act.dtype == np.float32 and obs.dtype == np.float32
    assert np.all(act.low == -1.0) and np.all(act.high == 1.0)
    assert np.all(np.isfinite(obs.low)) and np.all(np.isfinite(obs.high))
    assert np.all(obs.low < obs.high)
    names = env.observation_names
    assert len(names) == obs.shape[0] == L.NSN and len(set(names)) == len(names)
    # each name belongs to its channel's slots, in order
    for channel, (slot, n, _unit) in CHANNELS.items():
        assert all(names[slot + i].startswith(channel) for i in range(n))
    # the physical ranges: the hip angle a full turn, the current the amplifier's limit,
    # the pitch the simulator's fall
    r = env.robot
    assert obs.high[names.index("hip_angle_back")] == np.float32(math.pi)
    assert obs.high[names.index("motor_current_front")] == np.float32(r.current_limit)
    assert obs.high[names.index("pitch")] == np.float32(math.radians(env.pitch_limit_deg))
    # the observations of an episode that ends in a fall lie in the box
    o, _ = env.reset(seed=3)
    seen = [o]
    for _ in range(400):
        o, _, terminated, truncated, _ = env.step(np.ones(act.shape, np.float32))
        seen.append(o)
        if terminated or truncated:
            break
    assert terminated
    assert all(o.dtype == np.float32 and obs.contains(o) for o in seen)


def test_a_normalised_action_is_its_physical_action_and_the_physical_box_is_an_option():
    env = BoundEnv(action_type="torque")
    tau = env.robot.max_leg_torque
    np.testing.assert_array_equal(env.action_half_width, [tau, tau])
    np.testing.assert_array_equal(env.physical_action([0.5, -2.0]), [0.5 * tau, -tau])
    physical = BoundEnv(action_type="torque", normalize_actions=False)
    assert physical.action_space.dtype == np.float32
    np.testing.assert_allclose(physical.action_space.high, [tau, tau], rtol=1e-7)
    np.testing.assert_array_equal(physical.physical_action([10.0, -99.0]), [10.0, -tau])
    # set-points: 0 is the controller's own set-points, +-1 moves each by 25 deg
    env = BoundEnv(action_type="setpoints", touchdown_angle_back=math.radians(17.0))
    own = [getattr(env.controller, name) for name in scoutsim.envs.bound.SETPOINTS]
    np.testing.assert_array_equal(env.physical_action(np.zeros(4)), own)
    np.testing.assert_allclose(
        env.physical_action(np.ones(4)) - own, math.radians(25.0), rtol=1e-12
    )
    with pytest.raises(ValueError, match="finite"):
        env.physical_action([np.nan, 0.0, 0.0, 0.0])


def test_sync_and_async_vector_environments_from_the_id_give_the_same_observations():
    """The same seeds give the same episodes whether the environments step in this process
    or in worker processes."""
    runs = {}
    for mode in ("sync", "async"):
        envs = gymnasium.make_vec(ID, num_envs=2, vectorization_mode=mode)
        try:
            obs, _ = envs.reset(seed=[11, 12])
            observations, rewards = [obs], []
            rng = np.random.default_rng(0)
            for _ in range(20):
                obs, reward, _, _, _ = envs.step(rng.uniform(-1, 1, (2, 2)).astype(np.float32))
                observations.append(obs)
                rewards.append(reward)
            runs[mode] = np.array(observations), np.array(rewards)
        finally:
            envs.close()
    (obs_sync, rew_sync), (obs_async, rew_async) = runs["sync"], runs["async"]
    assert obs_sync.dtype == obs_async.dtype == np.float32
    assert np.array_equal(obs_sync, obs_async) and np.array_equal(rew_sync, rew_async)
    # two seeds, two episodes
    assert not np.array_equal(obs_sync[:, 0], obs_sync[:, 1])


def test_make_vec_with_four_envs_steps_in_sync_and_async_mode():
    for mode, n in (("sync", 4), ("async", 2)):
        envs = gymnasium.make_vec(
            ID, num_envs=n, vectorization_mode=mode, action_type="setpoints", start="random"
        )
        try:
            obs, _ = envs.reset(seed=5)
            assert obs.shape == (n, L.NSN)
            for _ in range(5):
                obs, reward, terminated, truncated, info = envs.step(
                    np.tile(TABLE_I_SETPOINTS, (n, 1))
                )
            assert obs.shape == (n, L.NSN) and reward.shape == (n,)
            assert not terminated.any() and not truncated.any()
            # a random start each: the envs run different episodes
            assert len(set(info["x_position"].tolist())) == n
        finally:
            envs.close()
    assert type(gymnasium.make_vec(ID, num_envs=4)).__name__ == "SyncVectorEnv"


def test_same_seed_gives_the_same_episode_bit_for_bit_and_another_seed_another():
    env = gymnasium.make(ID, model="II", sensors=NOISY)
    a = _episode(env, 7, 60, _pd_policy)
    b = _episode(env, 7, 60, _pd_policy)
    c = _episode(env, 8, 60, _pd_policy)
    assert np.array_equal(a, b, equal_nan=True)
    assert a.shape != c.shape or not np.array_equal(a, c, equal_nan=True)
    # the noise alone (a fixed start) differs with the seed too
    env = gymnasium.make(ID, model="II", start="flight", sensors=NOISY)
    assert not np.array_equal(_episode(env, 1, 3, _pd_policy), _episode(env, 2, 3, _pd_policy))


@pytest.mark.parametrize("model", ["ideal", "I", "II"])
def test_a_zero_torque_policy_falls_and_terminates(model):
    # nothing holds the legs: they splay and the torso comes down
    env = gymnasium.make(ID, model=model, action_type="torque")
    env.reset(seed=0)
    for _ in range(300):
        _, _, terminated, truncated, info = env.step(np.zeros(2))
        if terminated or truncated:
            break
    assert terminated and not truncated
    assert not info["is_healthy"] and info["reward_healthy"] == 0.0
    assert info["height"] < 0.2 or info["outcome"] == "fell"
    with pytest.raises(RuntimeError, match="reset"):
        env.unwrapped.step(np.zeros(2))


@pytest.mark.parametrize("model", ["ideal", "I", "II"])
def test_table_i_setpoints_bound_and_stay_up_for_three_seconds(model):
    env = gymnasium.make(ID, model=model, action_type="setpoints", healthy_reward=2.0)
    env.reset(seed=0)
    healthy = []
    for _ in range(300):
        _, _, terminated, truncated, info = env.step(TABLE_I_SETPOINTS)
        assert not terminated and not truncated
        healthy.append(info["reward_healthy"])
    assert healthy == [2.0] * 300
    # bounding forward: Scout II's bound runs at 1.3 m/s and more
    assert info["x_position"] / info["t"] > 1.0
    assert info["t"] == pytest.approx(3.0, abs=1e-12)


def test_reward_terms_in_info_add_up_to_the_reward():
    env = gymnasium.make(
        ID,
        model="I",
        action_type="setpoints",
        target_speed=1.5,
        forward_reward_weight=0.7,
        energy_cost_weight=0.03,
        healthy_reward=0.5,
    )
    env.reset(seed=3)
    rng = np.random.default_rng(0)
    for _ in range(50):
        action = TABLE_I_SETPOINTS + rng.normal(0.0, 0.03, 4)
        _, reward, terminated, _, info = env.step(action)
        assert reward == pytest.approx(
            info["reward_forward"] + info["reward_energy"] + info["reward_healthy"],
            rel=1e-15,
            abs=1e-15,
        )
        # speed rewarded up to the target, less beyond it
        assert info["reward_forward"] == pytest.approx(
            0.7 * (1.5 - abs(info["x_velocity"] - 1.5)), rel=1e-15, abs=1e-15
        )
        assert info["reward_energy"] == pytest.approx(-0.03 * info["electrical_energy"], rel=1e-15)
        if terminated:
            break


@pytest.mark.parametrize("model", ["ideal", "II"])
def test_a_step_is_simulate_with_the_same_controller_motion_and_energy_balance(model):
    # the set-point action holding Table I's values runs the Table I controller of
    # simulate(): the same motion bit for bit, and the energy term the energy balance's
    # electrical energy over each step
    w = 0.02
    env = gymnasium.make(
        ID, model=model, action_type="setpoints", energy_cost_weight=w, start="flight"
    )
    env.reset(seed=0)
    x, energy, reward_energy = [], [], []
    for _ in range(100):
        _, _, _, _, info = env.step(TABLE_I_SETPOINTS)
        x.append(info["x_position"])
        energy.append(info["electrical_energy"])
        reward_energy.append(info["reward_energy"])
    r = scoutsim.simulate(duration=1.0, model=model, energy=True)
    n = env.unwrapped.samples_per_step
    assert np.array_equal(x, r.state[n::n, 0])
    cumulative = r.cumulative_energy("electrical")[::n]
    np.testing.assert_allclose(energy, np.diff(cumulative), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(reward_energy, -w * np.diff(cumulative), rtol=1e-12, atol=1e-12)
    assert sum(energy) > 100.0  # (the motors work: some 500 W over 1 s)


def test_observations_are_the_readings_a_controller_sees_delays_and_noise_included():
    # zero torques from the flight start: the environment's readings at each step are
    # what a controller called by simulate() at that sample reads, bit for bit; the
    # observation is them in float32, within the observation box
    env = gymnasium.make(
        ID, model="II", action_type="torque", sensors=NOISY, start="flight"
    ).unwrapped
    first, _ = env.reset(seed=11)
    obs, readings = [first], [env.readings]
    seed = int(env.engine.block.ints[L.CB_SEED])
    for _ in range(40):
        o, _, terminated, _, _ = env.step(np.zeros(2))
        obs.append(o)
        readings.append(env.readings)
        assert not terminated
    box = env.observation_space
    np.testing.assert_array_equal(
        obs, np.clip(np.array(readings).astype(np.float32), box.low, box.high)
    )

    class Recorder(scoutsim.Controller):
        def __init__(self):
            self.readings = []

        def command(self, t, sensors):
            self.readings.append(sensors.vector.copy())
            return 0.0, 0.0

    rec = Recorder()
    scoutsim.simulate(duration=0.4, model="II", controller=rec, sensors=NOISY.replace(seed=seed))
    n = env.samples_per_step
    assert np.array_equal(np.array(readings), np.array(rec.readings[::n]))


def test_truncation_at_the_time_limit():
    env = gymnasium.make(ID, model="ideal", action_type="setpoints", max_episode_steps=7)
    env.reset(seed=0)
    ends = [env.step(TABLE_I_SETPOINTS)[2:4] for _ in range(7)]
    assert ends == [(False, False)] * 6 + [(False, True)]
    assert gymnasium.spec(ID).max_episode_steps == scoutsim.envs.DEFAULT_MAX_EPISODE_STEPS


def test_standing_start_stays_standing_under_table_i_setpoints():
    # the standing robot is a static equilibrium the stance-brake law holds
    env = gymnasium.make(ID, model="II", action_type="setpoints", start="standing")
    obs, info = env.reset(seed=0)
    robot = scoutsim.RobotParameters()
    # each virtual leg (two physical legs' springs) carries half the weight
    k_virtual = robot.legs_per_virtual_leg * robot.leg_stiffness
    sag = robot.total_mass * robot.gravity / (2.0 * k_virtual)
    np.testing.assert_allclose(
        obs[L.SN_LENGTH_B : L.SN_LENGTH_B + 2], robot.leg_rest_length - sag, rtol=0.02
    )
    for _ in range(50):
        _, _, terminated, _, info = env.step(TABLE_I_SETPOINTS)
        assert not terminated
    assert abs(info["x_position"]) < 1e-6 and abs(info["pitch"]) < 1e-6


def test_random_starts_lie_in_the_documented_neighbourhood_and_follow_the_seed():
    env = BoundEnv()  # the default start is the random one
    robot, ctrl = env.robot, env.controller
    seen = []
    for seed in range(40):
        env.reset(seed=seed)
        s = env.engine.s.copy()
        y, theta = s[1], s[2]
        assert 1.0 <= s[L.NQ] <= 1.4
        assert math.radians(100.0) <= s[L.NQ + 2] <= math.radians(200.0)
        assert abs(theta) <= math.radians(3.0)
        for leg, td in ((0, ctrl.touchdown_angle_back), (1, ctrl.touchdown_angle_front)):
            phi = s[L.IPHB + leg]
            assert abs(phi - td) <= math.radians(3.0) + 1e-12
            # both toes start above the ground by the clearance, or more
            toe = (
                y
                + robot.hip_offset(leg) * math.sin(theta)
                - robot.leg_rest_length * math.cos(theta + phi)
            )
            assert toe >= 0.005 - 1e-12
        # the height: its interval, or raised just enough for the toes' clearance
        assert 0.315 <= y <= 0.345 + 0.02
        seen.append(s)
        env.reset(seed=seed)
        assert np.array_equal(env.engine.s, s)  # the same seed, the same start
    assert len({tuple(s[:3]) for s in seen}) == 40
    # the fixed start for evaluation
    fixed = BoundEnv(start="flight")
    fixed.reset(seed=1)
    s1 = fixed.engine.s.copy()
    fixed.reset(seed=2)
    assert np.array_equal(fixed.engine.s, s1)


@pytest.mark.parametrize("model", ["ideal", "I", "II"])
def test_table_i_bounds_from_every_random_start(model):
    """The start distribution is one a bounding controller runs from: Table I's set-points
    keep the robot up for 2 s from each of 8 random starts, in every model."""
    env = gymnasium.make(ID, model=model, action_type="setpoints")
    for seed in range(8):
        env.reset(seed=seed)
        for _ in range(200):
            _, _, terminated, truncated, info = env.step(TABLE_I_SETPOINTS)
            assert not (terminated or truncated), (seed, info["t"])
        assert info["x_position"] / info["t"] > 1.0


def test_running_earns_much_more_than_standing_still():
    """The default reward makes running the optimum: Table I's bound over 2 s earns at
    least four times what standing still earns."""
    run = gymnasium.make(ID, action_type="setpoints")
    stand = gymnasium.make(ID, action_type="setpoints", start="standing")
    totals = []
    for env in (run, stand):
        env.reset(seed=0)
        total = 0.0
        for _ in range(200):
            _, reward, terminated, truncated, _ = env.step(TABLE_I_SETPOINTS)
            total += reward
            assert not (terminated or truncated)
        totals.append(total)
    assert totals[0] > 4.0 * totals[1] > 0.0


def test_action_spaces_are_the_physical_limits_and_options_pass_through():
    env = BoundEnv(
        model="I", current_limit=10.0, friction_coefficient=math.inf, normalize_actions=False
    )
    r = env.robot
    # current-limited torque at the leg: N eta K_T i_max
    limit = (
        r.planetary_ratio
        * r.sprocket_ratio
        * r.gearbox_efficiency
        * r.sprocket_efficiency
        * r.torque_constant
        * 10.0
    )
    assert env.action_half_width == pytest.approx([limit, limit], rel=1e-14)
    assert env.action_space.high == pytest.approx([limit, limit], rel=1e-7)
    assert np.array_equal(env.action_space.low, -env.action_space.high)
    env = BoundEnv(action_type="setpoints", touchdown_angle_back=math.radians(17.0))
    assert env.controller.touchdown_angle_back == math.radians(17.0)
    assert env.action_center[0] == math.radians(17.0)
    with pytest.raises(TypeError, match="touchdown_angle_back"):
        BoundEnv(touchdown_angel_back=0.3)
    with pytest.raises(ValueError, match="whole multiple"):
        BoundEnv(policy_period=0.0025)
    assert BoundEnv(policy_period=0.001).samples_per_step == 1


def test_scoutsim_alone_does_not_import_gymnasium_and_envs_says_what_to_install():
    code = "import sys, scoutsim; print('gymnasium' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
    code = (
        "import sys; sys.modules['gymnasium'] = None\n"
        "try:\n    import scoutsim.envs\nexcept ImportError as e:\n    print(e)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "pip install" in out.stdout and "rl" in out.stdout


def test_a_robot_file_sets_robot_controller_and_sensors(tmp_path):
    f = tmp_path / "robot.toml"
    f.write_text(
        "[robot]\ntorso_mass = 21.0\n\n[controller]\n"
        'touchdown_angle_front = { value = 22.0, unit = "deg" }\n\n'
        "[sensors]\nseed = 5\n[sensors.pitch]\n"
        'noise = { value = 0.5, unit = "deg" }\n'
    )
    env = gymnasium.make(
        ID, robot_file=str(f), action_type="setpoints", current_limit=11.0, start="flight"
    ).unwrapped
    assert env.robot.torso_mass == 21.0 and env.robot.current_limit == 11.0
    assert env.controller.touchdown_angle_front == pytest.approx(math.radians(22.0))
    assert env.sensors.pitch.noise == pytest.approx(math.radians(0.5))
    # the flight start's legs are at the file's touchdown angles (hip encoders at rest)
    obs, _ = env.reset(seed=0)
    assert env.readings[L.SN_ANGLE_F] == pytest.approx(math.radians(22.0), abs=1e-9)
    # pitch noise: the level torso's pitch reading is not exactly 0
    assert obs[L.SN_PITCH] != 0.0
    with pytest.raises(ValueError, match="robot_file"):
        BoundEnv(robot_file=str(f), robot=scoutsim.RobotParameters())
