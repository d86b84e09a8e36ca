"""The motor currents' derivatives along the columns a run carries, at one recorded sample
(compiled): what the hip-unit identification's exact Jacobian reads for a current channel
(:class:`~scoutsim.simulation.sample_derivatives.SampleDerivatives`,
docs/identification.md), in closed form (:func:`~.evaluate.motor_currents_t`) from one
evaluation of the right-hand side at the sample.
"""

from __future__ import annotations

import numpy as np

from ...._numba.jit import allocating
from ..evaluate import evaluate_ws
from ..layout import NAUX, NS
from ..workspace import new_eval_workspace
from .evaluate import derivative_workspace, motor_currents_t


@allocating
def current_derivatives(s, P, mi, mf, cmd, columns, dP):
    """(2, m): d i_leg [A] along each of the m columns at state ``s`` (modes ``mi``, toe
    anchors ``mf``) under the held commands ``cmd`` [N m] and packed parameters ``P``.
    ``columns`` = (phi_s (NS x m), phi_mf (NMF x m), phi_cmd (2 x m)): the columns' rows
    of the state, the anchors and the commands; ``dP`` (m x len(P)): column j's tangent of
    the packed parameters."""
    phi_s, phi_mf, phi_cmd = columns
    m = phi_s.shape[1]
    wk, wA, piv = new_eval_workspace()
    stiff = np.zeros((1, 1))
    ew = (wk, wA, piv, stiff)
    evaluate_ws(s, P, mi, mf, cmd, np.zeros(NS), np.zeros(NAUX), ew, False, stiff, False)
    dw = derivative_workspace(m)
    out = np.zeros((2, m))
    motor_currents_t(P, mi, cmd, ew, dw, (phi_s, phi_mf, phi_cmd, dP), np.zeros((NS, m)), out)
    return out
