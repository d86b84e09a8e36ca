"""Policies exported from Stable-Baselines3 (scoutsim.envs.policy_export) and run as
controllers (scoutsim.control.policy). The fixtures are two tiny PPO policies trained on
scoutsim/Bound-v0 (torque and set-point actions, VecNormalize) and exported, with 1,000
observations and PyTorch's deterministic actions for them (tools/make_policy_fixture.py;
no PyTorch here). Checked: the exported policy gives PyTorch's actions to 1e-5, through
the NumPy evaluation and through the compiled command; the file carries the environment's
observation box, action map, policy period and Table I parameters; and a run of
:func:`scoutsim.simulate` under the policy is the environment's episode under the same
policy, state for state (the controller reads, decides and holds as the environment
does): bit for bit with the compiled evaluation of the policy deciding the episode's
actions, to 1e-9 with its NumPy evaluation."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium
import numpy as np
import pytest

import scoutsim
import scoutsim.envs  # noqa: F401 - registers scoutsim/Bound-v0
from scoutsim import InitialState
from scoutsim.control.policy import PolicyController
from scoutsim.control.sensors import Sensors

DATA = Path(__file__).resolve().parents[1] / "data"
ACTION_TYPES = ("torque", "setpoints")
#: the tolerance the exported policy meets against PyTorch's float32 evaluation, in the
#: normalised action
TORCH_TOLERANCE = 1e-5
#: how far apart the states [SI] of a run and of an episode under the same policy may be
STATE_TOLERANCE = 1e-9


def _fixture(action_type: str):
    policy = PolicyController.load(DATA / f"policy_{action_type}.npz")
    with np.load(DATA / f"policy_{action_type}_recording.npz") as rec:
        recording = {k: rec[k] for k in rec.files}
    return policy, recording


@pytest.mark.parametrize("action_type", ACTION_TYPES)
def test_the_exported_policy_gives_the_torch_policys_actions(action_type):
    """Over the 1,000 recorded observations (rollouts, and points anywhere in the
    observation box, where VecNormalize's clip acts): the NumPy evaluation and the compiled
    command (at a policy tick, as the run loop calls it) give PyTorch's deterministic
    actions to 1e-5."""
    policy, rec = _fixture(action_type)
    obs, torch_actions = rec["observations"], rec["actions"]
    assert obs.shape == (1000, policy.observation.low.size)
    assert obs.dtype == np.float32 and torch_actions.dtype == np.float32
    assert np.abs(policy.predict(obs) - torch_actions).max() <= TORCH_TOLERANCE
    compiled = []
    n, dt = policy.samples_per_step, policy.control_period
    for i, y in enumerate(obs.astype(np.float64)):
        for k in range(i * n, (i + 1) * n):  # (a policy step: its tick, then held)
            policy.command(k * dt, Sensors.from_vector(y))
            if k == i * n:
                compiled.append(policy.held_action)
    normalised = (np.array(compiled) - policy.action.center) / policy.action.half_width
    assert np.abs(normalised - torch_actions).max() <= TORCH_TOLERANCE
    # the observations spread: the normalisation's clip is reached by some of them
    seen = policy.observation
    assert seen.normalised and seen.mean is not None
    z = (obs - seen.mean) / seen.std
    assert (np.abs(z) > seen.clip).any() and (np.abs(z) < 1.0).any()


@pytest.mark.parametrize("action_type", ACTION_TYPES)
def test_the_file_carries_the_environments_spaces_and_action_map(action_type):
    """What the controller needs of the environment it was trained in, as the environment
    has it: observation box, action centre and half-width, action box [-1, 1], policy
    period, Table I parameters, model."""
    policy, rec = _fixture(action_type)
    env = gymnasium.make("scoutsim/Bound-v0", model="II", action_type=action_type).unwrapped
    assert np.array_equal(policy.observation.low, env.observation_space.low)
    assert np.array_equal(policy.observation.high, env.observation_space.high)
    assert np.array_equal(policy.action.center, env.action_center)
    assert np.array_equal(policy.action.half_width, env.action_half_width)
    assert np.array_equal(policy.action.low, -np.ones(len(env.action_center)))
    assert np.array_equal(policy.action.high, np.ones(len(env.action_center)))
    assert policy.action.type == action_type
    assert policy.policy_period == env.policy_period
    assert policy.samples_per_step == env.samples_per_step
    assert policy.controller_parameters == env.controller
    assert policy.metadata["model"] == "II"
    assert policy.metadata["observation_names"] == list(env.observation_names)
    assert json.loads(str(rec["provenance"]))["action_type"] == action_type


def _episode(env, decide, steps: int):
    """The environment's episode with actions ``decide(observation)``: the state after
    every step and whether it ended."""
    obs, _ = env.reset(seed=0)
    states = []
    for _ in range(steps):
        obs, _, terminated, truncated, _ = env.step(decide(obs))
        states.append(env.unwrapped.engine.s.copy())
        if terminated or truncated:
            return np.array(states), True
    return np.array(states), False


#: the environment's start, in flight
START = InitialState(dx=1.1, dtheta=2.0)


@pytest.mark.parametrize("action_type", ACTION_TYPES)
def test_a_run_under_the_policy_is_the_environments_episode_bit_for_bit(action_type):
    """From the same start, simulate() with the policy as its controller and the
    environment stepped by the compiled evaluation of the same policy on its own
    observations reach the same state at the end of every policy step, bit for bit, to
    the end of the episode (the set-point policy: 1.5 s of bounding; the torque policy:
    until the robot is down, and the simulator's fall in the same step)."""
    policy, _ = _fixture(action_type)
    env = gymnasium.make("scoutsim/Bound-v0", model="II", action_type=action_type, start=START)
    steps = 150
    states, ended = _episode(env, policy.compiled_action, steps)
    n = policy.samples_per_step
    run = scoutsim.simulate(
        controller=policy, initial_state=START, duration=steps * policy.policy_period, model="II"
    )
    if action_type == "setpoints":
        assert not ended and run.outcome == "completed" and len(states) == steps
    else:  # (the robot goes down: the episode ends before the simulator's fall)
        assert ended and run.outcome == "fell" and run.t_end > len(states) * policy.policy_period
    at_steps = run.state[n : n * (len(states) + 1) : n]
    assert np.array_equal(at_steps, states)


@pytest.mark.parametrize("action_type", ACTION_TYPES)
def test_a_run_under_the_policy_is_the_episode_under_its_numpy_evaluation(action_type):
    """The environment stepped by the NumPy evaluation of the policy (float64 actions;
    the two evaluations of the network differ in the last bits): the same states as the
    run to 1e-9 over 1.5 s of bounding (set-points) and over the torque policy's first
    0.5 s, before its toes chatter on the ground as the robot goes down (where the times
    of the impacts amplify a last bit)."""
    policy, _ = _fixture(action_type)
    env = gymnasium.make("scoutsim/Bound-v0", model="II", action_type=action_type, start=START)
    steps = 150 if action_type == "setpoints" else 50
    # (float64, as the controller holds it: a float32 action, as PyTorch gives it, differs
    # by its rounding, about 1e-8 of the action)
    states, ended = _episode(env, policy.predict, steps)
    assert not ended and len(states) == steps
    n = policy.samples_per_step
    run = scoutsim.simulate(
        controller=policy, initial_state=START, duration=steps * policy.policy_period, model="II"
    )
    at_steps = run.state[n : n * (steps + 1) : n]
    assert np.abs(at_steps - states).max() <= STATE_TOLERANCE
    assert np.abs(at_steps[1:] - at_steps[:-1]).max() > 1e3 * STATE_TOLERANCE  # (it moves)
