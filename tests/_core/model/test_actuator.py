"""Torque-dependent transmission efficiency (docs/model.md "Transmission losses").

The gearbox loses tau_loss = tau_idle + c_load |tau_out| (leg side, per physical leg),
opposing the power flow. With both zero the constant efficiency N eta K_T i is recovered
bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest

from scoutsim._core.model import actuator
from scoutsim._core.model.packing import robot_array
from scoutsim.parameters import ParameterError, RobotParameters, load_robot
from scoutsim.simulation.simulator import simulate

IDLE = 0.5
CLOAD = 0.05


@pytest.fixture(scope="module")
def lossy_run():
    robot = load_robot(
        overrides={"gearbox_idle_loss_torque": IDLE, "gearbox_load_loss_coefficient": CLOAD}
    )
    return robot, simulate(robot, duration=0.5, model="I")


def test_defaults_are_zero():
    robot = load_robot()
    assert robot.gearbox_idle_loss_torque == 0.0
    assert robot.gearbox_load_loss_coefficient == 0.0
    assert RobotParameters().gearbox_idle_loss_torque == 0.0


def test_zero_losses_reproduce_constant_efficiency_bit_for_bit():
    base = simulate(load_robot(), duration=0.5, model="I")
    zero = simulate(
        load_robot(
            overrides={"gearbox_idle_loss_torque": 0.0, "gearbox_load_loss_coefficient": 0.0}
        ),
        duration=0.5,
        model="I",
    )
    assert base.state.shape == zero.state.shape
    assert np.array_equal(base.state, zero.state)
    robot = load_robot()
    for leg in ("back", "front"):
        i = base.motor_current(leg)
        np.testing.assert_array_equal(
            base.hip_torque_applied(leg),
            robot.gear_ratio * robot.efficiency * robot.torque_constant * i,
        )


def test_delivered_torque_function_directions():
    robot = load_robot(
        overrides={"gearbox_idle_loss_torque": IDLE, "gearbox_load_loss_coefficient": CLOAD}
    )
    P = robot_array(robot, "I")
    k0 = robot.gear_ratio * robot.efficiency * robot.torque_constant
    for cur in (-3.0, -0.1, 0.1, 3.0):
        tau0 = k0 * cur
        s = np.sign(cur)
        # motoring: reduced, never reversed
        tm = actuator.delivered_torque(cur, 50.0 * s, 0, P)
        assert tm == pytest.approx(s * max(abs(tau0) - IDLE, 0.0) / (1 + CLOAD))
        assert abs(tm) <= abs(tau0) and tm * tau0 >= 0.0
        # back-driven: the leg must supply more than the constant-efficiency torque
        tb = actuator.delivered_torque(cur, -50.0 * s, 0, P)
        assert tb == pytest.approx((tau0 + s * IDLE) / (1 - CLOAD))
        loss = IDLE + CLOAD * abs(tb)
        assert abs(tb) - abs(tau0) == pytest.approx(loss)
    # unpowered, output turning: pure idle friction opposing the motion
    assert actuator.delivered_torque(0.0, 50.0, 0, P) == pytest.approx(-IDLE / (1 - CLOAD))
    assert actuator.delivered_torque(0.0, 0.0, 0, P) == 0.0


def test_losses_reduce_delivered_torque_in_motoring_samples(lossy_run):
    robot, res = lossy_run
    k0 = robot.gear_ratio * robot.efficiency * robot.torque_constant
    checked = 0
    for leg in ("back", "front"):
        tau = res.hip_torque_applied(leg)
        tau0 = k0 * res.motor_current(leg)
        om = res.motor_speed(leg)
        motoring = (tau0 * om > 0) & (np.abs(om) >= actuator.LOSS_SPEED_REG)
        assert motoring.sum() > 10
        assert np.all(np.abs(tau[motoring]) <= np.abs(tau0[motoring]) + 1e-12)
        unclipped = motoring & (np.abs(tau0) > IDLE + 1e-9)
        diff = np.abs(tau0[unclipped]) - np.abs(tau[unclipped])
        np.testing.assert_allclose(
            diff, IDLE + CLOAD * np.abs(tau[unclipped]), rtol=1e-9, atol=1e-12
        )
        clipped = motoring & (np.abs(tau0) <= IDLE)
        assert np.all(tau[clipped] == 0.0)
        checked += unclipped.sum()
    assert checked > 10


def test_efficiency_falls_at_low_torque(lossy_run):
    robot, res = lossy_run
    k = robot.gear_ratio * robot.torque_constant
    cur = np.concatenate([res.motor_current(l) for l in ("back", "front")])
    tau = np.concatenate([res.hip_torque_applied(l) for l in ("back", "front")])
    om = np.concatenate([res.motor_speed(l) for l in ("back", "front")])
    motoring = (cur * om > 0) & (np.abs(om) >= actuator.LOSS_SPEED_REG)
    a = np.abs(cur[motoring])
    eff = np.abs(tau[motoring]) / (k * a)
    low = a < 1.0
    high = a > 4.0
    assert low.sum() > 3 and high.sum() > 3
    assert eff[low].mean() < eff[high].mean() < robot.efficiency
    # the efficiency curve is monotone in |i| (at fixed tau_idle, c_load)
    order = np.argsort(a)
    assert np.all(np.diff(eff[order]) >= -1e-12)


@pytest.mark.parametrize(
    "name,value",
    [
        ("gearbox_idle_loss_torque", -0.1),
        ("gearbox_load_loss_coefficient", -0.01),
        ("gearbox_load_loss_coefficient", 1.0),
        ("gearbox_idle_loss_torque", float("inf")),
    ],
)
def test_validation_refuses_bad_loss_values(name, value):
    with pytest.raises(ParameterError, match=name) as err:
        load_robot(overrides={name: value})
    assert err.value.field == name
