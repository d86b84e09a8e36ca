"""Rigid-body terms of the planar model (compiled): mass matrix, velocity terms, gravity and
energies (docs/specification.md sections 1-2, 5; paper eq. 1, Table III; docs/model.md
derives every term).

Bodies: the torso (m_t, I_t at (x, y)); per virtual leg a rigid leg body of mass n_p m_l and
inertia n_p I_l about its COM at hip + d (sin g, -cos g) (d = leg_com_distance); in Model II
the gear pairs of the hip unit (model/transmission.py). With the body Jacobians J_b,

    M = sum_b m_b J_b^T J_b + I_b J_wb^T J_wb,     h = sum_b m_b J_b^T (dJ_b/dt dq),

and M ddq + h = Q. Each term has one source, the ``*_at`` kernels below, which take the
sines and cosines of the configuration (for a pinned toe the projection gives them straight
from the toe-hip vector); :func:`mass_matrix`, :func:`coriolis`, :func:`potential_energy`
and :func:`kinetic_energy` are the same terms at a configuration q.
"""

from __future__ import annotations

import math

import numpy as np

from ..._numba.jit import allocating, kernel
from .hip_unit import geared
from .kinematics import hip_offset
from .layout import (
    IL_B,
    IPHB,
    IPHF,
    ITH,
    IX,
    IY,
    NQ,
    P_D,
    P_G,
    P_IL,
    P_IT,
    P_K,
    P_L0,
    P_ML,
    P_MT,
    P_NP,
)
from .transmission import add_gear_inertia, belt_energy


@kernel(inline="always")
def mass_matrix_at(M, P, sth, cth, sg0, cg0, sg1, cg1):
    """Fill M (7 x 7, symmetric) with the generalized mass matrix at pitch sin/cos
    (sth, cth) and leg angles from the vertical sin/cos (sg0, cg0) back, (sg1, cg1)
    front."""
    for i in range(NQ):
        for j in range(NQ):
            M[i, j] = 0.0
    npl = P[P_NP]
    M[0, 0] += P[P_MT]
    M[1, 1] += P[P_MT]
    M[2, 2] += P[P_IT]
    for leg in range(2):
        ml = npl * P[P_ML + leg]
        il = npl * P[P_IL + leg]
        d = P[P_D + leg]
        sL = hip_offset(P, leg)
        sg = sg0 if leg == 0 else sg1
        cg = cg0 if leg == 0 else cg1
        jth_x = -sL * sth + d * cg
        jth_y = sL * cth + d * sg
        jph_x = d * cg
        jph_y = d * sg
        k = IPHB + leg
        # translational part m J^T J over coordinates (x, y, theta, phi_leg)
        M[0, 0] += ml
        M[1, 1] += ml
        M[0, 2] += ml * jth_x
        M[1, 2] += ml * jth_y
        M[0, k] += ml * jph_x
        M[1, k] += ml * jph_y
        M[2, 2] += ml * (jth_x * jth_x + jth_y * jth_y)
        M[2, k] += ml * (jth_x * jph_x + jth_y * jph_y)
        M[k, k] += ml * (jph_x * jph_x + jph_y * jph_y)
        # rotational part (leg angular velocity dtheta + dphi)
        M[2, 2] += il
        M[2, k] += il
        M[k, k] += il
    if geared(P):
        add_gear_inertia(M, P)
    for i in range(NQ):
        for j in range(i):
            M[i, j] = M[j, i]


@kernel(inline="always")
def coriolis_at(h, dq, P, sth, cth, sg0, cg0, sg1, cg1):
    """Fill h (7) with the velocity-product terms of M ddq + h = Q (leg bodies only; the
    torso and the gears turn about fixed points of their own coordinates)."""
    for i in range(NQ):
        h[i] = 0.0
    dth = dq[ITH]
    for leg in range(2):
        ml = P[P_NP] * P[P_ML + leg]
        d = P[P_D + leg]
        sL = hip_offset(P, leg)
        sg = sg0 if leg == 0 else sg1
        cg = cg0 if leg == 0 else cg1
        dg = dth + dq[IPHB + leg]
        ax = -sL * cth * dth * dth - d * sg * dg * dg
        ay = -sL * sth * dth * dth + d * cg * dg * dg
        jth_x = -sL * sth + d * cg
        jth_y = sL * cth + d * sg
        h[IX] += ml * ax
        h[IY] += ml * ay
        h[ITH] += ml * (jth_x * ax + jth_y * ay)
        h[IPHB + leg] += ml * d * (cg * ax + sg * ay)


@kernel(inline="always")
def add_gravity_at(Q, P, sth, cth, sg0, cg0, sg1, cg1):
    """Add the generalized gravity forces of the torso and the leg bodies to Q."""
    grav = P[P_G]
    Q[IY] -= P[P_MT] * grav
    for leg in range(2):
        mlg = P[P_NP] * P[P_ML + leg] * grav
        d = P[P_D + leg]
        sL = hip_offset(P, leg)
        sg = sg0 if leg == 0 else sg1
        Q[IY] -= mlg
        Q[ITH] -= mlg * (sL * cth + d * sg)
        Q[IPHB + leg] -= mlg * d * sg


@kernel(inline="always")
def potential_energy_at(q, l, P, sth, cg0, cg1):
    """Potential energy [J]: gravity (torso and leg bodies), the leg springs (Table III k,
    rest length l0) and the Model II belt springs."""
    grav = P[P_G]
    npl = P[P_NP]
    e = P[P_MT] * grav * q[IY]
    for leg in range(2):
        ml = npl * P[P_ML + leg]
        sL = hip_offset(P, leg)
        cg = cg0 if leg == 0 else cg1
        yc = q[IY] + sL * sth - P[P_D + leg] * cg
        e += ml * grav * yc
        dl = P[P_L0 + leg] - l[leg]
        e += 0.5 * npl * P[P_K + leg] * dl * dl
        if geared(P):
            e += belt_energy(q, leg, P)
    return e


@kernel(inline="always")
def kinetic_energy_at(M, dq):
    """Kinetic energy 1/2 dq^T M dq [J] for the mass matrix M."""
    e = 0.0
    for i in range(NQ):
        acc = 0.0
        for j in range(NQ):
            acc += M[i, j] * dq[j]
        e += dq[i] * acc
    return 0.5 * e


@kernel(inline="always")
def _trig(q):
    sth = math.sin(q[ITH])
    cth = math.cos(q[ITH])
    g0 = q[ITH] + q[IPHB]
    g1 = q[ITH] + q[IPHF]
    return sth, cth, math.sin(g0), math.cos(g0), math.sin(g1), math.cos(g1)


@kernel
def mass_matrix(q, P, M):
    """Fill M (7 x 7) with the generalized mass matrix at q (docs/specification.md
    sections 2, 5)."""
    sth, cth, sg0, cg0, sg1, cg1 = _trig(q)
    mass_matrix_at(M, P, sth, cth, sg0, cg0, sg1, cg1)


@kernel
def coriolis(q, dq, P, h):
    """Fill h (7) with the velocity-product terms at (q, dq), M ddq + h = Q."""
    sth, cth, sg0, cg0, sg1, cg1 = _trig(q)
    coriolis_at(h, dq, P, sth, cth, sg0, cg0, sg1, cg1)


@kernel
def potential_energy(q, l, P):
    """Gravity + leg springs + Model II belt springs [J] at q, leg lengths l."""
    sth, cth, sg0, cg0, sg1, cg1 = _trig(q)
    return potential_energy_at(q, l, P, sth, cg0, cg1)


@kernel
def kinetic_energy_ws(q, dq, P, M):
    """Kinetic energy 1/2 dq^T M(q) dq [J], the mass matrix built in the scratch ``M``
    (7 x 7)."""
    mass_matrix(q, P, M)
    return kinetic_energy_at(M, dq)


@allocating
def kinetic_energy(q, dq, P):
    """Kinetic energy 1/2 dq^T M(q) dq [J]."""
    return kinetic_energy_ws(q, dq, P, np.empty((NQ, NQ)))


@kernel
def state_energy_ws(s, P, M):
    """:func:`state_energy` without allocation: the mass matrix is built in the scratch
    ``M`` (7 x 7)."""
    return kinetic_energy_ws(s[0:NQ], s[NQ : 2 * NQ], P, M) + potential_energy(
        s[0:NQ], s[IL_B : IL_B + 2], P
    )


@allocating
def state_energy(s, P):
    """Total mechanical energy of a full state vector s [J]: kinetic plus potential (gravity,
    leg springs, Model II belts); the same quantity as the ``energy`` output."""
    return state_energy_ws(s, P, np.empty((NQ, NQ)))
