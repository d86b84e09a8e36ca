"""Make the learned-policy test fixtures: tiny PPO policies trained on scoutsim/Bound-v0,
exported to policy files, with 1,000 observations and the PyTorch policy's actions for them.

Needs PyTorch and Stable-Baselines3 (not scoutsim's dependencies; the tests that read the
fixtures need neither)::

    PYTHONPATH=. /path/to/venv-with-sb3/bin/python tools/make_policy_fixture.py [--steps 4096]

For each action type ("torque", and "setpoints"), with fixed seeds:

1. trains PPO (``MlpPolicy``, ``net_arch`` [32, 32], tanh) for ``--steps`` environment
   steps on Model II behind ``VecNormalize`` (observations and rewards normalised);
2. records 1,000 raw observations (float32, as the environment returns them): 800 from
   rollouts of the trained policy, sampling its Gaussian so that the states spread
   (episodes from the environment's random starts), and 200 drawn uniformly from the
   observation box (far from the training's statistics: the normalisation's clip, and
   actions beyond the action box, are exercised);
3. computes the PyTorch policy's deterministic actions for them, as one deploys it:
   ``model.predict(vec_normalize.normalize_obs(obs), deterministic=True)`` (clipped to
   the action box), and the network's output before the clip (``policy.get_distribution
   (...).distribution.mean``);
4. exports the policy (:func:`scoutsim.envs.policy_export.export_policy`) to
   ``tests/data/policy_<type>.npz`` and writes the recording to
   ``tests/data/policy_<type>_recording.npz`` (``observations``, ``actions``,
   ``unclipped_actions``, ``provenance``).

The files are small (about 30 kB each). Rerun it after a change of the observation, the
action map or the policy file's format, and commit the files it writes.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
#: observations recorded per policy
N_OBSERVATIONS = 1000
#: of them, drawn uniformly from the observation box (the rest from rollouts)
N_UNIFORM = 200
SEED = 7


def make(action_type: str, steps: int) -> None:
    import gymnasium
    import stable_baselines3
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    import scoutsim.envs  # noqa: F401 - registers scoutsim/Bound-v0
    from scoutsim.envs.policy_export import export_policy

    torch.manual_seed(SEED)
    torch.set_num_threads(1)

    def one():
        return gymnasium.make("scoutsim/Bound-v0", model="II", action_type=action_type)

    venv = VecNormalize(DummyVecEnv([one]), norm_obs=True, norm_reward=True, clip_obs=10.0)
    venv.seed(SEED)
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=512,
        batch_size=128,
        n_epochs=4,
        seed=SEED,
        device="cpu",
        policy_kwargs=dict(net_arch=[32, 32]),
        verbose=0,
    )
    model.learn(total_timesteps=steps)
    venv.training = False  # (the statistics stay as trained from here on)

    # rollouts: raw observations, actions sampled from the policy's Gaussian
    env = one()
    rng = np.random.default_rng(SEED)
    observations = []
    obs, _ = env.reset(seed=SEED)
    while len(observations) < N_OBSERVATIONS - N_UNIFORM:
        observations.append(obs)
        action, _ = model.predict(venv.normalize_obs(obs[None]), deterministic=False)
        obs, _, terminated, truncated, _ = env.step(action[0])
        if terminated or truncated:
            obs, _ = env.reset(seed=int(rng.integers(2**31)))
    # and observations anywhere in the observation box: normalised, most are far out
    # (VecNormalize's clip), and some actions beyond the box (predict's clip)
    box = env.observation_space
    uniform = rng.uniform(box.low.astype(np.float64), box.high, size=(N_UNIFORM, box.shape[0]))
    observations = np.concatenate([np.array(observations), uniform]).astype(np.float32)

    normalised = venv.normalize_obs(observations)
    actions, _ = model.predict(normalised, deterministic=True)
    with torch.no_grad():
        tensor, _ = model.policy.obs_to_tensor(normalised)
        unclipped = model.policy.get_distribution(tensor).distribution.mean.cpu().numpy()

    DATA.mkdir(parents=True, exist_ok=True)
    policy_path = DATA / f"policy_{action_type}.npz"
    export_policy(
        model,
        policy_path,
        vec_normalize=venv,
        env=venv,
        metadata={"seed": SEED, "net_arch": [32, 32], "made_by": "tools/make_policy_fixture.py"},
    )
    provenance = {
        "environment": "scoutsim/Bound-v0",
        "model": "II",
        "action_type": action_type,
        "training_steps": int(model.num_timesteps),
        "seed": SEED,
        "torch": torch.__version__,
        "stable_baselines3": stable_baselines3.__version__,
        "actions": "model.predict(vec_normalize.normalize_obs(observations), deterministic=True)",
        "unclipped_actions": "the policy's Gaussian mean for the same inputs",
    }
    np.savez_compressed(
        DATA / f"policy_{action_type}_recording.npz",
        observations=observations,
        actions=np.asarray(actions, dtype=np.float32),
        unclipped_actions=np.asarray(unclipped, dtype=np.float32),
        provenance=np.array(json.dumps(provenance, sort_keys=True)),
    )
    clipped = float(np.mean(np.abs(unclipped) > 1.0))
    print(
        f"{action_type}: {model.num_timesteps} steps; wrote {policy_path.name} "
        f"({policy_path.stat().st_size / 1e3:.0f} kB) and its recording of "
        f"{len(observations)} observations ({clipped:.0%} of the action entries clipped)"
    )


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=4096, help="PPO training steps per policy")
    ap.add_argument("--types", default="torque,setpoints", help="action types to make")
    args = ap.parse_args(argv)
    for action_type in args.types.split(","):
        make(action_type, args.steps)


if __name__ == "__main__":
    main()
