"""The event log of a run by name: the times [s] of touchdowns, lift-offs and the other
event kinds (:data:`scoutsim.model.layout.EVENT_KIND_NAMES`), the events as dicts, and the
touchdown impacts (impulses [N s], kinetic energy lost [J]). A mixin of
:class:`~scoutsim.result.SimulationResult`, which holds the event records (``events``,
layout ``layout.EVR_*``).
"""

from __future__ import annotations

import numpy as np

from .model import layout as L
from .result_series import _leg

__all__ = ["EventAccessors"]


class EventAccessors:
    """Named accessors of a run's event records."""

    def event_times(self, kind: str, leg=None) -> np.ndarray:
        """Times [s] of events of a kind ("touchdown", "liftoff", ...), optionally of one leg."""
        codes = {v: k for k, v in L.EVENT_KIND_NAMES.items()}
        if kind not in codes:
            raise ValueError(f"kind = {kind!r} is not allowed: must be one of {sorted(codes)}")
        m = self.events[:, 1] == codes[kind]
        if leg is not None:
            m &= self.events[:, 2] == _leg(leg)
        return self.events[m, 0]

    def event_table(self) -> list[dict]:
        """Events as a list of dicts (time, kind, leg, values)."""
        out = []
        for row in self.events:
            leg = int(row[2])
            out.append({"t": float(row[0]), "kind": L.EVENT_KIND_NAMES.get(int(row[1]), "?"),
                        "leg": L.LEG_NAMES[leg] if leg >= 0 else None,
                        "values": [float(v) for v in row[3:]]})
        return out

    def impacts(self):
        """Touchdown impacts: (t, leg, normal impulse [N s], tangential impulse [N s],
        kinetic energy lost [J]) as an array."""
        m = self.events[:, 1] == L.EK_TOUCHDOWN
        return self.events[m][:, [0, 2, 3, 4, 5]]
