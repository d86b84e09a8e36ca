"""Learning to run: Stable-Baselines3's PPO on ``scoutsim/Bound-v0``, its learning curve,
wall time, and the trained policies' running next to Table I and a tuned controller.

    python benchmarks/bench_learn.py --out learn_out                    # 3 seeds, 600k steps
    python benchmarks/bench_learn.py --out learn_out --steps 2000000 --seeds 0 1 2
    python benchmarks/bench_learn.py --out learn_out --action-type setpoints
    python benchmarks/bench_learn.py --out learn_out --train-models ideal I II --seeds 0
    python benchmarks/bench_learn.py --out learn_out --evaluate-only     # the table again
    python benchmarks/bench_learn.py --quick --out /tmp/learn           # minutes: a smoke run

Needs ``pip install "scoutsim[rl]"`` (Gymnasium and Stable-Baselines3, which brings
PyTorch). Each (model, action type, seed) is one training run, in a process of its own
(``--jobs`` at once; each uses one core: 2 environments in a ``DummyVecEnv`` and one
PyTorch thread, so ``--jobs 2`` fills a 2-core machine with two seeds):

* the environment: ``make_vec_env("scoutsim/Bound-v0", n_envs=2)`` with its defaults
  (random starts, the default reward: speed up to 1.3 m/s, healthy 0.25, energy 0.01 / J),
  ``VecNormalize`` (observations and rewards);
* PPO with the settings the docs recommend (:data:`PPO_SETTINGS`: the MlpPolicy, two
  hidden layers of 64, 2,048 steps per update, 10 epochs of minibatches of 64, the
  learning rate 3e-4 decayed linearly to 0, the initial action standard deviation
  e^-1 = 0.37 of the normalised range).

Written to ``--out``: per run ``MODEL-ACTION-sSEED/`` with ``model.zip``,
``vecnormalize.pkl``, ``curve.csv`` (per update: environment steps, wall time [s], mean
return and length of the last 20 episodes) and ``policy.npz`` (the policy exported as a
scoutsim controller, :func:`scoutsim.envs.policy_export.export_policy`); then
``evaluation.csv`` and ``evaluation.md`` (each trained policy, Table I and a tuned
controller on ideal, Model I and Model II from ``--eval-episodes`` random starts of 10 s:
mean speed [m/s], cost of transport, falls, and whether a steady bound was found by
``scoutsim``'s gait analysis of the run with the exported policy from the fixed start),
``curve.png`` (the learning curves) and ``settings-ACTION.json`` (the settings, machine
and command).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from machine import machine

ENV_ID = "scoutsim/Bound-v0"
MODELS = ("ideal", "I", "II")
#: PPO's settings (Stable-Baselines3 keywords) for both action types
PPO_SETTINGS = {
    "n_steps": 1024,  # per environment: 2,048 steps per update with 2 environments
    "batch_size": 64,
    "n_epochs": 10,
    "learning_rate": 3e-4,  # decayed linearly to 0 over the run (LEARNING_RATE_DECAY)
    "gamma": 0.99,  # a horizon of about 1 s at the 10 ms policy period: four strides
    "gae_lambda": 0.95,
    "clip_range": 0.2,
    "ent_coef": 0.0,
}
#: the learning rate falls linearly from PPO_SETTINGS["learning_rate"] to 0 over the run:
#: with it constant, one of three seeds lost its bound in the last tenth of a million
#: steps (PPO's late updates undoing a gait it had held for 700,000 steps)
LEARNING_RATE_DECAY = True
#: the policy network and the initial exploration (log standard deviation of the
#: normalised action)
POLICY_KWARGS = {"net_arch": [64, 64], "log_std_init": -1.0}
N_ENVS = 2
#: the episodes of the evaluation start from these seeds' random starts (not the
#: training's: the training seeds the environments from its own seed)
EVAL_SEED0 = 10_000
#: a fall: an evaluation episode that ends before the time limit
EVAL_STEPS = 1000
#: the learning curves' colour per training model and line style per seed
MODEL_COLOURS = {"ideal": "tab:green", "I": "tab:orange", "II": "tab:blue"}
SEED_STYLES = ("-", "--", ":")
#: how many of the last episodes the learning curve averages
CURVE_WINDOW = 20


def run_name(model: str, action_type: str, seed: int) -> str:
    return f"{model}-{action_type}-s{seed}"


# -- training ---------------------------------------------------------------------------


def train(model: str, action_type: str, seed: int, steps: int, out: str) -> dict:
    """One training run in this process; returns its summary (and writes its files)."""
    import torch

    torch.set_num_threads(1)
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    import scoutsim.envs  # noqa: F401 (registers scoutsim/Bound-v0)

    where = Path(out) / run_name(model, action_type, seed)
    where.mkdir(parents=True, exist_ok=True)
    venv = make_vec_env(
        ENV_ID, n_envs=N_ENVS, seed=seed, env_kwargs={"model": model, "action_type": action_type}
    )
    venv = VecNormalize(venv, gamma=PPO_SETTINGS["gamma"])
    rows: list[dict] = []
    t0 = time.perf_counter()

    class Curve(BaseCallback):
        def _on_step(self) -> bool:
            return True

        def _on_rollout_end(self) -> None:
            infos = list(self.model.ep_info_buffer)[-CURVE_WINDOW:]
            if infos:
                rows.append(
                    {
                        "steps": self.num_timesteps,
                        "wall_s": round(time.perf_counter() - t0, 2),
                        "mean_return": float(np.mean([i["r"] for i in infos])),
                        "mean_length": float(np.mean([i["l"] for i in infos])),
                    }
                )

    settings = dict(PPO_SETTINGS)
    if LEARNING_RATE_DECAY:
        rate = settings["learning_rate"]
        settings["learning_rate"] = lambda remaining: rate * remaining  # remaining: 1 -> 0
    agent = PPO(
        "MlpPolicy",
        venv,
        seed=seed,
        verbose=0,
        device="cpu",
        policy_kwargs=dict(POLICY_KWARGS),
        **settings,
    )
    agent.learn(total_timesteps=steps, callback=Curve())
    wall = time.perf_counter() - t0
    agent.save(where / "model.zip")
    venv.save(str(where / "vecnormalize.pkl"))
    with open(where / "curve.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["steps", "wall_s", "mean_return", "mean_length"])
        w.writeheader()
        w.writerows(rows)
    summary = {
        "model": model,
        "action_type": action_type,
        "seed": seed,
        "steps": int(agent.num_timesteps),
        "wall_s": round(wall, 1),
        "steps_per_s": round(agent.num_timesteps / wall, 1),
    }
    (where / "training.json").write_text(json.dumps(summary, indent=2) + "\n")
    return summary


# -- export and evaluation --------------------------------------------------------------


def export_run(where: Path, model: str, action_type: str) -> Path:
    """The trained policy of the run in ``where`` (``model.zip`` and ``vecnormalize.pkl``)
    exported as a scoutsim controller, ``policy.npz``."""
    import gymnasium
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    import scoutsim.envs  # noqa: F401
    from scoutsim.envs.policy_export import export_policy

    def make():
        return gymnasium.make(ENV_ID, model=model, action_type=action_type)

    venv = VecNormalize.load(str(where / "vecnormalize.pkl"), DummyVecEnv([make]))
    agent = PPO.load(where / "model.zip", device="cpu")
    path = where / "policy.npz"
    export_policy(agent, path, vec_normalize=venv, env=venv.venv.envs[0].unwrapped)
    return path


def evaluate_actions(policy_fn, model: str, action_type: str, episodes: int, **env_kwargs) -> dict:
    """``policy_fn(obs) -> action`` over ``episodes`` random starts of 10 s on ``model``:
    mean speed [m/s] (distance over time of each episode, averaged), mean cost of transport
    (electrical energy / (m g distance) of the episodes that moved forward), falls (the
    episodes that ended before the time limit)."""
    import gymnasium

    import scoutsim.envs  # noqa: F401

    env = gymnasium.make(ENV_ID, model=model, action_type=action_type, **env_kwargs)
    robot = env.unwrapped.robot
    weight = robot.total_mass * robot.gravity
    speeds, cots, falls = [], [], 0
    for i in range(episodes):
        obs, info = env.reset(seed=EVAL_SEED0 + i)
        x0, energy, steps = info["x_position"], 0.0, 0
        while True:
            obs, _, terminated, truncated, info = env.step(policy_fn(obs))
            energy += info["electrical_energy"]
            steps += 1
            if terminated or truncated:
                break
        distance = info["x_position"] - x0
        falls += int(terminated or steps < EVAL_STEPS)
        speeds.append(distance / info["t"])
        if distance > 0.1:
            cots.append(energy / (weight * distance))
    return {
        "speed_m_s": float(np.mean(speeds)),
        "cost_of_transport": float(np.mean(cots)) if cots else math.nan,
        "falls": falls,
        "episodes": episodes,
    }


def steady_bound(controller, model: str) -> tuple[bool, float]:
    """scoutsim's gait analysis of a 10 s run from the fixed flight start: (steady bounding,
    mean speed [m/s], NaN without a gait)."""
    import scoutsim

    s = scoutsim.simulate(controller=controller, duration=10.0, model=model).summary()
    speed = s["mean_speed_m_s"]  # (None: no gait to measure, e.g. a fall)
    return bool(s["steady_bounding"]), math.nan if speed is None else float(speed)


def evaluate_policy_file(path: Path, model: str, episodes: int) -> dict:
    from scoutsim.control.policy import PolicyController

    policy = PolicyController.load(path)
    row = evaluate_actions(
        lambda obs: policy.predict(obs).astype(np.float32), model, policy.action.type, episodes
    )
    row["steady_bound"], row["fixed_start_speed_m_s"] = steady_bound(policy, model)
    return row


def tuned_controller():
    """Table I's touchdown angles tuned by CMA-ES for 1.3 m/s on Model II (``scoutsim
    tune``'s function, 24 evaluations of 5 s)."""
    from scoutsim.analysis.tune import tune

    result = tune(
        ["controller.touchdown_angle_front_deg", "controller.touchdown_angle_back_deg"],
        objective="speed",
        target=1.30,
        model="II",
        duration=5.0,
        budget=24,
        seed=0,
        workers=1,
    )
    return result.controller_parameters


def evaluate_builtin(params, model: str, episodes: int) -> dict:
    """The Table I law with ``params``: the set-point action 0 (the controller's own
    set-points) in the environment, and its run from the fixed start."""
    zero = np.zeros(4, dtype=np.float32)
    row = evaluate_actions(lambda obs: zero, model, "setpoints", episodes, controller=params)
    row["steady_bound"], row["fixed_start_speed_m_s"] = steady_bound(params, model)
    return row


def _evaluate_row(task: tuple) -> dict:
    """One row of the evaluation: (label fields, what to run, the model it runs on)."""
    labels, what, model, episodes = task
    if isinstance(what, Path):
        row = evaluate_policy_file(what, model, episodes)
    else:
        row = evaluate_builtin(what, model, episodes)
    return {**labels, "evaluated_on": model, **row}


def evaluate_all(
    out: Path, runs: list[tuple[str, str, int]], episodes: int, jobs: int = 1
) -> list[dict]:
    """Table I, the tuned controller and every trained policy on each of :data:`MODELS`
    (``jobs`` rows at once, in processes of their own)."""
    from scoutsim.parameters import ControllerParameters

    tasks = []
    for name, params in (
        ("Table I", ControllerParameters()),
        ("tuned (CMA-ES, Model II)", tuned_controller()),
    ):
        labels = {"controller": name, "trained_on": "", "seed": ""}
        tasks += [(labels, params, model, episodes) for model in MODELS]
    for train_model, action_type, seed in runs:
        where = out / run_name(train_model, action_type, seed)
        if not (where / "model.zip").exists():
            print(f"no {where}/model.zip: skipped", flush=True)
            continue
        path = export_run(where, train_model, action_type)
        labels = {"controller": f"PPO, {action_type}", "trained_on": train_model, "seed": seed}
        tasks += [(labels, path, model, episodes) for model in MODELS]
    rows = []
    with ProcessPoolExecutor(max_workers=max(1, jobs)) as pool:
        for row in pool.map(_evaluate_row, tasks):
            rows.append(row)
            print(_line(row), flush=True)
    return rows


def _line(row: dict) -> str:
    return (
        f"{row['controller']:26s} {str(row['trained_on']):6s} {str(row['seed']):3s} on "
        f"{row['evaluated_on']:5s}: {row['speed_m_s']:.2f} m/s, CoT {row['cost_of_transport']:.2f}, "
        f"falls {row['falls']}/{row['episodes']}, steady bound from the fixed start "
        f"{row['steady_bound']} ({row['fixed_start_speed_m_s']:.2f} m/s)"
    )


def write_evaluation(out: Path, rows: list[dict]) -> None:
    fields = list(rows[0])
    with open(out / "evaluation.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)
    lines = [
        "| controller | trained on | seed | evaluated on | speed [m/s] | cost of transport "
        "| falls | steady bound (fixed start) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['controller']} | {r['trained_on'] or '-'} | {r['seed'] if r['seed'] != '' else '-'} "
            f"| {r['evaluated_on']} | {r['speed_m_s']:.2f} | {r['cost_of_transport']:.2f} "
            f"| {r['falls']} / {r['episodes']} | {'yes' if r['steady_bound'] else 'no'} "
            f"({r['fixed_start_speed_m_s']:.2f} m/s) |"
        )
    (out / "evaluation.md").write_text("\n".join(lines) + "\n")


def plot_curves(out: Path, runs: list[tuple[str, str, int]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_r, ax_l) = plt.subplots(1, 2, figsize=(10, 3.8), constrained_layout=True)
    seeds = sorted({seed for _, _, seed in runs})
    for train_model, action_type, seed in runs:
        f = out / run_name(train_model, action_type, seed) / "curve.csv"
        if not f.exists():
            continue
        with open(f) as fh:
            data = list(csv.DictReader(fh))
        if not data:
            continue
        steps = np.array([float(r["steps"]) for r in data]) / 1e6
        label = f"{train_model}, {action_type}, seed {seed}"
        style = {
            "color": MODEL_COLOURS[train_model],
            "ls": SEED_STYLES[seeds.index(seed) % len(SEED_STYLES)],
            "lw": 1.3,
            "label": label,
        }
        ax_r.plot(steps, [float(r["mean_return"]) for r in data], **style)
        ax_l.plot(steps, [float(r["mean_length"]) / 100.0 for r in data], **style)
    ax_r.set_xlabel("environment steps [millions]")
    ax_r.set_ylabel(f"mean return of the last {CURVE_WINDOW} episodes")
    ax_l.set_xlabel("environment steps [millions]")
    ax_l.set_ylabel("mean episode length [s]")
    ax_r.legend(fontsize=7)
    fig.suptitle("PPO on scoutsim/Bound-v0 (10 s episodes from random starts)")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _train_job(args) -> dict:
    return train(*args)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="learn_out")
    ap.add_argument("--steps", type=int, default=600_000, help="environment steps per run")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--train-models", nargs="+", default=["II"], choices=MODELS)
    ap.add_argument("--action-type", default="torque", choices=("torque", "setpoints"))
    ap.add_argument("--jobs", type=int, default=2, help="training runs at once (one core each)")
    ap.add_argument("--eval-episodes", type=int, default=10)
    ap.add_argument("--evaluate-only", action="store_true")
    ap.add_argument("--quick", action="store_true", help="20k steps, 1 seed, 2 episodes")
    ap.add_argument("--figure", default=None, help="also write the learning curves here")
    args = ap.parse_args(argv)
    if args.quick:
        args.steps, args.seeds, args.eval_episodes = 20_000, args.seeds[:1], 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    runs = [(m, args.action_type, s) for m in args.train_models for s in args.seeds]
    print(f"machine: {machine()}; load average {os.getloadavg()}", flush=True)
    settings = {
        "ppo": PPO_SETTINGS,
        "policy_kwargs": POLICY_KWARGS,
        "learning_rate_decay": LEARNING_RATE_DECAY,
        "n_envs": N_ENVS,
        "steps": args.steps,
        "runs": [run_name(*r) for r in runs],
        "machine": machine(),
        "python": sys.version.split()[0],
        "command": " ".join([Path(sys.argv[0]).name, *(argv or sys.argv[1:])]),
    }
    try:
        settings["git"] = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            cwd=Path(__file__).resolve().parent,
        ).stdout.strip()
    except OSError:
        pass
    (out / f"settings-{args.action_type}.json").write_text(json.dumps(settings, indent=2) + "\n")
    if not args.evaluate_only:
        todo = [(m, a, s, args.steps, str(out)) for m, a, s in runs]
        with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            for summary in pool.map(_train_job, todo):
                print(f"trained: {summary}", flush=True)
    plot_curves(out, runs, out / "curve.png")
    if args.figure:
        plot_curves(out, runs, Path(args.figure))
    rows = evaluate_all(out, runs, args.eval_episodes, args.jobs)
    write_evaluation(out, rows)
    print(f"wrote {out}/evaluation.md, evaluation.csv, curve.png", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
