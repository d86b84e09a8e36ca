"""The schema of every parameter: its TOML section, type, unit, dimension, packaged default,
source and plausible range, taken from the packaged ``scout2.toml``; and which fields may
differ between the back and the front legs (:data:`PER_LEG_FIELDS`).

The dataclasses (:mod:`.robot`, :mod:`.controller`) are built on this schema and validated
against it (:func:`.packaged.packaged_defaults`), so it is read from the file alone."""

from __future__ import annotations

import dataclasses
import typing
from dataclasses import dataclass
from functools import cache, lru_cache

from .packaged import PACKAGED_NAME, packaged_table
from .units import UNIT_INDEX, UNITS

#: TOML sections of :class:`~scoutsim.parameters.RobotParameters` and of
#: :class:`~scoutsim.parameters.ControllerParameters` (``files.SECTIONS`` maps each to its
#: class).
ROBOT_SECTIONS = ("robot", "transmission", "motor")
CONTROLLER_SECTIONS = ("controller",)

#: Fields that take one value for both legs or a (back, front) pair: the leg bodies, the
#: telescopic legs, the hip units (transmission) and the motors with their amplifiers.
#: The torso, the hip spacing, the battery and gravity are one value for the robot.
PER_LEG_FIELDS = (
    "leg_mass",
    "leg_inertia",
    "leg_stiffness",
    "leg_damping",
    "leg_rest_length",
    "leg_com_distance",
    "planetary_ratio",
    "sprocket_ratio",
    "gearbox_efficiency",
    "sprocket_efficiency",
    "gearbox_idle_loss_torque",
    "gearbox_load_loss_coefficient",
    "drive_gear_inertia",
    "driven_gear_inertia",
    "joint_stiction",
    "joint_damping",
    "belt_stiffness",
    "belt_damping",
    "belt_backlash",
    "leg_friction_force",
    "leg_friction_side_load_coefficient",
    "leg_damping_angle_coefficient",
    "torque_constant",
    "speed_constant",
    "armature_resistance",
    "current_limit",
)


def given_per_leg(value) -> bool:
    """Whether a field's value is given leg by leg: a list, a tuple or a 1-d array (of two
    values, back then front, for a valid one)."""
    return isinstance(value, (list, tuple)) or getattr(value, "ndim", 0) == 1


# -- plausible values ------------------------------------------------------------------------
#: What a robot of Scout II's kind has: a running legged robot of a few to a few hundred
#: kilograms, legs of decimetres, hip motors of tens to hundreds of watts. A value outside
#: its plausible range is allowed (validation refuses only what no robot has, and
#: researchers explore) but warned of (:mod:`.plausibility`): most such values are a unit
#: slip. By default a field's plausible range is within a factor of
#: :data:`PLAUSIBLE_FACTOR` of Scout II's value, either way.
PLAUSIBLE_FACTOR = 10.0

#: Plausible ranges that differ from the default, in the field's unit in ``scout2.toml``
#: (low, high); None: no plausible range beyond the allowed one (a signed quantity, or one
#: whose allowed range is already its whole physical span).
_PLAUSIBLE_RANGES: dict[str, tuple[float, float] | None] = {
    # signed, or bounded by validation to their physical span
    "com_offset": None,
    "gearbox_load_loss_coefficient": None,
    "touchdown_angle_front": None,
    "touchdown_angle_back": None,
    "sweep_limit_front": None,
    "sweep_limit_back": None,
    "pitch_gain_front": None,
    "pitch_gain_back": None,
    "pitch_rate_gain_front": None,
    "pitch_rate_gain_back": None,
    # one physical leg per virtual leg (a planar one-legged half) up to a tripod
    "legs_per_virtual_leg": (1, 3),
    # 1: direct drive (no planetary stage); robot hip gearboxes stay below 1000 : 1; a belt
    # or chain stage may take most of the reduction (up to 30 : 1), or speed up
    "planetary_ratio": (1.0, 1000.0),
    "sprocket_ratio": (0.1, 30.0),
    # motors of 10-500 W at 12-48 V: from small high-speed motors to frameless torque motors
    "torque_constant": (0.003, 1.0),
    "speed_constant": (0.003, 1.0),
    "armature_resistance": (0.05, 50.0),
    # effects whose Scout II value is 0 (off): up to strong but real ones
    "gearbox_idle_loss_torque": (0.0, 5.0),  # N m at the leg; Scout II's hip: ~30 N m
    "belt_backlash": (0.0, 10.0),  # deg: gearboxes have arcminutes
    "leg_friction_force": (0.0, 100.0),  # N: Scout II's weight per leg is ~60 N
    "leg_friction_side_load_coefficient": (0.0, 1.0),  # a dry friction coefficient
    "leg_damping_angle_coefficient": (0.0, 100.0),  # 1/rad^2: 17x the damping at 0.4 rad
    "battery_resistance": (0.0, 1.0),  # ohm: batteries have milliohms
}

#: Fields whose value 0 is plausible as well (the effect switched off, or idealised away:
#: massless legs, an undamped leg, a gain of 0); a value > 0 is still held to the range.
_ZERO_PLAUSIBLE = frozenset(
    {
        "leg_mass",
        "leg_inertia",
        "leg_damping",
        "leg_com_distance",
        "drive_gear_inertia",
        "driven_gear_inertia",
        "joint_stiction",
        "joint_damping",
        "belt_damping",
        "liftoff_compression",
        *(
            f"{kind}_{gain}_{end}"
            for kind in ("flight", "brake")
            for gain in ("kp", "kd")
            for end in ("front", "back")
        ),
    }
)


@dataclass(frozen=True)
class Plausible:
    """Plausible values of a field in SI: ``low <= x <= high``, or ``x == 0`` if
    ``zero``. The comparison is widened by rounding's worth (:attr:`bounds`), so that
    e.g. exactly 10 times Scout II's value, computed in SI, is inside."""

    low: float
    high: float
    zero: bool = False

    @property
    def bounds(self) -> tuple[float, float]:
        """(low, high) as compared."""
        return self.low * (1.0 - 1.0e-9), self.high * (1.0 + 1.0e-9)


@dataclass(frozen=True)
class FieldSpec:
    """Schema of one field, taken from the packaged TOML."""

    name: str
    section: str
    kind: str  # "float", "int" or "bool"
    unit: str  # unit as written in scout2.toml
    dimension: str
    factor: float
    written: typing.Any  # value as written in scout2.toml (float, int or bool)
    source: str
    plausible: Plausible | None = None  # None: every allowed value is plausible

    @property
    def label(self) -> str:
        return f"{self.section}.{self.name}"

    @property
    def si_unit(self) -> str:
        return next(iter(UNITS[self.dimension]))

    @property
    def default_si(self) -> float | int | bool:
        """Scout II's value (the packaged default) in SI."""
        return self.written * self.factor if self.kind == "float" else self.written


def field_dimension(name: str) -> str | None:
    """Physical dimension ("angle", "mass", ...) of a RobotParameters / ControllerParameters
    field (from the packaged scout2.toml), or None for an unknown name."""
    spec = field_schema().get(name)
    return None if spec is None else spec.dimension


def plausible_range(name: str) -> tuple[float, float] | None:
    """Plausible values [SI] of a field, ``(low, high)``: what a robot of Scout II's kind
    has (a value outside is allowed, with an
    :class:`~scoutsim.parameters.ImplausibleParameterWarning`); None if every allowed value
    is plausible. Fields where 0 switches an effect off also take 0."""
    spec = field_schema()[name]
    return None if spec.plausible is None else (spec.plausible.low, spec.plausible.high)


def _plausible(name: str, kind: str, factor: float, written) -> Plausible | None:
    if kind == "bool":
        return None
    if name in _PLAUSIBLE_RANGES:
        given = _PLAUSIBLE_RANGES[name]
        if given is None:
            return None
        low, high = given
    else:
        low, high = written / PLAUSIBLE_FACTOR, written * PLAUSIBLE_FACTOR
    if not 0.0 <= low <= written <= high:
        raise RuntimeError(
            f"packaged {PACKAGED_NAME}: {name}'s value {written} is not in its "
            f"plausible range [{low}, {high}]"
        )
    return Plausible(low * factor, high * factor, name in _ZERO_PLAUSIBLE)


@lru_cache(maxsize=1)
def field_schema() -> dict[str, FieldSpec]:
    """Field name -> :class:`FieldSpec`, in the file's order."""
    data = packaged_table()
    if set(data) != {*ROBOT_SECTIONS, *CONTROLLER_SECTIONS}:
        raise RuntimeError(
            f"packaged {PACKAGED_NAME} has sections {sorted(data)}, expected "
            f"{sorted({*ROBOT_SECTIONS, *CONTROLLER_SECTIONS})}"
        )
    schema: dict[str, FieldSpec] = {}
    for section, entries in data.items():
        for name, entry in entries.items():
            if name in schema:
                raise RuntimeError(
                    f"packaged {PACKAGED_NAME}: {name} is in [{section}] and "
                    f"[{schema[name].section}]"
                )
            dim, factor = UNIT_INDEX[entry["unit"]]
            kind = type(entry["value"]).__name__  # TOML: float, int or bool
            schema[name] = FieldSpec(
                name,
                section,
                kind,
                entry["unit"],
                dim,
                factor,
                entry["value"],
                entry["source"],
                _plausible(name, kind, factor, entry["value"]),
            )
    if unknown := set(_PLAUSIBLE_RANGES) - set(schema):
        raise RuntimeError(f"plausible ranges of unknown fields {sorted(unknown)}")
    return schema


@cache
def fields_of(cls: type) -> dict[str, FieldSpec]:
    """Field name -> :class:`FieldSpec` of every parameter field of the dataclass ``cls``, in its
    order (a subclass's own extra fields are not parameters)."""
    schema = field_schema()
    return {f.name: schema[f.name] for f in dataclasses.fields(cls) if f.name in schema}
