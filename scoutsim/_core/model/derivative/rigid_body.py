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

Each function takes m directions at once: the tangents of the sines and cosines, of the
velocities and of its outputs have a column per direction ((NTR, m), (NQ, m)), those of the
parameters a row (``P_t`` (m, NP)); the tangent-free products are formed once for all
columns, and each column's arithmetic is that of one direction alone.
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
def _add_pair(out, i, j, c, v, ai, aj):
    """Add to column c of ``out`` the product of a symmetric matrix whose only nonzero
    entries are (i, j) = (j, i) = v (i != j) with the accelerations a, of which ``ai`` =
    a[i] and ``aj`` = a[j]."""
    out[i, c] += v * aj
    out[j, c] += v * ai


@kernel(inline="always")
def _leg_body(P, leg):
    """Leg ``leg``'s body: (mass n_p m_l [kg], COM distance d [m] from the hip, hip offset
    s L [m] along the torso axis)."""
    return P[P_NP] * P[P_ML + leg], P[P_D + leg], hip_offset(P, leg)


@kernel(inline="always")
def _leg_body_t(P, Pc, leg):
    """The tangents of :func:`_leg_body`'s (mass, COM distance, hip offset) along the
    parameters' tangents ``Pc`` (NP, one direction's)."""
    ml_t = Pc[P_NP] * P[P_ML + leg] + P[P_NP] * Pc[P_ML + leg]
    return ml_t, Pc[P_D + leg], hip_offset_t(Pc, leg)


@kernel(inline="always")
def _pitch_arm(d, sL, tr, leg):
    """The pitch column of leg ``leg``'s body COM Jacobian, (jth_x, jth_y) =
    (-sL sin th + d cos g, sL cos th + d sin g) [m], for the COM distance ``d`` and the
    hip offset ``sL`` of :func:`_leg_body`."""
    jx = -sL * tr[TR_STH] + d * tr[TR_CGB + 2 * leg]
    jy = sL * tr[TR_CTH] + d * tr[TR_SGB + 2 * leg]
    return jx, jy


@kernel(inline="always")
def _pitch_arm_t(d, d_t, sL, sL_t, tr, tr_t, leg, c):
    """The tangent (jth_x_t, jth_y_t) of :func:`_pitch_arm` along column c of ``tr_t``
    (NTR, m) and the tangents ``d_t``, ``sL_t`` of :func:`_leg_body_t`."""
    jx_t = (
        -sL_t * tr[TR_STH]
        - sL * tr_t[TR_STH, c]
        + d_t * tr[TR_CGB + 2 * leg]
        + d * tr_t[TR_CGB + 2 * leg, c]
    )
    jy_t = (
        sL_t * tr[TR_CTH]
        + sL * tr_t[TR_CTH, c]
        + d_t * tr[TR_SGB + 2 * leg]
        + d * tr_t[TR_SGB + 2 * leg, c]
    )
    return jx_t, jy_t


@kernel(inline="always")
def _gear_inertia_times_t(out, a, P, P_t):
    """Add to each column c of ``out`` (NQ, m) the tangent along row c of ``P_t`` (m, NP)
    of :func:`~scoutsim._core.model.transmission.add_gear_inertia`'s terms (the reflected
    gear inertias [kg m^2], symmetric) times the accelerations ``a`` (NQ) [per s^2]: the
    entries n_p (J_1 + J_2) on (theta, theta), n_p (J_2 + N J_1) on (theta, alpha) and
    n_p (J_2 + N^2 J_1) on (alpha, alpha)."""
    m = out.shape[1]
    npl = P[P_NP]
    ath = a[ITH]
    for leg in range(2):
        J1 = P[P_J1 + leg]
        J2 = P[P_J2 + leg]
        j1 = npl * J1
        N = P[P_N + leg]
        N2 = 2.0 * N
        NN = N * N
        k = IALB + leg
        ak = a[k]
        for c in range(m):
            Pc = P_t[c]
            npl_t = Pc[P_NP]
            j1_t = npl_t * J1 + npl * Pc[P_J1 + leg]
            j2_t = npl_t * J2 + npl * Pc[P_J2 + leg]
            N_t = Pc[P_N + leg]
            out[ITH, c] += (j1_t + j2_t) * ath
            _add_pair(out, ITH, k, c, j2_t + N_t * j1 + N * j1_t, ath, ak)
            out[k, c] += (j2_t + N2 * N_t * j1 + NN * j1_t) * ak


@kernel(inline="always")
def mass_matrix_times_t(out, a, P, tr, tr_t, P_t):
    """Add to each column c of ``out`` (NQ, m) the product M_t a [N or N m] of the tangent
    M_t of the mass matrix of :func:`~scoutsim._core.model.rigid_body.mass_matrix_at` (with
    the gear pairs of a geared hip unit, :func:`~scoutsim._core.model.transmission.
    add_gear_inertia`) with the accelerations ``a`` (NQ) [m/s^2, rad/s^2], the same for
    every column, along direction c: column c of the tangents ``tr_t`` (NTR, m) of the
    sines and cosines ``tr`` (``TR_*``) and row c of the tangents ``P_t`` (m, NP) of the
    parameters ``P``. M_t is not formed: each leg body's entries add their tangents times
    ``a``, the off-diagonal ones on both sides of the diagonal."""
    m = out.shape[1]
    ax = a[IX]
    ay = a[IY]
    ath = a[ITH]
    for c in range(m):
        mt_t = P_t[c, P_MT]
        out[IX, c] += mt_t * ax
        out[IY, c] += mt_t * ay
        out[ITH, c] += P_t[c, P_IT] * ath
    npl = P[P_NP]
    for leg in range(2):
        ml, d, sL = _leg_body(P, leg)
        il = P[P_IL + leg]
        jx, jy = _pitch_arm(d, sL, tr, leg)
        sg = tr[TR_SGB + 2 * leg]
        cg = tr[TR_CGB + 2 * leg]
        # the leg-angle column (d cos g, d sin g) [m]
        px = d * cg
        py = d * sg
        ml2 = 2.0 * ml
        jj = jx * jx + jy * jy
        jp = jx * px + jy * py
        pp = px * px + py * py
        k = IPHB + leg
        ak = a[k]
        for c in range(m):
            Pc = P_t[c]
            ml_t, d_t, sL_t = _leg_body_t(P, Pc, leg)
            il_t = Pc[P_NP] * il + npl * Pc[P_IL + leg]
            jx_t, jy_t = _pitch_arm_t(d, d_t, sL, sL_t, tr, tr_t, leg, c)
            px_t = d_t * cg + d * tr_t[TR_CGB + 2 * leg, c]
            py_t = d_t * sg + d * tr_t[TR_SGB + 2 * leg, c]
            # translational part m J^T J over (x, y, theta, phi_leg)
            out[IX, c] += ml_t * ax
            out[IY, c] += ml_t * ay
            _add_pair(out, IX, ITH, c, ml_t * jx + ml * jx_t, ax, ath)
            _add_pair(out, IY, ITH, c, ml_t * jy + ml * jy_t, ay, ath)
            _add_pair(out, IX, k, c, ml_t * px + ml * px_t, ax, ak)
            _add_pair(out, IY, k, c, ml_t * py + ml * py_t, ay, ak)
            m_tt = ml_t * jj + ml2 * (jx * jx_t + jy * jy_t)
            m_tk = ml_t * jp + ml * (jx_t * px + jx * px_t + jy_t * py + jy * py_t)
            m_kk = ml_t * pp + ml2 * (px * px_t + py * py_t)
            # with the rotational part n_p I_l on (theta, theta), (theta, phi), (phi, phi)
            out[ITH, c] += (m_tt + il_t) * ath
            _add_pair(out, ITH, k, c, m_tk + il_t, ath, ak)
            out[k, c] += (m_kk + il_t) * ak
    if geared(P):
        _gear_inertia_times_t(out, a, P, P_t)


@kernel(inline="always")
def coriolis_t(h_t, dq, dq_t, P, tr, tr_t, P_t):
    """Fill each column c of ``h_t`` (NQ, m) with the tangent [N, N m] of the velocity
    terms h of :func:`~scoutsim._core.model.rigid_body.coriolis_at` at the velocities
    ``dq`` (NQ) [m/s, rad/s], the sines and cosines ``tr`` (``TR_*``) and the parameters
    ``P``, along direction c: column c of the tangents ``dq_t`` (NQ, m) and ``tr_t``
    (NTR, m), row c of ``P_t`` (m, NP)."""
    m = h_t.shape[1]
    for i in range(NQ):
        for c in range(m):
            h_t[i, c] = 0.0
    dth = dq[ITH]
    w = dth * dth
    dth2 = 2.0 * dth
    sth = tr[TR_STH]
    cth = tr[TR_CTH]
    for leg in range(2):
        ml, d, sL = _leg_body(P, leg)
        jx, jy = _pitch_arm(d, sL, tr, leg)
        sg = tr[TR_SGB + 2 * leg]
        cg = tr[TR_CGB + 2 * leg]
        k = IPHB + leg
        dg = dth + dq[k]
        v = dg * dg
        dg2 = 2.0 * dg
        # the leg body COM's velocity-product acceleration (ax, ay) [m/s^2]
        ax = -sL * cth * w - d * sg * v
        ay = -sL * sth * w + d * cg * v
        sLc = sL * cth
        sLs = sL * sth
        dsg = d * sg
        dcg = d * cg
        p = jx * ax + jy * ay
        r = cg * ax + sg * ay
        mld = ml * d
        for c in range(m):
            ml_t, d_t, sL_t = _leg_body_t(P, P_t[c], leg)
            jx_t, jy_t = _pitch_arm_t(d, d_t, sL, sL_t, tr, tr_t, leg, c)
            sth_t = tr_t[TR_STH, c]
            cth_t = tr_t[TR_CTH, c]
            sg_t = tr_t[TR_SGB + 2 * leg, c]
            cg_t = tr_t[TR_CGB + 2 * leg, c]
            dth_t = dq_t[ITH, c]
            w_t = dth2 * dth_t
            v_t = dg2 * (dth_t + dq_t[k, c])
            ax_t = -(sL_t * cth + sL * cth_t) * w - sLc * w_t
            ax_t -= (d_t * sg + d * sg_t) * v + dsg * v_t
            ay_t = -(sL_t * sth + sL * sth_t) * w - sLs * w_t
            ay_t += (d_t * cg + d * cg_t) * v + dcg * v_t
            h_t[IX, c] += ml_t * ax + ml * ax_t
            h_t[IY, c] += ml_t * ay + ml * ay_t
            p_t = jx_t * ax + jx * ax_t + jy_t * ay + jy * ay_t
            h_t[ITH, c] += ml_t * p + ml * p_t
            r_t = cg_t * ax + cg * ax_t + sg_t * ay + sg * ay_t
            h_t[k, c] += (ml_t * d + ml * d_t) * r + mld * r_t


@kernel(inline="always")
def add_gravity_t(Q_t, P, tr, tr_t, P_t):
    """Add to each column c of ``Q_t`` (NQ, m) the tangent [N, N m] of the generalized
    gravity forces :func:`~scoutsim._core.model.rigid_body.add_gravity_at` adds (torso and
    leg bodies) at the sines and cosines ``tr`` (``TR_*``) and the parameters ``P``, along
    direction c: column c of the tangents ``tr_t`` (NTR, m), row c of ``P_t`` (m, NP)."""
    m = Q_t.shape[1]
    grav = P[P_G]
    mt = P[P_MT]
    for c in range(m):
        Q_t[IY, c] -= P_t[c, P_MT] * grav + mt * P_t[c, P_G]
    cth = tr[TR_CTH]
    for leg in range(2):
        ml, d, sL = _leg_body(P, leg)
        mlg = ml * grav
        sg = tr[TR_SGB + 2 * leg]
        # the leg body COM's horizontal distance from the torso COM (sL cos th + d sin g)
        u = sL * cth + d * sg
        k = IPHB + leg
        for c in range(m):
            Pc = P_t[c]
            ml_t, d_t, sL_t = _leg_body_t(P, Pc, leg)
            mlg_t = ml_t * grav + ml * Pc[P_G]
            cth_t = tr_t[TR_CTH, c]
            sg_t = tr_t[TR_SGB + 2 * leg, c]
            u_t = sL_t * cth + sL * cth_t + d_t * sg + d * sg_t
            Q_t[IY, c] -= mlg_t
            Q_t[ITH, c] -= mlg_t * u + mlg * u_t
            Q_t[k, c] -= mlg_t * d * sg + mlg * (d_t * sg + d * sg_t)
