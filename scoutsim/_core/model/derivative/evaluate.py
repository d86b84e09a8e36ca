"""Directional derivative of the right-hand side in closed form
(:func:`scoutsim._core.model.evaluate.evaluate_ws`), from the evaluation a workspace holds.

The right-hand side is ds = [dq, ddq, dl] of the projected state, ddq from the KKT system
``M ddq + R^T nu = Q - h``, ``R ddq = r`` (docs/model.md). Along a direction with tangents
(s_t, mf_t, cmd_t, P_t) of the state, the toe anchors, the held commands and the packed
parameters, its tangent is

    M ddq_t + R^T nu_t = Q_t - h_t - M_t ddq - R_t^T nu,   R ddq_t = r_t - R_t ddq,

solved with the factors the evaluation kept: one solve per direction. Q_t, h_t, M_t ddq
and the rows' tangents come from the derivative of each concept (this package's modules),
at the projected state and with the discrete choices the evaluation made (modes, limits,
friction directions).

Every direction the caller carries (a column) is taken in one call: each tangent has a
trailing axis of the m columns (a state's tangents (NS, m), the parameters' (m, len(P)),
row c column c's), the quantities that do not depend on the direction are computed once
and the columns' arithmetic runs in the innermost loops. Each column's numbers are those
of the derivative taken along it alone.
"""

from __future__ import annotations

import numpy as np

from ...._numba.jit import allocating, kernel
from ..flags import is_set
from ..hip_unit import geared
from ..kkt import MAX_KKT, MAX_ROWS, kkt_reduced_solve_columns
from ..layout import (
    IALB,
    IL_B,
    IPHB,
    IPHF,
    MI_MOTOR_B,
    MODEL_PASSIVE,
    NQ,
    P_MODEL,
    P_N,
    STUCK,
)
from ..workspace import (
    LG_CUR,
    LG_OM,
    LG_TAPP,
    LG_TBELT,
    MT_CG_B,
    MT_CG_F,
    MT_CTH,
    MT_KKT_OK,
    MT_NROWS,
    MT_SCHUR,
    MT_SG_B,
    MT_SG_F,
    MT_STH,
    MT_VBATT,
    NMETA,
    NWK_LEG,
    WA_M,
    WK_B,
    WK_B2,
    WK_DQ,
    WK_L,
    WK_LEG,
    WK_META,
    WK_Q,
    WK_RKIND,
    WK_RLEG,
    WK_Y,
)
from .actuator import (
    battery_voltage_t,
    branch_current_t,
    current_branch,
    delivered_torque_t,
    hip_unit_forces_t,
    motor_speed_t,
)
from .contact import leg_contact_t
from .kinematics import NTR, TR_CGB, TR_CGF, TR_CTH, TR_SGB, TR_SGF, TR_STH, project_t
from .rigid_body import add_gravity_t, coriolis_t, mass_matrix_times_t

# rows of the derivative's scratch matrix (:func:`derivative_workspace`: a row per quantity,
# a column per direction; the primal rows use column 0)
DW_Q_T = 0  # tangents of the projected state: q (NQ), dq (NQ), l (2)
DW_DQ_T = DW_Q_T + NQ
DW_L_T = DW_DQ_T + NQ
DW_TR = DW_L_T + 2  # the configuration's sines and cosines (kinematics.TR_*; primal)
DW_TR_T = DW_TR + NTR  # ... their tangents
DW_G = DW_TR_T + NTR  # the tangent of the KKT system's right-hand side, its first NQ rows
DW_H_T = DW_G + NQ  # the velocity terms' tangent
DW_DDQ = DW_H_T + NQ  # the primal accelerations (NQ; zero beyond the active coordinates)
DW_GR = DW_DDQ + NQ  # ... its constraint rows (MAX_ROWS)
DW_VB_T = DW_GR + MAX_ROWS  # the battery voltage's tangent
DW_OM_T = DW_VB_T + 1  # a leg's motor speed's, motor current's, delivered torque's,
DW_CUR_T = DW_OM_T + 1  # joint friction torque's, belt torque's tangents, the torque
DW_TAPP_T = DW_CUR_T + 1  # the hip applies to the leg's, the leg-length rate's (one
DW_TF_T = DW_TAPP_T + 1  # leg at a time)
DW_TB_T = DW_TF_T + 1
DW_TAU_T = DW_TB_T + 1
DW_LD_T = DW_TAU_T + 1
DW_ZERO = DW_LD_T + 1  # zeros (a torque without a tangent)
DW_B = DW_ZERO + 1  # the tangent KKT systems' right-hand sides and solutions (MAX_KKT)
DW_Y = DW_B + MAX_KKT  # ... their solver's scratch (MAX_KKT)
DW_SIZE = DW_Y + MAX_KKT


#: how far ahead along the motion [s] the motor current's branch is read: a current on a
#: kink of the amplifier's law (on the torque-speed line and at the commanded current at
#: once) is differentiated on the side the trajectory enters, the side the flow's
#: derivative sees (the kink is met at an instant, the branch is followed after it). A
#: current within BRANCH_LOOKAHEAD x its motor's acceleration of a kink is taken as on it.
BRANCH_LOOKAHEAD = 1e-9


#: the branch codes of :func:`current_branches` (base: one digit per leg)
BRANCH_BASE = 8


@kernel(inline="always")
def _leg_branch(P, cmd, wk, leg):
    """The branch (``CUR_*``) of leg ``leg``'s motor current at the evaluation summarised in
    ``wk``, BRANCH_LOOKAHEAD ahead along the motion (the motor speed moved by its
    acceleration from the evaluation's solve; none if that failed)."""
    b = wk[WK_B : WK_B + MAX_KKT]
    LG = wk[WK_LEG : WK_LEG + NWK_LEG]
    meta = wk[WK_META : WK_META + NMETA]
    i = IALB + leg if geared(P) else IPHB + leg
    om_dot = P[P_N + leg] * b[i] if is_set(meta[MT_KKT_OK]) else 0.0
    om = LG[2 * LG_OM + leg] + BRANCH_LOOKAHEAD * om_dot
    return current_branch(cmd[leg], om, meta[MT_VBATT], leg, P)


@kernel
def current_branches(P, cmd, ew):
    """The motor currents' branches at the evaluation the workspace ``ew`` holds (the last
    ``evaluate_ws`` call on it, with commands ``cmd``), read ahead along the motion as
    :func:`evaluate_t` reads them: branch_back * BRANCH_BASE + branch_front. Where it
    differs between two states of a trajectory, the current crossed a kink of the
    amplifier's law between them (the torque-speed line met or left)."""
    code = 0
    for leg in range(2):
        code = code * BRANCH_BASE + _leg_branch(P, cmd, ew[0], leg)
    return code


@kernel(inline="always")
def _motor_t(leg, P, cmd, wk, dq, tangents, out):
    """``out`` = (om_t, cur_t) (m,) := the tangents of leg ``leg``'s motor speed [rad/s]
    and motor current [A] along each column, at the evaluation summarised in ``wk``
    (rates ``dq``, commands ``cmd``); ``tangents`` = (dq_t (NQ, m), cmd_t (2, m), vb_t
    (m,), P_t (m, len(P))): those of the projected rates, the commands, the battery voltage
    and the packed parameters. The current is on its branch a moment ahead along the
    motion: where it sits on a kink (a controller that commands the torque-speed line's
    torque at a sample puts it exactly there), the side the trajectory enters."""
    dq_t, cmd_t, vb_t, P_t = tangents
    om_t, cur_t = out
    LG = wk[WK_LEG : WK_LEG + NWK_LEG]
    vb = wk[WK_META + MT_VBATT]
    om = LG[2 * LG_OM + leg]
    branch = _leg_branch(P, cmd, wk, leg)
    for c in range(dq_t.shape[1]):
        Pc = P_t[c]
        o_t = motor_speed_t(dq_t, c, leg, P, dq, Pc)
        om_t[c] = o_t
        cur_t[c] = branch_current_t(
            branch, cmd[leg], om, vb, leg, P, (cmd_t[leg, c], o_t, vb_t[c], Pc)
        )


@allocating
def derivative_workspace(m):
    """The scratch matrix of :func:`evaluate_t` for ``m`` columns (rows ``DW_*``)."""
    return np.zeros((DW_SIZE, max(m, 1)))


@kernel(inline="always")
def _trig_of(meta, tr):
    """The configuration's sines and cosines (``TR_*``) from the evaluation's summary."""
    tr[TR_STH] = meta[MT_STH]
    tr[TR_CTH] = meta[MT_CTH]
    tr[TR_SGB] = meta[MT_SG_B]
    tr[TR_CGB] = meta[MT_CG_B]
    tr[TR_SGF] = meta[MT_SG_F]
    tr[TR_CGF] = meta[MT_CG_F]


@kernel
def evaluate_t(P, mi, cmd, ew, dw, tangents, ds_t):
    """ds_t (NS, m) := the derivative of ds = f(s)
    (:func:`~scoutsim._core.model.evaluate.evaluate_ws`) along each of m directions (the
    columns), at the evaluation the workspace ``ew`` holds (the last ``evaluate_ws`` call
    on it, with these parameters ``P``, modes ``mi`` and commands ``cmd``); ``tangents`` =
    (s_t (NS, m), mf_t (NMF, m), cmd_t (2, m), P_t (m, len(P))): the columns' tangents of
    the state given to that call, of the toe anchors, of the commands and (row c) of the
    packed parameters. ``dw``: scratch (:func:`derivative_workspace` for at least m
    columns). A failed factorization gives zero accelerations, as the evaluation does."""
    s_t, mf_t, cmd_t, P_t = tangents
    m = s_t.shape[1]
    wk, wA, piv = ew[0], ew[1], ew[2]
    q = wk[WK_Q : WK_Q + NQ]
    dq = wk[WK_DQ : WK_DQ + NQ]
    l = wk[WK_L : WK_L + 2]
    LG = wk[WK_LEG : WK_LEG + NWK_LEG]
    b = wk[WK_B : WK_B + MAX_KKT]
    b2 = wk[WK_B2 : WK_B2 + MAX_KKT]
    rkind = wk[WK_RKIND : WK_RKIND + MAX_ROWS]
    rleg = wk[WK_RLEG : WK_RLEG + MAX_ROWS]
    meta = wk[WK_META : WK_META + NMETA]
    M = wA[WA_M : WA_M + NQ]
    A = wA[0:MAX_KKT]
    gear = geared(P)
    nact = 7 if gear else 5
    nr = int(meta[MT_NROWS])
    ok = is_set(meta[MT_KKT_OK])
    q_t = dw[DW_Q_T : DW_Q_T + NQ]
    dq_t = dw[DW_DQ_T : DW_DQ_T + NQ]
    l_t = dw[DW_L_T : DW_L_T + 2]
    tr = dw[DW_TR : DW_TR + NTR, 0]
    tr_t = dw[DW_TR_T : DW_TR_T + NTR]
    g = dw[DW_G : DW_G + NQ]
    h_t = dw[DW_H_T : DW_H_T + NQ]
    ddq = dw[DW_DDQ : DW_DDQ + NQ, 0]
    gr = dw[DW_GR : DW_GR + MAX_ROWS]
    for i in range(NQ):
        ddq[i] = b[i] if (ok and i < nact) else 0.0
    # (the columns in the outer loops where each column's work is short: one loop to enter)
    for c in range(m):
        for i in range(NQ):
            g[i, c] = 0.0
        for rr in range(nr):
            gr[rr, c] = 0.0  # constant rows (a stuck joint's, a massless leg's, the clamps')
    # the projected state's tangents into q_t, dq_t, l_t and tr_t (ds_t is filled below)
    _trig_of(meta, tr)
    projected_t(q, dq, l, P, mi, dw, (s_t, mf_t, P_t), ds_t)

    # rigid bodies: Q_t - h_t - M_t ddq
    add_gravity_t(g, P, tr, tr_t, P_t)
    coriolis_t(h_t, dq, dq_t, P, tr, tr_t, P_t)
    for c in range(m):
        for i in range(NQ):
            g[i, c] -= h_t[i, c]
            h_t[i, c] = 0.0
    mass_matrix_times_t(h_t, ddq, P, tr, tr_t, P_t)
    for c in range(m):
        for i in range(NQ):
            g[i, c] -= h_t[i, c]

    # actuators and transmissions
    model = int(P[P_MODEL])
    vb = meta[MT_VBATT]
    vb_t = dw[DW_VB_T]
    battery_voltage_t(dq, cmd, P, vb, (dq_t, cmd_t, P_t), vb_t)
    om_t, cur_t, tapp_t = dw[DW_OM_T], dw[DW_CUR_T], dw[DW_TAPP_T]
    tf_t, tb_t, ld_t, zero = dw[DW_TF_T], dw[DW_TB_T], dw[DW_LD_T], dw[DW_ZERO]
    for c in range(m):
        zero[c] = 0.0
    nu0 = nact
    for leg in range(2):
        om = LG[2 * LG_OM + leg]
        cur = LG[2 * LG_CUR + leg]
        _motor_t(leg, P, cmd, wk, dq, (dq_t, cmd_t, vb_t, P_t), (om_t, cur_t))
        for c in range(m):
            tapp_t[c] = delivered_torque_t(cur, om, leg, P, cur_t[c], om_t[c], P_t[c])
        mode = mi[MI_MOTOR_B + leg]
        hip_unit_forces_t(g, q, dq, leg, mode, P, (q_t, dq_t, tapp_t, om_t, P_t), (tf_t, tb_t))
        # the torque the hip applies to the leg (its side load on the leg's friction)
        if gear:
            tau, tau_t = LG[2 * LG_TBELT + leg], tb_t
        elif model != MODEL_PASSIVE:
            tau, tau_t = LG[2 * LG_TAPP + leg], tapp_t
        else:
            tau, tau_t = 0.0, zero
        # the leg's rows start at nu0 (the evaluation appends them leg by leg, its contact
        # rows first, then a stuck motor joint's; the rig's clamps come after both legs')
        nu = b[nu0 : nu0 + 2] if ok else b2[0:2]
        leg_contact_t(
            leg,
            P,
            mi,
            (q, dq, l, tr, tau, ddq, nu),
            (q_t, dq_t, l_t, tr_t, tau_t, P_t),
            (g, gr[nu0 - nact : nu0 - nact + 2], ld_t),
        )
        for c in range(m):
            ds_t[IL_B + leg, c] = ld_t[c]
        while nu0 - nact < nr and int(rleg[nu0 - nact]) == leg:
            nu0 += 1
    for c in range(m):
        for i in range(NQ):
            ds_t[i, c] = dq_t[i, c]
            ds_t[NQ + i, c] = 0.0
    if ok:
        free0 = gear and mi[MI_MOTOR_B] != STUCK
        free1 = gear and mi[MI_MOTOR_B + 1] != STUCK
        schur = is_set(meta[MT_SCHUR])
        B = dw[DW_B : DW_B + MAX_KKT]
        for c in range(m):
            for i in range(nact):
                B[i, c] = g[i, c]
            for rr in range(nr):
                B[nact + rr, c] = gr[rr, c]
        kkt_reduced_solve_columns(
            A,
            piv,
            M,
            rkind,
            rleg,
            (nact, nr, free0, free1, schur),
            B,
            dw[DW_Y : DW_Y + MAX_KKT],
            (wk, WK_B2, WK_Y),
        )
        for c in range(m):
            for i in range(nact):
                ds_t[NQ + i, c] = B[i, c]
    if not gear:
        for c in range(m):
            ds_t[NQ + IALB, c] = ds_t[NQ + IPHB, c]
            ds_t[NQ + IALB + 1, c] = ds_t[NQ + IPHF, c]
    return ok


@kernel
def motor_currents_t(P, mi, cmd, ew, dw, tangents, s_out, cur_t):
    """cur_t (2, m) := the derivative of the motor current [A] of each leg (the
    evaluation's ``aux`` ``A_CURRENT``, :func:`~scoutsim._core.model.actuator.motor_current`)
    along each column, at the evaluation the workspace ``ew`` holds; ``tangents`` = (s_t,
    mf_t, cmd_t, P_t) as for :func:`evaluate_t`, whose current tangents these are (the same
    branch read ahead along the motion, the battery's voltage by the implicit function
    theorem). ``dw``: scratch (:func:`derivative_workspace`); ``s_out`` (NS, m): scratch,
    left with the projected state's tangent."""
    s_t, mf_t, cmd_t, P_t = tangents
    wk = ew[0]
    dq = wk[WK_DQ : WK_DQ + NQ]
    dq_t = dw[DW_DQ_T : DW_DQ_T + NQ]
    meta = wk[WK_META : WK_META + NMETA]
    _trig_of(meta, dw[DW_TR : DW_TR + NTR, 0])
    projected_t(wk[WK_Q : WK_Q + NQ], dq, wk[WK_L : WK_L + 2], P, mi, dw, (s_t, mf_t, P_t), s_out)
    vb_t = dw[DW_VB_T]
    battery_voltage_t(dq, cmd, P, meta[MT_VBATT], (dq_t, cmd_t, P_t), vb_t)
    for leg in range(2):
        _motor_t(leg, P, cmd, wk, dq, (dq_t, cmd_t, vb_t, P_t), (dw[DW_OM_T], cur_t[leg]))


@kernel
def projection_t(P, mi, ew, dw, tangents, s_out):
    """s_out (NS, m) := the derivative of the projected state along each column, at the
    evaluation the workspace ``ew`` holds (the projection of the state given to it);
    ``tangents`` = (s_t (NS, m), mf_t (NMF, m), P_t (m, len(P))): the columns' tangents
    of that state, of the toe anchors and of the packed parameters."""
    wk = ew[0]
    tr = dw[DW_TR : DW_TR + NTR, 0]
    _trig_of(wk[WK_META : WK_META + NMETA], tr)
    projected_t(
        wk[WK_Q : WK_Q + NQ],
        wk[WK_DQ : WK_DQ + NQ],
        wk[WK_L : WK_L + 2],
        P,
        mi,
        dw,
        tangents,
        s_out,
    )


@kernel
def projected_t(q, dq, l, P, mi, dw, tangents, s_out):
    """s_out (NS, m) := the derivative of the projection along each column at the
    projected state ``q, dq, l`` whose sines and cosines ``dw[DW_TR:, 0]`` holds;
    ``tangents`` = (s_t, mf_t, P_t) as for :func:`projection_t`."""
    s_t, mf_t, P_t = tangents
    m = s_t.shape[1]
    q_t = dw[DW_Q_T : DW_Q_T + NQ]
    dq_t = dw[DW_DQ_T : DW_DQ_T + NQ]
    l_t = dw[DW_L_T : DW_L_T + 2]
    tr = dw[DW_TR : DW_TR + NTR, 0]
    tr_t = dw[DW_TR_T : DW_TR_T + NTR]
    for c in range(m):
        for i in range(NQ):
            q_t[i, c] = s_t[i, c]
            dq_t[i, c] = s_t[NQ + i, c]
        l_t[0, c] = s_t[IL_B, c]
        l_t[1, c] = s_t[IL_B + 1, c]
    project_t(q, dq, l, P, mi, tr, (q_t, dq_t, l_t, mf_t, P_t, tr_t))
    for c in range(m):
        for i in range(NQ):
            s_out[i, c] = q_t[i, c]
            s_out[NQ + i, c] = dq_t[i, c]
        s_out[IL_B, c] = l_t[0, c]
        s_out[IL_B + 1, c] = l_t[1, c]
