"""The rules that couple fields: within a robot (the leg's centre of mass on the leg,
massless legs on both legs or neither, the torso's centre of mass between the hips),
within a controller (lift-off below touchdown compression), and between the two
(touchdown compression below the leg's rest length). The rules of a single field are
:mod:`.field_rules`."""

from __future__ import annotations

from .field_rules import reject
from .parameter_error import format_bound
from .schema import field_schema


def _pair(value) -> tuple:
    """A per-leg field's stored value as its (back, front) pair."""
    return value if type(value) is tuple else (value, value)


def check_robot_couplings(p, origins) -> None:
    """The leg's centre of mass on the leg, massless legs on both legs or neither, and the
    torso's centre of mass between the hips."""
    masses, inertias = _pair(p.leg_mass), _pair(p.leg_inertia)
    distances, rests = _pair(p.leg_com_distance), _pair(p.leg_rest_length)
    for leg in (0, 1):
        mass, distance, rest = masses[leg], distances[leg], rests[leg]
        if 0.0 < distance <= rest or (mass == 0.0 and distance == 0.0):
            continue
        spec = field_schema()["leg_com_distance"]
        differ = any(
            isinstance(getattr(p, n), tuple)
            for n in ("leg_com_distance", "leg_rest_length", "leg_mass")
        )
        l0 = format_bound(rest / spec.factor)
        massless = " (massless legs)" if mass == 0.0 else ""
        reject(
            spec,
            distance,
            f"must be in {'[' if mass == 0.0 else '('}0, leg_rest_length = "
            f"{l0}] {spec.unit}{massless}",
            origins,
            leg if differ else None,
        )
    if (masses[0] == 0.0 and inertias[0] == 0.0) != (masses[1] == 0.0 and inertias[1] == 0.0):
        front_massless = masses[1] == 0.0 and inertias[1] == 0.0
        reject(
            field_schema()["leg_mass"],
            masses[int(front_massless)],
            "the model's massless legs (leg_mass = leg_inertia = 0) are both legs or neither",
            origins,
            int(front_massless),
        )
    half = 0.5 * p.hip_spacing
    if not -half < p.com_offset < half:
        spec = field_schema()["com_offset"]
        reject(
            spec,
            p.com_offset,
            f"must be in (-hip_spacing / 2, hip_spacing / 2) = "
            f"({format_bound(-half / spec.factor)}, {format_bound(half / spec.factor)}) "
            f"{spec.unit} (the torso COM between the hips)",
            origins,
        )


def check_controller_couplings(c, origins) -> None:
    """Lift-off compression below touchdown compression."""
    if c.liftoff_compression >= c.touchdown_compression:
        spec = field_schema()["liftoff_compression"]
        td = format_bound(c.touchdown_compression / spec.factor)
        reject(
            spec,
            c.liftoff_compression,
            f"must be >= 0 and < touchdown_compression = {td} {spec.unit}",
            origins,
        )


def check_pair_couplings(robot, controller, origins) -> None:
    """Touchdown compression below the (shorter) leg's rest length."""
    if controller.touchdown_compression >= min(robot.per_leg("leg_rest_length")):
        spec = field_schema()["touchdown_compression"]
        l0 = format_bound(min(robot.per_leg("leg_rest_length")) / spec.factor)
        reject(
            spec,
            controller.touchdown_compression,
            f"must be > liftoff_compression and < leg_rest_length = {l0} {spec.unit}",
            origins,
        )
