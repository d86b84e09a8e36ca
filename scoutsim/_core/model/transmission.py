"""The transmission between motor and leg (compiled): the rigid hip unit (ideal, Model I,
passive; model/rigid_hip.py) and what the geared hip units of Model II share (docs/specification.md
section 5; paper Sec. III, Table II, Fig. 6). Which unit a run has, and the belt each
geared unit brings, is :mod:`scoutsim._core.model.hip_unit`'s.

Rigid unit: the gear output drives the leg angle phi directly (Model I adds the motor's
torque-speed line and the battery; model/actuator.py). Geared units (Model II): the motor
drives a gear pair (drive gear J_1 on the motor shaft, driven gear J_2 at angle alpha
relative to the torso, ratio N) that drives the leg through a belt, a spring-damper
(k_b, c_b) on alpha - phi (model/belt.py; with play, model/backlash.py); the motor joint has
viscous friction b_J and stiction tau_s, so it is either stuck (alpha' = 0, a constraint
row of kind ``ROW_GEAR``) or slipping (Coulomb torque tau_s against the motion). What the
geared unit adds to the model is here: its inertia (:func:`add_gear_inertia`), its
potential energy (:func:`belt_energy`), its generalized forces (:func:`hip_unit_forces`),
the stuck joint's row (:func:`motor_joint_row`), whether a joint has stiction that can
hold it (:func:`joint_has_stiction`) and the joint's stick/slip mode after an impact
(:func:`motor_mode_from_rate`).
"""

from __future__ import annotations

from ..._numba.jit import kernel
from .hip_unit import belt_spring, geared
from .kkt import new_row
from .layout import (
    IALB,
    IPHB,
    MI_MOTOR_B,
    MODEL_PASSIVE,
    P_B_J,
    P_CB,
    P_J1,
    P_J2,
    P_KB,
    P_MODEL,
    P_N,
    P_NP,
    P_TAU_S,
    ROW_GEAR,
    SLIP_NEG,
    SLIP_POS,
    STUCK,
)


@kernel(inline="always")
def motor_speed(dq, leg, P):
    """Motor speed relative to the torso [rad/s] of leg ``leg``: N times the rate of the
    coordinate the gear output turns (the driven gear alpha of a geared unit, the leg phi
    otherwise)."""
    return P[P_N + leg] * (dq[IALB + leg] if geared(P) else dq[IPHB + leg])


@kernel(inline="always")
def belt_energy(q, leg, P):
    """Potential energy [J] of the belt springs of virtual leg ``leg`` (geared units)."""
    bd = belt_spring(q[IALB + leg] - q[IPHB + leg], leg, P)[0]
    return 0.5 * P[P_NP] * P[P_KB + leg] * bd * bd


@kernel(inline="always")
def add_gear_inertia(M, P):
    """Add the Model II gear pairs to the mass matrix M (upper triangle): per virtual leg
    n_p J_2 turning at theta + alpha and n_p J_1 at theta + N alpha, i.e. the reflected
    inertia J_2 + N^2 J_1 on alpha and its coupling to the pitch."""
    npl = P[P_NP]
    for leg in range(2):
        j1 = npl * P[P_J1 + leg]
        j2 = npl * P[P_J2 + leg]
        N = P[P_N + leg]
        a = IALB + leg
        M[2, 2] += j1 + j2
        M[2, a] += j2 + N * j1
        M[a, a] += j2 + N * N * j1


@kernel(inline="always")
def joint_friction_torque(om, mode, leg, P):
    """Friction torque [N m] of virtual leg ``leg``'s Model II motor joint at motor speed
    ``om`` [rad/s] in stick/slip mode ``mode``: viscous b_J om, plus the Coulomb level
    tau_s in the slip direction while slipping (a stuck joint's holding torque is a
    constraint force)."""
    tf = P[P_B_J + leg] * om
    if mode != STUCK:
        tf += P[P_TAU_S + leg] * mode
    return tf


@kernel(inline="always")
def belt_torque(q, dq, leg, P):
    """Torque [N m] of the belt spring-damper on the leg of virtual leg ``leg``, per
    physical leg: k_b (alpha - phi) (with the dead zone of the backlash) plus
    c_b (alpha' - phi')."""
    spring = P[P_KB + leg] * belt_spring(q[IALB + leg] - q[IPHB + leg], leg, P)[0]
    damper = P[P_CB + leg] * (dq[IALB + leg] - dq[IPHB + leg])
    return spring + damper


@kernel(inline="always")
def hip_unit_forces(Q, q, dq, leg, tapp, om, mode, P):
    """Add the generalized forces of virtual leg ``leg``'s hip drive to Q for the delivered
    torque ``tapp`` [N m per physical leg] at motor speed ``om`` [rad/s].

    Ideal / Model I: tapp acts on the leg angle phi. Passive: nothing. Model II: tapp acts
    on the driven gear alpha; the joint friction (at the motor, N times larger at alpha)
    opposes it, and the belt couples alpha and phi. Returns (joint friction torque at the
    motor, belt torque on the leg) [N m], both 0 outside Model II."""
    npl = P[P_NP]
    if geared(P):
        Q[IALB + leg] += npl * tapp
        tf = joint_friction_torque(om, mode, leg, P)
        Q[IALB + leg] -= npl * P[P_N + leg] * tf
        tb = belt_torque(q, dq, leg, P)
        Q[IPHB + leg] += npl * tb
        Q[IALB + leg] -= npl * tb
        return tf, tb
    if int(P[P_MODEL]) != MODEL_PASSIVE:
        Q[IPHB + leg] += npl * tapp
    return 0.0, 0.0


@kernel(inline="always")
def motor_joint_row(R, r, rkind, rleg, nr, leg, mi, P):
    """Append the row alpha'' = 0 of a stuck Model II motor joint (kind ``ROW_GEAR``; its
    multiplier is the stiction holding torque). Returns the new row count."""
    if geared(P) and mi[MI_MOTOR_B + leg] == STUCK:
        new_row(R, r, rkind, rleg, nr, 0.0, ROW_GEAR, leg)
        R[nr, IALB + leg] = 1.0
        nr += 1
    return nr


@kernel(inline="always")
def joint_has_stiction(leg, P):
    """True if virtual leg ``leg`` has a motor joint with stiction (a geared unit with
    tau_s > 0): its joint can stick, and its stick/slip events and transitions apply."""
    return geared(P) and P[P_TAU_S + leg] > 0.0


@kernel(inline="always")
def motor_mode_from_rate(w, leg, P):
    """Stick/slip mode of virtual leg ``leg``'s Model II motor joint whose gear rate is
    ``w`` [rad/s] with no
    other information: slipping in the direction of motion; at exactly zero rate stuck if
    the joint has stiction (a joint without stiction is never stuck: nothing could release
    it, so it "slips" with zero Coulomb torque)."""
    if w > 0.0:
        return SLIP_POS
    if w < 0.0:
        return SLIP_NEG
    return STUCK if P[P_TAU_S + leg] > 0.0 else SLIP_POS
