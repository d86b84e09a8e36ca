"""Units of the study tables and plots, and the tuning's default search ranges: a sweep's
``_deg`` column holds degrees and runs the same point as its SI name in radians; a field
given twice is refused; the map's axes carry each parameter's unit; a parameter given
without a range is searched near its base value (touchdown angles within 20 deg of it),
inside the field's allowed range."""

import math

import pytest

from scoutsim.analysis import sweep as SW
from scoutsim.analysis.tune_parameters import ANGLE_HALF_SPAN, parse_parameter
from scoutsim.parameters import ControllerParameters, allowed_range

DEG = "controller.touchdown_angle_front_deg"
SI = "controller.touchdown_angle_front"


def test_a_deg_column_holds_degrees_and_runs_the_point_its_si_name_runs():
    """The same two points, named in degrees and in radians: the same runs, and each
    table's parameter column in the unit of its name."""
    in_deg = SW.sweep([{DEG: 19.0}, {DEG: 23.0}], model="I", duration=0.6, workers=1)
    in_rad = SW.sweep(
        [{SI: math.radians(19.0)}, {SI: math.radians(23.0)}], model="I", duration=0.6, workers=1
    )
    assert [r[DEG] for r in in_deg.rows] == [19.0, 23.0]
    assert [r[SI] for r in in_rad.rows] == [math.radians(19.0), math.radians(23.0)]
    for a, b in zip(in_deg.rows, in_rad.rows):
        assert a["status"] == b["status"] == "ok"
        assert {k: v for k, v in a.items() if k != DEG} == {k: v for k, v in b.items() if k != SI}
    assert in_deg.rows[0]["average_speed_m_s"] != in_deg.rows[1]["average_speed_m_s"]


@pytest.mark.parametrize(
    "points, words",
    [
        ([{DEG: 19.0, SI: 0.3}], "set the same field"),
        ([{"robot.torso_mass_deg": 20.0}], "not an angle"),
    ],
)
def test_a_field_named_twice_or_degrees_of_no_angle_are_refused(points, words):
    with pytest.raises(ValueError, match=words):
        SW.sweep(points, model="I", duration=0.1, workers=1)


def hold(t, y, params, state, torque, leg_states):
    """A compiled controller that reads no ControllerParameters: zero torque."""
    torque[0] = 0.0
    torque[1] = 0.0
    return 0


def test_a_controller_object_cannot_sweep_controller_fields():
    """A controller object that does not read ControllerParameters (a compiled
    controller of its own; pitch feedback does read them): sweeping them would change
    nothing, so it is refused before any point (a factory gets them)."""
    from scoutsim.control import CompiledController

    with pytest.raises(ValueError, match="MODULE:FACTORY"):
        SW.sweep([{DEG: 19.0}], controller=CompiledController(hold), duration=0.1, workers=1)


def test_map_axes_carry_each_parameters_unit():
    """A _deg axis in degrees, an SI angle shown in degrees, another field in its SI
    unit; never the placeholder "[SI]"."""
    pytest.importorskip("matplotlib")
    grid = SW.grid_points({DEG: [19.0, 23.0], "robot.leg_damping": [50.0, 60.0]})
    res = SW.sweep(grid, model="I", duration=0.3, workers=1)
    ax = res.plot_map(DEG, "robot.leg_damping", "average_speed_m_s").axes[0]
    assert ax.get_xlabel() == f"{DEG} [deg]"
    assert ax.get_ylabel() == "robot.leg_damping [N s/m]"
    grid = SW.grid_points(
        {SI: [math.radians(19.0), math.radians(23.0)], "controller.flight_kp_front": [240.0, 260.0]}
    )
    res = SW.sweep(grid, model="I", duration=0.3, workers=1)
    fig = res.plot_map(SI, "controller.flight_kp_front", "average_speed_m_s")
    ax = fig.axes[0]
    assert ax.get_xlabel() == f"{SI} [deg]"
    assert ax.get_ylabel() == "controller.flight_kp_front [N m/rad]"
    lo, hi = ax.get_xlim()  # the axis spans the degrees, not the radians
    assert lo < 19.0 < 23.0 < hi < 30.0
    assert SW.axis_label("robot.gearbox_efficiency") == (1.0, "robot.gearbox_efficiency [-]")
    assert SW.axis_label("mean_speed_m_s") == (1.0, "mean_speed_m_s")


@pytest.mark.parametrize(
    "name",
    [
        "controller.touchdown_angle_front_deg",
        "controller.touchdown_angle_back",
        "controller.sweep_limit_front_deg",
    ],
)
def test_an_angle_without_a_range_is_searched_within_20_deg_of_its_base(name):
    """Around the base controller's value (Scout II's, or the one given), never the
    allowed +-90 deg."""
    fld = name.removesuffix("_deg").partition(".")[2]
    for base in (
        ControllerParameters(),
        ControllerParameters().replace(**{fld: math.radians(30.0)}),
    ):
        p = parse_parameter(name, cparams=base)
        value = getattr(base, fld)
        assert p.low == pytest.approx(value - ANGLE_HALF_SPAN, abs=1e-15)
        assert p.high == pytest.approx(value + ANGLE_HALF_SPAN, abs=1e-15)
        assert p.high - p.low < (allowed_range(fld)[1] - allowed_range(fld)[0]) / 4


def test_a_default_range_stays_inside_the_allowed_range():
    """A base near the end of the allowed range: the default range is cut there."""
    base = ControllerParameters().replace(touchdown_angle_front=math.radians(85.0))
    p = parse_parameter("controller.touchdown_angle_front", cparams=base)
    lo_r, hi_r, _, hi_closed = allowed_range("touchdown_angle_front")
    assert p.high < hi_r and not hi_closed
    assert p.low == pytest.approx(math.radians(65.0))


def test_a_field_without_a_default_range_still_needs_one():
    with pytest.raises(ValueError, match="needs a range"):
        parse_parameter("robot.leg_stiffness")
