"""Derivative of a leg's ground contact (:func:`scoutsim._core.model.contact.leg_contact`)
and of its telescopic leg (:mod:`scoutsim._core.model.leg`).

The contact gives the generalized forces of the leg force and the ground force (added to
Q), the constraint rows R and their right-hand sides r, and the leg-length rate. In the
tangent of the KKT system ``M ddq + R^T nu = Q - h``, ``R ddq = r`` the rows enter through
``R_t^T nu`` and ``r_t - R_t ddq`` (``ddq``, ``nu`` the primal solution): the functions here
add the first to the right-hand side's tangent ``g`` and write the second, row by row,
without forming R_t. :func:`leg_contact_t` takes m directions at once (the tangents' columns);
the helpers before it take one.
"""

from __future__ import annotations

from ...._numba.jit import kernel
from ..contact import toe_can_slip
from ..flags import is_set
from ..kinematics import hip_offset
from ..layout import (
    IPHB,
    ITH,
    IX,
    IY,
    MI_CONTACT_B,
    MI_SLIDE_DIR_B,
    P_C,
    P_K,
    P_L0,
    P_LEG_C_ANGLE,
    P_LEG_FRIC,
    P_LEG_FRIC_SIDE,
    P_MASSLESS,
    P_MU,
    P_NP,
    P_STRUT_OMEGA,
    SLIDE,
    STICK,
    STRUT,
)
from ..leg import LEG_FRICTION_SPEED, leg_axial_force, leg_damping, leg_friction_level
from .kinematics import TR_CGB, TR_CTH, TR_SGB, TR_STH, hip_offset_t


@kernel(inline="always")
def leg_damping_t(phi, phi_t, leg, P, P_t):
    """Tangent [N s/m] of :func:`~scoutsim._core.model.leg.leg_damping`."""
    a = P[P_LEG_C_ANGLE + leg]
    c = P[P_C + leg]
    return P_t[P_C + leg] * (1.0 + a * phi * phi) + c * (
        P_t[P_LEG_C_ANGLE + leg] * phi * phi + 2.0 * a * phi * phi_t
    )


@kernel(inline="always")
def leg_friction_level_t(tau, ll, leg, P, tangents):
    """Tangent [N] of :func:`~scoutsim._core.model.leg.leg_friction_level`;
    ``tangents`` = (tau_t, ll_t, P_t)."""
    tau_t, ll_t, P_t = tangents
    side = P[P_LEG_FRIC_SIDE + leg]
    at = abs(tau)
    at_t = tau_t if tau > 0.0 else (-tau_t if tau < 0.0 else 0.0)
    return (
        P_t[P_LEG_FRIC + leg]
        + P_t[P_LEG_FRIC_SIDE + leg] * at / ll
        + side * (at_t / ll - at * ll_t / (ll * ll))
    )


@kernel(inline="always")
def leg_axial_force_t(k, c, l0, ll, ld, fc, tangents):
    """Tangent [N] of :func:`~scoutsim._core.model.leg.leg_axial_force`; ``tangents`` =
    (k_t, c_t, l0_t, ll_t, ld_t, fc_t)."""
    k_t, c_t, l0_t, ll_t, ld_t, fc_t = tangents
    sat = ld / LEG_FRICTION_SPEED
    sat_t = ld_t / LEG_FRICTION_SPEED
    if sat > 1.0:
        sat = 1.0
        sat_t = 0.0
    elif sat < -1.0:
        sat = -1.0
        sat_t = 0.0
    return k_t * (l0 - ll) + k * (l0_t - ll_t) - c_t * ld - c * ld_t - fc_t * sat - fc * sat_t


@kernel(inline="always")
def flight_leg_rate_t(k, c, l0, ll, fc, tangents):
    """Tangent [m/s] of :func:`~scoutsim._core.model.leg.flight_leg_rate`; ``tangents`` =
    (k_t, c_t, l0_t, ll_t, fc_t)."""
    k_t, c_t, l0_t, ll_t, fc_t = tangents
    if c <= 0.0 or ll >= l0:
        return 0.0
    f = k * (l0 - ll)
    f_t = k_t * (l0 - ll) + k * (l0_t - ll_t)
    den = c + fc / LEG_FRICTION_SPEED
    den_t = c_t + fc_t / LEG_FRICTION_SPEED
    lin = f / den
    if lin <= LEG_FRICTION_SPEED:
        return (f_t - lin * den_t) / den
    return (f_t - fc_t - (f - fc) * c_t / c) / c


@kernel(inline="always")
def _row_t(g, c, ddq, nu, row_t):
    """Add -R_t^T nu of one row to column ``c`` of ``g`` (NQ, m) and return that column's
    r_t - R_t ddq; ``row_t`` = (the row's tangent along x, y, theta, the leg angle, the leg
    angle's index, r_t) of column ``c``."""
    rx, ry, rth, rph, kk, r_t = row_t
    g[IX, c] -= rx * nu
    g[IY, c] -= ry * nu
    g[ITH, c] -= rth * nu
    g[kk, c] -= rph * nu
    return r_t - (rx * ddq[IX] + ry * ddq[IY] + rth * ddq[ITH] + rph * ddq[kk])


@kernel(inline="always")
def _pinned_motion_t(c, leg, hip, tangents):
    """Column ``c``'s tangents of a pinned toe's leg: (sin th, cos th, sin g, cos g, the
    hip offset s L, th', g', the leg length, the leg-length rate); ``hip`` = (sin th,
    cos th, sin g, cos g, s L, th', the hip's velocity x and y), ``tangents`` = (dq_t,
    l_t, tr_t, Pc: column c's parameter tangents)."""
    sth, cth, sg, cg, sL, dth, hvx, hvy = hip
    dq_t, l_t, tr_t, Pc = tangents
    kk = IPHB + leg
    sth_t, cth_t = tr_t[TR_STH, c], tr_t[TR_CTH, c]
    sg_t, cg_t = tr_t[TR_SGB + 2 * leg, c], tr_t[TR_CGB + 2 * leg, c]
    sL_t = hip_offset_t(Pc, leg)
    dth_t = dq_t[ITH, c]
    dg_t = dth_t + dq_t[kk, c]
    hvx_t = dq_t[IX, c] - (sL_t * sth + sL * sth_t) * dth - sL * sth * dth_t
    hvy_t = dq_t[IY, c] + (sL_t * cth + sL * cth_t) * dth + sL * cth * dth_t
    lt = -(hvx_t * sg + hvx * sg_t - hvy_t * cg - hvy * cg_t)
    return sth_t, cth_t, sg_t, cg_t, sL_t, dth_t, dg_t, l_t[leg, c], lt


@kernel(inline="always")
def _pinned_force_and_row_t(c, kk, out, pinned, t, F_t):
    """Add column ``c``'s tangent of a pinned toe's leg force ``F_t`` (along the leg) to
    ``g`` and write its row across the leg's r_t - R_t ddq to ``gr[0, c]``; ``out`` = (g,
    gr, ddq); ``pinned`` = (the hip as :func:`_pinned_motion_t` takes it, (ll, g', the
    leg-length rate, F, the toe's Jacobian columns jx, jy, px, py, sin(g - th), the hip's
    acceleration bx, by at zero ddq), nu of that row); ``t``: :func:`_pinned_motion_t`'s
    value. Returns the tangents of bx and by."""
    g, gr, ddq = out
    hip, primal, nu0 = pinned
    sth, cth, sg, cg, sL, dth = hip[0], hip[1], hip[2], hip[3], hip[4], hip[5]
    ll, dg, ld, F, jx, jy, px, py, sph, bx, by = primal
    sth_t, cth_t, sg_t, cg_t, sL_t, dth_t, dg_t, ll_t, lt = t
    fx = -F * sg
    fy = F * cg
    jx_t = -(sL_t * sth + sL * sth_t) + ll_t * cg + ll * cg_t
    jy_t = sL_t * cth + sL * cth_t + ll_t * sg + ll * sg_t
    px_t = ll_t * cg + ll * cg_t
    py_t = ll_t * sg + ll * sg_t
    fx_t = -F_t * sg - F * sg_t
    fy_t = F_t * cg + F * cg_t
    g[IX, c] += fx_t
    g[IY, c] += fy_t
    g[ITH, c] += jx_t * fx + jx * fx_t + jy_t * fy + jy * fy_t
    g[kk, c] += px_t * fx + px * fx_t + py_t * fy + py * fy_t
    sph_t = sg_t * cth + sg * cth_t - cg_t * sth - cg * sth_t
    bx_t = -(sL_t * cth + sL * cth_t) * dth * dth - 2.0 * sL * cth * dth * dth_t
    by_t = -(sL_t * sth + sL * sth_t) * dth * dth - 2.0 * sL * sth * dth * dth_t
    r_t = -(bx_t * cg + bx * cg_t + by_t * sg + by * sg_t + 2.0 * (lt * dg + ld * dg_t))
    gr[0, c] = _row_t(g, c, ddq, nu0, (cg_t, sg_t, sL_t * sph + sL * sph_t + ll_t, ll_t, kk, r_t))
    return bx_t, by_t


@kernel(inline="always")
def leg_contact_t(leg, P, mi, primal, tangents, out):
    """The tangent of :func:`~scoutsim._core.model.contact.leg_contact` of virtual leg
    ``leg`` in its contact mode, along m directions (columns) at once.

    ``primal`` = (q, dq, l, tr, tau_hip, ddq, nu), shared by the columns: the projected
    state, its sines and cosines (``TR_*``), the torque the hip applies to one physical leg
    [N m], the primal KKT solution's accelerations (7) and the multipliers of this leg's
    rows (its first rows from ``nu[0]`` on); ``tangents`` = (q_t, dq_t, l_t, tr_t,
    tau_hip_t, P_t): q_t, dq_t (NQ, m), l_t (2, m), tr_t (NTR, m), tau_hip_t (m,) [N m],
    P_t (m, NP) (row c is column c's). ``out`` = (g, gr, ld_t): adds column c's tangent of
    the generalized forces less R_t^T nu to ``g[:, c]`` (g (NQ, m)), writes column c's
    r_t - R_t ddq of this leg's rows to ``gr[0, c]``, ``gr[1, c]`` (gr (2, m); the rows
    the mode has: none in flight and in a slide, one in stick, two in strut) and column
    c's tangent of the leg-length rate [m/s] to ``ld_t[c]`` (ld_t (m,))."""
    q, dq, l, tr, tau_hip, ddq, nu = primal
    q_t, dq_t, l_t, tr_t, tau_hip_t, P_t = tangents
    g, gr, ld_t = out
    m = q_t.shape[1]
    massless = is_set(P[P_MASSLESS])
    npl = P[P_NP]
    l0 = P[P_L0 + leg]
    k = P[P_K + leg]
    mode = mi[MI_CONTACT_B + leg]
    sth, cth = tr[TR_STH], tr[TR_CTH]
    sg, cg = tr[TR_SGB + 2 * leg], tr[TR_CGB + 2 * leg]
    sL = hip_offset(P, leg)
    kk = IPHB + leg
    phi = q[kk]
    dth = dq[ITH]
    dg = dth + dq[kk]
    hy = q[IY] + sL * sth
    hvx = dq[IX] - sL * sth * dth
    hvy = dq[IY] + sL * cth * dth
    ll = l[leg]
    c_l = leg_damping(phi, leg, P)
    fc_l = leg_friction_level(tau_hip, ll, leg, P)
    if mode != STICK and mode != STRUT and mode != SLIDE:
        if massless:
            for c in range(m):
                ld_t[c] = 0.0  # the prescribed angle's row is constant, l = l0 (projection)
            return
        for c in range(m):
            Pc = P_t[c]
            ll_t = l_t[leg, c]
            c_l_t = leg_damping_t(phi, q_t[kk, c], leg, P, Pc)
            fc_l_t = leg_friction_level_t(tau_hip, ll, leg, P, (tau_hip_t[c], ll_t, Pc))
            ld_t[c] = flight_leg_rate_t(
                k, c_l, l0, ll, fc_l, (Pc[P_K + leg], c_l_t, Pc[P_L0 + leg], ll_t, fc_l_t)
            )
        return
    # the leg's Jacobian columns (theta, phi) of the toe
    jx = -sL * sth + ll * cg
    jy = sL * cth + ll * sg
    px = ll * cg
    py = ll * sg
    if mode == SLIDE:
        ld = hvy / cg + hy * sg * dg / (cg * cg)
        fa = leg_axial_force(k, c_l, l0, ll, ld, fc_l)
        F = npl * fa
        slip = toe_can_slip(P)
        sdir = mi[MI_SLIDE_DIR_B + leg]
        sig = 0.0
        if slip:
            sig = P[P_MU] * sdir
        den = cg + sig * sg
        gn = F / den
        gt = -sig * gn
        for c in range(m):
            Pc = P_t[c]
            sth_t, cth_t = tr_t[TR_STH, c], tr_t[TR_CTH, c]
            sg_t, cg_t = tr_t[TR_SGB + 2 * leg, c], tr_t[TR_CGB + 2 * leg, c]
            sL_t = hip_offset_t(Pc, leg)
            dth_t = dq_t[ITH, c]
            dg_t = dth_t + dq_t[kk, c]
            hy_t = q_t[IY, c] + sL_t * sth + sL * sth_t
            hvy_t = dq_t[IY, c] + (sL_t * cth + sL * cth_t) * dth + sL * cth * dth_t
            ll_t = l_t[leg, c]
            c_l_t = leg_damping_t(phi, q_t[kk, c], leg, P, Pc)
            fc_l_t = leg_friction_level_t(tau_hip, ll, leg, P, (tau_hip_t[c], ll_t, Pc))
            jx_t = -(sL_t * sth + sL * sth_t) + ll_t * cg + ll * cg_t
            jy_t = sL_t * cth + sL * cth_t + ll_t * sg + ll * sg_t
            px_t = ll_t * cg + ll * cg_t
            py_t = ll_t * sg + ll * sg_t
            lt = (
                hvy_t / cg
                - hvy * cg_t / (cg * cg)
                + (hy_t * sg * dg + hy * sg_t * dg + hy * sg * dg_t) / (cg * cg)
                - 2.0 * hy * sg * dg * cg_t / (cg * cg * cg)
            )
            F_t = Pc[P_NP] * fa + npl * leg_axial_force_t(
                k, c_l, l0, ll, ld, fc_l, (Pc[P_K + leg], c_l_t, Pc[P_L0 + leg], ll_t, lt, fc_l_t)
            )
            sig_t = 0.0
            if slip:
                sig_t = Pc[P_MU] * sdir
            den_t = cg_t + sig_t * sg + sig * sg_t
            gn_t = (F_t - gn * den_t) / den
            gt_t = -sig_t * gn - sig * gn_t
            g[IX, c] += gt_t
            g[IY, c] += gn_t
            g[ITH, c] += jx_t * gt + jx * gt_t + jy_t * gn + jy * gn_t
            g[kk, c] += px_t * gt + px * gt_t + py_t * gn + py * gn_t
            ld_t[c] = lt
        return
    # pinned toe (stick, strut): a loop per mode (a strut's second row in a shared loop
    # slowed the stick's columns by a sixth), the shared part in the two helpers above
    ld = -(hvx * sg - hvy * cg)
    # row across the leg: R = [cg, sg, sL sph + ll, ll], r = -(bx cg + by sg + 2 ld dg)
    sph = sg * cth - cg * sth
    bx = -sL * cth * dth * dth
    by = -sL * sth * dth * dth
    nu0 = nu[0]
    hip = (sth, cth, sg, cg, sL, dth, hvx, hvy)
    if mode == STICK:
        fa = leg_axial_force(k, c_l, l0, ll, ld, fc_l)
        F = npl * fa
        pinned = (hip, (ll, dg, ld, F, jx, jy, px, py, sph, bx, by), nu0)
        for c in range(m):
            Pc = P_t[c]
            t = _pinned_motion_t(c, leg, hip, (dq_t, l_t, tr_t, Pc))
            c_l_t = leg_damping_t(phi, q_t[kk, c], leg, P, Pc)
            fc_l_t = leg_friction_level_t(tau_hip, ll, leg, P, (tau_hip_t[c], t[7], Pc))
            F_t = Pc[P_NP] * fa + npl * leg_axial_force_t(
                k, c_l, l0, ll, ld, fc_l, (Pc[P_K + leg], c_l_t, Pc[P_L0 + leg], t[7], t[8], fc_l_t)
            )
            _pinned_force_and_row_t(c, kk, (g, gr, ddq), pinned, t, F_t)
            ld_t[c] = t[8]
        return
    F = npl * k * (l0 - ll)
    pinned = (hip, (ll, dg, ld, F, jx, jy, px, py, sph, bx, by), nu0)
    # row along the leg: R = [sg, -cg, -sL cph, 0],
    # r = -(bx sg - by cg) + ll dg^2 + 2 w ld + w^2 (ll - l0)
    w = P[P_STRUT_OMEGA]
    cph = cg * cth + sg * sth
    nu1 = nu[1]
    for c in range(m):
        Pc = P_t[c]
        t = _pinned_motion_t(c, leg, hip, (dq_t, l_t, tr_t, Pc))
        sth_t, cth_t, sg_t, cg_t, sL_t, dth_t, dg_t, ll_t, lt = t
        l0_t = Pc[P_L0 + leg]
        F_t = Pc[P_NP] * k * (l0 - ll) + npl * (Pc[P_K + leg] * (l0 - ll) + k * (l0_t - ll_t))
        bx_t, by_t = _pinned_force_and_row_t(c, kk, (g, gr, ddq), pinned, t, F_t)
        w_t = Pc[P_STRUT_OMEGA]
        cph_t = cg_t * cth + cg * cth_t + sg_t * sth + sg * sth_t
        r_t = (
            -(bx_t * sg + bx * sg_t - by_t * cg - by * cg_t)
            + ll_t * dg * dg
            + 2.0 * ll * dg * dg_t
            + 2.0 * (w_t * ld + w * lt)
            + 2.0 * w * w_t * (ll - l0)
            + w * w * (ll_t - l0_t)
        )
        gr[1, c] = _row_t(g, c, ddq, nu1, (sg_t, -cg_t, -(sL_t * cph + sL * cph_t), 0.0, kk, r_t))
        ld_t[c] = lt
