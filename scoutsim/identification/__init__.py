"""Hip-unit identification (issue 5; docs/identification.md): virtual bench rigs that are
configurations of the simulator, and a nonlinear least-squares fit of the Model II hip
parameters with confidence intervals and an identifiability report."""

from .rigs import (HIP_PARAMETERS, RIG_NAMES, FlightSteps, FreeSwing, RigNoise, Stall,
                   hip_parameters, rig_log, run_rig, stall_deflection, with_toe_mass)
from .fit import (DEFAULT_PARAMS, FittedParameter, IdentificationResult, example_logs,
                  example_robot, identify, prepare_log)

__all__ = ["HIP_PARAMETERS", "RIG_NAMES", "FlightSteps", "FreeSwing", "RigNoise", "Stall",
           "hip_parameters", "rig_log", "run_rig", "stall_deflection", "with_toe_mass",
           "DEFAULT_PARAMS", "FittedParameter", "IdentificationResult", "example_logs",
           "example_robot", "identify", "prepare_log"]
