"""Derivative of the actuator (:mod:`scoutsim._core.model.actuator`: the amplifier's motor
current, the torque the transmission delivers with its losses, the battery's terminal
voltage) and of what a hip unit adds to the generalized forces
(:func:`~scoutsim._core.model.transmission.hip_unit_forces`, with the motor speed
:func:`~scoutsim._core.model.transmission.motor_speed` it is driven at).

The amplifier's current is on one of the branches :func:`current_branch` names (no
current, the shorted leads, the command, either current limit, either side of the
torque-speed line): its tangent is that branch's. The battery's voltage solves
V = F(V) (:func:`~scoutsim._core.model.actuator.battery_voltage`); its tangent follows from
the implicit function theorem, V_t = F_x x_t / (1 - F_V), with F's partial derivatives in
closed form at the solution.

P[P_NP], the number of physical legs a virtual leg stands for, is a count, not a quantity
with a derivative: its tangent is not read.
"""

from __future__ import annotations

import math

from ...._numba.jit import kernel
from ..actuator import LOSS_SPEED_REG, motor_current, torque_per_amp
from ..hip_unit import belt_spring, geared
from ..layout import (
    CIRCUIT_OPEN,
    CIRCUIT_SHORT,
    IALB,
    IPHB,
    MODEL_IDEAL,
    MODEL_PASSIVE,
    P_B_J,
    P_BACKLASH,
    P_C_LOAD,
    P_CB,
    P_CIRCUIT,
    P_ETA,
    P_IMAX,
    P_KB,
    P_KT,
    P_KW,
    P_MODEL,
    P_N,
    P_NP,
    P_RA,
    P_RB,
    P_TAU_IDLE,
    P_TAU_S,
    P_VB,
    STUCK,
)
from ..transmission import joint_friction_torque, motor_speed

# the branches of the amplifier's current (motor_current), what current_branch returns
CUR_ZERO = 0  # no current: passive, or the motor leads open
CUR_SHORT = 1  # the leads shorted: -K_w w_m / R_A
CUR_COMMAND = 2  # the commanded current tau / (N eta K_T)
CUR_LIMIT_NEG = 3  # at the current limit -i_max
CUR_LIMIT_POS = 4  # at the current limit +i_max
CUR_LINE_NEG = 5  # on the torque-speed line's low side (-V_b - K_w w_m) / R_A
CUR_LINE_POS = 6  # on its high side (V_b - K_w w_m) / R_A


@kernel(inline="always")
def torque_per_amp_t(leg, P, P_t):
    """Tangent [N m / A] of :func:`~scoutsim._core.model.actuator.torque_per_amp`, the hip
    torque per ampere N eta K_T of virtual leg ``leg``."""
    N = P[P_N + leg]
    eta = P[P_ETA + leg]
    kt = P[P_KT + leg]
    return P_t[P_N + leg] * eta * kt + N * P_t[P_ETA + leg] * kt + N * eta * P_t[P_KT + leg]


@kernel(inline="always")
def motor_speed_t(dq_t, c, leg, P, dq, P_t):
    """Tangent [rad/s] of :func:`~scoutsim._core.model.transmission.motor_speed`, the motor
    speed N x (the rate of the driven gear alpha of a geared unit, of the leg phi
    otherwise) of virtual leg ``leg``, for column ``c`` of the tangents ``dq_t`` (NQ, m)
    of the rates ``dq``; ``P_t``: that column's parameter tangents."""
    i = IALB + leg if geared(P) else IPHB + leg
    return P_t[P_N + leg] * dq[i] + P[P_N + leg] * dq_t[i, c]


@kernel(inline="always")
def current_branch(cmd_torque, omega_m, vb, leg, P):
    """The branch (``CUR_*``) of :func:`~scoutsim._core.model.actuator.motor_current` the
    motor current of virtual leg ``leg`` is on for the commanded torque ``cmd_torque``
    [N m] at motor speed ``omega_m`` [rad/s] and battery voltage ``vb`` [V]: the same
    comparisons in the same order as the primal's."""
    model = int(P[P_MODEL])
    if model == MODEL_PASSIVE:
        return CUR_ZERO
    circuit = int(P[P_CIRCUIT])
    if circuit == CIRCUIT_OPEN:
        return CUR_ZERO
    if circuit == CIRCUIT_SHORT:
        return CUR_SHORT
    imax = P[P_IMAX + leg]
    ic = cmd_torque / torque_per_amp(leg, P)
    branch = CUR_COMMAND
    if ic < -imax:
        ic = -imax
        branch = CUR_LIMIT_NEG
    if ic > imax:
        ic = imax
        branch = CUR_LIMIT_POS
    if model != MODEL_IDEAL:
        r = P[P_RA + leg]
        v_lo = (-vb - P[P_KW + leg] * omega_m) / r
        v_hi = (vb - P[P_KW + leg] * omega_m) / r
        if ic < v_lo:
            ic = v_lo
            branch = CUR_LINE_NEG
        if ic > v_hi:
            branch = CUR_LINE_POS
    return branch


@kernel(inline="always")
def branch_current_t(branch, cmd, om, vb, leg, P, tangents):
    """Tangent [A] of :func:`~scoutsim._core.model.actuator.motor_current` (the motor
    current of virtual leg ``leg`` for the commanded torque ``cmd`` [N m] at motor speed
    ``om`` [rad/s] and battery voltage ``vb`` [V]) on the given ``branch`` (``CUR_*``, the
    one :func:`current_branch` names for them); ``tangents`` = (cmd_t,
    om_t, vb_t, P_t). Where the current sits on a kink (two branches give the same value),
    the caller chooses the side."""
    cmd_t, om_t, vb_t, P_t = tangents
    if branch == CUR_ZERO:
        return 0.0
    if branch == CUR_COMMAND:
        k = torque_per_amp(leg, P)
        return (cmd_t - cmd / k * torque_per_amp_t(leg, P, P_t)) / k
    if branch == CUR_LIMIT_NEG:
        return -P_t[P_IMAX + leg]
    if branch == CUR_LIMIT_POS:
        return P_t[P_IMAX + leg]
    kw = P[P_KW + leg]
    r = P[P_RA + leg]
    # the shorted leads (no voltage) or a side of the line: i = (s V_b - K_w w_m) / R_A
    s = 0.0
    if branch == CUR_LINE_NEG:
        s = -1.0
    elif branch == CUR_LINE_POS:
        s = 1.0
    i = (s * vb - kw * om) / r
    return (s * vb_t - P_t[P_KW + leg] * om - kw * om_t - i * P_t[P_RA + leg]) / r


@kernel(inline="always")
def current_voltage_slope(cmd, om, vb, leg, P):
    """Partial derivative [A/V] of :func:`~scoutsim._core.model.actuator.motor_current`
    with respect to the battery voltage ``vb``: +-1 / R_A on the torque-speed line's high /
    low side, 0 on every other branch."""
    branch = current_branch(cmd, om, vb, leg, P)
    if branch == CUR_LINE_POS:
        return 1.0 / P[P_RA + leg]
    if branch == CUR_LINE_NEG:
        return -1.0 / P[P_RA + leg]
    return 0.0


@kernel(inline="always")
def _loss_branch_t(tau0, d, idle, cl, tau0_t, idle_t, cl_t):
    """(value [N m], tangent [N m]) of the actuator's delivered torque for output motion in
    direction d = +-1 (its ``_loss_branch``), for the tangents of the constant-efficiency
    torque ``tau0``, the idle loss ``idle`` and the load loss coefficient ``cl``."""
    if tau0 * d > 0.0:
        # motoring: sign(tau0) = d, |tau0| = d tau0
        mag = (abs(tau0) - idle) / (1.0 + cl)
        if mag < 0.0:
            return 0.0, 0.0  # the loss eats the whole torque: held at zero
        mag_t = (d * tau0_t - idle_t - mag * cl_t) / (1.0 + cl)
        return (mag if tau0 > 0.0 else -mag), d * mag_t
    # back-driven (tau0 d <= 0, so |tau0| = -d tau0): (tau0 - d idle) / (1 - cl)
    val = -d * (abs(tau0) + idle) / (1.0 - cl)
    return val, (tau0_t - d * idle_t + val * cl_t) / (1.0 - cl)


@kernel(inline="always")
def delivered_torque_t(cur, om, leg, P, cur_t, om_t, P_t):
    """Tangent [N m] of :func:`~scoutsim._core.model.actuator.delivered_torque` (the torque
    delivered to virtual leg ``leg`` per physical leg for the motor current ``cur`` [A] at
    motor speed ``om`` [rad/s]), for the tangents ``cur_t``, ``om_t`` and ``P_t`` (N, eta,
    K_T, tau_idle, c_load): the motoring or back-driven branch for |w_m| >= LOSS_SPEED_REG,
    their linear blend below it.

    Without losses (tau_idle = c_load = 0) and a direction that leaves them at zero this is
    the tangent of tau_0 = N eta K_T i; a direction that changes them gets the tangent of
    the lossy law, which is smooth across zero losses (the primal's exact return of tau_0
    there is the same value)."""
    k = torque_per_amp(leg, P)
    tau0 = k * cur
    tau0_t = torque_per_amp_t(leg, P, P_t) * cur + k * cur_t
    idle = P[P_TAU_IDLE + leg]
    cl = P[P_C_LOAD + leg]
    idle_t = P_t[P_TAU_IDLE + leg]
    cl_t = P_t[P_C_LOAD + leg]
    if idle == 0.0 and cl == 0.0 and idle_t == 0.0 and cl_t == 0.0:
        return tau0_t
    w = om / LOSS_SPEED_REG
    if w >= 1.0:
        return _loss_branch_t(tau0, 1.0, idle, cl, tau0_t, idle_t, cl_t)[1]
    if w <= -1.0:
        return _loss_branch_t(tau0, -1.0, idle, cl, tau0_t, idle_t, cl_t)[1]
    fwd, fwd_t = _loss_branch_t(tau0, 1.0, idle, cl, tau0_t, idle_t, cl_t)
    bwd, bwd_t = _loss_branch_t(tau0, -1.0, idle, cl, tau0_t, idle_t, cl_t)
    w_t = om_t / LOSS_SPEED_REG
    return 0.5 * w_t * (fwd - bwd) + 0.5 * (1.0 + w) * fwd_t + 0.5 * (1.0 - w) * bwd_t


@kernel(inline="always")
def battery_voltage_t(dq, cmd, P, vb, tangents, vb_t):
    """vb_t[c] := the tangent [V] of :func:`~scoutsim._core.model.actuator.battery_voltage`
    (the battery's terminal voltage for the rates ``dq`` and the commanded torques ``cmd``
    [N m]) along column c, given its value ``vb`` [V]; ``tangents`` = (dq_t (NQ, m), cmd_t
    (2, m), P_t (m, NP)): the columns' tangents of the rates, the commands and the
    parameters (V_oc, R_b and the motors' N, eta, K_T, i_max, R_A, K_w).

    An ideal source (R_b <= 0, or the ideal or passive variant): V_oc's tangent. Otherwise
    V solves V = F(V) = (V_oc + sqrt(D)) / 2, D = V_oc^2 - 4 R_b P(V), P(V) the motors'
    power at their currents for V; by the implicit function theorem
    V_t = F_x x_t / (1 - F_V), with F_x x_t = (V_oc_t + (V_oc V_oc_t - 2 (R_b_t P +
    R_b P_x x_t)) / sqrt(D)) / 2 and F_V = -R_b P_V / sqrt(D) <= 0 (P_V >= 0: only a motor
    on its torque-speed line draws a current that depends on V). Where the battery
    collapses (D <= 0 at the solution, V = V_oc / 2, the primal's lower bracket end) F is
    V_oc / 2 and the tangent V_oc_t / 2."""
    dq_t, cmd_t, P_t = tangents
    m = dq_t.shape[1]
    voc = P[P_VB]
    rb = P[P_RB]
    model = int(P[P_MODEL])
    if rb <= 0.0 or model == MODEL_IDEAL or model == MODEL_PASSIVE:
        for c in range(m):
            vb_t[c] = P_t[c, P_VB]
        return
    if vb <= 0.5 * voc:
        for c in range(m):
            vb_t[c] = 0.5 * P_t[c, P_VB]
        return
    npl = P[P_NP]
    # the primal power P and its voltage slope P_V, leg by leg
    pw = 0.0
    pw_v = 0.0  # P_V
    om0 = motor_speed(dq, 0, P)
    om1 = motor_speed(dq, 1, P)
    i0 = motor_current(cmd[0], om0, vb, 0, P)
    i1 = motor_current(cmd[1], om1, vb, 1, P)
    br0 = current_branch(cmd[0], om0, vb, 0, P)
    br1 = current_branch(cmd[1], om1, vb, 1, P)
    # P = n_p i (R_A i + K_w w_m): dP/di = n_p (2 R_A i + K_w w_m)
    dpdi0 = npl * (2.0 * P[P_RA] * i0 + P[P_KW] * om0)
    dpdi1 = npl * (2.0 * P[P_RA + 1] * i1 + P[P_KW + 1] * om1)
    pw += npl * i0 * (P[P_RA] * i0 + P[P_KW] * om0)
    pw_v += dpdi0 * current_voltage_slope(cmd[0], om0, vb, 0, P)
    pw += npl * i1 * (P[P_RA + 1] * i1 + P[P_KW + 1] * om1)
    pw_v += dpdi1 * current_voltage_slope(cmd[1], om1, vb, 1, P)
    disc = voc * voc - 4.0 * rb * pw
    if disc <= 0.0:
        for c in range(m):
            vb_t[c] = 0.5 * P_t[c, P_VB]
        return
    sd = math.sqrt(disc)
    f_v = -rb * pw_v / sd
    for c in range(m):
        Pc = P_t[c]
        pw_t = 0.0  # P_x x_t: at fixed V
        om_t = motor_speed_t(dq_t, c, 0, P, dq, Pc)
        i_t = branch_current_t(br0, cmd[0], om0, vb, 0, P, (cmd_t[0, c], om_t, 0.0, Pc))
        pw_t += dpdi0 * i_t + npl * i0 * (Pc[P_RA] * i0 + Pc[P_KW] * om0 + P[P_KW] * om_t)
        om_t = motor_speed_t(dq_t, c, 1, P, dq, Pc)
        i_t = branch_current_t(br1, cmd[1], om1, vb, 1, P, (cmd_t[1, c], om_t, 0.0, Pc))
        pw_t += dpdi1 * i_t + npl * i1 * (
            Pc[P_RA + 1] * i1 + Pc[P_KW + 1] * om1 + P[P_KW + 1] * om_t
        )
        voc_t = Pc[P_VB]
        f_x = 0.5 * (voc_t + (voc * voc_t - 2.0 * (Pc[P_RB] * pw + rb * pw_t)) / sd)
        vb_t[c] = f_x / (1.0 - f_v)


@kernel(inline="always")
def _belt_branch(q, leg, P):
    """(deflection [rad], engaged, s) of virtual leg ``leg``'s belt spring
    (:func:`~scoutsim._core.model.hip_unit.belt_spring` at alpha - phi): the deflection's
    tangent is delta_t - s b_t / 2 (b the play) while the spring is engaged, s the sign of
    delta - deflection (+1 beyond the play's upper end, -1 beyond its lower end, 0 for a
    belt without play), and 0 inside the play."""
    delta = q[IALB + leg] - q[IPHB + leg]
    bd, engaged = belt_spring(delta, leg, P)
    off = delta - bd
    s = 1.0 if off > 0.0 else (-1.0 if off < 0.0 else 0.0)
    return bd, engaged, s


@kernel(inline="always")
def hip_unit_forces_t(Q_t, q, dq, leg, mode, P, tangents, out):
    """Add to ``Q_t`` (NQ, m) the tangent, column by column, of what
    :func:`~scoutsim._core.model.transmission.hip_unit_forces` adds to the generalized
    forces Q [N m per unit of the coordinate, N] for virtual leg ``leg`` in motor-joint
    mode ``mode``; ``tangents`` = (q_t (NQ, m), dq_t (NQ, m), tapp_t (m,), om_t (m,), P_t
    (m, NP)): the columns' tangents of the state, of the delivered torque, of the motor
    speed (its value is motor_speed(dq, leg, P), as the evaluation passes it) and of the
    parameters (N, b_J, tau_s, k_b, c_b, the play b).

    ``out`` = (tf_t, tb_t) (m,): the tangents [N m] of what it returns (joint friction
    torque at the motor, belt torque on the leg), both 0 outside Model II. The joint
    friction b_J w_m (+ tau_s mode while slipping) and the belt's k_b x deflection + c_b
    (alpha' - phi') are differentiated on the branch the primal took (the mode, the belt
    engaged or in its play)."""
    q_t, dq_t, tapp_t, om_t, P_t = tangents
    tf_t, tb_t = out
    m = q_t.shape[1]
    npl = P[P_NP]
    k = IPHB + leg
    if geared(P):
        a = IALB + leg
        om = motor_speed(dq, leg, P)
        tf = joint_friction_torque(om, mode, leg, P)
        bd, engaged, s = _belt_branch(q, leg, P)
        rate = dq[a] - dq[k]
        for c in range(m):
            Pc = P_t[c]
            tf_c = Pc[P_B_J + leg] * om + P[P_B_J + leg] * om_t[c]
            if mode != STUCK:
                tf_c += Pc[P_TAU_S + leg] * mode
            bd_t = q_t[a, c] - q_t[k, c] - s * 0.5 * Pc[P_BACKLASH + leg] if engaged else 0.0
            rate_t = dq_t[a, c] - dq_t[k, c]
            tb_c = Pc[P_KB + leg] * bd + P[P_KB + leg] * bd_t + Pc[P_CB + leg] * rate
            tb_c = tb_c + P[P_CB + leg] * rate_t
            Q_t[a, c] += npl * (tapp_t[c] - Pc[P_N + leg] * tf - P[P_N + leg] * tf_c - tb_c)
            Q_t[k, c] += npl * tb_c
            tf_t[c] = tf_c
            tb_t[c] = tb_c
        return
    if int(P[P_MODEL]) != MODEL_PASSIVE:
        for c in range(m):
            Q_t[k, c] += npl * tapp_t[c]
    for c in range(m):
        tf_t[c] = 0.0
        tb_t[c] = 0.0
