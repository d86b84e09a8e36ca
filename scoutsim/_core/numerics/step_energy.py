"""The work-energy accounting of a step: the energy of every power flow over it.

The power flows (:mod:`scoutsim._core.model.power_flows`) are integrated over each step
of the integrator of one control period (:mod:`scoutsim._core.numerics.hybrid`) by
Gauss-Legendre quadrature on the method's continuous extension. Compiled with Numba.
"""

from __future__ import annotations

from ..._numba.jit import kernel
from ..model.evaluate import evaluate_ws
from ..model.kinematics import project_state
from ..model.power_flows import power_flows
from .stepper import method_dense

#: Gauss-Legendre nodes and weights on [0, 1] (3 points, exact for polynomials of degree 5)
GAUSS_NODES = (0.5 - 0.15**0.5, 0.5, 0.5 + 0.15**0.5)
GAUSS_WEIGHTS = (5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0)


@kernel
def accumulate_energy(method, s, y_new, h, K, P, mi, mf, cmd, sc):
    """Add the energy of every power flow (model/power_flows.py) over the step of size ``h``
    from ``s`` to ``y_new`` to ``sc.energy``: 3-point Gauss-Legendre quadrature on the
    method's continuous extension, with the step's modes and held commands. Uses its own
    evaluation workspace, so the integration is unchanged, bit for bit."""
    ew = sc.ew_e
    y = sc.y_e
    p = sc.p_e
    for g in range(3):
        method_dense(method, s, y_new, h, K, GAUSS_NODES[g], y)
        project_state(y, P, mi, mf)
        evaluate_ws(y, P, mi, mf, cmd, sc.ds_e, sc.aux_e, ew, False, ew[3], True)
        power_flows(y, sc.ds_e, sc.aux_e, P, mi, ew[0], ew[1], p)
        w = GAUSS_WEIGHTS[g] * h
        for i in range(p.shape[0]):
            sc.energy[i] += w * p[i]
