"""The right-hand side of the hybrid model in its current modes (compiled): assembles the
rigid-body terms, actuators, transmission and contact into one KKT system and solves it.

Summary (docs/model.md derives every term; docs/specification.md sections 1-5):

* Generalized coordinates q = [x, y, theta, phi_b, phi_f, alpha_b, alpha_f] (paper eq. 1 with
  the leg lengths l_b, l_f carried separately because the toe is massless, and the Model II
  driven-gear angles alpha). Only the *active* coordinates enter the dynamics: 7 in
  Model II, the first 5 otherwise (alpha is then a copy of phi).
* Mass matrix, velocity terms, gravity and energies: model/rigid_body.py; actuator laws
  (paper eqs. 2-5 act through the commanded torque; current limits, torque-speed line,
  battery, losses): model/actuator.py; the ideal / Model I / Model II transmissions:
  model/transmission.py; the contact modes' forces and rows: model/contact.py.
* Contact and stiction are holonomic constraints on q, solved together with the dynamics in
  one KKT system ``[M R^T; R 0] [ddq; -lambda] = [Q - h; r]`` (model/kkt.py). Coordinates
  fixed by a constraint that can be solved explicitly (stance leg angle from the toe anchor,
  massless flight legs, stuck motor joint) are *projected* before every evaluation
  (model/kinematics.py), so the constraints hold exactly and do not drift; the multipliers
  lambda are the ground and holding forces.

Speed: the small helpers of :func:`evaluate_ws` (projection, the per-concept terms, motor
and battery laws, the reduced KKT solve) are inlined at the Numba IR level
(``inline="always"``): 17 % off an ARK3 step, bit-identical results, for more first-call
compilation (the cache keeps it). So are the Schur-complement factorization and the clamp
rows, which run at every evaluation: a call passes every array as 7-9 machine words, more
than such a part's own work. (The output fills run once per accepted step: inlining them
makes runs no faster, docs/model.md "Compile time".)
"""

from __future__ import annotations

import numpy as np

from ..._numba.jit import allocating, kernel
from .actuator import (
    back_emf_damping,
    battery_voltage,
    delivered_torque,
    motor_current,
    on_speed_line,
)
from .contact import leg_contact
from .flags import FLAG_OFF, FLAG_ON, is_set
from .hip_unit import belt_spring, geared
from .kinematics import hip_offset, project
from .kkt import (
    MAX_KKT,
    MAX_ROWS,
    SCHUR_MAX_ROWS,
    add_clamp_rows,
    kkt_reduced_factor,
    kkt_reduced_solve,
    kkt_schur_factor,
)
from .layout import (
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
    FLIGHT,
    IALB,
    IALF,
    IL_B,
    IPHB,
    IPHF,
    ITH,
    IX,
    IY,
    MI_CONTACT_B,
    MI_MOTOR_B,
    MODEL_PASSIVE,
    NAUX_LEG,
    NQ,
    NS,
    P_B_J,
    P_CB,
    P_KB,
    P_MASSLESS,
    P_MODEL,
    P_N,
    P_NP,
    P_TD_WORLD,
    ROW_GEAR,
    ROW_TOE_ACROSS,
    ROW_TOE_ALONG,
    STICK,
    STRUT,
    STUCK,
)
from .rigid_body import (
    add_gravity_at,
    coriolis_at,
    kinetic_energy_at,
    mass_matrix_at,
    potential_energy_at,
)
from .transmission import hip_unit_forces, motor_joint_row, motor_speed
from .workspace import (
    LG_CUR,
    LG_FAX,
    LG_GN,
    LG_GT,
    LG_HOLD,
    LG_LDOT,
    LG_OM,
    LG_STRUT,
    LG_TAPP,
    LG_TBELT,
    LG_TFRIC,
    LG_TOEVX,
    LG_TOEX,
    LG_TOEY,
    MT_CG_B,
    MT_CG_F,
    MT_CTH,
    MT_ENERGY,
    MT_KKT_OK,
    MT_NROWS,
    MT_SCHUR,
    MT_SG_B,
    MT_SG_F,
    MT_STH,
    MT_VBATT,
    NLG,
    NMETA,
    NWK_LEG,
    WA_M,
    WA_R,
    WA_ROWS,
    WK_B,
    WK_B2,
    WK_DQ,
    WK_H,
    WK_L,
    WK_LEG,
    WK_META,
    WK_Q,
    WK_Q_,
    WK_R,
    WK_RKIND,
    WK_RLEG,
    WK_SIZE,
    WK_Y,
)

NSTIFF = 4  # rank of the stiff-Jacobian factorization of evaluate_ws
#: Motor-side damping rate [1/s] from which evaluate_ws puts it into the stiff factors (the
#: two motor columns). Below it the explicit part of the ARK methods is stable and accurate
#: at steps up to the 1 ms control period (|h lambda| <= 1, inside the explicit stability
#: interval of ARK3 / ARK4); above it (user robots with a light gear train or strong
#: back-EMF) the damping is treated implicitly.
STIFF_MOTOR_RATE = 1000.0


@kernel(inline="always")
def fill_derivative(ds, dq, b, LG, nact, gear, ok):
    """ds = [dq, ddq, dl]: the accelerations are the first ``nact`` entries of the KKT
    solution b (zero if the factorization failed, ``ok`` False), the leg-length rates come
    from the per-leg scalars LG; without a geared hip unit (``gear`` False) the gear angles
    follow the legs (alpha = phi)."""
    for i in range(NQ):
        ds[i] = dq[i]
        ds[NQ + i] = 0.0
    if ok:
        for i in range(nact):
            ds[NQ + i] = b[i]
    if not gear:
        ds[NQ + IALB] = ds[NQ + IPHB]
        ds[NQ + IALF] = ds[NQ + IPHF]
    ds[IL_B] = LG[2 * LG_LDOT]
    ds[IL_B + 1] = LG[2 * LG_LDOT + 1]


@kernel
def fill_outputs(P, mi, cmd, aux, wk):
    """The outputs aux of :func:`evaluate_ws` from the evaluation held in the workspace
    ``wk`` (its per-leg scalars, the KKT solution with the multipliers after the ``nact``
    accelerations, the rows' kinds and legs, and the summary ``MT_*``); the ground force
    of a pinned toe is summed afresh, so a second call after a new solve
    (:func:`evaluate_command_change`) is exact."""
    q = wk[WK_Q : WK_Q + NQ]
    LG = wk[WK_LEG : WK_LEG + NWK_LEG]
    b = wk[WK_B : WK_B + MAX_KKT]
    rkind = wk[WK_RKIND : WK_RKIND + MAX_ROWS]
    rleg = wk[WK_RLEG : WK_RLEG + MAX_ROWS]
    meta = wk[WK_META : WK_META + NMETA]
    gear = geared(P)
    nact = 7 if gear else 5
    nr = int(meta[MT_NROWS])
    ok = is_set(meta[MT_KKT_OK])
    sgl0, cgl0, sgl1, cgl1 = meta[MT_SG_B], meta[MT_CG_B], meta[MT_SG_F], meta[MT_CG_F]
    vb = meta[MT_VBATT]
    energy = meta[MT_ENERGY]
    npl = P[P_NP]
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
        if kind == ROW_TOE_ACROSS:
            LG[2 * LG_GT + leg] += lam * cg
            LG[2 * LG_GN + leg] += lam * sg
        elif kind == ROW_TOE_ALONG:
            LG[2 * LG_STRUT + leg] = lam
            LG[2 * LG_GT + leg] += lam * sg
            LG[2 * LG_GN + leg] -= lam * cg
        elif kind == ROW_GEAR:
            LG[2 * LG_HOLD + leg] = lam / (npl * P[P_N + leg])
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
        aux[o + A_BELT] = q[IALB + leg] - q[IPHB + leg]
        if gear and mi[MI_MOTOR_B + leg] == STUCK:
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
    aux[A_KKT_OK] = FLAG_ON if ok else FLAG_OFF


@kernel
def evaluate_command_change(P, mi, cmd, ds, aux, wk, wA, piv):
    """Update ds = f(s) and the outputs aux for new commanded torques ``cmd`` at the state
    and modes of the last :func:`evaluate_ws` call on this workspace (made with
    ``want_aux``); ds and aux are filled completely (they need not hold that evaluation).

    The commands enter the dynamics only through the delivered hip torques (docs/specification.md
    section 4: current limits, torque-speed line, battery), i.e. the right-hand side of the KKT system,
    whose factorization is kept: the change of torque is solved with those factors and added
    to the accelerations and multipliers. Equal to a fresh evaluation up to round-off, for
    the cost of one solve. Returns the KKT flag."""
    model = int(P[P_MODEL])
    gear = geared(P)
    nact = 7 if gear else 5
    meta = wk[WK_META : WK_META + NMETA]
    ok = is_set(meta[MT_KKT_OK])
    if not ok:
        aux[A_KKT_OK] = FLAG_OFF
        return False
    schur = is_set(meta[MT_SCHUR])
    nr = int(meta[MT_NROWS])
    n = nact + nr
    dq = wk[WK_DQ : WK_DQ + NQ]
    LG = wk[WK_LEG : WK_LEG + NWK_LEG]
    b = wk[WK_B : WK_B + MAX_KKT]
    b2 = wk[WK_B2 : WK_B2 + MAX_KKT]
    rkind = wk[WK_RKIND : WK_RKIND + MAX_ROWS]
    rleg = wk[WK_RLEG : WK_RLEG + MAX_ROWS]
    A = wA[0:MAX_KKT]
    M = wA[WA_M : WA_M + NQ]
    npl = P[P_NP]
    vb = battery_voltage(dq, cmd, P)
    for i in range(n):
        b2[i] = 0.0
    row = 5 if gear else 3
    for leg in range(2):
        om = LG[2 * LG_OM + leg]
        cur = motor_current(cmd[leg], om, vb, leg, P)
        tapp = delivered_torque(cur, om, leg, P)
        if model != MODEL_PASSIVE:
            b2[row + leg] = npl * (tapp - LG[2 * LG_TAPP + leg])
        LG[2 * LG_CUR + leg] = cur
        LG[2 * LG_TAPP + leg] = tapp
    free0 = gear and mi[MI_MOTOR_B] != STUCK
    free1 = gear and mi[MI_MOTOR_B + 1] != STUCK
    kkt_reduced_solve(A, piv, M, rkind, rleg, (nact, nr, free0, free1, schur), wk, WK_B2, wk, WK_Y)
    for i in range(n):
        b[i] += b2[i]
    fill_derivative(ds, dq, b, LG, nact, gear, ok)
    meta[MT_VBATT] = vb
    fill_outputs(P, mi, cmd, aux, wk)
    return ok


@kernel
def fill_stiff_factors(stiff, P, mi, cmd, wk, wA, piv):
    """The rank-NSTIFF factorization of the stiff part of the Jacobian (see
    :func:`evaluate_ws`), from the evaluation just made, held in the workspace ``wk, wA,
    piv`` (the projected state, per-leg scalars, KKT factors and summary ``MT_*``)."""
    q = wk[WK_Q : WK_Q + NQ]
    dq = wk[WK_DQ : WK_DQ + NQ]
    l = wk[WK_L : WK_L + 2]
    LG = wk[WK_LEG : WK_LEG + NWK_LEG]
    rkind = wk[WK_RKIND : WK_RKIND + MAX_ROWS]
    rleg = wk[WK_RLEG : WK_RLEG + MAX_ROWS]
    meta = wk[WK_META : WK_META + NMETA]
    A = wA[0:MAX_KKT]
    M = wA[WA_M : WA_M + NQ]
    gear = geared(P)
    nact = 7 if gear else 5
    nr = int(meta[MT_NROWS])
    ok = is_set(meta[MT_KKT_OK])
    schur = is_set(meta[MT_SCHUR])
    vb = meta[MT_VBATT]
    sth, cth = meta[MT_STH], meta[MT_CTH]
    sgl0, cgl0, sgl1, cgl1 = meta[MT_SG_B], meta[MT_CG_B], meta[MT_SG_F], meta[MT_CG_F]
    free0 = gear and mi[MI_MOTOR_B] != STUCK
    free1 = gear and mi[MI_MOTOR_B + 1] != STUCK
    for i in range(NS):
        for j in range(2 * NSTIFF):
            stiff[i, j] = 0.0
    if not gear or not ok:
        return
    n = nact + nr
    npl = P[P_NP]
    massless = is_set(P[P_MASSLESS])
    dth = dq[ITH]
    b2 = wk[WK_B2 : WK_B2 + MAX_KKT]
    for leg in range(2):
        cb = P[P_CB + leg]
        # the spring's stiffness where it is engaged (0 inside a backlash's play)
        kb = P[P_KB + leg] if belt_spring(q[IALB + leg] - q[IPHB + leg], leg, P)[1] else 0.0
        for i in range(n):
            b2[i] = 0.0
        b2[IALB + leg] = 1.0
        b2[IPHB + leg] = -1.0
        kkt_reduced_solve(
            A, piv, M, rkind, rleg, (nact, nr, free0, free1, schur), wk, WK_B2, wk, WK_Y
        )
        # U: response of ddq to a unit belt torque pair, -npl G w
        for i in range(nact):
            stiff[NQ + i, leg] = -npl * b2[i]
        # V: belt torque c_b (dalpha - dphi) + k_b (alpha - phi) differentiated
        # with respect to s through the projection of the dependent coordinates
        vcol = NSTIFF + leg
        stiff[IALB + leg, vcol] = kb
        if mi[MI_MOTOR_B + leg] != STUCK:
            stiff[NQ + IALB + leg, vcol] = cb
        mode = mi[MI_CONTACT_B + leg]
        if mode == STICK or mode == STRUT:
            sg = sgl0 if leg == 0 else sgl1
            cg = cgl0 if leg == 0 else cgl1
            sL = hip_offset(P, leg)
            ll = l[leg]
            sph = sg * cth - cg * sth
            # phi = atan2(anchor - hip_x, hip_y) - theta; dphi from R dq = 0
            d0 = cg / ll
            d1 = sg / ll
            d2 = (sL * sph + ll) / ll
            # the damper also depends on q through the projected dphi:
            # dphi = dg - dtheta, dg = -(hvx b + hvy a) / ll^2 with
            # a = anchor - hip_x = ll sin g, b = hip_y = ll cos g
            hvx = dq[IX] - sL * sth * dth
            hvy = dq[IY] + sL * cth * dth
            aa = ll * sg
            bb = ll * cg
            D2 = ll * ll
            dgv = -(hvx * bb + hvy * aa) / D2
            dga = -hvy / D2 - 2.0 * aa * dgv / D2
            dgb = -hvx / D2 - 2.0 * bb * dgv / D2
            e0 = -dga
            e1 = dgb
            e2 = dga * sL * sth + dgb * sL * cth + (bb * sL * cth + aa * sL * sth) * dth / D2
            stiff[IX, vcol] = kb * d0 - cb * e0
            stiff[IY, vcol] = kb * d1 - cb * e1
            stiff[ITH, vcol] = kb * d2 - cb * e2
            stiff[NQ + IX, vcol] = cb * d0
            stiff[NQ + IY, vcol] = cb * d1
            stiff[NQ + ITH, vcol] = cb * d2
        elif mode == FLIGHT and massless:
            if is_set(P[P_TD_WORLD]):
                stiff[ITH, vcol] = kb
                stiff[NQ + ITH, vcol] = cb
        else:
            stiff[IPHB + leg, vcol] = -kb
            stiff[NQ + IPHB + leg, vcol] = -cb

    # motor-side damping on alpha: joint viscous friction and, while the current is
    # limited by the torque-speed line, the back-EMF; only where it is stiff, i.e.
    # its rate on the gear train's own inertia, n d_m / M_aa, is at least
    # STIFF_MOTOR_RATE (Scout II: ~400 /s on the torque-speed line, so these columns
    # stay zero and the ARK step runs at rank 2)
    for leg in range(2):
        if mi[MI_MOTOR_B + leg] == STUCK:
            continue
        dm = P[P_B_J + leg]
        if on_speed_line(cmd[leg], LG[2 * LG_OM + leg], vb, leg, P):
            dm += back_emf_damping(leg, P)
        N = P[P_N + leg]
        dm *= N * N
        if npl * dm < STIFF_MOTOR_RATE * M[IALB + leg, IALB + leg]:
            continue  # not stiff: left to the explicit part (column stays zero)
        for i in range(n):
            b2[i] = 0.0
        b2[IALB + leg] = 1.0
        kkt_reduced_solve(
            A, piv, M, rkind, rleg, (nact, nr, free0, free1, schur), wk, WK_B2, wk, WK_Y
        )
        for i in range(nact):
            stiff[NQ + i, 2 + leg] = -npl * b2[i]
        stiff[NQ + IALB + leg, NSTIFF + 2 + leg] = dm


@kernel
def evaluate_ws(s, P, mi, mf, cmd, ds, aux, ew, want_stiff, stiff, want_aux):
    """:func:`evaluate` without allocations, on the evaluation workspace ``ew`` = (wk, wA,
    piv, stiff scratch): the scratch arrays of
    :func:`~scoutsim._core.model.workspace.new_eval_workspace` and a (NS, 2 NSTIFF) array
    (:func:`~scoutsim._core.numerics.dopri5.eval_workspace` makes all four).

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
    wk, wA, piv = ew[0], ew[1], ew[2]
    model = int(P[P_MODEL])
    gear = geared(P)
    nact = 7 if gear else 5
    q = wk[WK_Q : WK_Q + NQ]
    dq = wk[WK_DQ : WK_DQ + NQ]
    l = wk[WK_L : WK_L + 2]
    for i in range(NQ):
        q[i] = s[i]
        dq[i] = s[NQ + i]
    l[0] = s[IL_B]
    l[1] = s[IL_B + 1]
    sth, cth, sgl0, cgl0, sgl1, cgl1 = project(q, dq, l, P, mi, mf)
    meta = wk[WK_META : WK_META + NMETA]
    meta[MT_STH] = sth
    meta[MT_CTH] = cth

    Q = wk[WK_Q_ : WK_Q_ + NQ]
    h = wk[WK_H : WK_H + NQ]
    r = wk[WK_R : WK_R + MAX_ROWS]
    LG = wk[WK_LEG : WK_LEG + NWK_LEG]
    for i in range(NQ):
        Q[i] = 0.0
    for i in range(2 * NLG):
        LG[i] = 0.0
    A = wA[0:MAX_KKT]
    R = wA[WA_R : WA_R + MAX_ROWS]
    M = wA[WA_M : WA_M + NQ]
    massless = is_set(P[P_MASSLESS])

    # rigid bodies: mass matrix, velocity terms, gravity, potential energy
    mass_matrix_at(M, P, sth, cth, sgl0, cgl0, sgl1, cgl1)
    coriolis_at(h, dq, P, sth, cth, sgl0, cgl0, sgl1, cgl1)
    add_gravity_at(Q, P, sth, cth, sgl0, cgl0, sgl1, cgl1)

    # actuators and transmissions
    vb = battery_voltage(dq, cmd, P)
    for leg in range(2):
        om = motor_speed(dq, leg, P)
        cur = motor_current(cmd[leg], om, vb, leg, P)
        tapp = delivered_torque(cur, om, leg, P)
        LG[2 * LG_OM + leg] = om
        LG[2 * LG_CUR + leg] = cur
        LG[2 * LG_TAPP + leg] = tapp
        tf, tb = hip_unit_forces(Q, q, dq, leg, tapp, om, mi[MI_MOTOR_B + leg], P)
        if gear:
            LG[2 * LG_TFRIC + leg] = tf
            LG[2 * LG_TBELT + leg] = tb

    # contact forces and constraint rows, then the stuck motor joints and the rig clamps
    rkind = wk[WK_RKIND : WK_RKIND + MAX_ROWS]
    rleg = wk[WK_RLEG : WK_RLEG + MAX_ROWS]
    nr = 0
    for leg in range(2):
        # the torque the hip applies to the leg (through the belt of a geared unit)
        tau_hip = (
            LG[2 * LG_TBELT + leg]
            if gear
            else (LG[2 * LG_TAPP + leg] if model != MODEL_PASSIVE else 0.0)
        )
        sg = sgl0 if leg == 0 else sgl1
        cg = cgl0 if leg == 0 else cgl1
        nr = leg_contact(leg, P, mi, mf, sg, cg, tau_hip, nr, wk, wA)
        nr = motor_joint_row(R, r, rkind, rleg, nr, leg, mi, P)
    nr = add_clamp_rows(P, R, r, rkind, rleg, nr)

    # the energy (an output) before the factorization
    energy = 0.0
    if want_aux:
        energy = kinetic_energy_at(M, dq) + potential_energy_at(q, l, P, sth, cgl0, cgl1)

    # KKT system [M R^T; R 0] [ddq; nu] = [Q - h; r]; generalized constraint force = -R^T nu
    b = wk[WK_B : WK_B + MAX_KKT]
    for i in range(nact):
        b[i] = Q[i] - h[i]
    for rr in range(nr):
        b[nact + rr] = r[rr]
    free0 = gear and mi[MI_MOTOR_B] != STUCK
    free1 = gear and mi[MI_MOTOR_B + 1] != STUCK
    # structured (Schur-complement) factorization whenever the mass matrix is positive
    # definite (its translation block is m I by construction, above); the LU path keeps
    # the massless-leg model (zero leg inertia)
    schur = not massless and nr <= SCHUR_MAX_ROWS
    if schur:
        ok, nred = kkt_schur_factor(A, M, R, rkind, nact, nr, free0, free1)
    else:
        ok, nred = kkt_reduced_factor(A, piv, M, R, rkind, nact, nr, free0, free1)
    if ok:
        kkt_reduced_solve(
            A, piv, M, rkind, rleg, (nact, nr, free0, free1, schur), wk, WK_B, wk, WK_Y
        )
    meta[MT_SCHUR] = FLAG_ON if schur else FLAG_OFF
    meta[MT_NROWS] = nr
    meta[MT_KKT_OK] = FLAG_ON if ok else FLAG_OFF
    meta[MT_VBATT] = vb
    meta[MT_SG_B] = sgl0
    meta[MT_CG_B] = cgl0
    meta[MT_SG_F] = sgl1
    meta[MT_CG_F] = cgl1

    fill_derivative(ds, dq, b, LG, nact, gear, ok)

    if want_stiff:
        fill_stiff_factors(stiff, P, mi, cmd, wk, wA, piv)

    if not want_aux:
        aux[A_KKT_OK] = FLAG_ON if ok else FLAG_OFF
        return ok
    meta[MT_ENERGY] = energy
    fill_outputs(P, mi, cmd, aux, wk)
    return ok


@kernel(inline="always")
def evaluated_state(ew, s):
    """Copy into ``s`` the projected state of the last :func:`evaluate_ws` call on the
    workspace ``ew`` (the state it was given, its dependent coordinates projected: what
    :func:`~scoutsim._core.model.kinematics.project_state` makes of that state, bit for bit,
    without computing the projection again) and return the pitch's (sin, cos) there."""
    wk = ew[0]
    for i in range(NQ):
        s[i] = wk[WK_Q + i]
        s[NQ + i] = wk[WK_DQ + i]
    s[IL_B] = wk[WK_L]
    s[IL_B + 1] = wk[WK_L + 1]
    return wk[WK_META + MT_STH], wk[WK_META + MT_CTH]


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
    return evaluate_ws(s, P, mi, mf, cmd, ds, aux, (wk, wA, piv, stiff), False, stiff, True)
