"""The paper's reported results, checked on the default Scout II configuration.

Default floor (Coulomb mu = 1.0) and default start (scoutsim.default_initial_state()), 10 s
runs; the quotes are from Poulakakis, Smith & Buehler, ICRA 2004. Where scoutsim differs
from the paper, the test says so and asserts what scoutsim shows; docs/explanation/paper-results.md
says the same.
"""

import math

import numpy as np
import pytest

import scoutsim
from scoutsim.control.bounding import BoundingController
from scoutsim.parameters import ControllerParameters, RobotParameters

ROBOT = RobotParameters()
FLIGHT, RETRACTION, BRAKE = 0, 1, 2  # controller leg states (result.leg_state)
#: relative closeness to a motor limit that counts as "on" it (docs/model.md: 0.1 %)
ON_LIMIT = 1e-3


@pytest.fixture(scope="module")
def runs():
    return {m: scoutsim.simulate(duration=10.0, model=m) for m in ("ideal", "I", "II")}


def _steady(r):
    """Sample mask of the steady strides: from the first steady stride's back-leg lift-off
    to the last one's end."""
    st = r.gait().steady_strides
    return (r.t >= st[0].t_start) & (r.t < st[-1].t_end)


def _on_motor_limit(r, leg):
    """Per sample: the motor works on a limit of section 4, the current limit
    |i| >= (1 - 0.1 %) i_max or the torque-speed line |R_A i + K_w w_m| >= (1 - 0.1 %) V_b."""
    i = np.asarray(r.motor_current(leg))
    v_terminal = ROBOT.armature_resistance * i + ROBOT.speed_constant * np.asarray(
        r.motor_speed(leg)
    )
    on_current = np.abs(i) >= (1.0 - ON_LIMIT) * ROBOT.current_limit
    on_line = np.abs(v_terminal) >= (1.0 - ON_LIMIT) * np.asarray(r.battery_voltage)
    return on_current | on_line


@pytest.mark.parametrize("model", ["I", "II"])
def test_models_i_and_ii_reach_a_steady_stride(runs, model):
    """Figs. 8-11 draw "Model I (dotted) and Model II (dashed)" over a steady stride, and
    Fig. 12 gives both models' errors over 70 strides: both run the Table I controller to a
    cycle ("at least seven steady state strides" per experiment)."""
    r = runs[model]
    g = r.gait()
    assert r.outcome == "completed"
    assert g.n_steady_strides >= 7
    assert g.is_steady_bounding()


def test_model_ii_speed_near_paper_1_3_m_s(runs):
    """ "the resulting average forward speed was approximately 1.3 m/s"."""
    assert 1.1 <= runs["II"].gait().mean_speed_m_s <= 1.5


def test_model_ii_belt_deflection_below_the_stall_deflection(runs):
    """The belt spring was chosen so that "the maximum spring deflection during bounding in
    simulation does not exceed that which is measured by the robot applying maximum hip
    torque with the torso and legs constrained on a horizontal plane (approximately 8°)".

    The robot measured about 8 deg; the model's own version of that measurement is the
    static deflection at the largest torque the hip unit can hold, (N eta K_T i_max +
    N tau_s) / k_b = 4.53 deg by hand (docs/identification.md: the model reaches 55 % of
    the robot's 8 deg). During bounding the peak must stay below that (measured 0.46 and
    1.02 deg). And the belt spring carries the hip torque on average: over whole steady
    strides the damper's and the gear inertia's parts average out, so the mean applied
    torque equals k_b times the mean deflection up to the motor joint's friction
    (|.| <= N tau_s = 0.56 N m; measured 0.006 and 0.039 N m)."""
    robot = scoutsim.RobotParameters()
    N = robot.planetary_ratio * robot.sprocket_ratio
    eta = robot.gearbox_efficiency * robot.sprocket_efficiency
    stall = (
        N * eta * robot.torque_constant * robot.current_limit + N * robot.joint_stiction
    ) / robot.belt_stiffness
    r = runs["II"]
    m = _steady(r)
    for leg in ("back", "front"):
        d = np.asarray(r.belt_deflection(leg))
        assert np.max(np.abs(d)) < stall
        tau = np.asarray(r.hip_torque_applied(leg))[m]
        assert abs(tau.mean() - robot.belt_stiffness * d[m].mean()) <= N * robot.joint_stiction


@pytest.mark.parametrize("model", ["I", "II"])
def test_motors_saturated_most_of_the_step(runs, model):
    """Fig. 11 (leg speed against motor torque over one step): "One can see that the motors
    are saturated most of the time and that both simulation models adequately capture this
    effect."

    Over the whole steady strides (flight, stance-retraction and stance-brake), each motor
    works on its current limit or on its torque-speed line (docs/specification.md section 4)
    more than half of the time, in Model I and in Model II. Measured: Model I 61 % (back) /
    54 % (front), Model II 60 % / 57 %: all of stance-retraction (the law of eqs. 2-5
    commands the limit), about 30 % of flight (the start of the swing) and 23-70 % of
    stance-brake. The claim holds, with little to spare on the front legs.
    """
    r = runs[model]
    w = _steady(r)
    for leg in ("back", "front"):
        on_limit = _on_motor_limit(r, leg)[w]
        assert np.mean(on_limit) > 0.5, leg


def _quadrant_shares(r, leg, mask):
    """Shares of the samples in ``mask`` in each quadrant of Fig. 11's (torque, leg speed)
    plane: applied hip torque and leg angular rate, positive forward (toe moving ahead)."""
    tau = np.asarray(r.hip_torque_applied(leg))[mask]
    rate = np.asarray(r.leg_rate(leg))[mask]
    return {
        1: np.mean((tau > 0) & (rate > 0)),
        2: np.mean((tau < 0) & (rate > 0)),
        3: np.mean((tau < 0) & (rate < 0)),
        4: np.mean((tau > 0) & (rate < 0)),
    }


@pytest.mark.parametrize("model", ["I", "II"])
def test_retraction_in_third_quadrant_saturated_flight_in_first(runs, model):
    """Fig. 11: "Note also, according to the sign conventions shown in Fig. 2, that during
    stance-retraction the motors operate in the third quadrant while during flight they
    operate in the first quadrant (positive torques correspond to the leg moving forward)."

    Over the steady strides: in stance-retraction the torque and the leg speed are both
    negative (measured: 100 % of the time, 98.8 % for Model II's front legs, which still
    swing forward for a moment after touchdown). In flight, the motor is in the first
    quadrant whenever it is saturated (measured: 100 %), the forward swing at full torque.
    Over the whole flight it is there only 29-39 % of the time: this is where scoutsim
    differs from the paper's words. The flight servo then brakes the swing towards the
    touchdown angle, below the limits, with negative torque on a leg still moving forward
    (second quadrant, 48-59 % of the flight), the "nonsaturation region" where the paper
    says most of Fig. 11's discrepancies lie.
    """
    r = runs[model]
    w = _steady(r)
    on_limit = _on_motor_limit(r, leg="back"), _on_motor_limit(r, leg="front")
    for k, leg in enumerate(("back", "front")):
        state = r.leg_state(leg)
        retraction = _quadrant_shares(r, leg, w & (state == RETRACTION))
        assert retraction[3] > 0.95, leg
        saturated_flight = _quadrant_shares(r, leg, w & (state == FLIGHT) & on_limit[k])
        assert saturated_flight[1] > 0.95, leg
        flight = _quadrant_shares(r, leg, w & (state == FLIGHT))
        assert flight[1] < 0.5, leg
        assert flight[2] > flight[1], leg


def _front_touchdown_phases(r):
    """Phase of each front-leg touchdown within the back leg's stride, measured from
    back-leg touchdown to the next, in [0, 1), over the steady strides; and the number of
    front touchdowns in each of those back strides."""
    st = r.gait().steady_strides
    a, b = st[0].t_start, st[-1].t_end
    back = np.sort(r.event_times("touchdown", "back"))
    front = np.sort(r.event_times("touchdown", "front"))
    back = back[(back >= a) & (back <= b)]
    phases, counts = [], []
    for t0, t1 in zip(back[:-1], back[1:]):
        f = front[(front >= t0) & (front < t1)]
        counts.append(len(f))
        phases.extend((f - t0) / (t1 - t0))
    return np.array(phases), counts


@pytest.mark.parametrize("model", ["I", "II"])
def test_bound_front_legs_touch_down_out_of_phase_with_back_legs(runs, model):
    """Sec. II: "the bounding running gait": the front and back leg pairs alternate
    (unlike a pronk, where all legs touch down together and the torso barely pitches).

    The phase of the front touchdown in the back leg's stride (back touchdown to back
    touchdown) is 0 (or 1) in a pronk and 1/2 when the pairs alternate evenly; a bound is
    nearer to the alternation than to the pronk: phase in (1/4, 3/4), once per stride, and
    the torso pitches nose-up and nose-down every stride. Measured: 0.63 (Model I), 0.59
    (Model II), the same in every steady stride.
    """
    r = runs[model]
    phases, counts = _front_touchdown_phases(r)
    assert len(counts) >= 7
    assert all(c == 1 for c in counts)
    assert np.all((phases > 0.25) & (phases < 0.75))
    for st in r.gait().steady_strides:
        assert st.pitch_max_deg > 0 > st.pitch_min_deg


@pytest.mark.parametrize("model, after", [("I", False), ("II", True)])
def test_front_touchdown_close_to_back_liftoff(runs, model, after):
    """Fig. 8 text: "in experiment front leg touchdown occurs slightly after back leg
    lift-off while in simulation it occurs slightly before."

    In every steady stride the front legs touch down within 5 % of the stride period of
    the back legs' lift-off. Model I's front touchdown comes before it, as in the paper's
    simulations (measured 4.4 ms); Model II's comes after it (3.4 ms), as in the paper's
    experiment, not its simulations: here scoutsim's Model II differs from the paper's.
    """
    r = runs[model]
    front_td = np.sort(r.event_times("touchdown", "front"))
    gaps = []
    for s in r.gait().steady_strides:
        # the back-leg lift-off closing the stride, and the front touchdown nearest to it
        f = front_td[np.argmin(np.abs(front_td - s.t_end))]
        gaps.append((f - s.t_end) / s.period_s)
    gaps = np.array(gaps)
    assert np.all(np.abs(gaps) < 0.05)
    assert np.all(gaps > 0) if after else np.all(gaps < 0)


def test_ideal_actuator_with_the_retraction_law_reaches_a_cycle(runs):
    """Conclusion: "without the actuator saturation taken into account the models do not
    converge to cyclic motion". A documented difference: scoutsim's ideal actuator (a
    constant torque limit N eta K_T i_max, no torque-speed line) reaches a steady bounding
    cycle from the default start (1.53 m/s, 4.81 Hz; Model I 1.51 m/s, 4.86 Hz).

    Why: the stance-retraction law of eqs. 2-5 commands the torque-speed line itself
    ("To include motor saturation into the controller, torques are commanded according to
    the prescription"), so the ideal actuator still retracts along the line; it leaves the
    line only in flight, where the servo's command exceeds it (measured: 21-24 % of the
    flight), and that does not decide convergence. Without the line in the controller too,
    the ideal actuator does not converge (next test).
    """
    r = runs["ideal"]
    assert r.gait().is_steady_bounding()
    assert _back_leg_bounces(r)[0] == 0
    w = _steady(r)
    for leg in ("back", "front"):
        # the current Model I's motor would allow at the same speed and battery voltage
        i = np.asarray(r.motor_current(leg))
        back_emf = ROBOT.speed_constant * np.asarray(r.motor_speed(leg))
        vb = np.asarray(r.battery_voltage)
        beyond_line = (i > (vb - back_emf) / ROBOT.armature_resistance + 1e-6) | (
            i < (-vb - back_emf) / ROBOT.armature_resistance - 1e-6
        )
        state = r.leg_state(leg)
        assert not np.any(beyond_line[w & (state == RETRACTION)]), leg
        assert np.mean(beyond_line[w & (state == FLIGHT)]) > 0.1, leg


def _back_leg_bounces(r, t0=2.0):
    """(number of back-leg lift-offs after t0 [s] followed by a new back-leg touchdown
    within 30 ms, number of front-leg touchdowns after t0): bounces, and strides."""
    t_lo = r.event_times("liftoff", "back")
    t_td = np.sort(r.event_times("touchdown", "back"))
    n = sum(1 for t in t_lo if t > t0 and np.any((t_td > t) & (t_td < t + 0.03)))
    return n, int(np.sum(r.event_times("touchdown", "front") > t0))


class ConstantMaxTorqueRetraction(BoundingController):
    """The Table I controller with a stance-retraction command of constant maximum torque,
    -N eta K_T i_max (the limit of eq. 4), instead of the torque-speed line of eqs. 2-3:
    the "constant max torque" assumption the paper's Conclusion warns about."""

    def reset(self, robot, initial_sensors=None):
        super().reset(robot, initial_sensors)
        self.max_torque = robot.max_leg_torque

    def command(self, t, sensors):
        cmd = list(super().command(t, sensors))  # updates self.leg_states
        for leg in range(2):
            if self.leg_states[leg] == RETRACTION:
                cmd[leg] = -self.max_torque
        return tuple(cmd)


def test_without_the_torque_speed_line_anywhere_the_ideal_actuator_finds_no_cycle():
    """Conclusion: "Both models included an experimentally validated motor driving system
    with battery model; without the actuator saturation taken into account the models do
    not converge to cyclic motion", and "commonly made assumptions (e.g. constant max
    torque, rigid torque transmission) might result in misleading models".

    With neither the actuator (ideal: constant limit N eta K_T i_max) nor the controller
    (constant maximum retraction torque) following the motor's torque-speed line, the robot
    does not converge to a cycle from the default start. It keeps running (about 1.9 m/s)
    without falling, but in most strides, not all, its back legs bounce: they lift off and
    touch down again about 10 ms later (measured: 38 of 42 strides in 10 s, 182 of 200 in
    40 s; the Table I runs never bounce), so the stride-to-stride motion never settles
    and there is no steady stride sequence. This agrees with the paper's claim. The same
    from each of 9 starts (1.0-1.4 m/s, pitch rate 100-200 deg/s) over 20 s, all of which
    reach the bounding cycle with the Table I law.
    """
    r = scoutsim.simulate(
        duration=10.0, model="ideal", controller=ConstantMaxTorqueRetraction(ControllerParameters())
    )
    assert r.outcome == "completed"
    assert not r.gait().is_steady_bounding()
    bounces, strides = _back_leg_bounces(r)
    assert bounces > strides / 2


def _brake_overshoot_deg(r, leg):
    """Largest angle [deg] by which the leg passes beyond its 0 deg sweep limit while the
    controller is in stance-brake, over the steady strides."""
    mask = (r.leg_state(leg) == BRAKE) & _steady(r)
    return float(-np.min(np.degrees(r.leg_angle(leg)[mask])))


def test_model_i_back_leg_is_not_held_at_the_sweep_limit_model_ii_holds_it_better(runs):
    """Fig. 9 text: "in Model I, the sweep limit controller is not able to hold the leg at
    the desired sweep limit angle", while "including the hip model ... significantly
    improves the accuracy of the simulation during the stance-brake phase. This is evident
    especially in the back legs".

    "Not able to hold": the back leg passes the sweep limit by more than the angle at which
    the stance-brake servo's command kp_b (phi_sweep - phi) reaches the actuator's torque
    limit N eta K_T i_max (31.1 / 300 rad = 5.9 deg): beyond it the servo pushes back with
    all it has and the leg still goes on. Model I: 9.7 deg. Model II passes it by less
    (8.4 deg), but also by more than 5.9 deg: in scoutsim neither model holds the back leg
    at the sweep limit, and Model II's improvement is small, not the paper's "significant".
    (Front legs: Model I 3.4 deg, Model II 4.1 deg, both within the servo's range.)
    """
    controller = ControllerParameters()
    saturating_deg = math.degrees(ROBOT.max_leg_torque / controller.brake_kp_back)
    over_i = _brake_overshoot_deg(runs["I"], "back")
    over_ii = _brake_overshoot_deg(runs["II"], "back")
    assert over_i > saturating_deg
    assert over_ii < over_i
    assert over_ii > saturating_deg  # where scoutsim differs from the paper


@pytest.fixture(scope="module")
def fig12_table():
    """The Fig. 12 error table of Model I and Model II against the shipped example data
    (a synthetic virtual Scout II, scoutsim.validation.make_example), as
    `scoutsim compare --example` computes it."""
    from scoutsim.validation import load_dataset
    from scoutsim.validation.errors import compare
    from scoutsim.validation.make_example import example_paths

    return compare(load_dataset(example_paths()), models=("I", "II"))


#: the Fig. 12 metrics on which Model II's mean error is below Model I's on the example data
MODEL_II_BETTER = (
    "stride_frequency_hz",
    "duty_factor_front",
    "pitch_max_deg",
    "height_max_m",
    "height_min_m",
)


def test_fig12_model_ii_errors_below_model_i_in_five_of_seven_and_all_below_25_percent(fig12_table):
    """Fig. 12 text: "the average errors for Model II in all the parameters are below the
    corresponding ones for Model I, and most strikingly, all are smaller than 25%".

    On the shipped example data (a virtual Scout II with leg friction, backlash and gearbox
    losses that neither model has; 66 steady strides): every Model II mean error is below
    25 % (largest: pitch minimum, 12.5 %), as in the paper; Model II's mean error is below
    Model I's in stride frequency, front duty factor, pitch maximum and height maximum and
    minimum, but not in all parameters: Model I's is smaller in the back duty factor
    (0.2 % against 6.7 %) and the pitch minimum (6.5 % against 12.5 %). This is where the
    example data differ from the paper's claim.
    """
    from scoutsim.validation.errors import ERROR_METRICS

    mean = {
        (m, metric): fig12_table.row(m, metric).mean_percent_error
        for m in ("I", "II")
        for metric in ERROR_METRICS
    }
    assert all(math.isfinite(v) for v in mean.values())
    better = tuple(metric for metric in ERROR_METRICS if mean["II", metric] < mean["I", metric])
    assert better == MODEL_II_BETTER
    assert all(mean["II", metric] < 25.0 for metric in ERROR_METRICS)
