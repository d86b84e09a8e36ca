"""Basin of attraction of the bounding cycle over a grid of initial states.

The paper calls the Table I controller robust on the robot; a simulator in which only a
narrow set of starts reaches steady bounding tells us a modelling assumption is off. This
module runs a grid of starts (forward speed, pitch rate, torso height; the rest of
:class:`~scoutsim.simulation.InitialState` at its defaults) per model variant, in parallel
processes, and reports the fraction that reaches steady bounding
(:meth:`~scoutsim.analysis.gait.GaitMetrics.is_steady_bounding`).
"""

from __future__ import annotations

import csv
import itertools
import math
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

DEFAULT_SPEEDS = (0.8, 1.1, 1.4, 1.7)            # m/s
DEFAULT_PITCH_RATES = (-100.0, -50.0, 0.0, 50.0)  # deg/s (edge unit: converted once below)
DEFAULT_HEIGHTS = (0.36, 0.40)                   # m


def _one(task):
    from ..simulation import InitialState, simulate
    model, speed, pitch_rate_deg_s, height, duration, robot, controller, mu = task
    row = {"model": model, "speed_m_s": speed, "pitch_rate_deg_s": pitch_rate_deg_s,
           "height_m": height}
    try:
        init = InitialState(y=height, dx=speed, dtheta=math.radians(pitch_rate_deg_s))
        r = simulate(robot, controller, init, duration, model=model, friction_coefficient=mu)
    except ValueError as e:
        return row | {"outcome": "invalid_start", "steady_bounding": False,
                      "mean_speed_m_s": None, "n_steady_strides": 0, "error": str(e)}
    g = r.gait()
    return row | {"outcome": r.outcome, "steady_bounding": bool(g.is_steady_bounding()),
                  "mean_speed_m_s": g.mean_speed_m_s, "n_steady_strides": g.n_steady_strides,
                  "error": ""}


@dataclass
class BasinResult:
    """Per-start outcomes and the steady-bounding fraction per model."""

    rows: list
    settings: dict = field(default_factory=dict)

    def fraction(self, model: str):
        """Fraction of valid starts of ``model`` that reach steady bounding (None if none)."""
        valid = [r for r in self.rows if r["model"] == model and r["outcome"] != "invalid_start"]
        if not valid:
            return None
        return sum(r["steady_bounding"] for r in valid) / len(valid)

    def models(self):
        return list(dict.fromkeys(r["model"] for r in self.rows))

    def summary(self) -> dict:
        out = {}
        for m in self.models():
            rows = [r for r in self.rows if r["model"] == m]
            out[m] = {"fraction_steady": self.fraction(m),
                      "n_starts": len(rows),
                      "n_invalid_starts": sum(r["outcome"] == "invalid_start" for r in rows),
                      "n_steady": sum(r["steady_bounding"] for r in rows)}
        return out

    def to_csv(self, path):
        keys = ["model", "speed_m_s", "pitch_rate_deg_s", "height_m", "outcome",
                "steady_bounding", "mean_speed_m_s", "n_steady_strides"]
        with open(path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
            w.writeheader()
            for r in self.rows:
                w.writerow(r)


def basin_of_attraction(models=("ideal", "I", "II"), speeds=DEFAULT_SPEEDS,
                        pitch_rates_deg_s=DEFAULT_PITCH_RATES, heights=DEFAULT_HEIGHTS,
                        duration: float = 10.0, robot=None, controller=None,
                        friction_coefficient: float = math.inf, workers: int | None = None,
                        progress: bool = False) -> BasinResult:
    """Run the grid of starts and classify each (see module docstring).

    Parameters
    ----------
    models : model variants ("ideal", "I", "II").
    speeds : initial forward speeds [m/s].
    pitch_rates_deg_s : initial pitch rates [deg/s].
    heights : initial torso-COM heights [m].
    duration : simulated time per start [s].
    friction_coefficient : toe Coulomb coefficient (inf = no slip).
    workers : processes (default: all cores; 1 = in this process).
    """
    tasks = [(m, float(v), float(w), float(y), duration, robot, controller,
              friction_coefficient)
             for m, v, w, y in itertools.product(models, speeds, pitch_rates_deg_s, heights)]
    workers = workers or os.cpu_count() or 1
    if workers == 1:
        rows = [_one(t) for t in tasks]
    else:
        with ProcessPoolExecutor(workers) as ex:
            rows = list(ex.map(_one, tasks))
    return BasinResult(rows=rows, settings={
        "models": list(models), "speeds_m_s": list(speeds),
        "pitch_rates_deg_s": list(pitch_rates_deg_s), "heights_m": list(heights),
        "duration_s": duration,
        "friction_coefficient": None if math.isinf(friction_coefficient) else friction_coefficient})
