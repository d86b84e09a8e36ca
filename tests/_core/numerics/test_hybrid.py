"""Physics and numerics tests of the compiled hybrid integrator (scoutsim/_core/numerics/hybrid.py)."""

import math

import numpy as np
import pytest

import scoutsim
from scoutsim import InitialState, IntegratorSettings, RobotParameters

MASSLESS = RobotParameters(leg_mass=0.0, leg_inertia=0.0, leg_damping=0.0)
TIGHT = IntegratorSettings(rtol=1e-10, atol=1e-10)


def passive(init, duration, td_deg=0.0, integ=TIGHT, robot=MASSLESS, **kw):
    return scoutsim.simulate(
        robot,
        None,
        init,
        duration,
        model="passive",
        passive_touchdown_angles=(math.radians(td_deg),) * 2,
        integrator=integ,
        **kw,
    )


def test_energy_conserved_passive_pronking_5s():
    """Massless, undamped legs: the passive model is conservative (docs/specification.md section 2)."""
    r = passive(InitialState(y=0.36, theta=0.0, dx=0.0, dtheta=0.0), 5.0)
    assert r.outcome == "completed"
    n_td = len(r.event_times("touchdown"))
    n_lo = len(r.event_times("liftoff"))
    assert n_td >= 20 and n_lo >= 20
    E = r.energy
    assert np.max(np.abs(E - E[0])) / abs(E[0]) < 1e-8


def test_energy_conserved_passive_bounding_with_pitch():
    """Rocking bound (pitching, legs touching down at different times): energy to 1e-8."""
    r = passive(InitialState(y=0.36, theta=0.0, dx=0.0, dtheta=math.radians(20.0)), 3.0)
    td_b = r.event_times("touchdown", "back")
    td_f = r.event_times("touchdown", "front")
    assert len(td_b) >= 10 and len(td_f) >= 10
    # legs touch down at different times: this is bounding, not pronking
    assert np.min(np.abs(td_b[:5] - td_f[:5])) > 1e-3
    E = r.energy
    assert np.max(np.abs(E - E[0])) / abs(E[0]) < 1e-8


def test_energy_lost_only_in_touchdown_impacts():
    """Massive undamped legs, no actuators: energy changes only by the reported impact losses."""
    robot = RobotParameters(leg_damping=0.0)
    r = scoutsim.simulate(
        robot,
        None,
        InitialState(y=0.36, dx=1.0, theta=0.0, dtheta=0.0),
        0.6,
        friction_coefficient=math.inf,
        model="passive",
        integrator=TIGHT,
    )
    imp = r.impacts()
    assert len(imp) >= 2
    assert np.all(imp[:, 4] > 0.0)  # each impact loses kinetic energy
    E = r.energy
    lost = E[0] - E[-1]
    assert lost == pytest.approx(imp[:, 4].sum(), rel=1e-6, abs=1e-7)


def test_touchdown_time_located_to_1e9_s():
    """Level drop with vertical massless legs: touchdown at t = sqrt(2 (y0 - l0) / g)."""
    y0 = 0.40
    r = passive(InitialState(y=y0, theta=0.0, dx=0.3, dtheta=0.0), 0.3)
    rob = MASSLESS
    t_exact = math.sqrt(2.0 * (y0 - rob.leg_rest_length) / rob.gravity)
    for leg in ("back", "front"):
        t_td = r.event_times("touchdown", leg)[0]
        assert abs(t_td - t_exact) < 1e-9
    # the event is not on the 1 ms control grid
    assert abs(t_exact * 1000 - round(t_exact * 1000)) > 1e-3


def test_liftoff_at_rest_length_for_undamped_massless_leg():
    """docs/specification.md section 3: for an undamped massless leg lift-off is exactly l = l0 (and Fn = 0)."""
    r = passive(InitialState(y=0.36, theta=0.0, dx=0.5, dtheta=0.0), 1.0, td_deg=4.0)
    lo = [e for e in r.event_table() if e["kind"] == "liftoff"]
    assert len(lo) >= 2
    for e in lo:
        assert e["values"][0] == pytest.approx(MASSLESS.leg_rest_length, abs=1e-9)


def test_gait_metrics_converge_with_tolerance():
    """Stride metrics at rtol 1e-6 and 1e-10 agree to 1e-4 relative (Model I, first strides)."""
    out = []
    for rtol in (1e-6, 1e-10):
        r = scoutsim.simulate(
            duration=1.5, model="I", integrator=IntegratorSettings(rtol=rtol, atol=rtol)
        )
        out.append(r)
    a, b = out
    ta = a.events[np.isin(a.events[:, 1], [1, 2]), 0]
    tb = b.events[np.isin(b.events[:, 1], [1, 2]), 0]
    assert len(ta) == len(tb) and len(ta) >= 4
    period = np.diff(tb).max()
    assert np.max(np.abs(ta - tb)) / period < 1e-4
    for fa, fb in ((a.pitch, b.pitch), (a.height, b.height)):
        n = min(len(fa), len(fb))
        assert np.max(np.abs(fa[:n] - fb[:n])) <= 1e-4 * np.max(np.abs(fb[:n]))


def test_same_inputs_bit_identical_outputs():
    r1 = scoutsim.simulate(duration=0.5, model="II")
    r2 = scoutsim.simulate(duration=0.5, model="II")
    assert np.array_equal(r1.state, r2.state)
    assert np.array_equal(r1.aux, r2.aux)
    assert np.array_equal(r1.events, r2.events, equal_nan=True)
