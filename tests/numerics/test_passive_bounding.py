"""The compiled simulator on periodic passive bounding orbits (found by
scoutsim.analysis.orbits with an independent SciPy integration of the stance phases)."""

import math

import numpy as np
import pytest

import scoutsim
from scoutsim import InitialState, IntegratorSettings
from scoutsim.analysis.orbits import passive_bounding_orbit, passive_robot

TIGHT = IntegratorSettings(rtol=1e-11, atol=1e-11)


@pytest.fixture(scope="module")
def orbit():
    return passive_bounding_orbit(1.3, 0.35, math.radians(50.0))


def run(orb, duration):
    init = InitialState(y=orb.apex_height, theta=0.0, dx=orb.speed, dy=0.0,
                        dtheta=orb.pitch_rate)
    return scoutsim.simulate(passive_robot(), None, init, duration, model="passive",
                             passive_touchdown_angles=orb.touchdown_angles,
                             integrator=TIGHT)


def test_energy_conserved_over_5s_of_passive_bounding(orbit):
    r = run(orbit, 5.0)
    assert r.outcome == "completed"
    td_b = r.event_times("touchdown", "back")
    td_f = r.event_times("touchdown", "front")
    assert len(td_b) >= 15 and len(td_f) >= 15
    assert len(r.event_times("liftoff")) >= 30
    E = r.energy
    assert np.max(np.abs(E - E[0])) / abs(E[0]) < 1e-8


def test_compiled_simulator_reproduces_the_orbit_period(orbit):
    """Apex to apex: the simulated pitch and height repeat after one orbit period."""
    r = run(orbit, 3.0 * orbit.period)
    k = int(round(orbit.period / 1e-3))
    # the orbit is unstable (multiplier > 1): compare the first period only
    i0 = 0
    i1 = np.searchsorted(r.t, orbit.period)
    assert r.outcome == "completed"
    assert abs(r.t[i1] - orbit.period) <= 1e-3
    assert abs(r.height[i1] - r.height[i0]) < 2e-3
    assert abs(r.pitch[i1] - r.pitch[i0]) < 2e-3
    assert k > 100


def test_massless_touchdown_at_rest_length_is_not_undone():
    """Regression: a massless undamped leg touches down exactly at rest length (normal
    force 0 +- rounding); it must not be released at the same instant (the toe then fell
    through the ground). Simultaneous touchdowns of a pronk hit it most often."""
    pronk = passive_bounding_orbit(1.3, 0.35, 0.0)
    r = run(pronk, 3.0)
    assert r.outcome == "completed"
    ev = r.events
    for leg in (0, 1):
        e = ev[ev[:, 2] == leg]
        for a, b in zip(e[:-1], e[1:]):
            if a[1] == 1 and b[1] == 2:          # touchdown then lift-off
                assert b[0] - a[0] > 1e-3
