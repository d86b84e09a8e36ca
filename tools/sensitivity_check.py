"""Orbit sensitivities against orbits solved again, for parameters of every kind.

    python tools/sensitivity_check.py [--parameters NAME ...] [--relative-step H]

At the default Model II orbit (Table I, default floor): each parameter's sensitivities
by the implicit function theorem (``orbit_sensitivities``) against central differences
of orbits solved again by Newton at p (1 +- H; default 1e-4, the sensitivities' own
step), metric by metric, the spectral radius's at the tolerances its ends are integrated
at (``radius_integrator``). Prints the relative differences, of the derivative or of its
floor if larger: the orbits' 1e-9 over the step (the reference's own noise), and for the
spectral radius the derivative of elasticity 1 (the radius's integration noise resolves
its elasticity to about 1e-3, not the derivative of a parameter that barely moves it);
then the radius's relative difference of its derivative alone, and its elasticity. About
5 min on a 2-core machine.
"""

from __future__ import annotations

import argparse

from scoutsim.analysis.controlled_orbit import controlled_fixed_point
from scoutsim.analysis.orbit_sensitivity import (
    SENSITIVITY_METRICS,
    orbit_metrics,
    orbit_sensitivities,
    radius_integrator,
    setting_with,
)

#: a leg spring and damper, a belt spring and damper, a motor constant, the current
#: limit, a touchdown angle, a servo gain, the floor
PARAMETERS = (
    "robot.leg_stiffness",
    "robot.leg_damping",
    "robot.belt_stiffness",
    "robot.belt_damping",
    "robot.torque_constant",
    "robot.current_limit",
    "controller.touchdown_angle_front",
    "controller.flight_kp_front",
    "friction_coefficient",
)


def resolved(orbit, name: str, value: float, integrator=None) -> dict:
    """The metrics of the orbit solved again by Newton with ``name`` = ``value``
    (``integrator``: the orbit's if None)."""
    st = setting_with(orbit.setting, name, value)
    integ = integrator or orbit.setting["integrator"]
    o = controlled_fixed_point(
        orbit.state,
        model=st["model"],
        friction_coefficient=st["friction_coefficient"],
        robot=st["robot"],
        controller=st["controller"],
        strides=orbit.strides,
        integrator=integ,
    )
    return orbit_metrics(o.state, o.period, st, integ, o.jacobian)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--parameters", nargs="+", default=list(PARAMETERS))
    ap.add_argument("--relative-step", type=float, default=1e-4, metavar="H")
    args = ap.parse_args()
    orbit = controlled_fixed_point(settle_duration=8.0)
    sens, _ = orbit_sensitivities(
        orbit, args.parameters, relative_step=args.relative_step, workers=None
    )
    metrics = [m for m in SENSITIVITY_METRICS if m != "stride_frequency_hz"]
    heads = metrics + ["spectral radius, of its derivative", "radius elasticity"]
    print("| parameter | " + " | ".join(heads) + " |")
    print("|---|" + "---:|" * len(heads))
    for name in args.parameters:
        s = sens[name]
        if s.status != "ok":
            print(f"| `{name}` | {s.status} |")
            continue
        p = s.value
        h = args.relative_step * abs(p)
        plus, minus = resolved(orbit, name, p + h), resolved(orbit, name, p - h)
        hr = s.radius_step
        tight = radius_integrator(orbit.setting["integrator"])
        rp, rm = resolved(orbit, name, p + hr, tight), resolved(orbit, name, p - hr, tight)
        cells = []
        for m in metrics:
            if m == "spectral_radius":
                ref = (rp[m] - rm[m]) / (2 * hr)
            else:
                ref = (plus[m] - minus[m]) / (2 * h)
            d = s.derivative[m]
            # the floor: the orbits' 1e-9 over the step; for the radius, the derivative of
            # elasticity 1 (its noise, 2.5e-7 over its step, resolves the elasticity)
            floor = rp[m] / abs(p) if m == "spectral_radius" else 1e-9 / h
            rel = abs(d - ref) / max(abs(ref), floor)
            cells.append(f"{rel:.1e}")
        d, ref = (
            s.derivative["spectral_radius"],
            (rp["spectral_radius"] - rm["spectral_radius"]) / (2 * hr),
        )
        cells.append(f"{abs(d - ref) / abs(ref):.1e}")
        cells.append(f"{s.elasticity['spectral_radius']:+.3f}")
        print(f"| `{name}` | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
