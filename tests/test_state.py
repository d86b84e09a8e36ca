"""The standing state (scoutsim.state.standing_state): a static equilibrium of the robot on
its four legs, checked against the model's own evaluation and against a hand computation
from Table III, and held by the stance-brake law in every actuated model."""

import dataclasses
import math

import numpy as np
import pytest

import scoutsim
from scoutsim import RobotParameters, standing_state
from scoutsim._core.model import layout as L
from scoutsim._core.model.evaluate import evaluate
from scoutsim._core.model.packing import robot_array
from scoutsim.state import standing_leg_compression

MODELS = ("ideal", "I", "II")
G = 9.81


def _modes(h):
    return h.mode_arrays()


def test_standing_leg_compression_is_half_the_weight_over_the_virtual_spring():
    # Table III: torso 20.865 kg, four legs of 0.97 kg, k = 3520 N/m per physical leg, two
    # physical legs per virtual leg: each virtual leg carries half of m g on 2 k
    m = 20.865 + 4 * 0.97
    assert standing_leg_compression() == pytest.approx(m * G / 2 / (2 * 3520.0), rel=1e-12)
    assert standing_leg_compression() == pytest.approx(0.01724, abs=1e-5)


def test_standing_state_geometry_toes_below_the_hips_torso_level_at_rest():
    h = standing_state(x=0.5)
    s = np.array(h.state)
    length = 0.323 - standing_leg_compression()
    assert s[L.IY] == pytest.approx(length, abs=1e-15)  # hips at the COM's height
    assert s[L.IL_B] == s[L.IL_F] == pytest.approx(length, abs=1e-15)
    assert s[L.ITH] == s[L.IPHB] == s[L.IPHF] == s[L.IALB] == s[L.IALF] == 0.0
    assert np.all(s[L.NQ : 2 * L.NQ] == 0.0)
    assert h.toe_anchors == pytest.approx((0.5 - 0.552 / 2, 0.5 + 0.552 / 2), abs=1e-15)
    assert h.contact_modes == (L.STICK, L.STICK)
    assert h.leg_states == (L.LS_BRAKE, L.LS_BRAKE)


@pytest.mark.parametrize("model", MODELS)
def test_standing_state_is_a_static_equilibrium_zero_accelerations_and_half_weight_per_leg(model):
    robot = RobotParameters()
    h = standing_state(robot, model)
    P = robot_array(robot, model, friction_coefficient=1.0)
    mi, mf = _modes(h)
    ds = np.zeros(L.NS)
    aux = np.zeros(L.NAUX)
    evaluate(np.array(h.state), P, mi, mf, np.zeros(2), ds, aux)
    # net force and moment zero: every acceleration (torso, legs, gears) ~ 0
    assert np.max(np.abs(ds[L.NQ : 2 * L.NQ])) < 1e-9
    # each toe carries half the weight, no tangential force (the hips hold no torque)
    m = 20.865 + 4 * 0.97
    for leg in range(2):
        assert aux[leg * L.NAUX_LEG + L.A_GN] == pytest.approx(m * G / 2, rel=1e-9)
        assert abs(aux[leg * L.NAUX_LEG + L.A_GT]) < 1e-9
        assert abs(aux[leg * L.NAUX_LEG + L.A_BELT]) == 0.0


@pytest.mark.parametrize("model", MODELS)
def test_standing_robot_held_by_the_stance_brake_stays_put_for_two_seconds(model):
    # resumed from the standing state, the Table I controller stays in stance-brake about
    # its sweep limit (the standing angle): nothing moves
    h = standing_state(model=model)
    r = scoutsim.simulate(None, None, h, 2.0, model=model)
    assert r.outcome == "completed"
    assert np.max(np.abs(r.state[:, L.NQ : 2 * L.NQ])) < 1e-9  # velocities
    assert np.max(np.abs(r.state[-1] - np.array(h.state))) < 1e-9  # drift [m, rad]
    assert np.all(r.leg_state("back") == L.LS_BRAKE)
    assert np.all(r.contact_mode("front") == L.STICK)
    if model == "II":  # the motor joints stay stuck by their stiction
        assert np.all(r.modes[:, L.RM_MOTOR_B : L.RM_MOTOR_B + 2] == L.STUCK)


def test_standing_robot_pushed_gently_recovers_and_stays_standing():
    # a 5 cm/s shove forward: the stance-brake PD (Table I gains) keeps it standing, its
    # toes stuck, and the motion dies away
    h = standing_state(model="I")
    s = list(h.state)
    s[L.NQ + L.IX] = 0.05
    r = scoutsim.simulate(None, None, dataclasses.replace(h, state=tuple(s)), 2.0, model="I")
    assert r.outcome == "completed"
    assert np.max(np.abs(r.state[-1, L.NQ : 2 * L.NQ])) < 0.005
    assert np.max(np.abs(np.degrees(r.pitch))) < 1.0
    for leg in ("back", "front"):
        assert np.all(r.leg_state(leg) == L.LS_BRAKE)
        assert np.all(r.contact_mode(leg) == L.STICK)


def test_standing_state_refuses_the_passive_model_and_too_soft_or_too_stiff_legs():
    with pytest.raises(ValueError, match="model = 'passive'"):
        standing_state(model="passive")
    with pytest.raises(ValueError, match="robot.leg_stiffness"):
        standing_state(RobotParameters().replace(leg_stiffness=100.0))
    with pytest.raises(ValueError, match="controller.touchdown_compression"):
        standing_state(
            controller=scoutsim.ControllerParameters().replace(
                touchdown_compression=0.02, liftoff_compression=0.015
            )
        )
    with pytest.raises(ValueError, match="x = "):
        standing_state(x=math.nan)


def test_state_vector_sets_components_by_name():
    """state_vector puts each named component in its slot of the layout (the rest zero);
    state_index finds it; an unknown name is refused."""
    from scoutsim.state import STATE_NAMES, state_index, state_vector

    assert STATE_NAMES == L.STATE_NAMES
    s = state_vector(y=0.4, dtheta=1.5, phi_front=-0.2, leg_length_back=0.3)
    expected = np.zeros(L.NS)
    expected[[L.IY, L.NQ + L.ITH, L.IPHF, L.IL_B]] = (0.4, 1.5, -0.2, 0.3)
    np.testing.assert_array_equal(s, expected)
    assert [state_index(n) for n in STATE_NAMES] == list(range(L.NS))
    with pytest.raises(ValueError, match="height"):
        state_vector(height=0.4)
