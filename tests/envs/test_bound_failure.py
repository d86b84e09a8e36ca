"""How scoutsim/Bound-v0 (scoutsim/envs/bound.py) ends an episode the simulator cannot go on
with: a numerical failure (a real one: dynamics that cannot be solved) or a controller
error is Gymnasium's truncation, never a healthy step (no healthy reward, is_healthy
False), told apart from the time limit in info (outcome, numerical_failure, the
diagnosis), while a fall stays a termination."""

import numpy as np
import pytest

gymnasium = pytest.importorskip(
    "gymnasium", reason="the learning environment needs gymnasium (pip install 'scoutsim[rl]')"
)

import scoutsim.envs  # noqa: E402,F401
from scoutsim._core.model import layout as L  # noqa: E402
from scoutsim.envs.bound import BoundEnv  # noqa: E402

ID = "scoutsim/Bound-v0"
#: the set-point action that runs the controller as it is (Table I by default): the
#: normalised action 0, the controller's own set-points
TABLE_I_SETPOINTS = np.zeros(4, dtype=np.float32)


def stopping_env(monkeypatch, status, torso_height=None):
    """An ideal-model environment whose next step ends with the run loop's ``status``
    after an ordinary advance (and, with ``torso_height`` [m], the torso COM put there)."""
    env = BoundEnv(model="ideal", action_type="setpoints")
    env.reset(seed=0)
    eng = env.engine
    advance = eng.advance

    def stopping_advance(k_stop):
        advance(k_stop)
        if torso_height is not None:
            eng.s[L.IY] = torso_height
        eng.status = status

    monkeypatch.setattr(eng, "advance", stopping_advance)
    return env


def test_a_numerical_failure_is_a_truncation_without_healthy_reward():
    """A torso inertia 1e6 x Scout II's makes the constrained dynamics unsolvable at the
    start (the run loop stops with "numerical_failure") while the robot stands at its
    healthy start height and pitch: the step is truncated, not terminated, and earns no
    healthy reward."""
    env = gymnasium.make(
        ID, model="I", action_type="setpoints", healthy_reward=5.0, torso_inertia=1.3e6
    )
    env.reset(seed=0)
    _, reward, terminated, truncated, info = env.step(TABLE_I_SETPOINTS)
    assert (terminated, truncated) == (False, True)
    assert info["outcome"] == "numerical_failure" and info["numerical_failure"] is True
    # the robot was up by the healthy ranges: only the failure withholds the reward
    unwrapped = env.unwrapped
    lo, hi = unwrapped.healthy_height_range
    assert lo <= info["height"] <= hi
    assert info["reward_healthy"] == 0.0 and info["is_healthy"] is False
    assert reward == info["reward_forward"] + info["reward_energy"]
    # the simulator's own diagnosis, naming the parameter
    assert "could not be solved" in info["failure_message"]
    assert "torso_inertia" in info["failure_message"]
    with pytest.raises(RuntimeError, match="reset"):
        unwrapped.step(TABLE_I_SETPOINTS)


def test_the_time_limit_is_a_truncation_of_healthy_steps_told_apart_by_info():
    env = gymnasium.make(
        ID, model="ideal", action_type="setpoints", max_episode_steps=3, healthy_reward=5.0
    )
    env.reset(seed=0)
    for _ in range(3):
        _, _, terminated, truncated, info = env.step(TABLE_I_SETPOINTS)
    assert (terminated, truncated) == (False, True)
    assert info["outcome"] == "running" and info["numerical_failure"] is False
    assert info["reward_healthy"] == 5.0 and "failure_message" not in info


def test_a_controller_error_is_a_truncation_without_healthy_reward(monkeypatch):
    """The run loop's other non-physical stop (forced here: the engine reports a controller
    error after an ordinary step) ends the same way, and is not called a numerical
    failure."""
    env = stopping_env(monkeypatch, L.ST_CONTROLLER_ERROR)
    _, reward, terminated, truncated, info = env.step(TABLE_I_SETPOINTS)
    assert (terminated, truncated) == (False, True)
    assert info["outcome"] == "controller_error" and info["numerical_failure"] is False
    assert info["reward_healthy"] == 0.0 and not info["is_healthy"]
    assert "controller" in info["failure_message"]


def test_a_failure_in_a_vector_env_is_reported_per_env():
    envs = gymnasium.make_vec(
        ID, num_envs=2, vectorization_mode="sync", model="I", torso_inertia=1.3e6
    )
    try:
        envs.reset(seed=0)
        _, _, terminated, truncated, info = envs.step(np.zeros((2, 2)))
        assert truncated.all() and not terminated.any()
        assert info["numerical_failure"].all()
        assert (info["reward_healthy"] == 0.0).all()
    finally:
        envs.close()


def test_an_integrator_stop_mid_episode_ends_healthy_steps_with_a_truncation():
    """A motor of no armature resistance (1e-300 ohm) makes Model II's electrical dynamics
    too fast for any step: the integrator stops about 0.2 s in. Every step before is a
    healthy one; the one that failed is a truncation with the integrator's diagnosis."""
    env = gymnasium.make(
        ID, model="II", action_type="setpoints", healthy_reward=1.0, armature_resistance=1e-300
    )
    env.reset(seed=0)
    healthy = []
    for _ in range(100):
        obs, _, terminated, truncated, info = env.step(TABLE_I_SETPOINTS)
        if terminated or truncated:
            break
        healthy.append(info["reward_healthy"])
    assert (terminated, truncated) == (False, True)
    assert len(healthy) >= 5 and healthy == [1.0] * len(healthy)
    assert info["numerical_failure"] and info["reward_healthy"] == 0.0
    assert "integrator" in info["failure_message"]
    assert "armature_resistance" in info["failure_message"]
    # the data up to the failure: a finite last observation, time short of the step's end
    assert np.all(np.isfinite(obs))
    assert info["t"] < (len(healthy) + 1) * env.unwrapped.dt


def test_a_failure_with_the_robot_already_down_is_a_termination(monkeypatch):
    """The task's rule comes first: a step that ends with the robot down (COM below the
    healthy height) is terminated, whatever stopped the simulator; info still names the
    numerical failure."""
    env = stopping_env(
        monkeypatch, L.ST_NUMERICAL_FAILURE, torso_height=0.1
    )  # below the healthy range's 0.2 m
    _, _, terminated, truncated, info = env.step(TABLE_I_SETPOINTS)
    assert (terminated, truncated) == (True, False)
    assert info["numerical_failure"] and info["reward_healthy"] == 0.0
