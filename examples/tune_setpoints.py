"""Tuning a structured controller through the learning environment: a random search over
the Table I controller's touchdown angles for a target speed.

Run it (after ``pip install -e ".[rl]"`` in the repository; needs Gymnasium):

    python examples/tune_setpoints.py [--robot FILE] [--target 1.6] [--candidates 24]
                                      [--model II] [--quick]

Each candidate holds its touchdown angles (back, front) and the controller's sweep limits
for a 4 s episode of ``scoutsim/Bound-v0`` from a random start (``start="random"``),
scored by the return: the speed error against ``--target``, the electrical energy and
staying up (the environment's reward terms); the search starts from the controller's
touchdown angles (Table I's 19 / 21 deg, or those of the robot file's ``[controller]``),
keeps the best and samples around it. The same seeds for every candidate make the
comparison fair (common random numbers). It prints each improvement and the best angles.

``--robot FILE`` is a robot file as ``scoutsim run --robot`` reads it (default Scout II);
``--quick`` runs 3 candidates on one 2 s episode each (seconds in all).
"""

from __future__ import annotations

import argparse
import math

import numpy as np

EPISODE_STEPS = 400  # policy steps of an episode (10 ms each: 4 s)
SEEDS = (1, 2, 3)  # the episodes' seeds, the same for every candidate
QUICK_EPISODE_STEPS = 200  # ... with --quick: 2 s
QUICK_SEEDS = (1,)
QUICK_CANDIDATES = 3
STEP_DEG = 1.5  # standard deviation of a candidate around the best [deg]


def episode_return(env, action, seeds) -> tuple[float, float]:
    """Mean return and mean speed [m/s] of the set-points ``action`` (the environment's
    SETPOINTS order: touchdown back, front, sweep limit back, front [rad]) over episodes
    from ``seeds``."""
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
    ap.add_argument(
        "--robot",
        metavar="FILE",
        help="TOML robot file, as `scoutsim run --robot` (default: Scout II)",
    )
    ap.add_argument("--target", type=float, default=1.6, help="target speed [m/s]")
    ap.add_argument(
        "--candidates",
        type=int,
        default=None,
        help=f"candidates tried (default 24, {QUICK_CANDIDATES} with --quick)",
    )
    ap.add_argument("--model", default="II", choices=["ideal", "I", "II"])
    ap.add_argument(
        "--quick", action="store_true", help="few candidates on one short episode (seconds in all)"
    )
    args = ap.parse_args(argv)
    candidates = (
        args.candidates if args.candidates is not None else QUICK_CANDIDATES if args.quick else 24
    )
    seeds = QUICK_SEEDS if args.quick else SEEDS

    import gymnasium

    import scoutsim.envs  # noqa: F401 (registers scoutsim/Bound-v0)
    from scoutsim.envs.bound import SETPOINTS
    from scoutsim.names import LEG_NAMES

    env = gymnasium.make(
        "scoutsim/Bound-v0",
        model=args.model,
        action_type="setpoints",
        normalize_actions=False,  # the search moves the set-points in rad
        target_speed=args.target,
        start="random",
        robot_file=args.robot,
        max_episode_steps=QUICK_EPISODE_STEPS if args.quick else EPISODE_STEPS,
    )
    start = np.array([getattr(env.unwrapped.controller, name) for name in SETPOINTS])
    touchdown = [SETPOINTS.index(f"touchdown_angle_{leg}") for leg in LEG_NAMES]
    rng = np.random.default_rng(0)
    best = start.copy()
    best_return, speed = episode_return(env, best, seeds)
    print(
        f"start: touchdown {np.degrees(best[touchdown]).round(2)} deg, return "
        f"{best_return:.1f}, speed {speed:.3f} m/s"
    )
    for i in range(candidates):
        action = best.copy()
        action[touchdown] += rng.normal(0.0, math.radians(STEP_DEG), len(touchdown))
        ret, speed = episode_return(env, action, seeds)
        if ret > best_return:
            best, best_return = action, ret
            print(
                f"candidate {i}: touchdown {np.degrees(action[touchdown]).round(2)} deg, "
                f"return {ret:.1f}, speed {speed:.3f} m/s"
            )
    print(
        f"best: touchdown angles back / front {np.degrees(best[touchdown]).round(2)} deg, "
        f"return {best_return:.1f}"
    )


if __name__ == "__main__":
    main()
