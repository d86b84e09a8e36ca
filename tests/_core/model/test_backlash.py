"""The belt with backlash (scoutsim._core.model.backlash): which robots run on it, and its
consistency.

Laws checked: a robot's hip unit follows its model and play (the belt with backlash for
Model II when either leg has play, the belt without, the rigid unit in the other models,
whatever the play); the stiff part
of the Jacobian that the ARK methods treat implicitly is the derivative of the dynamics
with respect to the gear angle, inside the play (where the spring is slack: zero) as
outside it (finite differences); the belt is rigid over a touchdown impact inside the play
too (the damper acts across it); a run on the backlash unit closes its energy balance
(also ``tests/analysis/test_energy.py``, whose every-option robot has play).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import scoutsim
from scoutsim._core.model import evaluate as D
from scoutsim._core.model import hip_unit
from scoutsim._core.model import layout as L
from scoutsim._core.model import workspace as W
from scoutsim._core.model.packing import robot_array
from scoutsim.simulation.integrator import IntegratorSettings

PLAY = math.radians(2.0)
BACKLASH_ROBOT = scoutsim.RobotParameters(belt_backlash=PLAY)


@pytest.mark.parametrize(
    "model,robot,unit",
    [
        ("II", scoutsim.RobotParameters(), "belt"),
        ("II", BACKLASH_ROBOT, "belt with backlash"),
        ("II", scoutsim.RobotParameters(belt_backlash=(0.0, PLAY)), "belt with backlash"),
        ("I", BACKLASH_ROBOT, "rigid"),
        ("ideal", BACKLASH_ROBOT, "rigid"),
        ("passive", BACKLASH_ROBOT, "rigid"),
    ],
)
def test_the_hip_unit_follows_the_model_and_the_play(model, robot, unit):
    assert hip_unit.NAMES[int(robot_array(robot, model)[L.P_HIP_UNIT])] == unit


def _state_in_stance(robot):
    """A Model II state of a short run with the back toe pinned, and its modes."""
    r = scoutsim.simulate(robot, duration=0.5, model="II", friction_coefficient=math.inf)
    k = int(np.argmax(r.modes[:, L.RM_CONTACT_B] == L.STICK)) + 5
    mi = np.zeros(L.NMI, dtype=np.int64)
    mi[L.MI_CONTACT_B : L.MI_CONTACT_B + 2] = r.modes[k, L.RM_CONTACT_B : L.RM_CONTACT_B + 2]
    mi[L.MI_MOTOR_B : L.MI_MOTOR_B + 2] = L.SLIP_POS
    mf = np.array([r.aux[k, leg * L.NAUX_LEG + L.A_TOE_X] for leg in range(2)])
    cmd = np.array([r.aux[k, L.A_TAU_CMD], r.aux[k, L.NAUX_LEG + L.A_TAU_CMD]])
    return r.state[k].copy(), mi, mf, cmd


@pytest.mark.parametrize("where", ["inside the play", "beyond the play"])
def test_stiff_factor_is_the_jacobian_of_the_belt_spring(where):
    """The stiff factorization's column of the gear angle alpha_back equals the central
    difference of the dynamics with respect to alpha_back (the belt spring is the only
    force that depends on it): zero inside the play, -n G w k_b beyond it."""
    P = robot_array(BACKLASH_ROBOT, "II", friction_coefficient=math.inf)
    s, mi, mf, cmd = _state_in_stance(BACKLASH_ROBOT)
    delta = 0.25 * PLAY if where == "inside the play" else 2.0 * PLAY
    s[L.IALB] = s[L.IPHB] + delta
    wk, wA, piv = W.new_eval_workspace()
    st = np.zeros((L.NS, 2 * D.NSTIFF))
    f0 = np.zeros(L.NS)
    aux = np.zeros(L.NAUX)
    D.evaluate_ws(s, P, mi, mf, cmd, f0, aux, (wk, wA, piv, st), True, st, True)
    Js = st[:, : D.NSTIFF] @ st[:, D.NSTIFF :].T
    e = 1e-7
    dp, dm = np.zeros(L.NS), np.zeros(L.NS)
    sp, sm = s.copy(), s.copy()
    sp[L.IALB] += e
    sm[L.IALB] -= e
    D.evaluate(sp, P, mi, mf, cmd, dp, aux)
    D.evaluate(sm, P, mi, mf, cmd, dm, aux)
    fd = (dp - dm) / (2 * e)
    scale = np.max(np.abs(fd)) if where == "beyond the play" else 1.0
    if where == "beyond the play":
        assert scale > 100.0  # the spring is felt: k_b over the gear train
    np.testing.assert_allclose(Js[:, L.IALB], fd, rtol=0, atol=1e-5 * scale)


def test_the_belt_is_rigid_over_an_impact_inside_the_play():
    """A touchdown with the belt slack: after the impact the gear turns with the leg."""
    r = scoutsim.simulate(BACKLASH_ROBOT, duration=1.0, model="II", friction_coefficient=math.inf)
    states = r.event_states
    rows = np.flatnonzero(r.events[:, L.EVR_KIND] == L.EK_TOUCHDOWN)
    assert len(rows) >= 2
    slack_seen = False
    for i in rows:
        leg = int(r.events[i, L.EVR_LEG])
        before, after = states[i, 0], states[i, 1]
        slack_seen |= abs(before[L.IALB + leg] - before[L.IPHB + leg]) < 0.5 * PLAY
        assert after[L.NQ + L.IALB + leg] == pytest.approx(after[L.NQ + L.IPHB + leg], abs=1e-9)
    assert slack_seen


def test_balance_closes_on_the_backlash_unit():
    r = scoutsim.simulate(
        BACKLASH_ROBOT,
        duration=4.0,
        model="II",
        energy=True,
        integrator=IntegratorSettings(method="dopri5"),
    )
    assert r.outcome == "completed"
    b = r.energy_balance()
    assert abs(b.relative_residual) < 1e-6, b.table()
