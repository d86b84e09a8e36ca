"""The actuator's and the hip unit's derivatives (scoutsim._core.model.derivative.actuator)
against central differences of the compiled primal functions along the same direction.

Each case is a realistic parameter array (``robot_array`` of the packaged robot) in one
branch of the primal, away from its kinks by far more than the difference step; the
direction is random in the inputs and in the float slots of P the function reads
(relative to their values, so one step is a relative change of about ``H``).
"""

from __future__ import annotations

import numpy as np
import pytest

from scoutsim._core.model import actuator, transmission
from scoutsim._core.model import layout as L
from scoutsim._core.model.derivative import actuator as D
from scoutsim._core.model.packing import robot_array
from scoutsim.parameters import load_robot

#: central-difference step (relative: the directions are scaled to the values)
H = 1e-6
#: relative tolerance of a tangent against the central difference
RTOL = 1e-7

MOTOR_SLOTS = (L.P_N, L.P_ETA, L.P_KT, L.P_IMAX, L.P_RA, L.P_KW)
LOSS_SLOTS = (L.P_N, L.P_ETA, L.P_KT, L.P_TAU_IDLE, L.P_C_LOAD)
HIP_SLOTS = (L.P_N, L.P_B_J, L.P_TAU_S, L.P_KB, L.P_CB, L.P_BACKLASH)


#: the largest relative error each test measured (read by a report, not by the tests)
def packed(model="I", circuit="amplifier", **overrides):
    return robot_array(load_robot(overrides=overrides or None), model, motor_circuit=circuit)


def direction(rng, P, slots, whole=()):
    """A random tangent of P in the per-leg ``slots`` (both legs) and the whole-robot
    slots ``whole``, relative to their values (absolute where a value is zero)."""
    P_t = np.zeros_like(P)
    for s in whole:
        P_t[s] = rng.uniform(-1.0, 1.0) * (abs(P[s]) or 1.0)
    for s in slots:
        for leg in range(2):
            P_t[s + leg] = rng.uniform(-1.0, 1.0) * (abs(P[s + leg]) or 1e-2)
    return P_t


def column(x):
    """A tangent vector as the one column of a batched tangent (rows, 1)."""
    return np.ascontiguousarray(np.asarray(x, dtype=float)[:, None])


def central(f):
    """Central difference of f(h) at h = 0 with step H."""
    return (np.asarray(f(H)) - np.asarray(f(-H))) / (2.0 * H)


def check(name, tangent, fd, rtol=RTOL, scale=0.0):
    """Assert |tangent - fd| <= rtol max(|fd|, scale) (elementwise for vectors: against
    the largest entry)."""
    tangent = np.atleast_1d(np.asarray(tangent, dtype=float))
    fd = np.atleast_1d(np.asarray(fd, dtype=float))
    ref = max(float(np.max(np.abs(fd))), scale)
    err = float(np.max(np.abs(tangent - fd)))
    rel = err / ref if ref > 0.0 else err
    assert err <= rtol * ref, (name, tangent, fd, rel)


# --- motor speed ---------------------------------------------------------------------


@pytest.mark.parametrize("model", ["I", "II"])
@pytest.mark.parametrize("leg", [0, 1])
def test_motor_speed_tangent_is_the_central_difference_of_motor_speed(model, leg):
    """The tangent of the motor speed N x (gear or leg rate) equals the central difference
    of motor_speed (the driven gear's rate in Model II, the leg's otherwise)."""
    rng = np.random.default_rng(1 + leg)
    P = packed(model)
    dq = rng.uniform(-5.0, 5.0, L.NQ)
    dq_t = rng.uniform(-5.0, 5.0, L.NQ)
    P_t = direction(rng, P, (L.P_N,))
    t = D.motor_speed_t(column(dq_t), 0, leg, P, dq, P_t)
    fd = central(lambda h: transmission.motor_speed(dq + h * dq_t, leg, P + h * P_t))
    check("motor_speed", t, fd)


# --- motor current -------------------------------------------------------------------

# (model, circuit, cmd [N m], motor speed [rad/s], V_b [V], leg, branch)
CURRENT_CASES = [
    ("I", "amplifier", 10.0, 100.0, 36.0, 0, D.CUR_COMMAND),
    ("I", "amplifier", 40.0, 100.0, 36.0, 1, D.CUR_LIMIT_POS),
    ("I", "amplifier", -40.0, -100.0, 30.0, 0, D.CUR_LIMIT_NEG),
    ("I", "amplifier", 20.0, 800.0, 36.0, 0, D.CUR_LINE_POS),
    ("I", "amplifier", -20.0, -800.0, 33.0, 1, D.CUR_LINE_NEG),
    # back-driven so fast that the line's current is beyond i_max
    ("I", "amplifier", 40.0, -1500.0, 36.0, 0, D.CUR_LINE_NEG),
    ("I", "amplifier", -40.0, 1500.0, 36.0, 1, D.CUR_LINE_POS),
    ("II", "amplifier", 20.0, 800.0, 36.0, 1, D.CUR_LINE_POS),
    ("ideal", "amplifier", 40.0, 800.0, 36.0, 0, D.CUR_LIMIT_POS),
    ("ideal", "amplifier", 10.0, 800.0, 36.0, 1, D.CUR_COMMAND),
    ("I", "short", 10.0, 300.0, 36.0, 0, D.CUR_SHORT),
    ("I", "short", 10.0, -300.0, 36.0, 1, D.CUR_SHORT),
    ("I", "open", 10.0, 300.0, 36.0, 0, D.CUR_ZERO),
    ("passive", "amplifier", 10.0, 300.0, 36.0, 0, D.CUR_ZERO),
]


@pytest.mark.parametrize("case", CURRENT_CASES, ids=lambda c: f"{c[0]}-{c[1]}-{c[6]}")
def test_motor_current_tangent_is_the_central_difference_of_motor_current(case):
    """The tangent of the amplifier's motor current equals the central difference of
    motor_current on each branch: the command, either current limit i_max, either side of
    the torque-speed line (also beyond i_max), shorted and open leads, passive."""
    model, circuit, cmd, om, vb, leg, branch = case
    rng = np.random.default_rng(10 + branch)
    P = packed(model, circuit)
    assert D.current_branch(cmd, om, vb, leg, P) == branch
    cmd_t, om_t, vb_t = rng.uniform(-1.0, 1.0, 3) * (abs(cmd), abs(om), vb)
    P_t = direction(rng, P, MOTOR_SLOTS)
    branch = D.current_branch(cmd, om, vb, leg, P)
    t = D.branch_current_t(branch, cmd, om, vb, leg, P, (cmd_t, om_t, vb_t, P_t))
    fd = central(
        lambda h: actuator.motor_current(
            cmd + h * cmd_t, om + h * om_t, vb + h * vb_t, leg, P + h * P_t
        )
    )
    if branch == D.CUR_ZERO:
        assert t == 0.0 and fd == 0.0
        return
    check("motor_current", t, fd)
    # and the partial derivative in V_b alone is the slope the battery's solve uses
    slope = central(lambda h: actuator.motor_current(cmd, om, vb + h * vb, leg, P)) / vb
    check("current_voltage_slope", D.current_voltage_slope(cmd, om, vb, leg, P), slope, scale=1.0)


# --- delivered torque ----------------------------------------------------------------

IDLE = 0.5
CLOAD = 0.05

# (current [A], motor speed [rad/s]); the gear's hip torque per ampere is about 2.6 N m/A
LOSS_CASES = [
    (3.0, 50.0),  # motoring
    (-3.0, -50.0),  # motoring
    (3.0, -50.0),  # back-driven
    (-3.0, 50.0),  # back-driven
    (0.0, 50.0),  # no current, output turning: idle friction alone
    (3.0, 0.3),  # blend
    (-2.0, -0.6),  # blend
    (0.1, 50.0),  # motoring, the loss larger than tau_0: held at zero
    (0.1, 0.4),  # blend of that and the back-driven branch
]


@pytest.mark.parametrize("cur, om", LOSS_CASES)
@pytest.mark.parametrize("leg", [0, 1])
def test_delivered_torque_tangent_is_the_central_difference_of_delivered_torque(cur, om, leg):
    """The tangent of the delivered torque with transmission losses equals the central
    difference of delivered_torque: motoring, back-driven, their linear blend at low
    speed, and the motoring torque held at zero (tangent 0)."""
    rng = np.random.default_rng(20 + leg)
    P = packed("I", gearbox_idle_loss_torque=IDLE, gearbox_load_loss_coefficient=CLOAD)
    cur_t, om_t = rng.uniform(-1.0, 1.0, 2) * (abs(cur) or 1.0, abs(om))
    if cur == 0.0:
        cur_t = 0.0  # (tau_0 = 0 is the motoring / back-driven kink)
    P_t = direction(rng, P, LOSS_SLOTS)
    t = D.delivered_torque_t(cur, om, leg, P, cur_t, om_t, P_t)
    fd = central(
        lambda h: actuator.delivered_torque(cur + h * cur_t, om + h * om_t, leg, P + h * P_t)
    )
    if cur == 0.1 and om >= 1.0:
        assert t == 0.0 and fd == 0.0
        return
    check("delivered_torque", t, fd)


@pytest.mark.parametrize("cur, om", [(3.0, 50.0), (3.0, -50.0), (2.0, 0.3), (0.0, -50.0)])
@pytest.mark.parametrize("losses_move", [False, True])
def test_delivered_torque_tangent_without_losses(cur, om, losses_move):
    """Without losses the tangent of the delivered torque equals the central difference of
    delivered_torque: tau_0's (N eta K_T i)' for a direction that keeps the losses at
    zero, and the lossy law's (smooth across zero losses) for one that moves them."""
    rng = np.random.default_rng(30)
    P = packed("I")
    assert P[L.P_TAU_IDLE] == 0.0 and P[L.P_C_LOAD] == 0.0
    cur_t = rng.uniform(-1.0, 1.0) * (abs(cur) or 1.0) if cur else 0.0
    om_t = rng.uniform(-1.0, 1.0) * abs(om)
    slots = LOSS_SLOTS if losses_move else (L.P_N, L.P_ETA, L.P_KT)
    P_t = direction(rng, P, slots)
    t = D.delivered_torque_t(cur, om, 0, P, cur_t, om_t, P_t)
    fd = central(
        lambda h: actuator.delivered_torque(cur + h * cur_t, om + h * om_t, 0, P + h * P_t)
    )
    check("delivered_torque (no losses)", t, fd)
    if not losses_move:
        k = actuator.torque_per_amp(0, P)
        assert t == D.torque_per_amp_t(0, P, P_t) * cur + k * cur_t


# --- battery voltage -----------------------------------------------------------------

BATTERY_SLOTS = MOTOR_SLOTS


def rates(model, back, front):
    """Rates dq with the motors' coordinates (alpha in Model II, phi otherwise) at
    ``back``, ``front`` [rad/s] and the rest moderate."""
    dq = np.array([0.8, -0.3, 0.5, 0.0, 0.0, 0.0, 0.0])
    i = L.IALB if model == "II" else L.IPHB
    dq[i] = back
    dq[i + 1] = front
    if model == "II":
        dq[L.IPHB : L.IPHB + 2] = (back - 0.2, front + 0.3)
    return dq


# (name, model, circuit, R_b [ohm], (back, front) rates [rad/s], cmd [N m], branches)
BATTERY_CASES = [
    ("both motors on their lines", "I", "amplifier", 0.5, (8.0, -7.5), (20.0, -20.0), (6, 5)),
    ("one on its line, one at i_max", "I", "amplifier", 0.5, (8.0, 1.0), (40.0, 40.0), (6, 4)),
    ("both at their commands", "I", "amplifier", 0.5, (1.0, -1.0), (10.0, -10.0), (2, 2)),
    ("Model II on the lines", "II", "amplifier", 0.3, (8.0, -7.5), (20.0, -20.0), (6, 5)),
    ("back-driven beyond i_max", "I", "amplifier", 0.2, (-15.0, 3.0), (40.0, 20.0), (5, 2)),
    ("shorted leads", "I", "short", 0.5, (8.0, -7.5), (20.0, -20.0), (1, 1)),
    ("open leads", "I", "open", 0.5, (8.0, -7.5), (20.0, -20.0), (0, 0)),
    ("ideal source R_b = 0", "I", "amplifier", 0.0, (8.0, -7.5), (20.0, -20.0), (6, 5)),
    ("ideal variant", "ideal", "amplifier", 0.5, (8.0, -7.5), (20.0, -20.0), (2, 2)),
    ("passive", "passive", "amplifier", 0.5, (8.0, -7.5), (20.0, -20.0), (0, 0)),
    ("collapsed at V_oc / 2", "I", "amplifier", 10.0, (0.5, 0.5), (40.0, 40.0), (4, 4)),
]


@pytest.mark.parametrize("case", BATTERY_CASES, ids=lambda c: c[0])
def test_battery_voltage_tangent_is_the_central_difference_of_battery_voltage(case):
    """The tangent of the battery voltage equals the central difference of
    battery_voltage: by the implicit function theorem with a motor on its torque-speed line
    (the current depends on V), with currents at i_max or at the command, in Model II, for
    shorted and open leads, the ideal source (R_b = 0: V_oc's tangent; the direction
    leaves R_b, whose primal is flat on R_b <= 0), the ideal and passive variants, and a
    battery collapsed to V_oc / 2 (V_oc's tangent / 2)."""
    name, model, circuit, rb, (wb, wf), cmd, branches = case
    rng = np.random.default_rng(40 + BATTERY_CASES.index(case))
    P = packed(model, circuit)
    P[L.P_RB] = rb
    dq = rates(model, wb, wf)
    cmd = np.array(cmd)
    vb = actuator.battery_voltage(dq, cmd, P)
    found = tuple(
        D.current_branch(cmd[leg], transmission.motor_speed(dq, leg, P), vb, leg, P)
        for leg in range(2)
    )
    assert found == branches, found
    if name.startswith("collapsed"):
        assert vb == 0.5 * P[L.P_VB]
    elif rb > 0.0 and model == "I" and circuit == "amplifier":
        assert abs(vb - P[L.P_VB]) > 0.05  # the battery's resistance matters
    whole = (L.P_VB,) if rb == 0.0 else (L.P_VB, L.P_RB)
    P_t = direction(rng, P, BATTERY_SLOTS, whole)
    dq_t = rng.uniform(-5.0, 5.0, L.NQ)
    cmd_t = rng.uniform(-5.0, 5.0, 2)
    vb_t = np.zeros(1)
    D.battery_voltage_t(dq, cmd, P, vb, (column(dq_t), column(cmd_t), P_t[None, :].copy()), vb_t)
    t = vb_t[0]
    fd = central(lambda h: actuator.battery_voltage(dq + h * dq_t, cmd + h * cmd_t, P + h * P_t))
    check("battery_voltage", t, fd, scale=abs(P_t[L.P_VB]))
    if circuit == "open" or rb == 0.0 or model in ("ideal", "passive"):
        assert t == P_t[L.P_VB]
    if name.startswith("collapsed"):
        assert t == 0.5 * P_t[L.P_VB]


# --- hip unit forces -----------------------------------------------------------------


def configuration(delta):
    """A configuration whose back and front gear/leg differences alpha - phi are
    ``delta`` (back, front) [rad]."""
    q = np.array([0.1, 0.45, 0.05, 0.3, -0.2, 0.0, 0.0])
    q[L.IALB : L.IALB + 2] = q[L.IPHB : L.IPHB + 2] + np.asarray(delta)
    return q


# (name, model, play b [rad], (back, front) alpha - phi [rad])
HIP_CASES = [
    ("belt", "II", 0.0, (0.01, -0.02)),
    ("play, beyond both ends", "II", 0.02, (0.03, -0.025)),
    ("play, inside and beyond", "II", 0.02, (0.004, 0.035)),
    ("Model I", "I", 0.0, (0.0, 0.0)),
    ("ideal", "ideal", 0.0, (0.0, 0.0)),
    ("passive", "passive", 0.0, (0.0, 0.0)),
]


@pytest.mark.parametrize("case", HIP_CASES, ids=lambda c: c[0])
@pytest.mark.parametrize("mode", [L.SLIP_POS, L.SLIP_NEG, L.STUCK])
@pytest.mark.parametrize("leg", [0, 1])
def test_hip_unit_forces_tangent_is_the_central_difference_of_hip_unit_forces(case, mode, leg):
    """The tangent of the hip unit's generalized forces (and of its joint friction and
    belt torques) equals the central difference of hip_unit_forces at the motor speed of
    the rates: the delivered torque on the gear (Model II) or the leg, the joint's viscous
    and Coulomb friction in each stick/slip mode, the belt spring engaged or in its play
    (whose tangent moves the play's ends) and the belt damper."""
    name, model, play, delta = case
    rng = np.random.default_rng(50 + 3 * leg + mode)
    P = packed(model, belt_backlash=play) if play else packed(model)
    q = configuration(delta)
    dq = rng.uniform(-3.0, 3.0, L.NQ)
    q_t = rng.uniform(-1.0, 1.0, L.NQ)
    dq_t = rng.uniform(-3.0, 3.0, L.NQ)
    tapp, tapp_t = 7.0, rng.uniform(-7.0, 7.0)
    P_t = direction(rng, P, HIP_SLOTS)
    om_t = D.motor_speed_t(column(dq_t), 0, leg, P, dq, P_t)
    Q_t = np.zeros((L.NQ, 1))
    tf_t, tb_t = np.zeros(1), np.zeros(1)
    D.hip_unit_forces_t(
        Q_t,
        q,
        dq,
        leg,
        mode,
        P,
        (column(q_t), column(dq_t), np.array([tapp_t]), np.array([om_t]), P_t[None, :].copy()),
        (tf_t, tb_t),
    )
    Q_t, tf_t, tb_t = Q_t[:, 0], tf_t[0], tb_t[0]

    def forces(h):
        Q = np.zeros(L.NQ)
        Ph = P + h * P_t
        dqh = dq + h * dq_t
        om = transmission.motor_speed(dqh, leg, Ph)
        tf, tb = transmission.hip_unit_forces(
            Q, q + h * q_t, dqh, leg, tapp + h * tapp_t, om, mode, Ph
        )
        return np.concatenate([Q, [tf, tb]])

    fd = central(forces)
    check("hip_unit_forces", np.concatenate([Q_t, [tf_t, tb_t]]), fd)
    if model == "passive":
        assert not Q_t.any()
    if model != "II":
        assert tf_t == 0.0 and tb_t == 0.0
    else:
        assert tb_t != 0.0 and tf_t != 0.0
