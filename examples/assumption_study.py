"""Which modelling assumption decides whether the Table I controller bounds?

Vary one assumption at a time around the Scout II defaults (default floor mu = 1.0,
detection thresholds 8 / 6 mm) and measure, per model, the fraction of the basin grid of
``scoutsim basin`` (8 speeds x 9 pitch rates x 2 heights = 144 starts, 10 s each) that
reaches steady bounding, and the median speed of the cycle reached.

    python examples/assumption_study.py            (about 6-8 minutes on 2 cores)

Results are recorded in docs/model.md ("What decides bounding").
"""

import math

import numpy as np

from scoutsim import ControllerParameters, RobotParameters
from scoutsim.analysis.basin import basin_of_attraction
from scoutsim.validation.make_example import VIRTUAL_SCOUT_EFFECTS

MODELS = ("ideal", "I", "II")


def report(label, b):
    parts = []
    for m in b.models():
        f = b.fraction(m)
        speeds = sorted(r["mean_speed_m_s"] for r in b.rows
                        if r["model"] == m and r["steady_bounding"] and r["mean_speed_m_s"])
        sp = f"{np.median(speeds):.2f} m/s" if speeds else "-"
        parts.append(f"{m}: {f:.2f} ({sp})")
    print(f"| {label} | " + " | ".join(parts) + " |", flush=True)


def main():
    print("fraction of 144 starts reaching steady bounding (median speed of those that do)")
    for mu in (0.6, 0.8, 1.0, 1.5, math.inf):
        report(f"toe friction mu = {mu}", basin_of_attraction(models=MODELS,
                                                               friction_coefficient=mu))
    for td, lo in ((4e-3, 3e-3), (5e-3, 4e-3), (10e-3, 8e-3)):
        c = ControllerParameters(touchdown_compression=td, liftoff_compression=lo)
        for mu in (1.0, math.inf):
            report(f"mu = {mu}, thresholds {td*1e3:.0f} / {lo*1e3:.0f} mm",
                   basin_of_attraction(models=MODELS, controller=c, friction_coefficient=mu))
    for name, value in VIRTUAL_SCOUT_EFFECTS.items():
        rob = RobotParameters().replace(**{name: value})
        report(f"{name} = {value:.4g}", basin_of_attraction(models=("I", "II"), robot=rob))
    report("all effects of the virtual Scout II",
           basin_of_attraction(models=("I", "II"),
                               robot=RobotParameters().replace(**VIRTUAL_SCOUT_EFFECTS)))


if __name__ == "__main__":
    main()
