"""The hip unit of a run (compiled): which transmission sits between each motor and its
leg, and the hooks through which the rest of the model reaches it.

Registered units (``layout.HIP_*``, chosen by :func:`scoutsim.model.packing.robot_array`
and stored in ``P[P_HIP_UNIT]``):

========================  =================================================================
``HIP_RIGID``             ideal, Model I, passive: the gear output is the leg (alpha = phi);
                          the actuator's torque acts on phi (model/actuator.py)
``HIP_BELT``              Model II (paper Sec. III): gear pair, motor-joint friction and
                          stick/slip (model/transmission.py), the belt spring-damper
                          (model/belt.py)
``HIP_BACKLASH``          Model II with play in the belt spring (model/backlash.py)
========================  =================================================================

A geared unit (belt, backlash) adds the driven-gear angles alpha to the coordinates. What
a geared unit adds to the model (inertia, generalized forces, the stuck joint's row, the
motor joint's stick/slip) is common to both and lives in :mod:`~scoutsim.model.transmission`;
what differs, the belt spring, is reached through :func:`belt_spring`, which dispatches to
the unit's module. A new belt variant is a module with a ``spring`` function and its
registration: a code in ``layout`` (``HIP_*``), its branch of :func:`belt_spring`, and when a
robot gets it (:func:`hip_unit_code`).
"""

from __future__ import annotations

from ..jit import kernel
from . import backlash, belt
from .layout import HIP_BACKLASH, HIP_RIGID, P_HIP_UNIT


@kernel(inline="always")
def geared(P):
    """True for a hip unit with a gear train of its own (the driven-gear angles alpha are
    coordinates, Model II); False for the rigid unit (alpha copies phi)."""
    return int(P[P_HIP_UNIT]) != HIP_RIGID


@kernel(inline="always")
def belt_spring(delta, leg, P):
    """(deflection [rad], engaged) of virtual leg ``leg``'s belt spring at the gear/leg
    angle difference ``delta`` = alpha - phi [rad], by the run's belt: the deflection its
    torque k_b x deflection and energy 1/2 k_b deflection^2 follow, and whether its
    stiffness counts (in the stiff Jacobian of the ARK methods). One branch per geared
    unit."""
    if int(P[P_HIP_UNIT]) == HIP_BACKLASH:
        return backlash.spring(delta, leg, P)
    return belt.spring(delta, leg, P)


def hip_unit_code(model: str, backlash_rad) -> int:
    """The hip unit of ``model`` ("ideal", "I", "II", "passive") with the belt play
    ``backlash_rad`` [rad] of each leg: Model II runs on the belt, or on the belt with
    backlash if either leg has play; the other models on the rigid unit."""
    from .layout import HIP_BELT
    if model != "II":
        return HIP_RIGID
    return HIP_BACKLASH if any(b > 0.0 for b in backlash_rad) else HIP_BELT
