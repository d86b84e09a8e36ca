"""Each law of the plant checked on a real run, at every recorded sample, against the
formula of docs/specification.md written out here (not the package's functions): the
amplifier's current (the motor's torque-speed line with its back-EMF sign, the current
limit), the delivered torque, a sliding toe's friction, the motor joint's Coulomb friction
and its stiction breakaway. A wrong sign or factor in one of them fails the test aimed at
it, whatever the gait does."""

from __future__ import annotations

import numpy as np
import pytest

import scoutsim
from scoutsim._core.model import layout as L

ROBOT = scoutsim.RobotParameters()
N = ROBOT.planetary_ratio * ROBOT.sprocket_ratio
ETA = ROBOT.gearbox_efficiency * ROBOT.sprocket_efficiency
TORQUE_PER_AMP = N * ETA * ROBOT.torque_constant


@pytest.fixture(scope="module")
def runs():
    """3 s of Model I and Model II bounding on the default (Coulomb) floor, and Model I
    with a battery resistance (the voltage then sags with the current drawn)."""
    return {
        "I": scoutsim.simulate(duration=3.0, model="I"),
        "II": scoutsim.simulate(duration=3.0, model="II"),
        "I_battery": scoutsim.simulate(
            ROBOT.replace(battery_resistance=0.2), duration=3.0, model="I"
        ),
    }


def _current_law(tau_cmd, w, vb, robot):
    """Section 4: i = tau / (N eta K_T), limited to |i| <= i_max and to the torque-speed
    line (-V_b - K_w w) / R_A <= i <= (V_b - K_w w) / R_A."""
    i = tau_cmd / TORQUE_PER_AMP
    lo = np.maximum(
        -robot.current_limit, (-vb - robot.speed_constant * w) / robot.armature_resistance
    )
    hi = np.minimum(
        robot.current_limit, (vb - robot.speed_constant * w) / robot.armature_resistance
    )
    return np.clip(i, lo, hi), lo, hi


@pytest.mark.parametrize("name", ["I", "II", "I_battery"])
def test_amplifier_current_follows_the_torque_speed_line_and_the_limit(runs, name):
    """The motor current at every sample is the commanded current clipped to the current
    limit and to the torque-speed line of the motor at its speed (the back-EMF K_w w_m
    *reduces* the current the battery voltage can push in the direction of motion), and
    the run exercises both limits and the unclipped command."""
    r = runs[name]
    robot = ROBOT.replace(battery_resistance=0.2) if name == "I_battery" else ROBOT
    vb = r.battery_voltage
    for leg in L.LEG_NAMES:
        i = r.motor_current(leg)
        w = r.motor_speed(leg)
        expected, lo, hi = _current_law(r.hip_torque_commanded(leg), w, vb, robot)
        assert np.allclose(i, expected, rtol=1e-12, atol=1e-9)
        at_line = (np.isclose(i, lo) & (lo > -robot.current_limit)) | (
            np.isclose(i, hi) & (hi < robot.current_limit)
        )
        at_limit = np.isclose(np.abs(i), robot.current_limit)
        assert at_line.mean() > 0.05 and at_limit.mean() > 0.05
        assert (~at_line & ~at_limit).mean() > 0.05


def test_battery_voltage_sags_with_the_power_drawn(runs):
    """Section 4: V_b = V_oc - R_b I_b, the battery current I_b = P / V_b carrying the
    power P = sum over the four motors of i (R_A i + K_w w_m)."""
    r = runs["I_battery"]
    p = sum(
        ROBOT.legs_per_virtual_leg
        * r.motor_current(leg)
        * (
            ROBOT.armature_resistance * r.motor_current(leg)
            + ROBOT.speed_constant * r.motor_speed(leg)
        )
        for leg in L.LEG_NAMES
    )
    vb = r.battery_voltage
    assert np.allclose(vb, ROBOT.battery_voltage - 0.2 * p / vb, rtol=1e-9, atol=1e-9)
    assert vb.min() < ROBOT.battery_voltage - 1.0  # it does sag


@pytest.mark.parametrize("name", ["I", "II"])
def test_delivered_torque_is_n_eta_kt_i(runs, name):
    """Without the optional transmission losses the hip unit delivers N eta K_T i (the
    paper's constant maximum efficiency), in both directions of power flow."""
    r = runs[name]
    for leg in L.LEG_NAMES:
        assert np.allclose(
            r.hip_torque_applied(leg), TORQUE_PER_AMP * r.motor_current(leg), rtol=1e-12, atol=1e-12
        )


def test_sliding_toe_friction_opposes_its_motion(runs):
    """Coulomb floor: a sliding toe's ground force has tangential part mu F_n against the
    toe's velocity (section 3)."""
    mu = scoutsim.parameters.DEFAULT_FRICTION_COEFFICIENT
    n = 0
    for r in runs.values():
        for k in range(len(L.LEG_NAMES)):
            slide = r.modes[:, L.RM_CONTACT_B + k] == L.SLIDE
            v = r.aux[:, k * L.NAUX_LEG + L.A_SLIP_V][slide]
            ft = r.aux[:, k * L.NAUX_LEG + L.A_GT][slide]
            fn = r.aux[:, k * L.NAUX_LEG + L.A_GN][slide]
            moving = np.abs(v) > 1e-6
            assert np.all(fn[moving] > 0.0)
            assert np.allclose(ft[moving], -mu * np.sign(v[moving]) * fn[moving], rtol=1e-9)
            n += moving.sum()
    assert n > 100


def test_slipping_motor_joint_friction(runs):
    """Model II, a slipping motor joint: friction torque b_J w_m + tau_s sign(w_m) at the
    motor, opposing its motion (section 5)."""
    r = runs["II"]
    n = 0
    for k, leg in enumerate(L.LEG_NAMES):
        mode = r.modes[:, L.RM_MOTOR_B + k]
        w = r.motor_speed(leg)
        tf = r.aux[:, k * L.NAUX_LEG + L.A_HOLD]
        slip = (mode != L.STUCK) & (np.abs(w) > 1e-6)
        expected = ROBOT.joint_damping * w + ROBOT.joint_stiction * np.sign(w)
        assert np.allclose(tf[slip], expected[slip], rtol=1e-12, atol=1e-15)
        n += slip.sum()
    assert n > 100


def test_stiction_breaks_away_at_its_level():
    """Model II, a stuck motor joint breaks away when the torque needed to hold it
    reaches tau_s (section 5): every breakaway located between two samples happens with
    |holding torque| = tau_s (a breakaway found at a sample, after a new command, with
    more). Tested with a stiction 20 times Table II's so that joints do stick and break
    away during bounding."""
    robot = ROBOT.replace(joint_stiction=20 * ROBOT.joint_stiction)
    r = scoutsim.simulate(robot, duration=3.0, model="II")
    ev = r.events[r.events[:, L.EVR_KIND] == L.EK_MOTOR_SLIP]
    dt = r.provenance["control_period_s"]
    on_sample = np.abs(ev[:, L.EVR_T] / dt - np.round(ev[:, L.EVR_T] / dt)) < 1e-6
    hold = np.abs(ev[:, L.EVR_V1])
    tau_s = robot.joint_stiction
    assert (~on_sample).sum() >= 5
    assert np.allclose(hold[~on_sample], tau_s, rtol=1e-6)
    # (a located breakaway that happened to fall on a sample holds tau_s to 1e-6 as well)
    assert np.all(hold[on_sample] >= tau_s * (1.0 - 1e-6))


def test_motor_current_is_odd_beyond_both_limits():
    """A motor back-driven beyond the speed at which its back-EMF exceeds V_b + R_A i_max
    carries the torque-speed line's current even beyond i_max (the amplifier applies at
    most the battery voltage against it), in either direction: the law is odd in
    (command, speed), i(-tau, -w) = -i(tau, w), at every command and speed."""
    from scoutsim._core.model.actuator import motor_current
    from scoutsim._core.model.packing import robot_array

    P = robot_array(ROBOT, "I")
    vb = ROBOT.battery_voltage
    w_edge = (vb + ROBOT.armature_resistance * ROBOT.current_limit) / ROBOT.speed_constant
    for w in (0.0, 300.0, 0.9 * w_edge, 1.1 * w_edge, 3.0 * w_edge):
        for tau in (-80.0, -31.0, -5.0, 0.0, 5.0, 31.0, 80.0):
            i = motor_current(tau, w, vb, 0, P)
            assert motor_current(-tau, -w, vb, 0, P) == -i
            if w > w_edge:  # the line's current, beyond the limit, whatever the command
                assert i == pytest.approx(
                    (vb - ROBOT.speed_constant * w) / ROBOT.armature_resistance, rel=1e-12
                )
                assert i < -ROBOT.current_limit
