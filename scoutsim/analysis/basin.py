"""Basin of attraction of the bounding cycle over a grid of initial states.

The paper calls the Table I controller robust on the robot; a simulator in which only a
narrow set of starts reaches steady bounding tells us a modelling assumption is off. This
module runs a grid of starts (forward speed, pitch rate, torso height; the rest of
:class:`~scoutsim.state.InitialState` at its defaults, i.e. level torso, legs at their
touchdown angles) per model variant and floor, in parallel processes, and reports the
fraction that reaches steady bounding
(:meth:`~scoutsim.analysis.gait.GaitMetrics.is_steady_bounding`) and the speed of the cycle
reached; :func:`scoutsim.presentation.plots.plot_basin_map` draws it as a map.

The default grid spans pitch rates of both signs, -150 to +250 deg/s, wide enough to show
the basin's edges: the Table I controller has no torso feedback, and the starts that enter
bounding are those with the nose rising, the motion the robot has after its front legs
push off (with :class:`~scoutsim.control.PitchFeedbackController` almost all do; README,
"Torso feedback").
"""

from __future__ import annotations

import csv
import itertools
import math
import os
from dataclasses import dataclass, field

from ..parameters import DEFAULT_FRICTION_COEFFICIENT, floor_label
from .parallel import map_tasks

DEFAULT_SPEEDS = (0.4, 0.6, 0.8, 1.0, 1.2, 1.4, 1.6, 1.8)                         # m/s
DEFAULT_PITCH_RATES = (-150.0, -100.0, -50.0, 0.0, 50.0, 100.0, 150.0, 200.0, 250.0)  # deg/s
DEFAULT_HEIGHTS = (0.33, 0.38)                                                     # m
#: floors of the default map: the package's default floor and the no-slip idealisation
DEFAULT_FLOORS = (DEFAULT_FRICTION_COEFFICIENT, math.inf)


BASIN_COLUMNS = ("model", "friction", "speed", "pitch_rate_deg_s", "height", "outcome",
                 "steady_bounding", "mean_speed_m_s", "n_steady_strides")


def _start_of(task: dict) -> dict:
    """The identifying columns of one start's row."""
    return {k: task[k] for k in ("model", "friction", "speed", "pitch_rate_deg_s", "height")}


def basin_task(task: dict) -> dict:
    """Run one start of the basin grid (top level so that worker processes can import it)."""
    from ..simulation import simulate
    from ..state import InitialState
    row = _start_of(task)
    try:
        init = InitialState(dx=task["speed"], dtheta=math.radians(task["pitch_rate_deg_s"]),
                            y=task["height"])
        result = simulate(task["robot"], task["controller"], init, task["duration"],
                          model=task["model"], integrator=task["integrator"],
                          friction_coefficient=task["friction"])
        if result.outcome == "interrupted":
            # Ctrl-C reached the run (simulate() returns the data so far): this start is
            # not done and must not be counted as if it were; the map stops
            raise KeyboardInterrupt
    except ValueError as exc:
        row.update(outcome="invalid_start", steady_bounding=False, mean_speed_m_s=None,
                   n_steady_strides=0, error=str(exc))
        return row
    except Exception as exc:  # noqa: BLE001 - reported per start, exit code 1
        row.update(outcome="error", steady_bounding=False, mean_speed_m_s=None,
                   n_steady_strides=0, error=f"{type(exc).__name__}: {exc}")
        return row
    g = result.gait()
    speed = g.mean_speed_m_s
    row.update(outcome=result.outcome, steady_bounding=bool(g.is_steady_bounding()),
               mean_speed_m_s=(float(speed) if speed is not None and math.isfinite(speed)
                               else None),
               n_steady_strides=int(g.n_steady_strides))
    return row


def _basin_error_row(task: dict, exc: Exception) -> dict:
    row = _start_of(task)
    row.update(outcome="error", steady_bounding=False, mean_speed_m_s=None,
               n_steady_strides=0, error=f"{type(exc).__name__}: {exc}")
    return row


def run_basin_tasks(tasks: list[dict], workers: int, progress: bool, scheduler=None,
                    on_result=None) -> list[dict]:
    """Run the starts (locally in parallel, or on a Dask cluster); rows in task order
    (``on_result(index, row)`` as each arrives: what an interrupted map keeps)."""
    return map_tasks(basin_task, tasks, workers=workers, scheduler=scheduler,
                     progress=progress, desc="basin", error_row=_basin_error_row,
                     on_result=on_result)


def basin_stats(rows: list[dict], models: list[str], floors=None) -> dict:
    """Per model (and floor, keys "MODEL @ FLOOR" when ``floors`` is given): starts,
    invalid starts, steady starts, fraction, outcomes, median cycle speed [m/s]."""
    per = {}
    keys = ([(m, None) for m in models] if floors is None else
            [(m, mu) for mu in floors for m in models])
    for m, mu in keys:
        mine = [r for r in rows if r["model"] == m and (mu is None or r["friction"] == mu)]
        speeds = sorted(r["mean_speed_m_s"] for r in mine
                        if r["steady_bounding"] and r["mean_speed_m_s"] is not None)
        invalid = sum(r["outcome"] == "invalid_start" for r in mine)
        valid = len(mine) - invalid
        steady = sum(bool(r["steady_bounding"]) for r in mine if r["outcome"] != "invalid_start")
        outcomes = {}
        for r in mine:
            outcomes[r["outcome"]] = outcomes.get(r["outcome"], 0) + 1
        key = m if mu is None else f"{m} @ {floor_label(mu)}"
        per[key] = {"model": m, "friction": mu, "n_starts": len(mine),
                    "n_invalid_start": invalid, "n_valid": valid,
                    "n_steady_bounding": steady,
                    "fraction_steady_bounding": (steady / valid) if valid else None,
                    "median_cycle_speed_m_s": (speeds[len(speeds) // 2] if speeds else None),
                    "outcomes": outcomes}
    return per



@dataclass
class BasinResult:
    """Per-start outcomes and the steady-bounding fraction per model and floor."""

    rows: list
    settings: dict = field(default_factory=dict)

    def fraction(self, model: str, friction: float | None = None):
        """Fraction of valid starts of ``model`` (on floor ``friction``; None = all floors)
        that reach steady bounding (None if there are none)."""
        valid = [r for r in self.rows if r["model"] == model and r["outcome"] != "invalid_start"
                 and (friction is None or r["friction"] == friction)]
        if not valid:
            return None
        return sum(r["steady_bounding"] for r in valid) / len(valid)

    def models(self):
        return list(dict.fromkeys(r["model"] for r in self.rows))

    def floors(self):
        return list(dict.fromkeys(r["friction"] for r in self.rows))

    def summary(self) -> dict:
        """Per model and floor: starts, invalid starts, steady starts, fraction, outcomes,
        median cycle speed."""
        return basin_stats(self.rows, self.models(), self.floors())

    def to_csv(self, path):
        with open(path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=BASIN_COLUMNS, extrasaction="ignore")
            w.writeheader()
            for r in self.rows:
                w.writerow({k: ("" if r.get(k) is None else r[k]) for k in BASIN_COLUMNS})


def basin_tasks(models, floors, speeds, pitch_rates_deg_s, heights, duration, robot=None,
                controller=None, integrator=None) -> list[dict]:
    """One task per (floor, model, speed, pitch rate, height), in that nesting order."""
    return [{"model": m, "speed": float(v), "pitch_rate_deg_s": float(w), "height": float(y),
             "robot": robot, "controller": controller, "duration": duration,
             "integrator": integrator, "friction": float(mu)}
            for mu, m, v, w, y in itertools.product(floors, models, speeds, pitch_rates_deg_s,
                                                    heights)]


def basin_of_attraction(models=("ideal", "I", "II"), speeds=DEFAULT_SPEEDS,
                        pitch_rates_deg_s=DEFAULT_PITCH_RATES, heights=DEFAULT_HEIGHTS,
                        duration: float = 10.0, robot=None, controller=None,
                        friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
                        workers: int | None = None, progress: bool = False, integrator=None,
                        floors=None) -> BasinResult:
    """Run the grid of starts and classify each (see module docstring).

    Parameters
    ----------
    models : model variants ("ideal", "I", "II").
    speeds : initial forward speeds [m/s].
    pitch_rates_deg_s : initial pitch rates [deg/s] (positive: nose rising).
    heights : initial torso-COM heights [m].
    duration : simulated time per start [s].
    robot : RobotParameters (default Scout II).
    controller : what every start runs: ControllerParameters (None: Table I) or a
        controller object, e.g. :class:`~scoutsim.control.PitchFeedbackController`; with
        ``workers`` > 1 it travels to the worker processes, so it must pickle (a
        PitchFeedbackController does: the worker rebuilds it from its parameters).
    friction_coefficient : toe Coulomb coefficient (inf = no slip), when ``floors`` is None.
    floors : several toe Coulomb coefficients (e.g. :data:`DEFAULT_FLOORS`); every start
        is run on each.
    workers : processes (default: all cores; 1 = in this process).
    """
    floors = tuple(floors) if floors is not None else (friction_coefficient,)
    tasks = basin_tasks(models, floors, speeds, pitch_rates_deg_s, heights, duration, robot,
                        controller, integrator)
    workers = workers or os.cpu_count() or 1
    rows = run_basin_tasks(tasks, workers, progress)
    return BasinResult(rows=rows, settings={
        "models": list(models), "speeds_m_s": list(speeds),
        "pitch_rates_deg_s": list(pitch_rates_deg_s), "heights_m": list(heights),
        "duration_s": duration,
        "controller": (None if controller is None or not hasattr(controller, "command")
                       else getattr(controller, "name", type(controller).__name__)),
        "floors": [None if math.isinf(mu) else mu for mu in floors]})
