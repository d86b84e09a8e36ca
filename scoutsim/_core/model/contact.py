"""Ground contact of one leg (compiled): the leg force and the constraint rows of each
contact mode (docs/specification.md section 3; docs/model.md "Contact").

* stick (toe pinned at its anchor): the spring-damper leg force along the leg acts on the
  hip; the toe cannot move across the leg (row ``ROW_TOE_ACROSS``, its multiplier the part
  of the ground force across the leg);
* strut (a pinned leg at its stop l0): as stick, and the leg length is held at l0 by a
  second row ``ROW_TOE_ALONG`` (with Baumgarte stabilisation at ``P_STRUT_OMEGA``);
* slide: the toe moves on the ground; the ground force is normal plus the Coulomb friction
  mu F_n against the slide direction (frictionless with mu = inf), balanced against the
  leg force along the leg;
* flight: no ground force; a massive leg's length relaxes to l0 (model/leg.py), a massless
  leg's angle is prescribed (row ``ROW_MASSLESS``).
"""

from __future__ import annotations

import math

from ..._numba.jit import kernel
from .flags import is_set
from .kinematics import hip_offset
from .kkt import MAX_ROWS, new_row
from .layout import (
    IPHB,
    ITH,
    IX,
    IY,
    MF_ANCHOR_B,
    MI_CONTACT_B,
    MI_SLIDE_DIR_B,
    NQ,
    P_K,
    P_L0,
    P_MASSLESS,
    P_MU,
    P_NO_SLIP,
    P_NP,
    P_STRUT_OMEGA,
    P_TD_WORLD,
    ROW_MASSLESS,
    ROW_TOE_ACROSS,
    ROW_TOE_ALONG,
    SLIDE,
    STICK,
    STRUT,
)
from .leg import flight_leg_rate, leg_axial_force, leg_damping, leg_friction_level
from .workspace import (
    LG_FAX,
    LG_GN,
    LG_GT,
    LG_LDOT,
    LG_TOEVX,
    LG_TOEX,
    LG_TOEY,
    MT_CTH,
    MT_STH,
    NWK_LEG,
    WA_R,
    WK_DQ,
    WK_L,
    WK_LEG,
    WK_META,
    WK_Q,
    WK_Q_,
    WK_R,
    WK_RKIND,
    WK_RLEG,
)


@kernel(inline="always")
def toe_can_slip(P):
    """True on a Coulomb floor (friction coefficient ``P[P_MU]``); False when the toes
    cannot slip (``P_NO_SLIP``: friction_coefficient = inf, a pinned toe holds any force)."""
    return not is_set(P[P_NO_SLIP])


#: a sliding toe jams when the share of its ground force along the leg
#: (:func:`slide_axial_share`) falls to this level: the slide's normal force is then
#: 1 / JAM_AXIAL_SHARE times the leg force over sqrt(1 + mu^2), and the pinning impulse
#: along the leg's normal lies on the friction cone's edge to within this fraction
#: (docs/model.md "A sliding toe that jams")
JAM_AXIAL_SHARE = 1e-3


@kernel(inline="always")
def slide_axial_share(g, direction, P):
    """The share of a sliding toe's ground force that acts along its leg [-]: the cosine of
    the angle between the leg axis and the ground force of the slide, which lies on the
    edge of the friction cone, (cos g + sigma sin g) / sqrt(1 + sigma^2) with sigma = mu x
    the slide ``direction`` (+1 forward, -1 backward; ``g``: the leg's absolute angle gamma
    [rad]). The massless toe's
    balance along the leg gives the slide's normal force G_n = F / (cos g + sigma sin g):
    as the share falls to zero the slide needs an unbounded normal force to carry the leg
    force F (the leg leans at the friction angle against the slide: a dynamic jam, the
    Painleve singularity of a sliding massless toe). 1 on a frictionless slide at g = 0."""
    sig = 0.0
    if toe_can_slip(P):
        sig = P[P_MU] * direction
    return (math.cos(g) + sig * math.sin(g)) / math.sqrt(1.0 + sig * sig)


@kernel(inline="always")
def slide_is_jammed(g, direction, P):
    """True if a slide of a massed leg's toe in ``direction`` at leg angle ``g`` [rad] would
    be jammed (:func:`slide_axial_share` at or below JAM_AXIAL_SHARE) on a Coulomb floor."""
    return (
        toe_can_slip(P)
        and not is_set(P[P_MASSLESS])
        and slide_axial_share(g, direction, P) <= JAM_AXIAL_SHARE
    )


@kernel(inline="always")
def leg_contact(leg, P, mi, mf, sg, cg, tau_hip, nr, wk, wA):
    """Contact forces and constraint rows of virtual leg ``leg`` in its contact mode, in the
    evaluation workspace ``wk, wA`` (model/workspace.py: the projected state q, dq, l and
    the pitch's sin/cos ``MT_STH``, ``MT_CTH``).

    Adds the leg's ground and leg forces to the generalized forces Q, appends its rows
    (R, right-hand sides r, kinds, legs) from row ``nr`` on, and writes the leg's per-leg
    scalars LG (axial force, leg-length rate, ground force of a sliding toe, toe position
    and velocity). ``sg, cg``: sin/cos of the leg's angle from the vertical;
    ``tau_hip`` [N m]: the torque the hip applies to one physical leg (for the side-load
    friction of the leg). Returns the new row count."""
    q = wk[WK_Q : WK_Q + NQ]
    dq = wk[WK_DQ : WK_DQ + NQ]
    l = wk[WK_L : WK_L + 2]
    Q = wk[WK_Q_ : WK_Q_ + NQ]
    r = wk[WK_R : WK_R + MAX_ROWS]
    rkind = wk[WK_RKIND : WK_RKIND + MAX_ROWS]
    rleg = wk[WK_RLEG : WK_RLEG + MAX_ROWS]
    LG = wk[WK_LEG : WK_LEG + NWK_LEG]
    R = wA[WA_R : WA_R + MAX_ROWS]
    sth = wk[WK_META + MT_STH]
    cth = wk[WK_META + MT_CTH]
    massless = is_set(P[P_MASSLESS])
    npl = P[P_NP]
    l0 = P[P_L0 + leg]
    k = P[P_K + leg]
    mode = mi[MI_CONTACT_B + leg]
    sL = hip_offset(P, leg)
    dth = dq[ITH]
    dg = dth + dq[IPHB + leg]
    hx = q[IX] + sL * cth
    hy = q[IY] + sL * sth
    hvx = dq[IX] - sL * sth * dth
    hvy = dq[IY] + sL * cth * dth
    ll = l[leg]
    jt_th_x = -sL * sth + ll * cg
    jt_th_y = sL * cth + ll * sg
    jt_ph_x = ll * cg
    jt_ph_y = ll * sg
    bx = -sL * cth * dth * dth
    by = -sL * sth * dth * dth
    kk = IPHB + leg
    # leg damper and sliding-joint friction (as Table III unless the effects beyond the
    # paper are switched on)
    c_l = leg_damping(q[kk], leg, P)
    fc_l = leg_friction_level(tau_hip, ll, leg, P)
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
        Q[IX] += fx
        Q[IY] += fy
        Q[ITH] += jt_th_x * fx + jt_th_y * fy
        Q[kk] += jt_ph_x * fx + jt_ph_y * fy
        new_row(R, r, rkind, rleg, nr, -(bx * cg + by * sg + 2.0 * ld * dg), ROW_TOE_ACROSS, leg)
        R[nr, IX] = cg
        R[nr, IY] = sg
        R[nr, ITH] = sL * sph + ll
        R[nr, kk] = ll
        nr += 1
        if mode == STRUT:
            w = P[P_STRUT_OMEGA]
            new_row(
                R,
                r,
                rkind,
                rleg,
                nr,
                -(bx * sg - by * cg) + ll * dg * dg + 2.0 * w * ld + w * w * (ll - l0),
                ROW_TOE_ALONG,
                leg,
            )
            R[nr, IX] = sg
            R[nr, IY] = -cg
            R[nr, ITH] = -sL * cph
            nr += 1
        LG[2 * LG_TOEX + leg] = mf[MF_ANCHOR_B + leg]
    elif mode == SLIDE:
        ld = hvy / cg + hy * sg * dg / (cg * cg)
        LG[2 * LG_LDOT + leg] = ld
        F = npl * leg_axial_force(k, c_l, l0, ll, ld, fc_l)
        LG[2 * LG_FAX + leg] = F
        sig = 0.0
        if toe_can_slip(P):
            sig = P[P_MU] * mi[MI_SLIDE_DIR_B + leg]
        gn = F / (cg + sig * sg)
        gt = -sig * gn
        LG[2 * LG_GN + leg] = gn
        LG[2 * LG_GT + leg] = gt
        Q[IX] += gt
        Q[IY] += gn
        Q[ITH] += jt_th_x * gt + jt_th_y * gn
        Q[kk] += jt_ph_x * gt + jt_ph_y * gn
        LG[2 * LG_TOEX + leg] = hx + ll * sg
        LG[2 * LG_TOEVX + leg] = hvx + ld * sg + ll * cg * dg
    else:
        if massless:
            new_row(R, r, rkind, rleg, nr, 0.0, ROW_MASSLESS, leg)
            R[nr, kk] = 1.0
            if is_set(P[P_TD_WORLD]):
                R[nr, ITH] = 1.0
            nr += 1
            ld = 0.0
        else:
            ld = flight_leg_rate(k, c_l, l0, ll, fc_l)
        LG[2 * LG_LDOT + leg] = ld
        LG[2 * LG_TOEX + leg] = hx + ll * sg
        LG[2 * LG_TOEY + leg] = hy - ll * cg
        LG[2 * LG_TOEVX + leg] = hvx + ld * sg + ll * cg * dg
    return nr
