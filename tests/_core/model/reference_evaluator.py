"""The reference evaluator: a second, allocating implementation of the model's right-hand
side (dense KKT solve, its own assembly of the forces and rows), the test oracle of the
optimized :func:`scoutsim._core.model.evaluate.evaluate_ws` (tests/_core/model/test_evaluate.py).
Not part of the package: it exists only to be compared against.

To be an oracle of the model's laws and not a copy of them, it writes every law itself, from
the text of docs/specification.md (sections 1-5) and docs/model.md ("Generalized forces",
"Transmission losses", "Effects beyond the paper's models"), and imports none of the
package's law kernels:

* the amplifier's motor current (current limit, torque-speed line, the bench rig's open and
  shorted motor leads), the delivered torque with the optional transmission losses, and the
  battery voltage with an internal resistance (solved here by bracketed root finding of
  V_b = V_oc - R_b P(V_b) / V_b with SciPy's brentq, to round-off);
* the telescopic leg: damper c (1 + a phi^2), sliding-joint friction level
  F_c + mu_s |tau_hip| / l, axial force, and the flight rate of the massless toe (solved
  here by root finding of the toe's force balance);
* the belt spring's dead zone, the gravity of the torso and leg bodies, the potential
  energy, and the mass matrix and velocity terms (assembled from explicit body Jacobians;
  tools/derive_eom.py and tests/_core/model/test_eom_independent.py check the package's against
  a SymPy derivation as well);
* the projection of the dependent coordinates onto the active constraints (the contact
  modes' geometry, the bench rig's clamps, the gear angles).

What it still takes from the package: the index layout (model/layout.py: names of slots,
modes and row kinds, not laws), the bench rig's clamp rows and the dense pivoted-LU solve
of the KKT system (model/kkt.py). It is plain Python, not compiled.

Two regularisation widths are numbers the documentation states and are written here from
it: the leg friction's linear band (1 mm/s, docs/model.md "Effects beyond the paper's
models") and the loss-direction blending band (1 rad/s at the motor, "Transmission
losses").
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from scoutsim._core.model.kkt import MAX_ROWS, add_clamp_rows, solve_dense
from scoutsim._core.model.layout import (
    A_BELT,
    A_CURRENT,
    A_ENERGY,
    A_FAX,
    A_GN,
    A_GT,
    A_HOLD,
    A_KKT_OK,
    A_OMEGA_M,
    A_SLIP_V,
    A_STRUT,
    A_TAU_APP,
    A_TAU_BELT,
    A_TAU_CMD,
    A_TOE_X,
    A_TOE_Y,
    A_VBATT,
    CIRCUIT_OPEN,
    CIRCUIT_SHORT,
    HIP_SIGN,
    IL_B,
    MF_ANCHOR_B,
    MI_CONTACT_B,
    MI_MOTOR_B,
    MI_SLIDE_DIR_B,
    MODEL_IDEAL,
    MODEL_II,
    MODEL_PASSIVE,
    NAUX_LEG,
    NQ,
    P_B_J,
    P_BACKLASH,
    P_C,
    P_C_LOAD,
    P_CB,
    P_CIRCUIT,
    P_CLAMP_LEGS,
    P_CLAMP_TORSO,
    P_COM_OFFSET,
    P_D,
    P_ETA,
    P_G,
    P_IL,
    P_IMAX,
    P_IT,
    P_J1,
    P_J2,
    P_K,
    P_KB,
    P_KT,
    P_KW,
    P_L,
    P_L0,
    P_LEG_C_ANGLE,
    P_LEG_FRIC,
    P_LEG_FRIC_SIDE,
    P_MASSLESS,
    P_ML,
    P_MODEL,
    P_MT,
    P_MU,
    P_N,
    P_NO_SLIP,
    P_NP,
    P_RA,
    P_RB,
    P_STRUT_OMEGA,
    P_TAU_IDLE,
    P_TAU_S,
    P_TD_B,
    P_TD_WORLD,
    P_VB,
    ROW_GEAR,
    ROW_MASSLESS,
    ROW_TOE_ACROSS,
    ROW_TOE_ALONG,
    SLIDE,
    STICK,
    STRUT,
    STUCK,
)

#: Leg-length rate [m/s] below which the sliding joint's Coulomb friction is linear in the
#: rate (docs/model.md, "Effects beyond the paper's models": 1 mm/s).
LEG_FRICTION_BAND = 1e-3
#: Motor speed [rad/s] over which the direction of the transmission losses is blended
#: linearly (docs/model.md, "Transmission losses": 1 rad/s at the motor).
LOSS_BLEND_BAND = 1.0


# --- constraints (docs/specification.md sections 1-3, docs/model.md "Constraints") ---


def project(q, dq, l, P, mi, mf):
    """Make the dependent coordinates consistent with the active constraints, in place
    (docs/model.md, "Constraints": they are projected before every evaluation): a pinned
    toe fixes the leg's angle, its rate and its length by the geometry of hip and anchor;
    a sliding toe on the ground fixes the length; a massless flight leg is placed at its
    touchdown angle at rest length; a massive flight leg is at most at its stop (at it
    when undamped); a clamped rig is at rest; outside Model II the gear angle is the leg
    angle, and a stuck Model II motor joint does not turn."""
    if P[P_CLAMP_TORSO] > 0.5:
        dq[0:3] = 0.0
        if P[P_CLAMP_LEGS] > 0.5:
            dq[3:5] = 0.0
    th = q[2]
    dth = dq[2]
    for leg in range(2):
        l0 = P[P_L0 + leg]
        sL = HIP_SIGN[leg] * P[P_L] - P[P_COM_OFFSET]
        hx = q[0] + sL * math.cos(th)
        hy = q[1] + sL * math.sin(th)
        hvx = dq[0] - sL * math.sin(th) * dth
        hvy = dq[1] + sL * math.cos(th) * dth
        mode = mi[MI_CONTACT_B + leg]
        if mode == STICK or mode == STRUT:
            # hip -> toe vector (a, -b) to the anchor on the ground; u = (sin g, -cos g)
            a = mf[MF_ANCHOR_B + leg] - hx
            b = hy
            g = math.atan2(a, b)
            # the anchor is fixed: da/dt = -hvx, db/dt = hvy
            dg = (b * -hvx - a * hvy) / (a * a + b * b)
            q[3 + leg] = g - th
            dq[3 + leg] = dg - dth
            l[leg] = math.hypot(a, b)
        elif mode == SLIDE:
            # toe height hy - l cos g = 0
            l[leg] = hy / math.cos(th + q[3 + leg])
        elif P[P_MASSLESS] > 0.5:
            td = P[P_TD_B + leg]
            if P[P_TD_WORLD] > 0.5:  # g = td fixed in the world
                q[3 + leg] = td - th
                dq[3 + leg] = -dth
            else:  # phi = td fixed on the torso
                q[3 + leg] = td
                dq[3 + leg] = 0.0
            l[leg] = l0
        elif P[P_C + leg] <= 0.0 or l[leg] > l0:
            l[leg] = l0
        if int(P[P_MODEL]) != MODEL_II:
            q[5 + leg] = q[3 + leg]
            dq[5 + leg] = dq[3 + leg]
        elif mi[MI_MOTOR_B + leg] == STUCK:
            dq[5 + leg] = 0.0


# --- actuator (docs/specification.md section 4) ------------------------------------------


def torque_per_amp(leg, P):
    """Torque at the gear output per ampere, N eta K_T [N m / A]."""
    return P[P_N + leg] * P[P_ETA + leg] * P[P_KT + leg]


def motor_speed(dq, leg, P):
    """w_m [rad/s]: N times the rate relative to the torso of the leg (ideal, Model I) or of
    the driven gear (Model II)."""
    rate = dq[5 + leg] if int(P[P_MODEL]) == MODEL_II else dq[3 + leg]
    return P[P_N + leg] * rate


def motor_current(cmd, om, vb, leg, P):
    """Motor current [A] for a commanded leg torque ``cmd`` [N m per physical leg] at motor
    speed ``om`` and battery voltage ``vb``.

    The amplifier asks for i = tau / (N eta K_T), at most i_max in magnitude. Its output
    voltage V lies between -V_b and V_b, and the motor circuit R_A i + K_w w_m = V then
    reaches only the currents between (-V_b - K_w w_m) / R_A and (V_b - K_w w_m) / R_A
    (the torque-speed line; not in the ideal variant). Bench rig: open leads carry no
    current, shorted leads 0 = R_A i + K_w w_m."""
    model = int(P[P_MODEL])
    if model == MODEL_PASSIVE:
        return 0.0
    circuit = int(P[P_CIRCUIT])
    if circuit == CIRCUIT_OPEN:
        return 0.0
    if circuit == CIRCUIT_SHORT:
        return -P[P_KW + leg] * om / P[P_RA + leg]
    i_max = P[P_IMAX + leg]
    wanted = min(max(cmd / torque_per_amp(leg, P), -i_max), i_max)
    if model == MODEL_IDEAL:
        return wanted
    reach_lo = (-vb - P[P_KW + leg] * om) / P[P_RA + leg]
    reach_hi = (vb - P[P_KW + leg] * om) / P[P_RA + leg]
    return min(max(wanted, reach_lo), reach_hi)


def delivered_torque(cur, om, leg, P):
    """Torque at the leg / driven gear [N m per physical leg] for current ``cur`` at motor
    speed ``om`` (docs/model.md, "Transmission losses").

    Constant efficiency tau_0 = N eta K_T i, less a loss tau_idle + c_load |tau_out| that
    opposes the power flow: when the motor drives the output (tau_0 along the motion) the
    loss comes off the transmitted torque (never reversing it); when the output drives the
    motor, the output must supply tau_0 and the loss, and its torque opposes the motion.
    The direction of motion is blended linearly over |w_m| < LOSS_BLEND_BAND."""
    tau0 = torque_per_amp(leg, P) * cur
    idle = P[P_TAU_IDLE + leg]
    c_load = P[P_C_LOAD + leg]

    def moving(direction):
        # the output turning in `direction` (+1 / -1) relative to the torso
        if tau0 * direction > 0.0:
            # motoring: |tau_out| = |tau_0| - idle - c_load |tau_out|, at least 0
            return math.copysign(max(abs(tau0) - idle, 0.0) / (1.0 + c_load), tau0)
        # back-driven: |tau_out| = |tau_0| + idle + c_load |tau_out|, against the motion
        return -direction * (abs(tau0) + idle) / (1.0 - c_load)

    s = om / LOSS_BLEND_BAND
    if s >= 1.0:
        return moving(1.0)
    if s <= -1.0:
        return moving(-1.0)
    forward = 0.5 * (1.0 + s)  # share of the forward direction in the blend
    return forward * moving(1.0) + (1.0 - forward) * moving(-1.0)


def battery_voltage(dq, cmd, P):
    """Battery terminal voltage V_b [V]: V_oc for an ideal source (and in the ideal and
    passive variants, which have no battery model); with internal resistance R_b,
    V_b = V_oc - R_b I_b with the battery current I_b = P / V_b of lossless amplifiers,
    P = sum over all motors of V_term i, V_term = R_A i + K_w w_m, where the currents
    themselves depend on V_b through the torque-speed line. Solved by bracketed root
    finding on the branch near V_oc."""
    voc = P[P_VB]
    rb = P[P_RB]
    model = int(P[P_MODEL])
    if rb <= 0.0 or model == MODEL_IDEAL or model == MODEL_PASSIVE:
        return voc

    def power(v):
        total = 0.0
        for leg in range(2):
            om = motor_speed(dq, leg, P)
            i = motor_current(cmd[leg], om, v, leg, P)
            total += P[P_NP] * (P[P_RA + leg] * i + P[P_KW + leg] * om) * i
        return total

    def residual(v):
        return v - voc + rb * power(v) / v

    return brentq(
        residual, 0.5 * voc, 2.0 * voc, xtol=1e-13, rtol=4 * np.finfo(float).eps, maxiter=500
    )


# --- telescopic leg (docs/specification.md section 2, docs/model.md) ----------------------


def leg_damper(phi, leg, P):
    """Leg damper [N s/m per physical leg] at leg angle phi: c (1 + a phi^2)."""
    return P[P_C + leg] * (1.0 + P[P_LEG_C_ANGLE + leg] * phi**2)


def leg_friction_level(tau_hip, ll, leg, P):
    """Sliding-joint Coulomb level [N per physical leg]: F_c + mu_s |tau_hip| / l."""
    return P[P_LEG_FRIC + leg] + P[P_LEG_FRIC_SIDE + leg] * abs(tau_hip) / ll


def leg_force(k, c, l0, ll, ld, fc):
    """Axial leg force [N per physical leg], compression positive: spring, damper, and the
    friction level fc opposing the length rate ld (linear within LEG_FRICTION_BAND)."""
    friction = fc * min(max(ld / LEG_FRICTION_BAND, -1.0), 1.0)
    return k * (l0 - ll) - c * ld - friction


def flight_rate(k, c, l0, ll, fc):
    """dl/dt [m/s] of a massive leg's massless toe in flight: the leg force vanishes
    (the force falls strictly with the rate, so the root is unique); 0 at the stop and for
    an undamped leg (it snaps to l0)."""
    if c <= 0.0 or ll >= l0:
        return 0.0
    upper = k * (l0 - ll) / c  # the rate without friction: the force is <= 0 there
    if upper == 0.0:
        return 0.0
    return brentq(
        lambda v: leg_force(k, c, l0, ll, v, fc),
        0.0,
        upper,
        xtol=1e-300,
        rtol=4 * np.finfo(float).eps,
        maxiter=500,
    )


# --- hip unit (docs/specification.md section 5) ------------------------------------------


def belt_spring_deflection(delta, leg, P):
    """What the belt spring is stretched by at gear-leg angle difference delta [rad]: the
    hip unit's total play b is a dead zone |delta| <= b / 2 around zero."""
    half_play = 0.5 * P[P_BACKLASH + leg]
    return math.copysign(max(abs(delta) - half_play, 0.0), delta)


# --- rigid bodies (docs/specification.md sections 1, 2, 5; docs/model.md) ---------------


def _leg_com(q, P, leg):
    """Leg-body COM position, its Jacobian (2 x NQ) and the angle g = theta + phi."""
    sL = HIP_SIGN[leg] * P[P_L] - P[P_COM_OFFSET]
    th = q[2]
    g = th + q[3 + leg]
    d = P[P_D + leg]
    pos = np.array(
        [q[0] + sL * math.cos(th) + d * math.sin(g), q[1] + sL * math.sin(th) - d * math.cos(g)]
    )
    J = np.zeros((2, NQ))
    J[0, 0] = 1.0
    J[1, 1] = 1.0
    J[0, 2] = -sL * math.sin(th) + d * math.cos(g)
    J[1, 2] = sL * math.cos(th) + d * math.sin(g)
    J[0, 3 + leg] = d * math.cos(g)
    J[1, 3 + leg] = d * math.sin(g)
    return pos, J, g


def mass_matrix(q, P):
    """M = sum over bodies of m J^T J + I J_w^T J_w: torso, the leg bodies (n_p m_l, n_p I_l
    per virtual leg, turning at theta + phi), in Model II the driven gears (n_p J_2 at
    theta + alpha) and the drive gears (n_p J_1 at theta + N alpha)."""
    npl = P[P_NP]
    M = np.zeros((NQ, NQ))
    Jt = np.zeros((2, NQ))
    Jt[0, 0] = 1.0
    Jt[1, 1] = 1.0
    M += P[P_MT] * Jt.T @ Jt
    M[2, 2] += P[P_IT]
    for leg in range(2):
        _, J, _ = _leg_com(q, P, leg)
        M += npl * P[P_ML + leg] * J.T @ J
        w = np.zeros(NQ)
        w[2] = 1.0
        w[3 + leg] = 1.0
        M += npl * P[P_IL + leg] * np.outer(w, w)
        if int(P[P_MODEL]) == MODEL_II:
            driven = np.zeros(NQ)
            driven[2] = 1.0
            driven[5 + leg] = 1.0
            drive = np.zeros(NQ)
            drive[2] = 1.0
            drive[5 + leg] = P[P_N + leg]
            M += npl * P[P_J2 + leg] * np.outer(driven, driven)
            M += npl * P[P_J1 + leg] * np.outer(drive, drive)
    return M


def velocity_terms(q, dq, P):
    """h of M ddq + h = Q: sum over the leg bodies of m J^T a_0, a_0 the COM acceleration
    at ddq = 0 (the torso and the gears turn about fixed points of their own coordinates,
    so they add none)."""
    h = np.zeros(NQ)
    th = q[2]
    dth = dq[2]
    for leg in range(2):
        sL = HIP_SIGN[leg] * P[P_L] - P[P_COM_OFFSET]
        _, J, g = _leg_com(q, P, leg)
        dg = dth + dq[3 + leg]
        # hip: sL (cos th, sin th) turning at dth; COM: d (sin g, -cos g) turning at dg
        a0 = sL * dth**2 * np.array([-math.cos(th), -math.sin(th)]) + P[
            P_D + leg
        ] * dg**2 * np.array([-math.sin(g), math.cos(g)])
        h += P[P_NP] * P[P_ML + leg] * J.T @ a0
    return h


def potential_energy(q, l, P):
    """Gravity of the torso and leg bodies, the leg springs (1/2 n_p k (l0 - l)^2 per
    virtual leg) and the Model II belt springs beyond the play [J]."""
    npl = P[P_NP]
    grav = P[P_G]
    e = P[P_MT] * grav * q[1]
    for leg in range(2):
        pos, _, _ = _leg_com(q, P, leg)
        e += npl * P[P_ML + leg] * grav * pos[1]
        e += 0.5 * npl * P[P_K + leg] * (P[P_L0 + leg] - l[leg]) ** 2
        if int(P[P_MODEL]) == MODEL_II:
            e += (
                0.5
                * npl
                * P[P_KB + leg]
                * belt_spring_deflection(q[5 + leg] - q[3 + leg], leg, P) ** 2
            )
    return e


def evaluate_reference(s, P, mi, mf, cmd, ds, aux):
    """Reference implementation of :func:`evaluate` (allocating, dense KKT solve); kept
    for cross-checks of the optimized ``evaluate_ws``.

    Same arguments, outputs and return value as :func:`scoutsim._core.model.evaluate.evaluate`
    (state ``s`` [SI], parameters ``P``, modes ``mi``/``mf``, command ``cmd`` [N m]; fills
    ``ds`` and ``aux``; False if the constrained dynamics are singular).
    """
    model = int(P[P_MODEL])
    nact = 7 if model == MODEL_II else 5
    q = s[0:NQ].copy()
    dq = s[NQ : 2 * NQ].copy()
    l = s[IL_B : IL_B + 2].copy()
    project(q, dq, l, P, mi, mf)

    M = mass_matrix(q, P)
    h = velocity_terms(q, dq, P)

    npl = P[P_NP]
    grav = P[P_G]
    th = q[2]
    dth = dq[2]
    massless = P[P_MASSLESS] > 0.5

    Q = np.zeros(NQ)
    # gravity
    Q[1] -= P[P_MT] * grav
    for leg in range(2):
        mlg = npl * P[P_ML + leg] * grav
        d = P[P_D + leg]
        g = th + q[3 + leg]
        sL = HIP_SIGN[leg] * P[P_L] - P[P_COM_OFFSET]
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
        om[leg] = motor_speed(dq, leg, P)
        cur[leg] = motor_current(cmd[leg], om[leg], vb, leg, P)
        tau_app[leg] = delivered_torque(cur[leg], om[leg], leg, P)
        if model == MODEL_II:
            Q[5 + leg] += npl * tau_app[leg]
            mm = mi[MI_MOTOR_B + leg]
            tf = P[P_B_J + leg] * om[leg]
            if mm != STUCK:
                tf += P[P_TAU_S + leg] * mm
            tau_fric[leg] = tf
            Q[5 + leg] -= npl * P[P_N + leg] * tf
            tb = P[P_KB + leg] * belt_spring_deflection(q[5 + leg] - q[3 + leg], leg, P) + P[
                P_CB + leg
            ] * (dq[5 + leg] - dq[3 + leg])
            tau_belt[leg] = tb
            Q[3 + leg] += npl * tb
            Q[5 + leg] -= npl * tb
        elif model != MODEL_PASSIVE:
            Q[3 + leg] += npl * tau_app[leg]

    # contact forces and constraint rows
    R = np.zeros((MAX_ROWS, NQ))
    r = np.zeros(MAX_ROWS)
    row_kind = np.zeros(MAX_ROWS, dtype=np.int64)  # layout.ROW_*
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
        sL = HIP_SIGN[leg] * P[P_L] - P[P_COM_OFFSET]
        l0 = P[P_L0 + leg]
        k = P[P_K + leg]
        g = th + q[3 + leg]
        dg = dth + dq[3 + leg]
        sg = math.sin(g)
        cg = math.cos(g)
        # hip at (x, y) + sL (cos th, sin th) on the torso axis, and its velocity
        hx = q[0] + sL * math.cos(th)
        hy = q[1] + sL * math.sin(th)
        hvx = dq[0] - sL * math.sin(th) * dth
        hvy = dq[1] + sL * math.cos(th) * dth
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
        c_l = leg_damper(q[kk], leg, P)
        tau_hip = (
            tau_belt[leg]
            if model == MODEL_II
            else (tau_app[leg] if model != MODEL_PASSIVE else 0.0)
        )
        fc_l = leg_friction_level(tau_hip, ll, leg, P)
        if mode == STICK or mode == STRUT:
            ld = -(hvx * sg - hvy * cg)  # dl/dt = -dhip . u
            ldot[leg] = ld
            F = npl * leg_force(k, c_l, l0, ll, ld, fc_l)
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
            row_kind[nr] = ROW_TOE_ACROSS
            row_leg[nr] = leg
            nr += 1
            if mode == STRUT:
                w = P[P_STRUT_OMEGA]
                R[nr, 0] = sg
                R[nr, 1] = -cg
                R[nr, 2] = -sL * math.cos(q[3 + leg])
                r[nr] = -(bx * sg - by * cg) + ll * dg * dg + 2.0 * w * ld + w * w * (ll - l0)
                row_kind[nr] = ROW_TOE_ALONG
                row_leg[nr] = leg
                nr += 1
            toe_x[leg] = mf[MF_ANCHOR_B + leg]
            toe_y[leg] = 0.0
            toe_vx[leg] = 0.0
        elif mode == SLIDE:
            # toe on the ground (height 0), l = hy / cos(g)
            ld = hvy / cg + hy * sg * dg / (cg * cg)
            ldot[leg] = ld
            F = npl * leg_force(k, c_l, l0, ll, ld, fc_l)
            Fax[leg] = F
            sig = 0.0
            if P[P_NO_SLIP] < 0.5:  # a Coulomb floor: the toe slides against mu F_n
                sig = P[P_MU] * mi[MI_SLIDE_DIR_B + leg]
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
                row_kind[nr] = ROW_MASSLESS
                row_leg[nr] = leg
                nr += 1
                ld = 0.0
            else:
                ld = flight_rate(k, c_l, l0, ll, fc_l)
            ldot[leg] = ld
            toe_x[leg] = hx + ll * sg
            toe_y[leg] = hy - ll * cg
            toe_vx[leg] = hvx + ld * sg + ll * cg * dg
        if model == MODEL_II and mi[MI_MOTOR_B + leg] == STUCK:
            R[nr, 5 + leg] = 1.0
            r[nr] = 0.0
            row_kind[nr] = ROW_GEAR
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
        if row_kind[rr] == ROW_TOE_ACROSS:  # perpendicular ground force lam * n
            Gt[leg] += lam * math.cos(g)
            Gn[leg] += lam * math.sin(g)
        elif row_kind[rr] == ROW_TOE_ALONG:  # strut force lam * u (tension positive)
            strut[leg] = lam
            Gt[leg] += lam * math.sin(g)
            Gn[leg] -= lam * math.cos(g)
        elif row_kind[rr] == ROW_GEAR:  # holding torque at one motor
            hold[leg] = lam / (npl * P[P_N + leg])
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
