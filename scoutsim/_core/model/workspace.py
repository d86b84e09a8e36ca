"""Layout of the scratch space of the allocation-free evaluation (model/evaluate.py).

The integrators call :func:`~scoutsim._core.model.evaluate.evaluate_ws` on a preallocated float64
vector ``wk`` (size WK_SIZE), a 2-D array ``wA`` (WA_ROWS x MAX_KKT) and integer pivots
``piv`` (MAX_KKT); this module names their slots. ``wk`` keeps what a later
:func:`~scoutsim._core.model.evaluate.evaluate_command_change` needs of the last evaluation.
"""

from __future__ import annotations

import numpy as np

from ..._numba.jit import allocating
from .kkt import MAX_KKT, MAX_ROWS
from .layout import NQ

WK_Q = 0
WK_DQ = WK_Q + NQ
WK_L = WK_DQ + NQ
WK_Q_ = WK_L + 2  # generalized forces Q
WK_H = WK_Q_ + NQ  # Coriolis vector
WK_R = WK_H + NQ  # constraint right-hand sides r
WK_B = WK_R + MAX_ROWS  # KKT right-hand side / solution
WK_B2 = WK_B + MAX_KKT  # second right-hand side (stiff directions, command changes)
WK_RKIND = WK_B2 + MAX_KKT  # row kinds (layout.ROW_*)
WK_RLEG = WK_RKIND + MAX_ROWS
NLG = 14  # per-leg scalar slots LG_* below
WK_LEG = WK_RLEG + MAX_ROWS  # per-leg scalars, 16 slots x 2 legs (NLG used)
NWK_LEG = 32
WK_Y = WK_LEG + NWK_LEG  # reduced KKT right-hand side / solution
WK_META = WK_Y + MAX_KKT  # what evaluate_command_change needs of the last evaluation (MT_*)
NMETA = 11
WK_SIZE = WK_META + NMETA
WA_R = MAX_KKT  # rows of wA holding the constraint rows R
WA_M = WA_R + MAX_ROWS  # rows of wA holding the mass matrix M
WA_ROWS = WA_M + NQ

# per-leg scalar slots (offset WK_LEG + 2 * slot + leg)
(
    LG_FAX,
    LG_LDOT,
    LG_GT,
    LG_GN,
    LG_TOEX,
    LG_TOEY,
    LG_TOEVX,
    LG_CUR,
    LG_OM,
    LG_TAPP,
    LG_TBELT,
    LG_TFRIC,
    LG_HOLD,
    LG_STRUT,
) = range(NLG)

# slots of the last evaluation's summary (offset WK_META)
MT_SCHUR = 0  # 1 if the Schur-complement factorization was used, 0 for LU
MT_NROWS = 1  # number of constraint rows
MT_KKT_OK = 2  # 1 if the factorization succeeded
MT_VBATT = 3  # battery voltage [V]
MT_SG_B = 4  # sin / cos of the back leg's angle from the vertical
MT_CG_B = 5
MT_SG_F = 6  # sin / cos of the front leg's angle
MT_CG_F = 7
MT_ENERGY = 8  # total mechanical energy [J]
MT_STH = 9  # sin / cos of the pitch theta
MT_CTH = 10


@allocating
def new_eval_workspace():
    """Scratch arrays for :func:`~scoutsim._core.model.evaluate.evaluate_ws` (wk, wA, piv)."""
    return (np.zeros(WK_SIZE), np.zeros((WA_ROWS, MAX_KKT)), np.zeros(MAX_KKT, dtype=np.int64))
