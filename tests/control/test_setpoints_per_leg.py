"""Each leg of the Table I bounding controller runs to its own set-points (paper Sec. II,
Table I: a touchdown angle and a sweep limit per leg; docs/specification.md section 6),
through the whole path a user's ControllerParameters take: simulate, the controller's
array, the compiled loop and the recorded events.

With the back and front set-points far apart (touchdown angles 16 and 28 deg, sweep limits
-4 and +4 deg; Table I has 19 / 21 and 0 / 0, too close to tell apart), a bound of 1.5 s
checks two laws of each leg:

* the flight servo tau = kp (phi_td - phi) - kd dphi brings the leg to its own touchdown
  angle: at every touchdown after a flight under the servo the sensed hip angle is within
  ``SERVO_ERROR`` of that leg's phi_td, and so 10 deg or more from the other leg's;
* stance-retraction ends when the sensed hip angle falls below the leg's own sweep limit:
  at every sweep-limit record the angle is below it, by less than what two control periods
  at the sensed rate move it (one period's motion, with a margin for the rate's change).

A back / front swap of either set-point anywhere along the path (packing, the compiled
law's indexing, the loop's legs) fails the test of that set-point.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import scoutsim
from scoutsim import ControllerParameters
from scoutsim._core.model import layout as L
from scoutsim.names import EventKind, Leg

#: (back, front) set-points [rad]
TOUCHDOWN = (math.radians(16.0), math.radians(28.0))
SWEEP = (math.radians(-4.0), math.radians(4.0))
PARAMS = ControllerParameters().replace(
    touchdown_angle_back=TOUCHDOWN[Leg.BACK],
    touchdown_angle_front=TOUCHDOWN[Leg.FRONT],
    sweep_limit_back=SWEEP[Leg.BACK],
    sweep_limit_front=SWEEP[Leg.FRONT],
)
#: how far from its set-point the flight servo (Table I gains) may leave a leg at
#: touchdown [rad]: its swing toward the set-point is not quite over when the leg lands
#: (about 1 deg at most in these runs); a sixth of the set-points' separation
SERVO_ERROR = math.radians(2.0)


@pytest.fixture(scope="module", params=["ideal", "II"])
def bound(request):
    """1.5 s of bounding with the set-points above (the default start, in flight). The
    controller senses the motor-side angle alpha (Model II; phi in the ideal model)."""
    r = scoutsim.simulate(controller=PARAMS, duration=1.5, model=request.param)
    assert r.outcome == "completed", r.outcome
    return r


def _records(r, kind, leg):
    """(times [s], sensed hip angles [rad], their rates [rad/s]) at the event records of
    ``kind`` and ``leg``: the exact state at each (just before a plant transition)."""
    rows = np.flatnonzero((r.events[:, L.EVR_KIND] == kind) & (r.events[:, L.EVR_LEG] == leg))
    before = r.event_states[rows, L.EVS_BEFORE]
    return (r.events[rows, L.EVR_T], before[:, L.IALB + leg], before[:, L.NQ + L.IALB + leg])


@pytest.mark.parametrize("leg", list(Leg), ids=lambda leg: leg.label)
def test_each_leg_lands_at_its_own_touchdown_angle(bound, leg):
    own, other = TOUCHDOWN[leg], TOUCHDOWN[1 - leg]
    assert abs(own - other) > 5 * SERVO_ERROR
    liftoffs = bound.event_times(EventKind.CONTROLLER_LIFTOFF.label, leg)
    t, angle, _ = _records(bound, EventKind.TOUCHDOWN, leg)
    # the landings after a whole flight under the servo (the first follows the start state)
    served = angle[t > liftoffs[0]] if len(liftoffs) else angle[:0]
    assert np.all(np.abs(served - own) < SERVO_ERROR), np.degrees(served)
    assert np.all(np.abs(served - other) > abs(own - other) - SERVO_ERROR)
    assert len(served) >= 3, f"{len(served)} landings of the {leg.label} leg after a flight"


@pytest.mark.parametrize("leg", list(Leg), ids=lambda leg: leg.label)
def test_each_leg_brakes_at_its_own_sweep_limit(bound, leg):
    own, other = SWEEP[leg], SWEEP[1 - leg]
    _, angle, rate = _records(bound, EventKind.CONTROLLER_SWEEP, leg)
    assert np.all(rate < 0.0)  # retracting
    # below the limit at this sample, at or above it one sample before; twice the period's
    # motion at the sensed rate as the margin for the rate's change within the period
    step = 2.0 * np.abs(rate) * PARAMS.control_period
    assert np.all(angle < own), np.degrees(angle)
    assert np.all(angle >= own - step), np.degrees(angle)
    assert np.all(np.abs(angle - other) > abs(own - other) / 2)
    assert len(angle) >= 3, f"the {leg.label} leg passed its sweep limit {len(angle)} times"
