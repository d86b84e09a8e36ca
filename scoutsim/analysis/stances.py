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

from ..model import layout as L

__all__ = ["stance_intervals", "stance_overlap"]

_LEGS = {"back": 0, "front": 1, 0: 0, 1: 1}


def _leg(leg) -> int:
    try:
        return _LEGS[leg]
    except (KeyError, TypeError):
        raise ValueError(f"leg = {leg!r} is not allowed: must be 'back' or 'front'") from None


def _events(result) -> np.ndarray:
    ev = np.asarray(result.events, dtype=float)
    if ev.size == 0:
        return np.zeros((0, L.NEVREC))
    return ev.reshape(-1, ev.shape[-1])


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
    li = _leg(leg)
    ev = _events(result)
    m = (ev[:, 2] == li) & np.isin(ev[:, 1], (L.EK_TOUCHDOWN, L.EK_LIFTOFF))
    sel = ev[m]
    sel = sel[np.argsort(sel[:, 0], kind="stable")]
    t0 = float(result.t[0]) if len(result.t) else 0.0
    out = []
    start = None
    for i, row in enumerate(sel):
        kind = int(row[1])
        if kind == L.EK_TOUCHDOWN:
            if start is None:
                start = float(row[0])
        else:  # lift-off
            if start is not None:
                out.append((start, float(row[0])))
                start = None
            elif i == 0:
                out.append((t0, float(row[0])))
    if start is not None:
        out.append((start, max(float(result.t_end), start)))
    return np.array(out, dtype=float).reshape(-1, 2)


def stance_overlap(intervals: np.ndarray, a: float, b: float) -> float:
    """Total length [s] of the intersection of ``intervals`` with [a, b]."""
    if intervals.shape[0] == 0 or b <= a:
        return 0.0
    lo = np.maximum(intervals[:, 0], a)
    hi = np.minimum(intervals[:, 1], b)
    return float(np.sum(np.clip(hi - lo, 0.0, None)))
