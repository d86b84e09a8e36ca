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
"""

from __future__ import annotations

import numpy as np

from ...._numba.jit import allocating, kernel
from ..flags import is_set
from ..hip_unit import geared
from ..kkt import MAX_KKT, MAX_ROWS, kkt_reduced_solve
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

# slots of the derivative's scratch vector (:func:`derivative_workspace`)
DW_Q_T = 0  # tangents of the projected state: q (NQ), dq (NQ), l (2)
DW_DQ_T = DW_Q_T + NQ
DW_L_T = DW_DQ_T + NQ
DW_TR = DW_L_T + 2  # the configuration's sines and cosines (kinematics.TR_*)
DW_TR_T = DW_TR + NTR  # ... their tangents
DW_G = DW_TR_T + NTR  # the tangent of the KKT system's right-hand side, its first NQ rows
DW_H_T = DW_G + NQ  # the velocity terms' tangent
DW_DDQ = DW_H_T + NQ  # the primal accelerations (NQ; zero beyond the active coordinates)
DW_GR = DW_DDQ + NQ  # ... its constraint rows (MAX_ROWS)
DW_SIZE = DW_GR + MAX_ROWS

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
def _motor_t(leg, P, cmd, wk, dq, tangents):
    """(om_t, cur_t): the tangents of leg ``leg``'s motor speed [rad/s] and motor current
    [A] at the evaluation summarised in ``wk`` (rates ``dq``, commands ``cmd``);
    ``tangents`` = (dq_t, cmd_t, vb_t, P_t): those of the projected rates, the commands,
    the battery voltage and the packed parameters. The current is on its branch a moment
    ahead along the motion: where it sits on a kink (a controller that commands the
    torque-speed line's torque at a sample puts it exactly there), the side the
    trajectory enters."""
    dq_t, cmd_t, vb_t, P_t = tangents
    LG = wk[WK_LEG : WK_LEG + NWK_LEG]
    vb = wk[WK_META + MT_VBATT]
    om_t = motor_speed_t(dq_t, leg, P, dq, P_t)
    branch = _leg_branch(P, cmd, wk, leg)
    cur_t = branch_current_t(
        branch, cmd[leg], LG[2 * LG_OM + leg], vb, leg, P, (cmd_t[leg], om_t, vb_t, P_t)
    )
    return om_t, cur_t


@allocating
def derivative_workspace():
    """The scratch vector of :func:`evaluate_t` (slots ``DW_*``)."""
    return np.zeros(DW_SIZE)


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
    """ds_t := the derivative of ds = f(s) (:func:`~scoutsim._core.model.evaluate.evaluate_ws`)
    along one direction, at the evaluation the workspace ``ew`` holds (the last
    ``evaluate_ws`` call on it, with these parameters ``P``, modes ``mi`` and commands
    ``cmd``); ``tangents`` = (s_t, mf_t, cmd_t, P_t): the direction's tangents of the state
    given to that call (NS), of the toe anchors (2), of the commands (2) and of the packed
    parameters. ``dw``: scratch (:func:`derivative_workspace`). A failed factorization
    gives zero accelerations, as the evaluation does."""
    s_t, mf_t, cmd_t, P_t = tangents
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
    tr = dw[DW_TR : DW_TR + NTR]
    tr_t = dw[DW_TR_T : DW_TR_T + NTR]
    g = dw[DW_G : DW_G + NQ]
    h_t = dw[DW_H_T : DW_H_T + NQ]
    ddq = dw[DW_DDQ : DW_DDQ + NQ]
    gr = dw[DW_GR : DW_GR + MAX_ROWS]
    for i in range(NQ):
        g[i] = 0.0
        ddq[i] = b[i] if (ok and i < nact) else 0.0
    for rr in range(nr):
        gr[rr] = 0.0  # constant rows (a stuck joint's, a massless leg's, the clamps')
    # the projected state's tangents into q_t, dq_t, l_t and tr_t (ds_t is filled below)
    _trig_of(meta, tr)
    projected_t(q, dq, l, P, mi, dw, (s_t, mf_t, P_t), ds_t)

    # rigid bodies: Q_t - h_t - M_t ddq
    add_gravity_t(g, P, tr, tr_t, P_t)
    coriolis_t(h_t, dq, dq_t, P, tr, tr_t, P_t)
    for i in range(NQ):
        g[i] -= h_t[i]
        h_t[i] = 0.0
    mass_matrix_times_t(h_t, ddq, P, tr, tr_t, P_t)
    for i in range(NQ):
        g[i] -= h_t[i]

    # actuators and transmissions
    model = int(P[P_MODEL])
    vb = meta[MT_VBATT]
    vb_t = battery_voltage_t(dq, cmd, P, vb, dq_t, cmd_t, P_t)
    nu0 = nact
    for leg in range(2):
        om = LG[2 * LG_OM + leg]
        om_t, cur_t = _motor_t(leg, P, cmd, wk, dq, (dq_t, cmd_t, vb_t, P_t))
        tapp_t = delivered_torque_t(LG[2 * LG_CUR + leg], om, leg, P, cur_t, om_t, P_t)
        mode = mi[MI_MOTOR_B + leg]
        tb_t = hip_unit_forces_t(g, q, dq, leg, mode, P, q_t, dq_t, tapp_t, om_t, P_t)[1]
        # the torque the hip applies to the leg (its side load on the leg's friction)
        if gear:
            tau, tau_t = LG[2 * LG_TBELT + leg], tb_t
        elif model != MODEL_PASSIVE:
            tau, tau_t = LG[2 * LG_TAPP + leg], tapp_t
        else:
            tau, tau_t = 0.0, 0.0
        # the leg's rows start at nu0 (the evaluation appends them leg by leg, its contact
        # rows first, then a stuck motor joint's; the rig's clamps come after both legs')
        nu = b[nu0 : nu0 + 2] if ok else b2[0:2]
        ld_t = leg_contact_t(
            leg,
            P,
            mi,
            (q, dq, l, tr, tau, ddq, nu),
            (q_t, dq_t, l_t, tr_t, tau_t, P_t),
            (g, gr[nu0 - nact : nu0 - nact + 2]),
        )
        ds_t[IL_B + leg] = ld_t
        while nu0 - nact < nr and int(rleg[nu0 - nact]) == leg:
            nu0 += 1
    for i in range(NQ):
        ds_t[i] = dq_t[i]
        ds_t[NQ + i] = 0.0
    if ok:
        for i in range(nact):
            b2[i] = g[i]
        for rr in range(nr):
            b2[nact + rr] = gr[rr]
        free0 = gear and mi[MI_MOTOR_B] != STUCK
        free1 = gear and mi[MI_MOTOR_B + 1] != STUCK
        schur = is_set(meta[MT_SCHUR])
        kkt_reduced_solve(
            A, piv, M, rkind, rleg, (nact, nr, free0, free1, schur), wk, WK_B2, wk, WK_Y
        )
        for i in range(nact):
            ds_t[NQ + i] = b2[i]
    if not gear:
        ds_t[NQ + IALB] = ds_t[NQ + IPHB]
        ds_t[NQ + IALB + 1] = ds_t[NQ + IPHF]
    return ok


@kernel
def motor_currents_t(P, mi, cmd, ew, dw, tangents, s_out, cur_t):
    """cur_t[leg] := the derivative of the motor current [A] of each leg (the evaluation's
    ``aux`` ``A_CURRENT``, :func:`~scoutsim._core.model.actuator.motor_current`) along one
    direction, at the evaluation the workspace ``ew`` holds; ``tangents`` = (s_t, mf_t,
    cmd_t, P_t) as for :func:`evaluate_t`, whose current tangents these are (the same
    branch read ahead along the motion, the battery's voltage by the implicit function
    theorem). ``dw``: scratch (:func:`derivative_workspace`); ``s_out`` (NS): scratch, left
    with the projected state's tangent."""
    s_t, mf_t, cmd_t, P_t = tangents
    wk = ew[0]
    dq = wk[WK_DQ : WK_DQ + NQ]
    dq_t = dw[DW_DQ_T : DW_DQ_T + NQ]
    meta = wk[WK_META : WK_META + NMETA]
    _trig_of(meta, dw[DW_TR : DW_TR + NTR])
    projected_t(wk[WK_Q : WK_Q + NQ], dq, wk[WK_L : WK_L + 2], P, mi, dw, (s_t, mf_t, P_t), s_out)
    vb_t = battery_voltage_t(dq, cmd, P, meta[MT_VBATT], dq_t, cmd_t, P_t)
    for leg in range(2):
        cur_t[leg] = _motor_t(leg, P, cmd, wk, dq, (dq_t, cmd_t, vb_t, P_t))[1]


@kernel
def projection_t(P, mi, ew, dw, tangents, s_out):
    """s_out := the derivative of the projected state along one direction, at the
    evaluation the workspace ``ew`` holds (the projection of the state given to it);
    ``tangents`` = (s_t, mf_t, P_t): the direction's tangents of that state (NS), of the
    toe anchors and of the packed parameters."""
    wk = ew[0]
    tr = dw[DW_TR : DW_TR + NTR]
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
    """s_out := the derivative of the projection along one direction at the projected
    state ``q, dq, l`` whose sines and cosines ``dw[DW_TR:]`` holds; ``tangents`` = (s_t,
    mf_t, P_t) as for :func:`projection_t`."""
    s_t, mf_t, P_t = tangents
    q_t = dw[DW_Q_T : DW_Q_T + NQ]
    dq_t = dw[DW_DQ_T : DW_DQ_T + NQ]
    l_t = dw[DW_L_T : DW_L_T + 2]
    tr = dw[DW_TR : DW_TR + NTR]
    tr_t = dw[DW_TR_T : DW_TR_T + NTR]
    for i in range(NQ):
        q_t[i] = s_t[i]
        dq_t[i] = s_t[NQ + i]
    l_t[0] = s_t[IL_B]
    l_t[1] = s_t[IL_B + 1]
    project_t(q, dq, l, P, mi, tr, (q_t, dq_t, l_t, mf_t, P_t, tr_t))
    for i in range(NQ):
        s_out[i] = q_t[i]
        s_out[NQ + i] = dq_t[i]
    s_out[IL_B] = l_t[0]
    s_out[IL_B + 1] = l_t[1]
