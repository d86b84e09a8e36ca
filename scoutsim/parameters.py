"""Robot and controller parameters (docs/specification.md sections 2, 4, 5, 6; paper Tables I-III).

All fields are SI (angles in rad). The defaults live once, as data, in
``scoutsim/data/scout2.toml`` with unit and provenance; :func:`load_robot` and
:func:`load_controller` read that file, apply a user's TOML file and/or Python overrides,
convert units once, and validate every value.

Mass and hip-unit quantities are per *physical* leg. A virtual leg lumps
``legs_per_virtual_leg`` physical legs (docs/specification.md section 1); the compiled model multiplies
per-leg quantities by that number in exactly one place (the compiled model, ``scoutsim.model``).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import numbers
import tomllib
import typing
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from os import PathLike
from pathlib import Path

#: The default floor of every simulation, command and study: Coulomb friction mu = 1.0 at
#: the toe [assumed: rubber-covered toes on carpet, where the paper's experiments ran; the
#: paper gives no value]. mu = inf is a no-slip floor (the specification's idealisation), an option.
#: Why 1.0: from the default start, ideal, Model I and Model II all reach the bounding
#: cycle from every start of a neighbourhood around it on this floor (docs/model.md,
#: "Default start and floor"); on a no-slip floor Model II does from fewer than half.
DEFAULT_FRICTION_COEFFICIENT = 1.0


# =========================================================================================
# Units and the packaged defaults (scout2.toml: the one home of every default value)
# =========================================================================================

#: Allowed unit strings and their SI factors (SI value = value * factor), grouped by
#: dimension. The first unit of each group, with factor 1, is the SI unit. This is the one
#: place where degrees (and every other non-SI unit) are converted.
UNITS: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "cm": 1.0e-2, "mm": 1.0e-3},
    "angle": {"rad": 1.0, "deg": math.pi / 180.0},
    "time": {"s": 1.0, "ms": 1.0e-3},
    "angular rate": {"rad/s": 1.0, "deg/s": math.pi / 180.0},
    "mass": {"kg": 1.0, "g": 1.0e-3},
    "inertia": {"kg m^2": 1.0, "kg cm^2": 1.0e-4, "kg mm^2": 1.0e-6, "g cm^2": 1.0e-7},
    "acceleration": {"m/s^2": 1.0},
    "stiffness": {"N/m": 1.0, "N/mm": 1.0e3},
    "damping": {"N s/m": 1.0, "N s/mm": 1.0e3},
    "torque": {"N m": 1.0, "mN m": 1.0e-3},
    "force": {"N": 1.0},
    "per squared angle": {"1/rad^2": 1.0, "1/deg^2": (180.0 / math.pi) ** 2},
    "rotational stiffness": {"N m/rad": 1.0, "N m/deg": 180.0 / math.pi},
    "rotational damping": {"N m s/rad": 1.0, "N m/(rad/s)": 1.0, "N m/(deg/s)": 180.0 / math.pi},
    "torque constant": {"N m/A": 1.0, "mN m/A": 1.0e-3},
    "speed constant": {"V s/rad": 1.0, "V/(rad/s)": 1.0, "mV/rpm": 1.0e-3 * 60.0 / (2.0 * math.pi)},
    "resistance": {"ohm": 1.0},
    "current": {"A": 1.0, "mA": 1.0e-3},
    "voltage": {"V": 1.0},
    "dimensionless": {"1": 1.0},
    "angle per angle": {"rad/rad": 1.0, "deg/deg": 1.0},
    "angle per angular rate": {"rad/(rad/s)": 1.0, "deg/(deg/s)": 1.0},
    "boolean": {"bool": 1.0},
}

#: unit string -> (dimension, SI factor); every unit string belongs to one dimension only.
_UNIT_INDEX: dict[str, tuple[str, float]] = {
    unit: (dim, factor) for dim, group in UNITS.items() for unit, factor in group.items()
}
assert len(_UNIT_INDEX) == sum(map(len, UNITS.values())), "unit strings must be unique"

_PACKAGED_NAME = "scout2.toml"


@lru_cache(maxsize=1)
def _packaged() -> dict:
    """Parsed packaged ``scout2.toml`` (importlib.resources, with a file-system fallback)."""
    try:
        text = resources.files(__package__ or "scoutsim").joinpath("data", _PACKAGED_NAME).read_text("utf-8")
    except (OSError, TypeError, ValueError, ModuleNotFoundError):
        # e.g. a namespace package under an editable install
        text = (Path(__file__).resolve().parent / "data" / _PACKAGED_NAME).read_text("utf-8")
    return tomllib.loads(text)


def _packaged_defaults(*sections: str):
    """Class decorator: every annotated field of the class gets, as its default, the SI value
    of its entry in the packaged ``scout2.toml`` (in one of ``sections``), converted with the
    entry's unit. The dataclass field list and the file must name the same parameters."""
    def fill(cls):
        data = _packaged()
        entries = {n: e for sec in sections for n, e in data[sec].items()}
        for name, kind in cls.__annotations__.items():
            if name not in entries:
                raise RuntimeError(f"packaged {_PACKAGED_NAME} lacks {name} (sections {sections})")
            entry = entries[name]
            value = entry["value"]
            if kind == "bool":
                default = bool(value)
            elif kind == "int":
                default = int(value)
            else:
                default = float(value) * _UNIT_INDEX[entry["unit"]][1]
            setattr(cls, name, default)
        return cls
    return fill


@dataclass(frozen=True)
class Environment:
    """The world the robot runs in: a flat, rigid, level floor at y = 0 with Coulomb
    friction at the toe (docs/specification.md section 3).

    Attributes
    ----------
    friction_coefficient : float or None
        Coulomb coefficient mu [-] of the toe on the floor, > 0; ``math.inf`` is a no-slip
        floor. None (default): :data:`DEFAULT_FRICTION_COEFFICIENT` (1.0), except for
        massless legs (their ground force lies along the leg, so slip is not defined):
        no slip.
    """

    friction_coefficient: float | None = None

    def __post_init__(self):
        mu = self.friction_coefficient
        if mu is not None and not (isinstance(mu, numbers.Real) and not isinstance(mu, bool)
                                   and mu > 0.0):
            raise ParameterError(f"Environment.friction_coefficient = {mu!r} is not allowed: "
                                 "must be a number > 0 (inf for a no-slip floor) or None")

    def friction_for(self, robot: "RobotParameters") -> float:
        """The toe's Coulomb coefficient mu [-] for ``robot`` on this floor (the default
        rule above when ``friction_coefficient`` is None)."""
        if self.friction_coefficient is not None:
            return float(self.friction_coefficient)
        massless = robot.leg_mass == 0.0 and robot.leg_inertia == 0.0
        return math.inf if massless else DEFAULT_FRICTION_COEFFICIENT


def floor_label(mu: float) -> str:
    """Name of a floor by its toe friction coefficient mu [-]: 'no slip' (inf) or 'mu = 1.0'."""
    return "no slip" if math.isinf(mu) else f"mu = {mu:g}"


@dataclass(frozen=True)
@_packaged_defaults("robot", "transmission", "motor")
class RobotParameters:
    """Physical parameters of the planar Scout II model (SI units).

    Attributes
    ----------
    torso_mass : float
        Torso mass m_torso [kg] (Table III).
    torso_inertia : float
        Torso pitch inertia about its COM [kg m^2] (Table III).
    leg_mass : float
        Mass of one physical leg body [kg] (Table III).
    leg_inertia : float
        Inertia of one physical leg about its own COM [kg m^2] (Table III).
    leg_stiffness : float
        Leg spring constant k, one physical leg [N/m] (Table III).
    leg_damping : float
        Leg damper constant c, one physical leg [N s/m] (Table III).
    hip_spacing : float
        Distance between front and back hips [m] (Table III); L = hip_spacing/2.
    leg_rest_length : float
        Leg rest length l0 = mechanical stop [m] (Table III).
    leg_com_distance : float
        Distance from hip to leg COM along the leg axis [m] (assumed l0/2).
    legs_per_virtual_leg : int
        Physical legs lumped in one virtual leg (2 for bounding).
    gravity : float
        Gravitational acceleration [m/s^2].
    torso_length, torso_height : float
        Torso box used for fall detection [m] (assumed).
    planetary_ratio, sprocket_ratio : float
        Gear ratios [-]; N = planetary_ratio * sprocket_ratio (Table III).
    gearbox_efficiency, sprocket_efficiency : float
        Efficiencies in (0, 1]; eta = product (Table III).
    gearbox_idle_loss_torque : float
        tau_idle, torque-independent transmission loss at the leg side, per physical leg
        [N m] (assumed, default 0). Together with ``gearbox_load_loss_coefficient`` it makes
        the efficiency fall at low torque (paper Sec. IV.B; docs/model.md "Transmission
        losses"). Zero (with a zero coefficient) recovers the constant efficiency exactly.
    gearbox_load_loss_coefficient : float
        c_load, load-proportional loss tau_loss = tau_idle + c_load |tau_out| [-], in [0, 1)
        (assumed, default 0).
    drive_gear_inertia : float
        J_1, drive (motor-side) gear inertia [kg m^2] (Table II).
    driven_gear_inertia : float
        J_2, driven gear inertia [kg m^2] (Table II).
    joint_stiction : float
        Breakaway (and kinetic Coulomb) friction torque at the motor joint [N m] (Table II).
    joint_damping : float
        Viscous damping at the motor joint [N m s/rad] (Table II, 6.2e-7 N m/(deg/s)).
    belt_stiffness : float
        k_b, lumped backlash/belt torsional spring [N m/rad] (Table II, 7 N m/deg).
    belt_damping : float
        c_b, lumped belt damper [N m s/rad] (Table II, 4 N m/(deg/s)).
    belt_backlash : float
        Total angular play of the hip unit [rad] (assumed, default 0: the paper lumps
        backlash into the belt spring). With play b the belt spring acts only beyond
        |alpha - phi| = b / 2: tau_spring = k_b (delta - sign(delta) b / 2) there, 0 inside
        (a dead zone); the belt damper acts throughout (docs/model.md, "Effects beyond the
        paper's models").
    leg_friction_force : float
        Coulomb friction of the telescopic leg's sliding joint [N], per physical leg
        (assumed, default 0), opposing the leg-length rate; regularised linearly over
        |dl/dt| < ``model.leg.LEG_FRICTION_SPEED`` (1 mm/s), so it holds a leg whose net
        spring force is below it almost still (stiction).
    leg_friction_side_load_coefficient : float
        Additional leg friction per unit side load of the sliding joint [-] (assumed,
        default 0): friction force += coefficient x |hip torque| / l, the bending load the
        hip torque puts on the leg's bushings (torque-dependent friction, paper Sec. IV.B).
    leg_damping_angle_coefficient : float
        a_phi [1/rad^2] (assumed, default 0): the leg damper is c (1 + a_phi phi^2), rising
        with the leg's angle phi from the torso normal (angle-dependent damping, paper
        Sec. IV.B).
    torque_constant : float
        Motor torque constant K_T [N m/A] (assumed).
    speed_constant : float
        Motor back-EMF constant K_w [V s/rad] (assumed).
    armature_resistance : float
        R_A [ohm] (assumed).
    current_limit : float
        Amplifier current limit i_max [A] (assumed).
    battery_voltage : float
        Battery (open-circuit) voltage; V_bar = 36 V by default [V] (paper Sec. II.A).
    battery_resistance : float
        Internal resistance shared by all motors [ohm]; 0 = ideal source (assumed).
    """

    torso_mass: float
    torso_inertia: float
    leg_mass: float
    leg_inertia: float
    leg_stiffness: float
    leg_damping: float
    hip_spacing: float
    leg_rest_length: float
    leg_com_distance: float
    legs_per_virtual_leg: int
    gravity: float
    torso_length: float
    torso_height: float
    planetary_ratio: float
    sprocket_ratio: float
    gearbox_efficiency: float
    sprocket_efficiency: float
    gearbox_idle_loss_torque: float
    gearbox_load_loss_coefficient: float
    drive_gear_inertia: float
    driven_gear_inertia: float
    joint_stiction: float
    joint_damping: float
    belt_stiffness: float
    belt_damping: float
    belt_backlash: float
    leg_friction_force: float
    leg_friction_side_load_coefficient: float
    leg_damping_angle_coefficient: float
    torque_constant: float
    speed_constant: float
    armature_resistance: float
    current_limit: float
    battery_voltage: float
    battery_resistance: float

    # -- derived quantities (docs/specification.md section 4) ------------------------------------------
    @property
    def gear_ratio(self) -> float:
        """Combined gear ratio N = planetary x sprocket [-] (docs/specification.md section 4: 102.18)."""
        return self.planetary_ratio * self.sprocket_ratio

    @property
    def efficiency(self) -> float:
        """Constant transmission efficiency eta = gearbox x sprocket [-] (0.6528)."""
        return self.gearbox_efficiency * self.sprocket_efficiency

    @property
    def half_hip_spacing(self) -> float:
        """L, distance from torso COM to each hip [m]."""
        return 0.5 * self.hip_spacing

    @property
    def torque_per_amp(self) -> float:
        """Hip torque per ampere of motor current, N eta K_T [N m/A] (the compiled model's
        counterpart is ``scoutsim.model.actuator.torque_per_amp``)."""
        return self.gear_ratio * self.efficiency * self.torque_constant

    @property
    def stall_torque(self) -> float:
        """Torque-speed line at zero speed, at one physical leg: N eta K_T V / R_A [N m]
        (tau_max of the paper's eq. (3), written at the leg)."""
        return self.torque_per_amp * self.battery_voltage / self.armature_resistance

    @property
    def torque_speed_slope(self) -> float:
        """Torque lost per unit leg speed on the torque-speed line, at one physical leg:
        N^2 eta K_T K_w / R_A [N m s/rad] (minus the slope A of the paper's eq. (3), written
        at the leg)."""
        N = self.gear_ratio
        return N * N * self.efficiency * self.torque_constant * self.speed_constant \
            / self.armature_resistance

    @property
    def no_load_speed(self) -> float:
        """Leg speed where the torque-speed line crosses zero torque, V / (K_w N) [rad/s]."""
        return self.battery_voltage / (self.speed_constant * self.gear_ratio)

    @property
    def max_leg_torque(self) -> float:
        """Current-limited torque at one physical leg, N eta K_T i_max [N m]."""
        return self.torque_per_amp * self.current_limit

    @property
    def total_mass(self) -> float:
        """Torso plus all four physical legs [kg]."""
        return self.torso_mass + 2 * self.legs_per_virtual_leg * self.leg_mass

    def replace(self, **changes) -> "RobotParameters":
        """Return a copy with some fields changed (validated by the loader functions)."""
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
@_packaged_defaults("controller")
class ControllerParameters:
    """Bounding controller settings (paper Sec. II, Table I; docs/specification.md section 6), SI units.

    Gains are per physical leg, leg side (N m/rad, N m s/rad). Angles are relative to the
    torso [rad], positive with the toe ahead of the hip.

    Attributes
    ----------
    touchdown_angle_front, touchdown_angle_back : float
        Flight servo set point phi_td [rad] (Table I: 21 and 19 deg).
    sweep_limit_front, sweep_limit_back : float
        Sweep-limit angle ending stance-retraction [rad] (Table I: 0).
    flight_kp_front, flight_kd_front, flight_kp_back, flight_kd_back : float
        Flight PD gains [N m/rad], [N m s/rad] (Table I: 250, 5).
    brake_kp_front, brake_kd_front, brake_kp_back, brake_kd_back : float
        Stance-brake PD gains [N m/rad], [N m s/rad] (Table I: 300, 5).
    control_period : float
        Sample-and-hold period [s] (1 ms).
    touchdown_compression : float
        Leg compression l0 - l above which the controller declares touchdown [m] (assumed).
    liftoff_compression : float
        Leg compression below which the controller declares lift-off [m] (assumed);
        must be smaller than touchdown_compression (hysteresis).
    sense_motor_angle : bool
        Model II only: sense the motor-side angle alpha (encoder) instead of phi.
    pitch_gain_front, pitch_gain_back : float
        Torso feedback of :class:`~scoutsim.control.pitch_feedback.PitchFeedbackController`
        (not Table I; the Table I controller ignores them): change of the touchdown angle
        per unit of torso pitch, k_theta [rad/rad] (given in deg/deg).
    pitch_rate_gain_front, pitch_rate_gain_back : float
        Its change of the touchdown angle per unit of pitch rate, k_omega [rad/(rad/s)] = [s]
        (given in deg/(deg/s)).
    """

    touchdown_angle_front: float
    touchdown_angle_back: float
    sweep_limit_front: float
    sweep_limit_back: float
    flight_kp_front: float
    flight_kd_front: float
    flight_kp_back: float
    flight_kd_back: float
    brake_kp_front: float
    brake_kd_front: float
    brake_kp_back: float
    brake_kd_back: float
    control_period: float
    touchdown_compression: float
    liftoff_compression: float
    sense_motor_angle: bool
    pitch_gain_front: float
    pitch_gain_back: float
    pitch_rate_gain_front: float
    pitch_rate_gain_back: float

    def replace(self, **changes) -> "ControllerParameters":
        """Return a copy with some fields changed."""
        return dataclasses.replace(self, **changes)


# =========================================================================================
# Loading, unit conversion and validation
# =========================================================================================


#: TOML section -> dataclass whose fields it holds.
SECTIONS: dict[str, type] = {
    "robot": RobotParameters,
    "transmission": RobotParameters,
    "motor": RobotParameters,
    "controller": ControllerParameters,
}

#: sections of a robot file read by other loaders: name -> the function that reads them
SEPARATE_SECTIONS: dict[str, str] = {
    "sensors": "scoutsim.control.sensors.load_sensors",
    "controller_law": "scoutsim.analysis.controller_file.read_controller_file",
}

_HALF_PI = 0.5 * math.pi


def quantity_to_si(entry: object, dimension: str, unit: str, label: str) -> float:
    """One quantity of a file to SI: a plain number in ``unit``, or ``{ value = ..., unit =
    "..." }`` in any unit of :data:`UNITS` of ``dimension``; ParameterError naming
    ``label`` otherwise."""
    if isinstance(entry, dict):
        if extra := sorted(set(entry) - {"value", "unit", "source"}):
            raise ParameterError(f"{label}: unknown key(s) {extra}; allowed keys are value, "
                                 "unit, source", label)
        if "value" not in entry:
            raise ParameterError(f"{label}: entry has no 'value'", label)
        unit = entry.get("unit", unit)
        entry = entry["value"]
    if not isinstance(unit, str) or unit.strip() not in UNITS[dimension]:
        raise ParameterError(f"{label}: unit {unit!r} is not allowed; allowed units: "
                             f"{', '.join(UNITS[dimension])}", label)
    if isinstance(entry, bool) or not isinstance(entry, numbers.Real) or \
            not math.isfinite(float(entry)):
        raise ParameterError(f"{label} = {entry!r} is not allowed: must be a finite number",
                             label)
    return float(entry) * UNITS[dimension][unit.strip()]


class ParameterError(ValueError):
    """A parameter value, unit, key or file is not acceptable.

    Parameters
    ----------
    message : str
        Human-readable explanation naming the field, the offending value and what is allowed.
    field : str or None, optional
        Name of the offending field, when there is one.
    """

    def __init__(self, message: str, field: str | None = None):
        super().__init__(message)
        self.field = field


@dataclass(frozen=True)
class _Range:
    """Allowed interval of a field, in SI units (``None`` = unbounded)."""

    lo: float | None = None
    lo_closed: bool = True
    hi: float | None = None
    hi_closed: bool = True

    def contains(self, x: float) -> bool:
        if self.lo is not None and (x < self.lo or (x == self.lo and not self.lo_closed)):
            return False
        return self.hi is None or x < self.hi or (x == self.hi and self.hi_closed)

    def describe(self, factor: float, unit: str) -> str:
        lo = None if self.lo is None else _fmt_bound(self.lo / factor)
        hi = None if self.hi is None else _fmt_bound(self.hi / factor)
        if hi is None:
            text = f"{'>=' if self.lo_closed else '>'} {lo}"
        elif lo is None:
            text = f"{'<=' if self.hi_closed else '<'} {hi}"
        else:
            text = f"in {'[' if self.lo_closed else '('}{lo}, {hi}{']' if self.hi_closed else ')'}"
        nonzero = any(b not in (None, 0.0) for b in (self.lo, self.hi))
        return f"{text} {unit}" if nonzero and unit not in ("1", "bool") else text


_POSITIVE = _Range(0.0, False)
_NON_NEGATIVE = _Range(0.0, True)
_EFFICIENCY = _Range(0.0, False, 1.0, True)
_ANGLE = _Range(-_HALF_PI, False, _HALF_PI, False)

#: Single-field rules (SI). Fields absent here are checked by cross-field rules or type only.
_RULES: dict[str, _Range] = {
    "torso_mass": _POSITIVE, "torso_inertia": _POSITIVE,
    "leg_mass": _NON_NEGATIVE, "leg_inertia": _NON_NEGATIVE,
    "leg_stiffness": _POSITIVE, "leg_damping": _NON_NEGATIVE,
    "hip_spacing": _POSITIVE, "leg_rest_length": _POSITIVE,
    "legs_per_virtual_leg": _Range(1, True), "gravity": _POSITIVE,
    "torso_length": _POSITIVE, "torso_height": _POSITIVE,
    "planetary_ratio": _POSITIVE, "sprocket_ratio": _POSITIVE,
    "gearbox_efficiency": _EFFICIENCY, "sprocket_efficiency": _EFFICIENCY,
    "gearbox_idle_loss_torque": _NON_NEGATIVE,
    "gearbox_load_loss_coefficient": _Range(0.0, True, 1.0, False),
    "drive_gear_inertia": _NON_NEGATIVE, "driven_gear_inertia": _NON_NEGATIVE,
    "joint_stiction": _NON_NEGATIVE, "joint_damping": _NON_NEGATIVE,
    "belt_stiffness": _POSITIVE, "belt_damping": _NON_NEGATIVE,
    "belt_backlash": _Range(0.0, True, math.radians(45.0), True),
    "leg_friction_force": _NON_NEGATIVE, "leg_friction_side_load_coefficient": _NON_NEGATIVE,
    "leg_damping_angle_coefficient": _NON_NEGATIVE,
    "torque_constant": _POSITIVE, "speed_constant": _POSITIVE,
    "armature_resistance": _POSITIVE, "current_limit": _POSITIVE,
    "battery_voltage": _POSITIVE, "battery_resistance": _NON_NEGATIVE,
    "touchdown_angle_front": _ANGLE, "touchdown_angle_back": _ANGLE,
    "sweep_limit_front": _ANGLE, "sweep_limit_back": _ANGLE,
    **{f"{kind}_{gain}_{end}": _NON_NEGATIVE
       for kind in ("flight", "brake") for gain in ("kp", "kd") for end in ("front", "back")},
    "control_period": _Range(0.0, False, 0.1, True),
    "touchdown_compression": _POSITIVE, "liftoff_compression": _NON_NEGATIVE,
    # torso feedback (PitchFeedbackController): beyond these, the pitch (+-10 deg) and pitch
    # rates (+-200 deg/s) of a bound would move a touchdown angle by more than the +-90 deg
    # touchdown angles may span
    "pitch_gain_front": _Range(-9.0, True, 9.0, True),
    "pitch_gain_back": _Range(-9.0, True, 9.0, True),
    "pitch_rate_gain_front": _Range(-0.45, True, 0.45, True),
    "pitch_rate_gain_back": _Range(-0.45, True, 0.45, True),
}


@dataclass(frozen=True)
class _Limit:
    """Largest physically meaningful value of a field (SI) and why."""

    hi: float
    why: str


#: Size scales of the bounds below: far outside any legged robot that exists (Scout II:
#: 25 kg, 0.55 m, 1 g), so they refuse only values no robot has (1e308 kg, lengths in
#: kilometres, ...), which would otherwise overflow or make the equations of motion
#: numerically singular. Values inside them can still make a run fail; such a failure is
#: diagnosed after the run (:mod:`scoutsim.failure`).
_MASS_MAX = 1.0e5        # kg: 100 t
_LENGTH_MAX = 100.0      # m
_GRAVITY_MAX = 1.0e3     # m/s^2: about 100 g (Jupiter's surface gravity is 24.8 m/s^2)
_FORCE_MAX = _MASS_MAX * _GRAVITY_MAX           # N: the heaviest robot under the largest g
_TORQUE_MAX = _FORCE_MAX * _LENGTH_MAX          # N m: that force at the largest lever
_INERTIA_MAX = _MASS_MAX * _LENGTH_MAX ** 2     # kg m^2: the heaviest mass at the largest size
#: leg spring: a solid steel bar 0.1 m thick and 0.3 m long is E A / l = 5e9 N/m
_LEG_STIFFNESS_MAX = 1.0e10
#: rotational spring: a solid steel shaft 1 m thick and 1 m long is G J / l = 8e9 N m/rad
_ROT_STIFFNESS_MAX = 1.0e10

#: Single-field physical bounds (SI), checked after the rules of :data:`_RULES` (which give
#: the lower end). Controller gains have none: the current limit bounds the torque they
#: command.
_LIMITS: dict[str, _Limit] = {
    **{n: _Limit(_MASS_MAX, "a mass of at most 100 t")
       for n in ("torso_mass", "leg_mass")},
    **{n: _Limit(_INERTIA_MAX, "100 t at a radius of gyration of 100 m")
       for n in ("torso_inertia", "leg_inertia", "drive_gear_inertia", "driven_gear_inertia")},
    **{n: _Limit(_LENGTH_MAX, "a robot at most 100 m in size")
       for n in ("hip_spacing", "leg_rest_length", "torso_length", "torso_height")},
    "gravity": _Limit(_GRAVITY_MAX, "about 100 g"),
    "leg_stiffness": _Limit(_LEG_STIFFNESS_MAX, "a solid steel bar 0.1 m thick and 0.3 m "
                                                "long is 5e9 N/m"),
    # critical damping 2 sqrt(k m) of the stiffest leg under the heaviest robot: 6e7 N s/m
    "leg_damping": _Limit(1.0e8, "above the critical damping of the stiffest allowed leg "
                                 "under the heaviest allowed robot"),
    **{n: _Limit(1.0e4, "a single reduction stage of at most 10^4 : 1")
       for n in ("planetary_ratio", "sprocket_ratio")},
    **{n: _Limit(_TORQUE_MAX, "the weight of 100 t under 100 g at a 100 m lever")
       for n in ("gearbox_idle_loss_torque", "joint_stiction")},
    "belt_stiffness": _Limit(_ROT_STIFFNESS_MAX, "a solid steel shaft 1 m thick and 1 m "
                                                 "long is 8e9 N m/rad"),
    # critical damping 2 sqrt(k J) of the stiffest spring on the largest inertia: 6e9
    **{n: _Limit(1.0e10, "above the critical damping of the stiffest allowed spring on the "
                         "largest allowed inertia")
       for n in ("belt_damping", "joint_damping")},
    "leg_friction_force": _Limit(_FORCE_MAX, "the weight of 100 t under 100 g"),
    "leg_friction_side_load_coefficient": _Limit(10.0, "a friction coefficient; dry friction "
                                                       "coefficients are below about 2"),
    "leg_damping_angle_coefficient": _Limit(1.0e4, "the damper 10^4 times stronger at 1 rad "
                                                   "than at 0"),
    # (K_T [N m/A] and K_w [V s/rad] are the same number for an ideal DC motor)
    **{n: _Limit(1.0e3, "the largest torque motors have about 100 N m/A = V s/rad")
       for n in ("torque_constant", "speed_constant")},
    **{n: _Limit(1.0e6, "1 Mohm passes microamperes at robot voltages")
       for n in ("armature_resistance", "battery_resistance")},
    "current_limit": _Limit(1.0e5, "100 kA"),
    "battery_voltage": _Limit(1.0e4, "10 kV"),
}


assert set(_LIMITS) <= set(_RULES), "a physical bound needs a lower-end rule"


def physical_limit(name: str) -> float | None:
    """Largest value [SI] :func:`validate_robot` / :func:`validate_controller` accept for a
    field (the physical bound of the field), or None if it has none."""
    limit = _LIMITS.get(name)
    return None if limit is None else limit.hi


def allowed_range(name: str) -> tuple[float | None, float | None, bool, bool]:
    """The interval [SI] :func:`validate_robot` / :func:`validate_controller` accept for a
    field by itself: ``(low, high, low_closed, high_closed)``, None for an unbounded end
    (its sign rule, then its physical bound, :func:`physical_limit`). Rules that couple
    fields (liftoff below touchdown compression, ...) are not included."""
    rule = _RULES.get(name, _Range())
    hi, hi_closed = rule.hi, rule.hi_closed
    limit = _LIMITS.get(name)
    if limit is not None and (hi is None or limit.hi < hi):
        hi, hi_closed = limit.hi, True
    return rule.lo, hi, rule.lo_closed, hi_closed


def closed_range(name: str) -> tuple[float, float]:
    """The closed interval (lo, hi) [SI] of :func:`allowed_range` for the field ``name`` of
    :class:`RobotParameters` or :class:`ControllerParameters`: an open end replaced by the
    nearest float inside it; -inf / inf where it has none (e.g. a touchdown angle: just
    inside (-90, 90) deg)."""
    if name not in _schema():
        raise KeyError(f"no parameter named {name!r}")
    lo, hi, lo_closed, hi_closed = allowed_range(name)
    lo = -math.inf if lo is None else (float(lo) if lo_closed else math.nextafter(lo, math.inf))
    hi = math.inf if hi is None else (float(hi) if hi_closed else math.nextafter(hi, -math.inf))
    return lo, hi


@dataclass(frozen=True)
class _Spec:
    """Schema of one field, taken from the packaged TOML and the dataclass annotation."""

    name: str
    section: str
    kind: str  # "float", "int" or "bool"
    unit: str  # unit as written in scout2.toml
    dimension: str
    factor: float
    written: object  # value as written in scout2.toml
    source: str

    @property
    def label(self) -> str:
        return f"{self.section}.{self.name}"

    @property
    def si_unit(self) -> str:
        return next(iter(UNITS[self.dimension]))


def field_dimension(name: str) -> str | None:
    """Physical dimension ("angle", "mass", ...) of a RobotParameters / ControllerParameters
    field (from the packaged scout2.toml), or None for an unknown name."""
    spec = _schema().get(name)
    return None if spec is None else spec.dimension


def _fmt(x: object) -> str:
    """Short, noise-free text for a value (``-1.0``, ``95.0``, ``nan``, ``2``, ``true``)."""
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, numbers.Integral):
        return str(int(x))
    if isinstance(x, numbers.Real):
        x = float(x)
        return repr(x) if not math.isfinite(x) else repr(float(f"{x:.12g}"))
    return repr(x)


def _fmt_bound(x: float) -> str:
    return f"{x:.12g}"


def _is_bool(x: object) -> bool:
    return isinstance(x, bool) or type(x).__name__ in ("bool_", "bool")


@lru_cache(maxsize=1)
def _schema() -> dict[str, _Spec]:
    """Field name -> :class:`_Spec`, checked against both dataclasses."""
    data = _packaged()
    if set(data) != set(SECTIONS):
        raise RuntimeError(f"packaged {_PACKAGED_NAME} has sections {sorted(data)}, expected {sorted(SECTIONS)}")
    kinds = {}
    for cls in (RobotParameters, ControllerParameters):
        hints = typing.get_type_hints(cls)
        kinds.update({f.name: (cls, hints[f.name].__name__) for f in dataclasses.fields(cls)})
    schema: dict[str, _Spec] = {}
    for section, entries in data.items():
        for name, entry in entries.items():
            if name not in kinds or kinds[name][0] is not SECTIONS[section] or name in schema:
                raise RuntimeError(f"packaged {_PACKAGED_NAME}: unexpected entry [{section}] {name}")
            dim, factor = _UNIT_INDEX[entry["unit"]]
            schema[name] = _Spec(name, section, kinds[name][1], entry["unit"], dim, factor,
                                 entry["value"], entry["source"])
    if missing := set(kinds) - set(schema):
        raise RuntimeError(f"packaged {_PACKAGED_NAME} lacks {sorted(missing)}")
    return schema


def _fields_of(cls: type) -> dict[str, _Spec]:
    names = [f.name for f in dataclasses.fields(cls)]
    return {n: _schema()[n] for n in names}


def _coerce(spec: _Spec, value: object, where: str = "") -> float | int | bool:
    """Return ``value`` as the field's Python type, or raise on a wrong type."""
    if spec.kind == "bool":
        if _is_bool(value):
            return bool(value)
        expected = "true or false"
    elif not _is_bool(value) and isinstance(value, numbers.Real):
        try:
            x = float(value)
        except OverflowError:   # an integer beyond the float range (Python API only)
            rule = _RULES.get(spec.name)
            text = rule.describe(spec.factor, spec.unit) if rule else "a real number"
            digits = len(str(abs(int(value))))
            raise ParameterError(f"{spec.label} = an integer of {digits} digits is not allowed: "
                                 f"must be finite and {text}{where}", spec.name) from None
        if spec.kind == "float":
            return x
        if math.isfinite(x) and x.is_integer():
            return int(x)
        raise ParameterError(f"{spec.label} = {_fmt(value)} is not allowed: must be an integer "
                             f"{_RULES[spec.name].describe(1.0, '1')}{where}", spec.name)
    else:
        expected = "an integer" if spec.kind == "int" else "a number"
    raise ParameterError(f"{spec.label} = {value!r} has the wrong type ({type(value).__name__}): "
                         f"expected {expected}{where}", spec.name)


def _unknown(name: str, context: str, candidates: typing.Iterable[str], kind: str = "parameter") -> ParameterError:
    """Error for an unknown key or section, suggesting the closest valid name."""
    candidates = list(candidates)
    close = difflib.get_close_matches(name, candidates, n=1, cutoff=0.6)
    hint = f"did you mean '{close[0]}'?" if close else f"valid names: {', '.join(candidates)}"
    return ParameterError(f"unknown {kind} '{name}' {context}; {hint}", name)


def _convert_entry(spec: _Spec, entry: object, where: str) -> tuple[object, str | None]:
    """Convert one TOML entry (plain value or ``{value, unit, source}``) to SI.

    Returns the SI value and, when the user's unit differs from the display unit, a note
    ``"(given as ...)"`` for later messages.
    """
    unit = spec.unit
    if isinstance(entry, dict):
        if extra := sorted(set(entry) - {"value", "unit", "source"}):
            raise ParameterError(f"{spec.label}: unknown key(s) {extra} in entry; allowed keys are "
                                 f"value, unit, source{where}", spec.name)
        if "value" not in entry:
            raise ParameterError(f"{spec.label}: entry has no 'value'{where}", spec.name)
        unit = entry.get("unit", spec.unit)
        entry = entry["value"]
        if not isinstance(unit, str) or unit.strip() not in _UNIT_INDEX:
            raise ParameterError(f"{spec.label}: unknown unit {unit!r}; allowed units: "
                                 f"{', '.join(UNITS[spec.dimension])}{where}", spec.name)
        unit = unit.strip()
    dim, factor = _UNIT_INDEX[unit]
    if dim != spec.dimension:
        raise ParameterError(f"{spec.label}: unit '{unit}' is a {dim} unit, but {spec.name} is a "
                             f"{spec.dimension}; allowed units: {', '.join(UNITS[spec.dimension])}{where}",
                             spec.name)
    value = _coerce(spec, entry, where)
    note = None if unit == spec.unit else f"given as {_fmt(entry)} {unit}"
    return (value * factor if spec.kind == "float" else value), note


def _default_si(spec: _Spec) -> float | int | bool:
    """SI value of the packaged default of one field."""
    value = _coerce(spec, spec.written)
    return value * spec.factor if spec.kind == "float" else value


def _read_file(path: str | PathLike) -> tuple[dict[str, object], dict[str, tuple[str, str | None]]]:
    """Read a user's parameter file; return SI values and origins of every entry it sets."""
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"malformed TOML in parameter file '{path}': {exc}") from exc
    schema = _schema()
    values: dict[str, object] = {}
    origins: dict[str, tuple[str, str | None]] = {}
    for section, entries in data.items():
        if section in SEPARATE_SECTIONS:
            continue
        if section not in SECTIONS:
            raise _unknown(section, f"in parameter file '{path}'", SECTIONS, kind="section")
        if not isinstance(entries, dict):
            raise ParameterError(f"[{section}] in parameter file '{path}' must be a table, "
                                 f"got {entries!r}")
        where = f" (in [{section}] of file '{path}')"
        for name, entry in entries.items():
            spec = schema.get(name)
            if spec is None or spec.section != section:
                if spec is not None:
                    raise ParameterError(f"parameter '{name}' in [{section}] of file '{path}' belongs in "
                                         f"section [{spec.section}]", name)
                in_section = [n for n, s in schema.items() if s.section == section]
                raise _unknown(name, f"in [{section}] of file '{path}'", in_section)
            values[name], note = _convert_entry(spec, entry, where)
            origins[name] = (where, note)
    return values, origins


def _build(cls: type, path: str | PathLike | None, overrides: typing.Mapping | None,
           where_overrides: str = " (from overrides)"):
    """Defaults -> user file -> overrides; return the instance (unvalidated) and origins."""
    specs = _fields_of(cls)
    values = {name: _default_si(spec) for name, spec in specs.items()}
    origins: dict[str, tuple[str, str | None]] = {}
    if path is not None:
        file_values, file_origins = _read_file(path)
        values.update({k: v for k, v in file_values.items() if k in specs})
        origins.update({k: v for k, v in file_origins.items() if k in specs})
    for name, value in (overrides or {}).items():
        if name not in specs:
            other = _schema().get(name)
            if other is not None:
                raise ParameterError(f"'{name}' is a [{other.section}] parameter, not a "
                                     f"{cls.__name__} field{where_overrides}", name)
            raise _unknown(name, f"for {cls.__name__}{where_overrides}", specs)
        spec = specs[name]
        values[name] = _coerce(spec, value, where_overrides)
        note = f"given as {_fmt(value)} {spec.si_unit}" if spec.factor != 1.0 else None
        origins[name] = (where_overrides, note)
    return cls(**values), origins


def _fail(spec: _Spec, value: object, rule: str, origins) -> typing.NoReturn:
    where, note = origins.get(spec.name, ("", None))
    unit = "" if spec.unit in ("1", "bool") else f" {spec.unit}"
    shown = _fmt(value / spec.factor) if spec.kind == "float" else _fmt(value)
    note = f" ({note})" if note else ""
    raise ParameterError(f"{spec.label} = {shown}{unit}{note} is not allowed: {rule}{where}", spec.name)


def _check_fields(obj: object, origins) -> None:
    """Type, finiteness and single-field range of every field of ``obj``."""
    for name, spec in _fields_of(type(obj)).items():
        where = origins.get(name, ("", None))[0]
        value = getattr(obj, name)
        _coerce(spec, value, where)  # raises on a wrong type
        if spec.kind == "int" and not isinstance(value, numbers.Integral):
            raise ParameterError(f"{spec.label} = {value!r} has the wrong type ({type(value).__name__}): "
                                 f"expected an integer{where}", name)
        if spec.kind == "bool":
            continue
        rule = _RULES.get(name)
        finite = math.isfinite(value)
        if not finite or (rule is not None and not rule.contains(value)):
            # (the message is composed only for a value that fails: every simulate()
            # checks every field)
            text = rule.describe(spec.factor, spec.unit) if rule else "a real number"
            _fail(spec, value, f"must be finite and {text}" if not finite else f"must be {text}",
                  origins)
        limit = _LIMITS.get(name)
        if limit is not None and value > limit.hi:
            _fail(spec, value, f"must be {_describe_limit(rule, limit, spec)} ({limit.why})",
                  origins)


def _describe_limit(rule: _Range, limit: _Limit, spec: _Spec) -> str:
    """The whole allowed interval of a field with a physical bound, in its display unit."""
    lo = _fmt_bound(rule.lo / spec.factor)
    hi = f"{limit.hi / spec.factor:.9g}"
    unit = "" if spec.unit in ("1", "bool") else f" {spec.unit}"
    return f"in {'[' if rule.lo_closed else '('}{lo}, {hi}]{unit}"


def _validate_robot(p: RobotParameters, origins) -> RobotParameters:
    if not isinstance(p, RobotParameters):
        raise TypeError(f"expected RobotParameters, got {type(p).__name__}")
    _check_fields(p, origins)
    spec = _schema()["leg_com_distance"]
    l0 = _fmt_bound(p.leg_rest_length / spec.factor)
    if p.leg_mass == 0.0:
        if not 0.0 <= p.leg_com_distance <= p.leg_rest_length:
            _fail(spec, p.leg_com_distance,
                  f"must be in [0, leg_rest_length = {l0}] {spec.unit} (massless legs)", origins)
    elif not 0.0 < p.leg_com_distance <= p.leg_rest_length:
        _fail(spec, p.leg_com_distance, f"must be in (0, leg_rest_length = {l0}] {spec.unit}", origins)
    return p


def _validate_controller(c: ControllerParameters, origins) -> ControllerParameters:
    if not isinstance(c, ControllerParameters):
        raise TypeError(f"expected ControllerParameters, got {type(c).__name__}")
    _check_fields(c, origins)
    if c.liftoff_compression >= c.touchdown_compression:
        spec = _schema()["liftoff_compression"]
        td = _fmt_bound(c.touchdown_compression / spec.factor)
        _fail(spec, c.liftoff_compression,
              f"must be >= 0 and < touchdown_compression = {td} {spec.unit}", origins)
    return c


def _validate_pair(robot, controller, origins) -> None:
    if controller.touchdown_compression >= robot.leg_rest_length:
        spec = _schema()["touchdown_compression"]
        l0 = _fmt_bound(robot.leg_rest_length / spec.factor)
        _fail(spec, controller.touchdown_compression,
              f"must be > liftoff_compression and < leg_rest_length = {l0} {spec.unit}", origins)


def validate_robot(p: RobotParameters) -> RobotParameters:
    """Check every field of a :class:`RobotParameters`.

    Parameters
    ----------
    p : RobotParameters
        Parameters to check (SI units).

    Returns
    -------
    RobotParameters
        ``p`` itself, unchanged.

    Raises
    ------
    ParameterError
        On a wrong type, a NaN/infinite value or a value outside its allowed range (its
        sign rule, or a physical bound far beyond any legged robot: a mass above 100 t, a
        length above 100 m, ...; :func:`physical_limit`); the message names the field, the
        value (in the paper's unit) and the allowed range.
    """
    return _validate_robot(p, {})


def validate_controller(c: ControllerParameters) -> ControllerParameters:
    """Check every field of a :class:`ControllerParameters`, and liftoff < touchdown compression.

    Parameters
    ----------
    c : ControllerParameters
        Parameters to check (SI units); angle messages are reported in degrees.

    Returns
    -------
    ControllerParameters
        ``c`` itself, unchanged.

    Raises
    ------
    ParameterError
        As :func:`validate_robot`.
    """
    return _validate_controller(c, {})


def validate_parameters(robot: RobotParameters, controller: ControllerParameters) -> None:
    """Check both parameter sets and the rules that couple them.

    Besides :func:`validate_robot` and :func:`validate_controller`, requires
    ``touchdown_compression < robot.leg_rest_length``.

    Raises
    ------
    ParameterError
        On any violation.
    """
    validate_robot(robot)
    validate_controller(controller)
    _validate_pair(robot, controller, {})


def load_robot(path: str | PathLike | None = None,
               overrides: typing.Mapping[str, object] | None = None) -> RobotParameters:
    """Load robot parameters: packaged defaults, then a user's TOML file, then overrides.

    Parameters
    ----------
    path : str or os.PathLike, optional
        User TOML file with the layout of ``scout2.toml``. An entry is a plain value (in the
        unit ``scout2.toml`` uses for that field) or ``{ value = ..., unit = "..." }`` with any
        unit of :data:`UNITS` of the right dimension (``source`` is allowed and ignored). The
        whole file is checked, including its ``[controller]`` section.
    overrides : mapping, optional
        Field name -> value in SI units, applied last.

    Returns
    -------
    RobotParameters
        Validated parameters (SI units).

    Raises
    ------
    ParameterError
        Malformed TOML, unknown section or key, wrong unit dimension, wrong type, or a value
        out of range (see :func:`validate_robot`).
    """
    robot, origins = _build(RobotParameters, path, overrides)
    return _validate_robot(robot, origins)


def load_controller(path: str | PathLike | None = None,
                    overrides: typing.Mapping[str, object] | None = None) -> ControllerParameters:
    """Load controller parameters; as :func:`load_robot` but for ``[controller]``.

    Parameters
    ----------
    path : str or os.PathLike, optional
        User TOML file (see :func:`load_robot`).
    overrides : mapping, optional
        Field name -> value in SI units (angles in rad), applied last.

    Returns
    -------
    ControllerParameters
        Validated parameters (SI units). The coupling ``touchdown_compression <
        leg_rest_length`` is only checked by :func:`load_parameters`.
    """
    controller, origins = _build(ControllerParameters, path, overrides)
    return _validate_controller(controller, origins)


def load_parameters(path: str | PathLike | None = None,
                    robot_overrides: typing.Mapping[str, object] | None = None,
                    controller_overrides: typing.Mapping[str, object] | None = None,
                    ) -> tuple[RobotParameters, ControllerParameters]:
    """Load robot and controller parameters together and check the rules coupling them.

    Parameters
    ----------
    path : str or os.PathLike, optional
        User TOML file (see :func:`load_robot`).
    robot_overrides, controller_overrides : mapping, optional
        Field name -> SI value, applied last.

    Returns
    -------
    tuple of (RobotParameters, ControllerParameters)
        Validated parameters.
    """
    robot, r_origins = _build(RobotParameters, path, robot_overrides)
    controller, c_origins = _build(ControllerParameters, path, controller_overrides)
    _validate_robot(robot, r_origins)
    _validate_controller(controller, c_origins)
    _validate_pair(robot, controller, c_origins)
    return robot, controller


def parameter_table() -> list[dict]:
    """Every parameter with its default, unit and provenance (for documentation).

    Returns
    -------
    list of dict
        One dict per field of :class:`RobotParameters` then :class:`ControllerParameters`,
        with keys ``section``, ``name``, ``value`` and ``unit`` (as written in
        ``scout2.toml``), ``si_value``, ``si_unit`` and ``source``.
    """
    rows = []
    for cls in (RobotParameters, ControllerParameters):
        for name, spec in _fields_of(cls).items():
            rows.append({"section": spec.section, "name": name, "value": spec.written,
                         "unit": spec.unit, "si_value": _default_si(spec),
                         "si_unit": spec.si_unit, "source": spec.source})
    return rows


_DICT_FORMAT = "scoutsim.parameters/1"


def to_dict(robot: RobotParameters, controller: ControllerParameters) -> dict:
    """JSON-safe dict of both parameter sets (SI units), e.g. for result-file provenance.

    Parameters
    ----------
    robot : RobotParameters
    controller : ControllerParameters
        Both are validated first, so every number is finite.

    Returns
    -------
    dict
        ``{"format": ..., "units": "SI", "robot": {...}, "controller": {...}}``; see
        :func:`from_dict` for the inverse.
    """
    validate_parameters(robot, controller)
    return {"format": _DICT_FORMAT, "units": "SI",
            "robot": dataclasses.asdict(robot), "controller": dataclasses.asdict(controller)}


def from_dict(d: typing.Mapping) -> tuple[RobotParameters, ControllerParameters]:
    """Inverse of :func:`to_dict` (exact round trip, also through JSON).

    Parameters
    ----------
    d : mapping
        As produced by :func:`to_dict`; every field of both dataclasses must be present.

    Returns
    -------
    tuple of (RobotParameters, ControllerParameters)
        Validated parameters.

    Raises
    ------
    ParameterError
        Wrong format tag, unknown or missing keys, wrong types or invalid values.
    """
    if d.get("format", _DICT_FORMAT) != _DICT_FORMAT or d.get("units", "SI") != "SI":
        raise ParameterError(f"unsupported parameter dict format {d.get('format')!r} "
                             f"(units {d.get('units')!r}); expected {_DICT_FORMAT!r} in SI")
    if extra := sorted(set(d) - {"format", "units", "robot", "controller"}):
        raise ParameterError(f"unknown key(s) {extra} in parameter dict")
    out, origins = [], {}
    for key, cls in (("robot", RobotParameters), ("controller", ControllerParameters)):
        part = d.get(key, {})
        if missing := sorted(set(_fields_of(cls)) - set(part)):
            raise ParameterError(f"parameter dict [{key}] lacks {missing}")
        obj, o = _build(cls, None, part, where_overrides=" (from parameter dict)")
        out.append(obj)
        origins.update(o)
    robot, controller = out
    _validate_robot(robot, origins)
    _validate_controller(controller, origins)
    _validate_pair(robot, controller, origins)
    return robot, controller
