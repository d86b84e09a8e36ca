"""Phase-normalized comparison of simulation and experiment (beyond the paper).

The paper (Sec. IV.C) rules out comparing state variables in time because simulation and
experiment drift out of phase, and falls back to per-stride gait parameters (Fig. 12). A
finer comparison that still avoids the phase problem puts every stride on its *own* phase:

1. A stride runs from one back-leg lift-off to the next (as in
   :mod:`~scoutsim.validation.log_strides`); its phase is ``s = (t - t_start) / period``, 0 at
   the first lift-off, 1 at the next.
2. Every signal of every steady stride is resampled (linear interpolation) on a common
   phase grid of ``n_phase`` points from 0 to 1 inclusive.
3. Per source (the pooled experiment logs; each model) and signal, the **mean curve** over
   its strides (and its standard deviation) is taken.
4. Per model and signal the **error curve** is ``model mean - experiment mean`` and the
   **RMS error** is its root mean square over the phase grid (in the signal's SI unit), also
   given relative to the peak-to-peak range of the experiment's mean curve (%). A model
   compared with itself gives exactly zero.

Models are measured through the same chain as the logs
(:func:`~scoutsim.validation.measurement.to_log` with the first log's laser geometry and
filter, noise-free), so both sides are what the robot would log: filtered pitch and height,
encoder angles and rates (motor-side angle for Model II), torque from current.

Signals (:data:`SIGNALS`): pitch [rad], COM height [m], back and front leg angles [rad] and
rates [rad/s], back and front hip torques [N m]. Degrees appear only in the figure.

    cmp = phase_compare(logs, {"I": result_I, "II": result_II})
    print(cmp.format()); cmp.to_csv("phase_rms.csv")
    plot_phase(cmp, "phase.png")   # scoutsim.presentation.phase_plots

``models`` values may be :class:`~scoutsim.SimulationResult`,
:class:`~scoutsim.validation.errors.ModelRun` (as in ``ErrorTable.models``),
:class:`~scoutsim.validation.ExperimentLog` (already measured) or :class:`Source`; an
:class:`~scoutsim.validation.errors.ErrorTable` stands for its ``models``.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..names import MODEL_LABELS
from .experiment_log import ExperimentLog
from .log_strides import LogGait, log_strides
from .measurement import to_log_like

__all__ = [
    "SIGNALS",
    "Source",
    "as_source",
    "as_sources",
    "resample_strides",
    "PhaseComparison",
    "phase_compare",
]

#: name -> (label, SI unit, display unit, factor SI -> display, getter(log))
SIGNALS = {
    "pitch": ("pitch", "rad", "deg", math.degrees(1.0), lambda lg: lg.pitch),
    "height": ("COM height", "m", "m", 1.0, lambda lg: lg.height),
    "phi_back": (
        "back leg angle",
        "rad",
        "deg",
        math.degrees(1.0),
        lambda lg: lg.leg_angle("back"),
    ),
    "phi_front": (
        "front leg angle",
        "rad",
        "deg",
        math.degrees(1.0),
        lambda lg: lg.leg_angle("front"),
    ),
    "dphi_back": (
        "back leg rate",
        "rad/s",
        "deg/s",
        math.degrees(1.0),
        lambda lg: lg.leg_rate("back"),
    ),
    "dphi_front": (
        "front leg rate",
        "rad/s",
        "deg/s",
        math.degrees(1.0),
        lambda lg: lg.leg_rate("front"),
    ),
    "torque_back": ("back hip torque", "N m", "N m", 1.0, lambda lg: lg.hip_torque("back")),
    "torque_front": ("front hip torque", "N m", "N m", 1.0, lambda lg: lg.hip_torque("front")),
}


def _label(name: str) -> str:
    return MODEL_LABELS.get(name, str(name))


# -----------------------------------------------------------------------------------------
# sources: a measured record and its strides
# -----------------------------------------------------------------------------------------
@dataclass
class Source:
    """One source of strides: experiment logs or a model, as measured.

    logs : list of ExperimentLog (one per run; a model has one)
    gaits : list of LogGait, one per log
    status : "ok" or why there are no steady strides (e.g. "fell at t = 1.38 s")
    result : the SimulationResult behind a model (None for experiment logs)
    """

    name: str
    logs: list
    gaits: list
    status: str = "ok"
    result: object = field(default=None, repr=False)

    @property
    def label(self) -> str:
        return _label(self.name)

    @property
    def steady(self) -> list:
        """(log, Stride) of all steady strides."""
        return [(lg, s) for lg, g in zip(self.logs, self.gaits) for s in g.steady_strides]

    @property
    def all_strides(self) -> list:
        return [(lg, s) for lg, g in zip(self.logs, self.gaits) for s in g.strides]

    @property
    def n_steady(self) -> int:
        return len(self.steady)

    @property
    def synthetic(self) -> bool:
        return any(lg.synthetic for lg in self.logs)

    def representative(self):
        """(log, stride, steady?) of the stride to show: the steady stride whose period is
        closest to the median steady period; without steady strides the last complete
        stride (not steady); None without any stride."""
        st = self.steady
        if st:
            med = float(np.median([s.period_s for _, s in st]))
            return (*min(st, key=lambda ls: abs(ls[1].period_s - med)), True)
        allst = self.all_strides
        if allst:
            return (*allst[-1], False)
        return None


def _status(name, result, gait: LogGait | None) -> str:
    if gait is not None and gait.n_steady_strides > 0:
        return "ok"
    if result is not None and result.outcome != "completed":
        return f"no steady strides ({result.outcome} at t = {result.t_end:.2f} s)"
    return "no steady strides"


def as_source(
    obj, name: str | None = None, like: ExperimentLog | None = None, transient_s: float = 2.0
) -> Source:
    """A :class:`Source` from experiment logs (an ExperimentLog or a list of them), a
    SimulationResult, a ModelRun or a Source. Simulations are measured like ``like``."""
    from ..result.simulation_result import SimulationResult
    from .errors import ModelRun

    if isinstance(obj, Source):
        return obj
    if isinstance(obj, ExperimentLog):
        obj = [obj]
    if isinstance(obj, (list, tuple)) and obj and all(isinstance(o, ExperimentLog) for o in obj):
        gaits = [log_strides(lg, transient_s=transient_s) for lg in obj]
        src = Source(name or "experiment", list(obj), gaits)
        if src.n_steady == 0:
            src.status = "no steady strides"
        return src
    if isinstance(obj, ModelRun):
        if obj.result is None:
            return Source(name or obj.model, [], [], status=obj.status)
        name = name or obj.model
        obj = obj.result
    if isinstance(obj, SimulationResult):
        name = name or (obj.provenance or {}).get("model") or "model"
        lg = to_log_like(obj, like)
        gait = log_strides(lg, transient_s=transient_s) if len(lg.t) > 2 else None
        return Source(
            name,
            [lg] if gait is not None else [],
            [gait] if gait is not None else [],
            _status(name, obj, gait),
            obj,
        )
    raise TypeError(
        f"cannot use {type(obj).__name__} as a source: give an ExperimentLog "
        "(or a list of them), a SimulationResult, a ModelRun or a Source"
    )


def as_sources(models, like: ExperimentLog | None = None, transient_s: float = 2.0) -> dict:
    """name -> Source for a dict of models, an ErrorTable (its ``models``), a list of
    SimulationResults (named by their model) or None (no models)."""
    from .errors import ErrorTable

    if models is None:
        return {}
    if isinstance(models, ErrorTable):
        models = models.models
    if not isinstance(models, dict):
        items = list(models) if isinstance(models, (list, tuple)) else [models]
        models = {}
        for i, m in enumerate(items):
            src = as_source(m, like=like, transient_s=transient_s)
            key = src.name if src.name not in models else f"{src.name} ({i + 1})"
            models[key] = src
    return {str(k): as_source(v, str(k), like, transient_s) for k, v in models.items()}


# -----------------------------------------------------------------------------------------
# resampling on the stride phase
# -----------------------------------------------------------------------------------------
def resample_strides(pairs, signal: str, n_phase: int = 101) -> np.ndarray:
    """(k, n_phase) values of ``signal`` (SI) over the phase grid ``linspace(0, 1,
    n_phase)`` of each (log, stride) pair."""
    if signal not in SIGNALS:
        raise ValueError(f"signal = {signal!r} is not allowed: must be one of {', '.join(SIGNALS)}")
    s = np.linspace(0.0, 1.0, n_phase)
    out = np.empty((len(pairs), n_phase))
    get = SIGNALS[signal][4]
    for i, (lg, st) in enumerate(pairs):
        out[i] = np.interp(
            st.t_start + s * (st.t_end - st.t_start), lg.t, np.asarray(get(lg), dtype=float)
        )
    return out


@dataclass
class PhaseComparison:
    """Result of :func:`phase_compare` (all values SI; see the module docstring).

    phase : (n,) grid 0..1
    sources : name -> Source (experiment first)
    mean, std : name -> signal -> (n,) curve (absent for sources without steady strides)
    n_strides : name -> number of steady strides used
    error : model -> signal -> (n,) model mean - experiment mean
    rms : model -> signal -> RMS of the error curve (NaN if the model has no strides)
    rms_percent : model -> signal -> rms / peak-to-peak of the experiment mean curve * 100
    status : name -> "ok" or why it has no curves
    """

    phase: np.ndarray
    sources: dict
    signals: tuple
    mean: dict
    std: dict
    n_strides: dict
    error: dict
    rms: dict
    rms_percent: dict
    status: dict
    experiment: str = "experiment"

    @property
    def models(self) -> list:
        return [k for k in self.sources if k != self.experiment]

    @property
    def synthetic(self) -> bool:
        return self.sources[self.experiment].synthetic

    def rows(self) -> list[dict]:
        out = []
        for m in self.models:
            for sig in self.signals:
                out.append(
                    {
                        "model": m,
                        "signal": sig,
                        "unit": SIGNALS[sig][1],
                        "rms_error": self.rms[m][sig],
                        "rms_error_percent_of_range": self.rms_percent[m][sig],
                        "n_strides_model": self.n_strides.get(m, 0),
                        "n_strides_experiment": self.n_strides.get(self.experiment, 0),
                        "status": self.status[m],
                    }
                )
        return out

    def to_csv(self, path) -> Path:
        """One row per (model, signal): RMS error (SI unit), RMS % of the experiment's
        range, stride counts, status; NaN as empty cells."""
        path = Path(path)
        rows = self.rows()
        names = [
            "model",
            "signal",
            "unit",
            "rms_error",
            "rms_error_percent_of_range",
            "n_strides_model",
            "n_strides_experiment",
            "status",
        ]
        with open(path, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=names)
            w.writeheader()
            for r in rows:
                w.writerow(
                    {
                        k: ("" if isinstance(v, float) and not math.isfinite(v) else v)
                        for k, v in r.items()
                    }
                )
        return path

    def format(self) -> str:
        """Plain-text table (display units: deg, deg/s)."""
        lines = [
            f"Phase-normalized comparison: {self.n_strides.get(self.experiment, 0)} "
            f"experimental steady strides; RMS of (model mean - experiment mean) over "
            f"the stride phase"
        ]
        if self.synthetic:
            lines.append("NOTE: the experiment data are SYNTHETIC (generated by scoutsim).")
        head = f"  {'signal':<18}" + "".join(f"{_label(m):>22}" for m in self.models)
        lines.append(head)
        for sig in self.signals:
            lab, _, unit, f, _ = SIGNALS[sig]
            cells = []
            for m in self.models:
                v = self.rms[m][sig]
                p = self.rms_percent[m][sig]
                cells.append(
                    f"{'-':>22}"
                    if not math.isfinite(v)
                    else f"{v * f:>10.4g} {unit:<5} ({p:4.0f}%)"
                )
            lines.append(f"  {lab:<18}" + "".join(cells))
        for m in self.models:
            if self.status[m] != "ok":
                lines.append(f"  {_label(m)}: {self.status[m]}")
        return "\n".join(lines)


def phase_compare(
    experiment, models, n_phase: int = 101, transient_s: float = 2.0, signals=tuple(SIGNALS)
) -> PhaseComparison:
    """Phase-normalized comparison of ``models`` against ``experiment`` (module docstring).

    Parameters
    ----------
    experiment : ExperimentLog, list of ExperimentLog, SimulationResult or Source
        The reference; its steady strides are pooled.
    models : dict name -> SimulationResult / ModelRun / ExperimentLog / Source, a list of
        SimulationResults, or an ErrorTable
    n_phase : points of the phase grid (>= 2)
    transient_s : strides starting earlier (from each record's start) are not steady
    signals : names from :data:`SIGNALS`
    """
    if not isinstance(n_phase, (int, np.integer)) or n_phase < 2:
        raise ValueError(f"n_phase = {n_phase!r} is not allowed: must be an integer >= 2")
    signals = tuple(signals)
    bad = [s for s in signals if s not in SIGNALS]
    if bad or not signals:
        raise ValueError(f"signals = {signals!r} is not allowed: choose from {', '.join(SIGNALS)}")
    if isinstance(experiment, (list, tuple)) and not experiment:
        raise ValueError("experiment is empty: give at least one log")
    exp = as_source(experiment, "experiment", transient_s=transient_s)
    exp.name = "experiment"
    like = exp.logs[0] if exp.logs else None
    srcs = {"experiment": exp}
    for k, v in as_sources(models, like, transient_s).items():
        if k == "experiment":
            raise ValueError("a model may not be called 'experiment'")
        srcs[k] = v
    phase = np.linspace(0.0, 1.0, n_phase)
    mean: dict[str, dict[str, np.ndarray]]
    std: dict[str, dict[str, np.ndarray]]
    mean, std, nstr, status = {}, {}, {}, {}
    for k, src in srcs.items():
        pairs = src.steady
        nstr[k] = len(pairs)
        status[k] = (
            src.status if pairs else (src.status if src.status != "ok" else "no steady strides")
        )
        if pairs:
            mean[k], std[k] = {}, {}
            for sig in signals:
                v = resample_strides(pairs, sig, n_phase)
                mean[k][sig] = v.mean(axis=0)
                std[k][sig] = v.std(axis=0)
    error: dict[str, dict[str, np.ndarray]]
    rms: dict[str, dict[str, float]]
    rmsp: dict[str, dict[str, float]]
    error, rms, rmsp = {}, {}, {}
    for k in srcs:
        if k == "experiment":
            continue
        error[k], rms[k], rmsp[k] = {}, {}, {}
        for sig in signals:
            if k in mean and "experiment" in mean:
                e = mean[k][sig] - mean["experiment"][sig]
                r = float(np.sqrt(np.mean(e * e)))
                ptp = float(np.ptp(mean["experiment"][sig]))
                error[k][sig] = e
                rms[k][sig] = r
                rmsp[k][sig] = 100.0 * r / ptp if ptp > 0 else math.nan
            else:
                error[k][sig] = np.full(n_phase, np.nan)
                rms[k][sig] = math.nan
                rmsp[k][sig] = math.nan
    return PhaseComparison(phase, srcs, signals, mean, std, nstr, error, rms, rmsp, status)
