"""Which modelling assumption decides whether the Table I controller bounds?

Vary one assumption at a time around the Scout II defaults and measure the fraction of the
basin grid (scoutsim.analysis.basin defaults: 32 starts, 10 s each) that reaches steady
bounding, per model, and the speed of the cycle reached.

    python examples/assumption_study.py            (about 2-4 minutes on 2 cores)

Results are recorded in docs/model.md ("What decides bounding").
"""

import math

import numpy as np

from scoutsim import ControllerParameters
from scoutsim.analysis.basin import basin_of_attraction


def report(label, b):
    parts = []
    for m in b.models():
        f = b.fraction(m)
        speeds = [r["mean_speed_m_s"] for r in b.rows
                  if r["model"] == m and r["steady_bounding"] and r["mean_speed_m_s"]]
        sp = f"{np.mean(speeds):.2f} m/s" if speeds else "-"
        parts.append(f"{m}: {f:.2f} ({sp})")
    print(f"{label:<40} " + "   ".join(parts), flush=True)


def main():
    print("fraction of 32 starts reaching steady bounding (mean speed of those that do)")
    for mu in (0.5, 0.6, 0.8, 1.0, 1.5, math.inf):
        report(f"toe friction mu = {mu}", basin_of_attraction(models=("II", "I"),
                                                               friction_coefficient=mu))
    for td, lo in ((4e-3, 3e-3), (6e-3, 4e-3), (8e-3, 6e-3), (10e-3, 8e-3)):
        c = ControllerParameters(touchdown_compression=td, liftoff_compression=lo)
        report(f"mu = 0.8, thresholds {td*1e3:.0f}/{lo*1e3:.0f} mm",
               basin_of_attraction(models=("II",), controller=c, friction_coefficient=0.8))


if __name__ == "__main__":
    main()
