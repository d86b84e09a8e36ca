"""A robot's field by name, one leg's value of a per-leg field included
(scoutsim.parameters.robot_fields).

Laws checked: setting one leg changes that leg only and reads back; a per-leg field named
without a leg is both legs while they are equal, and is refused (naming the two leg names)
where they differ, since setting it would silently make them equal; a leg on a field that
is not per leg, or a leg that is neither back nor front, is refused by name.
"""

from __future__ import annotations

import pytest

from scoutsim.parameters import RobotParameters
from scoutsim.parameters.robot_fields import (
    field_of,
    leg_names_where_legs_differ,
    robot_value,
    robot_with_value,
    robot_with_values,
)


def test_one_leg_is_set_alone_and_reads_back():
    robot = RobotParameters()
    k = robot.leg_stiffness
    front = robot_with_value(robot, "leg_stiffness.front", 1.1 * k)
    assert front.per_leg("leg_stiffness") == (k, 1.1 * k)
    assert robot_value(front, "leg_stiffness.front") == 1.1 * k
    assert robot_value(front, "leg_stiffness.back") == k
    assert robot.leg_stiffness == k  # (a new robot; the first is unchanged)


def test_both_legs_at_once_while_they_are_equal():
    robot = RobotParameters()
    stiffer = robot_with_value(robot, "leg_stiffness", 2.0 * robot.leg_stiffness)
    assert stiffer.per_leg("leg_stiffness") == (2.0 * robot.leg_stiffness,) * 2
    assert robot_value(stiffer, "leg_stiffness") == 2.0 * robot.leg_stiffness


def test_both_legs_are_refused_where_they_differ():
    robot = robot_with_value(RobotParameters(), "current_limit.front", 11.0)
    for attempt in (
        lambda: robot_value(robot, "current_limit", "robot."),
        lambda: robot_with_value(robot, "current_limit", 12.0, "robot."),
    ):
        with pytest.raises(ValueError, match="differs between this robot's legs") as e:
            attempt()
        assert "'robot.current_limit.back'" in str(e.value)
        assert "'robot.current_limit.front'" in str(e.value)
    assert leg_names_where_legs_differ(robot, ["current_limit", "torso_mass"]) == [
        "current_limit.back",
        "current_limit.front",
        "torso_mass",
    ]


def test_several_at_once_and_a_field_both_legs_then_one():
    robot = robot_with_values(
        RobotParameters(), {"leg_damping": 9.0, "leg_damping.front": 8.0, "torso_mass": 7.0}
    )
    assert robot.per_leg("leg_damping") == (9.0, 8.0)
    assert robot.torso_mass == 7.0


@pytest.mark.parametrize(
    "name, why",
    [("torso_mass.front", "only a per-leg field takes a leg"), ("leg_mass.middle", "back, front")],
)
def test_a_bad_leg_is_refused_by_name(name, why):
    with pytest.raises(ValueError, match=why) as e:
        field_of(name, "robot.")
    assert f"'robot.{name}'" in str(e.value)
