"""The derivative of a step's flow, stage by stage, with the right-hand side's derivative in
closed form (compiled).

A step of an explicit or linearly implicit Runge-Kutta method is a chain of linear
combinations and evaluations of the right-hand side: each stage's state Y_i is linear in
the step's start y and the earlier stages' derivatives K_j (with the ARK methods' splitting
matrix of the step held), and K_i = f(Y_i). Its derivative along a column is the same
chain on the tangents,

    Y_i' = (the stage's combination of y' and the K_j'),   K_i' = Df(Y_i)[Y_i', p'],

with Df in closed form (:func:`~scoutsim._core.model.derivative.evaluate.evaluate_t`, one KKT
solve with the factors of the stage's evaluation), and the step's end projected
(:func:`~scoutsim._core.model.derivative.evaluate.projection_t`), both for all columns in
one call (a stage's column states gathered into ``tan.ft``). The stages are evaluated
again here (the run's step keeps only their derivatives), with the step's own size, modes,
anchors, commands and splitting: the derivative is that of the computed step, exact up to
rounding, with no difference step. Where a Dormand-Prince step contains a kink of the
amplifier's law (:func:`flow_dopri5`), it is split there for the derivative, which is then
the flow's along the computed trajectory.
"""

from __future__ import annotations

from ..._numba.jit import kernel
from ..model.derivative.evaluate import (
    DW_TR,
    current_branches,
    evaluate_t,
    projected_t,
    projection_t,
)
from ..model.derivative.kinematics import NTR, TR_CGB, TR_CGF, TR_CTH, TR_SGB, TR_SGF, TR_STH
from ..model.evaluate import evaluate_ws
from ..model.kinematics import project
from ..model.layout import IL_B, NMF, NQ, NS
from . import ark, dopri5
from .tangent_work import FT_CMD, FT_K, FT_MF, FT_Y, X_CMD, X_MF, X_S, unpacked


@kernel
def parameter_tangents(tan):
    """Each column's tangent of the packed robot parameters, sum_i Phi[par_i, j] dP[i],
    into ``tan.Pt`` (constant along a flow: the parameter rows do not change)."""
    Phi, Pt, dP = tan.Phi, tan.Pt, tan.dP
    npar = tan.pscale.shape[0]
    par0 = Phi.shape[0] - npar
    for j in range(Phi.shape[1]):
        for k in range(Pt.shape[1]):
            Pt[j, k] = 0.0
        for i in range(npar):
            w = Phi[par0 + i, j]
            if w != 0.0:
                for k in range(Pt.shape[1]):
                    Pt[j, k] += w * dP[i, k]


@kernel(inline="always")
def _columns(tan):
    """The columns' tangents of the anchors and the commands (constant along a step) into
    ``tan.ft`` (rows FT_MF, FT_CMD); returns the views (a stage's states (NS, m), the
    stages' derivatives (7 NS, m), anchors, commands) of ``tan.ft``."""
    Phi, ft = tan.Phi, tan.ft
    for c in range(Phi.shape[1]):
        for i in range(NMF):
            ft[FT_MF + i, c] = Phi[X_MF + i, c]
        for i in range(2):
            ft[FT_CMD + i, c] = Phi[X_CMD + i, c]
    return (
        ft[FT_Y : FT_Y + NS],
        ft[FT_K : FT_K + 7 * NS],
        ft[FT_MF : FT_MF + NMF],
        ft[FT_CMD : FT_CMD + 2],
    )


@kernel(inline="always")
def _column_state(j, tan, y0):
    """Column ``j``'s tangents of the state into ``y0``."""
    Phi = tan.Phi
    for i in range(NS):
        y0[i] = Phi[X_S + i, j]


@kernel
def projection_derivative(s, P, mi, mf, tan):
    """Phi := D[proj] Phi for the projection of the dependent coordinates of ``s`` (modes
    ``mi``, anchors ``mf``; ``s`` is not changed), in closed form; ``tan``: the unpacked
    work (:func:`~.tangent_work.unpacked`)."""
    Phi, sp, dw = tan.Phi, tan.sp, tan.dw
    for i in range(NS):
        sp[i] = s[i]
    q, dq, l = sp[0:NQ], sp[NQ : 2 * NQ], sp[IL_B : IL_B + 2]
    sth, cth, sg0, cg0, sg1, cg1 = project(q, dq, l, P, mi, mf)
    tr = dw[DW_TR : DW_TR + NTR, 0]
    tr[TR_STH] = sth
    tr[TR_CTH] = cth
    tr[TR_SGB] = sg0
    tr[TR_CGB] = cg0
    tr[TR_SGF] = sg1
    tr[TR_CGF] = cg1
    parameter_tangents(tan)
    ys, ks, mft, _ = _columns(tan)
    for j in range(Phi.shape[1]):
        for i in range(NS):
            ys[i, j] = Phi[X_S + i, j]
    out = ks[0:NS]
    projected_t(q, dq, l, P, mi, dw, (ys, mft, tan.Pt), out)
    for j in range(Phi.shape[1]):
        for i in range(NS):
            Phi[X_S + i, j] = out[i, j]


#: the most kinks of the amplifier's law one step's derivative is split at (more are
#: differentiated as the computed step)
MAX_KINK_SPLITS = 4
#: bisections locating a kink inside a step (its time to 2^-KINK_BISECTIONS of the step)
KINK_BISECTIONS = 36


@kernel(inline="always")
def _dopri5_pass(s, h, plant, tan, force):
    """The derivative of the Dormand-Prince step of size ``h`` [s] from ``s`` (``plant`` =
    (P, mi, mf, cmd)), stage by stage: Phi := it (the stages' tangents in ``tan.ft``), if
    ``force`` or the motor currents' branches at the step's start and end agree. The
    step's end state is left in ``tan.work.tmp``. Returns True if Phi was written."""
    P, mi, mf, cmd = plant
    Phi, own = tan.Phi, tan.work
    K, y, ew = own.K, own.tmp, own.ew
    m = Phi.shape[1]
    ys, ks, mft, cmdt = _columns(tan)
    start = 0
    end = 0
    for st in range(7):
        dopri5.stage_state(st, s, h, K, y)
        evaluate_ws(y, P, mi, mf, cmd, K[st], own.aux_new, ew, False, ew[3], False)
        if st == 0:
            start = current_branches(P, cmd, ew)
        elif st == 6:
            end = current_branches(P, cmd, ew)
            if end != start and not force:
                return False
        # the columns' stage states (dopri5.stage_state on the tangents, the columns in
        # the innermost loop)
        for i in range(NS):
            for j in range(m):
                ys[i, j] = Phi[X_S + i, j]
        for k in range(st):
            a = dopri5.A[st, k]
            if a != 0.0:
                ha = h * a
                for i in range(NS):
                    for j in range(m):
                        ys[i, j] += ha * ks[k * NS + i, j]
        kt = ks[st * NS : (st + 1) * NS]
        if st < 6:
            evaluate_t(P, mi, cmd, ew, tan.dw, (ys, mft, cmdt, tan.Pt), kt)
        else:  # the step's end (b_7 = 0: its derivative is not needed), projected
            projection_t(P, mi, ew, tan.dw, (ys, mft, tan.Pt), kt)
    for j in range(m):
        for i in range(NS):
            Phi[X_S + i, j] = ks[6 * NS + i, j]
    return True


@kernel(inline="always")
def _first_kink(s, h, plant, own):
    """The time [s] after ``s`` at which the motor currents' branches first differ from
    theirs at ``s``, within (0, ``h``]: bisection on Dormand-Prince steps from ``s`` (to
    2^-KINK_BISECTIONS h), the upper end (just past the kink)."""
    P, mi, mf, cmd = plant
    K, y, ew = own.K, own.tmp, own.ew
    evaluate_ws(s, P, mi, mf, cmd, K[0], own.aux_new, ew, False, ew[3], False)
    start = current_branches(P, cmd, ew)
    lo, hi = 0.0, h
    for _ in range(KINK_BISECTIONS):
        mid = 0.5 * (lo + hi)
        for st in range(1, 7):
            dopri5.stage_state(st, s, mid, K, y)
            evaluate_ws(y, P, mi, mf, cmd, K[st], own.aux_new, ew, False, ew[3], False)
        if current_branches(P, cmd, ew) == start:
            lo = mid
        else:
            hi = mid
    return hi


@kernel
def flow_dopri5(s, h, P, mi, mf, cmd, pack):
    """Phi := D[proj(step(.; h))] Phi over the Dormand-Prince step of size ``h`` [s] the
    run has just taken from ``s`` (modes ``mi``, anchors ``mf``, commands ``cmd``).

    Where the motor currents' branches differ at the step's start and end, the current
    met a kink of the amplifier's law (the torque-speed line) inside the step: the
    right-hand side's derivative jumps there, which the step's stages straddle, so the
    computed step's derivative is that of the flow only to O(h). The derivative is then
    taken over sub-steps that end just past each kink (:func:`_first_kink`, at most
    MAX_KINK_SPLITS): that of the flow along the computed trajectory, each piece smooth.
    The run's own step is not changed."""
    tan = unpacked(pack)
    plant = (P, mi, mf, cmd)
    parameter_tangents(tan)
    start, rest = tan.sp, h
    for i in range(NS):
        start[i] = s[i]
    for split in range(MAX_KINK_SPLITS + 1):
        if _dopri5_pass(start, rest, plant, tan, split == MAX_KINK_SPLITS):
            return
        tau = _first_kink(start, rest, plant, tan.work)
        _dopri5_pass(start, tau, plant, tan, True)
        for i in range(NS):
            start[i] = tan.work.tmp[i]
        rest -= tau


@kernel(inline="always")
def _flow_ark(s, h, plant, SF0, pack, tableau, ns):
    """Phi := D[proj(step(.; h))] Phi over the ARK step of size ``h`` [s] the run has just
    taken from ``s`` with the stiff factors ``SF0`` (held: the splitting of the step);
    ``plant`` = (P, mi, mf, cmd); ``tableau`` = (AE, AD, B, GAMMA), ``ns`` stages."""
    P, mi, mf, cmd = plant
    AE, AD, B, GAMMA = tableau
    tan = unpacked(pack)
    Phi, own, Kt, Zt, yt, y0 = tan.Phi, tan.work, tan.Kt, tan.Zt, tan.yt, tan.w
    K, y, ew, Z = own.K, own.tmp, own.ew, own.Z
    m = Phi.shape[1]
    parameter_tangents(tan)
    R = ark.splitting_rank(SF0)
    hg = h * GAMMA
    ark.factor_splitting(SF0, hg, Z, R)
    VU = Z[ark.NSTAGE : ark.NSTAGE + R]
    Si = Z[ark.NSTAGE + R : ark.NSTAGE + 2 * R]
    w = Z[ark.NSTAGE + 2 * R]
    mm = Z[ark.NSTAGE + 2 * R + 1]
    pp = Z[ark.NSTAGE + 2 * R + 2]
    split = (SF0, VU, Si, R)
    tab = (AE, AD, GAMMA)
    zr = ark.Z_ROWS
    ark.project_on_v(SF0, s, Z[0], R)
    ys, ks, mft, cmdt = _columns(tan)
    for st in range(ns):
        if st == 0:
            for i in range(NS):
                y[i] = s[i]
        else:
            ark.stage_state(st, s, h, (K, Z), split, tab, (y, w, mm, pp))
        evaluate_ws(y, P, mi, mf, cmd, K[st], own.aux_new, ew, False, ew[3], False)
        for j in range(m):
            _column_state(j, tan, y0)
            Zj = Zt[zr * j : zr * (j + 1)]
            if st == 0:
                ark.project_on_v(SF0, y0, Zj[0], R)
                for i in range(NS):
                    yt[i] = y0[i]
            else:
                ark.stage_state(st, y0, h, (Kt[7 * j : 7 * j + 7], Zj), split, tab, (yt, w, mm, pp))
            for i in range(NS):
                ys[i, j] = yt[i]
        kt = ks[0:NS]
        evaluate_t(P, mi, cmd, ew, tan.dw, (ys, mft, cmdt, tan.Pt), kt)
        for j in range(m):
            for i in range(NS):
                Kt[7 * j + st, i] = kt[i, j]
    # the step's end y + h sum_j b_j K_j, evaluated for its projection
    for i in range(NS):
        y[i] = 0.0
    for k in range(ns):
        for i in range(NS):
            y[i] += B[k] * K[k, i]
    for i in range(NS):
        y[i] = s[i] + h * y[i]
    evaluate_ws(y, P, mi, mf, cmd, K[6], own.aux_new, ew, False, ew[3], False)
    for j in range(m):
        _column_state(j, tan, y0)
        for i in range(NS):
            yt[i] = 0.0
        for k in range(ns):
            for i in range(NS):
                yt[i] += B[k] * Kt[7 * j + k, i]
        for i in range(NS):
            ys[i, j] = y0[i] + h * yt[i]
    kt = ks[0:NS]
    projection_t(P, mi, ew, tan.dw, (ys, mft, tan.Pt), kt)
    for j in range(m):
        for i in range(NS):
            Kt[7 * j + 6, i] = kt[i, j]
    for j in range(m):
        for i in range(NS):
            Phi[X_S + i, j] = Kt[7 * j + 6, i]


@kernel
def flow_ark4(s, h, plant, SF0, pack):
    """:func:`_flow_ark` with ARK4(3)6L[2]SA."""
    _flow_ark(s, h, plant, SF0, pack, (ark.AE, ark.AD, ark.B, ark.GAMMA), ark.NSTAGE)


@kernel
def flow_ark3(s, h, plant, SF0, pack):
    """:func:`_flow_ark` with ARK3(2)4L[2]SA."""
    _flow_ark(s, h, plant, SF0, pack, (ark.AE3, ark.AD3, ark.B3, ark.GAMMA3), 4)
