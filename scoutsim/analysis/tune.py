"""Tuning: optimise controller (and robot) parameters against an objective a user states.

What is tuned: fields of :class:`~scoutsim.parameters.ControllerParameters` (Table I and
the torso-feedback gains of :class:`~scoutsim.control.PitchFeedbackController`), named
``controller.<field>``; fields of :class:`~scoutsim.parameters.RobotParameters` for design
studies, ``robot.<field>``; entries of a :class:`~scoutsim.CompiledController`'s parameter
array, ``controller.params[i]``. A ``_deg`` suffix on an angle field takes degrees at the
edge (converted here, once); everything inside is SI. Bounds are the field's allowed range
(:func:`scoutsim.parameters.allowed_range`) or a range the user gives, ``NAME=LOW:HIGH``.

What is minimised (``objective``), over the steady strides of each run:

- ``"speed"``: ``|v - target|`` [m/s], v the mean forward speed of the steady strides;
- ``"max-speed"``: ``-v`` [m/s];
- ``"cot"``: the cost of transport [-] (electrical energy / (m g d), ``simulate(energy=True)``);
- ``"stability"``: the spectral radius [-] of the stride map at the run's periodic orbit
  (Newton from the run's last strides, :func:`scoutsim.analysis.orbits.controlled_fixed_point`;
  < 1: stable), a few seconds per evaluation; Table I controller only (the orbit tools
  cut the stride map at the lift-offs the controller logs, which compiled controllers
  do not log).

Constraints: the run must not fall (nor fail), must bound steadily
(:meth:`~scoutsim.analysis.gait.GaitMetrics.is_steady_bounding`: at least 7 steady strides
after the 2 s transient, stride periods within 5 %), and optionally keep the belt deflection
below ``max_belt_deflection`` [rad], the motor current below ``max_current`` [A] and the
steady speed above ``min_speed`` [m/s]. Robustness: each evaluation runs every scenario
(the product of ``models``, ``floors`` and ``starts``) and its score is the worst
(``aggregate="worst"``) or the mean of the scenarios' scores.

**Score** (what the optimiser sees, lower is better). CMA-ES ranks the candidates of a
generation and uses nothing but the ranks, so the penalties only have to order them:
every feasible candidate before every infeasible one, and among infeasible ones those
closer to feasible first, so the search is drawn towards the feasible region even when a
generation has no feasible member::

    feasible                        score = objective
    completed, k constraints broken score = P (1 + k + sum_j min(1, e_j)) + objective*
    fell / failed at t_end          score = 10 P (2 - t_end / duration)

with P = :data:`PENALTY` = 1000, e_j each broken constraint's relative excess (not steady:
the fraction of the 7 steady strides missing, 1 with them all but irregular) and
objective* the objective where it is defined (the whole-run average speed stands in for the
steady speed of a run with no steady strides; otherwise 0). A run that falls later ranks
before one that falls sooner.

**Optimiser**: CMA-ES (Hansen & Ostermeier, Evolutionary Computation 9(2), 2001), the
``cmaes`` library's implementation (the one Optuna's CMA-ES sampler uses), in the unit
cube of the parameters' bounds, started at the base parameters with step ``sigma`` (a
fraction of each range). Why CMA-ES: the scores are non-smooth (touchdown events, stride
counts, falls) and a few parameters are tuned at a time, where CMA-ES is the standard
derivative-free method; a generation is a batch of independent runs, which is what
:func:`scoutsim.analysis.parallel.map_tasks` runs on local cores or a Dask cluster. Why
``cmaes`` driven generation by generation rather than an Optuna study: its whole state,
random generator included, pickles, so the optimiser is saved after every generation and a
resumed run asks exactly the candidates the uninterrupted run asked (an Optuna sampler's
random state lives in the process, and its SQLite study would be a second copy of the
evaluations table).

**Resuming**: every finished evaluation is appended to ``out/evaluations.jsonl`` as it
arrives (Ctrl-C keeps them all), and the optimiser's state to ``out/optimizer.pkl``
(written atomically) after every generation. The same call again continues from them: the
generation that was cut re-asks the same candidates and runs only those not yet done, so
the table, the best parameters and everything after them equal an uninterrupted run's; a
call with a larger ``budget`` continues a finished one. Determinism: the same settings,
``seed`` and ``budget`` give the same evaluations, on one process, many, or a cluster.

Outputs in ``out``: ``tune.csv`` / ``tune.parquet`` (every evaluation), ``convergence.png``,
``best.toml`` (a controller file, :mod:`scoutsim.analysis.controller_file`, that
``scoutsim run --controller FILE`` reads), ``best.json`` and ``manifest.json``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import math
import os
import pickle
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from ..parameters import (DEFAULT_FRICTION_COEFFICIENT, ControllerParameters, RobotParameters,
                          allowed_range, field_dimension, physical_limit,
                          validate_parameters)
from ..run_directory import RunDirectory, atomic_write
from ..tables import write_rows_csv, write_rows_parquet
from .parallel import map_tasks, pool_is_broken, worker_pool
from .sweep import _check_name, _orbit_columns, parameter_names, read_checkpoint

__all__ = ["tune", "TuneParameter", "TuneResult", "parse_parameter", "OBJECTIVES",
           "AGGREGATES", "PENALTY", "EVALUATIONS", "OPTIMIZER_STATE", "tune_task",
           "MissingDependencyError", "EvaluationNotRunError"]

#: what can be minimised (module docstring)
OBJECTIVES = ("speed", "max-speed", "cot", "stability")
#: how the scenarios' scores make one
AGGREGATES = ("worst", "mean")
#: score of a broken constraint (module docstring); larger than any objective value
PENALTY = 1000.0
#: the checkpoint of the evaluations: one JSON record per evaluation, appended as it arrives
EVALUATIONS = "evaluations.jsonl"
#: the optimiser's state before the next generation (pickled, written atomically)
OPTIMIZER_STATE = "optimizer.pkl"
#: steady strides a steady bound needs (GaitMetrics.is_steady_bounding)
MIN_STEADY_STRIDES = 7
#: the table's columns after the parameters
COLUMNS = ("evaluation", "generation", "score", "objective", "feasible", "violations",
           "outcome", "t_end_s", "mean_speed_m_s", "average_speed_m_s", "n_steady_strides",
           "steady_bounding", "cost_of_transport", "max_belt_deflection_deg",
           "peak_current_a", "spectral_radius", "scenario", "error")

_PARAMS_NAME = re.compile(r"^controller\.params\[(\d+)\]$")


class MissingDependencyError(ImportError):
    """The optional optimiser library is not installed (the message says what to install)."""


def _cma_class():
    try:
        from cmaes import CMA
    except ImportError:
        raise MissingDependencyError(
            "tuning needs the CMA-ES library 'cmaes', which is not installed: "
            "pip install cmaes (or pip install 'scoutsim[tune]')") from None
    return CMA


# -----------------------------------------------------------------------------------------
# parameters
# -----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TuneParameter:
    """One tuned parameter.

    Attributes
    ----------
    name : the name as given (``controller.touchdown_angle_front_deg``, ``robot.leg_stiffness``,
        ``controller.params[3]``); the table's column of its values in the given unit.
    key : where it goes: ``controller.<field>``, ``robot.<field>`` (SI) or ``params[i]``.
    low, high : bounds [SI].
    scale : SI value per unit of the given value (pi / 180 for a ``_deg`` name, else 1).
    """

    name: str
    key: str
    low: float
    high: float
    scale: float = 1.0

    def shown(self, si: float) -> float:
        """The SI value ``si`` in the unit the name gives."""
        return si / self.scale


def parse_parameter(text: str, controller=None) -> TuneParameter:
    """``NAME`` or ``NAME=LOW:HIGH`` (LOW, HIGH in the name's unit: degrees for a ``_deg``
    name) as a :class:`TuneParameter`; without a range, the field's allowed range. A
    ``controller.params[i]`` needs a range and a :class:`~scoutsim.CompiledController`
    ``controller`` with at least i + 1 parameters. ValueError naming the parameter
    otherwise."""
    name, sep, rng = text.partition("=")
    name = name.strip()
    bounds = None
    if sep:
        parts = rng.split(":")
        try:
            bounds = [float(v) for v in parts]
        except ValueError:
            bounds = None
        if bounds is None or len(bounds) != 2:
            raise ValueError(f"parameter {text!r} is not allowed: give NAME or NAME=LOW:HIGH "
                             "with two numbers")
        if not all(math.isfinite(b) for b in bounds):
            raise ValueError(f"parameter {text!r}: LOW and HIGH must be finite numbers")
        if not bounds[0] < bounds[1]:
            raise ValueError(f"parameter {text!r} is not allowed: LOW must be below HIGH")
    m = _PARAMS_NAME.match(name)
    if m:
        i = int(m.group(1))
        n = getattr(controller, "params", None)
        if n is None or getattr(controller, "controller_parameters", None) is not None:
            raise ValueError(f"parameter {name!r} is not allowed: controller.params[i] tunes "
                             "the parameter array of a CompiledController given as the "
                             "controller (Table I and pitch feedback: tune their "
                             "controller.<field> instead)")
        if i >= len(n):
            raise ValueError(f"parameter {name!r} is not allowed: the controller has "
                             f"{len(n)} parameters (params[0] .. params[{len(n) - 1}])")
        if bounds is None:
            raise ValueError(f"parameter {name!r} needs a range: {name}=LOW:HIGH")
        return TuneParameter(name, f"params[{i}]", bounds[0], bounds[1])
    scale = 1.0
    base = name[:-4] if name.endswith("_deg") else name
    _check_tuned_name(name, base)
    if name.endswith("_deg"):
        if field_dimension(base.partition(".")[2]) != "angle":
            raise ValueError(f"parameter {name!r} is not allowed: the _deg suffix takes "
                             f"degrees for an angle; {base!r} is not an angle (give it in SI "
                             "units, without the suffix)")
        scale = math.pi / 180.0
    fld = base.partition(".")[2]
    if fld in ("legs_per_virtual_leg", "sense_motor_angle"):
        raise ValueError(f"parameter {name!r} is not allowed: tuning varies continuous "
                         "parameters, and this one is a whole number or a switch")
    lo_r, hi_r, lo_closed, hi_closed = allowed_range(fld)
    if bounds is None:
        # (an upper end that is only the physical bound, far beyond any robot, is no range
        # to search)
        if lo_r is None or hi_r is None or hi_r == physical_limit(fld):
            raise ValueError(f"parameter {name!r} needs a range: its allowed values are not "
                             f"a range to search; give {name}=LOW:HIGH")
        # an open end is moved inside by one part in 1e9 of the range
        eps = 1e-9 * (hi_r - lo_r)
        lo = lo_r if lo_closed else lo_r + eps
        hi = hi_r if hi_closed else hi_r - eps
    else:
        lo, hi = bounds[0] * scale, bounds[1] * scale
        ok_lo = lo_r is None or lo > lo_r or (lo == lo_r and lo_closed)
        ok_hi = hi_r is None or hi < hi_r or (hi == hi_r and hi_closed)
        if not (ok_lo and ok_hi):
            def show(v):
                return "unbounded" if v is None else f"{v / scale:.9g}"
            raise ValueError(f"parameter {text!r} is not allowed: the range must lie within "
                             f"the field's allowed values, {'[' if lo_closed else '('}"
                             f"{show(lo_r)}, {show(hi_r)}{']' if hi_closed else ')'}")
    return TuneParameter(name, base, lo, hi, scale)


def _check_tuned_name(name: str, base: str) -> None:
    """ValueError naming ``name`` (``base``: without its _deg suffix) unless it is a field
    of RobotParameters / ControllerParameters, with the nearest name as a hint."""
    try:
        _check_name(base)
    except ValueError:
        import difflib
        names = parameter_names()
        names += [n + "_deg" for n in names if field_dimension(n.partition(".")[2]) == "angle"]
        near = difflib.get_close_matches(name, names, n=1)
        hint = f"; did you mean {near[0]!r}?" if near else ""
        raise ValueError(f"parameter {name!r} is not allowed: must be robot.<field> or "
                         "controller.<field> of RobotParameters / ControllerParameters "
                         "(a _deg suffix on an angle takes degrees), or controller.params[i] "
                         f"of a CompiledController{hint}") from None


def _apply(values: dict, robot, cparams, params):
    """The robot, controller parameters and parameter array with the tuned ``values``
    ({key: SI}) set."""
    rob = {k.partition(".")[2]: v for k, v in values.items() if k.startswith("robot.")}
    ctl = {k.partition(".")[2]: v for k, v in values.items() if k.startswith("controller.")}
    robot = dataclasses.replace(robot, **rob) if rob else robot
    cparams = dataclasses.replace(cparams, **ctl) if ctl else cparams
    if params is not None:
        params = np.array(params, dtype=float)
        for k, v in values.items():
            if k.startswith("params["):
                params[int(k[7:-1])] = v
    return robot, cparams, params


# -----------------------------------------------------------------------------------------
# one evaluation (in a worker)
# -----------------------------------------------------------------------------------------
#: a worker's compiled user controllers, by their function (compiled once per process)
_COMPILED: dict = {}


def _controller(spec, cparams, params):
    """The controller of one run: Table I parameters, a PitchFeedbackController, or the
    user's CompiledController with the parameter array ``params``."""
    kind = spec["kind"]
    if kind == "table-i":
        return cparams
    if kind == "pitch-feedback":
        from ..control.pitch_feedback import PitchFeedbackController
        return PitchFeedbackController(cparams)
    from ..control.compiled import CompiledController
    fn = spec["command"]
    ctrl = _COMPILED.get(fn)
    if ctrl is None:
        ctrl = _COMPILED[fn] = CompiledController(fn, params, spec["state"],
                                                   control_period=spec["control_period"],
                                                   name=spec["name"])
    ctrl.params = np.array(params, dtype=np.float64)
    return ctrl


def _peak_current(result) -> float | None:
    try:
        return float(max(np.max(np.abs(result.motor_current(leg))) for leg in (0, 1)))
    except (AttributeError, KeyError, ValueError, TypeError):
        return None


def _scenario_row(task, scenario, robot, cparams, params) -> dict:
    """Run one scenario and score it (module docstring)."""
    from ..simulation import simulate
    goal = task["goal"]
    duration = task["duration"]
    ctrl = _controller(task["controller"], cparams, params)
    r = simulate(robot, ctrl, scenario["initial_state"], duration, model=scenario["model"],
                 friction_coefficient=scenario["friction"], energy=goal["objective"] == "cot")
    if r.outcome == "interrupted":
        raise KeyboardInterrupt          # a cut run is not an evaluation: never recorded
    s = r.summary()
    t_end = float(r.t[-1])
    avg = float((r.x[-1] - r.x[0]) / t_end) if t_end > 0 else None
    row = {"outcome": s["outcome"], "t_end_s": t_end, "mean_speed_m_s": s["mean_speed_m_s"],
           "average_speed_m_s": avg, "n_steady_strides": s["n_steady_strides"],
           "steady_bounding": bool(s["steady_bounding"]),
           "cost_of_transport": s.get("cost_of_transport"),
           "max_belt_deflection_deg": s.get("max_belt_deflection_deg"),
           "peak_current_a": _peak_current(r), "spectral_radius": None}
    if r.outcome != "completed":
        row.update(score=10.0 * PENALTY * (2.0 - min(1.0, t_end / duration)), objective=None,
                   feasible=False, violations=r.outcome)
        return row
    v = s["mean_speed_m_s"] if s["mean_speed_m_s"] is not None else avg
    broken = []                                   # (name, relative excess)
    if not row["steady_bounding"]:
        missing = 1.0 - min(s["n_steady_strides"] or 0, MIN_STEADY_STRIDES) / MIN_STEADY_STRIDES
        broken.append(("not steady", missing if missing > 0 else 1.0))
    if goal["max_belt_deflection"] is not None and row["max_belt_deflection_deg"] is not None:
        lim = math.degrees(goal["max_belt_deflection"])
        if row["max_belt_deflection_deg"] > lim:
            broken.append(("belt deflection", row["max_belt_deflection_deg"] / lim - 1.0))
    if goal["max_current"] is not None and row["peak_current_a"] is not None:
        if row["peak_current_a"] > goal["max_current"]:
            broken.append(("current", row["peak_current_a"] / goal["max_current"] - 1.0))
    if goal["min_speed"] is not None and (v is None or v < goal["min_speed"]):
        broken.append(("speed", 1.0 if v is None else 1.0 - v / goal["min_speed"]))
    objective = None
    kind = goal["objective"]
    if kind == "speed":
        objective = None if v is None else abs(v - goal["target"])
    elif kind == "max-speed":
        objective = None if v is None else -v
    elif kind == "cot":
        objective = row["cost_of_transport"]
    elif kind == "stability":
        if row["steady_bounding"]:
            orbit = _orbit_columns(r, robot, ctrl, {"model": scenario["model"],
                                                    "friction_coefficient": scenario["friction"]})
            row["spectral_radius"] = orbit["orbit_spectral_radius"]
            if orbit["orbit_spectral_radius"] is None:
                broken.append(("no periodic orbit", 1.0))
        objective = row["spectral_radius"]
    if objective is None and not broken:
        broken.append((f"no {kind} objective", 1.0))
    if broken:
        score = PENALTY * (1 + len(broken) + sum(min(1.0, e) for _, e in broken)) \
            + (objective if objective is not None else 0.0)
    else:
        score = objective
    row.update(score=float(score), objective=objective, feasible=not broken,
               violations="; ".join(n for n, _ in broken))
    return row


def tune_task(task: dict) -> dict:
    """One evaluation: every scenario at the candidate ``task["values"]`` ({key: SI}), its
    score and the metrics of the scenario that set it (top level: picklable for worker
    processes and Dask)."""
    row = {"evaluation": task["evaluation"], "generation": task["generation"],
           "values": dict(task["values"])}
    try:
        robot, cparams, params = _apply(task["values"], task["robot"], task["cparams"],
                                        task["controller"].get("params"))
        validate_parameters(robot, cparams)
        rows = [_scenario_row(task, sc, robot, cparams, params) for sc in task["scenarios"]]
        scores = [r["score"] for r in rows]
        worst = int(np.argmax(scores))
        picked = dict(rows[worst])
        if task["goal"]["aggregate"] == "mean":
            picked["score"] = float(np.mean(scores))
            objs = [r["objective"] for r in rows]
            picked["objective"] = (float(np.mean(objs)) if all(o is not None for o in objs)
                                   else None)
            picked["feasible"] = all(r["feasible"] for r in rows)
        picked["scenario"] = worst
        picked["error"] = ""
        row.update(picked)
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # noqa: BLE001 - recorded per evaluation, the tuning goes on
        row.update({k: None for k in COLUMNS[2:]})
        row.update(score=30.0 * PENALTY, feasible=False, outcome="error",
                   violations="error", error=f"{type(exc).__name__}: {exc}")
    return row


class EvaluationNotRunError(RuntimeError):
    """An evaluation could not be run at all: its worker process died twice, or a Dask
    worker could not load the task (a different environment). The tuning stops, keeping
    every finished evaluation; the same call again goes on once the cause is fixed."""


def _error_row(task: dict, exc: BaseException) -> dict:
    """What map_tasks records for an evaluation that could not be run (not a row: the
    tuning stops on it, see :class:`EvaluationNotRunError`)."""
    return {"not_run": True, "evaluation": task["evaluation"], "values": task["values"],
            "error": f"{type(exc).__name__}: {exc}"}


# -----------------------------------------------------------------------------------------
# the result
# -----------------------------------------------------------------------------------------
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
            raise ValueError("a CompiledController's parameters go to best.json, not to a "
                             "controller file")
        tuned_robot = any(p.key.startswith("robot.") for p in self.parameters)
        return write_controller_file(path, law, self.controller_parameters,
                                     self.robot if tuned_robot else None, header=header)

    def best_dict(self) -> dict:
        """JSON-safe summary of the best evaluation."""
        return {"best_score": self.best["score"], "best_evaluation": self.best["evaluation"],
                "parameters": {p.name: self.best[p.name] for p in self.parameters},
                "parameters_si": self.best_values,
                "params": None if self.params is None else [float(x) for x in self.params],
                "metrics": {k: self.best.get(k) for k in COLUMNS},
                "n_evaluations": len(self.rows), "stopped": self.stopped,
                "settings": self.settings}


# -----------------------------------------------------------------------------------------
# the driver
# -----------------------------------------------------------------------------------------
def _controller_spec(controller):
    """(kind, base ControllerParameters, spec for the workers) of the controller given."""
    from ..control.compiled import CompiledController
    from ..control.pitch_feedback import PitchFeedbackController
    if controller is None or isinstance(controller, ControllerParameters):
        return "table-i", controller or ControllerParameters(), {"kind": "table-i"}
    if isinstance(controller, str):
        if controller not in ("table-i", "pitch-feedback"):
            raise ValueError(f"controller = {controller!r} is not allowed: table-i, "
                             "pitch-feedback, ControllerParameters, a "
                             "PitchFeedbackController or a CompiledController")
        return controller, ControllerParameters(), {"kind": controller}
    if isinstance(controller, PitchFeedbackController):
        return ("pitch-feedback", controller.controller_parameters, {"kind": "pitch-feedback"})
    if isinstance(controller, CompiledController):
        base = controller.controller_parameters or ControllerParameters()
        return "compiled", base, {"kind": "compiled", "command": controller.command_function,
                                  "params": [float(x) for x in controller.params],
                                  "state": [float(x) for x in controller.initial_state],
                                  "control_period": controller.control_period,
                                  "name": controller.name}
    raise TypeError(f"controller of type {type(controller).__name__} cannot be tuned: give "
                    "ControllerParameters, a PitchFeedbackController or a CompiledController")


def _key(blob) -> str:
    text = json.dumps(blob, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def tune(parameters, *, objective: str = "speed", target: float | None = None,
         budget: int = 200, model: str = "II", models=None, floors=None, starts=None,
         aggregate: str = "worst", duration: float = 20.0, robot=None, controller=None,
         max_belt_deflection: float | None = None, max_current: float | None = None,
         min_speed: float | None = None, seed: int = 0, sigma: float = 0.1,
         population: int | None = None, out=None, workers: int | None = None,
         scheduler=None, progress: bool = False, resume: bool = True,
         command: str = "") -> TuneResult:
    """Optimise parameters against an objective with CMA-ES (module docstring).

    Parameters
    ----------
    parameters : names or :class:`TuneParameter` s (``"controller.touchdown_angle_front_deg"``,
        ``"robot.leg_stiffness=3000:4000"``, ``"controller.params[3]=0:1"``;
        :func:`parse_parameter`).
    objective : one of :data:`OBJECTIVES`; ``target`` [m/s] the speed of ``"speed"``.
    budget : the most evaluations; the tuning runs whole generations of ``population``
        candidates (default: CMA-ES's 4 + 3 ln n for n parameters), ``budget // population``
        of them, and ends sooner if CMA-ES converges.
    model, models : the model of every run, or a list of models (scenarios).
    floors : toe friction coefficients mu [-] (scenarios; default the default floor, 1.0).
    starts : :class:`~scoutsim.InitialState` s (scenarios; default the default start).
    aggregate : "worst" or "mean" of the scenarios' scores.
    duration : simulated time of every run [s] (default 20).
    robot : base RobotParameters; controller : ControllerParameters (Table I),
        ``"pitch-feedback"``, a PitchFeedbackController or a CompiledController (its
        command function must be importable by name to run in worker processes).
    max_belt_deflection [rad], max_current [A], min_speed [m/s] : optional constraints.
    seed : the optimiser's random seed; sigma : its initial step, a fraction of each range.
    out : output directory (module docstring); None: nothing written, nothing resumed.
    workers, scheduler : as :func:`scoutsim.analysis.parallel.map_tasks` (local processes,
        or a Dask address / Client / Executor).
    progress : a progress bar on stderr with the best score so far.
    resume : go on from ``out``'s evaluations and optimiser state (default); False starts
        afresh.
    command : the command line, recorded in the manifest.

    Raises
    ------
    ValueError : a bad parameter name or range, objective or setting (named).
    MissingDependencyError : the ``cmaes`` library is not installed.
    KeyboardInterrupt : Ctrl-C; every finished evaluation is in ``out/evaluations.jsonl``.
    EvaluationNotRunError : an evaluation could not be run (its worker died twice, a Dask
        worker without scoutsim's version); the finished ones are kept likewise.
    """
    CMA = _cma_class()
    if objective not in OBJECTIVES:
        raise ValueError(f"objective = {objective!r} is not allowed: must be one of "
                         f"{', '.join(OBJECTIVES)}")
    if objective == "speed":
        if target is None or not (math.isfinite(target) and target > 0):
            raise ValueError(f"target = {target!r} is not allowed: the speed objective needs "
                             "a target speed > 0 [m/s]")
    elif target is not None:
        raise ValueError(f"target is only allowed with objective 'speed', not {objective!r}")
    if aggregate not in AGGREGATES:
        raise ValueError(f"aggregate = {aggregate!r} is not allowed: must be worst or mean")
    if not (math.isfinite(sigma) and 0 < sigma <= 1):
        raise ValueError(f"sigma = {sigma!r} is not allowed: must be in (0, 1] (a fraction "
                         "of each parameter's range)")
    for name, v in (("max_belt_deflection", max_belt_deflection),
                    ("max_current", max_current), ("min_speed", min_speed)):
        if v is not None and not (math.isfinite(v) and v > 0):
            raise ValueError(f"{name} = {v!r} is not allowed: must be a number > 0")
    kind, cparams, spec = _controller_spec(controller)
    if objective == "stability" and kind != "table-i":
        raise ValueError(f"objective 'stability' is not allowed with the {kind} controller: "
                         "the orbit tools cut the stride map where the controller logs a "
                         "back-leg lift-off, which only the Table I controller logs")
    robot = robot or RobotParameters()
    params = [p if isinstance(p, TuneParameter) else parse_parameter(p, controller)
              for p in parameters]
    if not params:
        raise ValueError("no parameter to tune: give at least one")
    seen = set()
    for p in params:
        if p.key in seen:
            raise ValueError(f"parameter {p.name!r} is given twice")
        seen.add(p.key)
    models = list(models) if models else [model]
    floors = list(floors) if floors else [DEFAULT_FRICTION_COEFFICIENT]
    starts = list(starts) if starts else [None]
    scenarios = [{"model": m, "friction": mu, "initial_state": s}
                 for m in models for mu in floors for s in starts]
    dim = len(params)
    pop = int(population) if population else 4 + int(3 * math.log(dim))
    if pop < 4:     # (CMA-ES's weights need at least two selected candidates)
        raise ValueError(f"population = {population!r} is not allowed: must be >= 4")
    if budget < pop:
        raise ValueError(f"budget = {budget} is not allowed: it must hold at least one "
                         f"generation of {pop} evaluations")
    n_gen = budget // pop
    lo = np.array([p.low for p in params])
    hi = np.array([p.high for p in params])
    base = np.array([_base_value(p, robot, cparams, spec) for p in params])
    mean0 = np.clip((base - lo) / (hi - lo), 0.0, 1.0)
    goal = {"objective": objective, "target": target, "aggregate": aggregate,
            "max_belt_deflection": max_belt_deflection, "max_current": max_current,
            "min_speed": min_speed}
    settings = {"parameters": [dataclasses.asdict(p) for p in params], "goal": goal,
                "controller": kind,
                # (a user's command function by its importable name, not its address)
                "controller_spec": {k: (f"{getattr(v, '__module__', '')}."
                                        f"{getattr(v, '__qualname__', repr(v))}"
                                        if k == "command" else v)
                                    for k, v in spec.items()},
                "scenarios": [{"model": s["model"], "friction": None if math.isinf(s["friction"])
                               else s["friction"], "initial_state": None
                               if s["initial_state"] is None
                               else dataclasses.asdict(s["initial_state"])}
                              for s in scenarios],
                "duration_s": duration, "robot": dataclasses.asdict(robot),
                "controller_parameters": dataclasses.asdict(cparams), "seed": seed,
                "sigma": sigma, "population": pop}
    skey = _key(settings)
    task_base = {"goal": goal, "duration": duration, "robot": robot, "cparams": cparams,
                 "controller": spec, "scenarios": scenarios}

    done: dict = {}
    rd = ck = state_path = None
    cma = None
    gen = 0
    if out is not None:
        out = Path(out)
        rd = RunDirectory(out, command=command, info={
            "kind": "tune", "checkpoint": EVALUATIONS, "optimizer_state": OPTIMIZER_STATE,
            "budget": budget}).open()
        ck, state_path = out / EVALUATIONS, out / OPTIMIZER_STATE
        saved = _read_state(state_path) if resume else None
        if saved is not None and saved["key"] == skey:
            cma, gen = saved["cma"], saved["generation"]
            done = read_checkpoint(ck)
        else:
            for p in (ck, state_path):
                if p.exists():
                    p.unlink()
    if cma is None:
        cma = CMA(mean=mean0, sigma=sigma, bounds=np.array([[0.0, 1.0]] * dim), seed=seed,
                  population_size=pop)
        gen = 0
        cma = _write_state(state_path, skey, 0, cma)
    n_resumed = len(done)

    bar = tqdm(total=n_gen * pop, unit="run", desc="tune", file=sys.stderr,
               disable=not progress, leave=False)
    rows_by_key: dict = {}
    stopped = "budget"
    fh = open(ck, "a") if ck is not None else None
    best = math.inf

    def record(key, row):
        nonlocal best
        rows_by_key[key] = row
        best = min(best, row["score"])
        bar.set_postfix_str(f"best {best:.4g}")
        bar.update(1)

    n_workers = workers or os.cpu_count() or 1
    own_pool = scheduler is None and n_workers > 1
    pools = contextlib.ExitStack()
    try:
        # the generations already told: their rows come from the checkpoint
        for g in range(min(gen, n_gen)):
            for i in range(pop):
                k = _key([skey, g, i])
                if k not in done:
                    raise ValueError(f"{out}/{EVALUATIONS} lacks evaluation {g * pop + i} of "
                                     f"generation {g}, which {out}/{OPTIMIZER_STATE} has "
                                     "told the optimiser: start afresh (resume off, "
                                     "--no-resume)")
                record(k, done[k])
        while gen < n_gen:
            if cma.should_stop():
                stopped = "converged"
                break
            xs = [cma.ask() for _ in range(pop)]
            keys = [_key([skey, gen, i]) for i in range(pop)]
            tasks, todo = [], []
            for i, (x, k) in enumerate(zip(xs, keys)):
                values = {p.key: float(p.low + (p.high - p.low) * u) for p, u in zip(params, x)}
                if k in done and done[k].get("values") == values:
                    record(k, done[k])
                    continue
                tasks.append(task_base | {"values": values, "evaluation": gen * pop + i,
                                          "generation": gen})
                todo.append(k)

            def on_result(j, row, todo=todo):
                if row.get("not_run"):
                    not_run.append(row)
                    return
                if fh is not None:
                    fh.write(json.dumps({"key": todo[j], "row": row}, default=_json) + "\n")
                    fh.flush()
                record(todo[j], row)

            if tasks:
                if own_pool and (scheduler is None or pool_is_broken(scheduler)):
                    # one pool for every generation (a broken one is replaced)
                    pools.close()
                    scheduler = pools.enter_context(worker_pool(min(n_workers, pop)))
                not_run: list = []
                map_tasks(tune_task, tasks, workers=workers, scheduler=scheduler,
                          progress=False, on_result=on_result, error_row=_error_row)
                if not_run:
                    r = not_run[0]
                    shown = {p.name: p.shown(r["values"][p.key]) for p in params}
                    raise EvaluationNotRunError(
                        f"{len(not_run)} evaluation(s) of generation {gen} could not be run; "
                        f"evaluation {r['evaluation']} at {shown}: {r['error']}"
                        + (f"; the finished evaluations are kept in {ck}: the same call "
                           "again goes on from them" if ck is not None else ""))
            cma.tell([(x, rows_by_key[k]["score"]) for x, k in zip(xs, keys)])
            gen += 1
            cma = _write_state(state_path, skey, gen, cma)
    except BaseException as exc:
        pools.__exit__(type(exc), exc, exc.__traceback__)     # kills the workers at once
        if rd is not None and isinstance(exc, (KeyboardInterrupt, EvaluationNotRunError)):
            rd.finish(outcome="interrupted" if isinstance(exc, KeyboardInterrupt)
                      else "evaluation not run", partial=True)
        raise
    else:
        pools.close()
    finally:
        bar.close()
        if fh is not None:
            fh.close()

    keys = [_key([skey, g, i]) for g in range(gen if stopped == "converged" else n_gen)
            for i in range(pop)]
    raw = [rows_by_key[k] for k in keys]
    rows = []
    for r in raw:
        row = {p.name: p.shown(r["values"][p.key]) for p in params}
        row.update({k: r.get(k) for k in COLUMNS})
        rows.append(row)
    b = min(range(len(rows)), key=lambda j: (rows[j]["score"], j))
    best_row = rows[b]
    best_values = {p.key: raw[b]["values"][p.key] for p in params}
    b_robot, b_cparams, b_params = _apply(best_values, robot, cparams, spec.get("params"))
    res = TuneResult(rows=rows, parameters=params, best=best_row, best_values=best_values,
                     robot=b_robot, controller_parameters=b_cparams, params=b_params,
                     settings=_json_safe(settings) | {"budget": budget,
                                                      "n_resumed": n_resumed},
                     stopped=stopped)
    if rd is not None:
        _write_outputs(res, rd, command)
    return res


def _base_value(p: TuneParameter, robot, cparams, spec) -> float:
    if p.key.startswith("params["):
        return float(spec["params"][int(p.key[7:-1])])
    sec, _, fld = p.key.partition(".")
    return float(getattr(robot if sec == "robot" else cparams, fld))


def _write_outputs(res: TuneResult, rd: RunDirectory, command: str) -> None:
    rd.write("tune.csv", res.to_csv)
    try:
        rd.write("tune.parquet", res.to_parquet)
    except RuntimeError:
        pass
    rd.write("best.json", lambda p: p.write_text(
        json.dumps(_json_safe(res.best_dict()), indent=2, default=_json) + "\n"))
    if res.settings["controller"] in ("table-i", "pitch-feedback"):
        b = res.best
        header = (f"scoutsim controller file: the best of {len(res.rows)} evaluations of "
                  f"`{command or 'scoutsim.analysis.tune.tune'}`\n"
                  f"objective {res.settings['goal']['objective']}"
                  + (f" (target {res.settings['goal']['target']:g} m/s)"
                     if res.settings['goal']['target'] is not None else "")
                  + f": score {b['score']:.6g}, mean steady speed "
                  + (f"{b['mean_speed_m_s']:.4f} m/s" if b["mean_speed_m_s"] is not None
                     else "n/a")
                  + f", {b['n_steady_strides']} steady strides\n"
                  "run it: scoutsim run --controller THIS_FILE")
        rd.write("best.toml", lambda p: res.write_controller_file(p, header=header))
    try:
        rd.write("convergence.png", lambda p: res.plot_convergence(p))
    except ImportError:
        pass
    rd.finish(outcome="completed", partial=False)


def _read_state(path: Path):
    """The optimiser's state saved in ``path`` ({key, generation, cma}), or None."""
    if not path.exists():
        return None
    try:
        state = _thaw(path.read_bytes())
        return state if "key" in state else None
    except (OSError, pickle.UnpicklingError, EOFError, AttributeError, ImportError,
            KeyError, TypeError, ValueError):
        return None


def _freeze(key: str, generation: int, cma) -> bytes:
    """The optimiser's state as bytes. ``cmaes.CMA`` leaves its random generator out of its
    pickle (an unpickled one draws from a fresh, unseeded generator), so the generator's
    state is saved beside it."""
    return pickle.dumps({"key": key, "generation": generation, "cma": cma,
                         "rng": cma._rng.get_state()})


def _thaw(blob: bytes) -> dict:
    """:func:`_freeze` undone: the optimiser with its random generator where it was."""
    state = pickle.loads(blob)
    state["cma"]._rng.set_state(state.pop("rng"))
    return state


def _write_state(path: Path | None, key: str, generation: int, cma):
    """Save the optimiser's state to ``path`` (atomically; None: nowhere) and return the
    optimiser as read back from it, so that an uninterrupted tuning goes on from exactly
    what a resumed one reads."""
    blob = _freeze(key, generation, cma)
    if path is not None:
        atomic_write(path, lambda p: p.write_bytes(blob))
    return _thaw(blob)["cma"]


def _json_safe(v):
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, dict):
        return {k: _json_safe(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json_safe(x) for x in v]
    if isinstance(v, (np.floating, np.integer)):
        return _json_safe(v.item())
    return v


def _json(v):
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    return repr(v)
