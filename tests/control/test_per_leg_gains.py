"""The Table I controller applies each leg's own gains and angles (docs/specification.md
section 6): with every per-leg value different, each leg's command is its own law, so a
gain or angle read from the other leg fails here."""

from __future__ import annotations

import numpy as np
import pytest

from scoutsim._core.model import layout as L
from scoutsim.control.bounding import bounding_step, controller_array
from scoutsim.parameters import ControllerParameters, RobotParameters

PARAMS = ControllerParameters().replace(
    touchdown_angle_back=0.31,
    touchdown_angle_front=0.37,
    sweep_limit_back=-0.05,
    sweep_limit_front=0.02,
    flight_kp_back=210.0,
    flight_kd_back=3.0,
    flight_kp_front=270.0,
    flight_kd_front=7.0,
    brake_kp_back=330.0,
    brake_kd_back=4.0,
    brake_kp_front=290.0,
    brake_kd_front=6.0,
)


def _step(angles, rates, compression, states):
    robot = RobotParameters()
    C = controller_array(PARAMS, robot)
    y = np.zeros(L.NSN)
    for leg in range(2):
        y[L.SN_ANGLE_B + leg] = angles[leg]
        y[L.SN_RATE_B + leg] = rates[leg]
        y[L.SN_LENGTH_B + leg] = robot.leg_rest_length - compression[leg]
    ls = np.array(states, dtype=np.int64)
    cmd = np.zeros(2)
    tr = np.zeros(2, dtype=np.int64)
    bounding_step(y, C, ls, cmd, tr)
    return cmd, ls


def test_flight_servo_uses_each_legs_gains_and_touchdown_angle():
    """Flight: tau = kp (phi_td - phi) - kd dphi, per leg."""
    angles, rates = (0.1, -0.2), (1.5, -2.5)
    cmd, ls = _step(angles, rates, (0.0, 0.0), (L.LS_FLIGHT, L.LS_FLIGHT))
    assert list(ls) == [L.LS_FLIGHT, L.LS_FLIGHT]
    assert cmd[L.BACK] == pytest.approx(210.0 * (0.31 - 0.1) - 3.0 * 1.5, rel=1e-14)
    assert cmd[L.FRONT] == pytest.approx(270.0 * (0.37 + 0.2) - 7.0 * (-2.5), rel=1e-14)


def test_stance_brake_uses_each_legs_gains_and_sweep_limit():
    """Stance-brake: tau = kp_b (phi_sweep - phi) - kd_b dphi, per leg (legs compressed
    well beyond the lift-off threshold, so they stay in stance)."""
    angles, rates = (-0.12, -0.04), (-0.8, 0.6)
    cmd, ls = _step(angles, rates, (0.03, 0.03), (L.LS_BRAKE, L.LS_BRAKE))
    assert list(ls) == [L.LS_BRAKE, L.LS_BRAKE]
    assert cmd[L.BACK] == pytest.approx(330.0 * (-0.05 + 0.12) - 4.0 * (-0.8), rel=1e-14)
    assert cmd[L.FRONT] == pytest.approx(290.0 * (0.02 + 0.04) - 6.0 * 0.6, rel=1e-14)


def test_sweep_limit_is_each_legs_own():
    """Stance-retraction -> stance-brake when phi passes the leg's own sweep limit: at
    phi = -0.03 the back leg (limit -0.05) keeps retracting, the front (limit 0.02) brakes."""
    cmd, ls = _step((-0.03, -0.03), (-1.0, -1.0), (0.03, 0.03), (L.LS_RETRACTION, L.LS_RETRACTION))
    assert ls[L.BACK] == L.LS_RETRACTION
    assert ls[L.FRONT] == L.LS_BRAKE
