"""The touchdown impact (compiled): a rigid-body impact onto the constraints of the new
modes (docs/specification.md section 3; docs/model.md "Impact")."""

from __future__ import annotations

import math

import numpy as np

from ..._numba.jit import allocating
from .flags import is_set
from .hip_unit import geared
from .kinematics import hip_offset, project, project_state
from .kkt import MAX_ROWS, solve_dense
from .layout import (
    FLIGHT,
    IALB,
    IALF,
    IL_B,
    IMP_ENERGY_LOST,
    IMP_NORMAL,
    IMP_TANGENT,
    IPHB,
    IPHF,
    ITH,
    IX,
    IY,
    MI_CONTACT_B,
    MI_MOTOR_B,
    NIMP,
    NIMP_LEG,
    NQ,
    P_MASSLESS,
    P_TD_WORLD,
    ROW_GEAR,
    ROW_MASSLESS,
    ROW_TOE_ACROSS,
    ROW_TOE_ALONG,
    SLIP_POS,
    STICK,
    STRUT,
)
from .rigid_body import kinetic_energy_at, mass_matrix
from .transmission import motor_mode_from_rate


@allocating
def impact(s, P, mi, mf, out):
    """Rigid-body impact onto the constraints of the current modes, in place.

    Solves ``[M R^T; R 0] [dq+; Lambda] = [M dq-; 0]`` where R holds the velocity
    constraints that act impulsively: every pinned toe (perpendicular and, for a strut,
    axial), massless flight legs, and with a geared hip unit (Model II) a rigid belt for
    each leg (the belt damper is far stiffer than the gear-train inertia over an impact:
    alpha' = phi' after it; the damper acts across a backlash's play too, model/backlash.py).
    Stiction cannot carry an impulse, so stuck motor joints do not constrain it. Every row
    is homogeneous, so dq+ is the M-orthogonal projection of dq- onto the constrained
    velocities and the kinetic energy lost, 1/2 |dq- - dq+|_M^2, is never negative.

    out[leg * NIMP_LEG + IMP_NORMAL], out[leg * NIMP_LEG + IMP_TANGENT]: normal and
    tangential impulse [N s] of each pinned toe; out[IMP_ENERGY_LOST]: kinetic energy lost
    [J] (layout ``IMP_*``, NIMP slots). Returns False if singular.
    """
    gear = geared(P)
    nact = 7 if gear else 5
    q = s[0:NQ].copy()
    dq = s[NQ : 2 * NQ].copy()
    l = s[IL_B : IL_B + 2].copy()
    # stiction does not act impulsively: treat motor joints as free while projecting
    mi2 = mi.copy()
    mi2[MI_MOTOR_B] = SLIP_POS  # any mode but STUCK
    mi2[MI_MOTOR_B + 1] = SLIP_POS
    project(q, dq, l, P, mi2, mf)
    M = np.empty((NQ, NQ))
    mass_matrix(q, P, M)
    dq0 = s[NQ : 2 * NQ].copy()
    if not gear:
        dq0[IALB] = dq0[IPHB]
        dq0[IALF] = dq0[IPHF]
    ke0 = kinetic_energy_at(M, dq0)
    R = np.zeros((MAX_ROWS, NQ))
    r = np.zeros(MAX_ROWS)
    rleg = np.zeros(MAX_ROWS, dtype=np.int64)
    rkind = np.zeros(MAX_ROWS, dtype=np.int64)
    nr = 0
    th = q[ITH]
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        sL = hip_offset(P, leg)
        g = th + q[IPHB + leg]
        sg = math.sin(g)
        cg = math.cos(g)
        kk = IPHB + leg
        if mode == STICK or mode == STRUT:
            R[nr, IX] = cg
            R[nr, IY] = sg
            R[nr, ITH] = sL * math.sin(q[IPHB + leg]) + l[leg]
            R[nr, kk] = l[leg]
            rleg[nr] = leg
            rkind[nr] = ROW_TOE_ACROSS
            nr += 1
            if mode == STRUT:
                R[nr, IX] = sg
                R[nr, IY] = -cg
                R[nr, ITH] = -sL * math.cos(q[IPHB + leg])
                rleg[nr] = leg
                rkind[nr] = ROW_TOE_ALONG
                nr += 1
        elif mode == FLIGHT and is_set(P[P_MASSLESS]):
            R[nr, kk] = 1.0
            if is_set(P[P_TD_WORLD]):
                R[nr, ITH] = 1.0
            rleg[nr] = leg
            rkind[nr] = ROW_MASSLESS
            nr += 1
        if gear:
            # rigid belt over the impact: the gear rate equals the leg rate after it (the
            # belt damper, 80 us against the gear train, evens out the relative rate
            # within the impact; the energy of that relative motion is part of the logged
            # impact loss). A homogeneous row: the impact can only remove energy.
            R[nr, IALB + leg] = 1.0
            R[nr, IPHB + leg] = -1.0
            r[nr] = 0.0
            rleg[nr] = leg
            rkind[nr] = ROW_GEAR
            nr += 1
    n = nact + nr
    A = np.zeros((n, n))
    b = np.zeros(n)
    for i in range(nact):
        acc = 0.0
        for j in range(nact):
            A[i, j] = M[i, j]
            acc += M[i, j] * dq0[j]
        b[i] = acc
    for rr in range(nr):
        for j in range(nact):
            A[nact + rr, j] = R[rr, j]
            A[j, nact + rr] = R[rr, j]
        b[nact + rr] = r[rr]
    ok = solve_dense(A, b, n)
    for i in range(NIMP):
        out[i] = 0.0
    if not ok:
        return False
    for i in range(nact):
        dq[i] = b[i]
    if not gear:
        dq[IALB] = dq[IPHB]
        dq[IALF] = dq[IPHF]
    for rr in range(nr):
        lam = -b[nact + rr]
        leg = rleg[rr]
        g = th + q[IPHB + leg]
        if rkind[rr] == ROW_TOE_ACROSS:
            out[leg * NIMP_LEG + IMP_NORMAL] += lam * math.sin(g)
            out[leg * NIMP_LEG + IMP_TANGENT] += lam * math.cos(g)
        elif rkind[rr] == ROW_TOE_ALONG:
            out[leg * NIMP_LEG + IMP_NORMAL] -= lam * math.cos(g)
            out[leg * NIMP_LEG + IMP_TANGENT] += lam * math.sin(g)
    out[IMP_ENERGY_LOST] = ke0 - kinetic_energy_at(M, dq)
    # element by element: an array-to-slice assignment compiles Numba's shape-mismatch
    # error message (its string formatting: 2 s of the first run's compilation)
    for i in range(NQ):
        s[i] = q[i]
        s[NQ + i] = dq[i]
    s[IL_B] = l[0]
    s[IL_B + 1] = l[1]
    if gear:
        # Stiction carries no impulse, so every motor joint's stick/slip mode follows its
        # new gear rate (docs/specification.md section 3): the rigid belt moves the gear train with the leg, which
        # can reverse a slipping joint; a joint left at exactly zero rate is stuck (settle()
        # releases it if stiction cannot hold it). Keeping the old slip direction would
        # leave a joint "slipping" against its motion, which settle() could only reconcile
        # with an impulse that stiction cannot give.
        for leg in range(2):
            mi[MI_MOTOR_B + leg] = motor_mode_from_rate(dq[IALB + leg], leg, P)
    project_state(s, P, mi, mf)
    return True
