"""The telescopic leg's force and the Model II belt's torque checked on real runs, at every
recorded sample, against the laws of docs/specification.md sections 2 and 5 written out
here (not the package's functions), with every effect beyond the paper's models on (the
angle-dependent leg damper, the leg's sliding-joint friction with its side-load part, the
belt's backlash): a wrong sign or factor in the leg damper, its angle dependence, the leg
friction, the belt damper or the belt's dead zone fails the test aimed at it.

The work-energy balance (tests/analysis/test_energy.py) cannot stand in for these: it
books each dissipation from the force as it acted, so a wrong damper or friction law can
move energy between its terms and still close (a doubled angle dependence of the leg
damper, or a belt without its dead zone, passes every other physics test; docs/testing.md,
"Mutation study").

The leg length rate is not recorded; it is computed here from the recorded state by the
kinematics of a toe on the ground (section 1): the hip at (x, y) + s_L (cos theta,
sin theta), s_L = -+ half the hip spacing (back, front), the leg from the hip to the toe
along (sin g, -cos g), g = theta + phi."""

from __future__ import annotations

import numpy as np
import pytest

import scoutsim
from scoutsim._core.model import layout as L
from scoutsim.validation.make_example import VIRTUAL_SCOUT_EFFECTS

#: Table III plus every effect beyond the paper's models
ROBOT = scoutsim.RobotParameters().replace(**VIRTUAL_SCOUT_EFFECTS)
#: the speed [m/s] over which the leg's Coulomb friction is regularised
#: (``RobotParameters.leg_friction_force``: linear below 1 mm/s)
LEG_FRICTION_SPEED = 1e-3
#: measured agreement: 6e-13 N of forces up to 490 N, exact for the belt torque
REL_TOL = 1e-10


@pytest.fixture(scope="module")
def runs():
    """3 s of Model I and Model II bounding on the default (Coulomb) floor with every
    effect beyond the paper's models on."""
    return {m: scoutsim.simulate(ROBOT, duration=3.0, model=m) for m in ("I", "II")}


def _leg_kinematics(r, k):
    """Leg angle phi, rate of the leg angle from the vertical dg, leg length l and its rate
    l' of leg ``k`` at every sample, l' from the hip's velocity: a pinned toe (stick) sees
    the hip move along the leg, l' = -(v_hip . u); a sliding toe stays on the ground,
    l = y_hip / cos g, so l' = y_hip' / cos g + y_hip sin g g' / cos^2 g."""
    s = r.state
    side = (2 * k - 1) * 0.5 * ROBOT.hip_spacing
    th, dth = s[:, L.ITH], s[:, L.NQ + L.ITH]
    phi = s[:, 3 + k]
    g = th + phi
    dg = dth + s[:, L.NQ + 3 + k]
    hy = s[:, L.IY] + side * np.sin(th)
    hvx = s[:, L.NQ + 0] - side * np.sin(th) * dth
    hvy = s[:, L.NQ + L.IY] + side * np.cos(th) * dth
    ld_pinned = -(hvx * np.sin(g) - hvy * np.cos(g))
    ld_sliding = hvy / np.cos(g) + hy * np.sin(g) * dg / np.cos(g) ** 2
    mode = r.modes[:, L.RM_CONTACT_B + k]
    ld = np.where(mode == L.SLIDE, ld_sliding, ld_pinned)
    return phi, s[:, L.IL_B + k], ld, mode


@pytest.mark.parametrize("model", ["I", "II"])
def test_axial_leg_force_is_spring_damper_and_friction(runs, model):
    """Section 2, per virtual leg (n_p legs): F = n_p [k (l0 - l) - c (1 + a phi^2) l'
    - F_f sat(l' / v_f)], the leg friction level F_f = F_0 + c_s |tau_hip| / l from the
    torque the hip applies to the leg (the belt torque in Model II, the delivered torque
    otherwise), at every sample with a pinned (stick) or sliding toe; and each part is
    exercised: the damper, its angle dependence and the friction each change the force by
    newtons."""
    r = runs[model]
    npl = ROBOT.legs_per_virtual_leg
    n = 0
    for k, leg in enumerate(L.LEG_NAMES):
        phi, ll, ld, mode = _leg_kinematics(r, k)
        loaded = (mode == L.STICK) | (mode == L.SLIDE)
        tau_hip = (
            r.aux[:, k * L.NAUX_LEG + L.A_TAU_BELT] if model == "II" else r.hip_torque_applied(leg)
        )
        spring = ROBOT.leg_stiffness * (ROBOT.leg_rest_length - ll)
        damper = ROBOT.leg_damping * ld
        angle = ROBOT.leg_damping * ROBOT.leg_damping_angle_coefficient * phi**2 * ld
        level = (
            ROBOT.leg_friction_force
            + ROBOT.leg_friction_side_load_coefficient * np.abs(tau_hip) / ll
        )
        friction = level * np.clip(ld / LEG_FRICTION_SPEED, -1.0, 1.0)
        expected = npl * (spring - damper - angle - friction)
        f = np.asarray(r.leg_axial_force(leg))
        scale = np.max(np.abs(expected[loaded]))
        assert np.allclose(f[loaded], expected[loaded], rtol=0.0, atol=REL_TOL * scale)
        for part in (damper, angle, friction):
            assert np.max(np.abs(npl * part[loaded])) > 2.0
        # the side-load part of the friction acts too
        assert (
            np.max(
                npl
                * ROBOT.leg_friction_side_load_coefficient
                * np.abs(tau_hip[loaded])
                / ll[loaded]
            )
            > 1.0
        )
        n += loaded.sum()
    assert n > 1000


def test_belt_torque_is_spring_with_dead_zone_and_damper(runs):
    """Section 5, Model II, per physical leg: tau_b = k_b dz(alpha - phi) + c_b (alpha' -
    phi'), dz the belt's dead zone of width b (the backlash): 0 for |delta| <= b / 2,
    delta -+ b / 2 beyond; at every sample, with samples inside the dead zone and beyond
    it, and a damper part of newton-metres."""
    r = runs["II"]
    s = r.state
    h = 0.5 * ROBOT.belt_backlash
    for k in range(len(L.LEG_NAMES)):
        delta = s[:, 5 + k] - s[:, 3 + k]
        rate = s[:, L.NQ + 5 + k] - s[:, L.NQ + 3 + k]
        dz = np.where(delta > h, delta - h, np.where(delta < -h, delta + h, 0.0))
        spring = ROBOT.belt_stiffness * dz
        damper = ROBOT.belt_damping * rate
        tb = r.aux[:, k * L.NAUX_LEG + L.A_TAU_BELT]
        scale = np.max(np.abs(tb))
        assert np.allclose(tb, spring + damper, rtol=0.0, atol=REL_TOL * scale)
        inside = np.abs(delta) < h
        assert 0.05 < inside.mean() < 0.95
        # beyond the dead zone the spring carries the torque; inside it, only the damper
        assert np.max(np.abs(spring[~inside])) > 0.5
        assert np.max(np.abs(damper)) > 1.0
        assert np.max(np.abs(ROBOT.belt_stiffness * delta[inside])) > 1.0
