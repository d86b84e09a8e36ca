"""The belt with backlash (compiled): the Model II hip unit with an angular play b
(``RobotParameters.belt_backlash``, per leg) in its belt spring. An effect beyond the
paper's models, which lumps the backlash into the spring (Sec. III); docs/model.md
"Effects beyond the paper's models".

The spring is slack for |alpha - phi| <= b / 2 (a dead zone) and deflected by the excess
beyond it, tau_spring = k_b (delta - sign(delta) b / 2), so its potential energy is
1/2 k_b (excess)^2 and zero inside the play; the damper c_b acts throughout, as in the
paper's belt. Consistent with that:

- the stiff part of the Jacobian the ARK methods treat implicitly has the spring's
  stiffness k_b only where the spring is engaged, 0 inside the play (the damper's part
  stays);
- the touchdown impact keeps the belt rigid (alpha' = phi' after it) inside the play too:
  that row stands for the damper evening out the relative rate within the impact
  (docs/model.md "Impact"), and the damper acts across the play.

Registered in :mod:`scoutsim._core.model.hip_unit` after the belt: a Model II robot with any
play > 0 runs on this unit, one without on :mod:`scoutsim._core.model.belt`. Its gear train is
the belt's (:mod:`scoutsim._core.model.transmission`); its function :func:`spring` takes the
angle difference ``delta`` = alpha - phi [rad] of virtual leg ``leg``.
"""

from __future__ import annotations

from ..._numba.jit import kernel
from .layout import P_BACKLASH

NAME = "belt with backlash"
GEARED = True


def applies(model: str, robot) -> bool:
    """Model II with play in either leg's belt (``RobotParameters.belt_backlash`` > 0)."""
    return model == "II" and any(b > 0.0 for b in robot.per_leg("belt_backlash"))


@kernel(inline="always")
def half_play(leg, P):
    """Half the play, b / 2 [rad], of virtual leg ``leg``'s hip unit."""
    return 0.5 * P[P_BACKLASH + leg]


@kernel(inline="always")
def spring(delta, leg, P):
    """(deflection [rad], engaged) of the belt spring at ``delta``: the excess beyond the
    dead zone |delta| <= b / 2 and True there; (0, False) inside the play."""
    h = half_play(leg, P)
    if delta > h:
        return delta - h, True
    if delta < -h:
        return delta + h, True
    return 0.0, False
