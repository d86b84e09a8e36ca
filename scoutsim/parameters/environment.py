"""The floor the robot runs on: :class:`Environment` (toe friction) and its default,
:data:`DEFAULT_FRICTION_COEFFICIENT`."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from .parameter_error import ParameterError
from .robot import RobotParameters

#: The default floor of every simulation, command and study: Coulomb friction mu = 1.0 at
#: the toe [assumed: rubber-covered toes on carpet, where the paper's experiments ran; the
#: paper gives no value]. mu = inf is a no-slip floor (the specification's idealisation), an option.
#: Why 1.0: from the default start, ideal, Model I and Model II all reach the bounding
#: cycle from every start of a neighbourhood around it on this floor (docs/model.md,
#: "Default start and floor"); on a no-slip floor Model II does from fewer than half.
DEFAULT_FRICTION_COEFFICIENT = 1.0


@dataclass(frozen=True)
class Environment:
    """The world the robot runs in: a flat, rigid, level floor at y = 0 with Coulomb
    friction at the toe (docs/specification.md section 3).

    Attributes
    ----------
    friction_coefficient : float or None
        Coulomb coefficient mu [-] of the toe on the floor, > 0; ``math.inf`` is a no-slip
        floor. None (default): :data:`DEFAULT_FRICTION_COEFFICIENT` (1.0), except for
        massless legs (their ground force lies along the leg, so slip is not defined):
        no slip.
    """

    friction_coefficient: float | None = None

    def __post_init__(self):
        mu = self.friction_coefficient
        if mu is not None and not (
            isinstance(mu, numbers.Real) and not isinstance(mu, bool) and mu > 0.0
        ):
            raise ParameterError(
                f"Environment.friction_coefficient = {mu!r} is not allowed: "
                "must be a number > 0 (inf for a no-slip floor) or None",
                "friction_coefficient",
            )

    def friction_for(self, robot: RobotParameters) -> float:
        """The toe's Coulomb coefficient mu [-] for ``robot`` on this floor (the default
        rule above when ``friction_coefficient`` is None)."""
        if self.friction_coefficient is not None:
            return float(self.friction_coefficient)
        massless = robot.leg_mass == 0.0 and robot.leg_inertia == 0.0
        return math.inf if massless else DEFAULT_FRICTION_COEFFICIENT


def floor_label(mu: float) -> str:
    """Name of a floor by its toe friction coefficient mu [-]: 'no slip' (inf) or 'mu = 1.0'."""
    return "no slip" if math.isinf(mu) else f"mu = {mu:g}"
