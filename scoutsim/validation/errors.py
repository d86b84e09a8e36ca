"""The Fig. 12 error assessment: simulation models against experiment logs.

    table = compare(logs, models=("ideal", "I", "II"))
    print(table.format()); table.to_csv("errors.csv"); table.to_markdown()

Procedure (paper Sec. IV.C; docs/specification.md section 8):

1. Every experiment log is split into strides
   (:func:`~scoutsim.validation.log_strides.experiment_strides`: a log too short to hold one
   steady stride, or with no stride detected, is refused with a LogError); its steady
   strides, pooled over all runs, are the experimental strides. If no log has a steady
   stride, :func:`compare` raises LogError (the table would be empty).
2. Every model is simulated (default start, the robot/controller parameters given, toe
   friction of the default floor, at least 10 s and at least as long as the longest log) and the simulation
   is passed through the *same* measurement chain as the logs
   (:func:`~scoutsim.validation.measurement.to_log`, noise-free, with the laser geometry and
   low-pass settings of the first log), then split into strides the same way. Comparing
   filtered, sampled data with filtered, sampled data keeps the chain's own effects (15 Hz
   smoothing of the pitch peaks, 1 ms quantization of lift-off, controller-detected
   contact) out of the error.
3. **Pairing by rank**: the model's steady strides are a sample of the same kind as the
   experiment's, so per metric the experimental strides are paired with the model's by
   rank: the k-th smallest experimental value x_(k) (plotting position
   p_k = (k + 1/2)/n) with the model's empirical quantile at p_k, m(p_k) (linear
   interpolation between the model's sorted values at their own plotting positions; with
   equally many strides this is plain rank-to-rank pairing). Phase differences rule out
   stride-by-stride or time-domain pairing (paper). Per metric the percent error is
   ``e_k = 100 |m(p_k) - x_(k)| / |x_(k)|`` (relative to the experiment); the table
   reports the mean and the max of e_k over all experimental strides of all runs, and
   ``n_strides``, the number of strides compared. A model identical to the experiment
   gives exactly 0 % in every metric (the same strides, sorted alike). For a model on a
   steady limit cycle (all its strides alike) m(p_k) is its stride value, so this is the
   paper's comparison of every experimental stride with the simulated stride, and the
   errors include the experiment's stride-to-stride scatter the model does not
   reproduce. The error of the means, ``100 |mean m - mean x| / |mean x|``, is reported
   separately (:attr:`ErrorRow.percent_error_of_means`).
4. A model that falls, or has no steady strides, has no errors: its rows carry NaN
   errors, ``n_strides = 0`` and a status saying why.

Metrics (:data:`ERROR_METRICS`): stride frequency, duty factor of each virtual leg,
max/min pitch, max/min COM height.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..parameters import DEFAULT_FRICTION_COEFFICIENT
from .log_strides import LogGait, experiment_strides, log_strides
from .torso_sensors import EDGE_S

__all__ = [
    "ERROR_METRICS",
    "METRIC_LABELS",
    "ErrorRow",
    "ErrorTable",
    "ModelRun",
    "percent_errors",
    "rank_paired_model_values",
    "assess_errors",
    "simulate_model",
    "compare",
    "CSV_COLUMNS",
]

ERROR_METRICS = (
    "stride_frequency_hz",
    "duty_factor_back",
    "duty_factor_front",
    "pitch_max_deg",
    "pitch_min_deg",
    "height_max_m",
    "height_min_m",
)
METRIC_LABELS = {
    "stride_frequency_hz": "stride frequency",
    "duty_factor_back": "duty factor back",
    "duty_factor_front": "duty factor front",
    "pitch_max_deg": "pitch max",
    "pitch_min_deg": "pitch min",
    "height_max_m": "height max",
    "height_min_m": "height min",
}
#: Columns of errors.csv, in order.
CSV_COLUMNS = ("model", "metric", "mean_percent_error", "max_percent_error", "n_strides")
#: Minimum simulated time for a model [s] (the transient lasts 3-5 s).
MIN_MODEL_DURATION_S = 10.0


def rank_paired_model_values(model_values, experiment_values) -> np.ndarray:
    """The model value paired with each experimental value by rank (module docstring, 3).

    Returns an array aligned with ``experiment_values`` (not sorted): entry k is the model's
    empirical quantile at the plotting position of x_k's rank among the experiment's values.
    Ties keep their order of appearance (stable sort), so identical inputs pair exactly."""
    x = np.asarray(experiment_values, dtype=float)
    m = np.sort(np.asarray(model_values, dtype=float))
    if m.size == 0:
        raise ValueError("rank pairing needs at least one model value")
    n = x.size
    order = np.argsort(x, kind="stable")
    out = np.empty(n)
    if m.size == n:
        out[order] = m
    elif m.size == 1:
        out[:] = m[0]
    else:
        p_exp = (np.arange(n) + 0.5) / n
        p_mod = (np.arange(m.size) + 0.5) / m.size
        out[order] = np.interp(p_exp, p_mod, m)
    return out


def percent_errors(model_value, experiment_values) -> np.ndarray:
    """``100 |m_k - x_k| / |x_k|`` for every experimental value x_k (NaN where x_k = 0);
    ``model_value`` is one value or one per x_k."""
    x = np.asarray(experiment_values, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        e = 100.0 * np.abs(model_value - x) / np.abs(x)
    return np.where(x == 0, np.nan, e)


@dataclass
class ErrorRow:
    model: str
    metric: str
    mean_percent_error: float
    max_percent_error: float
    n_strides: int
    percent_error_of_means: float = math.nan
    experiment_mean: float = math.nan
    model_mean: float = math.nan
    status: str = "ok"


@dataclass
class ModelRun:
    """One model's simulation and its strides, as compared."""

    model: str
    outcome: str
    t_end: float
    gait: LogGait | None
    status: str = "ok"
    result: object = field(default=None, repr=False)


@dataclass
class ErrorTable:
    """The Fig. 12 table: one row per (model, metric)."""

    rows: list
    n_runs: int
    n_experiment_strides: int
    models: dict = field(default_factory=dict)  # model -> ModelRun
    synthetic: bool = False
    notes: list = field(default_factory=list)

    def row(self, model: str, metric: str) -> ErrorRow:
        for r in self.rows:
            if r.model == model and r.metric == metric:
                return r
        raise KeyError((model, metric))

    def to_csv(self, path) -> Path:
        """Write ``errors.csv``: columns :data:`CSV_COLUMNS`; NaN errors as empty cells."""
        path = Path(path)
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(CSV_COLUMNS)
            for r in self.rows:
                w.writerow(
                    [
                        r.model,
                        r.metric,
                        _cell(r.mean_percent_error),
                        _cell(r.max_percent_error),
                        r.n_strides,
                    ]
                )
        return path

    def to_detail_csv(self, path) -> Path:
        """Write the rows with all fields (means, error of the means, status)."""
        path = Path(path)
        names = list(ErrorRow.__dataclass_fields__)
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(names)
            for r in self.rows:
                w.writerow(
                    [
                        _cell(getattr(r, n)) if isinstance(getattr(r, n), float) else getattr(r, n)
                        for n in names
                    ]
                )
        return path

    def _lines(self, sep: str, md: bool) -> list[str]:
        head = [
            "model",
            "metric",
            "mean % err",
            "max % err",
            "err of means %",
            "experiment",
            "model value",
            "n strides",
        ]
        body = []
        for r in self.rows:
            body.append(
                [
                    r.model,
                    METRIC_LABELS.get(r.metric, r.metric),
                    _fmt(r.mean_percent_error),
                    _fmt(r.max_percent_error),
                    _fmt(r.percent_error_of_means),
                    _fmt_val(r.experiment_mean, r.metric),
                    _fmt_val(r.model_mean, r.metric),
                    str(r.n_strides),
                ]
            )
        if md:
            out = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
            out += ["| " + " | ".join(b) + " |" for b in body]
            return out
        w = [
            max(len(h), *(len(b[i]) for b in body)) if body else len(h) for i, h in enumerate(head)
        ]
        out = [sep.join(h.ljust(w[i]) if i < 2 else h.rjust(w[i]) for i, h in enumerate(head))]
        out.append(sep.join("-" * x for x in w))
        out += [
            sep.join(c.ljust(w[i]) if i < 2 else c.rjust(w[i]) for i, c in enumerate(b))
            for b in body
        ]
        return out

    def _header(self) -> list[str]:
        lines = [
            f"Simulation vs experiment (Fig. 12): {self.n_experiment_strides} steady "
            f"experimental strides from {self.n_runs} run(s); each paired by rank with "
            "the model's steady strides."
        ]
        if self.synthetic:
            lines.append(
                "NOTE: the experiment data are SYNTHETIC (generated by scoutsim), "
                "not robot measurements."
            )
        for m, run in self.models.items():
            if run.status != "ok":
                lines.append(f"model {m}: {run.status}")
            else:
                lines.append(
                    f"model {m}: {run.gait.n_steady_strides} steady strides "
                    f"(simulated {run.t_end:g} s)"
                )
        lines += list(self.notes)
        return lines

    def format(self) -> str:
        """Plain-text table for the terminal."""
        return "\n".join(self._header() + [""] + self._lines("  ", md=False))

    def to_markdown(self) -> str:
        return "\n".join(self._header() + [""] + self._lines("", md=True)) + "\n"


def _cell(v):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return ""
    return repr(float(v)) if isinstance(v, float) else v


def _fmt(v) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.2f}"


def _fmt_val(v, metric) -> str:
    if v is None or not math.isfinite(v):
        return "-"
    return f"{v:.4f}" if metric.endswith("_m") else f"{v:.3f}"


def assess_errors(
    experiment_strides: list, model_runs: dict, n_runs: int = 1, synthetic: bool = False
) -> ErrorTable:
    """Error table from pooled experimental steady strides and each model's
    :class:`ModelRun` (see the module docstring for the pairing)."""
    rows = []
    n = len(experiment_strides)
    for model, run in model_runs.items():
        ok = run.status == "ok" and run.gait is not None and run.gait.n_steady_strides > 0
        if run.status == "ok" and not ok:
            run.status = f"no steady strides (outcome {run.outcome} at t = {run.t_end:.3f} s)"
        for metric in ERROR_METRICS:
            x = np.array([s[metric] for s in experiment_strides], dtype=float)
            xm = float(np.mean(x)) if n else math.nan
            if not ok or n == 0:
                rows.append(
                    ErrorRow(
                        model,
                        metric,
                        math.nan,
                        math.nan,
                        0,
                        experiment_mean=xm,
                        status=run.status if not ok else "no experimental strides",
                    )
                )
                continue
            m = float(run.gait.means[metric])
            model_strides = np.array([s[metric] for s in run.gait.steady_strides], dtype=float)
            model_strides = model_strides[np.isfinite(model_strides)]
            paired = (
                rank_paired_model_values(model_strides, x) if model_strides.size else np.full(n, m)
            )
            e = percent_errors(paired, x)
            good = np.isfinite(e)
            rows.append(
                ErrorRow(
                    model,
                    metric,
                    float(np.mean(e[good])) if good.any() else math.nan,
                    float(np.max(e[good])) if good.any() else math.nan,
                    int(np.count_nonzero(good)),
                    percent_error_of_means=float(percent_errors(m, [xm])[0]),
                    experiment_mean=xm,
                    model_mean=m,
                )
            )
    return ErrorTable(
        rows=rows, n_runs=n_runs, n_experiment_strides=n, models=model_runs, synthetic=synthetic
    )


def simulate_model(
    model: str,
    duration: float,
    robot=None,
    controller=None,
    friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
    initial_state=None,
    integrator=None,
    like=None,
    transient_s: float = 2.0,
    progress: bool = False,
) -> ModelRun:
    """Simulate one model and measure it like the log ``like`` (noise-free)."""
    from ..simulation.simulator import simulate
    from .measurement import to_log_like

    res = simulate(
        robot,
        controller,
        initial_state,
        duration,
        model=model,
        integrator=integrator,
        friction_coefficient=friction_coefficient,
        progress=progress,
    )
    if res.outcome == "numerical_failure":
        return ModelRun(
            model,
            res.outcome,
            float(res.t_end),
            None,
            status=f"numerical failure at t = {res.t_end:.3f} s",
            result=res,
        )
    log = to_log_like(res, like)
    gait = log_strides(log, transient_s=transient_s) if len(log.t) > 2 else None
    run = ModelRun(model, res.outcome, float(res.t_end), gait, result=res)
    if gait is None or gait.n_steady_strides == 0:
        why = "fell" if res.outcome == "fell" else res.outcome
        run.status = f"no steady strides ({why} at t = {res.t_end:.3f} s)"
    return run


def compare(
    logs,
    models=("ideal", "I", "II"),
    robot=None,
    controller=None,
    duration: float | None = None,
    friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
    transient_s: float = 2.0,
    initial_state=None,
    integrator=None,
    progress: bool = False,
) -> ErrorTable:
    """Fig. 12 error table of ``models`` against the experiment ``logs`` (module docstring).

    Parameters
    ----------
    logs : list of ExperimentLog (or one)
    models : model names for :func:`scoutsim.simulate`
    robot, controller : parameters of the simulations (defaults: Scout II, Table I)
    duration : simulated time per model [s]; default max(10 s, longest log)
    transient_s : strides starting earlier (from each record's start) are not steady

    Raises
    ------
    LogError
        For a log too short to hold one steady stride or with no stride detected
        (:func:`~scoutsim.validation.log_strides.experiment_strides`), and when no log has a
        steady stride; before any model is simulated.
    """
    from .experiment_log import ExperimentLog
    from .log_format import LogError

    if isinstance(logs, ExperimentLog):
        logs = [logs]
    logs = list(logs)
    if not logs:
        raise ValueError("compare needs at least one log")
    exp = []
    notes = []
    n_strides = []
    for lg in logs:
        g = experiment_strides(lg, transient_s=transient_s)
        if g.n_steady_strides == 0:
            notes.append(f"log {lg.name}: no steady strides ({g.n_strides} strides in all)")
        elif g.n_steady_strides < 7:
            notes.append(
                f"log {lg.name}: only {g.n_steady_strides} steady strides (the paper "
                "used >= 7 per run)"
            )
        exp.extend(g.steady_strides)
        n_strides.append(g.n_strides)
    if not exp:
        counts = "; ".join(
            f"{lg.path or lg.name}: {n} strides, none steady" for lg, n in zip(logs, n_strides)
        )
        raise LogError(
            f"no steady strides in {'the log' if len(logs) == 1 else 'any log'} ({counts}): "
            "a steady stride starts at least "
            f"{max(float(transient_s), EDGE_S):g} s after the start of its record "
            f"(transient_s), ends at least {EDGE_S:g} s before its end (EDGE_S), and belongs "
            "to the final run of strides whose periods agree within 5 % of the median of "
            "the last seven (the gait has settled); without one there is nothing to compare: "
            "give longer or steadier logs",
            logs[0].path if len(logs) == 1 else None,
        )
    if duration is None:
        duration = max([MIN_MODEL_DURATION_S] + [lg.duration for lg in logs])
    runs = {
        m: simulate_model(
            m,
            duration,
            robot,
            controller,
            friction_coefficient,
            initial_state,
            integrator,
            like=logs[0],
            transient_s=transient_s,
            progress=progress,
        )
        for m in models
    }
    table = assess_errors(exp, runs, n_runs=len(logs), synthetic=any(lg.synthetic for lg in logs))
    table.notes = notes + table.notes
    return table
