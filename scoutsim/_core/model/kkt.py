"""The constrained dynamics' linear algebra (compiled): constraint rows and the KKT solve.

The dynamics in the current modes are one KKT system
``[M R^T; R 0] [ddq; -lambda] = [Q - h; r]`` (docs/model.md): M the mass matrix, R the
constraint rows (a pinned toe, a strut, a stuck motor joint, a massless leg, the rig clamps;
their kinds are ``layout.ROW_*``), lambda their multipliers (ground forces, holding torques).
Two factorizations of the same system: :func:`kkt_schur_factor` (Schur complements on the
structure of M, every body with mass) and :func:`kkt_reduced_factor` (LU, also for the
massless-leg model); both first eliminate the Model II gear coordinates. :func:`solve_dense`
is the plain dense solve the impact map uses.
"""

from __future__ import annotations

import math

import numpy as np

from ..._numba.jit import allocating, kernel
from .flags import is_set
from .layout import IPHB, NQ, P_CLAMP_LEGS, P_CLAMP_TORSO, ROW_CLAMP_LEG, ROW_CLAMP_TORSO, ROW_GEAR

MAX_ROWS = 11  # at most 2 rows per leg (strut) + 1 per motor joint, + 5 rig clamps
MAX_KKT = NQ + MAX_ROWS


@kernel(inline="always")
def new_row(R, r, rkind, rleg, nr, rhs, kind, leg):
    """Start constraint row nr: zero R[nr], set its right-hand side,
    kind (``layout.ROW_*``) and leg (the caller fills the nonzero entries of R[nr])."""
    for j in range(NQ):
        R[nr, j] = 0.0
    r[nr] = rhs
    rkind[nr] = kind
    rleg[nr] = leg


@kernel(inline="always")
def add_clamp_rows(P, R, r, rkind, rleg, nr):
    """Bench-rig clamps as constraint rows (scoutsim.identification.rigs;
    docs/identification.md): with P_CLAMP_TORSO, ddx = ddy = ddtheta = 0 (``ROW_CLAMP_TORSO``); with P_CLAMP_LEGS also ddphi = 0 for
    both legs (``ROW_CLAMP_LEG``). The multipliers are the clamp's force and torques. Returns the new
    row count."""
    if is_set(P[P_CLAMP_TORSO]):
        for j in range(3):
            new_row(R, r, rkind, rleg, nr, 0.0, ROW_CLAMP_TORSO, 0)
            R[nr, j] = 1.0
            nr += 1
        if is_set(P[P_CLAMP_LEGS]):
            for leg in range(2):
                new_row(R, r, rkind, rleg, nr, 0.0, ROW_CLAMP_LEG, leg)
                R[nr, IPHB + leg] = 1.0
                nr += 1
    return nr


@allocating
def solve_dense(A, b, n):
    """Solve A[:n,:n] x = b[:n] in place by Gaussian elimination with partial pivoting
    (:func:`lu_factor` then :func:`lu_solve`; deterministic, systems of at most 13 x 13).
    Returns False if a pivot is numerically zero (the constrained dynamics are singular)."""
    piv = np.empty(n, dtype=np.int64)
    if not lu_factor(A, piv, n):
        return False
    lu_solve(A, piv, b, 0, n)
    return True


@kernel
def lu_factor(A, piv, n):
    """LU factorization with partial pivoting of A[:n,:n] in place (multipliers below the
    diagonal, row interchanges in piv). The same operations as :func:`solve_dense`, so
    ``lu_solve`` reproduces its results bit for bit. Returns False if singular."""
    scale = 0.0
    for i in range(n):
        for j in range(n):
            a = abs(A[i, j])
            if a > scale:
                scale = a
    tiny = 1e-13 * scale if scale > 0.0 else 1e-300
    for k in range(n):
        p = k
        best = abs(A[k, k])
        for i in range(k + 1, n):
            a = abs(A[i, k])
            if a > best:
                best = a
                p = i
        piv[k] = p
        if best <= tiny:
            return False
        if p != k:
            # columns < k hold the multipliers of earlier steps, which stay with the row
            # position they were computed for (as the right-hand side is swapped in order)
            for j in range(k, n):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
        inv = 1.0 / A[k, k]
        for i in range(k + 1, n):
            f = A[i, k] * inv
            A[i, k] = f
            if f != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]
    return True


@kernel(inline="always")
def lu_solve(A, piv, b, o, n):
    """Solve with the factors of :func:`lu_factor`; right-hand side b[o:o+n], in place."""
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[o + k]
            b[o + k] = b[o + p]
            b[o + p] = tmp
        bk = b[o + k]
        for i in range(k + 1, n):
            f = A[i, k]
            if f != 0.0:
                b[o + i] -= f * bk
    for i in range(n - 1, -1, -1):
        acc = b[o + i]
        for j in range(i + 1, n):
            acc -= A[i, j] * b[o + j]
        b[o + i] = acc / A[i, i]


@kernel
def kkt_reduced_factor(A, piv, M, R, rkind, nact, nr, free0, free1):
    """Assemble and factor the KKT matrix with the Model II gear coordinates eliminated.

    The driven-gear angles alpha (coordinates 5, 6) couple to the rest of the mass matrix
    only through M[2, alpha]; no contact row involves them. A free gear's row is solved
    for its acceleration and folded into the theta row (Schur complement
    M22 - M2a^2 / Maa); a stuck gear has ddalpha = its row's right-hand side and its
    multiplier follows from its row. What is left is [M5 R_c^T; R_c 0] with the contact rows
    only (at most 5 + 4 unknowns instead of 7 + 6). Returns (ok, size)."""
    m = 5
    for i in range(m):
        for j in range(m):
            A[i, j] = M[i, j]
    if nact == 7:
        if free0:
            A[2, 2] -= M[2, 5] * M[2, 5] / M[5, 5]
        if free1:
            A[2, 2] -= M[2, 6] * M[2, 6] / M[6, 6]
    nc = 0
    for rr in range(nr):
        if rkind[rr] == ROW_GEAR:
            continue
        for j in range(m):
            A[m + nc, j] = R[rr, j]
            A[j, m + nc] = R[rr, j]
        nc += 1
    n = m + nc
    for i in range(m, n):
        for j in range(m, n):
            A[i, j] = 0.0
    return lu_factor(A, piv, n), n


@kernel(inline="always")
def kkt_reduced_solve(A, piv, M, rkind, rleg, system, b, o, y, yo):
    """Solve the full KKT system [M R^T; R 0] x = b[o:o+nact+nr] (in place, original
    ordering) with the factors of :func:`kkt_schur_factor` or :func:`kkt_reduced_factor`;
    ``system`` = (nact, nr, free0, free1, schur): the active coordinates, the rows, whether
    each motor joint is free (not stuck) and whether the factors are the Schur complement's;
    y[yo:] is scratch."""
    nact, nr, free0, free1, schur = system
    m = 5
    for i in range(m):
        y[yo + i] = b[o + i]
    if nact == 7:
        if free0:
            y[yo + 2] -= M[2, 5] / M[5, 5] * b[o + 5]
        if free1:
            y[yo + 2] -= M[2, 6] / M[6, 6] * b[o + 6]
    nc = 0
    for rr in range(nr):
        if rkind[rr] == ROW_GEAR:
            continue
        y[yo + m + nc] = b[o + nact + rr]
        nc += 1
    if schur:
        kkt_schur_solve(A, nc, y, yo)
    else:
        lu_solve(A, piv, y, yo, m + nc)
    ddth = y[yo + 2]
    if nact == 7:
        if free0:
            b[o + 5] = (b[o + 5] - M[2, 5] * ddth) / M[5, 5]
        if free1:
            b[o + 6] = (b[o + 6] - M[2, 6] * ddth) / M[6, 6]
    nc = 0
    for rr in range(nr):
        if rkind[rr] == ROW_GEAR:
            a = 5 + int(rleg[rr])
            dda = b[o + nact + rr]
            b[o + nact + rr] = b[o + a] - M[2, a] * ddth - M[a, a] * dda
            b[o + a] = dda
        else:
            b[o + nact + rr] = y[yo + m + nc]
            nc += 1
    for i in range(m):
        b[o + i] = y[yo + i]


# --- structured KKT solve (Schur complements) ----------------------------------------------
# Layout of the factors in A (MAX_KKT x MAX_KKT):
#   A[0:5, 0:5]        M5^-1 (the reduced mass matrix, free gears folded into theta)
#   A[5+c, 0:5]        constraint row c (non-stuck rows, in order)
#   A[5+c, 5:10]       Y[:, c] = M5^-1 R_c^T
#   A[5+c, 10:10+nc]   Cholesky factor of S = R M5^-1 R^T (lower triangle, row c)
SCHUR_MAX_ROWS = MAX_KKT - 10


@kernel(inline="always")
def kkt_schur_factor(A, M, R, rkind, nact, nr, free0, free1):
    """Factor the reduced KKT system of :func:`kkt_reduced_factor` by Schur complements,
    using the structure of the mass matrix: the torso translations have the scalar inertia
    m (M[0,0] = M[1,1] = total mass, M[0,1] = 0), so M5^-1 follows from the 3 x 3 Schur
    complement C - B^T B / m of the rotational block; the constraint rows then give the
    SPD matrix S = R M5^-1 R^T, factored by Cholesky. Needs M5 positive definite (every
    body with mass and inertia; the massless-leg model uses the LU path). Returns
    (ok, nc); ok False if M5 or S is numerically singular."""
    m = M[0, 0]
    im = 1.0 / m
    # C' = C - B^T B / m, B = M[0:2, 2:5], C = M[2:5, 2:5] (theta with the free gears folded)
    c00 = M[2, 2]
    if nact == 7:
        if free0:
            c00 -= M[2, 5] * M[2, 5] / M[5, 5]
        if free1:
            c00 -= M[2, 6] * M[2, 6] / M[6, 6]
    b00 = M[0, 2]
    b01 = M[0, 3]
    b02 = M[0, 4]
    b10 = M[1, 2]
    b11 = M[1, 3]
    b12 = M[1, 4]
    s00 = c00 - im * (b00 * b00 + b10 * b10)
    s01 = M[2, 3] - im * (b00 * b01 + b10 * b11)
    s02 = M[2, 4] - im * (b00 * b02 + b10 * b12)
    s11 = M[3, 3] - im * (b01 * b01 + b11 * b11)
    s12 = M[3, 4] - im * (b01 * b02 + b11 * b12)
    s22 = M[4, 4] - im * (b02 * b02 + b12 * b12)
    # symmetric 3 x 3 inverse by cofactors
    a00 = s11 * s22 - s12 * s12
    a01 = s02 * s12 - s01 * s22
    a02 = s01 * s12 - s02 * s11
    det = s00 * a00 + s01 * a01 + s02 * a02
    scale = max(s00, max(s11, s22))
    if not (det > 1e-13 * scale * scale * scale):
        return False, 0
    idet = 1.0 / det
    i00 = a00 * idet
    i01 = a01 * idet
    i02 = a02 * idet
    i11 = (s00 * s22 - s02 * s02) * idet
    i12 = (s01 * s02 - s00 * s12) * idet
    i22 = (s00 * s11 - s01 * s01) * idet
    A[2, 2] = i00
    A[2, 3] = i01
    A[2, 4] = i02
    A[3, 2] = i01
    A[3, 3] = i11
    A[3, 4] = i12
    A[4, 2] = i02
    A[4, 3] = i12
    A[4, 4] = i22
    # W = B Ci (2 x 3); M5^-1: tc block -W/m, tt block I/m + W B^T / m^2
    w00 = b00 * i00 + b01 * i01 + b02 * i02
    w01 = b00 * i01 + b01 * i11 + b02 * i12
    w02 = b00 * i02 + b01 * i12 + b02 * i22
    w10 = b10 * i00 + b11 * i01 + b12 * i02
    w11 = b10 * i01 + b11 * i11 + b12 * i12
    w12 = b10 * i02 + b11 * i12 + b12 * i22
    A[0, 2] = -im * w00
    A[0, 3] = -im * w01
    A[0, 4] = -im * w02
    A[1, 2] = -im * w10
    A[1, 3] = -im * w11
    A[1, 4] = -im * w12
    A[2, 0] = A[0, 2]
    A[3, 0] = A[0, 3]
    A[4, 0] = A[0, 4]
    A[2, 1] = A[1, 2]
    A[3, 1] = A[1, 3]
    A[4, 1] = A[1, 4]
    im2 = im * im
    A[0, 0] = im + im2 * (w00 * b00 + w01 * b01 + w02 * b02)
    A[0, 1] = im2 * (w00 * b10 + w01 * b11 + w02 * b12)
    A[1, 0] = A[0, 1]
    A[1, 1] = im + im2 * (w10 * b10 + w11 * b11 + w12 * b12)
    # constraint rows, Y = M5^-1 R^T, S = R Y
    nc = 0
    for rr in range(nr):
        if rkind[rr] == ROW_GEAR:
            continue
        row = 5 + nc
        for j in range(5):
            A[row, j] = R[rr, j]
        for i in range(5):
            acc = 0.0
            for j in range(5):
                acc += A[i, j] * R[rr, j]
            A[row, 5 + i] = acc
        nc += 1
    for c in range(nc):
        for d in range(c + 1):
            acc = 0.0
            for j in range(5):
                acc += A[5 + c, j] * A[5 + d, 5 + j]
            A[5 + c, 10 + d] = acc
    # Cholesky of S in place (lower triangle)
    for c in range(nc):
        for d in range(c + 1):
            acc = A[5 + c, 10 + d]
            for e in range(d):
                acc -= A[5 + c, 10 + e] * A[5 + d, 10 + e]
            if c == d:
                if not (acc > 1e-13 * A[5 + c, 10 + c] + 1e-300):
                    return False, nc
                A[5 + c, 10 + c] = math.sqrt(acc)
            else:
                A[5 + c, 10 + d] = acc / A[5 + d, 10 + d]
    return True, nc


@kernel(inline="always")
def kkt_schur_solve(A, nc, y, yo):
    """Solve the reduced KKT system with the factors of :func:`kkt_schur_factor`, right-hand
    side y[yo:yo+5+nc] = [forces; constraint right-hand sides], in place: ddq then the
    multipliers."""
    x0 = y[yo + 0]
    x1 = y[yo + 1]
    x2 = y[yo + 2]
    x3 = y[yo + 3]
    x4 = y[yo + 4]
    z0 = A[0, 0] * x0 + A[0, 1] * x1 + A[0, 2] * x2 + A[0, 3] * x3 + A[0, 4] * x4
    z1 = A[1, 0] * x0 + A[1, 1] * x1 + A[1, 2] * x2 + A[1, 3] * x3 + A[1, 4] * x4
    z2 = A[2, 0] * x0 + A[2, 1] * x1 + A[2, 2] * x2 + A[2, 3] * x3 + A[2, 4] * x4
    z3 = A[3, 0] * x0 + A[3, 1] * x1 + A[3, 2] * x2 + A[3, 3] * x3 + A[3, 4] * x4
    z4 = A[4, 0] * x0 + A[4, 1] * x1 + A[4, 2] * x2 + A[4, 3] * x3 + A[4, 4] * x4
    if nc > 0:
        # t = R z - r, then S nu = t (forward / back substitution with the Cholesky factor)
        for c in range(nc):
            row = 5 + c
            acc = (
                A[row, 0] * z0
                + A[row, 1] * z1
                + A[row, 2] * z2
                + A[row, 3] * z3
                + A[row, 4] * z4
                - y[yo + row]
            )
            for e in range(c):
                acc -= A[row, 10 + e] * y[yo + 5 + e]
            y[yo + row] = acc / A[row, 10 + c]
        for c in range(nc - 1, -1, -1):
            row = 5 + c
            acc = y[yo + row]
            for e in range(c + 1, nc):
                acc -= A[5 + e, 10 + c] * y[yo + 5 + e]
            y[yo + row] = acc / A[row, 10 + c]
        # ddq = z - Y nu
        for c in range(nc):
            row = 5 + c
            nu = y[yo + row]
            z0 -= A[row, 5] * nu
            z1 -= A[row, 6] * nu
            z2 -= A[row, 7] * nu
            z3 -= A[row, 8] * nu
            z4 -= A[row, 9] * nu
    y[yo + 0] = z0
    y[yo + 1] = z1
    y[yo + 2] = z2
    y[yo + 3] = z3
    y[yo + 4] = z4


@kernel
def kkt_reduced_solve_columns(A, piv, M, rkind, rleg, system, B, Y, one):
    """:func:`kkt_reduced_solve` for m right-hand sides at once: the columns of ``B``
    (rows 0 to nact + nr - 1, (MAX_KKT, m)), each solved in place as that function solves
    one (the same operations, column by column); ``Y`` (MAX_KKT, m) scratch. With the
    Schur complement's factors the right-hand sides are gathered and scattered with the
    columns in the innermost loops and each column of ``Y`` is solved by
    :func:`kkt_schur_solve`; with the LU factors (the massless legs' model) one at a time,
    in ``one`` = (w, o, yo): w[o:] and w[yo:] as :func:`kkt_reduced_solve`'s b and y."""
    nact, nr, free0, free1, schur = system
    m = B.shape[1]
    if not schur:
        w, o, yo = one
        n = nact + nr
        for c in range(m):
            for i in range(n):
                w[o + i] = B[i, c]
            kkt_reduced_solve(A, piv, M, rkind, rleg, system, w, o, w, yo)
            for i in range(n):
                B[i, c] = w[o + i]
        return
    fold = nact == 7
    f0 = M[2, 5] / M[5, 5] if fold and free0 else 0.0
    f1 = M[2, 6] / M[6, 6] if fold and free1 else 0.0
    for c in range(m):
        for i in range(5):
            Y[i, c] = B[i, c]
        if fold:
            if free0:
                Y[2, c] -= f0 * B[5, c]
            if free1:
                Y[2, c] -= f1 * B[6, c]
    nc = 0
    for rr in range(nr):
        if rkind[rr] == ROW_GEAR:
            continue
        for c in range(m):
            Y[5 + nc, c] = B[nact + rr, c]
        nc += 1
    for c in range(m):
        kkt_schur_solve(A, nc, Y[:, c], 0)
    if fold:
        for c in range(m):
            ddth = Y[2, c]
            if free0:
                B[5, c] = (B[5, c] - M[2, 5] * ddth) / M[5, 5]
            if free1:
                B[6, c] = (B[6, c] - M[2, 6] * ddth) / M[6, 6]
    nc = 0
    for rr in range(nr):
        if rkind[rr] == ROW_GEAR:
            a = 5 + int(rleg[rr])
            for c in range(m):
                dda = B[nact + rr, c]
                B[nact + rr, c] = B[a, c] - M[2, a] * Y[2, c] - M[a, a] * dda
                B[a, c] = dda
        else:
            for c in range(m):
                B[nact + rr, c] = Y[5 + nc, c]
            nc += 1
    for c in range(m):
        for i in range(5):
            B[i, c] = Y[i, c]
