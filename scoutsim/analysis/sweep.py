"""Parameter sweeps: many runs over a grid or a random sample of robot/controller values.

Each point sets some fields of :class:`~scoutsim.parameters.RobotParameters` and/or
:class:`~scoutsim.parameters.ControllerParameters` (names ``robot.<field>`` and
``controller.<field>``, SI units as in those classes), runs :func:`scoutsim.simulate`, and
records the outcome, the whole-run average speed, the steady-state gait metrics and the
cycle's regularity (steady bounding, stride-period coefficient of variation) and, with
``orbit=True``, the periodic orbit's period and Floquet stability (Newton on the sampled
stride map from the run's last strides). Points run in parallel on all local
cores by default or on a Dask cluster (``scheduler``); each finished point is appended at
once to a checkpoint file in the output directory, so an interrupted sweep resumes
without recomputing what it finished (a point cut by Ctrl-C is never recorded; a last
line cut by a kill is skipped), and a failing point is recorded with its error without
stopping the sweep (a point whose worker process dies is retried once, then recorded as
an error with the reason; see :mod:`scoutsim.analysis.parallel`). The table is written as
Parquet (``pyarrow``) and CSV.

Names and units: a point's names are ``robot.<field>`` / ``controller.<field>`` in SI
units, or ``<name>_deg`` in degrees for an angle field (:mod:`scoutsim.analysis.sweep_points`).

Controllers: the base controller is ControllerParameters (Table I; ``controller.<field>``
points set its fields), a PitchFeedbackController (``controller.<field>`` points set the
fields of its ControllerParameters, torso-feedback gains included), a user's controller
object (a CompiledController, a Python controller; only ``robot.<field>`` points), or a user's factory, ``"MODULE:FACTORY"`` or
a :class:`~scoutsim.control.factory.ControllerSpec`, called in the worker with the point's
robot and controller parameters (``controller.<field>`` points set the parameters the
factory gets). It is checked before the first point runs
(:mod:`scoutsim.analysis.study_controller`). Each row's ``status`` says whether the point
ran (ok), is not allowed (invalid: outcome ``invalid_parameters``) or could not be run by
the study (error: :mod:`scoutsim.analysis.study_failures`, ``on_error``).

The parts have their own modules: :mod:`~scoutsim.analysis.sweep_points` (the names a
sweep varies, grid and random points), :mod:`~scoutsim.analysis.sweep_orbit` (a point's
periodic orbit, ``orbit=True``) and :mod:`~scoutsim.analysis.sweep_checkpoint` (the
checkpoint file a sweep resumes from). This module runs the points and holds the table,
and re-exports their public names.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..control.factory import ControllerSpec
from ..control.pitch_feedback import PitchFeedbackController
from ..io.tables import write_rows_csv, write_rows_parquet
from ..parameters import (
    DEFAULT_FRICTION_COEFFICIENT,
    ControllerParameters,
    RobotParameters,
    plausibility_warnings_off,
    validate_parameters,
)
from ..parameters.robot_fields import field_of, robot_value, robot_with_values
from ..simulation.initial_conditions import NAMED_STARTS
from ..state import HybridState, InitialState
from .study_controller import (
    build_controller,
    check_controller_travels,
    check_factory_reads,
    controller_ranges,
    describe_controller,
    study_controller,
)
from .study_failures import (
    StudyError,
    check_on_error,
    end_of_study,
    error_fields,
    is_error,
    run_failure,
)
from .sweep_checkpoint import (
    CHECKPOINT,
    map_with_checkpoint,
    open_study_directory,
    read_checkpoint,
)
from .sweep_orbit import ORBIT_COLUMNS, ORBIT_RTOL, ORBIT_TOL, orbit_columns
from .sweep_points import (
    DEG,
    axis_label,
    check_name,
    grid_points,
    parameter_names,
    point_key,
    random_points,
    si_name,
)

__all__ = [
    "sweep",
    "sweep_task",
    "SweepBase",
    "SweepResult",
    "SUMMARY_COLUMNS",
    "ORBIT_COLUMNS",
    "ORBIT_RTOL",
    "ORBIT_TOL",
    "orbit_columns",
    "CHECKPOINT",
    "read_checkpoint",
    "DEG",
    "parameter_names",
    "si_name",
    "axis_label",
    "grid_points",
    "random_points",
    "point_key",
]

#: a run's cost of transport (summary.json), in a row of a task run with ``energy``
COST_OF_TRANSPORT = "cost_of_transport"
SUMMARY_COLUMNS = (
    "outcome",
    "t_end_s",
    "average_speed_m_s",
    "mean_speed_m_s",
    "stride_frequency_hz",
    "duty_factor_back",
    "duty_factor_front",
    "pitch_max_deg",
    "pitch_min_deg",
    "height_max_m",
    "height_min_m",
    "n_steady_strides",
    "stride_period_cv",
    "steady_bounding",
    "max_friction_ratio",
    "status",
    "error",
)


def _point_parameters(task: dict):
    """The robot and controller parameters of a point ({name: value as named}), SI;
    ControllerParameters None for a controller object."""
    rob: dict[str, Any] = {}
    ctl: dict[str, Any] = {}
    for name, v in task["point"].items():
        base, scale = si_name(name)
        sec, _, fld = base.partition(".")
        (rob if sec == "robot" else ctl)[fld] = v * scale
    if "legs_per_virtual_leg" in rob:
        rob["legs_per_virtual_leg"] = int(rob["legs_per_virtual_leg"])
    robot = robot_with_values(task["robot"], rob, "robot.")
    c = task["controller"]
    if isinstance(c, ControllerParameters):
        return robot, dataclasses.replace(c, **ctl)
    if isinstance(c, ControllerSpec):
        return robot, dataclasses.replace(c.params or ControllerParameters(), **ctl)
    if isinstance(c, PitchFeedbackController):  # (it runs on ControllerParameters)
        law = c.controller_parameters or ControllerParameters()
        return robot, dataclasses.replace(law, **ctl)
    return robot, None


def sweep_task(task: dict) -> dict:
    """Run one point (top level: picklable for worker processes and Dask). Its row's
    ``status``: ok (a run: its outcome), invalid (``invalid_parameters``: the point's
    parameters are not allowed) or error (the study could not run it). Values far from a
    robot of this kind were warned of once, by :func:`sweep`, not here per point."""
    with plausibility_warnings_off():
        return _sweep_point(task)


def _warn_of_range_ends(points: list[dict], names: list[str], base: dict) -> None:
    """Make the parameters of the points at each swept parameter's lowest and highest
    value once, here, so a value far from a robot of this kind is warned of once for the
    sweep (:class:`~scoutsim.parameters.ImplausibleParameterWarning`); points that are not
    allowed are the points' own business."""
    for name in names:
        held = [p for p in points if name in p]
        for p in {
            id(q): q for q in (min(held, key=lambda q: q[name]), max(held, key=lambda q: q[name]))
        }.values():
            try:
                _point_parameters(base | {"point": p})
            except (ValueError, TypeError):
                pass


def _sweep_point(task: dict) -> dict:
    from ..simulation.simulator import simulate

    row = dict(task["point"])
    row.update({k: None for k in SUMMARY_COLUMNS})
    if task.get("orbit"):
        row.update({k: None for k in ORBIT_COLUMNS})
    row["steady_bounding"] = False
    c = task["controller"]
    try:
        robot, cparams = _point_parameters(task)
        if isinstance(c, (ControllerSpec, PitchFeedbackController)):
            # (the factory, or the pitch-feedback law, gets parameters that are allowed)
            validate_parameters(robot, cparams)
    except ValueError as exc:
        row.update(status="invalid", outcome="invalid_parameters", error=str(exc))
        return row
    try:
        if isinstance(c, ControllerParameters):
            ctrl = cparams
        elif isinstance(c, PitchFeedbackController):
            ctrl = PitchFeedbackController(cparams)
        else:
            ctrl = build_controller(c, robot, cparams)
    except Exception as exc:  # noqa: BLE001 - an error of the study, reported per point
        row.update(error_fields(exc))
        return row
    try:
        r = simulate(
            robot,
            ctrl,
            task["initial_state"],
            task["duration"],
            model=task["model"],
            friction_coefficient=task["friction_coefficient"],
            energy=bool(task.get("energy", False)),
        )
    except Exception as exc:  # noqa: BLE001 - classified and reported per point
        row.update(run_failure(exc, "invalid_parameters"))
        return row
    if r.outcome == "interrupted":
        # Ctrl-C reached the run (simulate() returns the data so far): the point is
        # not done and must not be recorded as if it were; the sweep stops
        raise KeyboardInterrupt
    try:
        s = r.summary()
        row.update({k: s.get(k) for k in SUMMARY_COLUMNS if k in s})
        # whole-run average speed: defined even for runs too short for steady strides
        row["average_speed_m_s"] = float((r.x[-1] - r.x[0]) / r.t[-1]) if r.t[-1] > 0 else None
        row["steady_bounding"] = bool(s.get("steady_bounding"))
        if task.get("energy"):  # (the run accounted for its energy: what the gait costs)
            row[COST_OF_TRANSPORT] = s.get(COST_OF_TRANSPORT)
        if task.get("orbit"):
            if row["steady_bounding"]:
                row.update(orbit_columns(r, robot, ctrl, task))
            else:
                row.update(orbit_status="no orbit: not steady bounding")
        row.update(status="ok", error="")
    except Exception as exc:  # noqa: BLE001 - an error of the study, reported per point
        row.update({k: None for k in SUMMARY_COLUMNS})
        row.update(error_fields(exc), steady_bounding=False)
    return row


@dataclass
class SweepResult:
    """The sweep table: one row per point, in point order."""

    rows: list
    parameters: list
    settings: dict = field(default_factory=dict)

    def column(self, name) -> np.ndarray:
        return np.array(
            [np.nan if r.get(name) is None else r.get(name) for r in self.rows],
            dtype=float if name not in ("outcome", "status", "error") else object,
        )

    def errors(self) -> list:
        """The rows of the points the study could not run (status "error")."""
        return [r for r in self.rows if is_error(r)]

    @staticmethod
    def axis_label(name: str) -> tuple[float, str]:
        """How a plot shows the column ``name``: :func:`axis_label`."""
        return axis_label(name)

    def columns(self) -> dict:
        names = list(self.parameters) + [c for c in SUMMARY_COLUMNS]
        if self.settings.get("orbit"):
            names += list(ORBIT_COLUMNS)
        return {n: [r.get(n) for r in self.rows] for n in names}

    def to_csv(self, path):
        write_rows_csv(path, self.columns())

    def to_parquet(self, path):
        write_rows_parquet(
            path, self.columns(), "pip install pyarrow (or pip install 'scoutsim[sweep]')"
        )

    def plot_map(self, x: str, y: str, value: str = "mean_speed_m_s", path=None):
        """Map of ``value`` over two swept parameters (grid sweeps); a convenience for
        :func:`scoutsim.presentation.plots.plot_sweep_map` (needs Matplotlib)."""
        from ..presentation.plots import plot_sweep_map

        return plot_sweep_map(self, x, y, value, path)


@dataclass(frozen=True)
class SweepBase:
    """The base configuration every point of a sweep modifies (``simulate`` arguments):
    ``model``, ``duration`` [s], ``robot``, ``controller``, ``initial_state`` (a state, or
    a start by name, "flight" or "standing", as :func:`~scoutsim.simulate` takes it) and
    ``friction_coefficient`` (the package's default floor, Coulomb mu = 1.0)."""

    model: str = "II"
    duration: float = 10.0
    robot: RobotParameters | None = None
    controller: object = None
    initial_state: InitialState | HybridState | str | None = None
    friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT


def sweep(
    points: list[dict],
    *,
    base: SweepBase | None = None,
    out=None,
    workers: int | None = None,
    scheduler=None,
    progress: bool = False,
    resume: bool = True,
    orbit: bool = False,
    command: str = "",
    on_error: str = "raise",
    **base_fields,
) -> SweepResult:
    """Run every point (see module docstring).

    Parameters
    ----------
    points : list of {name: value} (see :func:`grid_points`, :func:`random_points`);
        names ``robot.<field>`` / ``controller.<field>`` in SI, ``..._deg`` for an angle
        in degrees.
    base : :class:`SweepBase`, the configuration every point modifies; its fields
        (``model``, ``duration``, ``robot``, ``controller``, ``initial_state``,
        ``friction_coefficient``) may also be given as keywords, which override the
        bundle's. ``controller``: ControllerParameters (default Table I), a controller
        object, or ``"MODULE:FACTORY"`` / a ControllerSpec (module docstring).
    out : directory for ``points.jsonl`` (checkpoint), ``sweep.parquet``, ``sweep.csv`` and
        ``manifest.json`` ("complete" once the tables are written whole; "partial", with no
        table, after an interruption: the same call again resumes).
    workers : local processes (default all cores; a pool started for this call).
    scheduler : Dask address or Client, or a ``concurrent.futures.Executor`` to reuse
        (worker start-up is paid once; see :mod:`scoutsim.analysis.parallel`).
    resume : skip points already in ``out/points.jsonl`` with the same settings.
    command : the command line that asked for the sweep, recorded in ``out/manifest.json``.
    orbit : also find each steadily bounding point's periodic orbit by Newton from its run's
        last strides and record its period, spectral radius, stability and residual
        (:data:`ORBIT_COLUMNS`; a few seconds per point).
    on_error : "raise" (stop at the first point the study could not run and raise
        :class:`~scoutsim.analysis.study_failures.StudyError`; the points that arrived
        stay in the checkpoint, the failed ones run again on resuming) or "record" (a row
        with status "error", counted in ``settings["n_errors"]``; a RuntimeWarning).

    Raises
    ------
    ValueError : a bad name or setting; ``controller.<field>`` points with a controller
        object (which does not read ControllerParameters: give a factory instead).
    NotSendableError : the controller cannot be sent to the workers (before any point).
    FactoryError : a ``"MODULE:FACTORY"`` that cannot be imported (before any point).
    StudyError : a point could not be run (``on_error="raise"``).
    """
    fields = {f.name for f in dataclasses.fields(SweepBase)}
    if unknown := sorted(set(base_fields) - fields):
        raise TypeError(f"sweep() got an unexpected keyword argument {unknown[0]!r}")
    base = dataclasses.replace(base or SweepBase(), **base_fields)
    model, duration, robot, controller, initial_state, friction_coefficient = (
        base.model,
        base.duration,
        base.robot,
        base.controller,
        base.initial_state,
        base.friction_coefficient,
    )
    check_on_error(on_error)
    if isinstance(initial_state, str) and initial_state not in NAMED_STARTS:
        raise ValueError(
            f"initial_state = {initial_state!r} is not allowed: must be a state "
            f"or one of {list(NAMED_STARTS)}"
        )
    if not points:
        raise ValueError("points is empty: nothing to sweep")
    names = list(dict.fromkeys(k for p in points for k in p))
    fields_set: dict = {}
    for n in names:
        check_name(n)
        base_name = si_name(n)[0]
        if base_name in fields_set:
            raise ValueError(
                f"sweep parameters {fields_set[base_name]!r} and {n!r} set the same field: give one"
            )
        fields_set[base_name] = n
    robot = robot or RobotParameters()
    for n in names:
        sec, _, fld = si_name(n)[0].partition(".")
        if sec == "robot":
            robot_value(robot, fld, "robot.")  # (both legs at once only where they are equal)
            field, leg = field_of(fld)
            if leg is not None and f"robot.{field}" in fields_set:
                raise ValueError(
                    f"sweep parameters 'robot.{field}' and {n!r} set the same field: give one"
                )
    controller = study_controller(controller, robot) or ControllerParameters()
    if isinstance(controller, str):
        raise ValueError(
            f"controller = {controller!r} is not allowed: give "
            "ControllerParameters, a controller object, or MODULE:FACTORY"
        )
    if not isinstance(
        controller, (ControllerParameters, ControllerSpec, PitchFeedbackController)
    ) and any(n.startswith("controller.") for n in names):
        raise ValueError(
            f"sweep parameters {[n for n in names if n.startswith('controller.')]}"
            " are not allowed with a controller object, which does not read "
            "ControllerParameters: give the controller as 'MODULE:FACTORY' (a "
            "factory make(robot, params) gets each point's parameters), or "
            "sweep robot.<field> only"
        )
    if isinstance(controller, ControllerSpec):
        check_factory_reads(controller, robot, controller.params or ControllerParameters(),
                            controller_ranges(points))  # fmt: skip
    check_controller_travels(controller, workers, scheduler, len(points))
    settings = {
        "model": model,
        "duration_s": duration,
        "friction_coefficient": None if math.isinf(friction_coefficient) else friction_coefficient,
        "robot": dataclasses.asdict(robot),
        "controller": describe_controller(controller),
        "initial_state": (
            None
            if initial_state is None
            else initial_state
            if isinstance(initial_state, str)
            else dataclasses.asdict(initial_state)
        ),
        "orbit": bool(orbit),
    }
    keys = [point_key(p, settings) for p in points]
    rd, ck, done = open_study_directory(
        out, command=command, info={"kind": "sweep", "n_points": len(points)}, resume=resume
    )
    todo = [i for i, k in enumerate(keys) if k not in done]
    tasks: list[dict[str, Any]] = [
        {
            "point": points[i],
            "model": model,
            "duration": duration,
            "robot": robot,
            "controller": controller,
            "initial_state": initial_state,
            "friction_coefficient": friction_coefficient,
            "orbit": orbit,
        }
        for i in todo
    ]
    if tasks:
        _warn_of_range_ends([t["point"] for t in tasks], names, tasks[0])
    new_rows = map_with_checkpoint(
        sweep_task,
        tasks,
        [keys[i] for i in todo],
        ck=ck,
        rd=rd,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        desc="sweep",
        error_row=_error_row,
        stop_when=is_error if on_error == "raise" else None,
    )
    for j, row in zip(todo, new_rows):
        if row is not None:
            done[keys[j]] = row
    rows = [done[k] for k in keys if k in done]
    res = SweepResult(
        rows=rows,
        parameters=names,
        settings=settings
        | {
            "n_points": len(points),
            "n_resumed": len(points) - len(todo),
            "n_errors": sum(is_error(r) for r in rows),
        },
    )
    try:
        end_of_study(
            rows,
            on_error,
            "sweep",
            lambda r: str({n: r.get(n) for n in names}),
            result=res,
            n_points=len(keys),
        )
    except StudyError:
        if rd is not None:  # no table: the same call again runs the failed points
            rd.finish(outcome="study error", partial=True)
        raise
    if rd is not None:
        rd.write("sweep.csv", res.to_csv)
        try:
            rd.write("sweep.parquet", res.to_parquet)
        except RuntimeError:
            pass
        rd.finish(outcome="completed", partial=False)
    return res


def _error_row(task: dict, exc: BaseException) -> dict:
    """The row of a point whose task failed in its worker process (it could not be loaded
    there, or the worker died twice, see :func:`scoutsim.analysis.parallel.map_tasks`);
    ``sweep_task`` records its own errors."""
    row = dict(task["point"])
    row.update({k: None for k in SUMMARY_COLUMNS})
    if task.get("orbit"):
        row.update({k: None for k in ORBIT_COLUMNS})
    row.update(error_fields(exc), steady_bounding=False)
    return row
