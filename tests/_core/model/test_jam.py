"""The jam of a sliding toe (model/contact.py: slide_axial_share, JAM_AXIAL_SHARE;
docs/model.md "A sliding toe that jams"): the share of the slide's ground force along the
leg is the cosine of the angle between that force and the leg axis, so the slide's force
law G_n (cos gamma + sigma sin gamma) = F holds on the evaluated forces; it is zero at the
friction angle, where the leg's normal is the edge of the friction cone."""

import math

import numpy as np

from scoutsim import simulate
from scoutsim._core.model import layout as L
from scoutsim._core.model.contact import JAM_AXIAL_SHARE, slide_axial_share
from scoutsim._core.model.packing import robot_array
from scoutsim.control.protocol import Controller
from scoutsim.parameters import RobotParameters
from scoutsim.state import InitialState


class _Zero(Controller):
    def command(self, t, sensors):
        return (0.0, 0.0)


def test_share_is_the_cosine_between_the_sliding_ground_force_and_the_leg():
    """On every recorded sample of a sliding toe (Model II, zero torques, a start whose
    front toe slides towards the friction angle), the share computed from the leg angle and
    the slide direction equals the cosine of the angle between the evaluated ground force
    (G_t, G_n) and the leg axis, hip - toe; and G_n share sqrt(1 + mu^2) = F."""
    mu = 1.0
    P = robot_array(RobotParameters(), "II", friction_coefficient=mu)
    start = InitialState(y=0.34340258828578274, dx=1.0757281538159045, dtheta=2.0582517952283736)
    r = simulate(
        controller=_Zero(), initial_state=start, duration=0.6, model="II", friction_coefficient=mu
    )
    n = 0
    for k in range(len(r.t)):
        for leg in range(2):
            if r.modes[k, L.RECORDED_MODE_NAMES.index("contact_mode_back") + leg] != L.SLIDE:
                continue
            o = leg * L.NAUX_LEG
            gt, gn, f = r.aux[k, o + L.A_GT], r.aux[k, o + L.A_GN], r.aux[k, o + L.A_FAX]
            if gn < 1.0:
                continue
            direction = -1 if gt > 0.0 else 1  # friction opposes the slide
            g = r.state[k, L.ITH] + r.state[k, L.IPHB + leg]
            share = slide_axial_share(g, direction, P)
            axis = np.array([-math.sin(g), math.cos(g)])  # toe -> hip
            cosine = np.dot([gt, gn], axis) / math.hypot(gt, gn)
            assert abs(share - cosine) <= 1e-9
            assert abs(gn * share * math.sqrt(1.0 + mu * mu) - f) <= 1e-9 * max(1.0, abs(f))
            assert share > JAM_AXIAL_SHARE  # no slide goes on beyond its jam level
            n += 1
    assert n > 20


def test_share_vanishes_at_the_friction_angle_where_the_leg_normal_is_the_cone_edge():
    """At tan gamma = 1 / mu against the slide the share is zero, and the leg's normal
    (cos gamma, sin gamma), the direction of a pinned toe's impulse, lies on the friction
    cone's edge: |t| / n = mu."""
    for mu in (0.6, 1.0, 3.0):
        P = robot_array(RobotParameters(), "II", friction_coefficient=mu)
        for direction in (1, -1):
            g = -direction * math.atan(1.0 / mu)
            assert abs(slide_axial_share(g, direction, P)) <= 1e-12
            normal = (math.cos(g), math.sin(g))
            assert abs(abs(normal[0]) / abs(normal[1]) - mu) <= 1e-12
            # away from the angle, towards the vertical, the share grows
            assert slide_axial_share(0.5 * g, direction, P) > 0.1


def test_work_energy_balance_closes_through_a_jam():
    """Every joule is accounted for across a jam: with the reference integrator (DOPRI5,
    rtol 1e-10) the work-energy balance of a run with a jam (its impact's loss logged like a
    touchdown's) closes to 1e-7 J, as it does for runs without one (docs/model.md
    "Work-energy balance")."""
    from scoutsim.simulation.simulator import IntegratorSettings

    start = InitialState(y=0.34340258828578274, dx=1.0757281538159045, dtheta=2.0582517952283736)
    r = simulate(
        controller=_Zero(),
        initial_state=start,
        duration=0.6,
        model="II",
        friction_coefficient=1.0,
        energy=True,
        integrator=IntegratorSettings(method="dopri5", rtol=1e-10, atol=1e-11),
    )
    jams = r.events[r.events[:, L.EVR_KIND] == L.EK_JAM]
    assert len(jams) >= 1 and jams[0, L.EVR_V3] > 1e-5  # a jam that dissipates
    b = r.energy_balance()
    assert abs(b.residual_J) < 1e-7


#: the random start of the learning environment's reset(seed=107) (Model II): its front
#: toe passes the friction angle while its leg, 0.2 mm short of the stop, carries no force
_PRESSED_START = dict(y=0.3293306570796559, dx=1.2010949527676986, dtheta=3.027769061022595)


def test_toe_pressed_into_the_ground_at_the_friction_angle_stays_pinned():
    """A pinned toe whose friction cone asks for a jammed slide, and which released would
    be pressed into the ground by the motion (its leg carrying no force), stays pinned: the
    jammed contact locks (docs/model.md "A toe pressed into the ground at the friction
    angle"). The lock is the consistent mode, not a stuck one: on every recorded sample
    after it, the pinned front toe's ground force lies inside the friction cone and pushes;
    no transition leaves a mode inconsistent with its forces other than the lock's instant
    itself (the force it needs there lies outside the cone: the rigid idealisation the
    audit names); every jam's impulse dissipates and lies within the cone (to the jam
    level); and the run goes on to the robot's fall instead of a numerical failure."""
    from scoutsim.analysis.transition_audit import audit_transitions

    mu = 1.0
    r = simulate(
        controller=_Zero(),
        initial_state=InitialState(**_PRESSED_START),
        duration=1.0,
        model="II",
        friction_coefficient=mu,
    )
    assert r.outcome == "fell"
    problems = audit_transitions(r).problems()
    assert all(p.endswith("pinned toe outside the friction cone") for p in problems), problems
    assert len(problems) <= 1
    jams = r.events[r.events[:, L.EVR_KIND] == L.EK_JAM]
    assert len(jams) >= 1
    tol = 2.0 * math.sqrt(1.0 + mu * mu) * JAM_AXIAL_SHARE
    assert np.all(jams[:, L.EVR_V1] > 0.0)
    assert np.all(np.abs(jams[:, L.EVR_V2]) <= mu * jams[:, L.EVR_V1] * (1.0 + tol))
    assert np.all(jams[:, L.EVR_V3] >= 0.0)
    # the pinned stretch after the lock: the front toe pinned on consecutive samples
    front = L.RECORDED_MODE_NAMES.index("contact_mode_back") + L.FRONT
    o = L.FRONT * L.NAUX_LEG
    pinned = [k for k in range(len(r.t)) if r.modes[k, front] == L.STICK and r.t[k] > 0.45]
    assert len(pinned) >= 10
    for k in pinned:
        gt, gn = r.aux[k, o + L.A_GT], r.aux[k, o + L.A_GN]
        assert gn > 0.0
        assert abs(gt) <= mu * gn


def test_work_energy_balance_closes_through_a_locked_jam():
    """Every joule is accounted for through the lock and the jams that follow it (the
    start above; DOPRI5 at rtol 1e-10): the residual of the work-energy balance stays below
    1e-7 J, as for runs without a jam."""
    from scoutsim.simulation.simulator import IntegratorSettings

    r = simulate(
        controller=_Zero(),
        initial_state=InitialState(**_PRESSED_START),
        duration=1.0,
        model="II",
        friction_coefficient=1.0,
        energy=True,
        integrator=IntegratorSettings(method="dopri5", rtol=1e-10, atol=1e-11),
    )
    assert r.outcome == "fell"
    jams = r.events[r.events[:, L.EVR_KIND] == L.EK_JAM]
    assert len(jams) >= 2 and jams[:, L.EVR_V3].sum() > 1e-2
    assert abs(r.energy_balance().residual_J) < 1e-7
