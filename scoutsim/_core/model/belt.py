"""The paper's belt (compiled): the Model II hip unit's lumped belt compliance and gear
backlash as a linear torsional spring k_b in parallel with a damper c_b on the angle
between the driven gear and the leg, alpha - phi (paper Sec. III, Fig. 6, Table II:
k_b = 7 N m/deg, c_b = 4 N m/(deg/s); docs/specification.md section 5).

One of the hip units registered in :mod:`scoutsim._core.model.hip_unit`; the gear pair and the
motor joint it shares with the other geared units are in :mod:`scoutsim._core.model.transmission`.
Its one function, :func:`spring`, takes the angle difference ``delta`` = alpha - phi [rad]
of virtual leg ``leg``.
"""

from __future__ import annotations

from ..._numba.jit import kernel

NAME = "belt"
GEARED = True


def applies(model: str, robot) -> bool:
    """Model II."""
    return model == "II"


@kernel(inline="always")
def spring(delta, leg, P):
    """(deflection [rad], engaged) of the belt spring at ``delta``: the whole angle
    difference, and always engaged (its stiffness always counts in the stiff Jacobian)."""
    return delta, True
