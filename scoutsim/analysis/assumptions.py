"""The paper's question asked of a controller: which modelling assumptions change its bound.

Poulakakis, Smith & Buehler (ICRA 2004) conclude that "without the actuator saturation
taken into account the models do not converge to cyclic motion" and that "the assumption
of rigid torque transmission is not valid and significantly affects the accuracy of the
results" (Sec. V). :func:`assumption_study` runs one controller on every case of
:mod:`scoutsim.analysis.assumption_cases` (a ladder of models, and each effect of the
richest model switched off one at a time) and measures, per case,

* the gait metrics of a run from the default start (``InitialState()``) with the energy
  accounting: the summary's ``mean_speed_m_s``, ``stride_frequency_hz``,
  ``duty_factor_back`` / ``_front``, ``pitch_max_deg`` / ``pitch_min_deg``,
  ``height_max_m`` / ``height_min_m`` (over the steady strides) and
  ``cost_of_transport``;
* the basin fraction: the share of a small grid of starts that reaches steady bounding
  (:func:`scoutsim.analysis.basin.basin_task` on each start, as ``scoutsim basin`` runs
  them),

each as a percent difference from the reference case, 100 (x - x_ref) / |x_ref|, in the
style of the paper's Fig. 12. A case whose run does not bound steadily (it fell, or
reached no steady bounding: :meth:`~scoutsim.analysis.gait.GaitMetrics.is_steady_bounding`)
has no gait metrics: its row says what the run did instead (``verdict``), never a NaN
percent. Every run goes through :func:`~scoutsim.analysis.parallel.map_tasks` (local
processes or Dask); the rows are in case order and do not depend on the workers.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, field

from ..io.run_directory import json_safe
from ..parameters import plausibility_warnings_off
from .assumption_cases import RICHEST, RUNG_NAMES, SWITCH_NAMES, AssumptionCase, assumption_cases
from .basin import basin_task, basin_tasks
from .parallel import map_tasks
from .study_controller import (
    build_controller,
    check_controller_travels,
    controller_label,
    study_controller,
)
from .study_failures import error_fields, run_failure

__all__ = [
    "METRICS",
    "FIG12_TOLERANCE_PERCENT",
    "AssumptionResult",
    "assumption_study",
    "basin_grid",
]

#: the metrics compared, with their units (the summary's names; ``basin_fraction`` [-])
METRICS = {
    "mean_speed_m_s": "m/s",
    "stride_frequency_hz": "Hz",
    "duty_factor_back": "-",
    "duty_factor_front": "-",
    "pitch_max_deg": "deg",
    "pitch_min_deg": "deg",
    "height_max_m": "m",
    "height_min_m": "m",
    "cost_of_transport": "-",
    "basin_fraction": "-",
}
#: the paper's Fig. 12 tolerance [%]: Model II's mean errors against experiment "all are
#: smaller than 25%" (Sec. IV.C)
FIG12_TOLERANCE_PERCENT = 25.0


def basin_grid(n_speeds: int = 2, n_pitch_rates: int = 1) -> dict:
    """A small grid of starts: ``n_speeds`` forward speeds evenly over 0.8-1.6 m/s (1.2
    m/s when 1) x ``n_pitch_rates`` pitch rates evenly over 50-200 deg/s (150 deg/s when
    1; nose rising: the starts from which the Table I controller can bound), height
    0.33 m; the keywords ``speeds`` [m/s], ``pitch_rates`` [rad/s], ``heights`` [m].
    ``n_speeds`` = 0 or ``n_pitch_rates`` = 0: no basin."""

    def spread(n, lo, hi, one):
        return (one,) if n == 1 else tuple(lo + (hi - lo) * k / (n - 1) for k in range(n))

    if n_speeds < 0 or n_pitch_rates < 0:
        raise ValueError(f"basin grid {n_speeds} x {n_pitch_rates}: counts must be >= 0")
    if n_speeds == 0 or n_pitch_rates == 0:
        return {"speeds": (), "pitch_rates": (), "heights": ()}
    return {
        "speeds": spread(n_speeds, 0.8, 1.6, 1.2),
        "pitch_rates": tuple(math.radians(w) for w in spread(n_pitch_rates, 50.0, 200.0, 150.0)),
        "heights": (0.33,),
    }


def metrics_task(task: dict) -> dict:
    """One case's run from the default start with the energy accounting (top level, so
    worker processes can import it): the summary's metrics and what the run did."""
    from ..simulation.simulator import simulate

    row = {"case": task["case"]}
    try:
        controller = build_controller(task["controller"], task["robot"])
        result = simulate(
            task["robot"],
            controller,
            None,
            task["duration"],
            model=task["model"],
            friction_coefficient=task["friction"],
            energy=True,
        )
    except Exception as exc:  # noqa: BLE001 - reported in the case's row
        return row | run_failure(exc, "invalid") | {"steady_bounding": False}
    if result.outcome == "interrupted":
        raise KeyboardInterrupt
    s = result.summary()
    row.update(
        status="ok",
        outcome=result.outcome,
        steady_bounding=bool(s["steady_bounding"]),
        behaviour=s["behaviour"],
        behaviour_kind=s["behaviour_kind"],
        energy_relative_residual=s.get("energy_relative_residual"),
        **{k: s.get(k) for k in METRICS if k != "basin_fraction"},
    )
    return row


def assumption_task(task: dict) -> dict:
    """A task of the study: a case's metrics run or one start of its basin (the switches'
    deliberate limits, e.g. 1e4 V, warn of nothing: :mod:`.assumption_cases`)."""
    with plausibility_warnings_off():
        if task["kind"] == "basin":
            return basin_task(task) | {"case": task["case"]}
        return metrics_task(task)


def _error_row(task: dict, exc: Exception) -> dict:
    return {"case": task["case"], "steady_bounding": False} | error_fields(exc)


def _percent(x, ref):
    if x is None or ref is None or not math.isfinite(x) or not math.isfinite(ref) or ref == 0.0:
        return None
    return 100.0 * (x - ref) / abs(ref)


def _verdict(run: dict) -> str:
    """What a case's run did, in a few words ("bounds" when it bounds steadily)."""
    if run.get("status") == "error":
        return f"error: {run.get('error', '')}"
    if run.get("steady_bounding"):
        return "bounds"
    if run.get("outcome") == "fell":
        return "fell"
    kind = run.get("behaviour_kind") or run.get("outcome") or "no run"
    return f"no steady bounding ({kind})"


@dataclass
class AssumptionResult:
    """The table of an assumption study: one row per case (:attr:`rows`, case order) with
    its status, verdict, the metrics (:data:`METRICS`) and their percent differences from
    the reference (``pct_<metric>``; None where a case or the reference does not bound,
    or a metric is not measured); :attr:`settings` the study's settings."""

    rows: list
    reference: str
    settings: dict = field(default_factory=dict)

    def row(self, case: str) -> dict:
        """The row of case ``case`` (``"I"``, ``"-belt"``, ...)."""
        for r in self.rows:
            if r["case"] == case:
                return r
        raise KeyError(f"no case {case!r}; cases: {', '.join(r['case'] for r in self.rows)}")

    def columns(self) -> list[str]:
        """The CSV's columns: the case, its status and verdict, the metrics, their
        percents, the run's energy balance residual, what it did, and the switch's
        parameters (as JSON)."""
        base = ["case", "kind", "model", "status", "verdict", "meaning"]
        return (
            base
            + list(METRICS)
            + [f"pct_{m}" for m in METRICS]
            + ["energy_relative_residual", "behaviour", "reason", "changes"]
        )

    def to_csv(self, path) -> None:
        """Write the table to ``path`` (:meth:`columns`; empty cells where a value is
        None)."""
        cols = self.columns()
        with open(path, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=cols, extrasaction="ignore")
            w.writeheader()
            for r in self.rows:
                out = {k: ("" if r.get(k) is None else r[k]) for k in cols}
                out["changes"] = json.dumps(json_safe(r.get("changes", {})), sort_keys=True)
                w.writerow(out)

    def to_dict(self) -> dict:
        """The reference, the settings and the rows (JSON-safe with ``json_safe``)."""
        return {"reference": self.reference, "settings": self.settings, "rows": self.rows}

    def to_json(self, path) -> None:
        """Write :meth:`to_dict` to ``path`` as strict JSON."""
        with open(path, "w") as fh:
            json.dump(json_safe(self.to_dict()), fh, indent=1, allow_nan=False)

    def markdown(self) -> str:
        """The table in Markdown: per case its verdict and the percent differences from the
        reference (a case that does not bound: its verdict, no percents)."""
        names = [m for m in METRICS]
        head = "| case | verdict | " + " | ".join(names) + " |"
        lines = [head, "|" + "---|" * (len(names) + 2)]
        for r in self.rows:
            cells = []
            for m in names:
                p = r.get(f"pct_{m}")
                if r["case"] == self.reference and r.get(m) is not None:
                    cells.append(f"{r[m]:.3g}")
                else:
                    cells.append("-" if p is None else f"{p:+.1f} %")
            ref = " (reference)" if r["case"] == self.reference else ""
            lines.append(f"| {r['case']}{ref} | {r['verdict']} | " + " | ".join(cells) + " |")
        return "\n".join(lines)


def _case_tasks(case: AssumptionCase, controller, duration, friction, grid) -> list[dict]:
    common = {"case": case.name, "robot": case.robot, "controller": controller}
    metric = common | {
        "kind": "metrics",
        "model": case.model,
        "duration": duration,
        "friction": friction,
    }
    starts = basin_tasks(
        (case.model,),
        (friction,),
        grid["speeds"],
        grid["pitch_rates"],
        grid["heights"],
        duration,
        case.robot,
        controller,
    )
    return [metric] + [s | {"kind": "basin", "case": case.name} for s in starts]


def _case_row(case: AssumptionCase, results: list[dict]) -> dict:
    row: dict = {
        "case": case.name,
        "kind": case.kind,
        "model": case.model,
        "meaning": case.meaning,
        "reason": case.reason,
        "changes": {k: v for k, v in case.changes.items()},
    }
    if case.status != "run":
        return row | {"status": case.status, "verdict": case.status.replace("_", " ")}
    run, starts = results[0], results[1:]
    row |= {k: v for k, v in run.items() if k != "case"}
    row["status"] = run.get("status", "error")
    row["verdict"] = _verdict(run)
    if not run.get("steady_bounding"):
        for m in METRICS:
            if m != "basin_fraction":
                row[m] = None
    valid = [s for s in starts if s.get("status") == "ok"]
    row["basin_fraction"] = (
        sum(bool(s["steady_bounding"]) for s in valid) / len(valid) if valid else None
    )
    row["basin_starts"] = len(starts)
    return row


def assumption_study(
    controller=None,
    robot=None,
    *,
    reference: str = RICHEST,
    duration: float = 10.0,
    friction_coefficient: float = 1.0,
    basin: dict | None = None,
    switches=SWITCH_NAMES,
    rungs=RUNG_NAMES,
    workers: int | None = 1,
    scheduler=None,
    progress: bool = False,
) -> AssumptionResult:
    """Run ``controller`` on every case of the study and compare each with the reference
    (module docstring).

    Parameters
    ----------
    controller : what every case runs, as the studies take it (None / ControllerParameters:
        Table I; a controller object such as
        :class:`~scoutsim.control.PitchFeedbackController`; ``"MODULE:FACTORY"`` or a
        ControllerSpec, made for each case's robot where it runs).
    robot : RobotParameters the cases start from (default Scout II).
    reference : the case the percents are taken from (a rung's name or ``"-SWITCH"``;
        default the richest rung, ``"II+effects"``).
    duration : simulated time of every run [s] (the metrics run and each basin start).
    friction_coefficient : toe Coulomb coefficient [-] (inf: no slip).
    basin : the basin's starts, :func:`basin_grid`'s keywords (default ``basin_grid()``:
        2 speeds x 1 pitch rate); an empty grid: no basin fraction.
    switches, rungs : the switches and rungs to run (default all).
    workers : local processes (1: in this process).
    scheduler : Dask address or Client, or an Executor (overrides ``workers``).
    progress : a progress bar on stderr.
    """
    cases = assumption_cases(robot, switches=switches, rungs=rungs)
    names = [c.name for c in cases]
    if reference not in names:
        raise ValueError(f"reference {reference!r} is not a case of the study: {', '.join(names)}")
    if not duration > 0.0:
        raise ValueError(f"duration = {duration!r} s must be > 0")
    grid = basin if basin is not None else basin_grid()
    controller = study_controller(controller, robot)
    tasks: list[dict] = []
    spans = []
    for case in cases:
        mine = (
            _case_tasks(case, controller, duration, friction_coefficient, grid)
            if case.status == "run"
            else []
        )
        spans.append((len(tasks), len(tasks) + len(mine)))
        tasks += mine
    check_controller_travels(controller, workers, scheduler, len(tasks))
    results = map_tasks(
        assumption_task,
        tasks,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        desc="assumptions",
        error_row=_error_row,
    )
    rows = [_case_row(c, results[a:b]) for c, (a, b) in zip(cases, spans)]
    ref = next(r for r in rows if r["case"] == reference)
    for r in rows:
        for m in METRICS:
            r[f"pct_{m}"] = _percent(r.get(m), ref.get(m)) if r.get("status") == "ok" else None
    settings = {
        "controller": controller_label(controller) or "Table I",
        "reference": reference,
        "duration_s": duration,
        "friction_coefficient": None if math.isinf(friction_coefficient) else friction_coefficient,
        "basin_speeds_m_s": list(grid["speeds"]),
        "basin_pitch_rates_deg_s": [math.degrees(w) for w in grid["pitch_rates"]],
        "basin_heights_m": list(grid["heights"]),
        "start": "InitialState() (1.2 m/s, pitch rate 150 deg/s, 0.33 m)",
    }
    return AssumptionResult(rows=rows, reference=reference, settings=settings)
