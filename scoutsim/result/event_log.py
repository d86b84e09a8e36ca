"""The event log of a run by name: the times [s] of touchdowns, lift-offs and the other
event kinds (:class:`scoutsim.names.EventKind`), the records as named columns or dicts,
and the touchdown impacts (impulses [N s], kinetic energy lost [J]). A mixin of
:class:`~scoutsim.result.simulation_result.SimulationResult`, which holds the event records (``events``,
layout ``layout.EVR_*``).
"""

from __future__ import annotations

import numpy as np

from .._core.model import layout as L
from ..names import leg_index
from .run_data import RunData

__all__ = ["EventAccessors", "EVENT_LOG_COLUMNS", "IMPACT_LOG_COLUMNS"]

#: the columns of :meth:`EventAccessors.event_log`, in the order of a record
EVENT_LOG_COLUMNS = (
    "t",
    "kind",
    "leg",
    "v1",
    "v2",
    "v3",
    "energy_before",
    "energy_after",
    "violations",
)
#: the columns of :meth:`EventAccessors.impact_log`
IMPACT_LOG_COLUMNS = ("t", "leg", "normal_impulse", "tangential_impulse", "energy_lost")


class EventAccessors(RunData):
    """Named accessors of a run's event records."""

    def event_times(self, kind: str, leg=None) -> np.ndarray:
        """Times [s] of events of a kind ("touchdown", "liftoff", ...), optionally of one leg."""
        codes = {v: k for k, v in L.EVENT_KIND_NAMES.items()}
        if kind not in codes:
            raise ValueError(f"kind = {kind!r} is not allowed: must be one of {sorted(codes)}")
        m = self.events[:, L.EVR_KIND] == codes[kind]
        if leg is not None:
            m &= self.events[:, L.EVR_LEG] == leg_index(leg)
        return self.events[m, L.EVR_T]

    def event_log(self, kinds=None, leg=None) -> dict:
        """The event records as named columns, in the order they were logged (time order),
        optionally only the records of some kinds and of one leg.

        Parameters
        ----------
        kinds : names of event kinds ("touchdown", "liftoff", ...: the labels of EventKind)
            or :class:`~scoutsim.names.EventKind` members, or None: every kind.
        leg : "back" / 0, "front" / 1, or None: the records of every leg and those of none.

        Returns
        -------
        dict of (m,) arrays (:data:`EVENT_LOG_COLUMNS`): ``t`` [s]; ``kind``, the
        :class:`~scoutsim.names.EventKind` code (int); ``leg`` (int: 0 back, 1 front, -1
        none); ``v1``, ``v2``, ``v3``, the kind's values (a touchdown: normal and tangential
        impulse [N s], kinetic energy lost [J]); ``energy_before``, ``energy_after``, the
        mechanical energy just before the transition and after its modes settled [J] (NaN
        for the controller's records, which are not plant transitions); ``violations``, the
        bit mask of the mode invariants violated after it (:class:`~scoutsim.names.Violation`;
        0: none), as floats: NaN where it was not recorded (a result saved before the
        transition audit existed).

        ValueError if the records lack the transition audit's columns (a result saved by
        an older scoutsim) or a kind is unknown.
        """
        ev = np.asarray(self.events, dtype=float)
        if ev.size == 0:
            ev = ev.reshape(0, L.NEVREC)
        elif ev.ndim == 1:
            ev = ev.reshape(1, -1)
        if ev.ndim != 2 or ev.shape[1] < L.NEVREC:
            raise ValueError(
                "these events carry no transition audit (a result saved by an "
                "older scoutsim): re-run the simulation"
            )
        m = np.ones(len(ev), dtype=bool)
        if kinds is not None:
            codes = {v: k for k, v in L.EVENT_KIND_NAMES.items()}
            wanted = []
            for kind in kinds:
                if isinstance(kind, str):
                    if kind not in codes:
                        raise ValueError(
                            f"kind = {kind!r} is not allowed: must be one of {sorted(codes)}"
                        )
                    kind = codes[kind]
                wanted.append(int(kind))
            m &= np.isin(ev[:, L.EVR_KIND], wanted)
        if leg is not None:
            m &= ev[:, L.EVR_LEG] == leg_index(leg)
        ev = ev[m]
        return {
            "t": ev[:, L.EVR_T],
            "kind": ev[:, L.EVR_KIND].astype(int),
            "leg": ev[:, L.EVR_LEG].astype(int),
            "v1": ev[:, L.EVR_V1],
            "v2": ev[:, L.EVR_V2],
            "v3": ev[:, L.EVR_V3],
            "energy_before": ev[:, L.EVR_E_BEFORE],
            "energy_after": ev[:, L.EVR_E_AFTER],
            "violations": ev[:, L.EVR_VIOLATIONS],
        }

    def event_table(self) -> list[dict]:
        """Events as a list of dicts (time, kind, leg, values)."""
        out = []
        for row in self.events:
            leg = int(row[L.EVR_LEG])
            out.append(
                {
                    "t": float(row[L.EVR_T]),
                    "kind": L.EVENT_KIND_NAMES.get(int(row[L.EVR_KIND]), "?"),
                    "leg": L.LEG_NAMES[leg] if leg >= 0 else None,
                    "values": [float(v) for v in row[L.EVR_V1 :]],
                }
            )
        return out

    def impacts(self):
        """Touchdown impacts: (t, leg, normal impulse [N s], tangential impulse [N s],
        kinetic energy lost [J]) as an array."""
        m = self.events[:, L.EVR_KIND] == L.EK_TOUCHDOWN
        return self.events[m][:, [L.EVR_T, L.EVR_LEG, L.EVR_V1, L.EVR_V2, L.EVR_V3]]

    def impact_log(self, t0: float | None = None, t1: float | None = None) -> dict:
        """The touchdown impacts with t0 <= t < t1 [s] (None: no bound) as named columns
        (:data:`IMPACT_LOG_COLUMNS`), in time order: ``t`` [s], ``leg`` (int: 0 back,
        1 front), ``normal_impulse`` and ``tangential_impulse`` [N s], ``energy_lost``, the
        kinetic energy the impact dissipated [J]."""
        ev = self.events
        m = ev[:, L.EVR_KIND] == L.EK_TOUCHDOWN
        if t0 is not None:
            m &= ev[:, L.EVR_T] >= t0
        if t1 is not None:
            m &= ev[:, L.EVR_T] < t1
        ev = ev[m]
        return {
            "t": ev[:, L.EVR_T],
            "leg": ev[:, L.EVR_LEG].astype(int),
            "normal_impulse": ev[:, L.EVR_V1],
            "tangential_impulse": ev[:, L.EVR_V2],
            "energy_lost": ev[:, L.EVR_V3],
        }
