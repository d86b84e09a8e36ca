"""The rules of a single field: its allowed range (sign rule, then physical bound, far
beyond any legged robot), the type a value must have, and the check of every field of a
parameter set by itself, with the error that names the field, its value and its range
(:class:`~scoutsim.parameters.ParameterError`). The rules that couple fields are
:mod:`.field_couplings`; :mod:`.validation` runs both."""

from __future__ import annotations

import math
import numbers
import typing
from dataclasses import dataclass

from ..names import LEG_NAMES
from .parameter_error import ParameterError, format_bound, format_value
from .plausibility import slip_hint
from .schema import PER_LEG_FIELDS, FieldSpec, field_schema, fields_of, given_per_leg

_HALF_PI = 0.5 * math.pi


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
        lo = None if self.lo is None else format_bound(self.lo / factor)
        hi = None if self.hi is None else format_bound(self.hi / factor)
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
    "torso_mass": _POSITIVE,
    "torso_inertia": _POSITIVE,
    "leg_mass": _NON_NEGATIVE,
    "leg_inertia": _NON_NEGATIVE,
    "leg_stiffness": _POSITIVE,
    "leg_damping": _NON_NEGATIVE,
    "hip_spacing": _POSITIVE,
    "leg_rest_length": _POSITIVE,
    "legs_per_virtual_leg": _Range(1, True),
    "gravity": _POSITIVE,
    "torso_length": _POSITIVE,
    "torso_height": _POSITIVE,
    "planetary_ratio": _POSITIVE,
    "sprocket_ratio": _POSITIVE,
    "gearbox_efficiency": _EFFICIENCY,
    "sprocket_efficiency": _EFFICIENCY,
    "gearbox_idle_loss_torque": _NON_NEGATIVE,
    "gearbox_load_loss_coefficient": _Range(0.0, True, 1.0, False),
    "drive_gear_inertia": _NON_NEGATIVE,
    "driven_gear_inertia": _NON_NEGATIVE,
    "joint_stiction": _NON_NEGATIVE,
    "joint_damping": _NON_NEGATIVE,
    "belt_stiffness": _POSITIVE,
    "belt_damping": _NON_NEGATIVE,
    "belt_backlash": _Range(0.0, True, math.radians(45.0), True),
    "leg_friction_force": _NON_NEGATIVE,
    "leg_friction_side_load_coefficient": _NON_NEGATIVE,
    "leg_damping_angle_coefficient": _NON_NEGATIVE,
    "torque_constant": _POSITIVE,
    "speed_constant": _POSITIVE,
    "armature_resistance": _POSITIVE,
    "current_limit": _POSITIVE,
    "battery_voltage": _POSITIVE,
    "battery_resistance": _NON_NEGATIVE,
    "touchdown_angle_front": _ANGLE,
    "touchdown_angle_back": _ANGLE,
    "sweep_limit_front": _ANGLE,
    "sweep_limit_back": _ANGLE,
    **{
        f"{kind}_{gain}_{end}": _NON_NEGATIVE
        for kind in ("flight", "brake")
        for gain in ("kp", "kd")
        for end in ("front", "back")
    },
    "control_period": _Range(0.0, False, 0.1, True),
    "touchdown_compression": _POSITIVE,
    "liftoff_compression": _NON_NEGATIVE,
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
#: diagnosed after the run (:mod:`scoutsim.result.failure`).
_MASS_MAX = 1.0e5  # kg: 100 t
_LENGTH_MAX = 100.0  # m
_GRAVITY_MAX = 1.0e3  # m/s^2: about 100 g (Jupiter's surface gravity is 24.8 m/s^2)
_FORCE_MAX = _MASS_MAX * _GRAVITY_MAX  # N: the heaviest robot under the largest g
_TORQUE_MAX = _FORCE_MAX * _LENGTH_MAX  # N m: that force at the largest lever
_INERTIA_MAX = _MASS_MAX * _LENGTH_MAX**2  # kg m^2: the heaviest mass at the largest size
#: leg spring: a solid steel bar 0.1 m thick and 0.3 m long is E A / l = 5e9 N/m
_LEG_STIFFNESS_MAX = 1.0e10
#: rotational spring: a solid steel shaft 1 m thick and 1 m long is G J / l = 8e9 N m/rad
_ROT_STIFFNESS_MAX = 1.0e10

#: Single-field physical bounds (SI), checked after the rules of :data:`_RULES` (which give
#: the lower end). Controller gains have none: the current limit bounds the torque they
#: command.
_LIMITS: dict[str, _Limit] = {
    **{n: _Limit(_MASS_MAX, "a mass of at most 100 t") for n in ("torso_mass", "leg_mass")},
    **{
        n: _Limit(_INERTIA_MAX, "100 t at a radius of gyration of 100 m")
        for n in ("torso_inertia", "leg_inertia", "drive_gear_inertia", "driven_gear_inertia")
    },
    **{
        n: _Limit(_LENGTH_MAX, "a robot at most 100 m in size")
        for n in ("hip_spacing", "leg_rest_length", "torso_length", "torso_height")
    },
    "gravity": _Limit(_GRAVITY_MAX, "about 100 g"),
    "leg_stiffness": _Limit(
        _LEG_STIFFNESS_MAX, "a solid steel bar 0.1 m thick and 0.3 m long is 5e9 N/m"
    ),
    # critical damping 2 sqrt(k m) of the stiffest leg under the heaviest robot: 6e7 N s/m
    "leg_damping": _Limit(
        1.0e8,
        "above the critical damping of the stiffest allowed leg under the heaviest allowed robot",
    ),
    **{
        n: _Limit(1.0e4, "a single reduction stage of at most 10^4 : 1")
        for n in ("planetary_ratio", "sprocket_ratio")
    },
    **{
        n: _Limit(_TORQUE_MAX, "the weight of 100 t under 100 g at a 100 m lever")
        for n in ("gearbox_idle_loss_torque", "joint_stiction")
    },
    "belt_stiffness": _Limit(
        _ROT_STIFFNESS_MAX, "a solid steel shaft 1 m thick and 1 m long is 8e9 N m/rad"
    ),
    # critical damping 2 sqrt(k J) of the stiffest spring on the largest inertia: 6e9
    **{
        n: _Limit(
            1.0e10,
            "above the critical damping of the stiffest allowed spring on the "
            "largest allowed inertia",
        )
        for n in ("belt_damping", "joint_damping")
    },
    "leg_friction_force": _Limit(_FORCE_MAX, "the weight of 100 t under 100 g"),
    "leg_friction_side_load_coefficient": _Limit(
        10.0, "a friction coefficient; dry friction coefficients are below about 2"
    ),
    "leg_damping_angle_coefficient": _Limit(
        1.0e4, "the damper 10^4 times stronger at 1 rad than at 0"
    ),
    # (K_T [N m/A] and K_w [V s/rad] are the same number for an ideal DC motor)
    **{
        n: _Limit(1.0e3, "the largest torque motors have about 100 N m/A = V s/rad")
        for n in ("torque_constant", "speed_constant")
    },
    **{
        n: _Limit(1.0e6, "1 Mohm passes microamperes at robot voltages")
        for n in ("armature_resistance", "battery_resistance")
    },
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
    if name not in field_schema():
        raise KeyError(f"no parameter named {name!r}")
    lo, hi, lo_closed, hi_closed = allowed_range(name)
    lo = -math.inf if lo is None else (float(lo) if lo_closed else math.nextafter(lo, math.inf))
    hi = math.inf if hi is None else (float(hi) if hi_closed else math.nextafter(hi, -math.inf))
    return lo, hi


def _is_bool(x: object) -> bool:
    return isinstance(x, bool) or type(x).__name__ in ("bool_", "bool")


def _coerce(spec: FieldSpec, value: object, where: str = "") -> float | int | bool:
    """Return ``value`` as the field's Python type, or raise on a wrong type."""
    if spec.kind == "bool":
        if _is_bool(value):
            return bool(value)
        expected = "true or false"
    elif not _is_bool(value) and isinstance(value, numbers.Real):
        try:
            x = float(value)
        except OverflowError:  # an integer beyond the float range (Python API only)
            rule = _RULES.get(spec.name)
            text = rule.describe(spec.factor, spec.unit) if rule else "a real number"
            digits = len(str(abs(typing.cast(int, value))))
            raise ParameterError(
                f"{spec.label} = an integer of {digits} digits is not allowed: "
                f"must be finite and {text}{where}",
                spec.name,
            ) from None
        if spec.kind == "float":
            return x
        if math.isfinite(x) and x.is_integer():
            return int(x)
        raise ParameterError(
            f"{spec.label} = {format_value(value)} is not allowed: must be an integer "
            f"{_RULES[spec.name].describe(1.0, '1')}{where}",
            spec.name,
        )
    else:
        expected = "an integer" if spec.kind == "int" else "a number"
    raise ParameterError(
        f"{spec.label} = {value!r} has the wrong type ({type(value).__name__}): "
        f"expected {expected}{where}",
        spec.name,
    )


def coerce_value(spec: FieldSpec, value: object, where: str = ""):
    """:func:`_coerce` for any field: a per-leg field (:data:`PER_LEG_FIELDS`) also takes a
    (back, front) pair (list, tuple or 1-d array of two), returned as a tuple."""
    if given_per_leg(value):
        pair = list(typing.cast(typing.Iterable, value))
        if spec.name not in PER_LEG_FIELDS:
            raise ParameterError(
                f"{spec.label} = {pair!r} is not allowed: one value for the whole robot (only "
                f"the leg, hip-unit and motor quantities may be given per leg as "
                f"[back, front]){where}",
                spec.name,
            )
        if len(pair) != 2:
            raise ParameterError(
                f"{spec.label} = {pair!r} is not allowed: give one value for "
                f"both legs or a pair [back, front]{where}",
                spec.name,
            )
        return tuple(_coerce(spec, v, where) for v in pair)
    return _coerce(spec, value, where)


def reject(
    spec: FieldSpec, value: typing.Any, rule: str, origins, leg: int | None = None
) -> typing.NoReturn:
    """Raise the ParameterError of a field whose value breaks ``rule``, naming the field (and
    the leg), the value in its display unit, where it came from (``origins``) and a likely
    unit slip."""
    where, note = origins.get(spec.name, ("", None))
    unit = "" if spec.unit in ("1", "bool") else f" {spec.unit}"
    shown = format_value(value / spec.factor) if spec.kind == "float" else format_value(value)
    slip = slip_hint(spec, value, note) if isinstance(value, float) else None
    slip = f" ({slip})" if slip else ""
    note = f" ({note})" if note else ""
    label = spec.label if leg is None else f"{spec.label} ({LEG_NAMES[leg]} leg)"
    raise ParameterError(
        f"{label} = {shown}{unit}{note} is not allowed: {rule}{where}{slip}", spec.name
    )


def check_fields(obj: typing.Any, origins) -> None:
    """Type, finiteness and single-field range of every field of ``obj``."""
    cls: typing.Any = type(obj)
    for name, spec in fields_of(cls).items():
        where = origins.get(name, ("", None))[0]
        given = getattr(obj, name)
        coerce_value(spec, given, where)  # raises on a wrong type or a pair not allowed
        pair = isinstance(given, tuple)
        for index, value in enumerate(given if pair else (given,)):
            leg = index if pair else None
            if spec.kind == "int" and not isinstance(value, numbers.Integral):
                raise ParameterError(
                    f"{spec.label} = {value!r} has the wrong type "
                    f"({type(value).__name__}): expected an integer{where}",
                    name,
                )
            if spec.kind == "bool":
                continue
            rule = _RULES.get(name)
            finite = math.isfinite(value)
            if not finite or (rule is not None and not rule.contains(value)):
                # (the message is composed only for a value that fails: every simulate()
                # checks every field)
                text = rule.describe(spec.factor, spec.unit) if rule else "a real number"
                reject(
                    spec,
                    value,
                    f"must be finite and {text}" if not finite else f"must be {text}",
                    origins,
                    leg,
                )
            limit = _LIMITS.get(name)
            if limit is not None and value > limit.hi:
                reject(
                    spec,
                    value,
                    f"must be {_describe_limit(rule, limit, spec)} ({limit.why})",
                    origins,
                    leg,
                )


def _describe_limit(rule: _Range | None, limit: _Limit, spec: FieldSpec) -> str:
    """The whole allowed interval of a field with a physical bound, in its display unit."""
    assert rule is not None and rule.lo is not None, "a field with a physical bound has a range"
    lo = format_bound(rule.lo / spec.factor)
    hi = f"{limit.hi / spec.factor:.9g}"
    unit = "" if spec.unit in ("1", "bool") else f" {spec.unit}"
    return f"in {'[' if rule.lo_closed else '('}{lo}, {hi}]{unit}"
