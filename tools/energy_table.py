"""The work-energy balance measurements of docs/model.md and docs/explanation/energy.md.

    python tools/energy_table.py            # residuals of every model, floor and robot
    python tools/energy_table.py --terms    # the table of terms of the default Model II run

10 s from the default start each (about a minute after the first compile).
"""

from __future__ import annotations

import argparse
import math

import scoutsim
from scoutsim.simulation.integrator import IntegratorSettings
from scoutsim.validation.make_example import VIRTUAL_SCOUT_EFFECTS

REFERENCE = IntegratorSettings(method="dopri5")
OPTIONS = dict(VIRTUAL_SCOUT_EFFECTS, battery_resistance=0.1)


def residual(model, robot, mu, integrator):
    r = scoutsim.simulate(
        robot,
        duration=10.0,
        model=model,
        integrator=integrator,
        friction_coefficient=mu,
        energy=True,
    )
    return r.energy_balance().relative_residual


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--terms", action="store_true", help="print the default Model II run's table of terms"
    )
    args = ap.parse_args()
    if args.terms:
        b = scoutsim.simulate(
            duration=10.0, model="II", energy=True, integrator=REFERENCE
        ).energy_balance()
        print(
            f"Model II, reference integrator: mean input {b.mean_input_power_W:.1f} W, "
            f"hip work {b.hip_work_J:.1f} J, cost of transport {b.cost_of_transport:.2f}"
        )
        print(b.table())
        d = scoutsim.simulate(duration=10.0, model="II", energy=True).energy_balance()
        print(
            f"default integrator (ARK3): input {d.input_J:.3f} J, relative residual "
            f"{d.relative_residual:.1e}"
        )
        return
    options = scoutsim.RobotParameters().replace(**OPTIONS)
    print("| run | residual, default robot | every option on (and R_b = 0.1 ohm) |")
    print("|---|---|---|")
    for model in ("ideal", "I", "II"):
        cells = []
        for robot in (None, options):
            pair = [residual(model, robot, mu, REFERENCE) for mu in (None, math.inf)]
            cells.append(" / ".join(f"{abs(x):.1e}" for x in pair))
        print(f"| {model}, Coulomb floor / no slip (DOPRI5 rtol 1e-8) | {cells[0]} | {cells[1]} |")
    default = IntegratorSettings()
    pair = [residual("II", None, mu, default) for mu in (None, math.inf)]
    print(
        f"| II, default integrator (ARK3 rtol 1e-5) | "
        f"{' / '.join(f'{abs(x):.1e}' for x in pair)} | "
        f"{abs(residual('II', options, None, default)):.1e} |"
    )


if __name__ == "__main__":
    main()
