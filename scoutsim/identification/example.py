"""The worked example of the fit (``scoutsim identify --example``): a "true" hip unit made
from the Table II values times known factors, and virtual rig logs of it with sensor noise,
from which the fit, started at Table II, must find those factors.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..parameters import RobotParameters
from ..validation.log_reading import load_log
from .rig_data import FITTABLE_RIGS
from .rigs import FlightSteps, FreeSwing, RigNoise, run_rig

__all__ = ["EXAMPLE_FACTORS", "example_robot", "example_logs"]

#: Factors applied to the Table II values to make the example's "true" hip unit: the fit
#: starts from Table II and must find these.
EXAMPLE_FACTORS = {
    "drive_gear_inertia": 1.5,
    "driven_gear_inertia": 0.7,
    "joint_stiction": 1.6,
    "joint_damping": 0.6,
    "belt_stiffness": 1.3,
    "belt_damping": 0.8,
}


def example_robot(base: RobotParameters | None = None) -> RobotParameters:
    """The example's true robot: Table II hip values times :data:`EXAMPLE_FACTORS`."""
    base = base or RobotParameters()
    return base.replace(**{k: getattr(base, k) * f for k, f in EXAMPLE_FACTORS.items()})


def example_logs(
    rigs=("free-swing", "flight-steps"), seed: int = 0, noise: RigNoise | None = None, out_dir=None
) -> list:
    """Virtual rig logs made with :func:`example_robot` and sensor noise (seeded; one seed
    per log, ``seed + i``). Saved as ``<rig>.csv.gz`` in ``out_dir`` if given."""
    from .rigs import rig_log

    true = example_robot()
    noise = noise or RigNoise()
    logs = []
    for i, name in enumerate(rigs):
        rig: FreeSwing | FlightSteps
        if name == "free-swing":
            rig = FreeSwing()
        elif name == "flight-steps":
            rig = FlightSteps()
        else:
            raise ValueError(
                f"rig = {name!r} is not allowed: must be one of {', '.join(FITTABLE_RIGS)}"
            )
        log = rig_log(
            run_rig(rig, true),
            noise=noise,
            seed=seed + i,
            notes="scoutsim identify --example: true hip unit = Table II x "
            + json.dumps(EXAMPLE_FACTORS),
        )
        if out_dir is not None:
            out = Path(out_dir)
            out.mkdir(parents=True, exist_ok=True)
            path = log.save(out / f"{name}.csv.gz")
            log = load_log(path)
        logs.append(log)
    return logs
