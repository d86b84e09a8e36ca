"""One evaluation of a tuning (:mod:`scoutsim.analysis.tune`): every scenario run at a
candidate and scored; what the optimiser sees.

Each scenario is a run of the candidate robot and controller (``simulate``; the energy
accounting on for the ``"cot"`` objective), scored by :func:`_scenario_row` as the tune
module's docstring states: the objective over the steady strides (``"speed"``:
``|v - target|`` [m/s]; ``"max-speed"``: ``-v`` [m/s]; ``"cot"``: cost of transport [-];
``"stability"``: spectral radius [-] of the stride map at the run's periodic orbit) if
every constraint holds, else :data:`PENALTY` times the number and relative excess of the
broken ones (belt deflection [rad, shown in deg], motor current [A], steady speed [m/s],
steady bounding), and ten times :data:`PENALTY` for a fall, less for a later one.
:func:`tune_task` (run in a worker process or on a Dask worker) scores every scenario and
keeps the worst, or the mean (``aggregate``).

Each evaluation's ``status`` (:mod:`scoutsim.analysis.study_failures`): "ok" (every
scenario ran; a controller that stopped its run, returning torques that are not finite,
scores as a fall at that time), "invalid" (the candidate's parameters are not allowed, or
a scenario's start is not: outcome ``invalid_parameters`` / ``invalid_start``, scored
``30 PENALTY``) or "error" (the tuning could not run it: the controller could not be made
or raised, the task could not be loaded; scored ``30 PENALTY`` when recorded, see
:func:`scoutsim.analysis.tune.tune`'s ``on_error``).
"""

from __future__ import annotations

import math

import numpy as np

from ..parameters import plausibility_warnings_off, validate_parameters
from .strides import MIN_STEADY_STRIDES  # steady strides a steady bound needs
from .study_controller import build_controller
from .study_failures import StudyError, error_fields, run_failure
from .sweep_orbit import orbit_columns
from .tune_parameters import apply_values

__all__ = [
    "tune_task",
    "candidate_controller",
    "OBJECTIVES",
    "AGGREGATES",
    "PENALTY",
    "MIN_STEADY_STRIDES",
    "COLUMNS",
    "EvaluationNotRunError",
]

#: what can be minimised (module docstring)
OBJECTIVES = ("speed", "max-speed", "cot", "stability")
#: how the scenarios' scores make one
AGGREGATES = ("worst", "mean")
#: score of a broken constraint (module docstring); larger than any objective value
PENALTY = 1000.0
#: the table's columns after the parameters
COLUMNS = (
    "evaluation",
    "generation",
    "phase",
    "score",
    "objective",
    "feasible",
    "violations",
    "outcome",
    "t_end_s",
    "mean_speed_m_s",
    "average_speed_m_s",
    "n_steady_strides",
    "steady_bounding",
    "cost_of_transport",
    "max_belt_deflection_deg",
    "peak_current_a",
    "spectral_radius",
    "scenario",
    "status",
    "error",
)
#: the score of an evaluation that is not allowed or could not be run
NOT_RUN_SCORE = 30.0 * PENALTY


def candidate_controller(spec, robot, cparams, params):
    """The controller of one evaluation: Table I parameters, a PitchFeedbackController,
    the user's controller object, or the one the user's factory makes for the candidate's
    ``robot`` and ``cparams``; a compiled controller's parameter array set to ``params``
    (on a copy: the user's object is not changed)."""
    kind = spec["kind"]
    if kind == "table-i":
        return cparams
    if kind == "pitch-feedback":
        from ..control.pitch_feedback import PitchFeedbackController

        return PitchFeedbackController(cparams)
    ctrl = build_controller(spec["controller"], robot, cparams)
    if params is not None and getattr(ctrl, "command_function", None) is not None:
        import copy

        ctrl = copy.copy(ctrl)  # (its compiled callback is shared, not compiled)
        ctrl.params = np.array(params, dtype=np.float64)
    return ctrl


def _peak_current(result) -> float | None:
    try:
        return float(max(np.max(np.abs(result.motor_current(leg))) for leg in (0, 1)))
    except (AttributeError, KeyError, ValueError, TypeError):
        return None


def _scenario_row(task, scenario, robot, cparams, params) -> dict:
    """Run one scenario of the candidate (``robot``, controller parameters ``cparams``, a
    compiled controller's array ``params``) and score it (module docstring)."""
    from ..control.protocol import ControllerError
    from ..simulation.simulator import simulate

    goal = task["goal"]
    duration = task["duration"]
    try:
        ctrl = candidate_controller(task["controller"], robot, cparams, params)
    except Exception as exc:  # noqa: BLE001 - an error of the tuning
        return (
            {k: None for k in COLUMNS[3:]}
            | error_fields(exc)
            | {
                "score": NOT_RUN_SCORE,
                "feasible": False,
                "steady_bounding": False,
                "violations": "error",
            }
        )
    try:
        r = simulate(
            robot,
            ctrl,
            scenario["initial_state"],
            duration,
            model=scenario["model"],
            friction_coefficient=scenario["friction"],
            energy=goal["objective"] == "cot",
        )
    except Exception as exc:  # noqa: BLE001 - classified: the controller's stop, or not
        failure = run_failure(exc, "invalid_start")
        if failure["status"] == "ok" and isinstance(exc, ControllerError):
            # the controller stopped its run: scored as a fall at that time
            return (
                {k: None for k in COLUMNS[3:]}
                | failure
                | {
                    "t_end_s": float(exc.t),
                    "steady_bounding": False,
                    "feasible": False,
                    "score": 10.0 * PENALTY * (2.0 - min(1.0, exc.t / duration)),
                    "violations": "controller_error",
                }
            )
        return (
            {k: None for k in COLUMNS[3:]}
            | failure
            | {
                "score": NOT_RUN_SCORE,
                "feasible": False,
                "steady_bounding": False,
                "violations": failure["outcome"],
            }
        )
    if r.outcome == "interrupted":
        raise KeyboardInterrupt  # a cut run is not an evaluation: never recorded
    s = r.summary()
    t_end = float(r.t[-1])
    avg = float((r.x[-1] - r.x[0]) / t_end) if t_end > 0 else None
    row = {
        "outcome": s["outcome"],
        "t_end_s": t_end,
        "mean_speed_m_s": s["mean_speed_m_s"],
        "average_speed_m_s": avg,
        "n_steady_strides": s["n_steady_strides"],
        "steady_bounding": bool(s["steady_bounding"]),
        "cost_of_transport": s.get("cost_of_transport"),
        "max_belt_deflection_deg": s.get("max_belt_deflection_deg"),
        "peak_current_a": _peak_current(r),
        "spectral_radius": None,
    }
    if r.outcome != "completed":
        row.update(
            score=10.0 * PENALTY * (2.0 - min(1.0, t_end / duration)),
            objective=None,
            feasible=False,
            violations=r.outcome,
            status="ok",
            error="",
        )
        return row
    v = s["mean_speed_m_s"] if s["mean_speed_m_s"] is not None else avg
    broken = []  # (name, relative excess)
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
            orbit = orbit_columns(
                r,
                robot,
                ctrl,
                {"model": scenario["model"], "friction_coefficient": scenario["friction"]},
            )
            row["spectral_radius"] = orbit["orbit_spectral_radius_per_stride"]
            if row["spectral_radius"] is None:
                broken.append(("no periodic orbit", 1.0))
        objective = row["spectral_radius"]
    if objective is None and not broken:
        broken.append((f"no {kind} objective", 1.0))
    if broken:
        score = PENALTY * (1 + len(broken) + sum(min(1.0, e) for _, e in broken)) + (
            objective if objective is not None else 0.0
        )
    else:
        assert objective is not None  # (a missing objective is a broken constraint)
        score = objective
    row.update(
        score=float(score),
        objective=objective,
        feasible=not broken,
        violations="; ".join(n for n, _ in broken),
        status="ok",
        error="",
    )
    return row


def _not_run(row: dict, fields: dict) -> dict:
    """``row`` as an evaluation that is not allowed or could not be run."""
    row.update({k: None for k in COLUMNS[2:]})
    row.update(
        fields,
        score=NOT_RUN_SCORE,
        feasible=False,
        steady_bounding=False,
        violations=fields["outcome"],
    )
    return row


def tune_task(task: dict) -> dict:
    """One evaluation: every scenario at the candidate ``task["values"]`` ({key: SI}), its
    score and the metrics of the scenario that set it (top level: picklable for worker
    processes and Dask). Values far from a robot of this kind are warned of once, for the
    search box's ends, by :func:`~scoutsim.analysis.tune.tune`, not per candidate."""
    with plausibility_warnings_off():
        return _evaluate(task)


def _evaluate(task: dict) -> dict:
    row = {
        "evaluation": task["evaluation"],
        "generation": task["generation"],
        "phase": task.get("phase", "cma-es"),
        "values": dict(task["values"]),
    }
    try:
        robot, cparams, params = apply_values(
            task["values"], task["robot"], task["cparams"], task["controller"].get("params")
        )
        validate_parameters(robot, cparams)
    except ValueError as exc:
        return _not_run(
            row, {"status": "invalid", "outcome": "invalid_parameters", "error": str(exc)}
        )
    try:
        rows = [_scenario_row(task, sc, robot, cparams, params) for sc in task["scenarios"]]
    except Exception as exc:  # noqa: BLE001 - an error of the tuning (scoring a run)
        return _not_run(row, error_fields(exc))
    for status in ("error", "invalid"):  # one scenario not run: the evaluation's
        bad = [r for r in rows if r.get("status", "ok") == status]
        if bad:
            return _not_run(row, {k: bad[0][k] for k in ("status", "outcome", "error")})
    scores = [r["score"] for r in rows]
    worst = int(np.argmax(scores))
    picked = dict(rows[worst])
    if task["goal"]["aggregate"] == "mean":
        picked["score"] = float(np.mean(scores))
        objs = [r["objective"] for r in rows]
        picked["objective"] = float(np.mean(objs)) if all(o is not None for o in objs) else None
        picked["feasible"] = all(r["feasible"] for r in rows)
    picked["scenario"] = worst
    row.update(picked)
    return row


class EvaluationNotRunError(StudyError):
    """An evaluation could not be run at all: its worker process died twice, or a Dask
    worker could not load the task (a different environment). The tuning stops, keeping
    every finished evaluation; the same call again goes on once the cause is fixed."""


def evaluation_error_row(task: dict, exc: BaseException) -> dict:
    """The row of an evaluation whose task failed in its worker (it died twice, or the
    task could not be loaded there): an error of the tuning (``not_run``: the tuning
    raises :class:`EvaluationNotRunError` unless it records errors)."""
    row = {
        "evaluation": task["evaluation"],
        "generation": task["generation"],
        "phase": task.get("phase", "cma-es"),
        "values": dict(task["values"]),
    }
    return _not_run(row, error_fields(exc)) | {"not_run": True}
