"""Physics of the hybrid transitions: touchdown impacts, stick/slip, simultaneous events.

Laws checked (docs/model.md, "Events and transitions"):
* the touchdown impact of Model II keeps the belt rigid (the gear rate jumps with the leg
  rate) and every motor joint's stick/slip mode follows its new gear rate, whatever it was
  before (stiction carries no impulse);
* mechanical energy drops only at touchdown impacts, by exactly the logged impact losses;
* after every transition the modes agree with the velocities and forces (the transition
  audit of scoutsim.analysis.transition_audit finds nothing), over many starts, every model and
  both kinds of floor;
* a stale mode (a resumed state whose joint slips against its motion) is reconciled
  without an impulse;
* simultaneous events (a pronk) are handled the same whichever of them rounding puts first.
"""

import itertools
import math

import numpy as np
import pytest

import scoutsim
from scoutsim._core.model import layout as L
from scoutsim._core.model.impact import impact
from scoutsim._core.model.packing import robot_array
from scoutsim._core.model.rigid_body import kinetic_energy
from scoutsim.analysis.transition_audit import audit_transitions
from scoutsim.parameters import ControllerParameters, RobotParameters
from scoutsim.state import HybridState, InitialState

#: the nose-up start of the stiction-bug study (docs/model.md "Transition audit"): a back-leg push-off's flight, nose rising
NOSE_UP = InitialState(x=0.0, y=0.33, theta=0.0, dx=0.8, dy=0.0, dtheta=1.5)


def _touchdown_state(P, leg, dphi, dalpha, dx=1.0, dy=-0.6, dtheta=0.5):
    """A Model II state at the instant the toe of ``leg`` touches the ground (the other leg
    in flight), legs at 19 / 21 deg, gear rates given (a relative gear/leg rate left over
    from flight, even a large one, must not let the impact add energy)."""
    s = np.zeros(L.NS)
    th = 0.05
    phi = (math.radians(19.0), math.radians(21.0))
    l0 = P[L.P_L0]
    sL = (2 * leg - 1) * P[L.P_L]
    g = th + phi[leg]
    s[L.IY] = -sL * math.sin(th) + l0 * math.cos(g)  # toe height exactly 0
    s[L.ITH] = th
    s[L.IPHB], s[L.IPHF] = phi
    s[L.IALB], s[L.IALF] = phi
    s[L.NQ + L.IX], s[L.NQ + L.IY], s[L.NQ + L.ITH] = dx, dy, dtheta
    s[L.NQ + L.IPHB + leg] = dphi
    s[L.NQ + L.IALB + leg] = dalpha
    s[L.IL_B] = s[L.IL_F] = l0
    return s


@pytest.mark.parametrize(
    "mode_before,dphi,dalpha",
    [
        (L.STUCK, 2.0, 0.0),
        (L.STUCK, -3.0, 0.0),
        (L.SLIP_POS, 1.1, 1.1),
        (L.SLIP_POS, 6.0, 5.0),
        (L.SLIP_NEG, -1.5, -1.2),
        (L.SLIP_NEG, -6.0, -6.5),
    ],
)
@pytest.mark.parametrize("leg", [0, 1])
def test_touchdown_impact_rigid_belt_and_slip_mode_follows_new_gear_rate(
    mode_before, dphi, dalpha, leg
):
    P = robot_array(RobotParameters(), "II")
    s = _touchdown_state(P, leg, dphi, dalpha)
    mi = np.zeros(L.NMI, dtype=np.int64)
    mf = np.zeros(L.NMF)
    mi[L.MI_CONTACT_B + leg] = L.STICK
    mi[L.MI_MOTOR_B + leg] = mode_before
    other = 1 - leg
    mi[L.MI_MOTOR_B + other] = L.SLIP_POS
    sL = (2 * leg - 1) * P[L.P_L]
    g = s[L.ITH] + s[L.IPHB + leg]
    mf[L.MF_ANCHOR_B + leg] = s[L.IX] + sL * math.cos(s[L.ITH]) + P[L.P_L0] * math.sin(g)
    before = s.copy()
    out = np.zeros(L.NIMP)
    assert impact(s, P, mi, mf, out)
    dq0, dq1 = before[L.NQ : 2 * L.NQ], s[L.NQ : 2 * L.NQ]
    for lg in (0, 1):
        # rigid belt: after the impact the gear rate equals the leg rate
        assert dq1[L.IALB + lg] == pytest.approx(dq1[L.IPHB + lg], abs=1e-10)
        # the stick/slip mode follows the new gear rate (stiction carries no impulse)
        w = dq1[L.IALB + lg]
        assert w != 0.0
        assert mi[L.MI_MOTOR_B + lg] == (L.SLIP_POS if w > 0 else L.SLIP_NEG)
    # the kinetic energy lost is the one logged, and it is a loss
    ke0 = kinetic_energy(before[: L.NQ], dq0, P)
    ke1 = kinetic_energy(s[: L.NQ], dq1, P)
    assert out[L.IMP_ENERGY_LOST] == pytest.approx(ke0 - ke1, rel=1e-9, abs=1e-12)
    assert out[L.IMP_ENERGY_LOST] >= 0.0


def test_touchdown_that_reverses_a_slipping_gear_train_leaves_it_slipping_backwards():
    """The stiction bug of docs/model.md "Transition audit": the back gear train slips forward at +1.1 rad/s and the
    touchdown impact reverses it; it must then slip backwards, not be held by stiction."""
    P = robot_array(RobotParameters(), "II")
    s = _touchdown_state(P, 0, 1.1, 1.1, dx=0.8, dy=-0.8, dtheta=1.0)
    mi = np.zeros(L.NMI, dtype=np.int64)
    mf = np.zeros(L.NMF)
    mi[L.MI_CONTACT_B] = L.STICK
    mi[L.MI_MOTOR_B] = mi[L.MI_MOTOR_F] = L.SLIP_POS
    sL = -P[L.P_L]
    mf[L.MF_ANCHOR_B] = (
        s[L.IX] + sL * math.cos(s[L.ITH]) + P[L.P_L0] * math.sin(s[L.ITH] + s[L.IPHB])
    )
    out = np.zeros(L.NIMP)
    assert impact(s, P, mi, mf, out)
    assert s[L.NQ + L.IALB] < 0.0  # reversed by the impulse
    assert mi[L.MI_MOTOR_B] == L.SLIP_NEG


#: Table I with touchdown / lift-off detected at 5 / 4 mm of leg compression
DETECT_5_4 = ControllerParameters().replace(touchdown_compression=5e-3, liftoff_compression=4e-3)


@pytest.fixture(scope="module")
def model_ii_no_slip():
    return scoutsim.simulate(
        controller=DETECT_5_4,
        initial_state=NOSE_UP,
        duration=20.0,
        model="II",
        friction_coefficient=math.inf,
    )


def test_model_ii_no_slip_bounds_steadily_from_the_nose_up_start(model_ii_no_slip):
    """With the stiction bookkeeping right, Model II bounds on a no-slip
    floor from this start with lift-off detected at a few mm (the bug made it fall at
    1.3 s; with the default 8 / 6 mm it runs the 20 s without settling on a cycle)."""
    r = model_ii_no_slip
    assert r.outcome == "completed"
    g = r.gait()
    assert g.is_steady_bounding()
    assert g.n_steady_strides >= 7


def test_model_ii_no_slip_energy_lost_at_events_equals_logged_impact_losses(model_ii_no_slip):
    a = audit_transitions(model_ii_no_slip)
    n_td = len(model_ii_no_slip.event_times("touchdown"))
    assert n_td >= 50
    assert a.total_logged_loss_J > 0.0
    assert a.total_energy_drop_J == pytest.approx(a.total_logged_loss_J, rel=1e-9)
    assert a.problems() == []


def test_energy_is_continuous_at_every_transition_but_a_touchdown(model_ii_no_slip):
    a = audit_transitions(model_ii_no_slip)
    kinds = set()
    for tr in a.transitions:
        kinds.update(tr.kinds)
        if "touchdown" not in tr.kinds:
            assert tr.energy_after_J == pytest.approx(tr.energy_before_J, rel=1e-9)
    # the run exercised the motor-joint transitions too
    assert {"touchdown", "liftoff", "motor_stick", "motor_slip"} <= kinds


def _starts(n):
    """n starts spread over speed, pitch rate and height (a deterministic lattice)."""
    speeds = np.linspace(0.5, 1.7, 5)
    rates = np.radians([-100.0, -30.0, 40.0, 110.0, 180.0])
    heights = (0.33, 0.37)
    grid = list(itertools.product(speeds, rates, heights))
    return [
        InitialState(y=float(h), theta=0.0, dx=float(v), dtheta=float(w)) for v, w, h in grid[:n]
    ]


def _audit_many_starts(model, floor):
    n_transitions = 0
    bad = {}
    for init in _starts(50):
        r = scoutsim.simulate(
            initial_state=init, duration=3.0, model=model, friction_coefficient=floor
        )
        a = audit_transitions(r)
        n_transitions += a.n_transitions
        if a.problems():
            bad[init] = a.problems()
    return n_transitions, bad


@pytest.mark.parametrize("floor", [1.0, math.inf], ids=["mu1", "no_slip"])
@pytest.mark.parametrize("model", ["ideal", "I", "II"])
def test_transition_invariants_hold_over_many_starts(model, floor):
    """Energy accounting and mode consistency at every transition of 50 starts (falls and
    all), each run 3 s, on the default floor (mu = 1.0) and on a no-slip floor. (Before the
    toe-stub rules, docs/model.md, 11 of the 150 no-slip runs failed here.)"""
    n_transitions, bad = _audit_many_starts(model, floor)
    assert bad == {}
    assert n_transitions > (500 if floor == 1.0 else 300)


@pytest.mark.parametrize("floor", [math.inf, 1.0])
def test_no_toe_in_flight_is_ever_below_the_ground(floor):
    """Over the 50 starts of every model, at every sample, a toe in flight is above the
    ground: a toe stub (a leg swept through at its stop, a short hop after a release) is
    caught as it happens, not left to move into the ground unseen (it went 0.12 m deep in
    one of these runs before)."""
    worst = 0.0
    for model in ("ideal", "I", "II"):
        for init in _starts(50):
            r = scoutsim.simulate(
                initial_state=init, duration=3.0, model=model, friction_coefficient=floor
            )
            for leg in (L.BACK, L.FRONT):
                flight = r.contact_mode(leg) == L.FLIGHT
                toe_y = r.aux[flight, leg * L.NAUX_LEG + L.A_TOE_Y]
                if toe_y.size:
                    worst = min(worst, float(toe_y.min()))
    assert worst >= -1e-9


def test_a_toe_stub_becomes_a_slide_that_loads_the_leg():
    """The toe stub the transition audit found (docs/model.md "Toe stubs"): from this start the back leg, swung forward at its stop
    behind the hip, meets the ground at 1.50 s. The toe slides (cause: stub), its leg is
    compressed as it is swept through (the leg force is never negative beyond rounding), and
    it lifts off again; no toe goes below the ground."""
    init = InitialState(y=0.37, theta=0.0, dx=0.5, dtheta=math.radians(-30.0))
    r = scoutsim.simulate(
        initial_state=init, duration=3.0, model="ideal", friction_coefficient=math.inf
    )
    stubs = [
        e
        for e in r.events
        if int(e[L.EVR_KIND]) == L.EK_SLIDE_START and e[L.EVR_V3] == L.SLIDE_CAUSE_STUB
    ]
    assert stubs
    assert audit_transitions(r).problems() == []
    t0, leg = stubs[0][L.EVR_T], int(stubs[0][L.EVR_LEG])
    t1 = min(t for t in r.event_times("liftoff", leg) if t > t0)
    during = (r.t > t0) & (r.t < t1)
    assert np.all(r.contact_mode(leg)[during] == L.SLIDE)
    o = leg * L.NAUX_LEG
    fax = r.aux[during, o + L.A_FAX]
    assert np.all(fax >= -1e-6 * 24.745 * 9.81)
    assert np.all(r.aux[during, o + L.A_GN] >= -1e-6 * 24.745 * 9.81)
    assert fax.max() > 10.0  # the swept leg is loaded
    assert np.all(r.state[during, L.IL_B + leg] <= 0.323)


def test_transition_invariants_hold_for_the_massless_passive_model():
    from scoutsim.analysis.passive_orbits import passive_bounding_orbit
    from scoutsim.analysis.passive_reference import passive_robot

    orb = passive_bounding_orbit(1.3, 0.35, math.radians(50.0))
    z = orb.z
    r = scoutsim.simulate(
        passive_robot(),
        None,
        InitialState(y=z[0], theta=z[1], dx=z[2], dy=0.0, dtheta=z[3]),
        3.0,
        model="passive",
        passive_touchdown_angles=orb.touchdown_angles,
    )
    a = audit_transitions(r)
    assert a.n_transitions >= 20
    assert a.total_logged_loss_J == pytest.approx(0.0, abs=1e-12)  # massless legs: no impact
    assert a.problems() == []


def test_stale_slip_direction_is_reconciled_without_an_impulse():
    """A resumed state whose back motor joint is recorded as slipping forward while the
    gear train turns backwards: the joint must slip on backwards with its rate kept (the
    old rule stuck it: an impulse stiction cannot give, a drop of energy nobody logged)."""
    r = scoutsim.simulate(
        initial_state=NOSE_UP, duration=1.0, model="II", friction_coefficient=math.inf
    )
    k = next(
        k
        for k in range(len(r.t))
        if r.modes[k, L.RM_MOTOR_B] == L.SLIP_NEG and r.state[k, L.NQ + L.IALB] < -1.0
    )
    hs = r.hybrid_state(k)
    stale = HybridState(
        state=hs.state,
        leg_states=hs.leg_states,
        contact_modes=hs.contact_modes,
        motor_modes=(L.SLIP_POS, hs.motor_modes[1]),
        slide_directions=hs.slide_directions,
        toe_anchors=hs.toe_anchors,
    )
    a = scoutsim.simulate(
        initial_state=hs, duration=0.05, model="II", friction_coefficient=math.inf
    )
    b = scoutsim.simulate(
        initial_state=stale, duration=0.05, model="II", friction_coefficient=math.inf
    )
    assert b.modes[0, L.RM_MOTOR_B] == L.SLIP_NEG
    assert b.state[0, L.NQ + L.IALB] == a.state[0, L.NQ + L.IALB]
    assert np.array_equal(a.state, b.state)


@pytest.mark.parametrize("eps", [0.0, 1e-15, -1e-15, 3e-14, -3e-14])
def test_simultaneous_touchdowns_are_decided_alike_whatever_rounding_does(eps):
    """A pronk's two touchdowns and lift-offs are simultaneous; perturbing the start at
    rounding level (either sign) decides which one is found first, and must change nothing
    beyond rounding (on another CPU a tie once decided it differently)."""
    from scoutsim.analysis.passive_orbits import passive_bounding_orbit
    from scoutsim.analysis.passive_reference import passive_apex_map, passive_robot

    pronk = passive_bounding_orbit(1.3, 0.35, 0.0)
    z = np.array(pronk.z) + np.array([0.0, eps, 0.0, eps])
    m = passive_apex_map(z, pronk.touchdown_angles)
    assert np.max(np.abs(m.z - pronk.z)) < 1e-9
    r = scoutsim.simulate(
        passive_robot(),
        None,
        InitialState(y=z[0], theta=z[1], dx=z[2], dy=0.0, dtheta=z[3]),
        2.0,
        model="passive",
        passive_touchdown_angles=pronk.touchdown_angles,
    )
    assert r.outcome == "completed"
    td_b, td_f = r.event_times("touchdown", "back"), r.event_times("touchdown", "front")
    assert len(td_b) == len(td_f) >= 5
    assert np.max(np.abs(td_b - td_f)) < 1e-9
    assert audit_transitions(r).problems() == []


@pytest.mark.parametrize("model", ["I", "II"])
def test_pinned_toe_stays_inside_the_friction_cone_on_a_coulomb_floor(model):
    """Coulomb's law in stance: a pinned toe never needs more than mu F_n (checked at every
    accepted step by max_friction_ratio), including a toe that sticks again on the edge
    of the cone after a slide (its stick -> slip event must be armed there)."""
    mu = 1.0
    r = scoutsim.simulate(duration=10.0, model=model, friction_coefficient=mu)
    assert r.event_times("slide_start").size > 0 and r.event_times("stick").size > 0
    assert r.stats["max_friction_ratio"] <= mu * (1.0 + 1e-6)
