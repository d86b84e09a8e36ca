"""Virtual bench rigs: each is the simulator with the torso clamped; the physics
of each rig is checked against hand-derived laws (pendulum period, back-EMF torque
balance, static belt balance), never against numbers taken from the code."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scoutsim._core.model.packing import robot_array
from scoutsim.identification.bench import run_bench
from scoutsim.identification.rigs import (
    FlightSteps,
    FreeSwing,
    RigNoise,
    Stall,
    rig_log,
    run_rig,
    stall_deflection,
)
from scoutsim.parameters import ControllerParameters, RobotParameters
from scoutsim.simulation.initial_conditions import default_initial_state, initial_state_vector
from scoutsim.simulation.integrator import IntegratorSettings
from scoutsim.simulation.simulator import simulate


def test_rig_engine_with_clamp_off_is_simulate_bit_for_bit():
    """The bench engine (run_bench) without clamps is simulate()."""
    robot = RobotParameters()
    ctrl = ControllerParameters()
    ref = simulate(robot, ctrl, duration=0.4, model="II")
    s0 = initial_state_vector(default_initial_state("II"), robot, ctrl, (0.0, 0.0), True)
    res = run_bench(
        robot,
        "II",
        s0,
        0.4,
        controller=ctrl,
        dt=ctrl.control_period,
        integrator=IntegratorSettings(),
    )
    assert np.array_equal(res.t, ref.t)
    assert np.array_equal(res.state, ref.state)
    assert np.array_equal(res.aux, ref.aux)
    assert np.array_equal(res.events, ref.events, equal_nan=True)


def test_clamped_torso_does_not_move():
    res = run_rig(FreeSwing(duration=0.5))
    assert res.outcome == "completed"
    assert np.all(res.state[:, 0] == 0.0) and np.all(res.state[:, 2] == 0.0)
    assert np.all(res.state[:, 1] == 1.0)
    assert np.all(res.state[:, 7:10] == 0.0)
    assert np.ptp(res.leg_angle("back")) > 0.5  # while the leg swings


def _pendulum(robot, toe_mass):
    """Hand-derived small-angle pendulum of one physical leg with its toe mass and the
    reflected gear train (belt rigid): I_hip = I_leg + m d^2 + m_t l0^2 + J_2 + N^2 J_1,
    gravity stiffness (m d + m_t l0) g."""
    N = robot.gear_ratio
    I = (
        robot.leg_inertia
        + robot.leg_mass * robot.leg_com_distance**2
        + toe_mass * robot.leg_rest_length**2
        + robot.driven_gear_inertia
        + N * N * robot.drive_gear_inertia
    )
    kg = (
        robot.leg_mass * robot.leg_com_distance + toe_mass * robot.leg_rest_length
    ) * robot.gravity
    return I, kg


def test_free_swing_small_oscillation_period_is_the_pendulum_with_reflected_gear_inertia():
    robot = RobotParameters().replace(joint_stiction=0.0, joint_damping=0.0)
    m_t = 1.0
    res = run_rig(
        FreeSwing(
            release_angle_back=math.radians(3.0),
            release_angle_front=0.0,
            toe_mass=m_t,
            duration=3.0,
        ),
        robot,
    )
    I, kg = _pendulum(robot, m_t)
    T = 2 * math.pi * math.sqrt(I / kg)
    phi = res.leg_angle("back")
    t = res.t
    k = np.flatnonzero((phi[:-1] > 0) & (phi[1:] <= 0))  # downward zero crossings
    tc = t[k] + phi[k] / (phi[k] - phi[k + 1]) * (t[k + 1] - t[k])
    T_sim = float(np.mean(np.diff(tc)))
    assert len(tc) >= 2
    assert T_sim == pytest.approx(T, rel=0.01)
    # the front leg hangs at rest
    assert np.max(np.abs(res.leg_angle("front"))) < 1e-9


def test_shorted_motor_creeps_at_the_back_emf_torque_balance():
    """Leads shorted: i = -K_w w_m / R_A, so the leg creeps where gravity balances the
    back-EMF torque N eta K_T i, the viscous joint damping N^2 b_J w and the stiction
    N tau_s: (m d + m_t l0) g sin(phi) = (N^2 eta K_T K_w / R_A + N^2 b_J) |dphi| + N tau_s."""
    robot = RobotParameters()
    m_t = 1.0
    res = run_rig(
        FreeSwing(
            release_angle_back=math.radians(60.0),
            release_angle_front=0.0,
            toe_mass=m_t,
            motor="short",
            duration=2.0,
        ),
        robot,
    )
    N = robot.gear_ratio
    b = (
        N
        * N
        * robot.efficiency
        * robot.torque_constant
        * robot.speed_constant
        / robot.armature_resistance
        + N * N * robot.joint_damping
    )
    _, kg = _pendulum(robot, m_t)
    k = res.t > 0.5  # after the short transient (I / b ~ 20 ms)
    phi = res.leg_angle("back")[k]
    rate = res.state[k, 7 + 5]  # gear-train rate dalpha (the belt creeps too)
    predicted = -(kg * np.sin(phi) - N * robot.joint_stiction) / b
    np.testing.assert_allclose(rate, predicted, rtol=0.01)
    # the logged current is the shorted-winding current
    w_m = N * res.state[k, 7 + 5]
    np.testing.assert_allclose(
        res.motor_current("back")[k],
        -robot.speed_constant * w_m / robot.armature_resistance,
        rtol=1e-12,
    )


def _hand_stall(robot, command):
    """The held hip unit by hand (specification.md sections 4-5), per physical leg.

    Delivered torque: the command, capped by the amplifier's current limit through the
    transmission, N eta K_T i_max, with N = planetary x sprocket ratio and eta = gearbox x
    sprocket efficiency (Table III); at zero speed the torque-speed line, N eta K_T V / R_A,
    lies above that cap for the Scout II constants. The gear, at rest on the unloaded belt,
    slips while the belt spring carries less than tau - N tau_s (the stiction and viscous
    damping sit at the motor joint, reflected by N and N^2). The leg is held, so the gear
    obeys J (d2 delta) + (c_b + N^2 b_J) (d delta) + k_b delta = tau - N tau_s with
    J = J_2 + N^2 J_1; heavily overdamped (fast pole J / (c_b + N^2 b_J) = 0.16 ms), its
    slow pole gives delta(t) = delta_s (1 - exp(-t / T)), delta_s = (tau - N tau_s) / k_b,
    T = (c_b + N^2 b_J) / k_b: the gear creeps up to the lower edge of the static band
    (tau -+ N tau_s) / k_b and sticks there.

    Returns (tau [N m], delta_s [rad], T [s])."""
    n = robot.planetary_ratio * robot.sprocket_ratio
    eta = robot.gearbox_efficiency * robot.sprocket_efficiency
    cap = n * eta * robot.torque_constant * robot.current_limit
    tau = cap if command is None else min(command, cap)
    delta_s = (tau - n * robot.joint_stiction) / robot.belt_stiffness
    t_creep = (robot.belt_damping + n * n * robot.joint_damping) / robot.belt_stiffness
    return tau, delta_s, t_creep


@pytest.mark.parametrize(
    "command, stiffness_factor",
    [
        (None, 1.0),  # the rig's default: maximum hip torque
        (15.0, 1.0),  # a torque below the current limit
        (80.0, 1.0),  # above the current limit: the amplifier caps it
        (None, 2.0),  # a belt twice as stiff: half the deflection
    ],
)
def test_stall_deflection_is_the_torque_over_the_belt_stiffness(command, stiffness_factor):
    """Static balance of the held hip unit, k_b (alpha - phi) = tau - N tau_s, and its
    overdamped creep delta(t) = delta_s (1 - exp(-t / T)), against the hand computation of
    ``_hand_stall``; the delivered torque is the command capped at N eta K_T i_max."""
    base = RobotParameters()
    robot = base.replace(belt_stiffness=stiffness_factor * base.belt_stiffness)
    tau, delta_s, t_creep = _hand_stall(robot, command)
    d = stall_deflection(robot, Stall(torque=command))
    assert d["torque_nm"] == pytest.approx(tau, rel=1e-12)
    res = d["result"]
    b = res.belt_deflection("back")
    for t in (0.2, 0.5, 1.0, 2.0, 6.0):
        k = int(round(t / 1e-3))
        assert res.t[k] == pytest.approx(t)
        # the neglected fast pole changes delta(t) by < 1e-3 relative for t >= 0.2 s
        assert b[k] == pytest.approx(delta_s * (1.0 - math.exp(-t / t_creep)), rel=1e-3)
    # after 6 s (> 5 T) the gear sits in the static band, at its lower edge
    assert d["deflection_final_rad"] == pytest.approx(delta_s, rel=1e-3)
    assert np.array_equal(res.belt_deflection("front"), b)  # both legs alike
    # the leg and torso did not move
    assert np.all(res.state[:, 3:5] == 0.0)


def test_stall_rig_falls_short_of_the_paper_measured_8_deg():
    """Documented difference, not agreement (docs/identification.md, "The stall rig shows
    4.4 deg, not the robot's ~8 deg"). The paper (Sec. III) quotes about 8 deg as the
    deflection "measured by the robot applying maximum hip torque with the torso and legs
    constrained on a horizontal plane". Through Table II's 7 N m/deg belt spring, 8 deg takes
    7 x 8 = 56 N m; the assumed motor constants (K_T = 0.0389 N m/A, i_max = 12 A) give the
    amplifier's N eta K_T i_max = 31.1 N m, so the rig stops 3.5 deg short. If a change of
    the motor or belt constants closes this gap, update that section and this test."""
    robot = RobotParameters()
    needed = robot.belt_stiffness * math.radians(8.0)  # 56 N m
    tau, delta_s, _ = _hand_stall(robot, None)
    n_tau_s = robot.gear_ratio * robot.joint_stiction
    # the amplifier cannot hold the measured 8 deg, even at the band's upper edge
    assert tau + n_tau_s < needed
    d = stall_deflection(robot)
    assert math.degrees(d["deflection_final_rad"]) < 8.0 - 3.0  # short by 3.6 deg
    # the motor itself could: at zero speed its torque-speed line (eq. 3 at 36 V, through
    # the transmission) lies above the 56 N m; the amplifier's current limit binds first
    n = robot.planetary_ratio * robot.sprocket_ratio
    eta = robot.gearbox_efficiency * robot.sprocket_efficiency
    assert n * eta * robot.torque_constant * 36.0 / robot.armature_resistance > needed


def test_flight_steps_servo_reaches_each_commanded_angle():
    rig = FlightSteps()
    res = run_rig(rig)
    assert res.outcome == "completed"
    td = rig.commands(res.t)
    for j, leg in enumerate(("back", "front")):
        enc = res.motor_angle(leg)
        for t_end in list(rig.step_times[1:]) + [rig.duration]:
            k = int(round(t_end / 1e-3)) - 1
            # the PD holds the motor-side angle within the gravity-load error
            # |tau_g| / kp <= m g d / kp
            err = 0.97 * 9.81 * 0.1615 / 250.0
            assert abs(enc[k] - td[k, j]) < err + 2e-3
        assert np.all(res.leg_state(leg) == 0)  # never leaves flight


def test_rig_log_has_the_log_format_and_quantised_encoder(tmp_path):
    from scoutsim.validation.log_reading import load_log

    res = run_rig(FreeSwing(duration=0.3))
    noise = RigNoise(encoder_counts_per_rev=500, angle_rad=0.0, current_a=0.0)
    log = rig_log(res, noise=noise, seed=3)
    path = log.save(tmp_path / "fs.csv.gz")
    back = load_log(path)
    q = 2 * math.pi / (500 * RobotParameters().gear_ratio)
    counts = back.leg_angle("back") / q
    np.testing.assert_allclose(counts, np.round(counts), atol=5e-3)  # CSV: 7 digits
    assert np.max(np.abs(back.leg_angle("back") - res.motor_angle("back"))) <= q / 2 + 1e-7
    assert back.meta["rig"] == "free-swing"
    assert back.meta["rig_config"]["toe_mass"] == 1.0


@pytest.mark.parametrize(
    "kw, field",
    [
        ({"release_angle_back": math.radians(95)}, "free_swing.release_angle_back"),
        ({"toe_mass": -1.0}, "free_swing.toe_mass"),
        ({"motor": "battery"}, "free_swing.motor"),
    ],
)
def test_bad_rig_configuration_names_the_field(kw, field):
    with pytest.raises(ValueError, match=field):
        FreeSwing(**kw)


def test_stall_needs_torso_clamp_and_flight_steps_need_ordered_times():
    with pytest.raises(ValueError, match="clamp_legs"):
        robot_array(RobotParameters(), "II", clamp_legs=True)
    with pytest.raises(ValueError, match="step_times"):
        FlightSteps(step_times=(0.0, 0.5, 0.4), angles_back=(0, 0, 0), angles_front=(0, 0, 0))
    with pytest.raises(ValueError, match="stall.leg_angle"):
        Stall(leg_angle=2.0)
