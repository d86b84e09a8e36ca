"""Derivative of a leg's ground contact (:func:`scoutsim._core.model.contact.leg_contact`)
and of its telescopic leg (:mod:`scoutsim._core.model.leg`).

The contact gives the generalized forces of the leg force and the ground force (added to
Q), the constraint rows R and their right-hand sides r, and the leg-length rate. In the
tangent of the KKT system ``M ddq + R^T nu = Q - h``, ``R ddq = r`` the rows enter through
``R_t^T nu`` and ``r_t - R_t ddq`` (``ddq``, ``nu`` the primal solution): the functions here
add the first to the right-hand side's tangent ``g`` and return the second, row by row,
without forming R_t.
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
def _row_t(g, gr, ddq, nu, row_t):
    """Add -R_t^T nu of one row to ``g`` and return r_t - R_t ddq; ``row_t`` = (the row's
    tangent along x, y, theta, the leg angle, the leg angle's index, r_t)."""
    rx, ry, rth, rph, kk, r_t = row_t
    g[IX] -= rx * nu
    g[IY] -= ry * nu
    g[ITH] -= rth * nu
    g[kk] -= rph * nu
    return r_t - (rx * ddq[IX] + ry * ddq[IY] + rth * ddq[ITH] + rph * ddq[kk])


@kernel(inline="always")
def leg_contact_t(leg, P, mi, primal, tangents, out):
    """The tangent of :func:`~scoutsim._core.model.contact.leg_contact` of virtual leg
    ``leg`` in its contact mode.

    ``primal`` = (q, dq, l, tr, tau_hip, ddq, nu): the projected state, its sines and
    cosines (``TR_*``), the torque the hip applies to one physical leg [N m], the primal
    KKT solution's accelerations (7) and the multipliers of this leg's rows (its first
    rows from ``nu[0]`` on); ``tangents`` = (q_t, dq_t, l_t, tr_t, tau_hip_t, P_t).
    ``out`` = (g, gr): adds the tangent of the generalized forces less R_t^T nu to ``g``
    (7) and writes r_t - R_t ddq of this leg's rows to ``gr[0]``, ``gr[1]``. Returns the
    leg-length rate's tangent [m/s]."""
    q, dq, l, tr, tau_hip, ddq, nu = primal
    q_t, dq_t, l_t, tr_t, tau_hip_t, P_t = tangents
    g, gr = out
    massless = is_set(P[P_MASSLESS])
    npl = P[P_NP]
    npl_t = P_t[P_NP]
    l0 = P[P_L0 + leg]
    l0_t = P_t[P_L0 + leg]
    k = P[P_K + leg]
    k_t = P_t[P_K + leg]
    mode = mi[MI_CONTACT_B + leg]
    sth, cth = tr[TR_STH], tr[TR_CTH]
    sth_t, cth_t = tr_t[TR_STH], tr_t[TR_CTH]
    sg, cg = tr[TR_SGB + 2 * leg], tr[TR_CGB + 2 * leg]
    sg_t, cg_t = tr_t[TR_SGB + 2 * leg], tr_t[TR_CGB + 2 * leg]
    sL = hip_offset(P, leg)
    sL_t = hip_offset_t(P_t, leg)
    kk = IPHB + leg
    dth = dq[ITH]
    dth_t = dq_t[ITH]
    dg = dth + dq[kk]
    dg_t = dth_t + dq_t[kk]
    hy = q[IY] + sL * sth
    hy_t = q_t[IY] + sL_t * sth + sL * sth_t
    hvx = dq[IX] - sL * sth * dth
    hvy = dq[IY] + sL * cth * dth
    hvx_t = dq_t[IX] - (sL_t * sth + sL * sth_t) * dth - sL * sth * dth_t
    hvy_t = dq_t[IY] + (sL_t * cth + sL * cth_t) * dth + sL * cth * dth_t
    ll = l[leg]
    ll_t = l_t[leg]
    c_l = leg_damping(q[kk], leg, P)
    c_l_t = leg_damping_t(q[kk], q_t[kk], leg, P, P_t)
    fc_l = leg_friction_level(tau_hip, ll, leg, P)
    fc_l_t = leg_friction_level_t(tau_hip, ll, leg, P, (tau_hip_t, ll_t, P_t))
    if mode != STICK and mode != STRUT and mode != SLIDE:
        if massless:
            return 0.0  # the prescribed angle's row is constant, l = l0 (projection)
        return flight_leg_rate_t(k, c_l, l0, ll, fc_l, (k_t, c_l_t, l0_t, ll_t, fc_l_t))
    # the leg's Jacobian columns (theta, phi) of the toe and their tangents
    jx = -sL * sth + ll * cg
    jy = sL * cth + ll * sg
    jx_t = -(sL_t * sth + sL * sth_t) + ll_t * cg + ll * cg_t
    jy_t = sL_t * cth + sL * cth_t + ll_t * sg + ll * sg_t
    px = ll * cg
    py = ll * sg
    px_t = ll_t * cg + ll * cg_t
    py_t = ll_t * sg + ll * sg_t
    if mode == SLIDE:
        ld = hvy / cg + hy * sg * dg / (cg * cg)
        ld_t = (
            hvy_t / cg
            - hvy * cg_t / (cg * cg)
            + (hy_t * sg * dg + hy * sg_t * dg + hy * sg * dg_t) / (cg * cg)
            - 2.0 * hy * sg * dg * cg_t / (cg * cg * cg)
        )
        fa = leg_axial_force(k, c_l, l0, ll, ld, fc_l)
        F = npl * fa
        F_t = npl_t * fa + npl * leg_axial_force_t(
            k, c_l, l0, ll, ld, fc_l, (k_t, c_l_t, l0_t, ll_t, ld_t, fc_l_t)
        )
        sig = 0.0
        sig_t = 0.0
        if toe_can_slip(P):
            sig = P[P_MU] * mi[MI_SLIDE_DIR_B + leg]
            sig_t = P_t[P_MU] * mi[MI_SLIDE_DIR_B + leg]
        den = cg + sig * sg
        den_t = cg_t + sig_t * sg + sig * sg_t
        gn = F / den
        gn_t = (F_t - gn * den_t) / den
        gt = -sig * gn
        gt_t = -sig_t * gn - sig * gn_t
        g[IX] += gt_t
        g[IY] += gn_t
        g[ITH] += jx_t * gt + jx * gt_t + jy_t * gn + jy * gn_t
        g[kk] += px_t * gt + px * gt_t + py_t * gn + py * gn_t
        return ld_t
    # pinned toe (stick, strut)
    ld = -(hvx * sg - hvy * cg)
    ld_t = -(hvx_t * sg + hvx * sg_t - hvy_t * cg - hvy * cg_t)
    if mode == STRUT:
        F = npl * k * (l0 - ll)
        F_t = npl_t * k * (l0 - ll) + npl * (k_t * (l0 - ll) + k * (l0_t - ll_t))
    else:
        fa = leg_axial_force(k, c_l, l0, ll, ld, fc_l)
        F = npl * fa
        F_t = npl_t * fa + npl * leg_axial_force_t(
            k, c_l, l0, ll, ld, fc_l, (k_t, c_l_t, l0_t, ll_t, ld_t, fc_l_t)
        )
    fx = -F * sg
    fy = F * cg
    fx_t = -F_t * sg - F * sg_t
    fy_t = F_t * cg + F * cg_t
    g[IX] += fx_t
    g[IY] += fy_t
    g[ITH] += jx_t * fx + jx * fx_t + jy_t * fy + jy * fy_t
    g[kk] += px_t * fx + px * fx_t + py_t * fy + py * fy_t
    # row across the leg: R = [cg, sg, sL sph + ll, ll], r = -(bx cg + by sg + 2 ld dg)
    sph = sg * cth - cg * sth
    sph_t = sg_t * cth + sg * cth_t - cg_t * sth - cg * sth_t
    bx = -sL * cth * dth * dth
    by = -sL * sth * dth * dth
    bx_t = -(sL_t * cth + sL * cth_t) * dth * dth - 2.0 * sL * cth * dth * dth_t
    by_t = -(sL_t * sth + sL * sth_t) * dth * dth - 2.0 * sL * sth * dth * dth_t
    r_t = -(bx_t * cg + bx * cg_t + by_t * sg + by * sg_t + 2.0 * (ld_t * dg + ld * dg_t))
    gr[0] = _row_t(g, gr, ddq, nu[0], (cg_t, sg_t, sL_t * sph + sL * sph_t + ll_t, ll_t, kk, r_t))
    if mode == STRUT:
        # row along the leg: R = [sg, -cg, -sL cph, 0],
        # r = -(bx sg - by cg) + ll dg^2 + 2 w ld + w^2 (ll - l0)
        w = P[P_STRUT_OMEGA]
        w_t = P_t[P_STRUT_OMEGA]
        cph = cg * cth + sg * sth
        cph_t = cg_t * cth + cg * cth_t + sg_t * sth + sg * sth_t
        r_t = (
            -(bx_t * sg + bx * sg_t - by_t * cg - by * cg_t)
            + ll_t * dg * dg
            + 2.0 * ll * dg * dg_t
            + 2.0 * (w_t * ld + w * ld_t)
            + 2.0 * w * w_t * (ll - l0)
            + w * w * (ll_t - l0_t)
        )
        gr[1] = _row_t(g, gr, ddq, nu[1], (sg_t, -cg_t, -(sL_t * cph + sL * cph_t), 0.0, kk, r_t))
    return ld_t
