"""What the robot's sensors read (compiled): the plant side of the controller boundary.

Scout II measures, per virtual leg, the hip angle and rate relative to the torso (by the
motor encoder: the driven-gear angle alpha in Model II, which differs from the leg angle phi
by the belt's deflection; or at the leg) and the leg length (a linear potentiometer); the
controller sees these readings (``layout.SN_*``) and nothing else of the plant
(docs/specification.md section 6).
"""

from __future__ import annotations

from ..jit import kernel
from .layout import IALB, IL_B, IPHB, NQ, SN_ANGLE_B, SN_LENGTH_B, SN_RATE_B


@kernel
def read_sensors(s, motor_side, y):
    """Fill the sensor readings y (``layout.NSN``) from the state s: hip angles [rad] and
    rates [rad/s] at the motor (``motor_side``: alpha) or at the leg (phi), and leg
    lengths [m]. Outside Model II alpha equals phi."""
    i0 = IALB if motor_side else IPHB
    for leg in range(2):
        y[SN_ANGLE_B + leg] = s[i0 + leg]
        y[SN_RATE_B + leg] = s[NQ + i0 + leg]
        y[SN_LENGTH_B + leg] = s[IL_B + leg]
