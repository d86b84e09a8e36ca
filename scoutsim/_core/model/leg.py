"""The telescopic leg (compiled): its spring, damper and sliding-joint friction.

Table III gives the leg spring k and damper c per physical leg; the leg is massless below
the hip (its mass and inertia belong to the rigid leg body, model/rigid_body.py), so its
length l is a kinematic output in stance and relaxes to the stop l0 in flight
(docs/specification.md section 2). The angle-dependent damper and the sliding-joint friction
are effects beyond the paper's models, off by default (``RobotParameters`` docs).
"""

from __future__ import annotations

from ..._numba.jit import kernel
from .layout import P_C, P_LEG_C_ANGLE, P_LEG_FRIC, P_LEG_FRIC_SIDE

#: Speed [m/s] below which the telescopic leg's Coulomb friction is regularised linearly
#: (``RobotParameters.leg_friction_force``): a leg loaded below the friction level creeps
#: at less than this speed instead of sticking exactly.
LEG_FRICTION_SPEED = 1e-3


@kernel(inline="always")
def leg_damping(phi, leg, P):
    """Leg damper [N s/m] per physical leg of virtual leg ``leg`` at leg angle ``phi``
    [rad]: c (1 + a phi^2) (a = ``P_LEG_C_ANGLE``, 0 = Table III's constant c)."""
    return P[P_C + leg] * (1.0 + P[P_LEG_C_ANGLE + leg] * phi * phi)


@kernel(inline="always")
def leg_friction_level(tau_hip, ll, leg, P):
    """Coulomb friction level [N] of the sliding joint of one physical leg of virtual leg
    ``leg``: a constant part and a part proportional to the side load |tau_hip| / l of the
    hip torque (0 = off)."""
    return P[P_LEG_FRIC + leg] + P[P_LEG_FRIC_SIDE + leg] * abs(tau_hip) / ll


@kernel(inline="always")
def leg_axial_force(k, c, l0, ll, ld, fc):
    """Axial force of one physical leg [N], compression positive: spring, damper and the
    sliding joint's Coulomb friction ``fc`` (regularised over LEG_FRICTION_SPEED)."""
    sat = ld / LEG_FRICTION_SPEED
    if sat > 1.0:
        sat = 1.0
    elif sat < -1.0:
        sat = -1.0
    return k * (l0 - ll) - c * ld - fc * sat


@kernel(inline="always")
def held_at_stop(c, l0, ll):
    """Whether a massive leg in flight of length ``ll`` [m] is held at its stop ``l0`` [m]:
    undamped (damper ``c`` <= 0 [N s/m]: its massless toe follows the spring at once) or at
    or beyond the stop. Otherwise it is free and relaxes towards the stop
    (:func:`flight_leg_rate`): the projection, its derivative and the sensitivities'
    difference steps all read this one test."""
    return c <= 0.0 or ll >= l0


@kernel(inline="always")
def flight_leg_rate(k, c, l0, ll, fc):
    """dl/dt [m/s] of a massive leg's massless toe in flight, from its force balance
    leg_axial_force(...) = 0 (it relaxes towards l0; docs/specification.md section 2); 0 at the stop."""
    if held_at_stop(c, l0, ll):
        return 0.0
    f = k * (l0 - ll)
    lin = f / (c + fc / LEG_FRICTION_SPEED)
    if lin <= LEG_FRICTION_SPEED:
        return lin
    return (f - fc) / c
