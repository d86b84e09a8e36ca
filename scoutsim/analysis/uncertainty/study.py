"""An uncertainty study (:mod:`scoutsim.analysis.uncertainty`): its runs, metrics,
indices and outputs.

The parameters (:mod:`~scoutsim.analysis.uncertainty.uncertain_parameters`: uniform or truncated
normal, named as a sweep's points, plus ``friction_coefficient``) are sampled by the
Saltelli design of :mod:`~scoutsim.analysis.uncertainty.sobol`: ``n`` base rows of A
and of B and d matrices AB_i, ``n (d + 2)`` runs of :func:`scoutsim.simulate` in all,
each a sweep point (:func:`~scoutsim.analysis.sweep.sweep_task`: the same parameter
handling, outcomes and errors), in local processes or on a Dask cluster
(:mod:`scoutsim.analysis.parallel`). Each finished run is appended to the checkpoint
``points.jsonl`` of the output directory, so an interrupted study (Ctrl-C) run again
with the same arguments finishes the rest and gives the same result, bit for bit.

Metrics (:data:`METRICS`, named as in a run's summary.json): the steady gait's mean
speed, stride frequency, duty factors and pitch and height extremes, and ``bounds``,
1 for a run that bounds steadily to its end and 0 for one that falls, stops bounding or
has parameters that are not allowed together (outcome ``invalid_parameters``); with
``energy=True`` (``--energy``) also the cost of transport, each run then accounting for
its energy (:attr:`UncertaintyResult.metrics`).

Runs that do not bound are an outcome of the study, counted and reported (the share of
samples that do not bound), never dropped: the estimator needs a value for every row of
A, B and AB, and a gait metric has none for a run that does not bound. So the indices of
``bounds`` are computed when each outcome, bounding and not, holds for at least
:data:`MIN_BASE_OUTCOMES` of the ``2 N`` base samples (A and B: the estimator divides by
the indicator's variance over them, and a handful of failures, or failures only in the AB
rows, gives indices and bootstrap intervals that rest on single rows), and the indices of
a gait metric only when every sample bounds; otherwise the metric is listed as not
computed, with the reason (also a metric that does not vary at all). Narrow the ranges to where the robot bounds
to get the gait metrics' indices.

Outputs (``out``): ``samples.parquet`` (every run: its design block, parameters and
metrics), ``indices.csv`` (``metric, parameter, S1, S1_conf, ST, ST_conf``: one row per
computed metric and parameter; ``*_conf`` the half-width of the bootstrap interval at
:data:`~scoutsim.analysis.uncertainty.sobol.CONFIDENCE_LEVEL`), ``summary.json`` and
the checkpoint; ``manifest.json`` lists the files once they are whole.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...control.factory import ControllerSpec
from ...io.run_directory import RunDirectory, json_default
from ...io.tables import write_rows_csv, write_rows_parquet
from ...parameters import ControllerParameters, RobotParameters
from ...parameters.robot_fields import field_of, robot_value, robot_with_value
from ...simulation.initial_conditions import NAMED_STARTS
from ..strides import MIN_STEADY_STRIDES
from ..study_controller import (
    check_controller_travels,
    check_factory_reads,
    controller_ranges,
    describe_controller,
    study_controller,
)
from ..study_failures import StudyError, end_of_study, error_fields, is_error
from ..sweep import COST_OF_TRANSPORT, SUMMARY_COLUMNS, SweepBase, sweep_task
from ..sweep_checkpoint import map_with_checkpoint, open_study_directory
from ..sweep_points import point_key
from .sobol import CONFIDENCE_LEVEL, design_rows, sobol_design, sobol_from_evaluations
from .uncertain_parameters import FRICTION, UncertainParameter

__all__ = [
    "uncertainty_study",
    "check_parameters",
    "uncertainty_task",
    "UncertaintyResult",
    "METRICS",
    "GAIT_METRICS",
    "BOUNDS",
    "INDEX_COLUMNS",
]

#: the indicator metric: 1 for a run that bounds steadily, 0 for one that does not
BOUNDS = "bounds"
#: the gait metrics of a run's summary.json the study computes indices of
GAIT_METRICS = (
    "mean_speed_m_s",
    "stride_frequency_hz",
    "duty_factor_back",
    "duty_factor_front",
    "pitch_max_deg",
    "pitch_min_deg",
    "height_max_m",
    "height_min_m",
)
#: the indicator's indices need each outcome (bounds, does not) in at least this many of the
#: ``2 N`` base samples A and B (module docstring)
MIN_BASE_OUTCOMES = 5

#: every metric of the study: ``bounds``, then the gait metrics
METRICS = (BOUNDS, *GAIT_METRICS)
#: the columns of indices.csv
INDEX_COLUMNS = ("metric", "parameter", "S1", "S1_conf", "ST", "ST_conf")


def uncertainty_task(task: dict) -> dict:
    """Run one sample (top level: picklable for worker processes and Dask): a sweep point
    (:func:`~scoutsim.analysis.sweep.sweep_task`) whose floor is the sample's
    ``friction_coefficient`` where it has one."""
    point = dict(task["point"])
    mu = point.pop(FRICTION, None)
    sub = task | {"point": point}
    if mu is not None:
        sub["friction_coefficient"] = mu
    row = sweep_task(sub)
    return ({FRICTION: mu} if mu is not None else {}) | row


def _error_row(task: dict, exc: BaseException) -> dict:
    """The row of a sample whose worker failed (:func:`map_tasks`)."""
    row = dict(task["point"]) | {k: None for k in SUMMARY_COLUMNS}
    return row | error_fields(exc) | {"steady_bounding": False}


@dataclass
class UncertaintyResult:
    """An uncertainty study: its ``parameters``, one row per run (``rows``, in design
    order: A, B, AB_1 ... AB_d, each ``n`` rows), the indices of the metrics computed
    (``indices``: metric -> :class:`~scoutsim.analysis.uncertainty.sobol.SobolIndices` of one output) and the reasons of those
    not computed (``not_computed``: metric -> reason), and its ``settings``."""

    parameters: list
    rows: list
    n: int
    indices: dict = field(default_factory=dict)
    not_computed: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.parameters]

    @property
    def metrics(self) -> tuple[str, ...]:
        """The study's metrics: :data:`METRICS`, and the cost of transport when its runs
        accounted for their energy (``energy=True``)."""
        return (*METRICS, COST_OF_TRANSPORT) if self.settings.get("energy") else METRICS

    def metric(self, name: str) -> np.ndarray:
        """A metric's values over the runs: ``bounds`` 1 or 0, a gait metric its value for
        a run that bounds and NaN for one that does not (samples.parquet keeps what a run
        that does not bound steadily measured all the same)."""
        bounds = np.array([float(bool(r.get("steady_bounding"))) for r in self.rows])
        if name == BOUNDS:
            return bounds
        v = np.array([np.nan if r.get(name) is None else float(r[name]) for r in self.rows])
        return np.where(bounds == 1.0, v, np.nan)

    def share_not_bounding(self) -> float:
        """The share of the samples that do not bound."""
        return float(1.0 - self.metric(BOUNDS).mean())

    def index_rows(self) -> list[dict]:
        """indices.csv's rows (:data:`INDEX_COLUMNS`), per computed metric and parameter."""
        rows = []
        for metric, ix in self.indices.items():
            for j, name in enumerate(self.names):
                rows.append(
                    {
                        "metric": metric,
                        "parameter": name,
                        "S1": float(ix.S1[0, j]),
                        "S1_conf": float(ix.S1_conf[0, j]),
                        "ST": float(ix.ST[0, j]),
                        "ST_conf": float(ix.ST_conf[0, j]),
                    }
                )
        return rows

    def samples_columns(self) -> dict:
        """samples.parquet's columns: sample, block (A, B or AB:<parameter>), base_row,
        the parameters, the outcome, ``bounds`` and the gait metrics."""
        d, n = len(self.parameters), self.n
        blocks = ["A", "B"] + [f"AB:{name}" for name in self.names]
        cols: dict[str, list] = {
            "sample": list(range((d + 2) * n)),
            "block": [blocks[i // n] for i in range((d + 2) * n)],
            "base_row": [i % n for i in range((d + 2) * n)],
        }
        for name in self.names:
            cols[name] = [r.get(name) for r in self.rows]
        for name in ("outcome", "status", "t_end_s"):
            cols[name] = [r.get(name) for r in self.rows]
        cols[BOUNDS] = [bool(r.get("steady_bounding")) for r in self.rows]
        for name in (*self.metrics[1:], "average_speed_m_s", "n_steady_strides", "error"):
            cols[name] = [r.get(name) for r in self.rows]
        return cols

    def summary(self) -> dict:
        """summary.json: the settings, the parameters, the outcomes, the share of samples
        that do not bound, and per metric its distribution over the runs that have it and
        whether its indices were computed (else why not)."""
        outcomes: dict[str, int] = {}
        for r in self.rows:
            outcomes[r.get("outcome")] = outcomes.get(r.get("outcome"), 0) + 1
        metrics = {}
        for m in self.metrics:
            v = self.metric(m)
            v = v[np.isfinite(v)]
            metrics[m] = {
                "indices_computed": m in self.indices,
                "reason": self.not_computed.get(m, ""),
                "n_values": int(v.size),
                "mean": float(v.mean()) if v.size else None,
                "sd": float(v.std()) if v.size else None,
                "min": float(v.min()) if v.size else None,
                "max": float(v.max()) if v.size else None,
            }
        return {
            "kind": "uncertainty",
            "n_base": self.n,
            "n_parameters": len(self.parameters),
            "n_runs": len(self.rows),
            "parameters": {p.name: p.describe() for p in self.parameters},
            "confidence_level": CONFIDENCE_LEVEL,
            "estimator": "scipy.stats.sobol_indices, saltelli_2010 (S1 Saltelli 2010, ST Jansen)",
            "outcomes": dict(sorted(outcomes.items())),
            "share_not_bounding": self.share_not_bounding(),
            "metrics": metrics,
            "indices": self.index_rows(),
            "settings": self.settings,
        }

    def write(self, rd: RunDirectory) -> None:
        """samples.parquet, indices.csv and summary.json into the study's directory."""
        rows = self.index_rows()
        rd.write("indices.csv", lambda p: write_rows_csv(p, _columns(rows, INDEX_COLUMNS)))
        rd.write(
            "samples.parquet",
            lambda p: write_rows_parquet(p, self.samples_columns(), "pip install pyarrow"),
        )
        text = json.dumps(self.summary(), indent=2, default=json_default) + "\n"
        rd.write("summary.json", lambda p: p.write_text(text))


def _columns(rows: list[dict], names) -> dict:
    return {n: [r[n] for r in rows] for n in names}


def _indices(res: UncertaintyResult, seed: int) -> None:
    """Fill ``res.indices`` / ``res.not_computed`` by the rule of the module docstring."""
    d = len(res.parameters)
    n_runs = len(res.rows)
    not_bounding = int(round(res.share_not_bounding() * n_runs))
    # runs that ended without falling and without the strides to count as steady
    # bounding: the ranges need not be what keeps them out, the duration may
    short = sum(
        1
        for r in res.rows
        if not r.get("steady_bounding")
        and r.get("outcome") == "completed"
        and (r.get("n_steady_strides") or 0) < MIN_STEADY_STRIDES
    )
    for m in res.metrics:
        v = res.metric(m)
        if m != BOUNDS and not_bounding:
            why = (
                f"; {short} of them ran to the end without falling but with fewer than "
                f"{MIN_STEADY_STRIDES} steady strides: a longer duration tells whether they "
                "settle into a bound"
                if short
                else " (narrow the ranges to where the robot bounds)"
            )
            res.not_computed[m] = (
                f"{not_bounding} of {n_runs} samples do not bound steadily: a gait metric "
                f"has no value for them{why}"
            )
        elif not np.all(np.isfinite(v)):
            res.not_computed[m] = f"{int(np.sum(~np.isfinite(v)))} runs have no value"
        elif np.ptp(v) == 0.0:
            res.not_computed[m] = (
                "does not vary over the samples"
                if m != BOUNDS
                else ("every sample bounds" if v[0] else "no sample bounds")
            )
        elif m == BOUNDS and _too_few_base_outcomes(v[: 2 * res.n]):
            base = v[: 2 * res.n]
            res.not_computed[m] = (
                f"{int(np.sum(base == 0.0))} of the {base.size} base samples (A and B) do not "
                f"bound and {int(np.sum(base == 1.0))} do: each outcome needs at least "
                f"{MIN_BASE_OUTCOMES} for the indicator's indices (a larger --samples, or "
                "ranges that fail more often); the runs that do not bound are in "
                "samples.parquet"
            )
        else:
            res.indices[m] = sobol_from_evaluations(v, d, seed=seed)


def _too_few_base_outcomes(base: np.ndarray) -> bool:
    """Whether the indicator over the base samples has fewer than
    :data:`MIN_BASE_OUTCOMES` of either outcome."""
    return min(int(np.sum(base == 0.0)), int(np.sum(base == 1.0))) < MIN_BASE_OUTCOMES


def _settings(base: SweepBase, robot, controller, parameters, n: int, seed: int) -> dict:
    mu = base.friction_coefficient
    return {
        "study": "uncertainty",
        "model": base.model,
        "duration_s": base.duration,
        "friction_coefficient": None if math.isinf(mu) else mu,
        "robot": dataclasses.asdict(robot),
        "controller": describe_controller(controller),
        "initial_state": (
            None
            if base.initial_state is None
            else base.initial_state
            if isinstance(base.initial_state, str)
            else dataclasses.asdict(base.initial_state)
        ),
        "parameters": {p.name: p.describe() for p in parameters},
        "n_base": n,
        "seed": seed,
    }


def _design_points(parameters: list, n: int, seed: int) -> list[dict]:
    """The study's points, A, B, AB_1 ... AB_d (:func:`design_rows`), as {name: value}."""
    A, B = sobol_design(len(parameters), n, seed)
    u = design_rows(A, B)
    cols = [p.values(u[:, j]) for j, p in enumerate(parameters)]
    return [{p.name: float(c[i]) for p, c in zip(parameters, cols)} for i in range(len(u))]


def _warn_of_range_ends(parameters: list, points: list[dict], robot, controller) -> None:
    """Make the robot or controller parameters at each uncertain field's lowest and highest
    sampled value once, here, so a value far from a robot of this kind is warned of once
    for the study (:class:`~scoutsim.parameters.ImplausibleParameterWarning`; the runs
    themselves do not warn); a value that is not allowed is the run's business."""
    for p in parameters:
        sec, _, fld = p.field.partition(".")
        obj = robot if sec == "robot" else controller
        if p.field == FRICTION or not isinstance(obj, (RobotParameters, ControllerParameters)):
            continue
        scale = 1.0 if p.name == p.field else math.pi / 180.0
        for v in {min(q[p.name] for q in points), max(q[p.name] for q in points)}:
            try:
                if isinstance(obj, RobotParameters):
                    robot_with_value(obj, fld, v * scale, "robot.")
                else:
                    dataclasses.replace(obj, **{fld: v * scale})
            except (ValueError, TypeError):
                pass


def check_parameters(parameters: list, robot: RobotParameters | None = None) -> None:
    """ValueError (TypeError for what is not an :class:`UncertainParameter`) unless
    ``parameters`` are a study's: at least one, no field set twice (a per-leg field's one
    leg beside the field itself included), and no per-leg field named without a leg where
    ``robot``'s legs differ in it (one value would make them equal; the message names the
    two legs' names)."""
    if not parameters:
        raise ValueError("parameters is empty: give at least one uncertain parameter")
    robot = robot or RobotParameters()
    fields: dict = {}
    for p in parameters:
        if not isinstance(p, UncertainParameter):
            raise TypeError(
                f"parameters: {p!r} is not an UncertainParameter (scoutsim.analysis.uncertainty.parse_parameter)"
            )
        section, _, name = p.field.partition(".")
        same = [p.field]
        if section == "robot":
            robot_value(robot, name, "robot.")  # (both legs at once only where equal)
            field, leg = field_of(name, "robot.")
            same += (
                [f"robot.{field}"]
                if leg is not None
                else [f"robot.{field}.{other}" for other in ("back", "front")]
            )
        for f in same:
            if f in fields:
                raise ValueError(f"parameters {fields[f]!r} and {p.name!r} set the same field")
        fields[p.field] = p.name


def _check(parameters: list, base: SweepBase, controller) -> None:
    check_parameters(parameters, base.robot)
    if isinstance(base.initial_state, str) and base.initial_state not in NAMED_STARTS:
        raise ValueError(
            f"initial_state = {base.initial_state!r} is not allowed: must be a state or "
            f"one of {list(NAMED_STARTS)}"
        )
    ctl = [p.name for p in parameters if p.name.startswith("controller.")]
    if ctl and not isinstance(controller, (ControllerParameters, ControllerSpec)):
        raise ValueError(
            f"parameters {ctl} are not allowed with a controller object, which does not "
            "read ControllerParameters: give the controller as 'MODULE:FACTORY'"
        )


def uncertainty_study(
    parameters: list,
    *,
    n: int = 64,
    seed: int = 0,
    base: SweepBase | None = None,
    out=None,
    workers: int | None = None,
    scheduler=None,
    progress: bool = False,
    resume: bool = True,
    command: str = "",
    energy: bool = False,
    **base_fields,
) -> UncertaintyResult:
    """Run an uncertainty study (module docstring) and compute its Sobol' indices.

    Parameters
    ----------
    parameters : list of :class:`UncertainParameter` (:func:`~.uncertain_parameters.parse_parameter`,
        :func:`~.uncertain_parameters.read_uncertainty`).
    n : base sample size (a power of two); the study runs ``n (d + 2)`` simulations.
    seed : seeds the Sobol' sequence and the bootstrap of the intervals.
    base : the configuration every run modifies (:class:`~scoutsim.analysis.sweep.SweepBase`:
        ``model``, ``duration`` [s], ``robot``, ``controller``, ``initial_state``,
        ``friction_coefficient``); its fields may also be given as keywords.
    out : directory for points.jsonl (checkpoint), samples.parquet, indices.csv,
        summary.json and manifest.json.
    workers, scheduler, progress : as :func:`~scoutsim.analysis.sweep.sweep` (local
        processes; a Dask address, Client or Executor; a progress bar).
    resume : skip runs already in ``out/points.jsonl`` with the same settings.
    command : the command line, recorded in ``out/manifest.json``.
    energy : also account for every run's energy (``simulate(..., energy=True)``: the
        trajectory is the same bit for bit, a run costs about 1.1 times as much) and add
        the cost of transport (electrical energy / (m g distance)) to the metrics.

    Raises
    ------
    ValueError : a bad parameter or setting.
    StudyError : runs the study could not run (an error of the study, not of the robot);
        the others stay in the checkpoint and the same call again runs the failed ones.
    KeyboardInterrupt : Ctrl-C; the finished runs stay in the checkpoint.
    """
    fields_ = {f.name for f in dataclasses.fields(SweepBase)}
    if unknown := sorted(set(base_fields) - fields_):
        raise TypeError(f"uncertainty_study() got an unexpected keyword argument {unknown[0]!r}")
    base = dataclasses.replace(base or SweepBase(), **base_fields)
    parameters = list(parameters)
    robot = base.robot or RobotParameters()
    controller = study_controller(base.controller, robot) or ControllerParameters()
    _check(parameters, base, controller)
    points = _design_points(parameters, n, seed)
    if isinstance(controller, ControllerSpec):
        check_factory_reads(controller, robot, controller.params or ControllerParameters(),
                            controller_ranges(points))  # fmt: skip
    check_controller_travels(controller, workers, scheduler, len(points))
    params_of = controller.params if isinstance(controller, ControllerSpec) else controller
    _warn_of_range_ends(parameters, points, robot, params_of or ControllerParameters())
    settings = _settings(base, robot, controller, parameters, n, seed)
    if energy:  # (a study without it keeps the checkpoint keys it always had)
        settings["energy"] = True
    keys = [point_key(p, settings) for p in points]
    rd, ck, done = open_study_directory(
        out,
        command=command,
        info={"kind": "uncertainty", "n_runs": len(points)},
        resume=resume,
    )
    # the runs still to do, each point once (a point drawn twice runs once)
    first = {k: i for i, k in reversed(list(enumerate(keys)))}
    todo = sorted(i for k, i in first.items() if k not in done)
    common: dict[str, Any] = {
        "model": base.model,
        "duration": base.duration,
        "robot": robot,
        "controller": controller,
        "initial_state": base.initial_state,
        "friction_coefficient": base.friction_coefficient,
        "energy": bool(energy),
    }
    tasks = [common | {"point": points[i]} for i in todo]
    new_rows = map_with_checkpoint(
        uncertainty_task,
        tasks,
        [keys[i] for i in todo],
        ck=ck,
        rd=rd,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        desc="uncertainty",
        error_row=_error_row,
        stop_when=is_error,
    )
    for j, row in zip(todo, new_rows):
        if row is not None:
            done[keys[j]] = row
    rows = [done.get(k) for k in keys]
    res = UncertaintyResult(parameters, rows, n, settings=settings)
    try:  # (a run is missing only after an error: stop_when stopped the study there)
        end_of_study(
            [r for r in rows if r is not None],
            "raise",
            "uncertainty study",
            lambda r: str({p.name: r.get(p.name) for p in parameters}),
            n_points=len(keys),
        )
    except StudyError:
        if rd is not None:
            rd.finish(outcome="study error", partial=True)
        raise
    _indices(res, seed)
    if rd is not None:
        res.write(rd)
        rd.finish(outcome="completed", partial=False)
    return res
