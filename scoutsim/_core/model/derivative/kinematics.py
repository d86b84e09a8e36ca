"""Derivative of the projection of the dependent coordinates
(:func:`scoutsim._core.model.kinematics.project`), and the layout of the configuration's
sines and cosines every other derivative reads.

The projection makes the dependent coordinates functions of the independent ones (a
pinned toe's leg angle and length from the anchor and the hip, a sliding toe's length from
the hip's height, a massless flight leg's prescribed angle, a rigid hip unit's gear angle
copying the leg's): its derivative replaces the tangents of those coordinates by the
derivatives of those functions, and gives the tangents of the pitch's and the legs'
sines and cosines. :func:`project_t` takes m directions at once, a column each (the
parameters' tangents a row each).
"""

from __future__ import annotations

from ...._numba.jit import kernel
from ..flags import is_set
from ..hip_unit import geared
from ..kinematics import hip_offset
from ..layout import (
    HIP_SIGN,
    IALB,
    IPHB,
    ITH,
    IX,
    IY,
    MF_ANCHOR_B,
    MI_CONTACT_B,
    MI_MOTOR_B,
    P_C,
    P_CLAMP_LEGS,
    P_CLAMP_TORSO,
    P_COM_OFFSET,
    P_L,
    P_L0,
    P_MASSLESS,
    P_TD_B,
    P_TD_WORLD,
    SLIDE,
    STICK,
    STRUT,
    STUCK,
)
from ..leg import held_at_stop

# slots of the configuration's sines and cosines (what project returns, in its order):
# the pitch theta, the back and the front leg's angle g from the vertical
TR_STH, TR_CTH, TR_SGB, TR_CGB, TR_SGF, TR_CGF = range(6)
NTR = 6


@kernel(inline="always")
def hip_offset_t(P_t, leg):
    """Tangent [m] of :func:`~scoutsim._core.model.kinematics.hip_offset`."""
    return HIP_SIGN[leg] * P_t[P_L] - P_t[P_COM_OFFSET]


@kernel(inline="always")
def project_t(q, dq, l, P, mi, tr, bundle):
    """The tangents of the projection at the projected configuration ``q, dq, l`` (the
    primal's output, with ``tr`` its sines and cosines, ``TR_*``), along m directions at
    once, in place: ``bundle`` = (q_t, dq_t, l_t, mf_t, P_t, tr_t), of shapes (NQ, m),
    (NQ, m), (2, m), (NMF, m), (m, NP) and (NTR, m), holds in column c (row c of ``P_t``)
    on entry direction c's tangents of the state given to the projection (of the anchors
    ``mf_t`` and the parameters ``P_t``), on return those of the projected state, and
    ``tr_t`` the tangents of the sines and cosines."""
    q_t, dq_t, l_t, mf_t, P_t, tr_t = bundle
    m = q_t.shape[1]
    gear = geared(P)
    massless = is_set(P[P_MASSLESS])
    td_world = is_set(P[P_TD_WORLD])
    clamp_torso = is_set(P[P_CLAMP_TORSO])
    clamp_legs = clamp_torso and is_set(P[P_CLAMP_LEGS])
    sth = tr[TR_STH]
    cth = tr[TR_CTH]
    dth = dq[ITH]
    for c in range(m):
        if clamp_torso:
            dq_t[IX, c] = 0.0
            dq_t[IY, c] = 0.0
            dq_t[ITH, c] = 0.0
            if clamp_legs:
                dq_t[IPHB, c] = 0.0
                dq_t[IPHB + 1, c] = 0.0
        th_t = q_t[ITH, c]
        tr_t[TR_STH, c] = cth * th_t
        tr_t[TR_CTH, c] = -sth * th_t
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        sL = hip_offset(P, leg)
        sg = tr[TR_SGB + 2 * leg]
        cg = tr[TR_CGB + 2 * leg]
        k = IPHB + leg
        if mode == STICK or mode == STRUT:
            sLs = sL * sth
            sLc = sL * cth
            hvx = dq[IX] - sLs * dth
            hvy = dq[IY] + sLc * dth
            ll = l[leg]
            # dg = -(hvx cg + hvy sg) / ll
            dg = -(hvx * cg + hvy * sg) / ll
            for c in range(m):
                sL_t = hip_offset_t(P_t[c], leg)
                th_t = q_t[ITH, c]
                dth_t = dq_t[ITH, c]
                hy_t = q_t[IY, c] + sL_t * sth + sL * tr_t[TR_STH, c]
                hx_t = q_t[IX, c] + sL_t * cth + sL * tr_t[TR_CTH, c]
                hvx_t = dq_t[IX, c] - (sL_t * sth + sL * tr_t[TR_STH, c]) * dth - sLs * dth_t
                hvy_t = dq_t[IY, c] + (sL_t * cth + sL * tr_t[TR_CTH, c]) * dth + sLc * dth_t
                # the toe-hip vector (ddx, ddy) = (anchor - hx, -hy) = ll (sg, -cg)
                ddx_t = mf_t[MF_ANCHOR_B + leg, c] - hx_t
                ddy_t = -hy_t
                ll_t = sg * ddx_t - cg * ddy_t
                g_t = (cg * ddx_t + sg * ddy_t) / ll
                sg_t = cg * g_t
                cg_t = -sg * g_t
                q_t[k, c] = g_t - th_t
                dg_t = -(hvx_t * cg + hvx * cg_t + hvy_t * sg + hvy * sg_t) / ll - dg * ll_t / ll
                dq_t[k, c] = dg_t - dth_t
                l_t[leg, c] = ll_t
                tr_t[TR_SGB + 2 * leg, c] = sg_t
                tr_t[TR_CGB + 2 * leg, c] = cg_t
        elif mode == SLIDE:
            ll = l[leg]
            for c in range(m):
                sL_t = hip_offset_t(P_t[c], leg)
                hy_t = q_t[IY, c] + sL_t * sth + sL * tr_t[TR_STH, c]
                g_t = q_t[ITH, c] + q_t[k, c]
                sg_t = cg * g_t
                cg_t = -sg * g_t
                # l = hy / cg
                l_t[leg, c] = (hy_t - ll * cg_t) / cg
                tr_t[TR_SGB + 2 * leg, c] = sg_t
                tr_t[TR_CGB + 2 * leg, c] = cg_t
        else:
            # a massive leg held at the stop (the projected l <= l0; a leg exactly at l0 is
            # taken as held: the derivative of the branch at the stop)
            held = not massless and held_at_stop(P[P_C + leg], P[P_L0 + leg], l[leg])
            for c in range(m):
                if massless:
                    if td_world:
                        q_t[k, c] = P_t[c, P_TD_B + leg] - q_t[ITH, c]
                        dq_t[k, c] = -dq_t[ITH, c]
                    else:
                        q_t[k, c] = P_t[c, P_TD_B + leg]
                        dq_t[k, c] = 0.0
                    l_t[leg, c] = P_t[c, P_L0 + leg]
                elif held:
                    l_t[leg, c] = P_t[c, P_L0 + leg]
                g_t = q_t[ITH, c] + q_t[k, c]
                tr_t[TR_SGB + 2 * leg, c] = cg * g_t
                tr_t[TR_CGB + 2 * leg, c] = -sg * g_t
        if not gear:
            for c in range(m):
                q_t[IALB + leg, c] = q_t[k, c]
                dq_t[IALB + leg, c] = dq_t[k, c]
        elif mi[MI_MOTOR_B + leg] == STUCK:
            for c in range(m):
                dq_t[IALB + leg, c] = 0.0
