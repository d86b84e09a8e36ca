"""Dormand-Prince 5(4) explicit Runge-Kutta step with dense output (compiled).

The classic embedded pair (Dormand & Prince 1980; Hairer, Norsett & Wanner, *Solving ODEs I*,
Sec. II.5), the method of MATLAB's ode45 and SciPy's RK45, with the same 4th-order
continuous extension as SciPy. Error-per-step control with the RMS norm
``||err / (atol + rtol max(|y|, |y_new|))||``. With the work-energy accounting, the power
flows at the stages are summed with the weights of the solution, b = A[6]
(:mod:`scoutsim._core.numerics.step_energy`).
"""

from __future__ import annotations

import numpy as np

from ..._numba.jit import allocating, kernel
from ..model.evaluate import NSTIFF, evaluate_ws
from ..model.layout import NAUX, NS
from ..model.workspace import new_eval_workspace
from .step_energy import accounting, add_stage, begin_step, power_at

C = np.array([0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0])
A = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
        [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
        [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
        [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
        [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
    ]
)
E = np.array(
    [
        -71.0 / 57600.0,
        0.0,
        71.0 / 16695.0,
        -71.0 / 1920.0,
        17253.0 / 339200.0,
        -22.0 / 525.0,
        1.0 / 40.0,
    ]
)
PD = np.array(
    [
        [
            1.0,
            -8048581381.0 / 2820520608.0,
            8663915743.0 / 2820520608.0,
            -12715105075.0 / 11282082432.0,
        ],
        [0.0, 0.0, 0.0, 0.0],
        [
            0.0,
            131558114200.0 / 32700410799.0,
            -68118460800.0 / 10900136933.0,
            87487479700.0 / 32700410799.0,
        ],
        [
            0.0,
            -1754552775.0 / 470086768.0,
            14199869525.0 / 1410260304.0,
            -10690763975.0 / 1880347072.0,
        ],
        [
            0.0,
            127303824393.0 / 49829197408.0,
            -318862633887.0 / 49829197408.0,
            701980252875.0 / 199316789632.0,
        ],
        [0.0, -282668133.0 / 205662961.0, 2019193451.0 / 616988883.0, -1453857185.0 / 822651844.0],
        [0.0, 40617522.0 / 29380423.0, -110615467.0 / 29380423.0, 69997945.0 / 29380423.0],
    ]
)


@kernel(inline="always")
def stage_state(st, y, h, K, out):
    """The state of stage ``st`` into ``out``: y + h sum_j A[st, j] K[j] over the earlier
    stages. Linear in (y, K): the flow's derivative applies it to their tangents
    (:mod:`.tangent_flow`)."""
    for i in range(NS):
        acc = y[i]
        for j in range(st):
            a = A[st, j]
            if a != 0.0:
                acc += h * a * K[j, i]
        out[i] = acc


@kernel
def step(y, h, P, mi, mf, cmd, w):
    """One Dormand-Prince step of size h from y, with w.K[0] = f(y) already filled, on the
    step's work ``w`` (:class:`~scoutsim._core.numerics.work.StepWork`).

    Fills K[1..6], y_new and aux_new (outputs at y_new; K[6] = f(y_new) is FSAL); with the
    energy accounting (``w.energy``), also the quadrature sum_j b_j P(Y_j) of the power
    flows and the power flows at y_new (``p_end``).
    Returns (error_norm, ok); ok is False if the dynamics were singular at a stage."""
    K, y_new, aux_new, tmp, ew, rtol, atol = w.K, w.y_new, w.aux_new, w.tmp, w.ew, w.rtol, w.atol
    en = w.energy
    counting = accounting(en)
    if counting:
        begin_step(A[6, 0], en)
    ok = True
    for st in range(1, 7):
        stage_state(st, y, h, K, tmp)
        if st == 6:
            for i in range(NS):
                y_new[i] = tmp[i]
        # the outputs (aux_new) are needed at y_new only (the last stage)
        if not evaluate_ws(tmp, P, mi, mf, cmd, K[st], aux_new, ew, False, ew[3], st == 6):
            ok = False
        if counting:
            if st == 6:  # (b_7 = 0: y_new is the next step's start)
                power_at(K[6], P, mi, ew, en.p_end)
            elif A[6, st] != 0.0:
                add_stage(A[6, st], K[st], P, mi, ew, en)
    err = 0.0
    for i in range(NS):
        e = 0.0
        for j in range(7):
            e += E[j] * K[j, i]
        e *= h
        sc = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        err += (e / sc) ** 2
    return np.sqrt(err / NS), ok


@kernel
def dense(y, h, K, theta, out):
    """Continuous extension: state at t + theta*h (0 <= theta <= 1) after a step from y."""
    t1 = theta
    t2 = theta * theta
    t3 = t2 * theta
    t4 = t3 * theta
    for i in range(NS):
        acc = 0.0
        for j in range(7):
            coef = PD[j, 0] * t1 + PD[j, 1] * t2 + PD[j, 2] * t3 + PD[j, 3] * t4
            if coef != 0.0:
                acc += coef * K[j, i]
        out[i] = y[i] + h * acc


def new_workspace():
    """Scratch arrays for the compiled integrator."""
    return (np.zeros((7, NS)), np.zeros(NS), np.zeros(NS), np.zeros(NAUX))


@allocating
def eval_workspace():
    """Evaluation workspace tuple (wk, wA, piv, stiff) for :func:`evaluate_ws`."""
    wk, wA, piv = new_eval_workspace()
    return (wk, wA, piv, np.zeros((NS, 2 * NSTIFF)))
