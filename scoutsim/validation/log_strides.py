"""Strides and per-stride gait metrics of a log (docs/specification.md section 8; paper Sec. IV.C).

The same definitions as :mod:`scoutsim.analysis.gait`, applied to what a robot logs
instead of the simulator's continuous-time events:

- **Lift-off / touchdown** of a leg is the first sample at which its logged controller
  state changes from stance (1 or 2) to flight (0) / from flight to stance (so event times
  are quantized to the 1 ms control period, as on the robot).
- A **stride** runs from one back-leg lift-off to the next.
- Per stride: ``period_s``, ``stride_frequency_hz`` (1/period), ``duty_factor_back`` and
  ``duty_factor_front`` (stance time inside the stride / period), ``pitch_max_deg``,
  ``pitch_min_deg``, ``height_max_m``, ``height_min_m`` (extremes of the *measured* pitch
  and height, :attr:`ExperimentLog.pitch`, over the samples from lift-off to lift-off
  inclusive). ``mean_speed_m_s`` is NaN: the robot did not log its forward position.
- **Steady strides**: start at or after ``transient_s``, lie entirely at least
  :data:`~scoutsim.validation.torso_sensors.EDGE_S` inside the record (no filter edge
  effects), and belong to the final contiguous block whose periods are within
  ``period_tolerance`` of the median period of the last seven candidates (as in
  :func:`scoutsim.analysis.gait.gait_metrics`).

The results are :class:`scoutsim.analysis.strides.Stride` objects, so the metric names match.

:func:`log_strides` accepts any log (a model that fell has few strides or none, which the
comparison reports). :func:`experiment_strides`, used for the experiment logs of the
comparison, refuses with :class:`~scoutsim.validation.log_format.LogError` a log too short to
hold one steady stride (it must last at least ``max(transient_s, EDGE_S) + EDGE_S`` plus
one stride period) and a log in which no stride is detected (fewer than two back-leg
lift-offs, or a front leg that never touches down or never lifts off).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..analysis.stances import stance_overlap
from ..analysis.strides import STRIDE_METRICS, Stride, converged_tail
from ..names import LegState
from .log_format import LogError
from .torso_sensors import EDGE_S

__all__ = [
    "log_strides",
    "experiment_strides",
    "min_steady_duration",
    "LogGait",
    "stance_intervals_log",
    "STRIDE_METRICS",
]


def stance_intervals_log(log, leg) -> np.ndarray:
    """(k, 2) [touchdown, lift-off] times [s] of one leg from its logged states; a stance
    open at the start begins at t[0], one open at the end ends at t[-1]."""
    s = log.leg_state(leg)
    t = log.t
    stance = s != LegState.FLIGHT
    edges = np.diff(stance.astype(int))
    starts: list[int] = (np.flatnonzero(edges == 1) + 1).tolist()
    ends: list[int] = (np.flatnonzero(edges == -1) + 1).tolist()
    if stance[0]:
        starts.insert(0, 0)
    if stance[-1]:
        ends.append(len(t) - 1)
    return np.array([[t[a], t[b]] for a, b in zip(starts, ends)], dtype=float).reshape(-1, 2)


@dataclass
class LogGait:
    """Strides of one log and the means over its steady strides (None without any)."""

    strides: list
    transient_s: float
    source: str = ""
    means: dict = field(default_factory=dict)

    def __post_init__(self):
        steady = self.steady_strides
        self.means = {
            k: (float(np.mean([s[k] for s in steady])) if steady else None) for k in STRIDE_METRICS
        }

    @property
    def steady_strides(self) -> list:
        return [s for s in self.strides if s.steady]

    @property
    def n_strides(self) -> int:
        return len(self.strides)

    @property
    def n_steady_strides(self) -> int:
        return len(self.steady_strides)

    def __getattr__(self, name):
        if name in STRIDE_METRICS:
            return self.means[name]
        raise AttributeError(name)


def log_strides(log, transient_s: float = 2.0, period_tolerance: float = 0.05) -> LogGait:
    """Split a log into strides and compute the per-stride metrics (module docstring)."""
    if not (math.isfinite(transient_s) and transient_s >= 0):
        raise ValueError(f"transient_s = {transient_s!r} is not allowed: must be >= 0")
    t = log.t
    lo = log.liftoff_times("back")
    stances = (stance_intervals_log(log, "back"), stance_intervals_log(log, "front"))
    th = np.asarray(log.pitch)
    y = np.asarray(log.height)
    t0, t1 = float(t[0]), float(t[-1])
    out: list[Stride] = []
    for k in range(len(lo) - 1):
        a, b = float(lo[k]), float(lo[k + 1])
        period = b - a
        i0 = int(np.searchsorted(t, a, side="left"))
        i1 = int(np.searchsorted(t, b, side="right"))
        out.append(
            Stride(
                index=len(out),
                t_start=a,
                t_end=b,
                period_s=period,
                stride_frequency_hz=1.0 / period,
                duty_factor_back=stance_overlap(stances[0], a, b) / period,
                duty_factor_front=stance_overlap(stances[1], a, b) / period,
                pitch_max_deg=math.degrees(float(np.max(th[i0:i1]))),
                pitch_min_deg=math.degrees(float(np.min(th[i0:i1]))),
                height_max_m=float(np.max(y[i0:i1])),
                height_min_m=float(np.min(y[i0:i1])),
                mean_speed_m_s=math.nan,
                steady=bool(a - t0 >= max(transient_s, EDGE_S) and b <= t1 - EDGE_S),
            )
        )
    out = converged_tail(out, period_tolerance)
    return LogGait(strides=out, transient_s=float(transient_s), source=log.name)


def min_steady_duration(transient_s: float = 2.0, period_s: float = 0.0) -> float:
    """Least duration [s] of a record that can hold one steady stride of period ``period_s``
    [s]: the stride must start at least ``max(transient_s, EDGE_S)`` after the start and
    end at least ``EDGE_S`` before the end (module docstring)."""
    return max(float(transient_s), EDGE_S) + EDGE_S + float(period_s)


def _state_summary(values) -> str:
    """'is 1 in every row' or 'takes the values 0, 1'."""
    u = np.unique(values)
    if u.size == 1:
        return f"is {u[0]:g} in every row"
    return "takes the values " + ", ".join(f"{x:g}" for x in u)


def experiment_strides(log, transient_s: float = 2.0, period_tolerance: float = 0.05) -> LogGait:
    """:func:`log_strides` of an experiment log, refusing a log that cannot give a stride.

    Parameters
    ----------
    log : ExperimentLog
    transient_s : float
        Strides starting earlier than this after the start of the record are transient [s].
    period_tolerance : float
        As in :func:`log_strides`.

    Returns
    -------
    LogGait
        As :func:`log_strides` (it may still have no *steady* stride, when the stride
        periods never settle within ``period_tolerance``; the comparison notes that).

    Raises
    ------
    LogError
        Naming the file and the column: ``t`` if the log lasts less than
        :func:`min_steady_duration` (with its shortest stride period, or without one if it
        has no complete stride); ``leg_state_back`` if it has fewer than two back-leg
        lift-offs (no stride: a stride runs from one to the next); ``leg_state_front`` if
        the front leg never touches down or never lifts off (not a bounding gait).
    """
    if not (math.isfinite(transient_s) and transient_s >= 0):
        raise ValueError(f"transient_s = {transient_s!r} is not allowed: must be >= 0")
    where = log.path or log.name
    duration = log.duration
    lo = log.liftoff_times("back")
    period = float(np.min(np.diff(lo))) if lo.size >= 2 else 0.0
    need = min_steady_duration(transient_s, period)
    if duration < need:
        start = max(float(transient_s), EDGE_S)
        why = (
            f"the transient: transient_s = {transient_s:g} s, --transient"
            if transient_s >= EDGE_S
            else f"EDGE_S, the low-pass edge effects; transient_s = {transient_s:g} s"
        )
        if lo.size >= 2:
            total = (
                f"{start + EDGE_S:g} s plus one stride period ({period:.3f} s, its "
                f"shortest) = {need:.3f} s"
            )
        else:
            total = (
                f"{start + EDGE_S:g} s plus one stride period (it has no complete "
                f"stride: {lo.size} back-leg lift-off(s))"
            )
        raise LogError(
            f"{where}: column 't': the log lasts {duration:.3f} s "
            f"({len(log.t)} samples), too short to hold one steady stride: a "
            "steady stride (one back-leg lift-off to the next) must start at least "
            f"{start:g} s after the start of the record ({why}) and end at least "
            f"{EDGE_S:g} s before its end (EDGE_S, the low-pass edge effects), so "
            f"the log must last at least {total}; give a longer log"
            + (" or a smaller --transient" if transient_s > EDGE_S else ""),
            log.path,
            "t",
        )
    if lo.size < 2:
        raise LogError(
            f"{where}: column 'leg_state_back': no stride detected in "
            f"{duration:.3f} s: a stride runs from one back-leg lift-off "
            "(leg_state_back changing from 1 or 2 to 0) to the next, and the log has "
            f"{lo.size} (leg_state_back {_state_summary(log.leg_state('back'))}); "
            "a log of bounding needs at least two: check that the robot was "
            "bounding and that the controller's leg states were logged",
            log.path,
            "leg_state_back",
        )
    for kind, times in (
        ("touches down", log.touchdown_times("front")),
        ("lifts off", log.liftoff_times("front")),
    ):
        if times.size == 0:
            raise LogError(
                f"{where}: column 'leg_state_front': no stride detected: the front "
                f"leg never {kind} in {duration:.3f} s (leg_state_front "
                f"{_state_summary(log.leg_state('front'))}); in a bounding stride "
                "each leg touches down and lifts off: check that the robot was "
                "bounding and that the controller's leg states were logged",
                log.path,
                "leg_state_front",
            )
    return log_strides(log, transient_s=transient_s, period_tolerance=period_tolerance)
