"""Tests for scoutsim.parameters: defaults, units, user files, overrides, validation."""

import dataclasses
import json
import math

import pytest

from scoutsim.parameters import (
    UNITS,
    ControllerParameters,
    ImplausibleParameterWarning,
    ParameterError,
    RobotParameters,
    from_dict,
    load_controller,
    load_parameters,
    load_robot,
    parameter_table,
    to_dict,
    validate_controller,
    validate_robot,
)


def _write(tmp_path, text, name="user.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# -- defaults ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "cls, loader", [(RobotParameters, load_robot), (ControllerParameters, load_controller)]
)
def test_dataclass_defaults_match_packaged_toml(cls, loader):
    loaded, default = loader(), cls()
    for f in dataclasses.fields(cls):
        a, b = getattr(loaded, f.name), getattr(default, f.name)
        assert type(a) is type(b), f.name
        assert a == pytest.approx(b, rel=1e-12, abs=0.0), f.name


def test_derived_defaults():
    robot, ctrl = load_parameters()
    assert robot.gear_ratio == pytest.approx(72.38 * 48 / 34, rel=1e-12)
    assert robot.gear_ratio == pytest.approx(102.1835, abs=1e-4)
    assert robot.efficiency == pytest.approx(0.6528, rel=1e-12)
    assert robot.belt_stiffness == pytest.approx(401.07, abs=5e-3)
    assert robot.belt_damping == pytest.approx(229.18, abs=5e-3)
    assert robot.joint_damping == pytest.approx(3.552e-5, rel=1e-3)
    assert ctrl.touchdown_angle_front == pytest.approx(math.radians(21.0), rel=1e-12)
    assert ctrl.touchdown_angle_back == pytest.approx(math.radians(19.0), rel=1e-12)
    assert ctrl.control_period == pytest.approx(1e-3, rel=1e-12)
    assert robot.total_mass == pytest.approx(24.745, rel=1e-12)


def test_unit_table_is_consistent():
    for dim, group in UNITS.items():
        assert next(iter(group.values())) == 1.0, dim  # first unit of each group is SI
    assert UNITS["angle"]["deg"] == pytest.approx(math.pi / 180)
    assert UNITS["speed constant"]["mV/rpm"] == pytest.approx(1e-3 * 60 / (2 * math.pi))


def test_parameter_table_covers_every_field():
    rows = parameter_table()
    names = [
        f.name for cls in (RobotParameters, ControllerParameters) for f in dataclasses.fields(cls)
    ]
    assert [r["name"] for r in rows] == names
    td = next(r for r in rows if r["name"] == "touchdown_angle_front")
    assert (td["section"], td["value"], td["unit"], td["si_unit"], td["source"]) == (
        "controller",
        21.0,
        "deg",
        "rad",
        "Table I",
    )
    assert td["si_value"] == pytest.approx(math.radians(21.0))
    belt = next(r for r in rows if r["name"] == "belt_stiffness")
    assert belt["section"] == "transmission" and belt["si_unit"] == "N m/rad"


# -- user files and overrides -------------------------------------------------------------------


def test_user_file_plain_number_and_unit_table(tmp_path):
    path = _write(
        tmp_path,
        """
[robot]
torso_mass = 25.0                       # plain number: kg, as in scout2.toml
hip_spacing = { value = 60, unit = "cm", source = "my robot" }
[transmission]
belt_stiffness = { value = 500.0, unit = "N m/rad" }
[controller]
touchdown_angle_front = { value = 0.3, unit = "rad" }
touchdown_angle_back = 17                # plain number: deg
control_period = { value = 0.002, unit = "s" }
sense_motor_angle = false
""",
    )
    robot, ctrl = load_parameters(path)
    assert robot.torso_mass == 25.0
    assert robot.hip_spacing == pytest.approx(0.6)
    assert robot.belt_stiffness == 500.0
    assert robot.leg_mass == RobotParameters().leg_mass  # untouched default
    assert ctrl.touchdown_angle_front == 0.3
    assert ctrl.touchdown_angle_back == pytest.approx(math.radians(17.0))
    assert ctrl.control_period == pytest.approx(2e-3)
    assert ctrl.sense_motor_angle is False


def test_overrides_are_si_and_applied_after_file(tmp_path):
    path = _write(
        tmp_path, "[robot]\ntorso_mass = 25.0\n[controller]\ntouchdown_angle_front = 15\n"
    )
    robot = load_robot(path, overrides={"torso_mass": 30.0, "legs_per_virtual_leg": 1})
    assert robot.torso_mass == 30.0 and robot.legs_per_virtual_leg == 1
    ctrl = load_controller(path, overrides={"touchdown_angle_back": 0.25})
    assert ctrl.touchdown_angle_front == pytest.approx(math.radians(15.0))
    assert ctrl.touchdown_angle_back == 0.25


def test_massless_leg_configuration_is_allowed():
    robot = load_robot(overrides={"leg_mass": 0.0, "leg_inertia": 0.0, "leg_com_distance": 0.0})
    assert robot.leg_mass == 0.0 and robot.leg_com_distance == 0.0
    with pytest.raises(ParameterError, match="leg_com_distance"):
        load_robot(overrides={"leg_com_distance": 0.0})


# -- refusals -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "overrides, pieces",
    [
        ({"torso_mass": -1.0}, ["robot.torso_mass", "-1.0 kg", "> 0"]),
        ({"torso_inertia": -0.5}, ["robot.torso_inertia", "-0.5", "> 0"]),
        ({"leg_inertia": -0.01}, ["robot.leg_inertia", "-0.01", ">= 0"]),
        ({"planetary_ratio": 0.0}, ["transmission.planetary_ratio", "0.0", "> 0"]),
        ({"gearbox_efficiency": 0.0}, ["transmission.gearbox_efficiency", "0.0", "(0, 1]"]),
        ({"sprocket_efficiency": 1.2}, ["transmission.sprocket_efficiency", "1.2", "(0, 1]"]),
        ({"leg_stiffness": float("nan")}, ["robot.leg_stiffness", "nan", "finite", "> 0"]),
        ({"current_limit": float("inf")}, ["motor.current_limit", "inf", "finite"]),
        ({"legs_per_virtual_leg": 0}, ["robot.legs_per_virtual_leg", "0", ">= 1"]),
        ({"leg_com_distance": 0.5}, ["robot.leg_com_distance", "0.5 m", "leg_rest_length = 0.323"]),
    ],
)
def test_bad_robot_values_refused(overrides, pieces):
    with pytest.raises(ParameterError) as err:
        load_robot(overrides=overrides)
    for piece in pieces:
        assert piece in str(err.value)
    assert err.value.field == next(iter(overrides))


@pytest.mark.parametrize(
    "overrides, pieces",
    [
        (
            {"touchdown_angle_front": math.radians(95.0)},
            ["controller.touchdown_angle_front", "95.0 deg", "(-90, 90) deg"],
        ),
        (
            {"touchdown_angle_back": math.radians(-90.0)},
            ["controller.touchdown_angle_back", "-90.0 deg", "(-90, 90) deg"],
        ),
        ({"flight_kp_front": -1.0}, ["controller.flight_kp_front", "-1.0", ">= 0"]),
        ({"control_period": 0.5}, ["controller.control_period", "500.0 ms", "(0, 100] ms"]),
        (
            {"liftoff_compression": 8e-3, "touchdown_compression": 8e-3},
            ["controller.liftoff_compression", "8.0 mm", "< touchdown_compression = 8 mm"],
        ),
        (
            {"liftoff_compression": 9e-3, "touchdown_compression": 8e-3},
            ["controller.liftoff_compression", "9.0 mm", "< touchdown_compression"],
        ),
    ],
)
def test_bad_controller_values_refused(overrides, pieces):
    with pytest.raises(ParameterError) as err:
        load_controller(overrides=overrides)
    for piece in pieces:
        assert piece in str(err.value)


@pytest.mark.filterwarnings("ignore::scoutsim.parameters.ImplausibleParameterWarning")
def test_touchdown_compression_must_be_below_rest_length():
    # coupling not checked alone; 0.5 m is far from Scout II's 8 mm (a warning, not an error)
    with pytest.warns(ImplausibleParameterWarning, match="touchdown_compression"):
        load_controller(overrides={"touchdown_compression": 0.5})
    with pytest.raises(ParameterError, match=r"touchdown_compression = 500\.0 mm.*leg_rest_length"):
        load_parameters(controller_overrides={"touchdown_compression": 0.5})


def test_file_errors_name_section_and_path(tmp_path):
    path = _write(tmp_path, '[robot]\ntorso_mass = { value = -1000, unit = "g" }\n')
    with pytest.raises(ParameterError) as err:
        load_robot(path)
    msg = str(err.value)
    for piece in ("robot.torso_mass", "-1.0 kg", "given as -1000 g", "> 0", "[robot]", str(path)):
        assert piece in msg


def test_file_touchdown_angle_in_degrees_refused(tmp_path):
    path = _write(tmp_path, "[controller]\ntouchdown_angle_front = 95\n")
    with pytest.raises(
        ParameterError, match=r"touchdown_angle_front = 95\.0 deg .*\(-90, 90\) deg"
    ):
        load_controller(path)


def test_nan_in_file_refused(tmp_path):
    path = _write(tmp_path, "[transmission]\nbelt_damping = nan\n")
    with pytest.raises(ParameterError, match=r"transmission\.belt_damping = nan .*finite and >= 0"):
        load_robot(path)


def test_unknown_key_suggests_closest_name(tmp_path):
    path = _write(tmp_path, "[robot]\ntorso_mas = 20.0\n")
    with pytest.raises(ParameterError, match=r"'torso_mas'.*did you mean 'torso_mass'"):
        load_robot(path)
    with pytest.raises(
        ParameterError, match=r"'gearbox_eficiency'.*did you mean 'gearbox_efficiency'"
    ):
        load_robot(overrides={"gearbox_eficiency": 0.5})


def test_key_in_wrong_section_and_unknown_section(tmp_path):
    with pytest.raises(ParameterError, match=r"belongs in section \[transmission\]"):
        load_robot(_write(tmp_path, "[robot]\nbelt_stiffness = 7.0\n", "a.toml"))
    with pytest.raises(
        ParameterError, match=r"unknown section 'controler'.*did you mean 'controller'"
    ):
        load_controller(_write(tmp_path, "[controler]\ncontrol_period = 1.0\n", "b.toml"))


def test_wrong_unit_dimension_refused(tmp_path):
    path = _write(tmp_path, '[robot]\nhip_spacing = { value = 0.5, unit = "kg" }\n')
    with pytest.raises(ParameterError) as err:
        load_robot(path)
    msg = str(err.value)
    for piece in ("robot.hip_spacing", "'kg'", "mass", "length", "m, cm, mm", str(path)):
        assert piece in msg


def test_unknown_unit_refused(tmp_path):
    path = _write(tmp_path, '[controller]\ntouchdown_angle_front = { value = 20, unit = "grad" }\n')
    with pytest.raises(ParameterError, match=r"unknown unit 'grad'; allowed units: rad, deg"):
        load_controller(path)


@pytest.mark.parametrize(
    "text, pieces",
    [
        (
            '[robot]\ntorso_mass = "heavy"\n',
            ["robot.torso_mass", "'heavy'", "wrong type", "number"],
        ),
        ("[robot]\ntorso_mass = true\n", ["robot.torso_mass", "True", "wrong type"]),
        (
            "[controller]\nsense_motor_angle = 1\n",
            ["controller.sense_motor_angle", "wrong type", "true or false"],
        ),
        ("[robot]\nlegs_per_virtual_leg = 1.5\n", ["robot.legs_per_virtual_leg", "1.5", "integer"]),
    ],
)
def test_wrong_types_in_file_refused(tmp_path, text, pieces):
    with pytest.raises(ParameterError) as err:
        load_parameters(_write(tmp_path, text))
    for piece in pieces:
        assert piece in str(err.value)


def test_malformed_toml_refused(tmp_path):
    path = _write(tmp_path, "[robot]\ntorso_mass = = 3\n")
    with pytest.raises(ParameterError, match="malformed TOML") as err:
        load_robot(path)
    assert str(path) in str(err.value)


def test_validate_instances_directly():
    assert validate_robot(RobotParameters()) == RobotParameters()
    with pytest.raises(
        ParameterError, match=r"robot\.torso_mass = -1\.0 kg is not allowed: must be > 0$"
    ):
        validate_robot(RobotParameters(torso_mass=-1.0))
    with pytest.raises(ParameterError, match=r"sprocket_ratio = 0\.0 is not allowed: must be > 0"):
        validate_robot(RobotParameters().replace(sprocket_ratio=0.0))
    with pytest.raises(ParameterError, match="wrong type"):
        validate_robot(RobotParameters(legs_per_virtual_leg=2.0))
    with pytest.raises(ParameterError, match=r"liftoff_compression = 3\.0 mm"):
        validate_controller(
            ControllerParameters(touchdown_compression=2e-3, liftoff_compression=3e-3)
        )


# -- provenance round trip ------------------------------------------------------------------


def test_to_dict_from_dict_round_trip_through_json():
    robot = load_robot(overrides={"torso_mass": 21.123456789012345, "legs_per_virtual_leg": 1})
    ctrl = load_controller(
        overrides={"touchdown_angle_front": 0.1 + 0.2, "sense_motor_angle": False}
    )
    text = json.dumps(to_dict(robot, ctrl), allow_nan=False)
    robot2, ctrl2 = from_dict(json.loads(text))
    assert (robot2, ctrl2) == (robot, ctrl)
    assert type(robot2.legs_per_virtual_leg) is int and ctrl2.sense_motor_angle is False


def test_from_dict_refuses_bad_content():
    d = to_dict(RobotParameters(), ControllerParameters())
    del d["robot"]["torso_mass"]
    with pytest.raises(ParameterError, match="torso_mass"):
        from_dict(d)
    d = to_dict(RobotParameters(), ControllerParameters())
    d["controller"]["gain"] = 1.0
    with pytest.raises(ParameterError, match="unknown parameter 'gain'"):
        from_dict(d)


def test_every_construction_is_checked_by_value_and_type():
    """Each construction checks its own values and their types: a per-leg robot equal to
    one built before is valid, one that differs in one leg's value is refused, and so is
    one whose value has the wrong type (True is no mass, though it equals 1 in Python)."""
    robot = RobotParameters(leg_rest_length=(0.323, 0.30))
    assert validate_robot(robot) is robot
    assert RobotParameters(leg_rest_length=(0.323, 0.30)) == robot
    with pytest.raises(ParameterError, match="leg_rest_length"):
        RobotParameters(leg_rest_length=(0.323, -0.30))
    RobotParameters(torso_mass=10.0)
    with pytest.raises(ParameterError, match="torso_mass"):
        RobotParameters(torso_mass=True)
