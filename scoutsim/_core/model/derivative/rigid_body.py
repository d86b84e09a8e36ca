"""Derivatives of the rigid-body terms (:mod:`scoutsim._core.model.rigid_body`): the mass
matrix (with the Model II gear pairs of
:func:`~scoutsim._core.model.transmission.add_gear_inertia`), the velocity terms and
gravity.

The primal terms are polynomials in the configuration's sines and cosines (``tr``, slots
``TR_*`` of :mod:`.kinematics`) and in the parameters; their tangents here take the
tangents of the sines and cosines (``tr_t``) as independent inputs (as the projection's
derivative gives them) and those of the parameters (``P_t``), so no relation between a
sine and its cosine is assumed. The mass matrix is never formed: M = sum of the torso's,
the leg bodies' and the gear pairs' terms, and :func:`mass_matrix_times_t` adds each
term's tangent times the accelerations, both halves of its symmetric pair.
"""

from __future__ import annotations

from ...._numba.jit import kernel
from ..hip_unit import geared
from ..kinematics import hip_offset
from ..layout import (
    IALB,
    IPHB,
    ITH,
    IX,
    IY,
    NQ,
    P_D,
    P_G,
    P_IL,
    P_IT,
    P_J1,
    P_J2,
    P_ML,
    P_MT,
    P_N,
    P_NP,
)
from .kinematics import TR_CGB, TR_CTH, TR_SGB, TR_STH, hip_offset_t


@kernel(inline="always")
def _add_pair(out, a, i, j, v):
    """Add to ``out`` the product with ``a`` of a symmetric matrix whose only nonzero
    entries are (i, j) = (j, i) = v (i != j)."""
    out[i] += v * a[j]
    out[j] += v * a[i]


@kernel(inline="always")
def _leg_body_t(P, P_t, leg):
    """Leg ``leg``'s body and its tangents: (mass n_p m_l [kg], its tangent, COM distance
    d [m] from the hip, its tangent, hip offset s L [m] along the torso axis, its
    tangent)."""
    ml = P[P_NP] * P[P_ML + leg]
    ml_t = P_t[P_NP] * P[P_ML + leg] + P[P_NP] * P_t[P_ML + leg]
    return ml, ml_t, P[P_D + leg], P_t[P_D + leg], hip_offset(P, leg), hip_offset_t(P_t, leg)


@kernel(inline="always")
def _pitch_arm_t(body, tr, tr_t, leg):
    """The pitch column of leg ``leg``'s body COM Jacobian, (jth_x, jth_y) =
    (-sL sin th + d cos g, sL cos th + d sin g) [m], and its tangent, for ``body`` the
    value of :func:`_leg_body_t`: (jth_x, jth_x_t, jth_y, jth_y_t)."""
    d, d_t, sL, sL_t = body[2], body[3], body[4], body[5]
    sg = tr[TR_SGB + 2 * leg]
    cg = tr[TR_CGB + 2 * leg]
    sg_t = tr_t[TR_SGB + 2 * leg]
    cg_t = tr_t[TR_CGB + 2 * leg]
    jx = -sL * tr[TR_STH] + d * cg
    jx_t = -sL_t * tr[TR_STH] - sL * tr_t[TR_STH] + d_t * cg + d * cg_t
    jy = sL * tr[TR_CTH] + d * sg
    jy_t = sL_t * tr[TR_CTH] + sL * tr_t[TR_CTH] + d_t * sg + d * sg_t
    return jx, jx_t, jy, jy_t


@kernel(inline="always")
def _gear_inertia_times_t(out, a, P, P_t):
    """Add to ``out`` (7) the tangent of :func:`~scoutsim._core.model.transmission.
    add_gear_inertia`'s terms (the reflected gear inertias [kg m^2], symmetric) times the
    accelerations ``a`` (7) [per s^2]: the entries n_p (J_1 + J_2) on (theta, theta),
    n_p (J_2 + N J_1) on (theta, alpha) and n_p (J_2 + N^2 J_1) on (alpha, alpha)."""
    npl = P[P_NP]
    npl_t = P_t[P_NP]
    for leg in range(2):
        j1 = npl * P[P_J1 + leg]
        j1_t = npl_t * P[P_J1 + leg] + npl * P_t[P_J1 + leg]
        j2_t = npl_t * P[P_J2 + leg] + npl * P_t[P_J2 + leg]
        N = P[P_N + leg]
        N_t = P_t[P_N + leg]
        k = IALB + leg
        out[ITH] += (j1_t + j2_t) * a[ITH]
        _add_pair(out, a, ITH, k, j2_t + N_t * j1 + N * j1_t)
        out[k] += (j2_t + 2.0 * N * N_t * j1 + N * N * j1_t) * a[k]


@kernel(inline="always")
def mass_matrix_times_t(out, a, P, tr, tr_t, P_t):
    """Add to ``out`` (7) the product M_t a [N or N m] of the tangent M_t of the mass
    matrix of :func:`~scoutsim._core.model.rigid_body.mass_matrix_at` (with the gear
    pairs of a geared hip unit, :func:`~scoutsim._core.model.transmission.
    add_gear_inertia`) with the accelerations ``a`` (7) [m/s^2, rad/s^2], along the
    direction of the tangents ``tr_t`` (6) of the sines and cosines ``tr`` (``TR_*``) and
    ``P_t`` of the parameters ``P``. M_t is not formed: each leg body's entries add their
    tangents times ``a``, the off-diagonal ones on both sides of the diagonal."""
    mt_t = P_t[P_MT]
    out[IX] += mt_t * a[IX]
    out[IY] += mt_t * a[IY]
    out[ITH] += P_t[P_IT] * a[ITH]
    for leg in range(2):
        body = _leg_body_t(P, P_t, leg)
        ml, ml_t, d, d_t = body[0], body[1], body[2], body[3]
        il_t = P_t[P_NP] * P[P_IL + leg] + P[P_NP] * P_t[P_IL + leg]
        jx, jx_t, jy, jy_t = _pitch_arm_t(body, tr, tr_t, leg)
        sg = tr[TR_SGB + 2 * leg]
        cg = tr[TR_CGB + 2 * leg]
        # the leg-angle column (d cos g, d sin g) [m]
        px = d * cg
        px_t = d_t * cg + d * tr_t[TR_CGB + 2 * leg]
        py = d * sg
        py_t = d_t * sg + d * tr_t[TR_SGB + 2 * leg]
        k = IPHB + leg
        # translational part m J^T J over (x, y, theta, phi_leg)
        out[IX] += ml_t * a[IX]
        out[IY] += ml_t * a[IY]
        _add_pair(out, a, IX, ITH, ml_t * jx + ml * jx_t)
        _add_pair(out, a, IY, ITH, ml_t * jy + ml * jy_t)
        _add_pair(out, a, IX, k, ml_t * px + ml * px_t)
        _add_pair(out, a, IY, k, ml_t * py + ml * py_t)
        m_tt = ml_t * (jx * jx + jy * jy) + 2.0 * ml * (jx * jx_t + jy * jy_t)
        m_tk = ml_t * (jx * px + jy * py) + ml * (jx_t * px + jx * px_t + jy_t * py + jy * py_t)
        m_kk = ml_t * (px * px + py * py) + 2.0 * ml * (px * px_t + py * py_t)
        # with the rotational part n_p I_l on (theta, theta), (theta, phi), (phi, phi)
        out[ITH] += (m_tt + il_t) * a[ITH]
        _add_pair(out, a, ITH, k, m_tk + il_t)
        out[k] += (m_kk + il_t) * a[k]
    if geared(P):
        _gear_inertia_times_t(out, a, P, P_t)


@kernel(inline="always")
def coriolis_t(h_t, dq, dq_t, P, tr, tr_t, P_t):
    """Fill ``h_t`` (7) with the tangent [N, N m] of the velocity terms h of
    :func:`~scoutsim._core.model.rigid_body.coriolis_at` at the velocities ``dq`` (7)
    [m/s, rad/s], the sines and cosines ``tr`` (``TR_*``) and the parameters ``P``, along
    the tangents ``dq_t``, ``tr_t`` and ``P_t``."""
    for i in range(NQ):
        h_t[i] = 0.0
    dth = dq[ITH]
    dth_t = dq_t[ITH]
    w = dth * dth
    w_t = 2.0 * dth * dth_t
    sth = tr[TR_STH]
    cth = tr[TR_CTH]
    sth_t = tr_t[TR_STH]
    cth_t = tr_t[TR_CTH]
    for leg in range(2):
        body = _leg_body_t(P, P_t, leg)
        ml, ml_t, d, d_t, sL, sL_t = body
        jx, jx_t, jy, jy_t = _pitch_arm_t(body, tr, tr_t, leg)
        sg = tr[TR_SGB + 2 * leg]
        cg = tr[TR_CGB + 2 * leg]
        sg_t = tr_t[TR_SGB + 2 * leg]
        cg_t = tr_t[TR_CGB + 2 * leg]
        k = IPHB + leg
        dg = dth + dq[k]
        v = dg * dg
        v_t = 2.0 * dg * (dth_t + dq_t[k])
        # the leg body COM's velocity-product acceleration (ax, ay) [m/s^2]
        ax = -sL * cth * w - d * sg * v
        ax_t = -(sL_t * cth + sL * cth_t) * w - sL * cth * w_t
        ax_t -= (d_t * sg + d * sg_t) * v + d * sg * v_t
        ay = -sL * sth * w + d * cg * v
        ay_t = -(sL_t * sth + sL * sth_t) * w - sL * sth * w_t
        ay_t += (d_t * cg + d * cg_t) * v + d * cg * v_t
        h_t[IX] += ml_t * ax + ml * ax_t
        h_t[IY] += ml_t * ay + ml * ay_t
        p = jx * ax + jy * ay
        p_t = jx_t * ax + jx * ax_t + jy_t * ay + jy * ay_t
        h_t[ITH] += ml_t * p + ml * p_t
        r = cg * ax + sg * ay
        r_t = cg_t * ax + cg * ax_t + sg_t * ay + sg * ay_t
        h_t[k] += (ml_t * d + ml * d_t) * r + ml * d * r_t


@kernel(inline="always")
def add_gravity_t(Q_t, P, tr, tr_t, P_t):
    """Add to ``Q_t`` (7) the tangent [N, N m] of the generalized gravity forces
    :func:`~scoutsim._core.model.rigid_body.add_gravity_at` adds (torso and leg bodies) at
    the sines and cosines ``tr`` (``TR_*``) and the parameters ``P``, along the tangents
    ``tr_t`` and ``P_t``."""
    grav = P[P_G]
    grav_t = P_t[P_G]
    Q_t[IY] -= P_t[P_MT] * grav + P[P_MT] * grav_t
    cth = tr[TR_CTH]
    cth_t = tr_t[TR_CTH]
    for leg in range(2):
        ml, ml_t, d, d_t, sL, sL_t = _leg_body_t(P, P_t, leg)
        mlg = ml * grav
        mlg_t = ml_t * grav + ml * grav_t
        sg = tr[TR_SGB + 2 * leg]
        sg_t = tr_t[TR_SGB + 2 * leg]
        # the leg body COM's horizontal distance from the torso COM (sL cos th + d sin g)
        u = sL * cth + d * sg
        u_t = sL_t * cth + sL * cth_t + d_t * sg + d * sg_t
        Q_t[IY] -= mlg_t
        Q_t[ITH] -= mlg_t * u + mlg * u_t
        Q_t[IPHB + leg] -= mlg_t * d * sg + mlg * (d_t * sg + d * sg_t)
