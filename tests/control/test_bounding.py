"""The Table I bounding controller, tested directly (paper Sec. II, Figs. 3-4, eqs. 2-5):
its leg-state machine and its control actions, through the controller interface a user
controller has (``reset`` / ``command(t, sensors)``). Expected values are computed here
from the paper's formulas and the robot's parameters, not from the controller's code."""

import numpy as np
import pytest

from scoutsim import BoundingController, ControllerParameters, RobotParameters
from scoutsim._core.model import layout as L
from scoutsim.control.sensors import Sensors

ROBOT = RobotParameters()
TABLE_I = ControllerParameters()
L0 = ROBOT.leg_rest_length
#: eq. (3) at the leg (through the gears, N and eta): offset and slope of the torque-speed
#: line, and eq. (4)'s current-limit torque
TAU_MAX = (
    ROBOT.gear_ratio
    * ROBOT.efficiency
    * ROBOT.torque_constant
    * ROBOT.battery_voltage
    / ROBOT.armature_resistance
)
A = (
    -(ROBOT.gear_ratio**2)
    * ROBOT.efficiency
    * ROBOT.torque_constant
    * ROBOT.speed_constant
    / ROBOT.armature_resistance
)
TAU_LIMIT = ROBOT.gear_ratio * ROBOT.efficiency * ROBOT.torque_constant * ROBOT.current_limit


def controller(params=TABLE_I, compression=(0.0, 0.0), angle=(0.3, 0.3)):
    c = BoundingController(params)
    c.reset(ROBOT, sensors(angle, (0.0, 0.0), compression))
    return c


def sensors(angle, rate, compression):
    return Sensors(
        hip_angle=np.array(angle, dtype=float),
        hip_rate=np.array(rate, dtype=float),
        leg_length=L0 - np.array(compression, dtype=float),
    )


def in_stance_retraction(rate_back):
    """A controller whose back leg is in stance-retraction (touchdown detected, angle above
    the sweep limit), commanded at back hip rate ``rate_back``."""
    c = controller()
    td = 2.0 * TABLE_I.touchdown_compression
    tau = c.command(0.0, sensors((0.2, 0.2), (rate_back, 0.0), (td, 0.0)))
    assert c.leg_states[L.BACK] == L.LS_RETRACTION
    return tau[L.BACK]


@pytest.mark.parametrize("rate", [-8.5, -7.5, -6.5, -5.8])
def test_stance_retraction_commands_the_motor_torque_speed_line_eqs_2_3(rate):
    tau = -TAU_MAX + A * rate
    assert -TAU_LIMIT < tau < 0.0  # inside the limits at these rates
    assert in_stance_retraction(rate) == pytest.approx(tau, rel=1e-12)


def test_stance_retraction_is_clipped_at_the_current_limit_eq_4():
    # at small hip rates the line asks for more torque than the amplifier's current allows
    for rate in (0.0, -1.0, 2.0):
        assert abs(-TAU_MAX + A * rate) > TAU_LIMIT
        assert in_stance_retraction(rate) == pytest.approx(-TAU_LIMIT, rel=1e-12)


def test_stance_retraction_never_commands_a_positive_torque_eq_5():
    """Beyond the motor's no-load speed (the leg spun backwards) the line asks for a
    positive torque: none is commanded (eq. 5), however large the line's value, which at
    1.5 x no-load exceeds the current limit (eq. 4 applies to the "excessively large
    torques" of small rates, paper footnote 2, not to a change of sign)."""
    no_load_rate = TAU_MAX / A  # where the line crosses zero (negative)
    assert no_load_rate < 0.0
    assert -TAU_MAX + A * 1.5 * no_load_rate > TAU_LIMIT
    for rate in (1.05 * no_load_rate, 1.5 * no_load_rate):
        assert in_stance_retraction(rate) == 0.0


def pd_torque(kp, kd, target, angle, rate):
    """A PD servo's torque [N m]: kp (target - angle) - kd rate."""
    return kp * (target - angle) - kd * rate


@pytest.mark.parametrize("state", ["flight", "brake"])
def test_flight_and_stance_brake_are_pd_servos(state):
    """Flight servos to the touchdown angle with the flight gains; stance-brake to the
    sweep limit with the brake gains (Table I), each leg with its own."""
    c = controller()
    p = TABLE_I
    if state == "flight":
        angle, rate, comp = (0.1, 0.5), (1.0, -2.0), 0.0
        expected_state = L.LS_FLIGHT
        gains = [
            (p.flight_kp_back, p.flight_kd_back, p.touchdown_angle_back),
            (p.flight_kp_front, p.flight_kd_front, p.touchdown_angle_front),
        ]
    else:
        # touchdown and the sweep limit in the same sample: straight to stance-brake
        angle, rate, comp = (-0.05, -0.02), (-1.5, 0.5), 2.0 * p.touchdown_compression
        expected_state = L.LS_BRAKE
        gains = [
            (p.brake_kp_back, p.brake_kd_back, p.sweep_limit_back),
            (p.brake_kp_front, p.brake_kd_front, p.sweep_limit_front),
        ]
    tau = c.command(0.0, sensors(angle, rate, (comp, comp)))
    assert tuple(c.leg_states) == (expected_state, expected_state)
    for leg in (L.BACK, L.FRONT):
        kp, kd, target = gains[leg]
        assert tau[leg] == pytest.approx(pd_torque(kp, kd, target, angle[leg], rate[leg]))


def test_leg_state_machine_follows_fig_3_with_hysteresis():
    p = TABLE_I.replace(touchdown_compression=6e-3, liftoff_compression=4e-3)
    c = controller(p)
    between = 5e-3  # between the lift-off and touchdown thresholds
    seq = [  # (compression of the back leg [m], back hip angle [rad]) -> expected state
        ((between, 0.2), L.LS_FLIGHT),  # not yet touchdown: above lift-off is not enough
        ((7e-3, 0.2), L.LS_RETRACTION),  # touchdown detected
        ((between, 0.1), L.LS_RETRACTION),  # hysteresis: stays in stance
        ((between, -0.01), L.LS_BRAKE),  # sweep limit (0) passed
        ((between, 0.05), L.LS_BRAKE),  # the brake holds: no way back to retraction
        ((3.9e-3, 0.05), L.LS_FLIGHT),  # lift-off detected
        ((between, 0.05), L.LS_FLIGHT),  # hysteresis: stays in flight
    ]
    for (comp, ang), expected in seq:
        c.command(0.0, sensors((ang, 0.3), (0.0, 0.0), (comp, 0.0)))
        assert c.leg_states[L.BACK] == expected, (comp, ang)
        assert c.leg_states[L.FRONT] == L.LS_FLIGHT  # the front leg never touched down


def test_a_leg_already_compressed_at_the_start_starts_in_stance():
    c = controller(compression=(2.0 * TABLE_I.touchdown_compression, 0.0))
    assert tuple(c.leg_states) == (L.LS_RETRACTION, L.LS_FLIGHT)


@pytest.mark.parametrize("sense_motor_angle", [True, False])
def test_the_controller_has_no_torso_feedback(sense_motor_angle):
    """Paper Sec. II: "no torso feedback". The compiled controller (every sensor read, then
    ``bounding_step``, as the run loop calls them) gives the same commands, leg states and
    transitions for plant states that differ only in the torso's position, pitch and their
    rates (so in the IMU's and the lasers' readings), at every 7th sample of a bounding run
    (every leg state); a change of a hip angle does change them (the comparison can
    fail)."""
    import scoutsim
    from scoutsim._core.model.sensor_readings import true_readings
    from scoutsim.control.bounding import bounding_step, controller_array
    from scoutsim.control.sensors import SensorParameters

    r = scoutsim.simulate(duration=1.0, model="II")
    geom = SensorParameters().geometry_array(ROBOT, sense_motor_angle)
    ds, aux = np.zeros(L.NS), np.zeros(L.NAUX)
    C = controller_array(TABLE_I.replace(sense_motor_angle=sense_motor_angle), ROBOT)
    torso = [L.IX, L.IY, L.ITH, L.NQ + L.IX, L.NQ + L.IY, L.NQ + L.ITH]
    hip = L.IALB if sense_motor_angle else L.IPHB
    rng = np.random.default_rng(7)

    def step(state, leg_states):
        y, ls = np.zeros(L.NSN), np.array(leg_states, dtype=np.int64)
        cmd, tr = np.zeros(2), np.zeros(2, dtype=np.int64)
        true_readings(state, ds, aux, ROBOT.gravity, geom, y)
        seen.append(y[[L.SN_PITCH, L.SN_PITCH_RATE, L.SN_RANGE_B, L.SN_RANGE_F]])
        bounding_step(y, C, ls, cmd, tr)
        return cmd, ls, tr

    visited, hip_matters, seen = set(), 0, []
    for k in range(1, len(r.t), 7):
        before = [r.leg_state(L.BACK)[k - 1], r.leg_state(L.FRONT)[k - 1]]
        s = r.state[k].copy()
        other = s.copy()
        other[torso] = s[torso] + rng.uniform(-1.0, 1.0, size=6)  # [m, rad, m/s, rad/s]
        cmd, ls, tr = step(s, before)
        cmd2, ls2, tr2 = step(other, before)
        assert np.all(seen[-1] != seen[-2])  # the controller was shown the torso moved
        assert np.array_equal(cmd, cmd2) and np.array_equal(ls, ls2) and np.array_equal(tr, tr2), k
        visited.update(ls)
        bent = s.copy()
        bent[hip] += 0.05
        hip_matters += not np.array_equal(step(bent, before)[0], cmd)
    assert visited == {L.LS_FLIGHT, L.LS_RETRACTION, L.LS_BRAKE}
    assert hip_matters > 0


def test_the_controller_knows_the_robot_it_was_reset_with():
    # eqs. 2-4 use the motor of the robot the controller runs on, packed at reset: a motor
    # with twice the armature resistance halves tau_max and the slope A (eqs. 2-3)
    robot = ROBOT.replace(armature_resistance=2.0 * ROBOT.armature_resistance)
    c = BoundingController(TABLE_I)
    c.reset(robot, sensors((0.3, 0.3), (0.0, 0.0), (0.0, 0.0)))
    td = 2.0 * TABLE_I.touchdown_compression
    rate = -7.0
    tau = c.command(0.0, sensors((0.2, 0.2), (rate, 0.0), (td, 0.0)))[L.BACK]
    assert tau == pytest.approx(-0.5 * TAU_MAX + 0.5 * A * rate, rel=1e-12)


def test_a_command_before_reset_is_refused():
    with pytest.raises(RuntimeError, match="reset"):
        BoundingController(TABLE_I).command(0.0, sensors((0.2, 0.2), (0.0, 0.0), (0.0, 0.0)))


@pytest.mark.parametrize("motor_side", [True, False])
def test_the_sensors_read_the_motor_or_the_leg_side(motor_side):
    from scoutsim._core.model.sensor_readings import read_encoders

    s = np.arange(L.NS, dtype=float) + 1.0
    y = np.zeros(L.NSN)
    read_encoders(s, motor_side, y)
    q0 = L.IALB if motor_side else L.IPHB
    for leg in (L.BACK, L.FRONT):
        assert y[L.SN_ANGLE_B + leg] == s[q0 + leg]
        assert y[L.SN_RATE_B + leg] == s[L.NQ + q0 + leg]
        assert y[L.SN_LENGTH_B + leg] == s[L.IL_B + leg]


def _held_command(y, C, ls, moves):
    """The commands of bounding_step at readings y and parameters C moved by ``moves``,
    asserting that the leg states ``ls`` are held (no transition)."""
    from scoutsim.control import bounding as B

    cmd, lsp, tr = np.zeros(2), ls.copy(), np.zeros(2, dtype=np.int64)
    B.bounding_step(y + moves[0], C + moves[1], lsp, cmd, tr)
    assert (lsp == ls).all() and not tr.any()
    return cmd


@pytest.mark.parametrize("state", [L.LS_FLIGHT, L.LS_RETRACTION, L.LS_BRAKE])
def test_the_laws_derivative_is_the_difference_of_the_law(state):
    """bounding_step_t (the commands' derivative with the leg states held) equals the
    central difference of bounding_step along random readings and parameter tangents, in
    each leg state, on both sides of the retraction torque's clipping (eqs. 4-5)."""
    from scoutsim.control import bounding as B

    rng = np.random.default_rng(state)
    C = B.controller_array(ControllerParameters(), RobotParameters())
    comp = {L.LS_FLIGHT: 0.0, L.LS_RETRACTION: 0.02, L.LS_BRAKE: 0.02}[state]
    # retraction: clipped at 0 (eq. 5), free, at the current limit (eq. 4)
    for rate in (-30.0, -7.0, 5.0, 40.0):
        y = np.zeros(L.NSN)
        for leg in range(2):
            y[L.SN_ANGLE_B + leg] = (0.3 if state != L.LS_BRAKE else -0.5) + 0.05 * leg
            y[L.SN_RATE_B + leg] = rate * (1 + 0.01 * leg)
            y[L.SN_LENGTH_B + leg] = C[B.C_L0 + leg] - comp
        y_t = rng.standard_normal(y.size)
        C_t = rng.standard_normal(C.size) * np.abs(C) * 0.1
        C_t[B.C_ENABLED] = C_t[B.C_SENSE_ALPHA] = 0.0
        ls = np.array([state, state], dtype=np.int64)
        cmd_t = np.zeros(2)
        B.bounding_step_t(y, C, ls, (y_t, C_t), cmd_t)

        e = 1e-6
        fd = (
            _held_command(y, C, ls, (e * y_t, e * C_t))
            - _held_command(y, C, ls, (-e * y_t, -e * C_t))
        ) / (2 * e)
        assert np.allclose(cmd_t, fd, rtol=1e-7, atol=1e-7 * np.abs(fd).max()), (rate, cmd_t, fd)
