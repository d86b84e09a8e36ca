"""Environment steps per second of ``scoutsim/Bound-v0``, single and vectorized, next to
MuJoCo Gymnasium environments of similar size at the same policy rate, in one run.

    python benchmarks/bench_env.py [--steps 4000] [--repeats 3] [--model II] [--no-mujoco]

Needs ``pip install "scoutsim[rl]"``; the MuJoCo rows ``pip install "gymnasium[mujoco]"``
(skipped if it is missing). Every environment steps at a 10 ms policy period:

* scoutsim/Bound-v0, "torque" actions: uniformly random hip torques over the whole
  box (the robot falls within about a second and the episode is reset: the resets are
  in the count);
* scoutsim/Bound-v0, "setpoints" actions: Table I's set-points with 1 deg of random
  noise (the robot bounds: the cost of steady bounding physics);
* Hopper-v5 (frame_skip 5 x 2 ms = 10 ms) and HalfCheetah-v5 (frame_skip 1 x 10 ms),
  uniformly random actions: planar MuJoCo robots of similar size (6 and 9 generalized
  coordinates; the scout model has 8 plus 2 leg lengths' worth of contact modes).

Each single environment is made with ``gymnasium.make`` (the wrappers a user gets); the
vectorized ones with ``gymnasium.make_vec(..., vectorization_mode="sync" / "async")``
with 2 and 4 copies (steps counted per copy). Environments are made and reset before
the clock starts. Reported: the median of ``--repeats`` timings of ``--steps`` steps.

Then what a native batched step could save at most: the share of a scoutsim step spent
outside the compiled run loop (the same episodes driven through the engine alone, without
the environment's Python), measured for the set-point actions.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import time

import numpy as np
from machine import machine

TABLE_I = np.radians([19.0, 21.0, 0.0, 0.0])


def policy(kind: str, space, rng):
    """The action of one step for one environment."""
    if kind == "setpoints":
        return TABLE_I + rng.normal(0.0, math.radians(1.0), 4)
    return rng.uniform(space.low, space.high)


def time_single(make, kind, steps, repeats):
    env = make()
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    env.action_space.seed(0)
    out = []
    resets = 0
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(steps):
            _, _, term, trunc, _ = env.step(policy(kind, env.action_space, rng))
            if term or trunc:
                env.reset()
                resets += 1
        out.append(steps / (time.perf_counter() - t0))
    env.close()
    return statistics.median(out), resets / repeats


def time_vector(make_vec, kind, n, steps, repeats):
    envs = make_vec(n)
    rng = np.random.default_rng(0)
    envs.reset(seed=0)
    space = envs.single_action_space
    out = []
    for _ in range(repeats):
        vsteps = max(1, steps // n)
        t0 = time.perf_counter()
        for _ in range(vsteps):
            envs.step(np.stack([policy(kind, space, rng) for _ in range(n)]))
        out.append(vsteps * n / (time.perf_counter() - t0))
    envs.close()
    return statistics.median(out)


def engine_share(model, steps, repeats):
    """(env steps/s, engine-only steps/s) of the set-point episodes."""
    import gymnasium

    from scoutsim.envs.bound import SETPOINTS

    env = gymnasium.make(
        "scoutsim/Bound-v0", model=model, action_type="setpoints", normalize_actions=False
    )
    rng = np.random.default_rng(0)
    actions = [policy("setpoints", None, rng) for _ in range(steps)]
    env_rates, eng_rates = [], []
    for _ in range(repeats):
        env.reset(seed=0)
        t0 = time.perf_counter()
        for a in actions:
            env.step(a)
        env_rates.append(steps / (time.perf_counter() - t0))
        env.reset(seed=0)
        eng = env.unwrapped.engine
        n = env.unwrapped.samples_per_step
        t0 = time.perf_counter()
        for a in actions:
            eng.retune(**dict(zip(SETPOINTS, a)))
            eng.advance(eng.k + n)
            eng.discard_records()
        eng_rates.append(steps / (time.perf_counter() - t0))
    # the engine's own per-call cost: a call of the compiled loop that runs no sample
    k = eng.k
    t0 = time.perf_counter()
    for _ in range(steps):
        eng.advance(k)
    call = (time.perf_counter() - t0) / steps
    return statistics.median(env_rates), statistics.median(eng_rates), call


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--model", default="II")
    ap.add_argument("--no-mujoco", action="store_true")
    args = ap.parse_args(argv)

    import gymnasium

    import scoutsim
    import scoutsim.envs  # noqa: F401 (registers)

    scoutsim.simulation.simulator.warm_up()
    print(f"load average (1, 5, 15 min) at the start: {os.getloadavg()}")
    print(
        f"machine: {machine()}; Python {platform.python_version()}, gymnasium "
        f"{gymnasium.__version__}, scoutsim {scoutsim.__version__}"
    )
    rows = []
    envs = []
    for kind in ("torque", "setpoints"):
        # physical actions (Table I's set-points in rad, torques in N m)
        kw = dict(model=args.model, action_type=kind, normalize_actions=False)
        envs.append(
            (
                f"scoutsim/Bound-v0 Model {args.model}, {kind}",
                kind,
                lambda kw=kw: gymnasium.make("scoutsim/Bound-v0", **kw),
                lambda n, kw=kw, m=None: gymnasium.make_vec(
                    "scoutsim/Bound-v0", num_envs=n, vectorization_mode=m, **kw
                ),
            )
        )
    if not args.no_mujoco:
        try:
            import mujoco

            for name, skip in (("Hopper-v5", 5), ("HalfCheetah-v5", 1)):
                envs.append(
                    (
                        f"{name} (MuJoCo {mujoco.__version__}), frame_skip {skip}",
                        "random",
                        lambda name=name, skip=skip: gymnasium.make(name, frame_skip=skip),
                        lambda n, name=name, skip=skip, m=None: gymnasium.make_vec(
                            name, num_envs=n, vectorization_mode=m, frame_skip=skip
                        ),
                    )
                )
        except ImportError:
            print("(mujoco not installed: no MuJoCo rows; pip install 'gymnasium[mujoco]')")
    for label, kind, make, make_vec in envs:
        probe = make()
        period = probe.unwrapped.dt
        probe.close()
        single, resets = time_single(make, kind, args.steps, args.repeats)
        row = {
            "env": label,
            "policy period [ms]": round(period * 1e3, 6),
            "single": single,
            "resets / run": resets,
        }
        for mode in ("sync", "async"):
            for n in (2, 4):
                row[f"{mode} {n}"] = time_vector(
                    lambda k, mode=mode, make_vec=make_vec: make_vec(k, m=mode),
                    kind,
                    n,
                    args.steps,
                    args.repeats,
                )
        rows.append(row)
        print(
            f"{label}: period {row['policy period [ms]']} ms, single {single:,.0f} "
            f"steps/s ({resets:.0f} resets per {args.steps} steps), "
            + ", ".join(f"{m} {row[m]:,.0f}" for m in ("sync 2", "sync 4", "async 2", "async 4")),
            flush=True,
        )
    print()
    cols = ("single", "sync 2", "sync 4", "async 2", "async 4")
    print(
        "| environment (10 ms policy period) | single | "
        + " | ".join(f"make_vec {c}" for c in cols[1:])
        + " |"
    )
    print("|---|" + "---|" * len(cols))
    for row in rows:
        print(f"| {row['env']} | " + " | ".join(f"{row[c]:,.0f}" for c in cols) + " |")
    env_rate, eng_rate, call = engine_share(args.model, args.steps, args.repeats)
    compiled = 1.0 / eng_rate - call
    print(
        f"\nset-point steps, Model {args.model}: environment {env_rate:,.0f} steps/s "
        f"({1e6 / env_rate:.1f} us per step), the engine alone {eng_rate:,.0f} steps/s "
        f"({1e6 / eng_rate:.1f} us), of which {1e6 * call:.1f} us the call of the compiled "
        f"loop itself: {1e6 * compiled:.1f} us in the compiled loop, "
        f"{100 * (1 - compiled * env_rate):.0f} % of a step outside it (the most a native "
        "batched step, all in compiled code, could save)"
    )
    print(f"load average (1, 5, 15 min) at the end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
