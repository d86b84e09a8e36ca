"""Stances of a run's virtual legs from the plant's contact events (docs/specification.md
section 8).

A stance starts at a ``"touchdown"`` event of a leg and ends at the next ``"liftoff"``
event of the same leg, at the plant's continuous-time event times (``result.events``),
not controller samples. Other plant events (``"slide_start"``, ``"stick"``, strut events,
...) and the controller's own detections (``"controller_touchdown"``, ...) do not start or
end a stance. Times in seconds.
"""

from __future__ import annotations

import numpy as np

from ..names import EventKind, leg_index

__all__ = ["stance_intervals", "stances_of_contacts", "stance_overlap"]


def stance_intervals(result, leg) -> np.ndarray:
    """Stance intervals of one virtual leg from the plant's contact events.

    A stance starts at a ``"touchdown"`` event and ends at the next ``"liftoff"`` event of
    the same leg (continuous-time event times; docs/specification.md section 8). A ``"slide_start"`` or any other
    event does not end a stance. A stance still open at the end of the data ends at
    ``result.t_end``. If the first contact event of the leg is a lift-off, the leg started
    the run on the ground and that stance starts at the first sample time ``result.t[0]``.

    Parameters
    ----------
    result : SimulationResult
    leg : {"back", "front", 0, 1}

    Returns
    -------
    (k, 2) ndarray
        Rows ``[t_touchdown, t_liftoff]`` [s], in time order.
    """
    log = result.event_log(kinds=(EventKind.TOUCHDOWN, EventKind.LIFTOFF), leg=leg_index(leg))
    t0 = float(result.t[0]) if len(result.t) else 0.0
    return stances_of_contacts(log["t"], log["kind"], t0, float(result.t_end))


def stances_of_contacts(times, kinds, t_first: float, t_end: float) -> np.ndarray:
    """:func:`stance_intervals` of one leg's touchdown and lift-off events, their times
    [s] and kinds (:class:`~scoutsim.names.EventKind` codes) in the order logged, for a
    run whose first sample is at ``t_first`` and which ended at ``t_end`` [s]."""
    times = np.asarray(times, dtype=float)
    kinds = np.asarray(kinds)
    order = np.argsort(times, kind="stable")
    times, kinds = times[order], kinds[order]
    out = []
    start = None
    for i, (te, kind) in enumerate(zip(times, kinds)):
        if kind == EventKind.TOUCHDOWN:
            if start is None:
                start = float(te)
        else:  # lift-off
            if start is not None:
                out.append((start, float(te)))
                start = None
            elif i == 0:
                out.append((t_first, float(te)))
    if start is not None:
        out.append((start, max(t_end, start)))
    return np.array(out, dtype=float).reshape(-1, 2)


def stance_overlap(intervals: np.ndarray, a: float, b: float) -> float:
    """Total length [s] of the intersection of ``intervals`` with [a, b]."""
    if intervals.shape[0] == 0 or b <= a:
        return 0.0
    lo = np.maximum(intervals[:, 0], a)
    hi = np.minimum(intervals[:, 1], b)
    return float(np.sum(np.clip(hi - lo, 0.0, None)))
