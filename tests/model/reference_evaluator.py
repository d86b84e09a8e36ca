"""The reference evaluator: a second, allocating implementation of the model's right-hand
side (dense KKT solve, its own assembly of the forces and rows), the test oracle of the
optimized :func:`scoutsim.model.evaluate.evaluate_ws` (tests/model/test_evaluate.py).
Not part of the package: it exists only to be compared against."""

from __future__ import annotations

import math

import numpy as np

from scoutsim.jit import allocating
from scoutsim.model.actuator import battery_voltage, delivered_torque, motor_current
from scoutsim.model.kinematics import hip_position, hip_velocity, project
from scoutsim.model.kkt import MAX_ROWS, add_clamp_rows, solve_dense
from scoutsim.model.layout import (
    A_BELT, A_CURRENT, A_ENERGY, A_FAX, A_GN, A_GT, A_HOLD, A_KKT_OK, A_OMEGA_M, A_SLIP_V,
    A_STRUT, A_TAU_APP, A_TAU_BELT, A_TAU_CMD, A_TOE_X, A_TOE_Y, A_VBATT, IL_B, MF_ANCHOR_B,
    MI_CONTACT_B, MI_MOTOR_B, MI_SLIDE_DIR_B, MODEL_II, MODEL_PASSIVE, NAUX_LEG, NQ, P_B_J,
    P_CB, P_D, P_G, P_K, P_KB, P_L, P_L0, P_MASSLESS, P_ML, P_MODEL, P_MT, P_MU, P_N, P_NP,
    P_STRUT_OMEGA, P_TAU_S, P_TD_WORLD, ROW_GEAR, ROW_MASSLESS, ROW_TOE_ACROSS,
    ROW_TOE_ALONG, SLIDE, STICK, STRUT, STUCK,
)
from scoutsim.model.leg import flight_leg_rate, leg_axial_force, leg_damping, leg_friction_level
from scoutsim.model.rigid_body import coriolis, mass_matrix, potential_energy
from scoutsim.model.transmission import belt_spring_deflection


@allocating
def evaluate_reference(s, P, mi, mf, cmd, ds, aux):
    """Reference implementation of :func:`evaluate` (allocating, dense KKT solve); kept
    for cross-checks of the optimized ``evaluate_ws``.

    Same arguments, outputs and return value as :func:`scoutsim.model.evaluate.evaluate`
    (state ``s`` [SI], parameters ``P``, modes ``mi``/``mf``, command ``cmd`` [N m]; fills
    ``ds`` and ``aux``; False if the constrained dynamics are singular).
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
    row_kind = np.zeros(MAX_ROWS, dtype=np.int64)   # layout.ROW_*
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
                row_kind[nr] = ROW_MASSLESS
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
        if row_kind[rr] == ROW_TOE_ACROSS:      # perpendicular ground force lam * n
            Gt[leg] += lam * math.cos(g)
            Gn[leg] += lam * math.sin(g)
        elif row_kind[rr] == ROW_TOE_ALONG:    # strut force lam * u (tension positive)
            strut[leg] = lam
            Gt[leg] += lam * math.sin(g)
            Gn[leg] -= lam * math.cos(g)
        elif row_kind[rr] == ROW_GEAR:    # holding torque at one motor
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
