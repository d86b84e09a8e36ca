"""The actuator of one leg (compiled): DC motor, current amplifier, battery and the
transmission's losses (docs/specification.md section 4; paper Sec. III, Table II).

The amplifier turns a commanded hip torque into a motor current, i_cmd = tau / (N eta K_T),
limited to |i| <= i_max and (except in the ideal variant) by the motor's torque-speed line
(-V_b - K_w w_m) / R_A <= i <= (V_b - K_w w_m) / R_A; the current delivers
N eta K_T i at the gear output, less the optional load-dependent losses. The battery's
terminal voltage V_b drops with the power drawn when it has an internal resistance R_b.

``N eta K_T`` (hip torque per ampere) has one home, :func:`torque_per_amp`.
"""

from __future__ import annotations

import math

from ..._numba.jit import kernel
from .layout import (
    CIRCUIT_OPEN,
    CIRCUIT_SHORT,
    MODEL_IDEAL,
    MODEL_PASSIVE,
    P_C_LOAD,
    P_CIRCUIT,
    P_ETA,
    P_IMAX,
    P_KT,
    P_KW,
    P_MODEL,
    P_N,
    P_NP,
    P_RA,
    P_RB,
    P_TAU_IDLE,
    P_VB,
)
from .roots import illinois_update
from .transmission import motor_speed


@kernel(inline="always")
def torque_per_amp(leg, P):
    """Hip torque per ampere of virtual leg ``leg``'s motor current, N eta K_T [N m / A]
    (gear ratio, gear efficiency, torque constant; Table II)."""
    return P[P_N + leg] * P[P_ETA + leg] * P[P_KT + leg]


@kernel(inline="always")
def back_emf_damping(leg, P):
    """Motor-side damping [N m s/rad] of the back-EMF of virtual leg ``leg``'s motor while
    the current follows the torque-speed line, eta K_T K_w / R_A (at the motor shaft,
    before the gear ratio)."""
    return P[P_ETA + leg] * P[P_KT + leg] * P[P_KW + leg] / P[P_RA + leg]


@kernel(inline="always")
def on_speed_line(cmd_torque, omega_m, vb, leg, P):
    """True if the amplifier's current for ``cmd_torque`` [N m] at motor speed ``omega_m``
    [rad/s] and battery voltage ``vb`` [V] is limited by the torque-speed line (not by
    i_max, not in the ideal variant): the current then depends on the motor speed."""
    if int(P[P_MODEL]) == MODEL_IDEAL:
        return False
    r_a = P[P_RA + leg]
    imax = P[P_IMAX + leg]
    ic = min(max(cmd_torque / torque_per_amp(leg, P), -imax), imax)
    v_lo = (-vb - P[P_KW + leg] * omega_m) / r_a
    v_hi = (vb - P[P_KW + leg] * omega_m) / r_a
    return ic > v_hi or ic < v_lo


@kernel(inline="always")
def motor_current(cmd_torque, omega_m, vb, leg, P):
    """Motor current [A] of virtual leg ``leg``'s motors delivered for a commanded leg
    torque (per physical leg) [N m].

    Section 4: i_cmd = tau / (N eta K_T), limited by |i| <= i_max and, except in the ideal
    variant, by the torque-speed line (-V_b - K_w w)/R_A <= i <= (V_b - K_w w)/R_A.

    The line binds last: a motor back-driven so fast that its back-EMF exceeds the battery
    voltage plus R_A i_max carries the line's current even beyond i_max (the amplifier can
    at most apply the full battery voltage against it), the same in either direction."""
    model = int(P[P_MODEL])
    if model == MODEL_PASSIVE:
        return 0.0
    circuit = int(P[P_CIRCUIT])
    if circuit == CIRCUIT_OPEN:
        return 0.0  # bench rig, motor leads open
    if circuit == CIRCUIT_SHORT:
        return -P[P_KW + leg] * omega_m / P[P_RA + leg]  # bench rig, leads shorted
    imax = P[P_IMAX + leg]
    ic = cmd_torque / torque_per_amp(leg, P)
    if ic < -imax:
        ic = -imax
    if ic > imax:
        ic = imax
    if model != MODEL_IDEAL:
        r = P[P_RA + leg]
        v_lo = (-vb - P[P_KW + leg] * omega_m) / r
        v_hi = (vb - P[P_KW + leg] * omega_m) / r
        if ic < v_lo:
            ic = v_lo
        if ic > v_hi:
            ic = v_hi
    return ic


#: Motor speed [rad/s] over which the direction of the transmission losses is blended
#: linearly (regularized Coulomb friction; docs/model.md "Transmission losses").
LOSS_SPEED_REG = 1.0


@kernel(inline="always")
def _loss_branch(tau0, d, idle, cl):
    """Delivered torque for output motion in direction d = +-1 (see delivered_torque)."""
    if tau0 * d > 0.0:  # motoring: forward power flow
        mag = (abs(tau0) - idle) / (1.0 + cl)
        if mag < 0.0:
            mag = 0.0
        return mag if tau0 > 0.0 else -mag
    return -d * (abs(tau0) + idle) / (1.0 - cl)  # back-driven: reverse power flow


@kernel(inline="always")
def delivered_torque(cur, omega_m, leg, P):
    """Torque delivered to virtual leg ``leg``'s leg / driven gear, per physical leg [N m],
    for motor current
    ``cur`` [A] at motor speed ``omega_m`` relative to the torso [rad/s] (docs/model.md,
    "Transmission losses").

    The constant-efficiency torque tau_0 = N eta K_T i is corrected by a loss torque
    tau_loss = tau_idle + c_load |tau_out| opposing the output motion (i.e. the power flow):
    motoring (tau_0 w_m > 0): |tau_out| = max(|tau_0| - tau_idle, 0) / (1 + c_load), sign of
    tau_0; back-driven (tau_0 w_m <= 0): tau_out = -sign(w_m) (|tau_0| + tau_idle) / (1 - c_load).
    For |w_m| < LOSS_SPEED_REG the two directions are blended linearly. With
    tau_idle = c_load = 0 this returns tau_0 exactly."""
    tau0 = torque_per_amp(leg, P) * cur
    idle = P[P_TAU_IDLE + leg]
    cl = P[P_C_LOAD + leg]
    if idle == 0.0 and cl == 0.0:
        return tau0
    w = omega_m / LOSS_SPEED_REG
    if w >= 1.0:
        return _loss_branch(tau0, 1.0, idle, cl)
    if w <= -1.0:
        return _loss_branch(tau0, -1.0, idle, cl)
    return 0.5 * (1.0 + w) * _loss_branch(tau0, 1.0, idle, cl) + 0.5 * (1.0 - w) * _loss_branch(
        tau0, -1.0, idle, cl
    )


@kernel(inline="always")
def _battery_fixed_point(v, voc, rb, dq, cmd, P):
    """The terminal voltage [V] the battery gives when the motors draw what they draw at
    terminal voltage ``v``: (V_oc + sqrt(V_oc^2 - 4 R_b P(v))) / 2 (the high root of
    V = V_oc - R_b P / V), P(v) the power of all motors at their currents for ``v``."""
    pw = 0.0
    for leg in range(2):
        om = motor_speed(dq, leg, P)
        i = motor_current(cmd[leg], om, v, leg, P)
        pw += P[P_NP] * i * (P[P_RA + leg] * i + P[P_KW + leg] * om)
    disc = voc * voc - 4.0 * rb * pw
    if disc < 0.0:
        disc = 0.0
    return 0.5 * (voc + math.sqrt(disc))


#: relative tolerance [-] of the battery voltage solve
BATTERY_VOLTAGE_RTOL = 1e-13


@kernel(inline="always")
def battery_voltage(dq, cmd, P):
    """Battery terminal voltage V_b [V] (docs/specification.md section 4).

    Ideal source (R_b = 0): V_b = V_oc. Otherwise the amplifiers are taken as lossless
    converters, so the battery supplies P = sum_motors V_term i and V_b = V_oc - R_b P / V_b,
    i.e. V_b = F(V_b) = (V_oc + sqrt(V_oc^2 - 4 R_b P(V_b))) / 2, where P depends on V_b
    through the motors' torque-speed lines. The power a motor on its line draws grows with
    the voltage, so F falls and V - F(V) has one root, bracketed by [V_oc / 2, F(V_oc / 2)]
    and found by the Illinois method to BATTERY_VOLTAGE_RTOL (a plain fixed-point iteration
    oscillates when a motor's current is on its line)."""
    voc = P[P_VB]
    rb = P[P_RB]
    if rb <= 0.0 or int(P[P_MODEL]) == MODEL_IDEAL or int(P[P_MODEL]) == MODEL_PASSIVE:
        return voc
    # V - F(V): negative at a = V_oc / 2, positive at b = F(a); Illinois on its negative
    # (the bracket convention of illinois_update: positive at a)
    a = 0.5 * voc
    ga = _battery_fixed_point(a, voc, rb, dq, cmd, P) - a
    if ga <= 0.0:
        return a
    b = a + ga
    gb = _battery_fixed_point(b, voc, rb, dq, cmd, P) - b
    if gb >= 0.0:
        return b
    side = 0
    c = b
    for _ in range(100):
        c = (a * gb - b * ga) / (gb - ga)
        gc = _battery_fixed_point(c, voc, rb, dq, cmd, P) - c
        if gc == 0.0 or b - a < BATTERY_VOLTAGE_RTOL * voc:
            break
        a, ga, b, gb, side = illinois_update(c, gc, a, ga, b, gb, side)
    return c
