"""Does a controller tuned or learned on one model survive another? The paper's question
(ideal actuator and rigid transmission "give misleading models") asked of optimised
controllers.

Two controllers are optimised on each training model and evaluated on every model:

* **tuned**: the Table I controller with its four set-points (touchdown angles and sweep
  limits, back and front) tuned by CMA-ES (:func:`scoutsim.analysis.tune.tune`) for a
  steady bound at the target speed, from the default start and from a level start;
* **learned**: a linear policy over the sensors, the touchdown angles corrected by a
  weighted sum of the IMU's pitch and pitch rate, the lasers' height and the
  accelerometer's forward reading (:func:`linear_policy`, a compiled controller), its
  weights found by the same CMA-ES (policy search, no deep-learning stack), for the same
  goal from the same starts.

Models: the ideal actuator, Model I, Model II, and the *virtual Scout II* (Model II with
the effects the paper names as error sources: belt play, leg friction, an angle-dependent
leg damper, a lossy gearbox; :func:`scoutsim.validation.make_example.example_robot`).
Each optimised controller is then run on every model: its steady speed and cost of
transport over 20 s from the default start, and its basin fraction on a small grid of
starts (:func:`scoutsim.analysis.basin.basin_of_attraction`).

    python examples/transfer_study.py [--budget 120] [--out transfer_out] [--workers N]

Prints the table (markdown) and writes it with every tuned parameter to ``--out``. The
ideal actuator has no electrical side: its cost of transport is hip work / (m g d), not
comparable with the other models' electrical one. The table and what it shows are in the
README, "Does a tuned or learned controller transfer?".
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

import scoutsim
from scoutsim import CompiledController, ControllerParameters, InitialState
from scoutsim.analysis.basin import basin_of_attraction
from scoutsim.analysis.tune import tune
from scoutsim.control import sensors as S
from scoutsim.control.bounding import C_TD_B, NC, bounding_step, controller_array
from scoutsim.validation.make_example import example_robot

TARGET = 1.30          # the target speed [m/s], Scout II's "up to 1.3 m/s"
MODELS = {"ideal": ("ideal", None), "I": ("I", None), "II": ("II", None),
          "virtual": ("II", "virtual")}
STARTS = (None, InitialState(dx=1.0, dtheta=0.0))   # the default start; a level start
BASIN_GRID = dict(speeds=(0.6, 1.0, 1.4), pitch_rates_deg_s=(-50.0, 50.0, 150.0),
                  heights=(0.33,))

# --- the learned policy: features of the sensor readings, and its parameter array ------
#: (slot or special, offset, scale): feature = (reading - offset) / scale
FEATURES = (("pitch", 0.0, 0.1), ("pitch_rate", 0.0, 2.0), ("height", 0.30, 0.03),
            ("accel_x", 0.0, 10.0))
NF = len(FEATURES)
W_BACK = NC            # weights of the back leg's touchdown correction [rad per feature]
W_FRONT = NC + NF      # ... of the front leg's
NPOL = NC + 2 * NF
MAX_CORRECTION = math.radians(15.0)   # the policy moves a touchdown angle at most this much


def linear_policy(t, y, params, state, torque, leg_states):
    """Table I with the touchdown angles corrected linearly from the sensors: pitch,
    pitch rate, the lasers' mean range as a height, the accelerometer along the torso."""
    f0 = y[S.PITCH] / 0.1
    f1 = y[S.PITCH_RATE] / 2.0
    f2 = (0.5 * (y[S.LASER_RANGE] + y[S.LASER_RANGE + 1]) - 0.30) / 0.03
    f3 = y[S.ACCELERATION] / 10.0
    C = params[:NC].copy()
    for leg in range(2):
        w = NC + NF * leg
        d = params[w] * f0 + params[w + 1] * f1 + params[w + 2] * f2 + params[w + 3] * f3
        d = min(MAX_CORRECTION, max(-MAX_CORRECTION, d))
        C[C_TD_B + leg] = params[C_TD_B + leg] + d
    transitions = np.zeros(2, dtype=np.int64)
    bounding_step(y, C, leg_states, torque, transitions)
    return 0


def policy_array(weights=None, controller: ControllerParameters | None = None) -> np.ndarray:
    p = np.zeros(NPOL)
    p[:NC] = controller_array(controller or ControllerParameters())
    if weights is not None:
        p[NC:] = weights
    return p


class LinearPolicy(CompiledController):
    """:func:`linear_policy` with its weights; picklable (rebuilt from its array)."""

    def __init__(self, params=None):
        super().__init__(linear_policy, params=policy_array() if params is None else params,
                         name="linear_policy")

    def __reduce__(self):
        return (type(self), (self.params,))


# --- the study ----------------------------------------------------------------------
def _robot(which):
    return example_robot() if which == "virtual" else None


def train(kind: str, on: str, budget: int, out: Path, workers: int):
    """Optimise ``kind`` ("tuned" or "learned") on model ``on``; returns the controller."""
    model, which = MODELS[on]
    common = dict(objective="speed", target=TARGET, budget=budget, model=model,
                  robot=_robot(which), starts=list(STARTS), duration=12.0, seed=1,
                  workers=workers, out=out / f"{kind}_{on}")
    if kind == "tuned":
        names = ["controller.touchdown_angle_back_deg=10:30",
                 "controller.touchdown_angle_front_deg=10:30",
                 "controller.sweep_limit_back_deg=-15:10",
                 "controller.sweep_limit_front_deg=-15:10"]
        res = tune(names, controller=ControllerParameters(), **common)
        return res.controller_parameters, res
    names = [f"controller.params[{i}]=-0.1:0.1" for i in range(NC, NPOL)]
    res = tune(names, controller=LinearPolicy(), sigma=0.2, **common)
    return LinearPolicy(res.params), res


def evaluate(controller, on: str, workers: int) -> dict:
    """Steady speed, cost of transport (20 s, default start) and basin fraction of
    ``controller`` on model ``on``."""
    model, which = MODELS[on]
    robot = _robot(which)
    r = scoutsim.simulate(robot, controller, None, 20.0, model=model, energy=True)
    s = r.summary()
    basin = basin_of_attraction(models=(model,), duration=10.0, robot=robot,
                                controller=controller, workers=workers, **BASIN_GRID)
    return {"outcome": r.outcome, "steady": bool(s.get("steady_bounding")),
            "speed_m_s": s.get("mean_speed_m_s"), "cot": s.get("cost_of_transport"),
            "basin": basin.fraction(model)}


def _fmt(row):
    if not row["steady"]:
        return f"falls / no bound ({row['outcome']})" if row["outcome"] != "completed" \
            else "no steady bound"
    cot = row["cot"]
    return (f"{row['speed_m_s']:.2f} m/s, CoT {cot:.2f}, basin {row['basin']:.2f}"
            if cot is not None else f"{row['speed_m_s']:.2f} m/s, basin {row['basin']:.2f}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--budget", type=int, default=120, help="evaluations per optimisation")
    ap.add_argument("--out", type=Path, default=Path("transfer_out"))
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--train", default="ideal,I,II,virtual",
                    help="comma-separated training models")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    rows = {}
    t0 = time.perf_counter()
    for kind in ("tuned", "learned"):
        for on in args.train.split(","):
            ctrl, res = train(kind, on, args.budget, args.out, args.workers)
            best = {"score": res.best["score"], "values": res.best_values}
            for ev in MODELS:
                rows[(kind, on, ev)] = evaluate(ctrl, ev, args.workers) | {"trained": best}
            print(f"{kind} on {on}: best score {res.best['score']:.4g}, "
                  f"{time.perf_counter() - t0:.0f} s so far", flush=True)
    lines = ["| controller | trained on | " + " | ".join(f"on {m}" for m in MODELS) + " |",
             "|---|---|" + "---|" * len(MODELS)]
    for kind in ("tuned", "learned"):
        for on in args.train.split(","):
            lines.append(f"| {kind} | {on} | " + " | ".join(
                _fmt(rows[(kind, on, ev)]) for ev in MODELS) + " |")
    table = "\n".join(lines)
    print(table)
    (args.out / "transfer.md").write_text(table + "\n")
    (args.out / "transfer.json").write_text(json.dumps(
        {f"{k}|{o}|{e}": v for (k, o, e), v in rows.items()}, indent=1, default=str))


if __name__ == "__main__":
    main()
