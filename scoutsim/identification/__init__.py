"""Hip-unit identification (docs/identification.md): virtual bench rigs that are
configurations of the simulator, and a nonlinear least-squares fit of the Model II hip
parameters with confidence intervals and an identifiability report.

The names below are imported from their modules on first use (PEP 562), so that importing
:mod:`.rigs` alone (the command line's help does) does not load SciPy's optimizers."""

from importlib import import_module

#: public name -> the module that defines it
_EXPORTS = {
    **{
        n: ".rigs"
        for n in (
            "HIP_PARAMETERS",
            "RIG_NAMES",
            "FlightSteps",
            "FreeSwing",
            "RigNoise",
            "Stall",
            "hip_parameters",
            "rig_log",
            "run_rig",
            "stall_deflection",
            "with_toe_mass",
            "DEFAULT_PARAMS",
        )
    },
    **{n: ".fit_result" for n in ("FittedParameter", "IdentificationResult")},
    **{n: ".example" for n in ("example_logs", "example_robot")},
    **{n: ".fit" for n in ("FitSettings", "identify")},
    "prepare_log": ".rig_data",
}

__all__ = list(_EXPORTS)


def __getattr__(name):
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(_EXPORTS[name], __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
