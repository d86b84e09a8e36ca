"""Linearly implicit additive Runge-Kutta step for the stiff Model II belt dampers (compiled).

Model II is stiff: each belt damper (c_b per physical leg) acts against the gear train's
reflected inertia and gives a relative gear/leg mode with eigenvalue ~ -6e3 ... -1.4e4 /s,
which holds an explicit method to ~0.1 ms steps. Everything else is slow: |lambda| < 500 /s,
the fastest being the back-EMF damping of a motor on its torque-speed line (~400 /s).

Splitting. At the start of each step the model supplies a low-rank factorization
L = U V^T of the stiff part of the Jacobian (``model.evaluate.evaluate_ws`` with ``want_stiff``):
the belt dampers (rank 2), plus the motor damping where it is stiff
(``model.evaluate.STIFF_MOTOR_RATE``, rank 4; not for Scout II). The right-hand side is split
*exactly* as

    f(y) = [f(y) - L y] + L y,

the first part treated explicitly, the linear second part implicitly, with the additive
Runge-Kutta pair ARK4(3)6L[2]SA of Kennedy & Carpenter (Appl. Numer. Math. 44, 2003):
ERK + L-stable, stiffly accurate ESDIRK (gamma = 1/4), order 4 with an embedded order-3
solution. Because L is constant within a step the splitting is exact and the pair keeps its
order whatever L is; L only has to capture the stiff modes for stability. Each implicit
stage solves (I - h gamma U V^T) Y = rhs by the Sherman-Morrison-Woodbury formula (a 2 x 2
or 4 x 4 system). Both parts share the weights b, so y_new = y + h sum b_j f(Y_j): the
physics is f itself, unchanged. Error control as in dopri5.py (RMS norm, per-component
atol + rtol max(|y|, |y_new|)), except that velocities get VELOCITY_ATOL_FACTOR x atol.
Dense output: cubic Hermite on (y, f(y), y_new, f(y_new)). With the work-energy accounting,
the power flows at the stages are summed with the same weights b
(:mod:`scoutsim._core.numerics.step_energy`).
"""

from __future__ import annotations

import numpy as np

from ..._numba.jit import kernel
from ..model.evaluate import NSTIFF, evaluate_ws
from ..model.layout import IALB, IALF, NQ, NS
from .step_energy import accounting, add_stage, begin_step, power_at

# U (the first NSTIFF columns of the stiff factors) is zero outside the acceleration rows
# NQ .. 2 NQ - 1 of the state (evaluate_ws: U = -npl G w, G the constrained inverse mass
# matrix); the loops over U skip the zero rows.
U0 = NQ
U1 = 2 * NQ
# Absolute tolerance of the velocity components (rows NQ .. 2 NQ - 1) in units of atol, i.e.
# a 0.1 s time scale between position [m, rad] and velocity [m/s, rad/s] tolerances. With
# one atol for both (1e-6), the error control chased 1e-6 rad/s on the leg and gear rates
# each time they pass through zero and took 20-40 small steps after a motor joint reversed;
# measured on 10 s of Model II at the default: 15 % fewer evaluations, gait metrics
# unchanged (within 3e-5 of the converged reference either way). docs/model.md.
VELOCITY_ATOL_FACTOR = 10.0

NSTAGE = 6
Z_ROWS = NSTAGE + 2 * NSTIFF + 3 + 4  # rows of the scratch array Z (2 NSTIFF columns)
Z_COLS = 2 * NSTIFF
GAMMA = 0.25
C = np.array([0.0, 1.0 / 2.0, 83.0 / 250.0, 31.0 / 50.0, 17.0 / 20.0, 1.0])
AE = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0 / 2.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [13861.0 / 62500.0, 6889.0 / 62500.0, 0.0, 0.0, 0.0, 0.0],
        [
            -116923316275.0 / 2393684061468.0,
            -2731218467317.0 / 15368042101831.0,
            9408046702089.0 / 11113171139209.0,
            0.0,
            0.0,
            0.0,
        ],
        [
            -451086348788.0 / 2902428689909.0,
            -2682348792572.0 / 7519795681897.0,
            12662868775082.0 / 11960479115383.0,
            3355817975965.0 / 11060851509271.0,
            0.0,
            0.0,
        ],
        [
            647845179188.0 / 3216320057751.0,
            73281519250.0 / 8382639484533.0,
            552539513391.0 / 3454668386233.0,
            3354512671639.0 / 8306763924573.0,
            4040.0 / 17871.0,
            0.0,
        ],
    ]
)
AI = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0 / 4.0, 1.0 / 4.0, 0.0, 0.0, 0.0, 0.0],
        [8611.0 / 62500.0, -1743.0 / 31250.0, 1.0 / 4.0, 0.0, 0.0, 0.0],
        [5012029.0 / 34652500.0, -654441.0 / 2922500.0, 174375.0 / 388108.0, 1.0 / 4.0, 0.0, 0.0],
        [
            15267082809.0 / 155376265600.0,
            -71443401.0 / 120774400.0,
            730878875.0 / 902184768.0,
            2285395.0 / 8070912.0,
            1.0 / 4.0,
            0.0,
        ],
        [
            82889.0 / 524892.0,
            0.0,
            15625.0 / 83664.0,
            69875.0 / 102672.0,
            -2260.0 / 8211.0,
            1.0 / 4.0,
        ],
    ]
)
B = np.array(
    [82889.0 / 524892.0, 0.0, 15625.0 / 83664.0, 69875.0 / 102672.0, -2260.0 / 8211.0, 1.0 / 4.0]
)
BHAT = np.array(
    [
        4586570599.0 / 29645900160.0,
        0.0,
        178811875.0 / 945068544.0,
        814220225.0 / 1159782912.0,
        -3700637.0 / 11593932.0,
        61727.0 / 225920.0,
    ]
)
# error weights b - bhat
EW = B - BHAT
# coefficients of U z_j in stage i: (AI - AE)[i, j]
AD = AI - AE


# ARK3(2)4L[2]SA (Kennedy & Carpenter 2003): 4 stages, order 3, embedded order 2, same
# structure (ERK + L-stable stiffly accurate ESDIRK sharing b).
GAMMA3 = 1767732205903.0 / 4055673282236.0
AE3 = np.zeros((NSTAGE, NSTAGE))
AE3[1, 0] = 1767732205903.0 / 2027836641118.0
AE3[2, 0] = 5535828885825.0 / 10492691773637.0
AE3[2, 1] = 788022342437.0 / 10882634858940.0
AE3[3, 0] = 6485989280629.0 / 16251701735622.0
AE3[3, 1] = -4246266847089.0 / 9704473918619.0
AE3[3, 2] = 10755448449292.0 / 10357097424841.0
B3 = np.zeros(NSTAGE)
B3[0] = 1471266399579.0 / 7840856788654.0
B3[1] = -4482444167858.0 / 7529755066697.0
B3[2] = 11266239266428.0 / 11593286722821.0
B3[3] = GAMMA3
BHAT3 = np.zeros(NSTAGE)
BHAT3[0] = 2756255671327.0 / 12835298489170.0
BHAT3[1] = -10771552573575.0 / 22201958757719.0
BHAT3[2] = 9247589265047.0 / 10645013368117.0
BHAT3[3] = 2193209047091.0 / 5459859503100.0
AI3 = np.zeros((NSTAGE, NSTAGE))
AI3[1, 0] = GAMMA3
AI3[1, 1] = GAMMA3
AI3[2, 0] = 2746238789719.0 / 10658868560708.0
AI3[2, 1] = -640167445237.0 / 6845629431997.0
AI3[2, 2] = GAMMA3
AI3[3, :4] = B3[:4]
EW3 = B3 - BHAT3
AD3 = AI3 - AE3


@kernel
def step(y, h, P, mi, mf, cmd, w, eval_end, want_sf):
    """ARK4(3)6L[2]SA step (see :func:`step_tab`)."""
    return step_tab(y, h, P, mi, mf, cmd, w, eval_end, want_sf, (AE, AD, B, EW, GAMMA), NSTAGE)


@kernel
def step3(y, h, P, mi, mf, cmd, w, eval_end, want_sf):
    """ARK3(2)4L[2]SA step (see :func:`step_tab`)."""
    return step_tab(y, h, P, mi, mf, cmd, w, eval_end, want_sf, (AE3, AD3, B3, EW3, GAMMA3), 4)


@kernel(inline="always")
def step_tab(y, h, P, mi, mf, cmd, work, eval_end, want_sf, tableau, ns):
    """One ARK step of size h from y with the method's ``tableau`` (AE, AD, B, EW, GAMMA)
    and ``ns`` stages (a constant where it is called, so the stage loops have a known trip
    count), on the step's ``work`` (:class:`~scoutsim._core.numerics.work.StepWork`), with
    K[0] = f(y) and SF0 = its stiff factors (U = SF0[:, :NSTIFF], V = SF0[:, NSTIFF:])
    already filled.

    Fills K[1..5] (stage derivatives), y_new and, if the step is accepted (error <= 1) or
    ``eval_end``, K[6] = f(y_new), aux_new and, if ``want_sf``, SF1 (stiff factors at
    y_new, FSAL). With the energy accounting (``work.energy``), also the quadrature
    sum_j B_j P(Y_j) of the power flows and the power flows at y_new (``p_end``).
    Z (Z_ROWS, Z_COLS) is scratch. Returns (error_norm, ok, evaluations)."""
    AE, AD, B, EW, GAMMA = tableau
    K, y_new, aux_new, tmp, ew = work.K, work.y_new, work.aux_new, work.tmp, work.ew
    SF0, SF1, Z, rtol, atol = work.SF0, work.SF1, work.Z, work.rtol, work.atol
    en = work.energy
    counting = accounting(en)
    if counting:
        begin_step(B[0], en)
    ok = True
    nfev = 0
    # rank of the splitting: the two motor-damping columns are zero unless the motor
    # damping is stiff (model.evaluate.STIFF_MOTOR_RATE); V (columns NSTIFF ...) then has rank 2
    R = splitting_rank(SF0)
    hg = h * GAMMA
    VU = Z[NSTAGE : NSTAGE + R]  # V^T U
    Si = Z[NSTAGE + R : NSTAGE + 2 * R]  # (I - h gamma V^T U)^-1
    project_on_v(SF0, y, Z[0], R)
    if not factor_splitting(SF0, hg, Z, R):
        return np.inf, False, nfev
    w = Z[NSTAGE + 2 * R]
    m = Z[NSTAGE + 2 * R + 1]
    pp = Z[NSTAGE + 2 * R + 2]
    for st in range(1, ns):
        stage_state(st, y, h, (K, Z), (SF0, VU, Si, R), (AE, AD, GAMMA), (tmp, w, m, pp))
        if not evaluate_ws(tmp, P, mi, mf, cmd, K[st], aux_new, ew, False, ew[3], False):
            ok = False
        nfev += 1
        if counting and B[st] != 0.0:
            add_stage(B[st], K[st], P, mi, ew, en)
    # error estimate, filtered through W^-1 (Hairer & Wanner IV.8: the raw difference
    # over-estimates the error in the damped stiff components)
    for a in range(R):
        m[a] = 0.0
    for i in range(NS):
        y_new[i] = 0.0
        tmp[i] = 0.0
    for j in range(ns):
        bj = B[j]
        ej = EW[j]
        for i in range(NS):
            y_new[i] += bj * K[j, i]
            tmp[i] += ej * K[j, i]
    for i in range(NS):
        y_new[i] = y[i] + h * y_new[i]
        e = tmp[i] * h
        tmp[i] = e
        for a in range(R):
            m[a] += SF0[i, NSTIFF + a] * e
    apply_w_inverse(SF0, Si, hg, m, pp, tmp, R)
    err = 0.0
    for i in range(NS):
        e = tmp[i]
        at = atol * VELOCITY_ATOL_FACTOR if (i >= NQ and i < 2 * NQ) else atol
        sc = at + rtol * max(abs(y[i]), abs(y_new[i]))
        err += (e / sc) ** 2
    err = np.sqrt(err / NS)
    if ok and (eval_end or err <= 1.0):
        if not evaluate_ws(y_new, P, mi, mf, cmd, K[6], aux_new, ew, want_sf, SF1, True):
            ok = False
        nfev += 1
        if counting:
            power_at(K[6], P, mi, ew, en.p_end)
    return err, ok, nfev


@kernel(inline="always")
def splitting_rank(SF0):
    """The rank of the splitting in the stiff factors ``SF0``: 4 where the motor damping is
    stiff (its columns are nonzero), else 2 (the belt dampers alone)."""
    return NSTIFF if (SF0[NQ + IALB, NSTIFF + 2] != 0.0 or SF0[NQ + IALF, NSTIFF + 3] != 0.0) else 2


@kernel(inline="always")
def factor_splitting(SF0, hg, Z, R):
    """V^T U into ``Z[NSTAGE : NSTAGE + R]`` and (I - hg V^T U)^-1 into the next ``R`` rows
    (the stiff factors ``SF0``, rank ``R``, hg = h gamma); False if singular."""
    VU = Z[NSTAGE : NSTAGE + R]
    Si = Z[NSTAGE + R : NSTAGE + 2 * R]
    for a in range(R):
        for b in range(R):
            acc = 0.0
            for i in range(U0, U1):
                acc += SF0[i, NSTIFF + a] * SF0[i, b]
            VU[a, b] = acc
    return invert_small(VU, hg, Si, R, Z[NSTAGE + 2 * R + 3 : NSTAGE + 2 * R + 7])


@kernel(inline="always")
def project_on_v(SF0, y, z, R):
    """z := V^T y (the first ``R`` columns of V = SF0[:, NSTIFF:])."""
    for a in range(R):
        acc = 0.0
        for i in range(NS):
            acc += SF0[i, NSTIFF + a] * y[i]
        z[a] = acc


@kernel(inline="always")
def stage_state(st, y, h, stages, split, tab, scratch):
    """The state Y of stage ``st`` into ``tmp`` and z = V^T Y into ``Z[st]``, from the
    step's start ``y`` and the earlier stages' derivatives ``K`` and z's (``stages`` =
    (K, Z)): Y = W^-1 (y + h sum_j [AE_sj f_j + AD_sj U z_j]), W = I - h gamma U V^T.
    ``split`` = (SF0, VU, Si, R): the stiff factors, V^T U, (I - h gamma V^T U)^-1 and the
    rank; ``tab`` = (AE, AD, GAMMA); ``scratch`` = (tmp, w, m, pp). Linear in (y, K, Z):
    the flow's derivative applies it to their tangents (:mod:`.tangent_flow`)."""
    K, Z = stages
    SF0, VU, Si, R = split
    AE, AD, GAMMA = tab
    tmp, w, m, pp = scratch
    hg = h * GAMMA
    # rhs = y + h sum_j [AE_ij f_j + (AI_ij - AE_ij) U z_j]
    for a in range(R):
        acc = 0.0
        for j in range(st):
            acc += AD[st, j] * Z[j, a]
        w[a] = h * acc
        m[a] = 0.0
    # (loops over the components innermost, in the order of the sums: each
    # component's sum runs over the stages in the same order as a sum per component)
    for i in range(NS):
        tmp[i] = 0.0
    for j in range(st):
        c = AE[st, j]
        for i in range(NS):
            tmp[i] += c * K[j, i]
    for i in range(NS):
        tmp[i] = y[i] + h * tmp[i]
    for i in range(U0, U1):
        r = tmp[i]
        for a in range(R):
            r += SF0[i, a] * w[a]
        tmp[i] = r
    for i in range(NS):
        r = tmp[i]
        for a in range(R):
            m[a] += SF0[i, NSTIFF + a] * r
    # Y = W^-1 rhs
    apply_w_inverse(SF0, Si, hg, m, pp, tmp, R)
    # z = V^T Y = m + (V^T U) p
    for a in range(R):
        acc = m[a]
        for b in range(R):
            acc += VU[a, b] * pp[b]
        Z[st, a] = acc


@kernel(inline="always")
def apply_w_inverse(SF0, Si, hg, m, pp, x, R):
    """x := W^-1 x = x + h gamma U S^-1 V^T x (Sherman-Morrison-Woodbury), given
    m = V^T x and Si = S^-1 = (I - h gamma V^T U)^-1; leaves p = h gamma S^-1 m in pp."""
    for a in range(R):
        acc = 0.0
        for b in range(R):
            acc += Si[a, b] * m[b]
        pp[a] = hg * acc
    for i in range(U0, U1):
        acc = x[i]
        for a in range(R):
            acc += SF0[i, a] * pp[a]
        x[i] = acc


@kernel(inline="always")
def invert_small(VU, hg, Si, R, M):
    """Si = (I - hg VU)^-1 by Gauss-Jordan with partial pivoting (R <= 4); M (4, 8) is
    scratch."""
    for a in range(R):
        for b in range(R):
            M[a, b] = (1.0 if a == b else 0.0) - hg * VU[a, b]
            M[a, R + b] = 1.0 if a == b else 0.0
    for k in range(R):
        p = k
        best = abs(M[k, k])
        for i in range(k + 1, R):
            if abs(M[i, k]) > best:
                best = abs(M[i, k])
                p = i
        if best == 0.0 or not (best == best):
            return False
        if p != k:
            for j in range(2 * R):
                t = M[k, j]
                M[k, j] = M[p, j]
                M[p, j] = t
        inv = 1.0 / M[k, k]
        for j in range(2 * R):
            M[k, j] *= inv
        for i in range(R):
            if i != k:
                f = M[i, k]
                if f != 0.0:
                    for j in range(2 * R):
                        M[i, j] -= f * M[k, j]
    for a in range(R):
        for b in range(R):
            Si[a, b] = M[a, R + b]
    return True


@kernel
def dense(y, y1, h, K, theta, out):
    """Cubic Hermite continuous extension on (y, K[0]) -> (y1, K[6]) at t + theta*h."""
    t2 = theta * theta
    t3 = t2 * theta
    h00 = 2.0 * t3 - 3.0 * t2 + 1.0
    h10 = t3 - 2.0 * t2 + theta
    h01 = -2.0 * t3 + 3.0 * t2
    h11 = t3 - t2
    for i in range(NS):
        out[i] = h00 * y[i] + h01 * y1[i] + h * (h10 * K[0, i] + h11 * K[6, i])
