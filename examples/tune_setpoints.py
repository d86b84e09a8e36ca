"""Tuning a structured controller through the learning environment: a random search over
the Table I controller's touchdown angles for a target speed.

    python examples/tune_setpoints.py [--target 1.6] [--candidates 24] [--model II]

Needs ``pip install "scoutsim[rl]"``. Each candidate holds its touchdown angles (back,
front) and Table I's sweep limits for a 4 s episode of ``scoutsim/Bound-v0`` from a random
start (``start="random"``), scored by the return: the speed error against ``--target``,
the electrical energy and staying up (the environment's reward terms); the search keeps
the best and samples around it. The same seeds for every candidate make the comparison
fair (common random numbers). It prints each improvement and the best angles.
"""

from __future__ import annotations

import argparse
import math

import numpy as np


def episode_return(env, angles, seeds) -> tuple[float, float]:
    """Mean return and mean speed [m/s] of the set-points ``angles`` (touchdown back,
    front [rad]) over episodes from ``seeds``."""
    action = np.array([angles[0], angles[1], 0.0, 0.0])
    returns, speeds = [], []
    for seed in seeds:
        env.reset(seed=seed)
        total, info = 0.0, {"x_position": 0.0, "t": 1.0}
        terminated = truncated = False
        while not (terminated or truncated):
            _, reward, terminated, truncated, info = env.step(action)
            total += reward
        returns.append(total)
        speeds.append(info["x_position"] / info["t"])
    return float(np.mean(returns)), float(np.mean(speeds))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--target", type=float, default=1.6, help="target speed [m/s]")
    ap.add_argument("--candidates", type=int, default=24)
    ap.add_argument("--model", default="II")
    args = ap.parse_args(argv)

    import gymnasium
    import scoutsim.envs  # noqa: F401 (registers scoutsim/Bound-v0)

    env = gymnasium.make("scoutsim/Bound-v0", model=args.model, action_type="setpoints",
                         target_speed=args.target, start="random", max_episode_steps=400)
    rng = np.random.default_rng(0)
    seeds = [1, 2, 3]
    best = np.radians([19.0, 21.0])          # Table I
    best_return, speed = episode_return(env, best, seeds)
    print(f"Table I: touchdown {np.degrees(best).round(2)} deg, return {best_return:.1f}, "
          f"speed {speed:.3f} m/s")
    for i in range(args.candidates):
        angles = best + rng.normal(0.0, math.radians(1.5), 2)
        ret, speed = episode_return(env, angles, seeds)
        if ret > best_return:
            best, best_return = angles, ret
            print(f"candidate {i}: touchdown {np.degrees(angles).round(2)} deg, return "
                  f"{ret:.1f}, speed {speed:.3f} m/s")
    print(f"best: touchdown angles back / front {np.degrees(best).round(2)} deg")


if __name__ == "__main__":
    main()
