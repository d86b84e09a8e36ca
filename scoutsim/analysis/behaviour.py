"""What a run did: steady bounding (at what speed), or what it did instead.

A run's summary gives the gait means over its steady strides (:mod:`~scoutsim.analysis.gait`);
a run without steady strides has none, and this module says why, from quantities the
result already holds: its outcome and the fall's event record, its strides and their
periods, the stances of each leg (touchdown / lift-off events), the distance the torso
travelled and the distance the toes slid on the floor.

:func:`classify_behaviour` gives a :class:`Behaviour`: a ``kind`` (one of
:data:`BEHAVIOUR_KINDS`), a sentence saying it (``text``; figure titles and the
``scoutsim run`` table print it), the time of what ended the run (``t_s``), the advice
("run longer") only where it is the actual reason, and the counts it was decided from.
First match wins:

``no_data``
    the result holds no sample.
``numerical_failure``, ``controller_error``, ``write_failed``
    the run stopped there (its outcome; :attr:`SimulationResult.failure` says why a run
    failed numerically).
``fell``
    the torso touched the ground or its pitch passed the limit (``pitch_limit_deg``, 60 deg
    by default; docs/specification.md section 3), at ``t_s``.
``bounding``
    steady bounding: :meth:`GaitMetrics.is_steady_bounding
    <scoutsim.analysis.gait.GaitMetrics.is_steady_bounding>` (at least 7 steady strides,
    paper Sec. IV.C, with converged periods), at the steady strides' mean speed.
``airborne``
    no toe touched the ground.
``standing`` (or ``sliding``)
    both toes on the ground and no lift-off for the last :data:`REST_S` seconds (or more)
    of the run: it stood from ``t_s`` on (before any stride: it did not leave the ground);
    ``sliding`` if the toes slid at least :data:`SLIDE_MIN_M` meanwhile and the torso went
    as far.
``periodic``
    a steady gait that is not a bound: the stride periods repeat every k = 2 or 3 strides
    (:data:`CYCLE_REPEATS` cycles after the transient), the back legs lifting off k times
    per cycle.
``hopping_in_place``
    the legs kept lifting off but the torso moved forward at less than
    :data:`IN_PLACE_SPEED_M_S` over the last strides.
``sliding``
    the toes slid on the floor at least :data:`SLIDE_PER_METRE` metres per metre the torso
    travelled: on a slippery floor the toes slid instead of carrying the robot.
``too_short``
    fewer than 7 steady strides, but the last :data:`SETTLED_STRIDES` or more converged;
    or every stride after the transient converged (or there is none) and the time after
    the transient holds fewer than 8 strides of the last period (a run that ended before
    the transient did, too): the only kind whose advice is "run longer".
``irregular``
    strides whose periods did not settle (none steady, or fewer than
    :data:`SETTLED_STRIDES` converged after unsettled ones), or back legs that stopped
    lifting off (no stride for the last :data:`REST_S` seconds and three periods).

The sentence of every kind mentions the toes' sliding when they slid at least
:data:`SLIDE_NOTE_PER_METRE` metres per metre travelled.
A run stopped by the user (outcome "interrupted") is classified by what it did until then,
its text prefixed with the stop. Units: s, m, m/s, Hz.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..names import ContactMode, EventKind, leg_index
from ..result.stride_record import toe_slide_length
from ..simulation.assembly import DEFAULT_PITCH_LIMIT_DEG
from .stances import stance_overlap
from .strides import MIN_STEADY_STRIDES, PERIOD_TOLERANCE

__all__ = [
    "Behaviour",
    "classify_behaviour",
    "toe_slide_distance",
    "BEHAVIOUR_KINDS",
    "IN_PLACE_SPEED_M_S",
    "SLIDE_PER_METRE",
    "SLIDE_NOTE_PER_METRE",
    "SLIDE_MIN_M",
    "REST_S",
    "SETTLED_STRIDES",
    "MAX_CYCLE_STRIDES",
    "CYCLE_REPEATS",
    "RUN_LONGER",
]

#: The kinds of behaviour, in the order :func:`classify_behaviour` tests them.
BEHAVIOUR_KINDS = (
    "no_data",
    "numerical_failure",
    "controller_error",
    "write_failed",
    "fell",
    "bounding",
    "airborne",
    "standing",
    "sliding",
    "periodic",
    "hopping_in_place",
    "too_short",
    "irregular",
)
#: Average forward speed [m/s] below which the robot counts as staying in place.
IN_PLACE_SPEED_M_S = 0.1
#: Toe sliding per metre the torso travelled [m/m] from which sliding is what the run did:
#: the toes slid farther than the torso went (both toes together). The Table I bound on the
#: default floor (mu = 1) slides 0.25-0.3 m per m in Model II, 0.4-0.45 in Model I and the
#: ideal actuator, at touchdown and lift-off; on a mu = 0.1 floor Model II slides 1.2.
SLIDE_PER_METRE = 1.0
#: Toe sliding per metre travelled [m/m] from which the sentence mentions it.
SLIDE_NOTE_PER_METRE = 0.5
#: Time [s] without a lift-off, both toes on the ground, that counts as standing.
REST_S = 1.0
#: Strides whose periods agree that make a gait look settled (for the "run longer" advice).
SETTLED_STRIDES = 3
#: Toe sliding [m] (both toes) below which it is not worth a mention.
SLIDE_MIN_M = 0.1
#: Longest cycle of unequal strides [strides] looked for, and the cycles that must repeat.
MAX_CYCLE_STRIDES = 3
CYCLE_REPEATS = 3
#: The advice of a run too short to tell.
RUN_LONGER = "run longer"


@dataclass(frozen=True)
class Behaviour:
    """What a run did (module docstring).

    Attributes
    ----------
    kind : str
        One of :data:`BEHAVIOUR_KINDS`.
    text : str
        The sentence that says it ("steady bounding at 1.39 m/s, 4.27 Hz", "fell at
        t = 0.66 s: the torso touched the ground, after 0 strides", ...).
    t_s : float or None
        Time [s] of what ended the run or the motion: the fall, the failure, the start of
        the standing; None otherwise.
    advice : str or None
        :data:`RUN_LONGER` when the run was too short to tell, else None.
    counts : dict
        What it was decided from, JSON-safe: ``n_strides``, ``n_steady_strides``,
        ``liftoffs`` and ``touchdowns`` per leg, ``ground_contact_fraction`` per leg [-]
        (stance time over the run's time), ``distance_m`` the torso travelled,
        ``average_speed_m_s`` over the run, ``toe_slide_m`` per leg (path length of each
        toe along the floor while on the ground, from the 1 kHz samples), ``slide_per_metre``
        [m/m] (both toes, None if the torso did not move), ``fall_cause`` ("pitch",
        "torso_contact" or None), ``speed_m_s`` and ``stride_frequency_hz`` of the steady
        strides (None without).
    """

    kind: str
    text: str
    t_s: float | None = None
    advice: str | None = None
    counts: dict = field(default_factory=dict)

    @property
    def bounding(self) -> bool:
        """Whether the run is steady bounding."""
        return self.kind == "bounding"

    def to_dict(self) -> dict:
        """JSON-safe dict: kind, text, t_s, advice, counts."""
        return {
            "kind": self.kind,
            "text": self.text,
            "t_s": _num(self.t_s),
            "advice": self.advice,
            "counts": dict(self.counts),
        }

    def __str__(self) -> str:
        return self.text


def _num(v):
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


def toe_slide_distance(result, leg, t0: float | None = None) -> float:
    """Path length [m] of a toe along the floor while on the ground: the sum of |dx| of its
    position between consecutive samples both in contact (stick, slide or strut; a pinned
    toe does not move, so this is the sliding), from the 1 kHz samples (those at or after
    ``t0`` [s] if given)."""
    record = getattr(result, "stride_record", None)
    if t0 is None and record is not None:  # a thinned or streamed run: from every sample
        return record.toe_slide[leg_index(leg)]
    k = 0 if t0 is None else int(np.searchsorted(np.asarray(result.t, dtype=float), t0))
    mode = np.asarray(result.contact_mode(leg))[k:]
    x = np.asarray(result.toe_position(leg)[0], dtype=float)[k:]
    return toe_slide_length(mode, x)


def _pitch_limit_deg(result) -> float:
    """The |pitch| [deg] the run counted as a fall (its provenance's, else the default)."""
    return float((result.provenance or {}).get("pitch_limit_deg", DEFAULT_PITCH_LIMIT_DEG))


def _fall(result):
    """(time [s], cause "pitch" / "torso_contact") of the run's fall record, or the end of
    the run and None if it has none."""
    log = result.event_log(kinds=(EventKind.FALL,))
    if log["t"].size == 0:
        return float(result.t_end), None
    limit = math.radians(_pitch_limit_deg(result))
    pitch = abs(float(log["v2"][-1]))  # the fall record: v1 = y, v2 = theta
    cause = "pitch" if pitch >= limit * (1.0 - 1e-6) else "torso_contact"
    return float(log["t"][-1]), cause


def _settled(strides, tol: float) -> bool:
    """Whether the last SETTLED_STRIDES strides have periods within ``tol`` (relative) of
    their median."""
    if len(strides) < SETTLED_STRIDES:
        return False
    p = np.array([s.period_s for s in strides[-SETTLED_STRIDES:]])
    ref = float(np.median(p))
    return bool(ref > 0 and np.all(np.abs(p - ref) <= tol * ref))


def _counts(result, gait) -> dict:
    """The counts a run's behaviour is decided from: over the whole run, from every
    sample (a thinned or streamed run's ``stride_record``) or from its samples."""
    record = getattr(result, "stride_record", None)
    legs = ("back", "front")
    if record is not None and record.t_first is not None:
        t0, x0, x1 = record.t_first, record.x_first, record.x_last
        liftoffs = {n: record.event_count(EventKind.LIFTOFF, i) for i, n in enumerate(legs)}
        touchdowns = {n: record.event_count(EventKind.TOUCHDOWN, i) for i, n in enumerate(legs)}
    else:
        x = np.asarray(result.x, dtype=float)
        t0, x0, x1 = float(result.t[0]), float(x[0]), float(x[-1])
        liftoffs = {n: int(len(result.event_times("liftoff", n))) for n in legs}
        touchdowns = {n: int(len(result.event_times("touchdown", n))) for n in legs}
    t1 = float(result.t_end)
    span = t1 - t0
    distance = float(x1 - x0)
    slide = [toe_slide_distance(result, leg) for leg in (0, 1)]
    steady = gait.n_steady_strides > 0
    return {
        "n_strides": gait.n_strides,
        "n_steady_strides": gait.n_steady_strides,
        "liftoffs": liftoffs,
        "touchdowns": touchdowns,
        "ground_contact_fraction": {
            n: (_num(stance_overlap(gait.stance[n], t0, t1) / span) if span > 0 else None)
            for n in legs
        },
        "distance_m": _num(distance),
        "average_speed_m_s": _num(distance / span) if span > 0 else None,
        "toe_slide_m": {n: _num(s) for n, s in zip(legs, slide)},
        "slide_per_metre": (_num(sum(slide) / abs(distance)) if abs(distance) > 1e-3 else None),
        "fall_cause": None,
        "speed_m_s": _num(gait.mean_speed_m_s) if steady else None,
        "stride_frequency_hz": _num(gait.stride_frequency_hz) if steady else None,
    }


def _last_liftoff(result) -> float | None:
    lo = np.concatenate([result.event_times("liftoff", leg) for leg in (0, 1)])
    return float(np.max(lo)) if lo.size else None


def classify_behaviour(result, gait=None, period_tolerance: float = PERIOD_TOLERANCE) -> Behaviour:
    """What ``result`` did (module docstring): steady bounding, or what instead.

    Parameters
    ----------
    result : SimulationResult
    gait : GaitMetrics, optional
        The run's strides (default: ``result.gait()``).
    period_tolerance : float
        Relative spread of the last strides' periods within which a gait looks settled
        (as :func:`~scoutsim.analysis.gait.gait_metrics`' tolerance; default
        :data:`~scoutsim.analysis.strides.PERIOD_TOLERANCE`, 5 %).

    Returns
    -------
    Behaviour
    """
    t = np.asarray(result.t, dtype=float)
    outcome = str(result.outcome)
    if t.size == 0:
        return Behaviour(
            "no_data",
            f"{outcome}: no sample recorded",
            None,
            None,
            {"n_strides": 0, "n_steady_strides": 0},
        )
    if gait is None:
        gait = result.gait()
    c = _counts(result, gait)
    n = gait.n_strides
    t_end = float(result.t_end)
    strides_so_far = f"after {_plural(n, 'stride')}"

    if outcome == "numerical_failure":
        why = ""
        failure = getattr(result, "failure", None)
        if failure is not None:
            why = f" ({failure.kind.replace('_', ' ')})"
        return Behaviour(
            "numerical_failure",
            f"the integration failed at t = {t_end:.2f} s{why}, {strides_so_far}",
            t_end,
            None,
            c,
        )
    if outcome == "controller_error":
        return Behaviour(
            "controller_error",
            f"the controller failed at t = {t_end:.2f} s, {strides_so_far}",
            t_end,
            None,
            c,
        )
    if outcome == "write_failed":
        return Behaviour(
            "write_failed",
            f"stopped at t = {t_end:.2f} s: the run's tables "
            f"could not be written, {strides_so_far}",
            t_end,
            None,
            c,
        )
    if outcome == "fell":
        t_fall, cause = _fall(result)
        c["fall_cause"] = cause
        how = {
            "pitch": f"its pitch passed {_pitch_limit_deg(result):g} deg",
            "torso_contact": "the torso touched the ground",
        }.get(cause, "")
        slid = _slide_note(c)
        return Behaviour(
            "fell",
            f"fell at t = {t_fall:.2f} s"
            + (f": {how}" if how else "")
            + f", {strides_so_far}"
            + (f"; {slid}" if slid else ""),
            t_fall,
            None,
            c,
        )

    stop = f"interrupted at t = {t_end:.2f} s; until then " if outcome == "interrupted" else ""
    b = _motion(result, gait, c, period_tolerance)
    return Behaviour(b.kind, stop + b.text, b.t_s, b.advice, c)


def _slide_note(c, per_metre: float = SLIDE_NOTE_PER_METRE) -> str:
    """ "the toes slid X m while the torso travelled Y m" when that is at least
    ``per_metre`` per metre travelled and SLIDE_MIN_M in all, else ""."""
    r = c["slide_per_metre"]
    slide = sum(v or 0.0 for v in c["toe_slide_m"].values())
    if r is None or r < per_metre or slide < SLIDE_MIN_M:
        return ""
    return f"the toes slid {slide:.2f} m while the torso travelled {abs(c['distance_m']):.2f} m"


def _cycle(strides, tol: float, transient_s: float):
    """The number k >= 2 of strides of a repeating cycle of unequal strides among the last
    strides after the transient (each stride's period within ``tol`` of the cycle's period
    of the one k strides earlier, for CYCLE_REPEATS cycles), or None."""
    late = [s for s in strides if s.t_start >= transient_s]
    for k in range(2, MAX_CYCLE_STRIDES + 1):
        m = CYCLE_REPEATS * k
        if len(late) < m:
            break
        p = np.array([s.period_s for s in late[-m:]])
        cycle = float(np.sum(p[-k:]))
        if np.all(np.abs(p[k:] - p[:-k]) <= tol * cycle) and np.ptp(p[-k:]) > tol * float(
            np.median(p[-k:])
        ):
            return k
    return None


def _motion(result, gait, c, tol) -> Behaviour:
    """The kind of a run that did not stop early (completed, or interrupted by the user)."""
    n, n_steady = gait.n_strides, gait.n_steady_strides
    strides = gait.strides
    t0, t_end = float(result.t[0]), float(result.t_end)
    slid = _slide_note(c)
    if gait.is_steady_bounding():
        v, f = c["speed_m_s"], c["stride_frequency_hz"]
        where = " in place" if abs(v) < IN_PLACE_SPEED_M_S else ""
        text = (
            f"steady bounding{where} at {v:.2f} m/s, {f:.2f} Hz ({n_steady} steady strides)"
        ) + (f"; {slid}" if slid else "")
        return Behaviour("bounding", text)
    if sum(c["touchdowns"].values()) == 0:
        return Behaviour(
            "airborne", f"in flight the whole run ({t_end - t0:.2f} s): no toe touched the ground"
        )

    # on the ground for good: stood, or slid on its toes
    last_lo = _last_liftoff(result)
    both_down = all(
        int(np.asarray(result.contact_mode(leg))[-1]) != ContactMode.FLIGHT for leg in (0, 1)
    )
    since = (
        last_lo
        if last_lo is not None
        else float(np.min(np.concatenate([result.event_times("touchdown", leg) for leg in (0, 1)])))
    )
    if both_down and t_end - since >= REST_S:
        x = np.asarray(result.x, dtype=float)
        moved = float(x[-1] - x[int(np.searchsorted(np.asarray(result.t), since))])
        slide = sum(toe_slide_distance(result, leg, since) for leg in (0, 1))
        before = "no stride before" if n == 0 else f"after {_plural(n, 'stride')}"
        if slide >= SLIDE_MIN_M and abs(moved) >= SLIDE_MIN_M:
            return Behaviour(
                "sliding",
                f"toes slid {slide:.2f} m on the ground from "
                f"t = {since:.2f} s on, without lifting off, while the torso "
                f"moved {moved:.2f} m ({before})",
                since,
            )
        if n == 0:
            return Behaviour(
                "standing",
                f"stood: did not leave the ground after "
                f"t = {since:.2f} s (no stride; the torso moved "
                f"{c['distance_m']:.2f} m in all)",
                since,
            )
        return Behaviour("standing", f"came to a stand at t = {since:.2f} s {before}", since)

    speed = _recent_speed(strides, c)
    k = _cycle(strides, tol, gait.transient_s)
    if k is not None:
        last = strides[-k:]
        cycle = sum(s.period_s for s in last)
        speed = sum(s.mean_speed_m_s * s.period_s for s in last) / cycle
        parts = " / ".join(f"{s.period_s:.3f}" for s in last)
        where = " in place" if abs(speed) < IN_PLACE_SPEED_M_S else ""
        return Behaviour(
            "periodic",
            f"a steady gait{where} with {k} back-leg lift-offs per "
            f"cycle (strides of {parts} s; cycle {cycle:.3f} s, "
            f"{1.0 / cycle:.2f} Hz) at {speed:.2f} m/s: not a bound of one "
            "lift-off per stride" + (f"; {slid}" if slid else ""),
        )
    note = f"; {slid}" if slid else ""
    if speed is not None and abs(speed) < IN_PLACE_SPEED_M_S:
        lo = sum(c["liftoffs"].values())
        return Behaviour(
            "hopping_in_place",
            f"hopped in place: {_plural(lo, 'lift-off')}, "
            f"{_plural(n, 'stride')}, mean forward speed {speed:.2f} m/s{note}",
        )
    if _slide_note(c, SLIDE_PER_METRE):
        return Behaviour(
            "sliding",
            f"{slid.removeprefix('the ')}; {_plural(n, 'stride')}, {_none_steady(n_steady)}",
        )

    # strides: too few after the transient to tell, or irregular
    tr = gait.transient_s
    cand = [s for s in strides if s.t_start >= tr]
    p = np.array([s.period_s for s in strides])
    spread = f"periods {p.min():.3f}-{p.max():.3f} s" if n else ""
    if n and t_end - strides[-1].t_end > max(REST_S, 3.0 * strides[-1].period_s):
        # the back legs stopped lifting off: not a matter of the run's length
        return Behaviour(
            "irregular",
            f"{_plural(n, 'stride')}, {_none_steady(n_steady)} "
            f"({spread}); no back-leg lift-off after t = {strides[-1].t_end:.2f} s"
            f"{note}",
        )
    if n_steady < MIN_STEADY_STRIDES:
        # too short a run: the last strides converged, at least SETTLED_STRIDES of them; or
        # every stride after the transient converged (or there is none) and the time after
        # the transient holds fewer than 7 strides of the last period
        room = (
            (t_end - tr) / float(np.median(p[-SETTLED_STRIDES:]))
            if n
            else (0.0 if t_end < tr else math.inf)
        )
        if n_steady >= SETTLED_STRIDES or (n_steady == len(cand) and room < MIN_STEADY_STRIDES + 1):
            if t_end < tr:
                how = (
                    (
                        f"the last {SETTLED_STRIDES} with equal periods"
                        if _settled(strides, tol)
                        else f"still settling ({spread})"
                    )
                    if n >= SETTLED_STRIDES
                    else (spread or "none complete")
                )
                how += f"; the run ended before the {tr:g} s transient did"
            else:
                how = (
                    f"{'the last ' if n_steady < len(cand) else ''}{n_steady} steady after "
                    f"the {tr:g} s transient, too few to call the gait steady (at least "
                    f"{MIN_STEADY_STRIDES})"
                )
            return Behaviour(
                "too_short", f"{_plural(n, 'stride')}, {how}: {RUN_LONGER}{note}", None, RUN_LONGER
            )
    if n == 0:
        return Behaviour(
            "irregular",
            "no complete stride: the back legs lifted off "
            f"{_plural(c['liftoffs']['back'], 'time')}{note}",
        )
    return Behaviour(
        "irregular", f"{_plural(n, 'stride')} taken, {_none_steady(n_steady)} ({spread}){note}"
    )


def _none_steady(n_steady: int) -> str:
    if n_steady == 0:
        return "none steady"
    return f"only the last {n_steady} steady"


def _recent_speed(strides, c):
    """Mean forward speed [m/s] over the last SETTLED_STRIDES strides (the whole run's
    average without strides)."""
    if strides:
        last = strides[-SETTLED_STRIDES:]
        span = sum(s.period_s for s in last)
        return sum(s.mean_speed_m_s * s.period_s for s in last) / span
    return c["average_speed_m_s"]
