"""Parameter sets are checked when they are constructed, and absurd values are warned of.

Behaviours checked:

- constructing a :class:`RobotParameters` / :class:`ControllerParameters` /
  :class:`Environment` (directly, with ``.replace`` or ``dataclasses.replace``) refuses a
  value its physics forbids, with a :class:`ParameterError` naming the field (and, for a
  robot whose legs differ, the leg) and the allowed range. What each field allows is
  written here from its physical meaning (a mass, a spring, a resistance is > 0; a
  damper, a friction, a gain is >= 0 with 0 meaning "absent"; an offset or an angle has a
  sign), not read from the code's tables;
- a value far outside what a robot of Scout II's kind has (1000 times its leg stiffness:
  the stiffness given in N/mm; a gain per degree given per radian) constructs, with an
  :class:`ImplausibleParameterWarning` naming the field, the value, Scout II's value and the
  likely unit slip (and the file, for a value read from one); shown once per distinct
  value by the default warnings filter, silenced by the standard filters;
- Scout II itself and every robot file shipped in the repository warn of nothing.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from scoutsim.parameters import (
    ControllerParameters,
    Environment,
    ImplausibleParameterWarning,
    ParameterError,
    RobotParameters,
    load_parameters,
    load_robot,
    validate_controller,
    validate_robot,
)

REPO = Path(__file__).resolve().parents[2]

# -- what each field allows, from its physical meaning ---------------------------------------
#: > 0: a body's mass and inertia, a size, a spring, a gear ratio, an efficiency (no
#: transmission passes nothing), a motor constant, a resistance, a supply, a sampling period,
#: a compression threshold that must be crossed to touch down. (leg_com_distance: the
#: centre of mass of a leg with mass lies on the leg, beyond the hip.)
POSITIVE = {
    "torso_mass",
    "torso_inertia",
    "leg_stiffness",
    "hip_spacing",
    "leg_rest_length",
    "leg_com_distance",
    "gravity",
    "torso_length",
    "torso_height",
    "planetary_ratio",
    "sprocket_ratio",
    "gearbox_efficiency",
    "sprocket_efficiency",
    "belt_stiffness",
    "torque_constant",
    "speed_constant",
    "armature_resistance",
    "current_limit",
    "battery_voltage",
    "control_period",
    "touchdown_compression",
}
#: >= 0, with 0 meaning the effect is absent (the paper's idealisations: massless legs, no
#: damping, no friction, no backlash, no losses, an ideal battery, a gain switched off)
NON_NEGATIVE = {
    "leg_mass",
    "leg_inertia",
    "leg_damping",
    "gearbox_idle_loss_torque",
    "gearbox_load_loss_coefficient",
    "drive_gear_inertia",
    "driven_gear_inertia",
    "joint_stiction",
    "joint_damping",
    "belt_damping",
    "belt_backlash",
    "leg_friction_force",
    "leg_friction_side_load_coefficient",
    "leg_damping_angle_coefficient",
    "battery_resistance",
    "liftoff_compression",
    *(
        f"{kind}_{gain}_{end}"
        for kind in ("flight", "brake")
        for gain in ("kp", "kd")
        for end in ("front", "back")
    ),
}
#: signed: an offset, an angle, a feedback gain
SIGNED = {
    "com_offset",
    "touchdown_angle_front",
    "touchdown_angle_back",
    "sweep_limit_front",
    "sweep_limit_back",
    "pitch_gain_front",
    "pitch_gain_back",
    "pitch_rate_gain_front",
    "pitch_rate_gain_back",
}
#: not real numbers: a count of legs and a switch
OTHER = {"legs_per_virtual_leg", "sense_motor_angle"}


def _owner(name: str) -> type:
    return (
        RobotParameters
        if name in {f.name for f in dataclasses.fields(RobotParameters)}
        else ControllerParameters
    )


def _build(name: str, value):
    return _owner(name)(**{name: value})


def _refused(name: str, value) -> str:
    with pytest.raises(ParameterError) as err:
        _build(name, value)
    assert err.value.field == name
    assert re.search(rf"\b{name}\b", str(err.value)), str(err.value)
    assert "not allowed" in str(err.value) or "wrong type" in str(err.value)
    return str(err.value)


def test_the_physical_classes_cover_every_field():
    """Every field of both parameter classes has its physical meaning written above, so a
    new field cannot go unchecked here."""
    fields = {
        f.name for cls in (RobotParameters, ControllerParameters) for f in dataclasses.fields(cls)
    }
    classes = (POSITIVE, NON_NEGATIVE, SIGNED, OTHER)
    assert set().union(*classes) == fields
    assert sum(map(len, classes)) == len(fields)  # no field in two classes


def test_a_negative_leg_mass_is_refused_on_construction_naming_field_and_range():
    with pytest.raises(ParameterError) as err:
        RobotParameters(leg_mass=-1)
    assert err.value.field == "leg_mass"
    assert re.fullmatch(
        r"robot\.leg_mass = -1(\.0)? kg is not allowed: must be >= 0", str(err.value)
    ), str(err.value)


@pytest.mark.parametrize("name", sorted(POSITIVE))
@pytest.mark.parametrize("sign", [-1.0, 0.0])
def test_a_quantity_that_must_be_positive_refuses_zero_and_negative(name, sign):
    default = getattr(_owner(name)(), name)
    message = _refused(name, sign * default)
    assert ">" in message or " in (" in message  # the allowed range is stated


@pytest.mark.parametrize("name", sorted(NON_NEGATIVE))
def test_a_quantity_that_is_absent_at_zero_refuses_negative_and_takes_zero(name):
    default = getattr(_owner(name)(), name)
    _refused(name, -(default or 1.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error", ImplausibleParameterWarning)
        assert getattr(_build(name, 0.0), name) == 0.0  # allowed, and plausible


@pytest.mark.parametrize("name", sorted(POSITIVE | NON_NEGATIVE | SIGNED))
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_a_real_quantity_refuses_nan_and_infinity(name, value):
    assert "finite" in _refused(name, value)


def test_numpy_numbers_are_checked_as_python_numbers():
    """A sweep over ``np.linspace`` passes NumPy numbers: the same refusals and warnings."""
    with pytest.raises(ParameterError, match="leg_mass"):
        RobotParameters(leg_mass=np.float64(-1.0))
    with pytest.raises(ParameterError, match="leg_mass.*finite"):
        RobotParameters(leg_mass=np.float64(np.nan))
    with pytest.raises(ParameterError, match=r"leg_mass \(front leg\)"):
        RobotParameters(leg_mass=np.array([1.0, -1.0]))
    with pytest.raises(ParameterError, match="legs_per_virtual_leg"):
        RobotParameters(legs_per_virtual_leg=np.float64(2.0))
    assert RobotParameters(legs_per_virtual_leg=np.int64(1)).legs_per_virtual_leg == 1
    with pytest.warns(ImplausibleParameterWarning, match="leg_stiffness.*N/mm"):
        RobotParameters(leg_stiffness=np.float64(3520.0e3))


def test_count_and_switch_refuse_the_wrong_kind():
    _refused("legs_per_virtual_leg", 0)
    _refused("legs_per_virtual_leg", 2.5)
    _refused("sense_motor_angle", 1)
    _refused("torso_mass", True)


def test_an_angle_in_degrees_read_as_radians_is_refused_naming_the_slip():
    """Table I's touchdown angle, 21 (degrees), passed in radians is 1203 deg: outside
    the +-90 deg a leg can point, refused; the message names the deg - rad slip."""
    message = _refused("touchdown_angle_front", 21.0)
    assert "must be in (-90, 90) deg" in message
    assert re.search(r"slip between (rad and deg|deg and rad)", message), message


def test_replace_checks_as_construction_does():
    robot, controller = RobotParameters(), ControllerParameters()
    for make in (
        lambda: dataclasses.replace(robot, leg_stiffness=-3520.0),
        lambda: robot.replace(leg_stiffness=-3520.0),
    ):
        with pytest.raises(ParameterError, match="leg_stiffness"):
            make()
    with pytest.raises(ParameterError, match="control_period"):
        dataclasses.replace(controller, control_period=0.0)
    with pytest.raises(ParameterError, match="liftoff_compression"):  # two fields together
        dataclasses.replace(controller, liftoff_compression=controller.touchdown_compression)
    with pytest.warns(ImplausibleParameterWarning, match="leg_stiffness"):
        dataclasses.replace(robot, leg_stiffness=1000.0 * robot.leg_stiffness)


@pytest.mark.parametrize("leg, pair", [("back", (-1.0, 3520.0)), ("front", (3520.0, -1.0))])
def test_a_per_leg_robot_names_the_bad_leg(leg, pair):
    with pytest.raises(ParameterError, match=rf"leg_stiffness \({leg} leg\) = -1\.0"):
        RobotParameters(leg_stiffness=pair)
    with pytest.raises(ParameterError, match=rf"leg_rest_length \({leg} leg\)"):
        RobotParameters(leg_rest_length=tuple(0.0 if x < 0 else 0.3 for x in pair))


def test_a_per_leg_robot_warns_of_the_implausible_leg_once():
    """The back leg's stiffness given in N/mm: the warning names the back leg, and neither
    asking for that leg's robot (``robot.leg("back")``) nor checking the robot again (as
    simulate() does) warns again."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = RobotParameters(leg_stiffness=(3.52, 3520.0))
        robot.leg("back"), robot.leg("front"), validate_robot(robot)
    texts = [str(w.message) for w in caught if w.category is ImplausibleParameterWarning]
    assert len(texts) == 1, texts
    assert "leg_stiffness (back leg) = 3.52 N/m" in texts[0] and "N/mm" in texts[0]


def test_environment_refuses_a_friction_coefficient_below_zero_or_nan():
    for mu in (-1.0, 0.0, math.nan):
        with pytest.raises(ParameterError, match="friction_coefficient") as err:
            Environment(friction_coefficient=mu)
        assert err.value.field == "friction_coefficient" and "> 0" in str(err.value)
    assert Environment(friction_coefficient=math.inf).friction_coefficient == math.inf


def test_validate_checks_a_set_made_without_its_constructor():
    """An instance that did not pass through ``__init__`` (as unpickling makes one) is
    still checked by validate_robot / validate_controller; other objects are a TypeError."""
    bad = copy.copy(RobotParameters())
    object.__setattr__(bad, "torso_mass", -1.0)
    with pytest.raises(ParameterError, match="torso_mass"):
        validate_robot(bad)
    with pytest.raises(TypeError, match="expected RobotParameters"):
        validate_robot(ControllerParameters())
    with pytest.raises(TypeError, match="expected ControllerParameters"):
        validate_controller(RobotParameters())


# -- plausibility ----------------------------------------------------------------------------
def _warning(make) -> str:
    with pytest.warns(ImplausibleParameterWarning) as caught:
        make()
    texts = [str(w.message) for w in caught if w.category is ImplausibleParameterWarning]
    assert len(texts) == 1, texts
    return texts[0]


@pytest.mark.parametrize("factor, said", [(1000.0, "1000x"), (1e-3, "1/1000 of")])
def test_a_leg_stiffness_a_thousand_times_off_warns_naming_n_per_mm(factor, said):
    """3520 N/m is 3.52 N/mm: a factor 1000 either way is the N/mm - N/m slip."""
    text = _warning(lambda: RobotParameters(leg_stiffness=3520.0 * factor))
    assert text.startswith(
        f"robot.leg_stiffness = {3520.0 * factor!r} N/m is {said} Scout II's 3520 N/m"
    ), text
    assert "N/mm" in text


def test_a_gain_per_degree_given_per_radian_warns_naming_degrees():
    """250 N m/rad is 4.36 N m/deg; 250 read as N m/deg is 57.3 times more."""
    text = _warning(lambda: ControllerParameters(flight_kp_front=250.0 * 180.0 / math.pi))
    assert "flight_kp_front" in text and "57.3x" in text and "deg" in text


def test_a_stiffness_given_in_kgf_per_mm_warns_naming_kgf():
    """3520 N/m is 0.359 kgf/mm (1 kgf = 9.80665 N)."""
    text = _warning(lambda: RobotParameters(leg_stiffness=3520.0 / 9806.65))
    assert "kgf/mm" in text


def test_a_value_from_a_file_warns_naming_the_file(tmp_path):
    """A robot file that labels Scout II's stiffness in N/m as N/mm."""
    path = tmp_path / "my_robot.toml"
    path.write_text('[robot]\nleg_stiffness = { value = 3520, unit = "N/mm" }\n')
    text = _warning(lambda: load_robot(path))
    assert "given as 3520 N/mm" in text and str(path) in text and "1000x" in text


def test_the_warning_is_shown_once_per_value_and_silenced_by_the_standard_filters():
    """A sweep that builds the same implausible robot a hundred times sees one warning,
    and one more for another implausible value; "ignore" silences it, "error" raises it."""
    robot = RobotParameters()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        for _ in range(100):
            dataclasses.replace(robot, leg_stiffness=4.0e6)
        assert len(caught) == 1
        dataclasses.replace(robot, leg_stiffness=5.0e6)
        assert len(caught) == 2
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        warnings.filterwarnings("ignore", category=ImplausibleParameterWarning)
        dataclasses.replace(robot, leg_stiffness=4.0e6)
    assert not caught
    with warnings.catch_warnings():
        warnings.simplefilter("error", ImplausibleParameterWarning)
        with pytest.raises(ImplausibleParameterWarning):
            dataclasses.replace(robot, leg_stiffness=4.0e6)


def _shipped_robot_files() -> list[tuple[str, str]]:
    """(name, TOML text) of every robot file in the repository: the *.toml files under
    scoutsim/, examples/, tests/, docs/, and the TOML blocks of README.md and docs/*.md
    with a parameter section."""
    out = []
    for top in ("scoutsim", "examples", "tests", "docs"):
        out += [
            (str(p.relative_to(REPO)), p.read_text(encoding="utf-8"))
            for p in sorted((REPO / top).rglob("*.toml"))
        ]
    for doc in [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]:
        if doc.exists():
            for i, block in enumerate(
                re.findall(r"```toml\n(.*?)```", doc.read_text(encoding="utf-8"), flags=re.S)
            ):
                if re.search(r"^\[(robot|transmission|motor|controller)\]", block, re.M):
                    out.append((f"{doc.relative_to(REPO)} block {i + 1}", block))
    return out


def test_scout2_and_every_shipped_robot_file_warn_of_nothing(tmp_path):
    files = _shipped_robot_files()
    assert any(name.endswith("scout2.toml") for name, _ in files)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ImplausibleParameterWarning)
        RobotParameters(), ControllerParameters(), load_parameters()
        for name, text in files:
            path = tmp_path / "robot.toml"
            path.write_text(text, encoding="utf-8")
            try:
                load_parameters(path)
            except ImplausibleParameterWarning as exc:  # pragma: no cover - the failure
                raise AssertionError(f"{name}: {exc}") from None
