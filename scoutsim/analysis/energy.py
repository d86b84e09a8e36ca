"""The work-energy balance of a run: where the energy the motors draw goes.

A run made with ``simulate(energy=True)`` integrates every power flow of the model over each
integrator step (``scoutsim._core.model.power_flows``) and logs the kinetic energy each touchdown impact
dissipates. The balance (docs/model.md "Work-energy balance"):

    electrical energy into the motors
        = copper losses + transmission losses (signed) + hip work
    hip work
        = motor-joint friction + belt damper + leg damper + leg friction + toe sliding
          + constraint work + impact losses + change of mechanical energy
          (kinetic, gravity, leg springs, belt springs)

and the battery's open-circuit energy is the electrical energy plus its internal losses.
For the ideal actuator (no electrical model) the hip work is the input; for the passive
model there is none. The residual (input less every term) is the integration error: it
closes to the integrator's tolerance, and a force that enters the equations of motion with
a power other than the one it claims shows up in it.

    b = scoutsim.simulate(model="II", energy=True).energy_balance()
    print(b.table()); b.residual_J, b.relative_residual

The transmission term follows the paper's constant efficiency N eta K_T in both directions:
while a leg back-drives its motor it is negative (the motor then generates 1/eta times the
mechanical power the leg puts in), a source, shown as such.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..names import LEG_NAMES

#: the terms of the balance, in order: (name, description, flows summed over both legs)
ELECTRICAL_TERMS = (
    ("copper", "motor copper losses R_A i^2", ("copper",)),
    (
        "transmission",
        "transmission losses: the constant efficiency (signed) and the "
        "optional load-dependent losses",
        ("conversion", "gear_loss"),
    ),
)
MECHANICAL_TERMS = (
    (
        "joint_friction",
        "motor-joint viscous and Coulomb friction (Model II)",
        ("joint_viscous", "joint_coulomb"),
    ),
    ("belt_damper", "belt damper (Model II)", ("belt_damper",)),
    ("leg_damper", "telescopic leg dampers", ("leg_damper",)),
    ("leg_friction", "telescopic leg sliding-joint friction", ("leg_friction",)),
    ("toe_sliding", "friction of sliding toes on the floor", ("toe_slide",)),
    (
        "constraint_work",
        "work of the constraint forces (zero up to a strut's stabilisation)",
        ("constraint",),
    ),
)


@dataclass(frozen=True)
class EnergyBalance:
    """One run's work-energy balance; every energy in J.

    ``terms``: (name, energy [J], description) in the order of the balance, each counted
    as a use of the input (positive: energy taken out of it; a negative term is a source);
    ``input_J``: the electrical energy into the motors (Model I, II), the hip work (ideal
    actuator) or 0 (passive); ``residual_J`` = input - sum of the terms;
    ``relative_residual`` = residual / reference, the reference being the input or, for the
    passive model, the mechanical energy at the start."""

    model: str
    input_name: str
    input_J: float
    terms: tuple
    battery_J: float
    battery_loss_J: float
    hip_work_J: float
    duration_s: float
    flows: dict  #: result.energy_flows: every flow per leg [J]
    #: distance the torso travelled forward over the run [m] (None for a streamed run,
    #: whose result holds only its end) and the robot's total mass [kg]
    distance_m: float | None = None
    total_mass_kg: float | None = None
    gravity: float = 9.81

    @property
    def mean_input_power_W(self) -> float:
        """The input averaged over the run [W]."""
        return self.input_J / self.duration_s if self.duration_s > 0 else float("nan")

    @property
    def cost_of_transport(self) -> float | None:
        """Input per weight and distance, E / (m g d) [-] (None without a distance)."""
        if not self.distance_m or not self.total_mass_kg or self.distance_m <= 0:
            return None
        return self.input_J / (self.total_mass_kg * self.gravity * self.distance_m)

    @property
    def residual_J(self) -> float:
        return self.input_J - sum(e for _, e, _ in self.terms)

    @property
    def reference_J(self) -> float:
        """What the residual is relative to [J]: the input, or for the passive model the
        mechanical energy at the start (at least 1 J)."""
        if self.input_J != 0.0:
            return abs(self.input_J)
        return max(abs(self.flows["mechanical_start"]), 1.0)

    @property
    def relative_residual(self) -> float:
        return self.residual_J / self.reference_J

    def term(self, name: str) -> float:
        """The energy [J] of the term ``name``."""
        for n, e, _ in self.terms:
            if n == name:
                return e
        raise KeyError(f"no term {name!r}: the terms are {', '.join(n for n, _, _ in self.terms)}")

    def as_dict(self) -> dict:
        """JSON-safe: the input, every term, the residual [J]."""
        return (
            {"model": self.model, "input": self.input_name, "input_J": self.input_J}
            | {f"{n}_J": e for n, e, _ in self.terms}
            | {
                "battery_J": self.battery_J,
                "battery_loss_J": self.battery_loss_J,
                "residual_J": self.residual_J,
                "relative_residual": self.relative_residual,
                "mean_input_power_W": self.mean_input_power_W,
                "cost_of_transport": self.cost_of_transport,
            }
        )

    def table(self) -> str:
        """The balance as a Markdown table (term, energy [J], share of the input)."""
        ref = self.reference_J
        rows = [f"| {self.input_name} (input) | {self.input_J:.3f} | 100 % |"]
        for _name, e, d in self.terms:
            rows.append(f"| {d} | {e:.3f} | {100.0 * e / ref:.1f} % |")
        rows.append(f"| residual | {self.residual_J:.2e} | {self.relative_residual:.1e} |")
        return "\n".join(["| term | energy [J] | share |", "|---|---|---|"] + rows)


def energy_balance(result) -> EnergyBalance:
    """The work-energy balance of ``result`` (a run made with ``simulate(energy=True)``)."""
    flows = result.energy_flows
    if flows is None:
        raise ValueError(
            "this run did not account for its energy: run it with "
            "simulate(..., energy=True) (scoutsim run does by default)"
        )
    model = result.provenance.get("model", "II")

    def both(*names):
        return sum(flows[f"{n}_{leg}"] for n in names for leg in LEG_NAMES)

    electrical = both("electrical")
    hip = both("hip_work")
    terms = []
    if model in ("I", "II"):
        input_name, input_J = "electrical energy into the motors", electrical
        for name, desc, names in ELECTRICAL_TERMS:
            terms.append((name, both(*names), desc))
    elif model == "ideal":
        input_name, input_J = "hip work", hip
    else:
        input_name, input_J = "none (passive)", 0.0
    for name, desc, names in MECHANICAL_TERMS:
        terms.append((name, both(*names), desc))
    terms.append(("impacts", flows["impacts"], "touchdown impacts"))
    terms.append(
        (
            "mechanical_change",
            flows["mechanical_end"] - flows["mechanical_start"],
            "change of mechanical energy (kinetic, gravity, leg and belt springs)",
        )
    )
    distance = None
    if "stream" not in result.provenance and len(result.t):
        distance = float(result.x[-1] - result.x[0])
    robot = result.provenance.get("robot") or {}
    mass = gravity = None
    if robot:
        from ..parameters import RobotParameters

        params = RobotParameters(**robot)
        mass, gravity = params.total_mass, params.gravity
    return EnergyBalance(
        model=model,
        input_name=input_name,
        input_J=input_J,
        terms=tuple(terms),
        battery_J=(electrical + flows["battery_loss"]) if model in ("I", "II") else 0.0,
        battery_loss_J=flows["battery_loss"],
        hip_work_J=hip,
        duration_s=float(result.t_end),
        flows=dict(flows),
        distance_m=distance,
        total_mass_kg=mass,
        gravity=gravity or 9.81,
    )
