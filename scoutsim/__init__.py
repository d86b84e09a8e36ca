"""scoutsim: simulation, analysis and validation of Scout II bounding.

Poulakakis, Smith & Buehler, "Experimentally Validated Bounding Models for the Scout II
Quadrupedal Robot", ICRA 2004. See README.md and docs/.
"""

from ._version import __version__  # noqa: E402
from .control import (  # noqa: E402
    BoundingController,
    CompiledController,
    Controller,
    PitchFeedbackController,
    SensorChannel,
    SensorParameters,
    load_sensors,
)
from .control.startup import StartupParameters  # noqa: E402
from .parameters import (  # noqa: E402
    ControllerParameters,
    Environment,
    ImplausibleParameterWarning,
    ParameterError,
    RobotParameters,
    load_controller,
    load_parameters,
    load_robot,
)
from .result.simulation_result import SimulationResult  # noqa: E402
from .simulation.initial_conditions import default_initial_state  # noqa: E402
from .simulation.integrator import IntegratorSettings  # noqa: E402
from .simulation.simulator import ControllerError, Recording, Sensors, simulate  # noqa: E402
from .state import (  # noqa: E402
    HybridState,
    InitialState,
    standing_state,  # noqa: E402
)

__all__ = [
    "simulate",
    "SimulationResult",
    "InitialState",
    "HybridState",
    "IntegratorSettings",
    "Sensors",
    "default_initial_state",
    "RobotParameters",
    "ControllerParameters",
    "Environment",
    "ParameterError",
    "ImplausibleParameterWarning",
    "ControllerError",
    "load_robot",
    "load_controller",
    "load_parameters",
    "BoundingController",
    "__version__",
    "Controller",
    "CompiledController",
    "PitchFeedbackController",
    "SensorParameters",
    "SensorChannel",
    "load_sensors",
    "StartupParameters",
    "standing_state",
    "Recording",
]
