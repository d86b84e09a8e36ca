"""The closed-form derivative of the right-hand side (model.derivative.evaluate.evaluate_t)
equals the central difference of the right-hand side itself (model.evaluate.evaluate_ws)
along the same direction, in every model, contact mode and motor-joint mode, with the
effects beyond the paper's models, a battery with internal resistance, unequal legs,
massless legs and the bench rigs; along directions in the state, the toe anchors, the
commands and the robot's parameters, several directions in one call each the derivative
along it alone."""

import math

import numpy as np
import pytest

import scoutsim
from scoutsim import RobotParameters
from scoutsim._core.model import layout as L
from scoutsim._core.model.derivative.evaluate import derivative_workspace, evaluate_t
from scoutsim._core.model.evaluate import evaluate_ws
from scoutsim._core.model.packing import robot_array
from scoutsim._core.numerics.dopri5 import eval_workspace

from ...sample_modes import sample_modes
from ..test_evaluate import EFFECTS

ROBOTS = {
    "default": RobotParameters(),
    "effects and battery": RobotParameters(battery_resistance=0.1, **EFFECTS),
    "unequal legs": RobotParameters(
        com_offset=0.03,
        battery_resistance=0.1,
        leg_mass=(1.0, 0.8),
        leg_stiffness=(3520.0, 3900.0),
        belt_stiffness=(401.0, 370.0),
        current_limit=(12.0, 11.0),
        belt_backlash=(math.radians(0.5), math.radians(0.8)),
    ),
}
#: the whole-robot slots a direction in the parameters moves (the integer codes and flags
#: have no derivative), with every per-leg slot
CONTINUOUS = [
    L.P_MT, L.P_IT, L.P_L, L.P_COM_OFFSET, L.P_G, L.P_VB, L.P_RB, L.P_MU, L.P_STRUT_OMEGA,
    L.P_TD_B, L.P_TD_F,
] + list(range(L.P_ML, L.NP_))  # fmt: skip
#: step of the differences along a direction (whose entries are of the order of the state's
#: and the parameters' own scale, :func:`_direction`): truncation error ~ STEP^2, rounding
#: ~ 1e-16 / STEP of the right-hand side's scale
STEP = 1e-5
#: the right-hand side's rounding in a difference, relative to its largest entry: the
#: derivative's error is measured against at least this scale
NOISE = 1e-6
#: two differences agree (a side converges, both sides are one slope) within this fraction
#: of the derivative's scale: ten times below the error the derivative is allowed, so that
#: a kink in one small entry is not taken for a smooth point
AGREE = 1e-7


def _samples(robot, model, rig=None, massless=False, world=True):
    """(P, [(s, mi, mf, cmd)]): states of a short bounding run, each in every contact and
    motor-joint mode."""
    mu = 0.8 if not massless else math.inf
    r = scoutsim.simulate(robot, duration=0.4, model=model, friction_coefficient=mu)
    P = robot_array(
        robot,
        model,
        friction_coefficient=mu,
        passive_touchdown_angles=(0.3, -0.2),
        passive_touchdown_world=world,
        **(rig or {}),
    )
    contacts = (None, [L.STRUT, L.STICK], [L.SLIDE, L.FLIGHT], [L.FLIGHT, L.SLIDE])
    if rig:
        contacts = ([L.FLIGHT, L.FLIGHT],)
    out = []
    for n in range(3, len(r.t), 37):
        mi, mf, cmd = sample_modes(r, n, 1 if n % 2 else -1)
        for motor, contact in zip(([0, 0], [1, -1], [0, 1], [-1, 1]), contacts * 2):
            mi2 = mi.copy()
            mi2[2:4] = motor
            if contact is not None:
                mi2[0:2] = contact
            out.append((r.state[n].copy(), mi2, mf.copy(), cmd))
    return P, out


def _direction(rng, s, P, with_parameters):
    """A random direction: each state entry by its own scale, the anchors, the commands,
    and (``with_parameters``) each continuous parameter relative to its value."""
    s_t = rng.standard_normal(L.NS) * np.maximum(np.abs(s), 0.1)
    mf_t = rng.standard_normal(L.NMF) * 0.01
    cmd_t = rng.standard_normal(2)
    P_t = np.zeros_like(P)
    if with_parameters:
        P_t[CONTINUOUS] = rng.standard_normal(len(CONTINUOUS)) * P[CONTINUOUS] * 0.1
    return s_t, mf_t, cmd_t, P_t


def _columns(directions):
    """The directions as columns: (s_t (NS, m), mf_t (NMF, m), cmd_t (2, m), P_t (m, len(P)))."""
    return tuple(
        np.ascontiguousarray(np.stack([d[k] for d in directions], axis=1)) for k in range(3)
    ) + (np.ascontiguousarray(np.stack([d[3] for d in directions])),)


def _f(s, P, mi, mf, cmd):
    ds = np.zeros(L.NS)
    aux = np.zeros(L.NAUX)
    ew = eval_workspace()
    evaluate_ws(s, P, mi, mf, cmd, ds, aux, ew, False, ew[3], True)
    return ds


def _moved(case, P, direction, e):
    s, mi, mf, cmd = case
    s_t, mf_t, cmd_t, P_t = direction
    return _f(s + e * s_t, P + e * P_t, mi, mf + e * mf_t, cmd + e * cmd_t)


def _one_sided(case, P, direction, f0, e):
    """The one-sided difference of second order along ``direction`` from the point (value
    ``f0``) towards the side of ``e``: (-3 f0 + 4 f(e) - f(2 e)) / (2 e)."""
    return (-3.0 * f0 + 4.0 * _moved(case, P, direction, e) - _moved(case, P, direction, 2 * e)) / (
        2.0 * e
    )


def _central(case, P, direction):
    """The central difference along ``direction``, Richardson-extrapolated from the steps
    STEP and 2 STEP (error ~ STEP^4)."""

    def c(e):
        return (_moved(case, P, direction, e) - _moved(case, P, direction, -e)) / (2.0 * e)

    return (4.0 * c(STEP) - c(2 * STEP)) / 3.0


def _check(P, cases, with_parameters, seed=0):
    """The largest error of evaluate_t over ``cases`` (relative to the derivative's
    largest entry) against the central difference where the right-hand side is smooth
    over the step (its one-sided differences either side agree; Richardson-extrapolated), and against the one-sided
    difference of the branch it took where a kink lies at the point itself (a limit met
    exactly, a leg at its stop: the derivative is that of one side); and how many cases
    were smooth, how many had a kink at the point and how many could be evaluated. A case with a kink inside the step
    but not at the point, or a jump (the transmission's idle loss switching direction
    at zero torque and speed), is left out."""
    rng = np.random.default_rng(seed)
    dw = derivative_workspace(2)
    dw1 = derivative_workspace(1)
    worst = 0.0
    smooth = 0
    at_kink = 0
    evaluable = 0
    for case in cases:
        s, mi, mf, cmd = case
        direction = _direction(rng, s, P, with_parameters)
        ew = eval_workspace()
        f0 = np.zeros(L.NS)
        aux = np.zeros(L.NAUX)
        if not evaluate_ws(s, P, mi, mf, cmd, f0, aux, ew, False, ew[3], True):
            continue  # singular (a massless leg's slide): no derivative to compare
        evaluable += 1
        # the direction with another one as a second column: each column's numbers are
        # those of the derivative along it alone
        both = np.zeros((L.NS, 2))
        evaluate_t(P, mi, cmd, ew, dw, _columns([direction, _direction(rng, s, P, True)]), both)
        ds_t = np.zeros((L.NS, 1))
        evaluate_t(P, mi, cmd, ew, dw1, _columns([direction]), ds_t)
        assert np.array_equal(ds_t[:, 0], both[:, 0])
        ds_t = ds_t[:, 0]
        sides = [_one_sided(case, P, direction, f0, e) for e in (STEP, -STEP)]
        wide = [_one_sided(case, P, direction, f0, e) for e in (3 * STEP, -3 * STEP)]
        scale = max(np.max(np.abs(sides[0])), np.max(np.abs(sides[1])), NOISE * np.max(np.abs(f0)))
        # each side's difference converges (no kink inside the step, no jump: a jump
        # grows its difference as 1 / step); a case where one does not is left out
        if not all(np.max(np.abs(a - b)) <= AGREE * scale for a, b in zip(sides, wide)):
            continue
        if np.max(np.abs(sides[0] - sides[1])) <= AGREE * scale:
            smooth += 1
            worst = max(worst, np.max(np.abs(ds_t - _central(case, P, direction))) / scale)
        else:
            # a kink at the point itself: the derivative is one side's, entry by entry
            # (both legs at their stops may take different sides)
            err = np.minimum(np.abs(ds_t - sides[0]), np.abs(ds_t - sides[1]))
            worst = max(worst, np.max(err) / scale)
            at_kink += 1
    return worst, smooth, at_kink, evaluable


@pytest.mark.parametrize("model", ["ideal", "I", "II", "passive"])
@pytest.mark.parametrize("robot", list(ROBOTS))
def test_the_derivative_equals_differences_of_the_right_hand_side(model, robot):
    """d f / d direction in closed form = the central difference of f (state, anchors,
    commands and parameters together), in every contact and motor-joint mode."""
    P, cases = _samples(ROBOTS[robot], model)
    worst, smooth, at_kink, evaluable = _check(P, cases, with_parameters=True)
    assert smooth >= 0.25 * evaluable and smooth + at_kink >= 0.6 * evaluable
    assert worst < 1e-6


def test_massless_legs_and_the_bench_rigs():
    """The massless-leg model (flight angles prescribed from the world's vertical or the
    torso's, LU factors) and the rigs' clamps and motor circuits: the same law."""
    massless = RobotParameters(leg_mass=0.0, leg_inertia=0.0, leg_damping=0.0)
    for robot, model, rig, world in (
        (massless, "passive", None, True),
        (massless, "passive", None, False),
        (RobotParameters(), "II", {"clamp_torso": True}, True),
        (RobotParameters(), "II", {"clamp_torso": True, "clamp_legs": True}, True),
        (RobotParameters(), "II", {"clamp_torso": True, "motor_circuit": "short"}, True),
    ):
        P, cases = _samples(robot, model, rig, massless=robot is massless, world=world)
        worst, smooth, at_kink, evaluable = _check(P, cases, with_parameters=True, seed=1)
        # (on the rigs the legs hang in flight at their stops: most points are kinks)
        assert smooth > 0 and smooth + at_kink >= 0.6 * evaluable, (model, rig)
        assert worst < 1e-6, (model, rig, worst)


def _currents(s, P, mi, mf, cmd):
    """The motor currents [A] (aux A_CURRENT of each leg) at a state."""
    ds = np.zeros(L.NS)
    aux = np.zeros(L.NAUX)
    ew = eval_workspace()
    evaluate_ws(s, P, mi, mf, cmd, ds, aux, ew, False, ew[3], True)
    return aux[[leg * L.NAUX_LEG + L.A_CURRENT for leg in (0, 1)]]


@pytest.mark.parametrize("model", ["ideal", "I", "II"])
@pytest.mark.parametrize("robot", list(ROBOTS))
def test_the_motor_currents_derivative_equals_differences_of_the_currents(model, robot):
    """The currents' derivative in closed form (current_derivatives, what the
    identification's exact Jacobian reads for a current channel: the amplifier's branch,
    the motor speed's and the battery's tangents), several directions at once, equals the
    Richardson-extrapolated central difference of the currents the right-hand side
    reports, where both sides' differences agree (no limit met within the step)."""
    from scoutsim._core.model.derivative.currents import current_derivatives

    P, cases = _samples(ROBOTS[robot], model)
    rng = np.random.default_rng(2)
    worst, smooth = 0.0, 0
    for s, mi, mf, cmd in cases:
        dirs = [_direction(rng, s, P, with_parameters=True) for _ in range(3)]
        carried = current_derivatives(
            s,
            P,
            mi,
            mf,
            cmd,
            _columns(dirs)[:3],
            _columns(dirs)[3],
        )
        for j, (s_t, mf_t, cmd_t, P_t) in enumerate(dirs):
            case = (s, mi, mf, cmd, s_t, mf_t, cmd_t, P_t)

            def moved(e, case=case):
                s, mi, mf, cmd, s_t, mf_t, cmd_t, P_t = case
                return _currents(s + e * s_t, P + e * P_t, mi, mf + e * mf_t, cmd + e * cmd_t)

            i0 = moved(0.0)
            sides = [(moved(e) - i0) / e for e in (STEP, -STEP)]
            wide = [(moved(e) - i0) / e for e in (2 * STEP, -2 * STEP)]
            scale = max(np.max(np.abs(sides[0])), 1e-3)  # [A per unit of the direction]
            # smooth over the step: each side converges and both sides are one slope
            # (first-order sides: agreement within STEP times the curvature, ~1e-4)
            if not all(np.max(np.abs(a - b)) <= 1e-4 * scale for a, b in zip(sides, wide)):
                continue
            if np.max(np.abs(sides[0] - sides[1])) > 1e-4 * scale:
                continue
            c1 = (moved(STEP) - moved(-STEP)) / (2 * STEP)
            c2 = (moved(2 * STEP) - moved(-2 * STEP)) / (4 * STEP)
            central = (4.0 * c1 - c2) / 3.0
            smooth += 1
            worst = max(worst, np.max(np.abs(carried[:, j] - central)) / scale)
    assert smooth >= 0.5 * 3 * len(cases), (smooth, len(cases))
    assert worst < 1e-6, worst
