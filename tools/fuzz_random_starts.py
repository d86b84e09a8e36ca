"""Random starts of the learning environment under open-loop torques: count the episodes
that end in a numerical failure of the integrator (there should be none).

    python tools/fuzz_random_starts.py                 # 300 episodes per model and torque
    python tools/fuzz_random_starts.py --episodes 60 --models II --torques zero
    python tools/fuzz_random_starts.py --keep-going    # episodes go on while the robot is down

Each episode is ``scoutsim/Bound-v0`` (scoutsim/envs/bound.py) from the fuzzed start
(:func:`fuzzed_start`: height, forward speed and pitch rate drawn about the flight start
with the environment's own seeding, ``reset(seed=seed)``, seeds 0 .. episodes-1), driven
by one of the open-loop torque regimes of :data:`TORQUES` until it ends (a fall, a
failure, or the 10 s limit).
Prints, per model and regime, the outcomes and the seeds that failed, and the wall time.
tests/envs/test_random_starts.py runs a subset of these episodes with the same driver.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

#: the open-loop torque regimes: what the policy commands at every step
#: ("zero": nothing; "random": uniform in the action box, drawn from a generator seeded
#: with the episode's seed; "saturated": the current-limited torque of the box, +limit on
#: both legs for even seeds and -limit for odd ones, reversed at every step)
TORQUES = ("zero", "random", "saturated")
MODELS = ("ideal", "I", "II")
#: the environment's time limit [steps] (its registration's max_episode_steps: 10 s)
MAX_STEPS = 1000


#: the fuzzed start: InitialState field -> half-width [SI] of its uniform draw about the
#: flight start, in the order drawn (the seeds the tests name are these draws')
FUZZED_HALF_WIDTHS = {"y": 0.015, "dx": 0.2, "dtheta": np.radians(50.0)}


def fuzzed_start(rng):
    """The start of a fuzzed episode drawn with the environment's generator ``rng``: the
    flight start with its height (0.315-0.345 m), forward speed (1.0-1.4 m/s) and pitch
    rate (100-200 deg/s) drawn uniformly, each in turn."""
    from scoutsim.state import InitialState

    init = InitialState()
    return init.replace(
        **{
            name: getattr(init, name) + half * float(rng.uniform(-1.0, 1.0))
            for name, half in FUZZED_HALF_WIDTHS.items()
        }
    )


def make_env(model: str, keep_going: bool = False):
    """The environment of the fuzzing: Bound-v0's defaults (torque actions) with the fuzzed
    start; ``keep_going``: the episode goes on when the robot is down
    (``terminate_when_fallen`` off), until the simulator's fall or the time limit (more of
    each episode is fuzzed)."""
    from scoutsim.envs.bound import BoundEnv

    return BoundEnv(model=model, start=fuzzed_start, terminate_when_fallen=not keep_going)


def run_episode(env, torques: str, seed: int, max_steps: int = MAX_STEPS) -> dict:
    """One episode from ``env.reset(seed=seed)`` under the regime ``torques``
    (:data:`TORQUES`); returns its outcome ("fell" or "numerical_failure": the simulator's;
    "not_up": the environment's end of an episode whose robot is down; "time_limit"), end
    time [s] and steps."""
    if torques not in TORQUES:
        raise ValueError(f"torques = {torques!r} is not allowed: must be one of {TORQUES}")
    env.reset(seed=seed)
    high = env.action_space.high
    rng = np.random.default_rng(seed)
    sign = 1.0 if seed % 2 == 0 else -1.0
    steps = 0
    for steps in range(1, max_steps + 1):  # noqa: B007 (the count after the loop is reported)
        if torques == "zero":
            a = np.zeros(2)
        elif torques == "random":
            a = rng.uniform(env.action_space.low, high)
        else:
            a = sign * high
            sign = -sign
        _, _, terminated, truncated, info = env.step(a)
        if terminated or truncated:
            break
    outcome = env.engine.status_name
    if outcome == "running":
        outcome = "not_up" if terminated else "time_limit"
    return {"outcome": outcome, "t": float(env.engine.t_now), "steps": steps}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--episodes",
        type=int,
        default=300,
        help="episodes (seeds 0..N-1) per model and torque regime (default 300)",
    )
    ap.add_argument("--models", nargs="+", default=list(MODELS), choices=MODELS)
    ap.add_argument("--torques", nargs="+", default=list(TORQUES), choices=TORQUES)
    ap.add_argument(
        "--keep-going",
        action="store_true",
        help="go on when the robot is down, until the simulator's fall or the time limit",
    )
    a = ap.parse_args(argv)
    failures = 0
    t_all = time.perf_counter()
    for model in a.models:
        env = make_env(model, a.keep_going)
        for torques in a.torques:
            t0 = time.perf_counter()
            counts: dict[str, int] = {}
            failed = []
            for seed in range(a.episodes):
                ep = run_episode(env, torques, seed)
                counts[ep["outcome"]] = counts.get(ep["outcome"], 0) + 1
                if ep["outcome"] == "numerical_failure":
                    failed.append((seed, round(ep["t"], 4)))
            failures += len(failed)
            print(
                f"model {model:5s} torques {torques:9s}: {a.episodes} episodes, "
                f"{dict(sorted(counts.items()))}, numerical_failure at (seed, t) "
                f"{failed}, {time.perf_counter() - t0:.1f} s",
                flush=True,
            )
    print(f"total: {failures} numerical failures, {time.perf_counter() - t_all:.1f} s")
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
