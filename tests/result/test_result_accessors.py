"""The named accessors of SimulationResult against independent computations from the raw
arrays and from physics (kinematics, the leg's spring-damper law, statics of the massless
toe, Coulomb friction, momentum over whole strides, the fall rule); the floor given as an
Environment; and what simulate() does when a Python controller fails."""

import math

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

import scoutsim
from scoutsim import Environment, InitialState, RobotParameters, SimulationResult
from scoutsim._core.model import layout as L
from scoutsim.io.run_directory import check_run_directory
from scoutsim.simulation.simulator import ControllerError

MODELS = ("II", "I", "ideal")
LEGS = (("back", -1.0), ("front", 1.0))  # leg, side of the hip (behind / ahead of the COM)
ROBOT = RobotParameters()


@pytest.fixture(scope="module")
def runs():
    """A 5 s bounding run from the default start per model (about 20 strides)."""
    return {m: scoutsim.simulate(None, None, None, 5.0, model=m) for m in MODELS}


def _hip(r, side):
    """Hip position and velocity [m, m/s] from the torso state: the hip sits at
    side * hip_spacing / 2 on the torso's long axis."""
    s = side * ROBOT.half_hip_spacing
    th, dth = r.pitch, r.pitch_rate
    dy = r.state[:, L.NQ + L.IY]
    pos = (r.x + s * np.cos(th), r.height + s * np.sin(th))
    vel = (r.forward_speed - s * np.sin(th) * dth, dy + s * np.cos(th) * dth)
    return pos, vel


def _stance(r, leg):
    return r.contact_mode(leg) != 0


# -----------------------------------------------------------------------------------------
# forward_speed, leg_rate: the time derivatives of x and of the leg angle
# -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("model", MODELS)
def test_forward_speed_is_the_time_derivative_of_x(runs, model):
    """forward_speed = dx/dt: its trapezoidal integral over the samples gives x(t) - x(0)
    (to 1e-4 m over the run's 6-7 m), and over each sample period the difference quotient
    of x equals the mean of the speeds at its ends, to dt |jump of the acceleration| / 8
    (about 1e-3 m/s where a touchdown or a torque step changes the force at once)."""
    r = runs[model]
    travelled = cumulative_trapezoid(r.forward_speed, r.t, initial=0.0)
    np.testing.assert_allclose(r.x - r.x[0], travelled, rtol=0, atol=1e-4)
    quotient = np.diff(r.x) / np.diff(r.t)
    mean = 0.5 * (r.forward_speed[1:] + r.forward_speed[:-1])
    assert np.max(np.abs(quotient - mean)) < 2e-3
    assert np.median(np.abs(quotient - mean)) < 1e-4


def _window_increments(values, rate, t, n=50):
    """Increments of ``values`` over every window of ``n`` samples, and the trapezoidal
    integrals of ``rate`` over the same windows."""
    integral = cumulative_trapezoid(rate, t, initial=0.0)
    return values[n:] - values[:-n], integral[n:] - integral[:-n]


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("leg", ["back", "front"])
def test_leg_rate_is_the_time_derivative_of_the_leg_angle(runs, model, leg):
    """leg_rate = d(leg_angle)/dt: over every 50 ms window its trapezoidal integral is
    the leg angle's change to 5e-4 rad (the leg swings about 0.5 rad per stride; the
    torque steps at the samples bound the accuracy), and the difference quotient of the
    angle matches the mean rate over most sample periods. In Model II the motor-side
    rate (through the belt) does not pass the same test."""
    r = runs[model]
    phi, rate = r.leg_angle(leg), r.leg_rate(leg)
    change, integral = _window_increments(phi, rate, r.t)
    assert np.max(np.abs(change - integral)) < 5e-4
    quotient = np.diff(phi) / np.diff(r.t)
    mean = 0.5 * (rate[1:] + rate[:-1])
    assert np.median(np.abs(quotient - mean)) < 1e-3
    if model == "II":
        motor_rate = r.state[:, L.NQ + L.IALB + (0 if leg == "back" else 1)]
        change, integral = _window_increments(phi, motor_rate, r.t)
        assert np.max(np.abs(change - integral)) > 2e-3


@pytest.mark.parametrize("model", MODELS)
def test_vertical_speed_is_the_time_derivative_of_the_height(runs, model):
    """vertical_speed = dy/dt: over every 50 ms window its trapezoidal integral is the
    height's change to 1e-4 m."""
    r = runs[model]
    change, integral = _window_increments(r.height, r.vertical_speed, r.t)
    assert np.max(np.abs(change - integral)) < 1e-4
    np.testing.assert_array_equal(r.vertical_speed, r.state[:, L.NQ + L.IY])


@pytest.mark.parametrize("leg", ["back", "front"])
def test_motor_angle_rate_is_the_time_derivative_of_the_gear_angle(runs, leg):
    """motor_angle_rate = d(motor_angle)/dt in Model II (over every 50 ms window, to 5e-4
    rad), and the leg rate itself where the gear angle is the leg angle (Model I)."""
    r = runs["II"]
    change, integral = _window_increments(r.motor_angle(leg), r.motor_angle_rate(leg), r.t)
    assert np.max(np.abs(change - integral)) < 5e-4
    np.testing.assert_array_equal(runs["I"].motor_angle_rate(leg), runs["I"].leg_rate(leg))


@pytest.mark.parametrize("model", MODELS)
def test_toe_position_is_the_hip_plus_the_leg(runs, model):
    """toe_position = hip + l (sin(theta + phi), -cos(theta + phi)) [m], on the ground in
    stance."""
    r = runs[model]
    for leg, side in LEGS:
        (hip_x, hip_y), _ = _hip(r, side)
        length, gamma = r.leg_length(leg), r.pitch + r.leg_angle(leg)
        toe_x, toe_y = r.toe_position(leg)
        np.testing.assert_allclose(toe_x, hip_x + length * np.sin(gamma), rtol=0, atol=1e-9)
        np.testing.assert_allclose(toe_y, hip_y - length * np.cos(gamma), rtol=0, atol=1e-9)
        assert np.max(np.abs(toe_y[_stance(r, leg)])) < 1e-9


def test_motor_joint_mode_is_a_stiction_mode_and_stuck_outside_model_ii(runs):
    """motor_joint_mode takes MotorJointMode codes, stuck at some samples of Model II's
    bounding, and is always stuck (0) in Model I and the ideal actuator."""
    from scoutsim.names import MotorJointMode

    for leg, _ in LEGS:
        m = runs["II"].motor_joint_mode(leg)
        assert set(np.unique(m)) <= {int(v) for v in MotorJointMode}
        assert MotorJointMode.STUCK in m
        for model in ("I", "ideal"):
            assert not np.any(runs[model].motor_joint_mode(leg))


def test_event_log_names_the_event_records(runs):
    """event_log: the records' columns by name, selected by kind and leg, agree with
    event_times and impacts; impact_log is the touchdowns in a half-open window."""
    from scoutsim.names import EventKind

    r = runs["II"]
    log = r.event_log()
    assert len(log["t"]) == len(r.events)
    np.testing.assert_array_equal(log["kind"], r.events[:, L.EVR_KIND])
    np.testing.assert_array_equal(log["violations"], r.events[:, L.EVR_VIOLATIONS])
    for leg, _ in LEGS:
        td = r.event_log(kinds=("touchdown", EventKind.LIFTOFF), leg=leg)
        assert set(td["kind"]) == {EventKind.TOUCHDOWN, EventKind.LIFTOFF}
        assert np.all(td["leg"] == (0 if leg == "back" else 1))
        np.testing.assert_array_equal(
            td["t"][td["kind"] == EventKind.TOUCHDOWN], r.event_times("touchdown", leg)
        )
    imp = r.impacts()
    t0, t1 = float(imp[3, 0]), float(imp[8, 0])
    window = r.impact_log(t0, t1)
    np.testing.assert_array_equal(window["t"], imp[3:8, 0])
    np.testing.assert_array_equal(window["energy_lost"], imp[3:8, 4])
    np.testing.assert_array_equal(r.impact_log()["normal_impulse"], imp[:, 2])
    with pytest.raises(ValueError, match="kind"):
        r.event_log(kinds=("landing",))


# -----------------------------------------------------------------------------------------
# leg_length, leg_axial_force, ground_force
# -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("model", MODELS)
def test_leg_length_puts_the_toe_on_the_ground_in_stance_and_relaxes_in_flight(runs, model):
    """Toe = hip + l (sin(theta + phi), -cos(theta + phi)). In stance the toe is on the
    ground (height 0 to round-off); in flight it is above it, the leg is never longer than
    l0, and with no force on the massless toe the damper lets the spring extend the leg as
    a first-order lag: l(t + dt) = l0 - (l0 - l(t)) exp(-dt k / c)."""
    r = runs[model]
    l0, rate = ROBOT.leg_rest_length, ROBOT.leg_stiffness / ROBOT.leg_damping
    for leg, side in LEGS:
        (_, hip_y), _ = _hip(r, side)
        length = r.leg_length(leg)
        toe_y = hip_y - length * np.cos(r.pitch + r.leg_angle(leg))
        stance = _stance(r, leg)
        assert stance.any() and (~stance).any()
        assert np.max(np.abs(toe_y[stance])) < 1e-12
        assert np.all(toe_y[~stance] > 0.0)
        assert np.all(length <= l0)
        k = np.flatnonzero(~stance[:-1] & ~stance[1:])  # both ends of the period in flight
        relaxed = l0 - (l0 - length[k]) * np.exp(-rate * np.diff(r.t)[k])
        np.testing.assert_allclose(length[k + 1], relaxed, rtol=0, atol=1e-8)


@pytest.mark.parametrize("model", MODELS)
def test_leg_axial_force_is_the_spring_damper_law_and_balances_the_toe(runs, model):
    """leg_axial_force (compression positive, per virtual leg) is
    n_p (k (l0 - l) - c dl/dt), with dl/dt the hip's velocity along the leg while the toe
    is pinned (stick); at the massless toe it balances the ground force's component along
    the leg, F = G_n cos(theta + phi) - G_t sin(theta + phi), in every stance sample; in
    flight it is zero."""
    r = runs[model]
    n_p = ROBOT.legs_per_virtual_leg
    for leg, side in LEGS:
        _, (vx, vy) = _hip(r, side)
        a = r.pitch + r.leg_angle(leg)
        ldot = -np.sin(a) * vx + np.cos(a) * vy  # hip velocity along toe -> hip
        law = n_p * (
            ROBOT.leg_stiffness * (ROBOT.leg_rest_length - r.leg_length(leg))
            - ROBOT.leg_damping * ldot
        )
        force = r.leg_axial_force(leg)
        stick = r.contact_mode(leg) == L.STICK
        assert stick.sum() > 100
        np.testing.assert_allclose(force[stick], law[stick], rtol=0, atol=1e-9)
        gt, gn = r.ground_force(leg)
        stance = _stance(r, leg)
        np.testing.assert_allclose(
            force[stance], (gn * np.cos(a) - gt * np.sin(a))[stance], rtol=0, atol=1e-9
        )
        assert np.all(force[~stance] == 0.0)
        assert force.max() > 100.0  # the legs carried the robot


@pytest.mark.parametrize("model", MODELS)
def test_ground_force_is_zero_in_flight_and_inside_the_friction_cone(runs, model):
    """ground_force = (tangential, normal) on the toe: zero in flight; in stance the
    normal force pushes (G_n >= 0) and the tangential force stays in the Coulomb cone
    |G_t| <= mu G_n of the default floor (mu = 1), on its edge while the toe slides."""
    r = runs[model]
    mu = r.provenance["friction_coefficient"]
    assert mu == 1.0
    for leg, _ in LEGS:
        gt, gn = r.ground_force(leg)
        stance = _stance(r, leg)
        assert np.all(gt[~stance] == 0.0) and np.all(gn[~stance] == 0.0)
        assert np.all(gn[stance] >= 0.0)
        assert np.all(np.abs(gt[stance]) <= mu * gn[stance] * (1 + 1e-12))
        slide = r.contact_mode(leg) == L.SLIDE
        np.testing.assert_allclose(np.abs(gt[slide]), mu * gn[slide], rtol=1e-12, atol=1e-9)


def _momentum(r):
    """Linear momentum (p_x, p_y) [N s] of torso and leg bodies from the state: each virtual
    leg of mass n_p m_leg has its COM at d from the hip along the leg."""
    m_leg = ROBOT.legs_per_virtual_leg * ROBOT.leg_mass
    dy = r.state[:, L.NQ + L.IY]
    px, py = ROBOT.torso_mass * r.forward_speed, ROBOT.torso_mass * dy
    for leg, side in LEGS:
        _, (vx, vy) = _hip(r, side)
        a = r.pitch + r.leg_angle(leg)
        w = r.pitch_rate + r.leg_rate(leg)
        px = px + m_leg * (vx + ROBOT.leg_com_distance * np.cos(a) * w)
        py = py + m_leg * (vy + ROBOT.leg_com_distance * np.sin(a) * w)
    return px, py


@pytest.mark.parametrize("model", MODELS)
def test_ground_force_over_whole_strides_carries_the_weight(runs, model):
    """Momentum over whole strides (from one controller-detected back lift-off to another,
    after the first strides): the mean normal ground force equals the robot's weight
    (torso + 4 legs) M g, the mean tangential force equals the small change of horizontal
    momentum (steady bounding does not accelerate), to within the 1 kHz sampling of
    forces that jump at touchdowns and at the controller's torque steps (~1 %)."""
    r = runs[model]
    t = r.t
    k = np.rint(r.event_times("controller_liftoff", "back") / 1e-3).astype(int)
    a, b = k[3], k[-1]
    assert len(k) - 4 >= 10  # at least 10 whole strides
    span = t[b] - t[a]
    weight = (ROBOT.torso_mass + 2 * ROBOT.legs_per_virtual_leg * ROBOT.leg_mass) * ROBOT.gravity
    gt = sum(r.ground_force(leg)[0] for leg, _ in LEGS)[a : b + 1]
    gn = sum(r.ground_force(leg)[1] for leg, _ in LEGS)[a : b + 1]
    px, py = _momentum(r)
    mean_gn = np.trapezoid(gn, t[a : b + 1]) / span
    assert mean_gn == pytest.approx(weight, rel=0.01)
    assert mean_gn - (py[b] - py[a]) / span == pytest.approx(weight, rel=0.005)
    mean_gt = np.trapezoid(gt, t[a : b + 1]) / span
    mean_abs_gt = np.trapezoid(np.abs(gt), t[a : b + 1]) / span
    assert abs(mean_gt - (px[b] - px[a]) / span) < 0.02 * mean_abs_gt


def test_momentum_is_conserved_horizontally_and_falls_freely_in_double_flight(runs):
    """Cross-check of the momentum used above: with both toes off the ground the only
    external force is gravity, so p_x stays constant and p_y falls at M g."""
    r = runs["I"]
    px, py = _momentum(r)
    flight = ~_stance(r, "back") & ~_stance(r, "front")
    k = np.flatnonzero(flight[:-1] & flight[1:])
    assert k.size > 100
    weight = ROBOT.total_mass * ROBOT.gravity
    dt = np.diff(r.t)[k]
    np.testing.assert_allclose(px[k + 1] - px[k], 0.0, atol=1e-9)
    np.testing.assert_allclose((py[k + 1] - py[k]) / dt, -weight, rtol=1e-6)


# -----------------------------------------------------------------------------------------
# fell
# -----------------------------------------------------------------------------------------
def _lowest_point(r):
    """Height [m] of the lowest torso corner or hip (the 0.70 m x 0.12 m box)."""
    th, y = r.pitch, r.height
    points = [
        y + a * np.sin(th) + b * np.cos(th)
        for a in (-ROBOT.torso_length / 2, ROBOT.torso_length / 2)
        for b in (-ROBOT.torso_height / 2, ROBOT.torso_height / 2)
    ]
    points += [y + s * ROBOT.half_hip_spacing * np.sin(th) for _, s in LEGS]
    return np.min(points, axis=0)


@pytest.mark.parametrize(
    "start, how",
    [
        (InitialState(y=0.8, dtheta=math.radians(400.0)), "pitch"),  # tumbles nose up
        (InitialState(y=0.6, theta=math.radians(-45.0), dtheta=0.0), "ground"),  # nose first
    ],
)
def test_fell_is_true_when_the_run_ends_by_the_fall_rule(start, how):
    """The fall rule (docs/specification.md section 3): |pitch| reaches the 60 deg limit,
    or the torso box or a hip touches the ground. fell is True, the run ends there (last
    sample at the fall), and until then the rule held."""
    r = scoutsim.simulate(None, None, start, 2.0, model="II")
    assert r.fell is True and r.outcome == "fell"
    assert r.t[-1] == pytest.approx(r.t_end) and r.t_end < 2.0
    limit = math.radians(r.provenance["pitch_limit_deg"])
    lowest = _lowest_point(r)
    if how == "pitch":
        assert abs(r.pitch[-1]) == pytest.approx(limit, abs=1e-9)
    else:
        assert lowest[-1] == pytest.approx(0.0, abs=1e-9)
    assert np.all(np.abs(r.pitch[:-1]) < limit) and np.all(lowest[:-1] > 0.0)


def test_fell_is_false_for_a_run_that_keeps_bounding(runs):
    """The default runs never break the fall rule, and fell says so."""
    for model, r in runs.items():
        assert r.fell is False and r.outcome == "completed", model
        assert np.all(np.abs(r.pitch) < math.radians(r.provenance["pitch_limit_deg"]))
        assert np.all(_lowest_point(r) > 0.0)


# -----------------------------------------------------------------------------------------
# the floor as an Environment
# -----------------------------------------------------------------------------------------
def test_environment_sets_the_floor_friction():
    """simulate(environment=Environment(mu)) runs on that floor: the same run as the
    friction_coefficient shortcut, bit for bit; the provenance records mu; the ground
    force stays in the cone |G_t| <= mu G_n (reaching its edge), while on a no-slip floor
    it leaves that cone."""
    env = scoutsim.simulate(
        None, None, None, 1.5, model="I", environment=Environment(friction_coefficient=0.3)
    )
    short = scoutsim.simulate(None, None, None, 1.5, model="I", friction_coefficient=0.3)
    for name in ("t", "state", "aux", "modes"):
        np.testing.assert_array_equal(getattr(env, name), getattr(short, name), err_msg=name)
    assert env.provenance["friction_coefficient"] == 0.3
    no_slip = scoutsim.simulate(
        None, None, None, 1.5, model="I", environment=Environment(friction_coefficient=math.inf)
    )
    assert no_slip.provenance["friction_coefficient"] is None
    ratio_env, ratio_no_slip = [], []
    for leg, _ in LEGS:
        for r, out in ((env, ratio_env), (no_slip, ratio_no_slip)):
            gt, gn = r.ground_force(leg)
            stance = _stance(r, leg) & (gn > 0)
            out.append(np.max(np.abs(gt[stance]) / gn[stance]))
    assert max(ratio_env) == pytest.approx(0.3, rel=1e-9)
    assert max(ratio_no_slip) > 0.3


def test_environment_and_friction_coefficient_together_are_refused():
    """Both ways of giving the floor at once: a ValueError that names both."""
    with pytest.raises(ValueError) as info:
        scoutsim.simulate(
            None, None, None, 0.1, environment=Environment(0.5), friction_coefficient=0.5
        )
    message = str(info.value)
    assert "friction_coefficient" in message and "environment" in message


# -----------------------------------------------------------------------------------------
# a Python controller that fails
# -----------------------------------------------------------------------------------------
class Swing:
    """A user controller: a smooth hip torque on both legs [N m]."""

    def command(self, t, sensors):
        return (0.4 * math.sin(20.0 * t), -0.3)


class RaisesAt(Swing):
    def __init__(self, t_fail):
        self.t_fail = t_fail

    def command(self, t, sensors):
        if t >= self.t_fail - 1e-12:
            raise RuntimeError("sensor bus timeout")
        return super().command(t, sensors)


class ReturnsAt(Swing):
    def __init__(self, t_fail, value):
        self.t_fail, self.value = t_fail, value

    def command(self, t, sensors):
        if t >= self.t_fail - 1e-12:
            return self.value
        return super().command(t, sensors)


START = InitialState(y=1.0, dx=0.0, dtheta=0.0)  # in the air: a short, simple run


def _prefix_of(kept, whole):
    """The kept run is the failing controller's run up to the failure: the first samples
    of the same controller's run without the failure, bit for bit."""
    n = len(kept.t)
    for name in ("t", "state", "aux", "modes"):
        np.testing.assert_array_equal(getattr(kept, name), getattr(whole, name)[:n], err_msg=name)


def test_a_controller_that_raises_stops_the_run_with_its_data():
    """command() raising at t = 0.05 s: simulate() raises ControllerError naming the
    controller, the sample time and the exception (chained as the cause); the error's
    result holds the run's samples before that one (t <= 0.049 s), outcome
    "controller_error", the message in the provenance."""
    whole = scoutsim.simulate(None, Swing(), START, 0.1, model="II")
    with pytest.raises(ControllerError) as info:
        scoutsim.simulate(None, RaisesAt(0.05), START, 0.1, model="II")
    err = info.value
    message = str(err)
    assert "RaisesAt" in message and "t = 0.05 s" in message
    assert "RuntimeError: sensor bus timeout" in message
    assert isinstance(err.__cause__, RuntimeError)
    assert err.t == pytest.approx(0.05) and err.sample == 50 and err.returned is None
    r = err.result
    assert r.outcome == "controller_error" and not r.fell
    assert len(r.t) == 50 and r.t[-1] == pytest.approx(0.049)
    assert r.provenance["controller_error"] == message
    assert r.provenance["controller_kind"] == "RaisesAt"
    _prefix_of(r, whole)


@pytest.mark.parametrize(
    "value, shown",
    [
        ((float("nan"), 0.0), "(nan, 0.0)"),
        ((0.0, float("inf")), "(0.0, inf)"),
        ((1.0, 2.0, 3.0), "(1.0, 2.0, 3.0)"),
        (None, "None"),
    ],
)
def test_a_controller_that_returns_no_finite_torques_stops_the_run(value, shown):
    """command() returning NaN, inf, three torques or nothing at t = 0.031 s: the
    ControllerError names the controller, the sample time and what it returned; the
    result keeps the samples before it."""
    whole = scoutsim.simulate(None, Swing(), START, 0.1, model="I")
    with pytest.raises(ControllerError) as info:
        scoutsim.simulate(None, ReturnsAt(0.031, value), START, 0.1, model="I")
    err = info.value
    message = str(err)
    assert "ReturnsAt" in message and "t = 0.031 s" in message
    assert f"returned {shown}" in message
    assert err.sample == 31 and err.returned is value
    assert err.result.outcome == "controller_error" and len(err.result.t) == 31
    _prefix_of(err.result, whole)


def test_a_controller_failing_at_the_first_sample_leaves_an_empty_run():
    """A failure at t = 0: nothing was computed; the error says so and its result has
    no samples."""
    with pytest.raises(ControllerError, match=r"t = 0 s.*before its first sample") as info:
        scoutsim.simulate(None, RaisesAt(0.0), START, 0.1, model="I")
    assert len(info.value.result.t) == 0 and info.value.result.outcome == "controller_error"


def test_a_controller_failure_in_a_streamed_run_keeps_the_tables(tmp_path):
    """A streamed run whose controller fails: the tables hold every sample before the
    failure, with the outcome "controller_error"; the directory is marked partial."""
    whole = scoutsim.simulate(None, Swing(), START, 0.1, model="I")
    with pytest.raises(ControllerError) as info:
        scoutsim.simulate(
            None,
            ReturnsAt(0.04, (math.nan, math.nan)),
            START,
            0.1,
            model="I",
            stream_to=tmp_path / "run",
        )
    back = SimulationResult.load(tmp_path / "run")
    assert back.outcome == "controller_error" and len(back.t) == 40
    _prefix_of(back, whole)
    assert "returned (nan, nan)" in back.provenance["controller_error"]
    assert check_run_directory(tmp_path / "run")["status"] == "partial"
    assert info.value.result.outcome == "controller_error"


def test_ctrl_c_inside_a_controller_is_still_an_interruption():
    """KeyboardInterrupt raised from command() is the user's Ctrl-C, not a controller
    error: the run returns with the data so far, outcome "interrupted"."""

    class CtrlC(Swing):
        def command(self, t, sensors):
            if t >= 0.02 - 1e-12:
                raise KeyboardInterrupt
            return super().command(t, sensors)

    r = scoutsim.simulate(None, CtrlC(), START, 0.1, model="I")
    assert r.outcome == "interrupted" and len(r.t) == 20
