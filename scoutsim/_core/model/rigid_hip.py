"""The rigid hip unit: the gear output is the leg (alpha = phi), in the ideal, Model I
and passive models (paper Sec. III; docs/specification.md section 5). The actuator's
torque acts on the leg angle phi (model/actuator.py); there is no gear train of its own
and no belt. Registered in :mod:`scoutsim._core.model.hip_unit` as code 0.
"""

from __future__ import annotations

NAME = "rigid"
GEARED = False


def applies(model: str, robot) -> bool:
    """Every model but Model II."""
    return model != "II"
