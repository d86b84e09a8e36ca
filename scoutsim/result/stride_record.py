"""What the strides of a run need from its samples, taken as the run is computed.

A stride's metrics (:mod:`scoutsim.analysis.strides`) read the time series only near its
two back-leg lift-offs and between them: the torso position, pitch and height at each
lift-off (cubic Hermite interpolation of the two samples around it), the samples nearest
to it for the energy (:mod:`scoutsim.analysis.stride_energy`), and the largest and smallest
pitch and height of the samples strictly between the two lift-offs. A
:class:`StrideRecorder` takes these from a run's samples piece by piece
(:meth:`StrideRecorder.feed`, at the full control rate) and keeps only them, the contact
events and the impacts: a :class:`StrideRecord`. A run recorded at a lower rate
(``simulate(record_rate=...)``) or streamed to disk computes its strides from the record,
not from the samples it keeps, and gets the same strides, bit for bit, as the same run
held whole at the full rate; a run held whole is split through the same record
(:func:`record_strides`), in one piece.

Times in seconds, positions and heights in metres, pitch in radians, energies in J.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._core.model import layout as L
from ..names import ContactMode, LegState
from .interpolation import hermite

__all__ = ["StrideRecord", "StrideRecorder", "record_strides", "toe_slide_length", "ENERGY_NAMES"]

#: the cumulative energies (``SimulationResult.cumulative_energy``) a stride's energy reads
ENERGY_NAMES = ("hip_work", "friction", "constraint", "electrical", "copper", "transmission")

#: the signals the record reads from the samples, each with its time derivative
_SIGNALS = ("x", "pitch", "height")
_RATES = ("forward_speed", "pitch_rate", "vertical_speed")
#: the signals whose extremes between two lift-offs a stride reports
_EXTREMES = ("pitch", "height")


def _samples(piece) -> dict:
    """The columns of ``piece`` (a result, or a window of one) the record reads."""
    cols = {"t": np.asarray(piece.t, dtype=float)}
    for name in _SIGNALS + _RATES:
        cols[name] = np.asarray(getattr(piece, name), dtype=float)
    for leg in (0, 1):
        cols[f"mode_{leg}"] = np.asarray(piece.contact_mode(leg))
        cols[f"toe_{leg}"] = np.asarray(piece.toe_position(leg)[0], dtype=float)
    if getattr(piece, "energy_series", None) is not None:
        cols["mechanical"] = np.asarray(piece.energy, dtype=float)
        for name in ENERGY_NAMES:
            cols["e_" + name] = piece.cumulative_energy(name)
    return cols


def toe_slide_length(mode: np.ndarray, x: np.ndarray) -> float:
    """Path length [m] of a toe along the floor while on the ground: the sum of |dx| of
    its position ``x`` [m] between consecutive samples both in contact (``mode``: its
    contact mode, :class:`~scoutsim.names.ContactMode`; a pinned toe does not move, so
    this is the sliding)."""
    if x.size < 2:
        return 0.0
    on = (mode[1:] != ContactMode.FLIGHT) & (mode[:-1] != ContactMode.FLIGHT)
    dx = np.abs(np.diff(x))[on]
    return float(np.sum(dx[np.isfinite(dx)]))


def retraction_saturation(piece, leg: int, motor) -> tuple[int, int]:
    """(stance-retraction samples, those at which the motor works on its limits) of leg
    ``leg`` (0 back, 1 front) over the samples of ``piece``, ``motor`` the leg's
    parameters (``RobotParameters.leg``): on the current limit, |i| >= (1 - 1e-3) i_max,
    or on the torque-speed line, |R_A i + K_w w_m| >= (1 - 1e-3) V_b
    (:meth:`~scoutsim.analysis.gait.GaitMetrics.motor_saturation_fraction`)."""
    m = np.asarray(piece.leg_state(leg)) == LegState.RETRACTION
    n = int(np.count_nonzero(m))
    if n == 0:
        return 0, 0
    i = np.asarray(piece.motor_current(leg))[m]
    w = np.asarray(piece.motor_speed(leg))[m]
    vb = np.asarray(piece.battery_voltage)[m]
    on_current = np.abs(i) >= (1.0 - 1e-3) * motor.current_limit
    v_term = motor.armature_resistance * i + motor.speed_constant * w
    on_voltage = np.abs(v_term) >= (1.0 - 1e-3) * vb
    return n, int(np.count_nonzero(on_current | on_voltage))


def _nearest(t: np.ndarray, te: float) -> int:
    """Index of the sample nearest to ``te`` (the earlier one on a tie)."""
    i = int(np.searchsorted(t, te))
    if i >= len(t):
        return len(t) - 1
    if i > 0 and te - t[i - 1] <= t[i] - te:
        return i - 1
    return i


@dataclass
class StrideRecord:
    """What a run's strides need (module docstring), as columns.

    Attributes
    ----------
    liftoffs : dict of (k,) arrays, one row per back-leg lift-off in time order: ``t``
        [s]; ``x`` [m], ``pitch`` [rad], ``height`` [m] there (Hermite); with the energy
        accounting also, at the sample nearest to it: ``sample`` (its index in the run),
        ``sample_t`` [s], ``sample_x`` [m], ``sample_mechanical`` [J] and ``e_NAME`` [J]
        for the names of :data:`ENERGY_NAMES`.
    interior : dict of (k - 1,) arrays, one row per pair of consecutive lift-offs:
        ``pitch_max``, ``pitch_min`` [rad], ``height_max``, ``height_min`` [m] of the
        samples strictly between them (-inf / inf where there is none).
    contacts : (m, NEVREC) the run's touchdown and lift-off event records, in the order
        logged (``layout.EVR_*``).
    t_first : time of the run's first sample [s] (None if it has none).
    n_samples : samples the run computed.
    energy : whether the run accounted for its energy.
    x_first, x_last : the torso's position at the run's first and last sample [m].
    toe_slide : (back, front) path length of each toe along the floor while on the
        ground, from every sample [m]
        (:func:`~scoutsim.analysis.behaviour.toe_slide_distance`).
    saturation : per leg (back, front), (stance-retraction samples, those on the motor's
        limits) (:func:`retraction_saturation`), or None without the robot.
    belt_deflection_max : the largest |belt deflection| of both legs over every sample
        [rad] (None without samples).
    """

    liftoffs: dict
    interior: dict
    contacts: np.ndarray
    t_first: float | None
    n_samples: int
    energy: bool
    x_first: float | None = None
    x_last: float | None = None
    toe_slide: tuple[float, float] = (0.0, 0.0)
    saturation: tuple | None = None
    belt_deflection_max: float | None = None

    def contact_log(self, leg: int) -> tuple[np.ndarray, np.ndarray]:
        """(times [s], kinds: :class:`~scoutsim.names.EventKind` codes) of the touchdowns
        and lift-offs of leg ``leg`` (0 back, 1 front), in the order logged."""
        ev = self.contacts[self.contacts[:, L.EVR_LEG] == leg]
        return ev[:, L.EVR_T], ev[:, L.EVR_KIND].astype(int)

    def event_count(self, kind: int, leg: int) -> int:
        """How many contact events of ``kind`` (``EventKind.TOUCHDOWN`` or ``LIFTOFF``)
        leg ``leg`` (0 back, 1 front) had."""
        ev = self.contacts
        return int(np.count_nonzero((ev[:, L.EVR_KIND] == kind) & (ev[:, L.EVR_LEG] == leg)))

    def impacts(self) -> tuple[np.ndarray, np.ndarray]:
        """(times [s], kinetic energy lost [J]) of the run's touchdown impacts, in time
        order."""
        ev = self.contacts[self.contacts[:, L.EVR_KIND] == L.EK_TOUCHDOWN]
        times, lost = ev[:, L.EVR_T], ev[:, L.EVR_V3]
        if times.size > 1 and not np.all(times[1:] >= times[:-1]):
            order = np.argsort(times, kind="stable")
            times, lost = times[order], lost[order]
        return times, lost


class StrideRecorder:
    """Takes a :class:`StrideRecord` from a run's samples and events, fed in time order in
    pieces of any size (module docstring). Each piece's samples must follow the previous
    piece's; its events are those logged since."""

    def __init__(self, robot=None):
        """``robot``: the run's :class:`~scoutsim.parameters.RobotParameters`, for the
        motors' saturation counts (None: not counted)."""
        self._motors = None if robot is None else (robot.leg(0), robot.leg(1))
        self._saturation = [[0, 0], [0, 0]]
        self._belt = -np.inf
        self._carry: dict | None = None  # the last two samples fed
        self._pending: list[float] = []  # lift-offs waiting for a sample after them
        self._open: dict | None = None  # the interior extremes since the last lift-off
        self._liftoffs: list[dict] = []
        self._interior: list[dict] = []
        self._contacts: list[np.ndarray] = []
        self._n = 0
        self._t_first: float | None = None
        self._energy: bool | None = None
        self._x_first: float | None = None
        self._slide = [0.0, 0.0]

    def feed(self, piece) -> None:
        """Take the samples and events of ``piece`` (a :class:`SimulationResult` holding
        the run's next samples and the events logged with them)."""
        ev = np.asarray(piece.events, dtype=float)
        ev = ev.reshape(0, L.NEVREC) if ev.size == 0 else ev[:, : L.NEVREC]
        contact = np.isin(ev[:, L.EVR_KIND], (L.EK_TOUCHDOWN, L.EK_LIFTOFF))
        self._contacts.append(ev[contact])
        back_lo = ev[contact & (ev[:, L.EVR_KIND] == L.EK_LIFTOFF) & (ev[:, L.EVR_LEG] == 0)]
        self._pending.extend(float(te) for te in back_lo[:, L.EVR_T])
        cols = _samples(piece)
        n = len(cols["t"])
        if self._energy is None and n:
            self._energy = "mechanical" in cols
        if n and self._t_first is None:
            self._t_first = float(cols["t"][0])
            self._x_first = float(cols["x"][0])
        if self._carry is not None and n:
            k = len(self._carry["t"])
            cols = {c: np.concatenate([self._carry[c], v]) for c, v in cols.items()}
            first = self._n - k
        else:
            first = self._n
        self._n += n
        if n:
            self._count(piece)
            start = max(0, len(cols["t"]) - n - 1)  # (the last sample fed before, and these)
            self._add_slide({c: v[start:] for c, v in cols.items()})
        if len(cols["t"]):
            self._resolve(cols, first, final=False)
            self._carry = {c: v[-2:].copy() for c, v in cols.items()}

    def finish(self) -> StrideRecord:
        """The record of everything fed: the lift-offs after the last sample are taken
        at it (as :func:`~scoutsim.result.interpolation.hermite` clamps)."""
        if self._carry is not None:
            self._resolve(self._carry, self._n - len(self._carry["t"]), final=True)
        energy = bool(self._energy) and self._n >= 2
        keys = ["t"] + list(_SIGNALS)
        if energy:
            keys += ["sample", "sample_t", "sample_x", "sample_mechanical"]
            keys += ["e_" + name for name in ENERGY_NAMES]
        lift = {k: np.array([row[k] for row in self._liftoffs], dtype=float) for k in keys}
        inner_keys = [f"{s}_{m}" for s in _EXTREMES for m in ("max", "min")]
        inner = {k: np.array([row[k] for row in self._interior], dtype=float) for k in inner_keys}
        contacts = (
            np.concatenate(self._contacts) if self._contacts else np.empty((0, L.NEVREC))
        ).reshape(-1, L.NEVREC)
        x_last = float(self._carry["x"][-1]) if self._carry is not None else None
        return StrideRecord(
            lift,
            inner,
            contacts,
            self._t_first,
            self._n,
            energy,
            self._x_first,
            x_last,
            (self._slide[0], self._slide[1]),
            None if self._motors is None else tuple(map(tuple, self._saturation)),
            self._belt if self._n else None,
        )

    def _count(self, piece) -> None:
        """Add the piece's samples to the saturation counts and the belt's extreme."""
        if self._motors is not None:
            for leg in (0, 1):
                n, k = retraction_saturation(piece, leg, self._motors[leg])
                self._saturation[leg][0] += n
                self._saturation[leg][1] += k
        for leg in (0, 1):
            b = np.abs(np.asarray(piece.belt_deflection(leg), dtype=float))
            self._belt = float(np.max([self._belt, np.max(b)]))

    def _add_slide(self, cols: dict) -> None:
        """Add the toes' slide over the samples ``cols`` (the last sample fed before, if
        any, and the piece's)."""
        for leg in (0, 1):
            self._slide[leg] += toe_slide_length(cols[f"mode_{leg}"], cols[f"toe_{leg}"])

    # -- the lift-offs of a stretch of samples -------------------------------------------
    def _resolve(self, cols: dict, first: int, *, final: bool) -> None:
        """Take the pending lift-offs that have a sample after them in ``cols`` (all of
        them if ``final``), in time order, and the interior extremes of the samples
        (``first``: the run's index of the first row of ``cols``)."""
        t = cols["t"]
        self._pending.sort()
        if final:
            ready, self._pending = self._pending, []
        else:
            cut = int(np.searchsorted(self._pending, t[-1], side="left"))
            ready, self._pending = self._pending[:cut], self._pending[cut:]
        at = np.array(ready, dtype=float)
        values = {s: hermite(t, cols[s], cols[r], at) for s, r in zip(_SIGNALS, _RATES)}
        for i, te in enumerate(ready):
            if self._open is not None:
                self._extend(cols, self._open["t"], te)
                self._interior.append({k: v for k, v in self._open.items() if k != "t"})
            row = {"t": te} | {s: float(values[s][i]) for s in _SIGNALS}
            if "mechanical" in cols:
                j = _nearest(t, te)
                row |= {
                    "sample": float(first + j),
                    "sample_t": float(t[j]),
                    "sample_x": float(cols["x"][j]),
                    "sample_mechanical": float(cols["mechanical"][j]),
                }
                row |= {"e_" + name: float(cols["e_" + name][j]) for name in ENERGY_NAMES}
            self._liftoffs.append(row)
            self._open = {"t": te} | {
                f"{s}_{m}": (-np.inf if m == "max" else np.inf)
                for s in _EXTREMES
                for m in ("max", "min")
            }
        if self._open is not None:
            self._extend(cols, self._open["t"], np.inf)

    def _extend(self, cols: dict, a: float, b: float) -> None:
        """Widen the open stride's interior extremes by the samples with a < t < b (a
        sample seen twice changes nothing)."""
        t = cols["t"]
        i0 = int(np.searchsorted(t, a, side="right"))
        i1 = int(np.searchsorted(t, b, side="left"))
        ext = self._open
        if i1 <= i0 or ext is None:
            return
        for s in _EXTREMES:
            y = cols[s][i0:i1]
            ext[f"{s}_max"] = float(np.max([ext[f"{s}_max"], np.max(y)]))
            ext[f"{s}_min"] = float(np.min([ext[f"{s}_min"], np.min(y)]))


def record_strides(result) -> StrideRecord:
    """The :class:`StrideRecord` of a run held whole: the record it was recorded with
    (``result.stride_record``: a run recorded at a lower rate, or streamed), else its
    samples and events taken in one piece."""
    kept = getattr(result, "stride_record", None)
    if kept is not None:
        return kept
    rec = StrideRecorder()
    rec.feed(result)
    return rec.finish()
