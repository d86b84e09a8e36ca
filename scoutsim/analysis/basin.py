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

The controller may be the user's own (a controller object, a CompiledController, or a
factory named ``"MODULE:FACTORY"`` / a ControllerSpec, made in each worker:
:mod:`scoutsim.analysis.study_controller`); it is checked before the first start runs.
A start the study could not run (the controller failed to load, or raised) is an error of
the study, never a start that did not bound (:mod:`scoutsim.analysis.study_failures`:
``status``, ``on_error``).
"""

from __future__ import annotations

import csv
import dataclasses
import itertools
import math
import os
import warnings
from dataclasses import dataclass, field

from ..parameters import DEFAULT_FRICTION_COEFFICIENT, floor_label
from .parallel import map_tasks
from .study_controller import (
    build_controller,
    check_controller_travels,
    controller_label,
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

DEFAULT_SPEEDS = (0.4, 0.6, 0.8, 1.0, 1.2, 1.4, 1.6, 1.8)  # m/s
#: initial pitch rates [rad/s]: -150 to 250 deg/s in steps of 50 deg/s
DEFAULT_PITCH_RATES = tuple(math.radians(w) for w in range(-150, 251, 50))
DEFAULT_HEIGHTS = (0.33, 0.38)  # m
#: floors of the default map: the package's default floor and the no-slip idealisation
DEFAULT_FLOORS = (DEFAULT_FRICTION_COEFFICIENT, math.inf)


BASIN_COLUMNS = (
    "model",
    "friction",
    "speed",
    "pitch_rate_deg_s",
    "height",
    "outcome",
    "steady_bounding",
    "mean_speed_m_s",
    "n_steady_strides",
    "status",
    "error",
)


def _start_of(task: dict) -> dict:
    """The identifying columns of one start's row."""
    return {k: task[k] for k in ("model", "friction", "speed", "pitch_rate_deg_s", "height")}


def pitch_rate_deg_s(pitch_rate: float) -> float:
    """A start's pitch rate [rad/s] as its row gives it [deg/s] (rounded to 1e-9 deg/s, so
    a rate given in whole degrees per second reads back as that number)."""
    return round(math.degrees(pitch_rate), 9)


def _failed(row: dict, fields: dict) -> dict:
    row.update(steady_bounding=False, mean_speed_m_s=None, n_steady_strides=0, **fields)
    return row


def basin_task(task: dict) -> dict:
    """Run one start of the basin grid (top level so that worker processes can import it).
    Its row's ``status``: ok (a run: its outcome), invalid (``invalid_start``: the start
    is not allowed) or error (the study could not run it; :mod:`.study_failures`)."""
    from ..simulation.simulator import simulate
    from ..state import InitialState

    row = _start_of(task)
    try:
        controller = build_controller(task["controller"], task["robot"])
    except Exception as exc:  # noqa: BLE001 - an error of the study, reported per start
        return _failed(row, error_fields(exc))
    try:
        init = InitialState(dx=task["speed"], dtheta=task["pitch_rate"], y=task["height"])
        result = simulate(
            task["robot"],
            controller,
            init,
            task["duration"],
            model=task["model"],
            integrator=task["integrator"],
            friction_coefficient=task["friction"],
        )
    except Exception as exc:  # noqa: BLE001 - classified and reported per start
        return _failed(row, run_failure(exc, "invalid_start"))
    if result.outcome == "interrupted":
        # Ctrl-C reached the run (simulate() returns the data so far): this start is
        # not done and must not be counted as if it were; the map stops
        raise KeyboardInterrupt
    g = result.gait()
    speed = g.mean_speed_m_s
    row.update(
        outcome=result.outcome,
        steady_bounding=bool(g.is_steady_bounding()),
        mean_speed_m_s=(float(speed) if speed is not None and math.isfinite(speed) else None),
        n_steady_strides=int(g.n_steady_strides),
        status="ok",
        error="",
    )
    return row


def _basin_error_row(task: dict, exc: Exception) -> dict:
    """The row of a start whose task failed in its worker (it could not be loaded there,
    or the worker died twice): an error of the study."""
    return _failed(_start_of(task), error_fields(exc))


def _where(row: dict) -> str:
    return (
        f"model {row['model']}, speed {row['speed']:g} m/s, pitch rate "
        f"{row['pitch_rate_deg_s']:g} deg/s, height {row['height']:g} m"
    )


def run_basin_tasks(
    tasks: list[dict],
    workers: int,
    progress: bool,
    scheduler=None,
    on_result=None,
    on_error: str = "record",
) -> list[dict]:
    """Run the starts (locally in parallel, or on a Dask cluster); rows in task order
    (``on_result(index, row)`` as each arrives: what an interrupted map keeps). The
    controller is checked before the first start runs (NotSendableError if it cannot go to
    the workers). ``on_error`` "record" (the default here) keeps the starts the study
    could not run as rows with status "error"; "raise" stops at the first and raises
    :class:`~scoutsim.analysis.study_failures.StudyError`."""
    check_on_error(on_error)
    if tasks:
        check_controller_travels(tasks[0]["controller"], workers, scheduler, len(tasks))
    rows = map_tasks(
        basin_task,
        tasks,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        desc="basin",
        error_row=_basin_error_row,
        on_result=on_result,
        stop_when=is_error if on_error == "raise" else None,
    )
    if on_error == "raise":
        arrived = [r for r in rows if r is not None]
        end_of_study(rows, on_error, "basin map", _where, result=BasinResult(rows=arrived))
    return rows


def _status(row: dict) -> str:
    """A row's status (a row written before statuses existed: from its outcome)."""
    status = row.get("status")
    if status:
        return status
    return {"invalid_start": "invalid", "error": "error"}.get(row["outcome"], "ok")


def basin_stats(rows: list[dict], models: list[str], floors=None) -> dict:
    """Per model (and floor, keys "MODEL @ FLOOR" when ``floors`` is given): starts,
    invalid starts, errors of the study, valid starts (the others), steady starts,
    fraction (steady / valid), outcomes, median cycle speed [m/s]."""
    per = {}
    keys = (
        [(m, None) for m in models]
        if floors is None
        else [(m, mu) for mu in floors for m in models]
    )
    for m, mu in keys:
        mine = [r for r in rows if r["model"] == m and (mu is None or r["friction"] == mu)]
        speeds = sorted(
            r["mean_speed_m_s"]
            for r in mine
            if r["steady_bounding"] and r["mean_speed_m_s"] is not None
        )
        invalid = sum(_status(r) == "invalid" for r in mine)
        errors = sum(_status(r) == "error" for r in mine)
        valid = len(mine) - invalid - errors
        steady = sum(bool(r["steady_bounding"]) for r in mine if _status(r) == "ok")
        outcomes: dict[str, int] = {}
        for r in mine:
            outcomes[r["outcome"]] = outcomes.get(r["outcome"], 0) + 1
        key = m if mu is None else f"{m} @ {floor_label(mu)}"
        per[key] = {
            "model": m,
            "friction": mu,
            "n_starts": len(mine),
            "n_invalid_start": invalid,
            "n_errors": errors,
            "n_valid": valid,
            "n_steady_bounding": steady,
            "fraction_steady_bounding": (steady / valid) if valid else None,
            "median_cycle_speed_m_s": (speeds[len(speeds) // 2] if speeds else None),
            "outcomes": outcomes,
        }
    return per


@dataclass
class BasinResult:
    """Per-start outcomes and the steady-bounding fraction per model and floor."""

    rows: list
    settings: dict = field(default_factory=dict)

    def fraction(self, model: str, friction: float | None = None):
        """Fraction of valid starts of ``model`` (on floor ``friction``; None = all floors)
        that reach steady bounding (None if there are none). Invalid starts and starts
        the study could not run (status "error") are not valid starts."""
        valid = [
            r
            for r in self.rows
            if r["model"] == model
            and _status(r) == "ok"
            and (friction is None or r["friction"] == friction)
        ]
        if not valid:
            return None
        return sum(r["steady_bounding"] for r in valid) / len(valid)

    def models(self):
        return list(dict.fromkeys(r["model"] for r in self.rows))

    def floors(self):
        return list(dict.fromkeys(r["friction"] for r in self.rows))

    def errors(self) -> list:
        """The rows of the starts the study could not run (status "error")."""
        return [r for r in self.rows if _status(r) == "error"]

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


def basin_tasks(
    models,
    floors,
    speeds,
    pitch_rates,
    heights,
    duration,
    robot=None,
    controller=None,
    integrator=None,
) -> list[dict]:
    """One task per (floor, model, speed [m/s], pitch rate [rad/s], height [m]), in that
    nesting order (a ``"MODULE:FACTORY"`` controller becomes a ControllerSpec, its factory
    imported once here: :func:`~scoutsim.analysis.study_controller.study_controller`).
    The rows give the pitch rate in deg/s (``pitch_rate_deg_s``)."""
    controller = study_controller(controller, robot)
    return [
        {
            "model": m,
            "speed": float(v),
            "pitch_rate": float(w),
            "pitch_rate_deg_s": pitch_rate_deg_s(w),
            "height": float(y),
            "robot": robot,
            "controller": controller,
            "duration": duration,
            "integrator": integrator,
            "friction": float(mu),
        }
        for mu, m, v, w, y in itertools.product(floors, models, speeds, pitch_rates, heights)
    ]


@dataclass(frozen=True)
class BasinGrid:
    """The starts of a basin map: every combination of

    Attributes
    ----------
    models : model variants ("ideal", "I", "II").
    speeds : initial forward speeds [m/s].
    pitch_rates : initial pitch rates [rad/s] (positive: nose rising); the rows give them
        in deg/s (``pitch_rate_deg_s``).
    heights : initial torso-COM heights [m].
    floors : toe Coulomb coefficients [-] (e.g. :data:`DEFAULT_FLOORS`; inf = no slip);
        None: ``friction_coefficient`` alone.
    friction_coefficient : the floor when ``floors`` is None.
    """

    models: tuple = ("ideal", "I", "II")
    speeds: tuple = DEFAULT_SPEEDS
    pitch_rates: tuple = DEFAULT_PITCH_RATES
    heights: tuple = DEFAULT_HEIGHTS
    floors: tuple | None = None
    friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT


def basin_of_attraction(
    grid: BasinGrid | None = None,
    *,
    duration: float = 10.0,
    robot=None,
    controller=None,
    integrator=None,
    workers: int | None = None,
    scheduler=None,
    progress: bool = False,
    on_error: str = "raise",
    **grid_fields,
) -> BasinResult:
    """Run the grid of starts and classify each (see module docstring).

    Parameters
    ----------
    grid : :class:`BasinGrid`, the starts; its fields (``models``, ``speeds``,
        ``pitch_rates`` [rad/s], ``heights``, ``floors``, ``friction_coefficient``) may
        also be given as keywords, which override the bundle's (``pitch_rates_deg_s``, the
        pitch rates in deg/s, is still taken, with a DeprecationWarning).
    duration : simulated time per start [s].
    robot : RobotParameters (default Scout II).
    controller : what every start runs: ControllerParameters (None: Table I), a
        controller object (e.g. :class:`~scoutsim.control.PitchFeedbackController`, a
        user's CompiledController or Python controller), or a user's factory
        ``"MODULE:FACTORY"`` / :class:`~scoutsim.control.factory.ControllerSpec`, made in
        each worker for ``robot``. With ``workers`` > 1 or a ``scheduler`` it travels to
        the workers, so it must pickle and be importable there: checked before the
        first start (:mod:`scoutsim.analysis.study_controller`).
    workers : processes (default: all cores; 1 = in this process).
    scheduler : Dask address or Client, or a ``concurrent.futures.Executor``
        (:func:`~scoutsim.analysis.parallel.map_tasks`); overrides ``workers``.
    on_error : "raise" (stop at the first start the study could not run and raise
        :class:`~scoutsim.analysis.study_failures.StudyError`) or "record" (keep it as a
        row with status "error", left out of the fractions; a RuntimeWarning).

    Raises
    ------
    NotSendableError : the controller cannot be sent to the workers (before any start).
    FactoryError : a ``"MODULE:FACTORY"`` that cannot be imported (before any start).
    StudyError : a start could not be run (``on_error="raise"``).
    """
    if "pitch_rates_deg_s" in grid_fields:
        if "pitch_rates" in grid_fields:
            raise TypeError(
                "basin_of_attraction() takes pitch_rates [rad/s] or the older "
                "pitch_rates_deg_s [deg/s], not both"
            )
        warnings.warn(
            "basin_of_attraction(pitch_rates_deg_s=...) is deprecated: give "
            "pitch_rates in rad/s (e.g. numpy.radians(rates_deg_s))",
            DeprecationWarning,
            stacklevel=2,
        )
        grid_fields["pitch_rates"] = tuple(
            math.radians(w) for w in grid_fields.pop("pitch_rates_deg_s")
        )
    fields = {f.name for f in dataclasses.fields(BasinGrid)}
    if unknown := sorted(set(grid_fields) - fields):
        raise TypeError(f"basin_of_attraction() got an unexpected keyword argument {unknown[0]!r}")
    grid = dataclasses.replace(grid or BasinGrid(), **grid_fields)
    check_on_error(on_error)
    floors = tuple(grid.floors) if grid.floors is not None else (grid.friction_coefficient,)
    tasks = basin_tasks(
        grid.models,
        floors,
        grid.speeds,
        grid.pitch_rates,
        grid.heights,
        duration,
        robot,
        controller,
        integrator,
    )
    workers = workers or os.cpu_count() or 1
    settings = {
        "models": list(grid.models),
        "speeds_m_s": list(grid.speeds),
        "pitch_rates_deg_s": [pitch_rate_deg_s(w) for w in grid.pitch_rates],
        "heights_m": list(grid.heights),
        "duration_s": duration,
        "controller": controller_label(tasks[0]["controller"]) if tasks else None,
        "floors": [None if math.isinf(mu) else mu for mu in floors],
    }
    try:
        rows = run_basin_tasks(tasks, workers, progress, scheduler=scheduler, on_error=on_error)
    except StudyError as exc:
        exc.result.settings = settings
        raise
    end_of_study(rows, on_error, "basin map", _where)
    return BasinResult(rows=rows, settings=settings | {"n_errors": sum(is_error(r) for r in rows)})
