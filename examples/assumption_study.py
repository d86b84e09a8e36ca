"""Which modelling assumption decides whether the Table I controller bounds?

Vary one assumption at a time around the robot's defaults (Scout II: floor mu = 1.0,
detection thresholds 8 / 6 mm) and measure, per model, the fraction of the basin grid of
``scoutsim basin`` (8 speeds x 9 pitch rates x 2 heights = 144 starts, 10 s each) that
reaches steady bounding, and the median speed of the cycle reached. The assumptions: the
toes' friction, the controller's touchdown / lift-off thresholds, and each effect of the
virtual Scout II (:data:`scoutsim.validation.make_example.VIRTUAL_SCOUT_EFFECTS`: belt
play, leg friction, angle-dependent leg damping, gearbox losses) alone and all together.

Run it (after ``pip install -e .`` in the repository):

    python examples/assumption_study.py [--robot FILE] [--workers N] [--quick]

(about 6-8 minutes on 2 cores). ``--robot FILE`` is a robot file as ``scoutsim run
--robot`` reads it (default Scout II; its ``[controller]`` section sets the controller the
thresholds are varied on); ``--quick`` runs one start (the default flight start) for 5 s
per case instead of the grid (seconds in all: the fractions are then 0 or 1). It prints a
markdown table, one row per assumption.

Results are recorded in docs/model.md ("What decides bounding").
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from scoutsim import load_parameters
from scoutsim.analysis.basin import (
    DEFAULT_HEIGHTS,
    DEFAULT_PITCH_RATES,
    DEFAULT_SPEEDS,
    basin_of_attraction,
)
from scoutsim.validation.make_example import VIRTUAL_SCOUT_EFFECTS

MODELS = ("ideal", "I", "II")
GRID = dict(
    speeds=DEFAULT_SPEEDS, pitch_rates=DEFAULT_PITCH_RATES, heights=DEFAULT_HEIGHTS, duration=10.0
)
#: --quick: the default flight start alone (1.2 m/s, 150 deg/s, 0.33 m), 5 s
QUICK_GRID = dict(speeds=(1.2,), pitch_rates=(math.radians(150.0),), heights=(0.33,), duration=5.0)
FRICTIONS = (0.6, 0.8, 1.0, 1.5, math.inf)
THRESHOLDS = ((4e-3, 3e-3), (5e-3, 4e-3), (10e-3, 8e-3))  # touchdown, lift-off [m]


def report(label, b):
    parts = []
    for m in b.models():
        f = b.fraction(m)
        speeds = sorted(
            r["mean_speed_m_s"]
            for r in b.rows
            if r["model"] == m and r["steady_bounding"] and r["mean_speed_m_s"]
        )
        sp = f"{np.median(speeds):.2f} m/s" if speeds else "-"
        parts.append(f"{m}: {f:.2f} ({sp})")
    print(f"| {label} | " + " | ".join(parts) + " |", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--robot",
        metavar="FILE",
        help="TOML robot file, as `scoutsim run --robot` (default: Scout II)",
    )
    ap.add_argument(
        "--workers", type=int, default=None, help="processes (default: all cores; 1 with --quick)"
    )
    ap.add_argument(
        "--quick", action="store_true", help="one start, 5 s, per case (seconds in all)"
    )
    args = ap.parse_args(argv)
    robot, controller = load_parameters(args.robot)
    grid = QUICK_GRID if args.quick else GRID
    workers = args.workers if args.workers is not None else (1 if args.quick else None)
    n = len(grid["speeds"]) * len(grid["pitch_rates"]) * len(grid["heights"])

    def basin(models=MODELS, rob=robot, ctrl=controller, **kw):
        return basin_of_attraction(
            models=models, robot=rob, controller=ctrl, workers=workers, **grid, **kw
        )

    print(
        f"fraction of {n} start{'' if n == 1 else 's'} reaching steady bounding (median "
        "speed of those that do)"
    )
    for mu in FRICTIONS:
        report(f"toe friction mu = {mu}", basin(friction_coefficient=mu))
    for td, lo in THRESHOLDS:
        c = controller.replace(touchdown_compression=td, liftoff_compression=lo)
        for mu in (1.0, math.inf):
            report(
                f"mu = {mu}, thresholds {td * 1e3:.0f} / {lo * 1e3:.0f} mm",
                basin(ctrl=c, friction_coefficient=mu),
            )
    for name, value in VIRTUAL_SCOUT_EFFECTS.items():
        report(
            f"{name} = {value:.4g}", basin(models=("I", "II"), rob=robot.replace(**{name: value}))
        )
    report(
        "all effects of the virtual Scout II",
        basin(models=("I", "II"), rob=robot.replace(**VIRTUAL_SCOUT_EFFECTS)),
    )


if __name__ == "__main__":
    main()
