"""A robot's field by name, one leg's value of a per-leg field included: the names studies
that move one parameter at a time take (orbit sensitivities, families of gaits, the rows
of carried derivatives).

A name is a field of :class:`~scoutsim.parameters.robot.RobotParameters` (``leg_stiffness``)
or, for a field of :data:`~scoutsim.parameters.schema.PER_LEG_FIELDS`, one leg's value of it
(``leg_stiffness.back``, ``leg_stiffness.front``). A per-leg field named without a leg is
both legs at once, which is one number only while the two legs have the same value: on a
robot whose legs differ in that field, reading or setting it without a leg is refused (it
would silently make the legs equal), naming the two names to use instead.

Units: those of the field (SI).
"""

from __future__ import annotations

import dataclasses
from typing import Any

from ..names import LEG_NAMES, leg_index
from .robot import RobotParameters
from .schema import PER_LEG_FIELDS

__all__ = [
    "field_of",
    "robot_value",
    "robot_with_value",
    "robot_with_values",
    "leg_names_where_legs_differ",
]


def field_of(name: str, prefix: str = "") -> tuple[str, int | None]:
    """(the field, the leg's index or None) of a name: ``"leg_stiffness.front"`` ->
    ``("leg_stiffness", 1)``, ``"leg_stiffness"`` -> ``("leg_stiffness", None)``. ValueError
    for a leg on a field that is not per leg, or a leg that is not back or front;
    ``prefix``: what the caller's names put before a field (``"robot."``), for its
    message."""
    field, dot, leg = name.partition(".")
    if not dot:
        return field, None
    if field not in PER_LEG_FIELDS:
        raise ValueError(
            f"{prefix + name!r} is not allowed: only a per-leg field takes a leg "
            f"({', '.join(PER_LEG_FIELDS)})"
        )
    if leg not in LEG_NAMES:
        raise ValueError(
            f"{prefix + name!r} is not allowed: the leg must be one of {', '.join(LEG_NAMES)}"
        )
    return field, leg_index(leg)


def _refuse_both_legs(robot: RobotParameters, field: str, prefix: str) -> None:
    back, front = robot.per_leg(field)
    name = prefix + field
    raise ValueError(
        f"{name!r} differs between this robot's legs (back {back:g}, front {front:g}): "
        f"name one leg, {name + '.back'!r} or {name + '.front'!r}"
    )


def robot_value(robot: RobotParameters, name: str, prefix: str = "") -> float:
    """The value of ``name`` (see the module docstring) in ``robot``; ``prefix``: what the
    caller's names put before a field (``"robot."``), for the message of a refusal."""
    field, leg = field_of(name, prefix)
    if field not in PER_LEG_FIELDS:
        return float(getattr(robot, field))
    pair = robot.per_leg(field)
    if leg is None:
        if pair[0] != pair[1]:
            _refuse_both_legs(robot, field, prefix)
        return float(pair[0])
    return float(pair[leg])


def robot_with_value(
    robot: RobotParameters, name: str, value: float, prefix: str = ""
) -> RobotParameters:
    """``robot`` with ``name`` (see the module docstring) set to ``value``; one leg's value
    makes the field a (back, front) pair. ``prefix``: as for :func:`robot_value`."""
    return robot_with_values(robot, {name: value}, prefix)


def robot_with_values(robot: RobotParameters, values: dict, prefix: str = "") -> RobotParameters:
    """``robot`` with each name of ``values`` ({name: value}) set (:func:`robot_with_value`),
    in the order given: a robot checked once, when the last is set."""
    if not values:
        return robot
    changes: dict[str, Any] = {}
    pairs: dict[str, list] = {}
    for name, value in values.items():
        field, leg = field_of(name, prefix)
        if field in PER_LEG_FIELDS:
            pair = pairs.setdefault(field, list(robot.per_leg(field)))
            if leg is None and pair[0] != pair[1]:
                _refuse_both_legs(robot, field, prefix)
            if leg is None:
                pair[:] = [value, value]
                changes[field] = value
            else:
                pair[leg] = value
                changes[field] = tuple(pair)
        else:
            changes[field] = value
    return dataclasses.replace(robot, **changes)


def leg_names_where_legs_differ(robot: RobotParameters, fields) -> list[str]:
    """The names of ``fields`` for ``robot``: a per-leg field whose legs differ as its two
    legs' names (``field.back``, ``field.front``), any other field as it is."""
    out = []
    for field in fields:
        if field in PER_LEG_FIELDS and len(set(robot.per_leg(field))) > 1:
            out += [f"{field}.{leg}" for leg in LEG_NAMES]
        else:
            out.append(field)
    return out
