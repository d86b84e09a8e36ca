"""Derivative of the projection of the dependent coordinates
(:func:`scoutsim._core.model.kinematics.project`), and the layout of the configuration's
sines and cosines every other derivative reads.

The projection makes the dependent coordinates functions of the independent ones (a
pinned toe's leg angle and length from the anchor and the hip, a sliding toe's length from
the hip's height, a massless flight leg's prescribed angle, a rigid hip unit's gear angle
copying the leg's): its derivative replaces the tangents of those coordinates by the
derivatives of those functions, and gives the tangents of the pitch's and the legs'
sines and cosines.
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
    """The tangent of the projection at the projected configuration ``q, dq, l`` (the
    primal's output, with ``tr`` its sines and cosines, ``TR_*``), in place: ``bundle`` =
    (q_t, dq_t, l_t, mf_t, P_t, tr_t) holds on entry the tangents of the state given to
    the projection (of the anchors ``mf_t`` and the parameters ``P_t``), on return those
    of the projected state, and ``tr_t`` the tangents of the sines and cosines."""
    q_t, dq_t, l_t, mf_t, P_t, tr_t = bundle
    gear = geared(P)
    massless = is_set(P[P_MASSLESS])
    if is_set(P[P_CLAMP_TORSO]):
        dq_t[IX] = 0.0
        dq_t[IY] = 0.0
        dq_t[ITH] = 0.0
        if is_set(P[P_CLAMP_LEGS]):
            dq_t[IPHB] = 0.0
            dq_t[IPHB + 1] = 0.0
    sth = tr[TR_STH]
    cth = tr[TR_CTH]
    th_t = q_t[ITH]
    dth = dq[ITH]
    dth_t = dq_t[ITH]
    tr_t[TR_STH] = cth * th_t
    tr_t[TR_CTH] = -sth * th_t
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        sL = hip_offset(P, leg)
        sL_t = hip_offset_t(P_t, leg)
        sg = tr[TR_SGB + 2 * leg]
        cg = tr[TR_CGB + 2 * leg]
        hy_t = q_t[IY] + sL_t * sth + sL * tr_t[TR_STH]
        if mode == STICK or mode == STRUT:
            hx_t = q_t[IX] + sL_t * cth + sL * tr_t[TR_CTH]
            hvx = dq[IX] - sL * sth * dth
            hvy = dq[IY] + sL * cth * dth
            hvx_t = dq_t[IX] - (sL_t * sth + sL * tr_t[TR_STH]) * dth - sL * sth * dth_t
            hvy_t = dq_t[IY] + (sL_t * cth + sL * tr_t[TR_CTH]) * dth + sL * cth * dth_t
            ll = l[leg]
            # the toe-hip vector (ddx, ddy) = (anchor - hx, -hy) = ll (sg, -cg)
            ddx_t = mf_t[MF_ANCHOR_B + leg] - hx_t
            ddy_t = -hy_t
            ll_t = sg * ddx_t - cg * ddy_t
            g_t = (cg * ddx_t + sg * ddy_t) / ll
            sg_t = cg * g_t
            cg_t = -sg * g_t
            q_t[IPHB + leg] = g_t - th_t
            # dg = -(hvx cg + hvy sg) / ll
            dg = -(hvx * cg + hvy * sg) / ll
            dg_t = -(hvx_t * cg + hvx * cg_t + hvy_t * sg + hvy * sg_t) / ll - dg * ll_t / ll
            dq_t[IPHB + leg] = dg_t - dth_t
            l_t[leg] = ll_t
        elif mode == SLIDE:
            g_t = th_t + q_t[IPHB + leg]
            sg_t = cg * g_t
            cg_t = -sg * g_t
            # l = hy / cg
            l_t[leg] = (hy_t - l[leg] * cg_t) / cg
        else:
            if massless:
                if is_set(P[P_TD_WORLD]):
                    q_t[IPHB + leg] = P_t[P_TD_B + leg] - th_t
                    dq_t[IPHB + leg] = -dth_t
                else:
                    q_t[IPHB + leg] = P_t[P_TD_B + leg]
                    dq_t[IPHB + leg] = 0.0
                l_t[leg] = P_t[P_L0 + leg]
            elif held_at_stop(P[P_C + leg], P[P_L0 + leg], l[leg]):
                # held at the stop (the projected l <= l0; a leg exactly at l0 is taken as
                # held: the derivative of the branch at the stop)
                l_t[leg] = P_t[P_L0 + leg]
            g_t = th_t + q_t[IPHB + leg]
            sg_t = cg * g_t
            cg_t = -sg * g_t
        tr_t[TR_SGB + 2 * leg] = sg_t
        tr_t[TR_CGB + 2 * leg] = cg_t
        if not gear:
            q_t[IALB + leg] = q_t[IPHB + leg]
            dq_t[IALB + leg] = dq_t[IPHB + leg]
        elif mi[MI_MOTOR_B + leg] == STUCK:
            dq_t[IALB + leg] = 0.0
