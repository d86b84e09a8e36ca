"""Units: the allowed unit strings, their dimensions and SI factors, and the conversion of one
quantity of a file to SI (the one place where degrees, and every other non-SI unit, are
converted)."""

from __future__ import annotations

import math
import numbers

from .parameter_error import ParameterError

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
UNIT_INDEX: dict[str, tuple[str, float]] = {
    unit: (dim, factor) for dim, group in UNITS.items() for unit, factor in group.items()
}
assert len(UNIT_INDEX) == sum(map(len, UNITS.values())), "unit strings must be unique"


def quantity_to_si(entry: object, dimension: str, unit: str, label: str) -> float:
    """One quantity of a file to SI: a plain number in ``unit``, or ``{ value = ..., unit =
    "..." }`` in any unit of :data:`UNITS` of ``dimension``; ParameterError naming
    ``label`` otherwise."""
    if isinstance(entry, dict):
        if extra := sorted(set(entry) - {"value", "unit", "source"}):
            raise ParameterError(
                f"{label}: unknown key(s) {extra}; allowed keys are value, unit, source", label
            )
        if "value" not in entry:
            raise ParameterError(f"{label}: entry has no 'value'", label)
        unit = entry.get("unit", unit)
        entry = entry["value"]
    if not isinstance(unit, str) or unit.strip() not in UNITS[dimension]:
        raise ParameterError(
            f"{label}: unit {unit!r} is not allowed; allowed units: {', '.join(UNITS[dimension])}",
            label,
        )
    if (
        isinstance(entry, bool)
        or not isinstance(entry, numbers.Real)
        or not math.isfinite(float(entry))
    ):
        raise ParameterError(f"{label} = {entry!r} is not allowed: must be a finite number", label)
    return float(entry) * UNITS[dimension][unit.strip()]
