"""Equations of motion of the planar Scout II model (compiled with Numba).

Implements SPEC.md sections 1-5; docs/model.md derives every term. Summary:

* Generalized coordinates q = [x, y, theta, phi_b, phi_f, alpha_b, alpha_f] (paper eq. 1 with
  the leg lengths l_b, l_f carried separately because the toe is massless, and the Model II
  driven-gear angles alpha). Only the *active* coordinates enter the dynamics: 7 in
  Model II, the first 5 otherwise (alpha is then a copy of phi).
* Mass matrix from body Jacobians, M = sum_b m_b J_b^T J_b + I_b J_w^T J_w (torso, two leg
  bodies, Model II gear pairs with reflected inertia J_2 + N^2 J_1), Coriolis/centripetal
  vector h = sum m_b J_b^T (dJ_b/dt dq).
* Contact and stiction are holonomic constraints on q, solved together with the dynamics in
  one KKT system ``[M R^T; R 0] [ddq; -lambda] = [Q - h; r]``. Coordinates fixed by a
  constraint that can be solved explicitly (stance leg angle from the toe anchor, massless
  flight legs, stuck motor joint) are *projected* before every evaluation, so the constraints
  hold exactly and do not drift; the multipliers lambda are the ground and holding forces.

Speed: the small helpers of :func:`evaluate_ws` (projection, motor and battery laws, the
reduced KKT solve) are inlined at the Numba IR level (``inline="always"``): 17 % off an
ARK3 step (5.24 -> 4.35 us), bit-identical results, for ~30 s more first-call compilation
(58 -> 88 s; the cache keeps it).
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import allocating, kernel
from .layout import (
    A_BELT, A_CURRENT, A_ENERGY, A_FAX, A_GN, A_GT, A_HOLD, A_KKT_OK, A_OMEGA_M, A_SLIP_V,
    A_STRUT, A_TAU_APP, A_TAU_BELT, A_TAU_CMD, A_TOE_X, A_TOE_Y, A_VBATT, FLIGHT, IL_B,
    MF_ANCHOR_B, MI_CONTACT_B, MI_MOTOR_B, MI_SLIDE_DIR_B, MODEL_II, MODEL_IDEAL,
    MODEL_PASSIVE, NAUX_LEG, NQ, NS, P_B_J, P_C, P_CB, P_D, P_ETA, P_G, P_IL, P_IMAX,
    P_IT, P_J1, P_J2, P_K, P_KB, P_KT, P_KW, P_L, P_L0, P_MASSLESS, P_ML, P_MODEL, P_MT,
    P_C_LOAD, P_MU, P_N, P_NP, P_RA, P_RB, P_STRUT_OMEGA, P_TAU_IDLE, P_TAU_S, P_TD_B, P_TD_WORLD, P_VB, SLIDE,
    SLIP_NEG, SLIP_POS, STICK, STRUT, STUCK,
)
from .layout import CIRCUIT_OPEN, CIRCUIT_SHORT, P_CIRCUIT, P_CLAMP_LEGS, P_CLAMP_TORSO
from .layout import P_BACKLASH, P_LEG_C_ANGLE, P_LEG_FRIC, P_LEG_FRIC_SIDE

MAX_ROWS = 11         # at most 2 rows per leg (strut) + 1 per motor joint, + 5 rig clamps
MAX_KKT = NQ + MAX_ROWS
NSTIFF = 4            # rank of the stiff-Jacobian factorization of evaluate_ws
#: Motor-side damping rate [1/s] from which evaluate_ws puts it into the stiff factors (the
#: two motor columns). Below it the explicit part of the ARK methods is stable and accurate
#: at steps up to the 1 ms control period (|h lambda| <= 1, inside the explicit stability
#: interval of ARK3 / ARK4); above it (user robots with a light gear train or strong
#: back-EMF) the damping is treated implicitly.
STIFF_MOTOR_RATE = 1000.0


@allocating
def solve_dense(A, b, n):
    """Solve A[:n,:n] x = b[:n] in place by Gaussian elimination with partial pivoting
    (:func:`lu_factor` then :func:`lu_solve`; deterministic, systems of at most 13 x 13).
    Returns False if a pivot is numerically zero (the constrained dynamics are singular)."""
    piv = np.empty(n, dtype=np.int64)
    if not lu_factor(A, piv, n):
        return False
    lu_solve(A, piv, b, 0, n)
    return True


@kernel
def hip_position(q, P, leg):
    """Hip position (hx, hy) [m] of virtual leg ``leg`` (0 back, 1 front), SPEC.md 1."""
    sL = (2.0 * leg - 1.0) * P[P_L]
    return q[0] + sL * math.cos(q[2]), q[1] + sL * math.sin(q[2])


@kernel
def hip_velocity(q, dq, P, leg):
    """Hip velocity [m/s]."""
    sL = (2.0 * leg - 1.0) * P[P_L]
    return dq[0] - sL * math.sin(q[2]) * dq[2], dq[1] + sL * math.cos(q[2]) * dq[2]


@kernel(inline="always")
def project(q, dq, l, P, mi, mf):
    """Make the dependent coordinates consistent with the active constraints (in place).

    * stance (stick/strut) leg: phi and dphi from the toe anchor and the hip, l = |toe - hip|;
    * sliding leg: l from the toe height being zero;
    * massless leg in flight: phi prescribed (touchdown angle, torso- or world-referenced),
      l = l0;
    * massive leg in flight: l limited to the stop l0 (and = l0 for an undamped leg);
    * ideal / Model I / passive: alpha := phi; Model II stuck motor joint: dalpha = 0.

    Returns (sin theta, cos theta, sin g_b, cos g_b, sin g_f, cos g_f) of the projected
    configuration, g = theta + phi the leg's angle from the world vertical (for a pinned
    toe straight from the toe-hip vector), for :func:`evaluate_ws` to reuse.
    """
    model = int(P[P_MODEL])
    l0 = P[P_L0]
    massless = P[P_MASSLESS] > 0.5
    if P[P_CLAMP_TORSO] > 0.5:
        # bench rig: the clamped torso is at rest (add_clamp_rows)
        dq[0] = 0.0
        dq[1] = 0.0
        dq[2] = 0.0
        if P[P_CLAMP_LEGS] > 0.5:
            dq[3] = 0.0
            dq[4] = 0.0
    sth = math.sin(q[2])
    cth = math.cos(q[2])
    sg0 = 0.0
    cg0 = 1.0
    sg1 = 0.0
    cg1 = 1.0
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        sL = (2.0 * leg - 1.0) * P[P_L]
        hx = q[0] + sL * cth
        hy = q[1] + sL * sth
        hvx = dq[0] - sL * sth * dq[2]
        hvy = dq[1] + sL * cth * dq[2]
        if mode == STICK or mode == STRUT:
            px = mf[MF_ANCHOR_B + leg]
            ddx = px - hx
            ddy = -hy
            ll = math.sqrt(ddx * ddx + ddy * ddy)
            g = math.atan2(ddx, -ddy)
            sg = ddx / ll
            cg = -ddy / ll
            q[3 + leg] = g - q[2]
            dg = -(hvx * cg + hvy * sg) / ll
            dq[3 + leg] = dg - dq[2]
            l[leg] = ll
        elif mode == SLIDE:
            g = q[2] + q[3 + leg]
            sg = math.sin(g)
            cg = math.cos(g)
            l[leg] = hy / cg
        else:
            if massless:
                td = P[P_TD_B + leg]
                if P[P_TD_WORLD] > 0.5:
                    q[3 + leg] = td - q[2]
                    dq[3 + leg] = -dq[2]
                else:
                    q[3 + leg] = td
                    dq[3 + leg] = 0.0
                l[leg] = l0
            else:
                if P[P_C] <= 0.0 or l[leg] > l0:
                    l[leg] = l0
            g = q[2] + q[3 + leg]
            sg = math.sin(g)
            cg = math.cos(g)
        if leg == 0:
            sg0 = sg
            cg0 = cg
        else:
            sg1 = sg
            cg1 = cg
        if model != MODEL_II:
            q[5 + leg] = q[3 + leg]
            dq[5 + leg] = dq[3 + leg]
        elif mi[MI_MOTOR_B + leg] == STUCK:
            dq[5 + leg] = 0.0
    return sth, cth, sg0, cg0, sg1, cg1


@kernel
def mass_matrix(q, P, M):
    """Fill M (7 x 7) with the generalized mass matrix at q (SPEC.md 2, 5)."""
    for i in range(NQ):
        for j in range(NQ):
            M[i, j] = 0.0
    npl = P[P_NP]
    ml = npl * P[P_ML]
    il = npl * P[P_IL]
    d = P[P_D]
    th = q[2]
    M[0, 0] += P[P_MT]
    M[1, 1] += P[P_MT]
    M[2, 2] += P[P_IT]
    for leg in range(2):
        sL = (2.0 * leg - 1.0) * P[P_L]
        g = th + q[3 + leg]
        jth_x = -sL * math.sin(th) + d * math.cos(g)
        jth_y = sL * math.cos(th) + d * math.sin(g)
        jph_x = d * math.cos(g)
        jph_y = d * math.sin(g)
        k = 3 + leg
        # translational part m J^T J over coordinates (x, y, theta, phi_leg)
        M[0, 0] += ml
        M[1, 1] += ml
        M[0, 2] += ml * jth_x
        M[1, 2] += ml * jth_y
        M[0, k] += ml * jph_x
        M[1, k] += ml * jph_y
        M[2, 2] += ml * (jth_x * jth_x + jth_y * jth_y)
        M[2, k] += ml * (jth_x * jph_x + jth_y * jph_y)
        M[k, k] += ml * (jph_x * jph_x + jph_y * jph_y)
        # rotational part (leg angular velocity dtheta + dphi)
        M[2, 2] += il
        M[2, k] += il
        M[k, k] += il
    if int(P[P_MODEL]) == MODEL_II:
        j1 = npl * P[P_J1]
        j2 = npl * P[P_J2]
        N = P[P_N]
        for leg in range(2):
            a = 5 + leg
            M[2, 2] += j1 + j2
            M[2, a] += j2 + N * j1
            M[a, a] += j2 + N * N * j1
    for i in range(NQ):
        for j in range(i):
            M[i, j] = M[j, i]


@kernel
def coriolis(q, dq, P, h):
    """Fill h (7) with the velocity-product terms, M ddq + h = Q (leg bodies only)."""
    for i in range(NQ):
        h[i] = 0.0
    ml = P[P_NP] * P[P_ML]
    d = P[P_D]
    th = q[2]
    dth = dq[2]
    for leg in range(2):
        sL = (2.0 * leg - 1.0) * P[P_L]
        g = th + q[3 + leg]
        dg = dth + dq[3 + leg]
        ax = -sL * math.cos(th) * dth * dth - d * math.sin(g) * dg * dg
        ay = -sL * math.sin(th) * dth * dth + d * math.cos(g) * dg * dg
        jth_x = -sL * math.sin(th) + d * math.cos(g)
        jth_y = sL * math.cos(th) + d * math.sin(g)
        h[0] += ml * ax
        h[1] += ml * ay
        h[2] += ml * (jth_x * ax + jth_y * ay)
        h[3 + leg] += ml * d * (math.cos(g) * ax + math.sin(g) * ay)


#: Speed [m/s] below which the telescopic leg's Coulomb friction is regularised linearly
#: (``RobotParameters.leg_friction_force``): a leg loaded below the friction level creeps
#: at less than this speed instead of sticking exactly.
LEG_FRICTION_SPEED = 1e-3


@kernel(inline="always")
def belt_spring_deflection(delta, P):
    """Deflection [rad] the belt spring sees at gear/leg angle difference ``delta`` [rad]:
    with the hip unit's play b (``P_BACKLASH``, 0 = the paper's model) the spring is slack
    for |delta| <= b / 2 (dead zone) and deflected by the excess beyond it."""
    h = 0.5 * P[P_BACKLASH]
    if delta > h:
        return delta - h
    if delta < -h:
        return delta + h
    return 0.0


@kernel(inline="always")
def leg_damping(phi, P):
    """Leg damper [N s/m] per physical leg at leg angle ``phi`` [rad]: c (1 + a phi^2)
    (a = ``P_LEG_C_ANGLE``, 0 = Table III's constant c)."""
    return P[P_C] * (1.0 + P[P_LEG_C_ANGLE] * phi * phi)


@kernel(inline="always")
def leg_friction_level(tau_hip, ll, P):
    """Coulomb friction level [N] of one physical leg's sliding joint: a constant part and
    a part proportional to the side load |tau_hip| / l of the hip torque (0 = off)."""
    return P[P_LEG_FRIC] + P[P_LEG_FRIC_SIDE] * abs(tau_hip) / ll


@kernel(inline="always")
def leg_axial_force(k, c, l0, ll, ld, fc):
    """Axial force of one physical leg [N], compression positive: spring, damper and the
    sliding joint's Coulomb friction ``fc`` (regularised over LEG_FRICTION_SPEED)."""
    sat = ld / LEG_FRICTION_SPEED
    if sat > 1.0:
        sat = 1.0
    elif sat < -1.0:
        sat = -1.0
    return k * (l0 - ll) - c * ld - fc * sat


@kernel(inline="always")
def flight_leg_rate(k, c, l0, ll, fc):
    """dl/dt [m/s] of a massive leg's massless toe in flight, from its force balance
    leg_axial_force(...) = 0 (it relaxes towards l0; SPEC.md 2); 0 at the stop."""
    if c <= 0.0 or ll >= l0:
        return 0.0
    f = k * (l0 - ll)
    lin = f / (c + fc / LEG_FRICTION_SPEED)
    if lin <= LEG_FRICTION_SPEED:
        return lin
    return (f - fc) / c


@allocating
def kinetic_energy(q, dq, P):
    """Kinetic energy 1/2 dq^T M dq [J]."""
    M = np.empty((NQ, NQ))
    mass_matrix(q, P, M)
    e = 0.0
    for i in range(NQ):
        for j in range(NQ):
            e += dq[i] * M[i, j] * dq[j]
    return 0.5 * e


@allocating
def state_energy(s, P):
    """Total mechanical energy of a full state vector s [J]: kinetic plus potential (gravity,
    leg springs, Model II belts); the same quantity as the ``energy`` output."""
    return kinetic_energy(s[0:NQ], s[NQ:2 * NQ], P) + potential_energy(s[0:NQ], s[IL_B:IL_B + 2], P)


@kernel
def potential_energy(q, l, P):
    """Gravity + leg springs + Model II belt springs [J]."""
    g = P[P_G]
    npl = P[P_NP]
    e = P[P_MT] * g * q[1]
    for leg in range(2):
        sL = (2.0 * leg - 1.0) * P[P_L]
        gam = q[2] + q[3 + leg]
        yc = q[1] + sL * math.sin(q[2]) - P[P_D] * math.cos(gam)
        e += npl * P[P_ML] * g * yc
        dl = P[P_L0] - l[leg]
        e += 0.5 * npl * P[P_K] * dl * dl
        if int(P[P_MODEL]) == MODEL_II:
            b = belt_spring_deflection(q[5 + leg] - q[3 + leg], P)
            e += 0.5 * npl * P[P_KB] * b * b
    return e


@kernel(inline="always")
def motor_current(cmd_torque, omega_m, vb, P):
    """Motor current [A] delivered for a commanded leg torque (per physical leg) [N m].

    SPEC.md 4: i_cmd = tau / (N eta K_T), limited by |i| <= i_max and, except in the ideal
    variant, by the torque-speed line (-V_b - K_w w)/R_A <= i <= (V_b - K_w w)/R_A."""
    model = int(P[P_MODEL])
    if model == MODEL_PASSIVE:
        return 0.0
    circuit = int(P[P_CIRCUIT])
    if circuit == CIRCUIT_OPEN:
        return 0.0      # bench rig, motor leads open
    if circuit == CIRCUIT_SHORT:
        return -P[P_KW] * omega_m / P[P_RA]   # bench rig, leads shorted: 0 = R_A i + K_w w_m
    imax = P[P_IMAX]
    ic = cmd_torque / (P[P_N] * P[P_ETA] * P[P_KT])
    lo = -imax
    hi = imax
    if model != MODEL_IDEAL:
        r = P[P_RA]
        v_lo = (-vb - P[P_KW] * omega_m) / r
        v_hi = (vb - P[P_KW] * omega_m) / r
        if v_lo > lo:
            lo = v_lo
        if v_hi < hi:
            hi = v_hi
    if ic < lo:
        ic = lo
    if ic > hi:
        ic = hi
    return ic


#: Motor speed [rad/s] over which the direction of the transmission losses is blended
#: linearly (regularized Coulomb friction; docs/model.md "Transmission losses").
LOSS_SPEED_REG = 1.0


@kernel(inline="always")
def _loss_branch(tau0, d, idle, cl):
    """Delivered torque for output motion in direction d = +-1 (see delivered_torque)."""
    if tau0 * d > 0.0:                      # motoring: forward power flow
        mag = (abs(tau0) - idle) / (1.0 + cl)
        if mag < 0.0:
            mag = 0.0
        return mag if tau0 > 0.0 else -mag
    return -d * (abs(tau0) + idle) / (1.0 - cl)   # back-driven: reverse power flow


@kernel(inline="always")
def delivered_torque(cur, omega_m, P):
    """Torque delivered to the leg / driven gear, per physical leg [N m], for motor current
    ``cur`` [A] at motor speed ``omega_m`` relative to the torso [rad/s] (docs/model.md,
    "Transmission losses").

    The constant-efficiency torque tau_0 = N eta K_T i is corrected by a loss torque
    tau_loss = tau_idle + c_load |tau_out| opposing the output motion (i.e. the power flow):
    motoring (tau_0 w_m > 0): |tau_out| = max(|tau_0| - tau_idle, 0) / (1 + c_load), sign of
    tau_0; back-driven (tau_0 w_m <= 0): tau_out = -sign(w_m) (|tau_0| + tau_idle) / (1 - c_load).
    For |w_m| < LOSS_SPEED_REG the two directions are blended linearly. With
    tau_idle = c_load = 0 this returns tau_0 exactly."""
    tau0 = P[P_N] * P[P_ETA] * P[P_KT] * cur
    idle = P[P_TAU_IDLE]
    cl = P[P_C_LOAD]
    if idle == 0.0 and cl == 0.0:
        return tau0
    w = omega_m / LOSS_SPEED_REG
    if w >= 1.0:
        return _loss_branch(tau0, 1.0, idle, cl)
    if w <= -1.0:
        return _loss_branch(tau0, -1.0, idle, cl)
    return (0.5 * (1.0 + w) * _loss_branch(tau0, 1.0, idle, cl)
            + 0.5 * (1.0 - w) * _loss_branch(tau0, -1.0, idle, cl))


@kernel(inline="always")
def battery_voltage(dq, cmd, P):
    """Battery terminal voltage V_b [V] (SPEC.md 4).

    Ideal source (R_b = 0): V_b = V_oc. Otherwise the amplifiers are taken as lossless
    converters, so the battery supplies P = sum_motors V_term i and
    V_b = (V_oc + sqrt(V_oc^2 - 4 R_b P)) / 2; the coupling through the voltage limits is
    resolved by fixed-point iteration."""
    voc = P[P_VB]
    rb = P[P_RB]
    if rb <= 0.0 or int(P[P_MODEL]) == MODEL_IDEAL or int(P[P_MODEL]) == MODEL_PASSIVE:
        return voc
    vb = voc
    for _ in range(4):
        pw = 0.0
        for leg in range(2):
            om = P[P_N] * (dq[5 + leg] if int(P[P_MODEL]) == MODEL_II else dq[3 + leg])
            i = motor_current(cmd[leg], om, vb, P)
            pw += P[P_NP] * i * (P[P_RA] * i + P[P_KW] * om)
        disc = voc * voc - 4.0 * rb * pw
        if disc < 0.0:
            disc = 0.0
        vb = 0.5 * (voc + math.sqrt(disc))
    return vb


@kernel(inline="always")
def new_row(R, r, rkind, rleg, nr, rhs, kind, leg):
    """Start constraint row nr of :func:`evaluate_ws`: zero R[nr], set its right-hand side,
    kind and leg (the caller fills the nonzero entries of R[nr])."""
    for j in range(NQ):
        R[nr, j] = 0.0
    r[nr] = rhs
    rkind[nr] = kind
    rleg[nr] = leg


@kernel
def add_clamp_rows(P, R, r, rkind, rleg, nr):
    """Bench-rig clamps as constraint rows (issue 5, docs/identification.md): with
    P_CLAMP_TORSO, ddx = ddy = ddtheta = 0 (kind 5); with P_CLAMP_LEGS also ddphi = 0 for
    both legs (kind 6). The multipliers are the clamp's force and torques. Returns the new
    row count."""
    if P[P_CLAMP_TORSO] > 0.5:
        for j in range(3):
            new_row(R, r, rkind, rleg, nr, 0.0, 5.0, 0)
            R[nr, j] = 1.0
            nr += 1
        if P[P_CLAMP_LEGS] > 0.5:
            for leg in range(2):
                new_row(R, r, rkind, rleg, nr, 0.0, 6.0, leg)
                R[nr, 3 + leg] = 1.0
                nr += 1
    return nr


@allocating
def evaluate_reference(s, P, mi, mf, cmd, ds, aux):
    """Reference implementation of :func:`evaluate` (allocating, dense KKT solve); kept
    for cross-checks of the optimized :func:`evaluate_ws`.

    Right-hand side ds = f(s) of the hybrid model in its current modes, and outputs.

    Parameters
    ----------
    s : (16,) state [q, dq, l_b, l_f] (SI).
    P : parameter array (layout.P_*).
    mi, mf : integer / float mode arrays (contact modes, motor-joint modes, toe anchors).
    cmd : (2,) commanded hip torque per physical leg, leg side [N m] (sample-and-hold).
    ds : (16,) output derivative.
    aux : (NAUX,) output ground forces, torques, currents, energy, ... (layout.A_*).

    Returns
    -------
    bool : False if the constrained dynamics are singular.
    """
    model = int(P[P_MODEL])
    nact = 7 if model == MODEL_II else 5
    q = s[0:NQ].copy()
    dq = s[NQ:2 * NQ].copy()
    l = s[IL_B:IL_B + 2].copy()
    project(q, dq, l, P, mi, mf)

    M = np.empty((NQ, NQ))
    h = np.empty(NQ)
    mass_matrix(q, P, M)
    coriolis(q, dq, P, h)

    npl = P[P_NP]
    grav = P[P_G]
    l0 = P[P_L0]
    k = P[P_K]
    d = P[P_D]
    N = P[P_N]
    th = q[2]
    dth = dq[2]
    massless = P[P_MASSLESS] > 0.5

    Q = np.zeros(NQ)
    # gravity
    Q[1] -= P[P_MT] * grav
    mlg = npl * P[P_ML] * grav
    for leg in range(2):
        g = th + q[3 + leg]
        sL = (2.0 * leg - 1.0) * P[P_L]
        Q[1] -= mlg
        Q[2] -= mlg * (sL * math.cos(th) + d * math.sin(g))
        Q[3 + leg] -= mlg * d * math.sin(g)

    # actuators
    vb = battery_voltage(dq, cmd, P)
    cur = np.zeros(2)
    om = np.zeros(2)
    tau_app = np.zeros(2)
    tau_belt = np.zeros(2)
    tau_fric = np.zeros(2)
    for leg in range(2):
        if model == MODEL_II:
            om[leg] = N * dq[5 + leg]
        else:
            om[leg] = N * dq[3 + leg]
        cur[leg] = motor_current(cmd[leg], om[leg], vb, P)
        tau_app[leg] = delivered_torque(cur[leg], om[leg], P)
        if model == MODEL_II:
            Q[5 + leg] += npl * tau_app[leg]
            mm = mi[MI_MOTOR_B + leg]
            tf = P[P_B_J] * om[leg]
            if mm != STUCK:
                tf += P[P_TAU_S] * mm
            tau_fric[leg] = tf
            Q[5 + leg] -= npl * N * tf
            tb = (P[P_KB] * belt_spring_deflection(q[5 + leg] - q[3 + leg], P)
                  + P[P_CB] * (dq[5 + leg] - dq[3 + leg]))
            tau_belt[leg] = tb
            Q[3 + leg] += npl * tb
            Q[5 + leg] -= npl * tb
        elif model != MODEL_PASSIVE:
            Q[3 + leg] += npl * tau_app[leg]

    # contact forces and constraint rows
    R = np.zeros((MAX_ROWS, NQ))
    r = np.zeros(MAX_ROWS)
    row_kind = np.zeros(MAX_ROWS, dtype=np.int64)   # 1 perp, 2 axial, 3 motor, 4 prescribed
    row_leg = np.zeros(MAX_ROWS, dtype=np.int64)
    nr = 0
    Fax = np.zeros(2)
    ldot = np.zeros(2)
    Gt = np.zeros(2)
    Gn = np.zeros(2)
    toe_x = np.zeros(2)
    toe_y = np.zeros(2)
    toe_vx = np.zeros(2)
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        sL = (2.0 * leg - 1.0) * P[P_L]
        g = th + q[3 + leg]
        dg = dth + dq[3 + leg]
        sg = math.sin(g)
        cg = math.cos(g)
        hx, hy = hip_position(q, P, leg)
        hvx, hvy = hip_velocity(q, dq, P, leg)
        ll = l[leg]
        # toe Jacobian (material point at distance ll on the leg axis), columns x, y, th, phi
        jt_th_x = -sL * math.sin(th) + ll * cg
        jt_th_y = sL * math.cos(th) + ll * sg
        jt_ph_x = ll * cg
        jt_ph_y = ll * sg
        # hip acceleration bias dJ_hip/dt dq
        bx = -sL * math.cos(th) * dth * dth
        by = -sL * math.sin(th) * dth * dth
        kk = 3 + leg
        # leg damper and sliding-joint friction (both as Table III unless the effects
        # beyond the paper are switched on)
        c_l = leg_damping(q[kk], P)
        tau_hip = (tau_belt[leg] if model == MODEL_II else
                   (tau_app[leg] if model != MODEL_PASSIVE else 0.0))
        fc_l = leg_friction_level(tau_hip, ll, P)
        if mode == STICK or mode == STRUT:
            ld = -(hvx * sg - hvy * cg)           # dl/dt = -dhip . u
            ldot[leg] = ld
            F = npl * leg_axial_force(k, c_l, l0, ll, ld, fc_l)
            if mode == STRUT:
                F = npl * k * (l0 - ll)
            Fax[leg] = F
            # Q += J_toe^T (-F u), u = (sg, -cg)
            fx = -F * sg
            fy = F * cg
            Q[0] += fx
            Q[1] += fy
            Q[2] += jt_th_x * fx + jt_th_y * fy
            Q[kk] += jt_ph_x * fx + jt_ph_y * fy
            # perpendicular pin: n^T J_toe ddq = -[(b . n) + 2 ldot dg]
            R[nr, 0] = cg
            R[nr, 1] = sg
            R[nr, 2] = sL * math.sin(q[3 + leg]) + ll
            R[nr, kk] = ll
            r[nr] = -(bx * cg + by * sg + 2.0 * ld * dg)
            row_kind[nr] = 1
            row_leg[nr] = leg
            nr += 1
            if mode == STRUT:
                w = P[P_STRUT_OMEGA]
                R[nr, 0] = sg
                R[nr, 1] = -cg
                R[nr, 2] = -sL * math.cos(q[3 + leg])
                r[nr] = -(bx * sg - by * cg) + ll * dg * dg + 2.0 * w * ld + w * w * (ll - l0)
                row_kind[nr] = 2
                row_leg[nr] = leg
                nr += 1
            toe_x[leg] = mf[MF_ANCHOR_B + leg]
            toe_y[leg] = 0.0
            toe_vx[leg] = 0.0
        elif mode == SLIDE:
            # toe on the ground (height 0), l = hy / cos(g)
            ld = hvy / cg + hy * sg * dg / (cg * cg)
            ldot[leg] = ld
            F = npl * leg_axial_force(k, c_l, l0, ll, ld, fc_l)
            Fax[leg] = F
            mu = P[P_MU]
            sig = 0.0
            if mu < 1e300:
                sig = mu * mi[MI_SLIDE_DIR_B + leg]
            gn = F / (cg + sig * sg)
            gt = -sig * gn
            Gn[leg] = gn
            Gt[leg] = gt
            Q[0] += gt
            Q[1] += gn
            Q[2] += jt_th_x * gt + jt_th_y * gn
            Q[kk] += jt_ph_x * gt + jt_ph_y * gn
            toe_x[leg] = hx + ll * sg
            toe_y[leg] = 0.0
            toe_vx[leg] = hvx + ld * sg + ll * cg * dg
        else:
            if massless:
                R[nr, kk] = 1.0
                if P[P_TD_WORLD] > 0.5:
                    R[nr, 2] = 1.0
                r[nr] = 0.0
                row_kind[nr] = 4
                row_leg[nr] = leg
                nr += 1
                ld = 0.0
            else:
                ld = flight_leg_rate(k, c_l, l0, ll, fc_l)
            ldot[leg] = ld
            toe_x[leg] = hx + ll * sg
            toe_y[leg] = hy - ll * cg
            toe_vx[leg] = hvx + ld * sg + ll * cg * dg
        if model == MODEL_II and mi[MI_MOTOR_B + leg] == STUCK:
            R[nr, 5 + leg] = 1.0
            r[nr] = 0.0
            row_kind[nr] = 3
            row_leg[nr] = leg
            nr += 1
    nr = add_clamp_rows(P, R, r, row_kind, row_leg, nr)

    # KKT system [M R^T; R 0] [ddq; nu] = [Q - h; r]; generalized constraint force = -R^T nu
    n = nact + nr
    A = np.zeros((n, n))
    b = np.zeros(n)
    for i in range(nact):
        for j in range(nact):
            A[i, j] = M[i, j]
        b[i] = Q[i] - h[i]
    for rr in range(nr):
        for j in range(nact):
            A[nact + rr, j] = R[rr, j]
            A[j, nact + rr] = R[rr, j]
        b[nact + rr] = r[rr]
    ok = solve_dense(A, b, n)

    for i in range(NQ):
        ds[i] = dq[i]
        ds[NQ + i] = 0.0
    if ok:
        for i in range(nact):
            ds[NQ + i] = b[i]
    if model != MODEL_II:
        ds[NQ + 5] = ds[NQ + 3]
        ds[NQ + 6] = ds[NQ + 4]
    ds[IL_B] = ldot[0]
    ds[IL_B + 1] = ldot[1]

    hold = np.zeros(2)
    strut = np.zeros(2)
    for rr in range(nr):
        lam = -b[nact + rr] if ok else 0.0
        leg = row_leg[rr]
        g = th + q[3 + leg]
        if row_kind[rr] == 1:      # perpendicular ground force lam * n
            Gt[leg] += lam * math.cos(g)
            Gn[leg] += lam * math.sin(g)
        elif row_kind[rr] == 2:    # strut force lam * u (tension positive)
            strut[leg] = lam
            Gt[leg] += lam * math.sin(g)
            Gn[leg] -= lam * math.cos(g)
        elif row_kind[rr] == 3:    # holding torque at one motor
            hold[leg] = lam / (npl * N)
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        if mode == STICK or mode == STRUT:
            g = th + q[3 + leg]
            # axial part of the ground force: -F u
            Gt[leg] += -Fax[leg] * math.sin(g)
            Gn[leg] += Fax[leg] * math.cos(g)
        o = leg * NAUX_LEG
        aux[o + A_GT] = Gt[leg]
        aux[o + A_GN] = Gn[leg]
        aux[o + A_FAX] = Fax[leg] if mode != STRUT else -strut[leg]
        aux[o + A_TAU_CMD] = cmd[leg]
        aux[o + A_TAU_APP] = tau_app[leg]
        aux[o + A_CURRENT] = cur[leg]
        aux[o + A_OMEGA_M] = om[leg]
        aux[o + A_BELT] = q[5 + leg] - q[3 + leg]
        if model == MODEL_II and mi[MI_MOTOR_B + leg] == STUCK:
            aux[o + A_HOLD] = hold[leg]
        else:
            aux[o + A_HOLD] = tau_fric[leg]
        aux[o + A_TOE_X] = toe_x[leg]
        aux[o + A_TOE_Y] = toe_y[leg]
        aux[o + A_SLIP_V] = toe_vx[leg]
        aux[o + A_STRUT] = strut[leg]
        aux[o + A_TAU_BELT] = tau_belt[leg]
    aux[A_VBATT] = vb
    ekin = 0.0
    for i in range(NQ):
        for j in range(NQ):
            ekin += dq[i] * M[i, j] * dq[j]
    aux[A_ENERGY] = 0.5 * ekin + potential_energy(q, l, P)
    aux[A_KKT_OK] = 1.0 if ok else 0.0
    return ok


# --- allocation-free evaluation ----------------------------------------------------------
# Workspace layout (float64 vector ``wk`` of size WK_SIZE; 2-D workspace ``wA`` of shape
# (WA_ROWS, MAX_KKT); integer pivots ``piv`` of size MAX_KKT).
WK_Q = 0
WK_DQ = WK_Q + NQ
WK_L = WK_DQ + NQ
WK_Q_ = WK_L + 2           # generalized forces Q
WK_H = WK_Q_ + NQ          # Coriolis vector
WK_R = WK_H + NQ           # constraint right-hand sides r
WK_B = WK_R + MAX_ROWS     # KKT right-hand side / solution
WK_B2 = WK_B + MAX_KKT     # second right-hand side (stiff directions)
WK_RKIND = WK_B2 + MAX_KKT
WK_RLEG = WK_RKIND + MAX_ROWS
WK_LEG = WK_RLEG + MAX_ROWS  # per-leg scalars, 16 slots x 2 legs
WK_Y = WK_LEG + 32         # reduced KKT right-hand side / solution
WK_META = WK_Y + MAX_KKT   # what evaluate_command_change needs of the last evaluation:
WK_SIZE = WK_META + 9      # [Schur path, row count, KKT ok, V_b, sin/cos g_b, sin/cos g_f,
                           #  energy]
WA_R = MAX_KKT             # rows of wA holding the constraint rows R
WA_M = WA_R + MAX_ROWS     # rows of wA holding the mass matrix M
WA_ROWS = WA_M + NQ
# per-leg scalar slots (offset WK_LEG + 2 * slot + leg)
LG_FAX, LG_LDOT, LG_GT, LG_GN, LG_TOEX, LG_TOEY, LG_TOEVX, LG_CUR, LG_OM, LG_TAPP, \
    LG_TBELT, LG_TFRIC, LG_HOLD, LG_STRUT = range(14)


@allocating
def new_eval_workspace():
    """Scratch arrays for :func:`evaluate_ws` (wk, wA, piv)."""
    return (np.zeros(WK_SIZE), np.zeros((WA_ROWS, MAX_KKT)),
            np.zeros(MAX_KKT, dtype=np.int64))


@kernel
def lu_factor(A, piv, n):
    """LU factorization with partial pivoting of A[:n,:n] in place (multipliers below the
    diagonal, row interchanges in piv). The same operations as :func:`solve_dense`, so
    ``lu_solve`` reproduces its results bit for bit. Returns False if singular."""
    scale = 0.0
    for i in range(n):
        for j in range(n):
            a = abs(A[i, j])
            if a > scale:
                scale = a
    tiny = 1e-13 * scale if scale > 0.0 else 1e-300
    for k in range(n):
        p = k
        best = abs(A[k, k])
        for i in range(k + 1, n):
            a = abs(A[i, k])
            if a > best:
                best = a
                p = i
        piv[k] = p
        if best <= tiny:
            return False
        if p != k:
            # columns < k hold the multipliers of earlier steps, which stay with the row
            # position they were computed for (as the right-hand side is swapped in order)
            for j in range(k, n):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
        inv = 1.0 / A[k, k]
        for i in range(k + 1, n):
            f = A[i, k] * inv
            A[i, k] = f
            if f != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]
    return True


@kernel(inline="always")
def lu_solve(A, piv, b, o, n):
    """Solve with the factors of :func:`lu_factor`; right-hand side b[o:o+n], in place."""
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[o + k]
            b[o + k] = b[o + p]
            b[o + p] = tmp
        bk = b[o + k]
        for i in range(k + 1, n):
            f = A[i, k]
            if f != 0.0:
                b[o + i] -= f * bk
    for i in range(n - 1, -1, -1):
        acc = b[o + i]
        for j in range(i + 1, n):
            acc -= A[i, j] * b[o + j]
        b[o + i] = acc / A[i, i]


@kernel
def kkt_reduced_factor(A, piv, M, R, rkind, nact, nr, free0, free1):
    """Assemble and factor the KKT matrix with the Model II gear coordinates eliminated.

    The driven-gear angles alpha (coordinates 5, 6) couple to the rest of the mass matrix
    only through M[2, alpha]; no contact row involves them. A free gear's row is solved
    for its acceleration and folded into the theta row (Schur complement
    M22 - M2a^2 / Maa); a stuck gear has ddalpha = its row's right-hand side and its
    multiplier follows from its row. What is left is [M5 R_c^T; R_c 0] with the contact rows
    only (at most 5 + 4 unknowns instead of 7 + 6). Returns (ok, size)."""
    m = 5
    for i in range(m):
        for j in range(m):
            A[i, j] = M[i, j]
    if nact == 7:
        if free0:
            A[2, 2] -= M[2, 5] * M[2, 5] / M[5, 5]
        if free1:
            A[2, 2] -= M[2, 6] * M[2, 6] / M[6, 6]
    nc = 0
    for rr in range(nr):
        if rkind[rr] == 3.0:
            continue
        for j in range(m):
            A[m + nc, j] = R[rr, j]
            A[j, m + nc] = R[rr, j]
        nc += 1
    n = m + nc
    for i in range(m, n):
        for j in range(m, n):
            A[i, j] = 0.0
    return lu_factor(A, piv, n), n


@kernel(inline="always")
def kkt_reduced_solve(A, piv, M, rkind, rleg, nact, nr, free0, free1, b, o, y, yo, schur):
    """Solve the full KKT system [M R^T; R 0] x = b[o:o+nact+nr] (in place, original
    ordering) with the factors of :func:`kkt_schur_factor` (``schur``) or
    :func:`kkt_reduced_factor`; y[yo:] is scratch."""
    m = 5
    for i in range(m):
        y[yo + i] = b[o + i]
    if nact == 7:
        if free0:
            y[yo + 2] -= M[2, 5] / M[5, 5] * b[o + 5]
        if free1:
            y[yo + 2] -= M[2, 6] / M[6, 6] * b[o + 6]
    nc = 0
    for rr in range(nr):
        if rkind[rr] == 3.0:
            continue
        y[yo + m + nc] = b[o + nact + rr]
        nc += 1
    if schur:
        kkt_schur_solve(A, nc, y, yo)
    else:
        lu_solve(A, piv, y, yo, m + nc)
    ddth = y[yo + 2]
    if nact == 7:
        if free0:
            b[o + 5] = (b[o + 5] - M[2, 5] * ddth) / M[5, 5]
        if free1:
            b[o + 6] = (b[o + 6] - M[2, 6] * ddth) / M[6, 6]
    nc = 0
    for rr in range(nr):
        if rkind[rr] == 3.0:
            a = 5 + int(rleg[rr])
            dda = b[o + nact + rr]
            b[o + nact + rr] = b[o + a] - M[2, a] * ddth - M[a, a] * dda
            b[o + a] = dda
        else:
            b[o + nact + rr] = y[yo + m + nc]
            nc += 1
    for i in range(m):
        b[o + i] = y[yo + i]


# --- structured KKT solve (Schur complements) ----------------------------------------------
# Layout of the factors in A (MAX_KKT x MAX_KKT):
#   A[0:5, 0:5]        M5^-1 (the reduced mass matrix, free gears folded into theta)
#   A[5+c, 0:5]        constraint row c (non-stuck rows, in order)
#   A[5+c, 5:10]       Y[:, c] = M5^-1 R_c^T
#   A[5+c, 10:10+nc]   Cholesky factor of S = R M5^-1 R^T (lower triangle, row c)
SCHUR_MAX_ROWS = MAX_KKT - 10


@kernel
def kkt_schur_factor(A, M, R, rkind, nact, nr, free0, free1):
    """Factor the reduced KKT system of :func:`kkt_reduced_factor` by Schur complements,
    using the structure of the mass matrix: the torso translations have the scalar inertia
    m (M[0,0] = M[1,1] = total mass, M[0,1] = 0), so M5^-1 follows from the 3 x 3 Schur
    complement C - B^T B / m of the rotational block; the constraint rows then give the
    SPD matrix S = R M5^-1 R^T, factored by Cholesky. Needs M5 positive definite (every
    body with mass and inertia; the massless-leg model uses the LU path). Returns
    (ok, nc); ok False if M5 or S is numerically singular."""
    m = M[0, 0]
    im = 1.0 / m
    # C' = C - B^T B / m, B = M[0:2, 2:5], C = M[2:5, 2:5] (theta with the free gears folded)
    c00 = M[2, 2]
    if nact == 7:
        if free0:
            c00 -= M[2, 5] * M[2, 5] / M[5, 5]
        if free1:
            c00 -= M[2, 6] * M[2, 6] / M[6, 6]
    b00 = M[0, 2]
    b01 = M[0, 3]
    b02 = M[0, 4]
    b10 = M[1, 2]
    b11 = M[1, 3]
    b12 = M[1, 4]
    s00 = c00 - im * (b00 * b00 + b10 * b10)
    s01 = M[2, 3] - im * (b00 * b01 + b10 * b11)
    s02 = M[2, 4] - im * (b00 * b02 + b10 * b12)
    s11 = M[3, 3] - im * (b01 * b01 + b11 * b11)
    s12 = M[3, 4] - im * (b01 * b02 + b11 * b12)
    s22 = M[4, 4] - im * (b02 * b02 + b12 * b12)
    # symmetric 3 x 3 inverse by cofactors
    a00 = s11 * s22 - s12 * s12
    a01 = s02 * s12 - s01 * s22
    a02 = s01 * s12 - s02 * s11
    det = s00 * a00 + s01 * a01 + s02 * a02
    scale = max(s00, max(s11, s22))
    if not (det > 1e-13 * scale * scale * scale):
        return False, 0
    idet = 1.0 / det
    i00 = a00 * idet
    i01 = a01 * idet
    i02 = a02 * idet
    i11 = (s00 * s22 - s02 * s02) * idet
    i12 = (s01 * s02 - s00 * s12) * idet
    i22 = (s00 * s11 - s01 * s01) * idet
    A[2, 2] = i00
    A[2, 3] = i01
    A[2, 4] = i02
    A[3, 2] = i01
    A[3, 3] = i11
    A[3, 4] = i12
    A[4, 2] = i02
    A[4, 3] = i12
    A[4, 4] = i22
    # W = B Ci (2 x 3); M5^-1: tc block -W/m, tt block I/m + W B^T / m^2
    w00 = b00 * i00 + b01 * i01 + b02 * i02
    w01 = b00 * i01 + b01 * i11 + b02 * i12
    w02 = b00 * i02 + b01 * i12 + b02 * i22
    w10 = b10 * i00 + b11 * i01 + b12 * i02
    w11 = b10 * i01 + b11 * i11 + b12 * i12
    w12 = b10 * i02 + b11 * i12 + b12 * i22
    A[0, 2] = -im * w00
    A[0, 3] = -im * w01
    A[0, 4] = -im * w02
    A[1, 2] = -im * w10
    A[1, 3] = -im * w11
    A[1, 4] = -im * w12
    A[2, 0] = A[0, 2]
    A[3, 0] = A[0, 3]
    A[4, 0] = A[0, 4]
    A[2, 1] = A[1, 2]
    A[3, 1] = A[1, 3]
    A[4, 1] = A[1, 4]
    im2 = im * im
    A[0, 0] = im + im2 * (w00 * b00 + w01 * b01 + w02 * b02)
    A[0, 1] = im2 * (w00 * b10 + w01 * b11 + w02 * b12)
    A[1, 0] = A[0, 1]
    A[1, 1] = im + im2 * (w10 * b10 + w11 * b11 + w12 * b12)
    # constraint rows, Y = M5^-1 R^T, S = R Y
    nc = 0
    for rr in range(nr):
        if rkind[rr] == 3.0:
            continue
        row = 5 + nc
        for j in range(5):
            A[row, j] = R[rr, j]
        for i in range(5):
            acc = 0.0
            for j in range(5):
                acc += A[i, j] * R[rr, j]
            A[row, 5 + i] = acc
        nc += 1
    for c in range(nc):
        for d in range(c + 1):
            acc = 0.0
            for j in range(5):
                acc += A[5 + c, j] * A[5 + d, 5 + j]
            A[5 + c, 10 + d] = acc
    # Cholesky of S in place (lower triangle)
    for c in range(nc):
        for d in range(c + 1):
            acc = A[5 + c, 10 + d]
            for e in range(d):
                acc -= A[5 + c, 10 + e] * A[5 + d, 10 + e]
            if c == d:
                if not (acc > 1e-13 * A[5 + c, 10 + c] + 1e-300):
                    return False, nc
                A[5 + c, 10 + c] = math.sqrt(acc)
            else:
                A[5 + c, 10 + d] = acc / A[5 + d, 10 + d]
    return True, nc


@kernel(inline="always")
def kkt_schur_solve(A, nc, y, yo):
    """Solve the reduced KKT system with the factors of :func:`kkt_schur_factor`, right-hand
    side y[yo:yo+5+nc] = [forces; constraint right-hand sides], in place: ddq then the
    multipliers."""
    x0 = y[yo + 0]
    x1 = y[yo + 1]
    x2 = y[yo + 2]
    x3 = y[yo + 3]
    x4 = y[yo + 4]
    z0 = A[0, 0] * x0 + A[0, 1] * x1 + A[0, 2] * x2 + A[0, 3] * x3 + A[0, 4] * x4
    z1 = A[1, 0] * x0 + A[1, 1] * x1 + A[1, 2] * x2 + A[1, 3] * x3 + A[1, 4] * x4
    z2 = A[2, 0] * x0 + A[2, 1] * x1 + A[2, 2] * x2 + A[2, 3] * x3 + A[2, 4] * x4
    z3 = A[3, 0] * x0 + A[3, 1] * x1 + A[3, 2] * x2 + A[3, 3] * x3 + A[3, 4] * x4
    z4 = A[4, 0] * x0 + A[4, 1] * x1 + A[4, 2] * x2 + A[4, 3] * x3 + A[4, 4] * x4
    if nc > 0:
        # t = R z - r, then S nu = t (forward / back substitution with the Cholesky factor)
        for c in range(nc):
            row = 5 + c
            acc = (A[row, 0] * z0 + A[row, 1] * z1 + A[row, 2] * z2 + A[row, 3] * z3
                   + A[row, 4] * z4 - y[yo + row])
            for e in range(c):
                acc -= A[row, 10 + e] * y[yo + 5 + e]
            y[yo + row] = acc / A[row, 10 + c]
        for c in range(nc - 1, -1, -1):
            row = 5 + c
            acc = y[yo + row]
            for e in range(c + 1, nc):
                acc -= A[5 + e, 10 + c] * y[yo + 5 + e]
            y[yo + row] = acc / A[row, 10 + c]
        # ddq = z - Y nu
        for c in range(nc):
            row = 5 + c
            nu = y[yo + row]
            z0 -= A[row, 5] * nu
            z1 -= A[row, 6] * nu
            z2 -= A[row, 7] * nu
            z3 -= A[row, 8] * nu
            z4 -= A[row, 9] * nu
    y[yo + 0] = z0
    y[yo + 1] = z1
    y[yo + 2] = z2
    y[yo + 3] = z3
    y[yo + 4] = z4


@kernel(inline="always")
def fill_derivative(ds, dq, b, LG, nact, model, ok):
    """ds = [dq, ddq, dl]: the accelerations are the first ``nact`` entries of the KKT
    solution b (zero if the factorization failed, ``ok`` False), the leg-length rates come
    from the per-leg scalars LG; outside Model II the gear angles follow the legs
    (alpha = phi)."""
    for i in range(NQ):
        ds[i] = dq[i]
        ds[NQ + i] = 0.0
    if ok:
        for i in range(nact):
            ds[NQ + i] = b[i]
    if model != MODEL_II:
        ds[NQ + 5] = ds[NQ + 3]
        ds[NQ + 6] = ds[NQ + 4]
    ds[IL_B] = LG[2 * LG_LDOT]
    ds[IL_B + 1] = LG[2 * LG_LDOT + 1]


@kernel(inline="always")
def fill_outputs(P, mi, cmd, aux, q, LG, b, rkind, rleg, nact, nr, ok, sgl0, cgl0, sgl1, cgl1,
                 vb, energy):
    """The outputs aux of :func:`evaluate_ws` from its per-leg scalars LG and the KKT
    solution b (multipliers b[nact:nact+nr]); the ground force of a pinned toe is summed
    afresh, so a second call after a new solve (:func:`evaluate_command_change`) is
    exact."""
    model = int(P[P_MODEL])
    npl = P[P_NP]
    N = P[P_N]
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        if mode == STICK or mode == STRUT:
            sg = sgl0 if leg == 0 else sgl1
            cg = cgl0 if leg == 0 else cgl1
            LG[2 * LG_GT + leg] = -LG[2 * LG_FAX + leg] * sg
            LG[2 * LG_GN + leg] = LG[2 * LG_FAX + leg] * cg
    for rr in range(nr):
        lam = -b[nact + rr] if ok else 0.0
        leg = int(rleg[rr])
        sg = sgl0 if leg == 0 else sgl1
        cg = cgl0 if leg == 0 else cgl1
        kind = int(rkind[rr])
        if kind == 1:
            LG[2 * LG_GT + leg] += lam * cg
            LG[2 * LG_GN + leg] += lam * sg
        elif kind == 2:
            LG[2 * LG_STRUT + leg] = lam
            LG[2 * LG_GT + leg] += lam * sg
            LG[2 * LG_GN + leg] -= lam * cg
        elif kind == 3:
            LG[2 * LG_HOLD + leg] = lam / (npl * N)
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        o = leg * NAUX_LEG
        aux[o + A_GT] = LG[2 * LG_GT + leg]
        aux[o + A_GN] = LG[2 * LG_GN + leg]
        aux[o + A_FAX] = LG[2 * LG_FAX + leg] if mode != STRUT else -LG[2 * LG_STRUT + leg]
        aux[o + A_TAU_CMD] = cmd[leg]
        aux[o + A_TAU_APP] = LG[2 * LG_TAPP + leg]
        aux[o + A_CURRENT] = LG[2 * LG_CUR + leg]
        aux[o + A_OMEGA_M] = LG[2 * LG_OM + leg]
        aux[o + A_BELT] = q[5 + leg] - q[3 + leg]
        if model == MODEL_II and mi[MI_MOTOR_B + leg] == STUCK:
            aux[o + A_HOLD] = LG[2 * LG_HOLD + leg]
        else:
            aux[o + A_HOLD] = LG[2 * LG_TFRIC + leg]
        aux[o + A_TOE_X] = LG[2 * LG_TOEX + leg]
        aux[o + A_TOE_Y] = LG[2 * LG_TOEY + leg]
        aux[o + A_SLIP_V] = LG[2 * LG_TOEVX + leg]
        aux[o + A_STRUT] = LG[2 * LG_STRUT + leg]
        aux[o + A_TAU_BELT] = LG[2 * LG_TBELT + leg]
    aux[A_VBATT] = vb
    aux[A_ENERGY] = energy
    aux[A_KKT_OK] = 1.0 if ok else 0.0


@kernel
def evaluate_command_change(P, mi, cmd, ds, aux, wk, wA, piv):
    """Update ds = f(s) and the outputs aux for new commanded torques ``cmd`` at the state
    and modes of the last :func:`evaluate_ws` call on this workspace (made with
    ``want_aux``); ds and aux are filled completely (they need not hold that evaluation).

    The commands enter the dynamics only through the delivered hip torques (SPEC.md 4:
    current limits, torque-speed line, battery), i.e. the right-hand side of the KKT system,
    whose factorization is kept: the change of torque is solved with those factors and added
    to the accelerations and multipliers. Equal to a fresh evaluation up to round-off, for
    the cost of one solve. Returns the KKT flag."""
    model = int(P[P_MODEL])
    nact = 7 if model == MODEL_II else 5
    meta = wk[WK_META:WK_META + 9]
    ok = meta[2] > 0.5
    if not ok:
        aux[A_KKT_OK] = 0.0
        return False
    schur = meta[0] > 0.5
    nr = int(meta[1])
    n = nact + nr
    dq = wk[WK_DQ:WK_DQ + NQ]
    q = wk[WK_Q:WK_Q + NQ]
    LG = wk[WK_LEG:WK_LEG + 32]
    b = wk[WK_B:WK_B + MAX_KKT]
    b2 = wk[WK_B2:WK_B2 + MAX_KKT]
    rkind = wk[WK_RKIND:WK_RKIND + MAX_ROWS]
    rleg = wk[WK_RLEG:WK_RLEG + MAX_ROWS]
    A = wA[0:MAX_KKT]
    M = wA[WA_M:WA_M + NQ]
    npl = P[P_NP]
    vb = battery_voltage(dq, cmd, P)
    for i in range(n):
        b2[i] = 0.0
    row = 5 if model == MODEL_II else 3
    for leg in range(2):
        om = LG[2 * LG_OM + leg]
        cur = motor_current(cmd[leg], om, vb, P)
        tapp = delivered_torque(cur, om, P)
        if model != MODEL_PASSIVE:
            b2[row + leg] = npl * (tapp - LG[2 * LG_TAPP + leg])
        LG[2 * LG_CUR + leg] = cur
        LG[2 * LG_TAPP + leg] = tapp
    free0 = model == MODEL_II and mi[MI_MOTOR_B] != STUCK
    free1 = model == MODEL_II and mi[MI_MOTOR_B + 1] != STUCK
    kkt_reduced_solve(A, piv, M, rkind, rleg, nact, nr, free0, free1, wk, WK_B2, wk, WK_Y,
                      schur)
    for i in range(n):
        b[i] += b2[i]
    fill_derivative(ds, dq, b, LG, nact, model, ok)
    meta[3] = vb
    fill_outputs(P, mi, cmd, aux, q, LG, b, rkind, rleg, nact, nr, ok, meta[4], meta[5],
                 meta[6], meta[7], vb, meta[8])
    return ok


@kernel
def evaluate_ws(s, P, mi, mf, cmd, ds, aux, wk, wA, piv, want_stiff, stiff, want_aux):
    """:func:`evaluate` without allocations, on the scratch arrays of
    :func:`new_eval_workspace`.

    If ``want_stiff``, also fills ``stiff`` (16 x 2 NSTIFF) with a rank-4 factorization
    J_s = U V^T (U = stiff[:, :NSTIFF], V = stiff[:, NSTIFF:]) of the Jacobian of ds with respect
    to s restricted to the Model II belt spring-dampers (the stiff part: eigenvalues
    ~ -1e4 /s from c_b against the gear-train inertia): per leg
    d(ddq)/ds ~ -npl G w (c_b w^T Pi_v + k_b w^T Pi_q), G the constrained inverse mass
    matrix (from the same factorization), w = e_alpha - e_phi, Pi_v / Pi_q the
    derivatives of the velocity / position projections; plus the motor-side damping on
    alpha (joint friction b_J, back-EMF while on the torque-speed line),
    -npl G e_alpha d_m e_alpha^T. Zero in the other models.

    ``want_aux`` False (the integrators' inner stages, whose outputs nobody reads) skips the
    outputs: aux is then left as it was, except ``aux[A_KKT_OK]``."""
    model = int(P[P_MODEL])
    nact = 7 if model == MODEL_II else 5
    q = wk[WK_Q:WK_Q + NQ]
    dq = wk[WK_DQ:WK_DQ + NQ]
    l = wk[WK_L:WK_L + 2]
    for i in range(NQ):
        q[i] = s[i]
        dq[i] = s[NQ + i]
    l[0] = s[IL_B]
    l[1] = s[IL_B + 1]
    sth, cth, sgl0, cgl0, sgl1, cgl1 = project(q, dq, l, P, mi, mf)

    Q = wk[WK_Q_:WK_Q_ + NQ]
    h = wk[WK_H:WK_H + NQ]
    r = wk[WK_R:WK_R + MAX_ROWS]
    LG = wk[WK_LEG:WK_LEG + 32]
    for i in range(NQ):
        Q[i] = 0.0
        h[i] = 0.0
    for i in range(28):
        LG[i] = 0.0
    A = wA[0:MAX_KKT]
    R = wA[WA_R:WA_R + MAX_ROWS]
    M = wA[WA_M:WA_M + NQ]

    npl = P[P_NP]
    grav = P[P_G]
    l0 = P[P_L0]
    k = P[P_K]
    d = P[P_D]
    N = P[P_N]
    Lh = P[P_L]
    ml = npl * P[P_ML]
    il = npl * P[P_IL]
    th = q[2]
    dth = dq[2]
    massless = P[P_MASSLESS] > 0.5

    # mass matrix, Coriolis vector, gravity (SPEC.md 2); as mass_matrix() / coriolis()
    for i in range(NQ):
        for j in range(NQ):
            M[i, j] = 0.0
    M[0, 0] = P[P_MT]
    M[1, 1] = P[P_MT]
    M[2, 2] = P[P_IT]
    Q[1] -= P[P_MT] * grav
    mlg = ml * grav
    epot = P[P_MT] * grav * q[1]
    for leg in range(2):
        sL = (2.0 * leg - 1.0) * Lh
        kk = 3 + leg
        dg = dth + dq[kk]
        sg = sgl0 if leg == 0 else sgl1
        cg = cgl0 if leg == 0 else cgl1
        jth_x = -sL * sth + d * cg
        jth_y = sL * cth + d * sg
        jph_x = d * cg
        jph_y = d * sg
        M[0, 0] += ml
        M[1, 1] += ml
        M[0, 2] += ml * jth_x
        M[1, 2] += ml * jth_y
        M[0, kk] += ml * jph_x
        M[1, kk] += ml * jph_y
        M[2, 2] += ml * (jth_x * jth_x + jth_y * jth_y)
        M[2, kk] += ml * (jth_x * jph_x + jth_y * jph_y)
        M[kk, kk] += ml * (jph_x * jph_x + jph_y * jph_y)
        M[2, 2] += il
        M[2, kk] += il
        M[kk, kk] += il
        ax = -sL * cth * dth * dth - d * sg * dg * dg
        ay = -sL * sth * dth * dth + d * cg * dg * dg
        h[0] += ml * ax
        h[1] += ml * ay
        h[2] += ml * (jth_x * ax + jth_y * ay)
        h[kk] += ml * d * (cg * ax + sg * ay)
        Q[1] -= mlg
        Q[2] -= mlg * (sL * cth + d * sg)
        Q[kk] -= mlg * d * sg
        # potential energy (as potential_energy())
        yc = q[1] + sL * sth - d * cg
        epot += ml * grav * yc
        dl = l0 - l[leg]
        epot += 0.5 * npl * k * dl * dl
        if model == MODEL_II:
            bd = belt_spring_deflection(q[5 + leg] - q[kk], P)
            epot += 0.5 * npl * P[P_KB] * bd * bd
    if model == MODEL_II:
        j1 = npl * P[P_J1]
        j2 = npl * P[P_J2]
        for leg in range(2):
            a = 5 + leg
            M[2, 2] += j1 + j2
            M[2, a] += j2 + N * j1
            M[a, a] += j2 + N * N * j1
    for i in range(NQ):
        for j in range(i):
            M[i, j] = M[j, i]

    # actuators
    vb = battery_voltage(dq, cmd, P)
    for leg in range(2):
        if model == MODEL_II:
            om = N * dq[5 + leg]
        else:
            om = N * dq[3 + leg]
        cur = motor_current(cmd[leg], om, vb, P)
        tapp = delivered_torque(cur, om, P)
        LG[2 * LG_OM + leg] = om
        LG[2 * LG_CUR + leg] = cur
        LG[2 * LG_TAPP + leg] = tapp
        if model == MODEL_II:
            Q[5 + leg] += npl * tapp
            mm = mi[MI_MOTOR_B + leg]
            tf = P[P_B_J] * om
            if mm != STUCK:
                tf += P[P_TAU_S] * mm
            LG[2 * LG_TFRIC + leg] = tf
            Q[5 + leg] -= npl * N * tf
            tb = (P[P_KB] * belt_spring_deflection(q[5 + leg] - q[3 + leg], P)
                  + P[P_CB] * (dq[5 + leg] - dq[3 + leg]))
            LG[2 * LG_TBELT + leg] = tb
            Q[3 + leg] += npl * tb
            Q[5 + leg] -= npl * tb
        elif model != MODEL_PASSIVE:
            Q[3 + leg] += npl * tapp

    # contact forces and constraint rows
    rkind = wk[WK_RKIND:WK_RKIND + MAX_ROWS]
    rleg = wk[WK_RLEG:WK_RLEG + MAX_ROWS]
    nr = 0
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        sL = (2.0 * leg - 1.0) * Lh
        sg = sgl0 if leg == 0 else sgl1
        cg = cgl0 if leg == 0 else cgl1
        dg = dth + dq[3 + leg]
        hx = q[0] + sL * cth
        hy = q[1] + sL * sth
        hvx = dq[0] - sL * sth * dth
        hvy = dq[1] + sL * cth * dth
        ll = l[leg]
        jt_th_x = -sL * sth + ll * cg
        jt_th_y = sL * cth + ll * sg
        jt_ph_x = ll * cg
        jt_ph_y = ll * sg
        bx = -sL * cth * dth * dth
        by = -sL * sth * dth * dth
        kk = 3 + leg
        # leg damper and sliding-joint friction (as Table III unless the effects beyond
        # the paper are switched on)
        c_l = leg_damping(q[kk], P)
        tau_hip = (LG[2 * LG_TBELT + leg] if model == MODEL_II else
                   (LG[2 * LG_TAPP + leg] if model != MODEL_PASSIVE else 0.0))
        fc_l = leg_friction_level(tau_hip, ll, P)
        # sin(phi), cos(phi) of the leg angle relative to the torso
        sph = sg * cth - cg * sth
        cph = cg * cth + sg * sth
        if mode == STICK or mode == STRUT:
            ld = -(hvx * sg - hvy * cg)
            LG[2 * LG_LDOT + leg] = ld
            F = npl * leg_axial_force(k, c_l, l0, ll, ld, fc_l)
            if mode == STRUT:
                F = npl * k * (l0 - ll)
            LG[2 * LG_FAX + leg] = F
            fx = -F * sg
            fy = F * cg
            Q[0] += fx
            Q[1] += fy
            Q[2] += jt_th_x * fx + jt_th_y * fy
            Q[kk] += jt_ph_x * fx + jt_ph_y * fy
            new_row(R, r, rkind, rleg, nr, -(bx * cg + by * sg + 2.0 * ld * dg), 1.0, leg)
            R[nr, 0] = cg
            R[nr, 1] = sg
            R[nr, 2] = sL * sph + ll
            R[nr, kk] = ll
            nr += 1
            if mode == STRUT:
                w = P[P_STRUT_OMEGA]
                new_row(R, r, rkind, rleg, nr, -(bx * sg - by * cg) + ll * dg * dg
                        + 2.0 * w * ld + w * w * (ll - l0), 2.0, leg)
                R[nr, 0] = sg
                R[nr, 1] = -cg
                R[nr, 2] = -sL * cph
                nr += 1
            LG[2 * LG_TOEX + leg] = mf[MF_ANCHOR_B + leg]
        elif mode == SLIDE:
            ld = hvy / cg + hy * sg * dg / (cg * cg)
            LG[2 * LG_LDOT + leg] = ld
            F = npl * leg_axial_force(k, c_l, l0, ll, ld, fc_l)
            LG[2 * LG_FAX + leg] = F
            mu = P[P_MU]
            sig = 0.0
            if mu < 1e300:
                sig = mu * mi[MI_SLIDE_DIR_B + leg]
            gn = F / (cg + sig * sg)
            gt = -sig * gn
            LG[2 * LG_GN + leg] = gn
            LG[2 * LG_GT + leg] = gt
            Q[0] += gt
            Q[1] += gn
            Q[2] += jt_th_x * gt + jt_th_y * gn
            Q[kk] += jt_ph_x * gt + jt_ph_y * gn
            LG[2 * LG_TOEX + leg] = hx + ll * sg
            LG[2 * LG_TOEVX + leg] = hvx + ld * sg + ll * cg * dg
        else:
            if massless:
                new_row(R, r, rkind, rleg, nr, 0.0, 4.0, leg)
                R[nr, kk] = 1.0
                if P[P_TD_WORLD] > 0.5:
                    R[nr, 2] = 1.0
                nr += 1
                ld = 0.0
            else:
                ld = flight_leg_rate(k, c_l, l0, ll, fc_l)
            LG[2 * LG_LDOT + leg] = ld
            LG[2 * LG_TOEX + leg] = hx + ll * sg
            LG[2 * LG_TOEY + leg] = hy - ll * cg
            LG[2 * LG_TOEVX + leg] = hvx + ld * sg + ll * cg * dg
        if model == MODEL_II and mi[MI_MOTOR_B + leg] == STUCK:
            new_row(R, r, rkind, rleg, nr, 0.0, 3.0, leg)
            R[nr, 5 + leg] = 1.0
            nr += 1
    nr = add_clamp_rows(P, R, r, rkind, rleg, nr)

    # kinetic energy before the factorization
    ekin = 0.0
    if want_aux:
        for i in range(NQ):
            acc = 0.0
            for j in range(NQ):
                acc += M[i, j] * dq[j]
            ekin += dq[i] * acc

    # KKT system [M R^T; R 0] [ddq; nu] = [Q - h; r]; generalized constraint force = -R^T nu
    n = nact + nr
    b = wk[WK_B:WK_B + MAX_KKT]
    for i in range(nact):
        b[i] = Q[i] - h[i]
    for rr in range(nr):
        b[nact + rr] = r[rr]
    free0 = model == MODEL_II and mi[MI_MOTOR_B] != STUCK
    free1 = model == MODEL_II and mi[MI_MOTOR_B + 1] != STUCK
    # structured (Schur-complement) factorization whenever the mass matrix is positive
    # definite (its translation block is m I by construction, above); the LU path keeps
    # the massless-leg model (zero leg inertia)
    schur = not massless and nr <= SCHUR_MAX_ROWS
    if schur:
        ok, nred = kkt_schur_factor(A, M, R, rkind, nact, nr, free0, free1)
    else:
        ok, nred = kkt_reduced_factor(A, piv, M, R, rkind, nact, nr, free0, free1)
    if ok:
        kkt_reduced_solve(A, piv, M, rkind, rleg, nact, nr, free0, free1, wk, WK_B, wk, WK_Y,
                          schur)
    meta = wk[WK_META:WK_META + 9]
    meta[0] = 1.0 if schur else 0.0
    meta[1] = nr
    meta[2] = 1.0 if ok else 0.0
    meta[3] = vb
    meta[4] = sgl0
    meta[5] = cgl0
    meta[6] = sgl1
    meta[7] = cgl1

    fill_derivative(ds, dq, b, LG, nact, model, ok)

    if want_stiff:
        for i in range(NS):
            for j in range(2 * NSTIFF):
                stiff[i, j] = 0.0
        if model == MODEL_II and ok:
            b2 = wk[WK_B2:WK_B2 + MAX_KKT]
            cb = P[P_CB]
            kb = P[P_KB]
            for leg in range(2):
                for i in range(n):
                    b2[i] = 0.0
                b2[5 + leg] = 1.0
                b2[3 + leg] = -1.0
                kkt_reduced_solve(A, piv, M, rkind, rleg, nact, nr, free0, free1, wk, WK_B2, wk,
                                  WK_Y, schur)
                # U: response of ddq to a unit belt torque pair, -npl G w
                for i in range(nact):
                    stiff[NQ + i, leg] = -npl * b2[i]
                # V: belt torque c_b (dalpha - dphi) + k_b (alpha - phi) differentiated
                # with respect to s through the projection of the dependent coordinates
                vcol = NSTIFF + leg
                stiff[5 + leg, vcol] = kb
                if mi[MI_MOTOR_B + leg] != STUCK:
                    stiff[NQ + 5 + leg, vcol] = cb
                mode = mi[MI_CONTACT_B + leg]
                if mode == STICK or mode == STRUT:
                    sg = sgl0 if leg == 0 else sgl1
                    cg = cgl0 if leg == 0 else cgl1
                    sL = (2.0 * leg - 1.0) * Lh
                    ll = l[leg]
                    sph = sg * cth - cg * sth
                    # phi = atan2(anchor - hip_x, hip_y) - theta; dphi from R dq = 0
                    d0 = cg / ll
                    d1 = sg / ll
                    d2 = (sL * sph + ll) / ll
                    # the damper also depends on q through the projected dphi:
                    # dphi = dg - dtheta, dg = -(hvx b + hvy a) / ll^2 with
                    # a = anchor - hip_x = ll sin g, b = hip_y = ll cos g
                    hvx = dq[0] - sL * sth * dth
                    hvy = dq[1] + sL * cth * dth
                    aa = ll * sg
                    bb = ll * cg
                    D2 = ll * ll
                    dgv = -(hvx * bb + hvy * aa) / D2
                    dga = -hvy / D2 - 2.0 * aa * dgv / D2
                    dgb = -hvx / D2 - 2.0 * bb * dgv / D2
                    e0 = -dga
                    e1 = dgb
                    e2 = (dga * sL * sth + dgb * sL * cth
                          + (bb * sL * cth + aa * sL * sth) * dth / D2)
                    stiff[0, vcol] = kb * d0 - cb * e0
                    stiff[1, vcol] = kb * d1 - cb * e1
                    stiff[2, vcol] = kb * d2 - cb * e2
                    stiff[NQ + 0, vcol] = cb * d0
                    stiff[NQ + 1, vcol] = cb * d1
                    stiff[NQ + 2, vcol] = cb * d2
                elif mode == FLIGHT and massless:
                    if P[P_TD_WORLD] > 0.5:
                        stiff[2, vcol] = kb
                        stiff[NQ + 2, vcol] = cb
                else:
                    stiff[3 + leg, vcol] = -kb
                    stiff[NQ + 3 + leg, vcol] = -cb

            # motor-side damping on alpha: joint viscous friction and, while the current is
            # limited by the torque-speed line, the back-EMF; only where it is stiff, i.e.
            # its rate on the gear train's own inertia, n d_m / M_aa, is at least
            # STIFF_MOTOR_RATE (Scout II: ~400 /s on the torque-speed line, so these columns
            # stay zero and the ARK step runs at rank 2)
            r_a = P[P_RA]
            for leg in range(2):
                if mi[MI_MOTOR_B + leg] == STUCK:
                    continue
                dm = P[P_B_J]
                om = LG[2 * LG_OM + leg]
                imax = P[P_IMAX]
                ic = cmd[leg] / (N * P[P_ETA] * P[P_KT])
                v_lo = (-vb - P[P_KW] * om) / r_a
                v_hi = (vb - P[P_KW] * om) / r_a
                if model != MODEL_IDEAL and ((v_hi < imax and ic > v_hi) or
                                             (v_lo > -imax and ic < v_lo)):
                    dm += P[P_ETA] * P[P_KT] * P[P_KW] / r_a
                dm *= N * N
                if npl * dm < STIFF_MOTOR_RATE * M[5 + leg, 5 + leg]:
                    continue    # not stiff: left to the explicit part (column stays zero)
                for i in range(n):
                    b2[i] = 0.0
                b2[5 + leg] = 1.0
                kkt_reduced_solve(A, piv, M, rkind, rleg, nact, nr, free0, free1, wk, WK_B2, wk,
                                  WK_Y, schur)
                for i in range(nact):
                    stiff[NQ + i, 2 + leg] = -npl * b2[i]
                stiff[NQ + 5 + leg, NSTIFF + 2 + leg] = dm

    if not want_aux:
        aux[A_KKT_OK] = 1.0 if ok else 0.0
        return ok
    meta[8] = 0.5 * ekin + epot
    fill_outputs(P, mi, cmd, aux, q, LG, b, rkind, rleg, nact, nr, ok, sgl0, cgl0, sgl1, cgl1,
                 vb, meta[8])
    return ok


@allocating
def evaluate(s, P, mi, mf, cmd, ds, aux):
    """Right-hand side ds = f(s) of the hybrid model in its current modes, and outputs.

    Parameters
    ----------
    s : (16,) state [q, dq, l_b, l_f] (SI).
    P : parameter array (layout.P_*).
    mi, mf : integer / float mode arrays (contact modes, motor-joint modes, toe anchors).
    cmd : (2,) commanded hip torque per physical leg, leg side [N m] (sample-and-hold).
    ds : (16,) output derivative.
    aux : (NAUX,) output ground forces, torques, currents, energy, ... (layout.A_*).

    Returns
    -------
    bool : False if the constrained dynamics are singular.

    Allocates its scratch space; the integrators call :func:`evaluate_ws` with a
    preallocated workspace instead.
    """
    wk = np.empty(WK_SIZE)
    wA = np.empty((WA_ROWS, MAX_KKT))
    piv = np.empty(MAX_KKT, dtype=np.int64)
    stiff = np.empty((1, 1))
    return evaluate_ws(s, P, mi, mf, cmd, ds, aux, wk, wA, piv, False, stiff, True)


@kernel
def project_state(s, P, mi, mf):
    """Project the dependent coordinates of a full state vector in place."""
    # views: project() writes the dependent coordinates straight into s
    project(s[0:NQ], s[NQ:2 * NQ], s[IL_B:IL_B + 2], P, mi, mf)


@allocating
def impact(s, P, mi, mf, out):
    """Rigid-body impact onto the constraints of the current modes (SPEC.md 3), in place.

    Solves ``[M R^T; R 0] [dq+; Lambda] = [M dq-; 0]`` where R holds the velocity
    constraints that act impulsively: every pinned toe (perpendicular and, for a strut,
    axial), massless flight legs, and in Model II a rigid belt for each leg (the belt damper
    is far stiffer than the gear-train inertia over an impact: alpha' = phi' after it).
    Stiction cannot carry an impulse, so stuck motor joints do not constrain it. Every row
    is homogeneous, so dq+ is the M-orthogonal projection of dq- onto the constrained
    velocities and the kinetic energy lost, 1/2 |dq- - dq+|_M^2, is never negative.

    out[leg*3 + 0..2]: normal impulse, tangential impulse [N s] of each pinned toe;
    out[6]: kinetic energy lost [J]. Returns False if singular.
    """
    model = int(P[P_MODEL])
    nact = 7 if model == MODEL_II else 5
    q = s[0:NQ].copy()
    dq = s[NQ:2 * NQ].copy()
    l = s[IL_B:IL_B + 2].copy()
    # stiction does not act impulsively: treat motor joints as free while projecting
    mi2 = mi.copy()
    mi2[MI_MOTOR_B] = 1
    mi2[MI_MOTOR_B + 1] = 1
    project(q, dq, l, P, mi2, mf)
    M = np.empty((NQ, NQ))
    mass_matrix(q, P, M)
    ke0 = 0.0
    dq0 = s[NQ:2 * NQ].copy()
    if model != MODEL_II:
        dq0[5] = dq0[3]
        dq0[6] = dq0[4]
    for i in range(NQ):
        for j in range(NQ):
            ke0 += dq0[i] * M[i, j] * dq0[j]
    R = np.zeros((MAX_ROWS, NQ))
    r = np.zeros(MAX_ROWS)
    rleg = np.zeros(MAX_ROWS, dtype=np.int64)
    rkind = np.zeros(MAX_ROWS, dtype=np.int64)
    nr = 0
    th = q[2]
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        sL = (2.0 * leg - 1.0) * P[P_L]
        g = th + q[3 + leg]
        sg = math.sin(g)
        cg = math.cos(g)
        kk = 3 + leg
        if mode == STICK or mode == STRUT:
            R[nr, 0] = cg
            R[nr, 1] = sg
            R[nr, 2] = sL * math.sin(q[3 + leg]) + l[leg]
            R[nr, kk] = l[leg]
            rleg[nr] = leg
            rkind[nr] = 1
            nr += 1
            if mode == STRUT:
                R[nr, 0] = sg
                R[nr, 1] = -cg
                R[nr, 2] = -sL * math.cos(q[3 + leg])
                rleg[nr] = leg
                rkind[nr] = 2
                nr += 1
        elif mode == FLIGHT and P[P_MASSLESS] > 0.5:
            R[nr, kk] = 1.0
            if P[P_TD_WORLD] > 0.5:
                R[nr, 2] = 1.0
            rleg[nr] = leg
            rkind[nr] = 4
            nr += 1
        if model == MODEL_II:
            # rigid belt over the impact: the gear rate equals the leg rate after it (the
            # belt damper, 80 us against the gear train, evens out the relative rate
            # within the impact; the energy of that relative motion is part of the logged
            # impact loss). A homogeneous row: the impact can only remove energy.
            R[nr, 5 + leg] = 1.0
            R[nr, 3 + leg] = -1.0
            r[nr] = 0.0
            rleg[nr] = leg
            rkind[nr] = 3
            nr += 1
    n = nact + nr
    A = np.zeros((n, n))
    b = np.zeros(n)
    for i in range(nact):
        acc = 0.0
        for j in range(nact):
            A[i, j] = M[i, j]
            acc += M[i, j] * dq0[j]
        b[i] = acc
    for rr in range(nr):
        for j in range(nact):
            A[nact + rr, j] = R[rr, j]
            A[j, nact + rr] = R[rr, j]
        b[nact + rr] = r[rr]
    ok = solve_dense(A, b, n)
    for i in range(7):
        out[i] = 0.0
    if not ok:
        return False
    for i in range(nact):
        dq[i] = b[i]
    if model != MODEL_II:
        dq[5] = dq[3]
        dq[6] = dq[4]
    for rr in range(nr):
        lam = -b[nact + rr]
        leg = rleg[rr]
        g = th + q[3 + leg]
        if rkind[rr] == 1:
            out[3 * leg] += lam * math.sin(g)
            out[3 * leg + 1] += lam * math.cos(g)
        elif rkind[rr] == 2:
            out[3 * leg] -= lam * math.cos(g)
            out[3 * leg + 1] += lam * math.sin(g)
    ke1 = 0.0
    for i in range(NQ):
        for j in range(NQ):
            ke1 += dq[i] * M[i, j] * dq[j]
    out[6] = 0.5 * (ke0 - ke1)
    s[0:NQ] = q
    s[NQ:2 * NQ] = dq
    s[IL_B:IL_B + 2] = l
    if model == MODEL_II:
        # Stiction carries no impulse, so every motor joint's stick/slip mode follows its
        # new gear rate (SPEC.md 3): the rigid belt moves the gear train with the leg, which
        # can reverse a slipping joint; a joint left at exactly zero rate is stuck (settle()
        # releases it if stiction cannot hold it). Keeping the old slip direction would
        # leave a joint "slipping" against its motion, which settle() could only reconcile
        # with an impulse that stiction cannot give.
        for leg in range(2):
            mi[MI_MOTOR_B + leg] = motor_mode_from_rate(dq[5 + leg], P)
    project_state(s, P, mi, mf)
    return True


@kernel(inline="always")
def motor_mode_from_rate(w, P):
    """Stick/slip mode of a Model II motor joint whose gear rate is ``w`` [rad/s] with no
    other information: slipping in the direction of motion; at exactly zero rate stuck if
    the joint has stiction (a joint without stiction is never stuck: nothing could release
    it, so it "slips" with zero Coulomb torque)."""
    if w > 0.0:
        return SLIP_POS
    if w < 0.0:
        return SLIP_NEG
    return STUCK if P[P_TAU_S] > 0.0 else SLIP_POS
