"""The cases of an assumption study (:mod:`scoutsim.analysis.assumptions`): a ladder of
models from the ideal actuator to Model II with the virtual Scout II's error sources, and
each effect of the richest model switched off one at a time.

The paper builds two models "exhibiting different levels of modeling complexity, towards
determining which assumptions are reasonable for Scout II" (Sec. I) and concludes that
"without the actuator saturation taken into account the models do not converge to cyclic
motion" and that "the assumption of rigid torque transmission is not valid" (Sec. V).
A case here is one such level: a model variant (``simulate(..., model=...)``) and the
robot's parameters changed from the study's robot. Every switch is a parameter set to its
neutral value or to a limit that was checked (energy balance, the switched-off run sane);
an effect that cannot be switched off that way is reported, not faked.

The ladder (rungs, from the simplest):

``ideal``
    The ideal actuator with constant maximum torque: ``model="ideal"``, the hip torque
    limited only by the current limit, N eta K_T i_max (31.1 N m at Scout II's leg), no
    torque-speed line, no battery; rigid transmission (docs/specification.md section 4).
``ideal+line``
    The ideal actuator with the motor's torque-speed line and nothing else: Model I with
    ``current_limit`` = :data:`NO_CURRENT_LIMIT_A` (1e5 A, the largest the parameters allow;
    the line's current is at most (V_b + K_w |w_m|) / R_A, 30 A at stall, so the limit
    never binds) and an ideal battery (``battery_resistance`` = 0): the torque is bounded
    by the line alone, up to the stall torque N eta K_T V / R_A (77.8 N m).
``I``
    Model I: the current limit and the torque-speed line (and battery sag if the robot has
    a battery resistance), rigid transmission without gear inertia.
``II``
    Model II: Model I plus the hip unit (belt spring and damper, gear inertias, motor-joint
    stiction and damping; paper Sec. III, Table II).
``II+effects``
    Model II with the virtual Scout II's error sources
    (:data:`~scoutsim.validation.make_example.VIRTUAL_SCOUT_EFFECTS`: backlash, leg
    friction with its side-load term, angle-dependent leg damping, gearbox losses), each
    applied where the robot's own value is 0 (off); a value the robot file sets is kept.
    The richest model, and the default reference.

The switches (each from the richest rung, one at a time; ``-NAME``):

``saturation``
    The torque-speed line off, the current limit kept: ``battery_voltage`` = 1e4 V (the
    largest allowed), which moves the line to (1e4 V - K_w w_m) / R_A, 8.3 kA, far beyond
    i_max. The controller is made for the run's robot, as every run's is: the Table I law's
    eqs. (2)-(4) take tau_max = N eta K_T V / R_A from it, so its stance-retraction command
    becomes the constant current limit. Actuator and controller then both lack the line:
    the paper's "constant max torque".
``belt``
    Belt compliance off (the rigid limit of the belt spring): ``belt_stiffness`` x
    :data:`RIGID_BELT_FACTOR` (1000, 4.0e5 N m/rad at Scout II). The gear train, its
    inertia, the motor joint, the belt damper and the backlash stay. Measured on Scout II
    with the virtual robot's effects (Table I, 6 s): the metrics at x100 and x1000 agree
    to 0.2 %, the belt's deflection falls to the backlash's half-play, and the energy
    balance closes as at x1 (relative residual 5e-7 at x1, 1e-6 at x100, 2.4e-6 at
    x1000: the ARK3 method's).
``gear-inertia``
    Not switchable alone: Model II's driven-gear coordinate needs an inertia (a reflected
    gear inertia of 0 is refused), and the limit towards 0 is not sane (at 1/100 of Table
    II the energy balance misses by 20 times the energy put in). Rigid transmission without
    gear inertia is Model I (the ladder).
``stiction``
    Motor-joint stiction off: ``joint_stiction`` = 0 (the joint's viscous damping stays).
``battery-sag``
    ``battery_resistance`` = 0 (an ideal source).
``backlash``
    ``belt_backlash`` = 0 (the belt spring engaged at every deflection).
``leg-friction``
    ``leg_friction_force`` = 0 and ``leg_friction_side_load_coefficient`` = 0.
``leg-damping-angle``
    ``leg_damping_angle_coefficient`` = 0 (the leg damper constant at every angle).
``gearbox-losses``
    ``gearbox_idle_loss_torque`` = 0 and ``gearbox_load_loss_coefficient`` = 0: the
    paper's constant efficiency (Table III) stays.

A switch whose robot equals the richest rung's (the effect is 0 there: Scout II has no
battery resistance) is reported as absent and not run.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass, field

from ..parameters import ImplausibleParameterWarning, RobotParameters

__all__ = [
    "AssumptionCase",
    "RUNG_NAMES",
    "SWITCH_NAMES",
    "RICHEST",
    "NO_CURRENT_LIMIT_A",
    "LINE_OFF_BATTERY_VOLTAGE_V",
    "RIGID_BELT_FACTOR",
    "assumption_cases",
    "richest_robot",
]

#: current limit [A] of the rung without one (the largest value the parameters allow)
NO_CURRENT_LIMIT_A = 1.0e5
#: battery voltage [V] that moves the torque-speed line far beyond the current limit
LINE_OFF_BATTERY_VOLTAGE_V = 1.0e4
#: factor on the belt spring of the rigid belt (checked: x100 and x1000 agree)
RIGID_BELT_FACTOR = 1000.0

#: the rungs of the ladder, simplest first
RUNG_NAMES = ("ideal", "ideal+line", "I", "II", "II+effects")
#: the richest rung: the switches start from it
RICHEST = "II+effects"
#: the effects switched off one at a time
SWITCH_NAMES = (
    "saturation",
    "belt",
    "gear-inertia",
    "stiction",
    "battery-sag",
    "backlash",
    "leg-friction",
    "leg-damping-angle",
    "gearbox-losses",
)

_MEANING = {
    "ideal": "ideal actuator, constant maximum torque (current limit only), rigid",
    "ideal+line": "torque-speed line only (Model I, no current limit, ideal battery), rigid",
    "I": "Model I: current limit and torque-speed line, rigid transmission",
    "II": "Model II: belt, gear inertia, motor-joint friction",
    "II+effects": "Model II + the virtual Scout II's error sources",
    "saturation": "torque-speed line off (battery_voltage 1e4 V), current limit kept",
    "belt": "belt spring x1000 (rigid belt), gears, damper and play kept",
    "gear-inertia": "not switchable alone: Model II needs the gear inertia",
    "stiction": "joint_stiction = 0",
    "battery-sag": "battery_resistance = 0",
    "backlash": "belt_backlash = 0",
    "leg-friction": "leg_friction_force = 0, leg_friction_side_load_coefficient = 0",
    "leg-damping-angle": "leg_damping_angle_coefficient = 0",
    "gearbox-losses": "gearbox_idle_loss_torque = 0, gearbox_load_loss_coefficient = 0",
}

_GEAR_INERTIA_REASON = (
    "Model II's driven-gear coordinate needs an inertia (J_2 + N^2 J_1 > 0) and the limit "
    "towards 0 is not sane (energy balance fails at 1/100 of Table II); rigid "
    "transmission without gear inertia is Model I"
)


@dataclass(frozen=True)
class AssumptionCase:
    """One case of an assumption study.

    Attributes
    ----------
    name : the rung's name (:data:`RUNG_NAMES`) or ``"-"`` + the switch's
        (:data:`SWITCH_NAMES`).
    kind : "rung" or "switch".
    model : the model variant the case runs ("ideal", "I", "II").
    robot : the case's RobotParameters (None when it does not run).
    meaning : what the case is, in a line.
    status : "run", "absent" (the effect is 0 in the richest rung: nothing to switch off)
        or "not_switchable" (the effect cannot be switched off alone; ``reason`` says why).
    reason : why a case does not run ("" when it runs).
    changes : the robot's fields the case sets, by name (SI): the switch's parameters, the
        rung's (``ideal+line``: the current limit and battery resistance; ``II+effects``:
        the virtual robot's effects); empty when the case is the robot itself.
    """

    name: str
    kind: str
    model: str
    robot: RobotParameters | None
    meaning: str
    status: str = "run"
    reason: str = ""
    changes: dict = field(default_factory=dict)


def _replace(robot: RobotParameters, **changes) -> RobotParameters:
    """``robot`` with ``changes`` (SI); the deliberate limits (1e4 V, 1e5 A) are far from a
    robot of this kind on purpose, so their plausibility warning is not shown."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ImplausibleParameterWarning)
        return robot.replace(**changes)


def richest_robot(robot: RobotParameters | None = None) -> RobotParameters:
    """``robot`` (default Scout II) with the virtual Scout II's error sources applied to
    the fields that are 0 (off) in it (a value the robot sets is kept)."""
    from ..validation.make_example import VIRTUAL_SCOUT_EFFECTS

    robot = robot if robot is not None else RobotParameters()
    changes = {
        name: value
        for name, value in VIRTUAL_SCOUT_EFFECTS.items()
        if all(v == 0.0 for v in robot.per_leg(name))
    }
    return _replace(robot, **changes) if changes else robot


def _scaled(robot: RobotParameters, name: str, factor: float):
    """The field ``name`` times ``factor``, per leg (a (back, front) pair if they differ)."""
    back, front = robot.per_leg(name)
    return back * factor if back == front else (back * factor, front * factor)


def _switch_changes(name: str, rich: RobotParameters) -> dict:
    """The parameter changes of switch ``name`` from the richest robot ``rich``."""
    if name == "saturation":
        return {"battery_voltage": LINE_OFF_BATTERY_VOLTAGE_V}
    if name == "belt":
        return {"belt_stiffness": _scaled(rich, "belt_stiffness", RIGID_BELT_FACTOR)}
    if name == "stiction":
        return {"joint_stiction": 0.0}
    if name == "battery-sag":
        return {"battery_resistance": 0.0}
    if name == "backlash":
        return {"belt_backlash": 0.0}
    if name == "leg-friction":
        return {"leg_friction_force": 0.0, "leg_friction_side_load_coefficient": 0.0}
    if name == "leg-damping-angle":
        return {"leg_damping_angle_coefficient": 0.0}
    if name == "gearbox-losses":
        return {"gearbox_idle_loss_torque": 0.0, "gearbox_load_loss_coefficient": 0.0}
    raise ValueError(f"unknown switch {name!r}; switches: {', '.join(SWITCH_NAMES)}")


def _rungs(robot: RobotParameters) -> list[AssumptionCase]:
    line = {"current_limit": NO_CURRENT_LIMIT_A, "battery_resistance": 0.0}
    rich = richest_robot(robot)
    effects = {
        k: getattr(rich, k)
        for k in dataclasses.asdict(rich)
        if getattr(rich, k) != getattr(robot, k)
    }
    specs: tuple[tuple[str, str, RobotParameters, dict], ...] = (
        ("ideal", "ideal", robot, {}),
        ("ideal+line", "I", _replace(robot, **line), line),
        ("I", "I", robot, {}),
        ("II", "II", robot, {}),
        (RICHEST, "II", rich, effects),
    )
    return [AssumptionCase(n, "rung", m, r, _MEANING[n], changes=c) for n, m, r, c in specs]


def _switch(name: str, rich: RobotParameters) -> AssumptionCase:
    label = "-" + name
    if name == "gear-inertia":
        return AssumptionCase(
            label, "switch", "II", None, _MEANING[name], "not_switchable", _GEAR_INERTIA_REASON
        )
    changes = _switch_changes(name, rich)
    robot = _replace(rich, **changes)
    if robot == rich:
        absent = ", ".join(f"{k} = {getattr(rich, k)!r}" for k in changes)
        return AssumptionCase(
            label,
            "switch",
            "II",
            None,
            _MEANING[name],
            "absent",
            f"not in the richest model ({absent}): nothing to switch off",
            changes,
        )
    return AssumptionCase(label, "switch", "II", robot, _MEANING[name], changes=changes)


def assumption_cases(
    robot: RobotParameters | None = None, switches=SWITCH_NAMES, rungs=RUNG_NAMES
) -> list[AssumptionCase]:
    """The cases of an assumption study of ``robot`` (default Scout II): the rungs
    ``rungs`` (of :data:`RUNG_NAMES`, in its order) and the switches ``switches`` (of
    :data:`SWITCH_NAMES`) from the richest rung (module docstring)."""
    robot = robot if robot is not None else RobotParameters()
    for name in rungs:
        if name not in RUNG_NAMES:
            raise ValueError(f"unknown rung {name!r}; rungs: {', '.join(RUNG_NAMES)}")
    for name in switches:
        if name not in SWITCH_NAMES:
            raise ValueError(f"unknown switch {name!r}; switches: {', '.join(SWITCH_NAMES)}")
    ladder = [c for c in _rungs(robot) if c.name in rungs]
    rich = richest_robot(robot)
    return ladder + [_switch(name, rich) for name in switches]
