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

Models: the ideal actuator, Model I, Model II, and the *virtual* robot (Model II with the
effects the paper names as error sources added to the robot: belt play, leg friction, an
angle-dependent leg damper, a lossy gearbox;
:data:`scoutsim.validation.make_example.VIRTUAL_SCOUT_EFFECTS`; on Scout II, the virtual
Scout II of :func:`scoutsim.validation.make_example.example_robot`).
Each optimised controller is then run on every model: its steady speed and cost of
transport over 20 s from the default start, and its basin fraction on a small grid of
starts (:func:`scoutsim.analysis.basin.basin_of_attraction`).

Run it (after ``pip install -e ".[tune]"`` in the repository; needs cmaes):

    python examples/transfer_study.py [--robot FILE] [--budget 120] [--out transfer_out]
                                      [--workers N] [--train ideal,I,II,virtual] [--quick]

``--robot FILE`` is a robot file as ``scoutsim run --robot`` reads it (default Scout II;
its ``[controller]`` section is the Table I controller both kinds start from); the
learned policy packs that robot's leg rest lengths and motor constants, per leg.
``--quick`` trains on Model II alone with one generation of 4 candidates on 3 s runs and
evaluates 5 s runs and one basin start (seconds in all; the numbers then show only that
it runs). Prints the table (markdown) and writes it, as ``transfer.md``, and every
evaluation with its tuned parameters, as ``transfer.json``, to ``--out``. The
ideal actuator has no electrical side: its cost of transport is hip work / (m g d), not
comparable with the other models' electrical one. The table and what it shows are in
docs/tuning.md.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

import scoutsim
from scoutsim import CompiledController, ControllerParameters, InitialState, RobotParameters
from scoutsim.analysis.basin import basin_of_attraction
from scoutsim.analysis.tune import tune
from scoutsim.control import sensors as S
from scoutsim.control.bounding import C_TD_B, NC, bounding_step, controller_array
from scoutsim.validation.make_example import VIRTUAL_SCOUT_EFFECTS

TARGET = 1.30  # the target speed [m/s], Scout II's "up to 1.3 m/s"
MODELS = {
    "ideal": ("ideal", False),
    "I": ("I", False),
    "II": ("II", False),
    "virtual": ("II", True),
}  # name: (model, with VIRTUAL_SCOUT_EFFECTS)
STARTS = (None, InitialState(dx=1.0, dtheta=0.0))  # the default start; a level start


@dataclass(frozen=True)
class StudySettings:
    """How much the study runs: the optimiser's budget (evaluations) and population (None:
    CMA-ES's default), the training runs' duration [s], the evaluation run's duration
    [s], the basin grid (speeds [m/s], pitch rates [deg/s], heights [m]) and its runs'
    duration [s], the training models."""

    budget: int = 120
    population: int | None = None
    train_duration: float = 12.0
    eval_duration: float = 20.0
    basin_grid: dict = field(
        default_factory=lambda: dict(
            speeds=(0.6, 1.0, 1.4),
            pitch_rates=tuple(math.radians(w) for w in (-50.0, 50.0, 150.0)),
            heights=(0.33,),
        )
    )
    basin_duration: float = 10.0
    train: tuple = ("ideal", "I", "II", "virtual")


#: --quick: one generation of 4 on Model II, short runs, the default start for the basin
QUICK = StudySettings(
    budget=4,
    population=4,
    train_duration=3.0,
    eval_duration=5.0,
    basin_grid=dict(speeds=(1.2,), pitch_rates=(math.radians(150.0),), heights=(0.33,)),
    basin_duration=5.0,
    train=("II",),
)

# --- the learned policy: features of the sensor readings, and its parameter array ------
# feature = (reading - offset) / scale; a leg's weights are in this order (W_* + F_*)
F_PITCH, F_PITCH_RATE, F_HEIGHT, F_ACCEL_X = range(4)
NF = 4
PITCH_SCALE = 0.1  # [rad]
PITCH_RATE_SCALE = 2.0  # [rad/s]
HEIGHT_OFFSET = 0.30  # [m] (the lasers' mean range)
HEIGHT_SCALE = 0.03  # [m]
ACCEL_X_SCALE = 10.0  # [m/s^2] (the accelerometer along the torso axis)
W_BACK = NC  # weights of the back leg's touchdown correction [rad per feature]
W_FRONT = NC + NF  # ... of the front leg's
NPOL = NC + 2 * NF
MAX_CORRECTION = math.radians(15.0)  # the policy moves a touchdown angle at most this much


def linear_policy(t, y, params, state, torque, leg_states):
    """Table I with the touchdown angles corrected linearly from the sensors: pitch,
    pitch rate, the lasers' mean range as a height, the accelerometer along the torso."""
    f_pitch = y[S.PITCH] / PITCH_SCALE
    f_rate = y[S.PITCH_RATE] / PITCH_RATE_SCALE
    f_height = (0.5 * (y[S.LASER_RANGE] + y[S.LASER_RANGE + 1]) - HEIGHT_OFFSET) / HEIGHT_SCALE
    f_accel = y[S.ACCELERATION] / ACCEL_X_SCALE
    C = params[:NC].copy()
    for leg in range(2):
        w = W_BACK + NF * leg
        d = (
            params[w + F_PITCH] * f_pitch
            + params[w + F_PITCH_RATE] * f_rate
            + params[w + F_HEIGHT] * f_height
            + params[w + F_ACCEL_X] * f_accel
        )
        d = min(MAX_CORRECTION, max(-MAX_CORRECTION, d))
        C[C_TD_B + leg] = params[C_TD_B + leg] + d
    transitions = np.zeros(2, dtype=np.int64)
    bounding_step(y, C, leg_states, torque, transitions)
    return 0


def policy_array(
    weights=None,
    controller: ControllerParameters | None = None,
    robot: RobotParameters | None = None,
) -> np.ndarray:
    """The policy's parameter array: the Table I array of ``controller`` on ``robot``
    (:func:`~scoutsim.control.bounding.controller_array`: set-points, gains and each leg's
    rest length and motor constants; defaults Table I, Scout II), then the weights (slots
    ``W_BACK``, ``W_FRONT``; default 0)."""
    p = np.zeros(NPOL)
    p[:NC] = controller_array(controller or ControllerParameters(), robot)
    if weights is not None:
        p[NC:] = weights
    return p


class LinearPolicy(CompiledController):
    """:func:`linear_policy` with its parameter array (default: :func:`policy_array`);
    picklable (rebuilt from its array)."""

    def __init__(self, params=None):
        super().__init__(
            linear_policy, params=policy_array() if params is None else params, name="linear_policy"
        )

    def __reduce__(self):
        return (type(self), (self.params,))


# --- the study ----------------------------------------------------------------------
def model_robot(robot: RobotParameters, on: str) -> RobotParameters:
    """The robot of model ``on``: ``robot``, with the virtual robot's effects for
    "virtual"."""
    return robot.replace(**VIRTUAL_SCOUT_EFFECTS) if MODELS[on][1] else robot


def train(
    kind: str,
    on: str,
    robot: RobotParameters,
    controller: ControllerParameters,
    settings: StudySettings,
    out: Path,
    workers: int | None,
):
    """Optimise ``kind`` ("tuned" or "learned") on model ``on`` from ``controller`` on
    ``robot``; returns the controller and the tuning's result."""
    common = dict(
        objective="speed",
        target=TARGET,
        budget=settings.budget,
        population=settings.population,
        model=MODELS[on][0],
        robot=model_robot(robot, on),
        starts=list(STARTS),
        duration=settings.train_duration,
        seed=1,
        workers=workers,
        out=out / f"{kind}_{on}",
    )
    if kind == "tuned":
        names = [
            "controller.touchdown_angle_back_deg=10:30",
            "controller.touchdown_angle_front_deg=10:30",
            "controller.sweep_limit_back_deg=-15:10",
            "controller.sweep_limit_front_deg=-15:10",
        ]
        res = tune(names, controller=controller, **common)
        return res.controller_parameters, res
    names = [f"controller.params[{i}]=-0.1:0.1" for i in range(NC, NPOL)]
    res = tune(
        names, controller=LinearPolicy(policy_array(None, controller, robot)), sigma=0.2, **common
    )
    return LinearPolicy(res.params), res


def evaluate(
    controller, on: str, robot: RobotParameters, settings: StudySettings, workers: int | None
) -> dict:
    """Steady speed, cost of transport (default start) and basin fraction of
    ``controller`` on model ``on``."""
    model = MODELS[on][0]
    rob = model_robot(robot, on)
    r = scoutsim.simulate(rob, controller, None, settings.eval_duration, model=model, energy=True)
    s = r.summary()
    basin = basin_of_attraction(
        models=(model,),
        duration=settings.basin_duration,
        robot=rob,
        controller=controller,
        workers=workers,
        **settings.basin_grid,
    )
    return {
        "outcome": r.outcome,
        "steady": bool(s.get("steady_bounding")),
        "speed_m_s": s.get("mean_speed_m_s"),
        "cot": s.get("cost_of_transport"),
        "basin": basin.fraction(model),
    }


def _fmt(row):
    if not row["steady"]:
        return (
            f"falls / no bound ({row['outcome']})"
            if row["outcome"] != "completed"
            else "no steady bound"
        )
    cot = row["cot"]
    return (
        f"{row['speed_m_s']:.2f} m/s, CoT {cot:.2f}, basin {row['basin']:.2f}"
        if cot is not None
        else f"{row['speed_m_s']:.2f} m/s, basin {row['basin']:.2f}"
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--robot",
        metavar="FILE",
        help="TOML robot file, as `scoutsim run --robot` (default: Scout II)",
    )
    ap.add_argument(
        "--budget",
        type=int,
        default=None,
        help="evaluations per optimisation (default 120, 4 with --quick)",
    )
    ap.add_argument("--out", type=Path, default=Path("transfer_out"))
    ap.add_argument(
        "--workers", type=int, default=None, help="processes (default: all cores; 1 with --quick)"
    )
    ap.add_argument(
        "--train",
        default=None,
        help="comma-separated training models (default ideal,I,II,virtual; II with --quick)",
    )
    ap.add_argument(
        "--quick", action="store_true", help="a tiny budget on short runs (seconds in all)"
    )
    args = ap.parse_args(argv)
    settings = QUICK if args.quick else StudySettings()
    if args.budget is not None:
        settings = replace(settings, budget=args.budget)
    if args.train is not None:
        settings = replace(settings, train=tuple(args.train.split(",")))
    unknown = [m for m in settings.train if m not in MODELS]
    if unknown:
        ap.error(f"--train {','.join(unknown)}: not a model; models: {', '.join(MODELS)}")
    workers = args.workers if args.workers is not None else (1 if args.quick else None)
    robot, controller = scoutsim.load_parameters(args.robot)
    args.out.mkdir(parents=True, exist_ok=True)
    rows = {}
    t0 = time.perf_counter()
    for kind in ("tuned", "learned"):
        for on in settings.train:
            ctrl, res = train(kind, on, robot, controller, settings, args.out, workers)
            best = {"score": res.best["score"], "values": res.best_values}
            for ev in MODELS:
                rows[(kind, on, ev)] = evaluate(ctrl, ev, robot, settings, workers) | {
                    "trained": best
                }
            print(
                f"{kind} on {on}: best score {res.best['score']:.4g}, "
                f"{time.perf_counter() - t0:.0f} s so far",
                flush=True,
            )
    lines = [
        "| controller | trained on | " + " | ".join(f"on {m}" for m in MODELS) + " |",
        "|---|---|" + "---|" * len(MODELS),
    ]
    for kind in ("tuned", "learned"):
        for on in settings.train:
            lines.append(
                f"| {kind} | {on} | "
                + " | ".join(_fmt(rows[(kind, on, ev)]) for ev in MODELS)
                + " |"
            )
    table = "\n".join(lines)
    print(table)
    (args.out / "transfer.md").write_text(table + "\n")
    (args.out / "transfer.json").write_text(
        json.dumps({f"{k}|{o}|{e}": v for (k, o, e), v in rows.items()}, indent=1, default=str)
    )
    print(f"wrote {args.out / 'transfer.md'} and {args.out / 'transfer.json'}")


if __name__ == "__main__":
    main()
