"""The result of a tuning (:mod:`scoutsim.analysis.tune`) and the files it writes.

:class:`TuneResult` holds every evaluation's row (the parameters in the unit of their
names, then :data:`~scoutsim.analysis.tune_evaluation.COLUMNS`: score, objective, the run's
outcome and metrics in SI units with the unit in the column's name), the best one, and the
robot and controller parameters with the best values set (SI). In the output directory:
``tune.csv`` / ``tune.parquet`` (every evaluation), ``best.json``, ``best.toml`` (a
controller file that ``scoutsim run --controller FILE`` reads) and ``convergence.png``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..io.run_directory import RunDirectory, json_default, json_safe
from ..io.tables import write_rows_csv, write_rows_parquet
from ..parameters import ControllerParameters, RobotParameters
from .tune_evaluation import COLUMNS

__all__ = ["TuneResult"]


@dataclass
class TuneResult:
    """Every evaluation of a tuning, in order, and the best one.

    Attributes
    ----------
    rows : one dict per evaluation: the parameters (as named, in the given unit), then
        :data:`COLUMNS`.
    parameters : the tuned :class:`TuneParameter` s.
    best : the row with the lowest score (the first of equal ones).
    best_values : the best parameters {key: SI}.
    robot, controller_parameters : the base with the best parameters set (SI).
    params : the best parameter array of a CompiledController (else None).
    settings : what was tuned against (objective, scenarios, budget, seed, ...).
    stopped : why the tuning ended: "budget" or "converged" (CMA-ES's stopping rule).
    n_errors : evaluations the tuning could not run (status "error", recorded with
        ``on_error="record"``; scored as infeasible).
    refinement : what the gradient refinement after CMA-ES did
        (:class:`~scoutsim.analysis.tune_refinement.Refinement` as a dict), None without
        one. Its evaluations are the rows whose ``phase`` is "refine".
    """

    rows: list
    parameters: list
    best: dict
    best_values: dict
    robot: RobotParameters
    controller_parameters: ControllerParameters
    params: np.ndarray | None
    settings: dict = field(default_factory=dict)
    stopped: str = "budget"
    n_errors: int = 0
    refinement: dict | None = None

    def columns(self) -> dict:
        names = [p.name for p in self.parameters] + list(COLUMNS)
        return {n: [r.get(n) for r in self.rows] for n in names}

    def to_csv(self, path):
        write_rows_csv(path, self.columns())

    def to_parquet(self, path):
        write_rows_parquet(path, self.columns())

    def best_so_far(self) -> np.ndarray:
        """The lowest score up to each evaluation [objective's unit, or penalised]."""
        return np.minimum.accumulate(np.array([r["score"] for r in self.rows], dtype=float))

    def plot_convergence(self, path=None):
        """Figure of every evaluation's score and the best so far (needs Matplotlib); a
        convenience for :func:`scoutsim.presentation.plots.plot_tune_convergence`."""
        from ..presentation.plots import plot_tune_convergence

        return plot_tune_convergence(self, path)

    def write_controller_file(self, path, header: str = "") -> Path:
        """The best parameters as a controller file (``scoutsim run --controller FILE``);
        the robot's sections too if robot parameters were tuned."""
        from .controller_file import write_controller_file

        law = self.settings["controller"]
        if law not in ("table-i", "pitch-feedback"):
            raise ValueError(
                "a CompiledController's parameters go to best.json, not to a controller file"
            )
        tuned_robot = any(p.key.startswith("robot.") for p in self.parameters)
        return write_controller_file(
            path,
            law,
            self.controller_parameters,
            self.robot if tuned_robot else None,
            header=header,
        )

    def best_dict(self) -> dict:
        """JSON-safe summary of the best evaluation."""
        return {
            "best_score": self.best["score"],
            "best_evaluation": self.best["evaluation"],
            "parameters": {p.name: self.best[p.name] for p in self.parameters},
            "parameters_si": self.best_values,
            "params": None if self.params is None else [float(x) for x in self.params],
            "metrics": {k: self.best.get(k) for k in COLUMNS},
            "n_evaluations": len(self.rows),
            "n_errors": self.n_errors,
            "stopped": self.stopped,
            "refinement": self.refinement,
            "settings": self.settings,
        }


def write_outputs(res: TuneResult, rd: RunDirectory, command: str) -> None:
    rd.write("tune.csv", res.to_csv)
    try:
        rd.write("tune.parquet", res.to_parquet)
    except RuntimeError:
        pass
    rd.write(
        "best.json",
        lambda p: p.write_text(
            json.dumps(json_safe(res.best_dict()), indent=2, default=json_default) + "\n"
        ),
    )
    if res.settings["controller"] in ("table-i", "pitch-feedback"):
        b = res.best
        header = (
            f"scoutsim controller file: the best of {len(res.rows)} evaluations of "
            f"`{command or 'scoutsim.analysis.tune.tune'}`\n"
            f"objective {res.settings['goal']['objective']}"
            + (
                f" (target {res.settings['goal']['target']:g} m/s)"
                if res.settings["goal"]["target"] is not None
                else ""
            )
            + f": score {b['score']:.6g}, mean steady speed "
            + (f"{b['mean_speed_m_s']:.4f} m/s" if b["mean_speed_m_s"] is not None else "n/a")
            + f", {b['n_steady_strides']} steady strides\n"
            "run it: scoutsim run --controller THIS_FILE"
        )
        rd.write("best.toml", lambda p: res.write_controller_file(p, header=header))
    try:
        rd.write("convergence.png", lambda p: res.plot_convergence(p))
    except ImportError:
        pass
    rd.finish(outcome="completed", partial=False)
