"""Tests of scoutsim.presentation.conventions: the figure of the coordinates draws each
coordinate's arrow in its positive direction as docs/specification.md section 1 defines it.

The reference is the specification's kinematics written out here (hip at h along the torso
axis from the COM, h = -L - e back, L - e front; toe = hip + l (sin gamma, -cos gamma),
gamma = theta + phi): the direction in which a point moves when a coordinate grows is its
finite difference, and every drawn arrow must point that way."""

import math

import numpy as np
import pytest

from scoutsim.parameters import RobotParameters
from scoutsim.presentation.conventions import ARROWS, ConventionsPose, plot_conventions

ROBOT = RobotParameters()
POSE = ConventionsPose()


def spec_points(x, y, theta, phi, l, e):
    """COM, hips and toes (back, front) by docs/specification.md section 1."""
    half = ROBOT.hip_spacing / 2
    com = np.array([x, y])
    axis = np.array([math.cos(theta), math.sin(theta)])
    hips = [com + (-half - e) * axis, com + (half - e) * axis]
    toes = [
        hip + li * np.array([math.sin(theta + ph), -math.cos(theta + ph)])
        for hip, ph, li in zip(hips, phi, l)
    ]
    return com, hips, toes


def motion(point, **change):
    """Direction in which ``point`` ("com", "hip0", "toe1", ...) moves when a coordinate of
    the pose grows (central finite difference of the specification's kinematics)."""
    base = {
        "x": POSE.x,
        "y": POSE.y,
        "theta": POSE.theta,
        "phi": list(POSE.phi),
        "l": list(POSE.l),
        "e": POSE.com_offset,
    }
    ((name, step),) = change.items()

    def at(sign):
        k = {key: (list(v) if isinstance(v, list) else v) for key, v in base.items()}
        if name.startswith(("phi", "l")):
            key, leg = name[:-1], int(name[-1])
            k[key][leg] += sign * step
        else:
            k[name] += sign * step
        com, hips, toes = spec_points(**k)
        return {"com": com, "hip0": hips[0], "hip1": hips[1], "toe0": toes[0], "toe1": toes[1]}[
            point
        ]

    d = at(1) - at(-1)
    return d / np.linalg.norm(d)


@pytest.fixture(scope="module")
def drawn():
    fig = plot_conventions(pose=POSE, robot=ROBOT)
    ax = fig.axes[0]
    arrows = {a.get_gid(): (np.array(a.xyann), np.array(a.xy)) for a in ax.texts if a.get_gid()}
    legs = {
        line.get_gid(): np.column_stack(line.get_data())
        for line in ax.lines
        if (line.get_gid() or "").startswith("leg_")
    }
    return arrows, legs


def cross(a, b) -> float:
    """z component of the cross product of two plane vectors (> 0: b turns
    counter-clockwise from a)."""
    return float(a[0] * b[1] - a[1] * b[0])


def direction(arrow):
    tail, head = arrow
    d = head - tail
    return d / np.linalg.norm(d)


def test_every_arrow_is_drawn(drawn):
    arrows, legs = drawn
    assert sorted(arrows) == sorted(ARROWS)
    assert sorted(legs) == ["leg_back", "leg_front"]


def test_the_drawn_legs_end_where_the_specification_puts_hips_and_toes(drawn):
    _, legs = drawn
    _, hips, toes = spec_points(POSE.x, POSE.y, POSE.theta, POSE.phi, POSE.l, POSE.com_offset)
    for leg, name in enumerate(("back", "front")):
        np.testing.assert_allclose(legs[f"leg_{name}"][0], hips[leg], atol=1e-12)
        np.testing.assert_allclose(legs[f"leg_{name}"][1], toes[leg], atol=1e-12)


def test_a_positive_leg_angle_puts_the_toe_ahead_of_the_hip(drawn):
    """phi > 0 (both legs in the drawn pose): the toe lies ahead of the hip along the
    torso axis, and the back hip lies behind the front hip."""
    _, legs = drawn
    axis = np.array([math.cos(POSE.theta), math.sin(POSE.theta)])
    assert min(POSE.phi) > 0
    for name in ("back", "front"):
        hip, toe = legs[f"leg_{name}"]
        assert (toe - hip) @ axis > 0.05
    assert (legs["leg_front"][0] - legs["leg_back"][0]) @ axis == pytest.approx(ROBOT.hip_spacing)


@pytest.mark.parametrize(
    "gid, point, change",
    [
        ("x", "com", {"x": 1e-6}),
        ("y", "com", {"y": 1e-6}),
        ("theta", "hip1", {"theta": 1e-6}),  # the torso's front end rises: nose up
        ("phi_back", "toe0", {"phi0": 1e-6}),
        ("phi_front", "toe1", {"phi1": 1e-6}),
        ("l_back", "toe0", {"l0": 1e-6}),
        ("l_front", "toe1", {"l1": 1e-6}),
        ("com_offset", "hip1", {"e": -1e-6}),  # the COM moves ahead of the hips' midpoint
    ],
)
def test_each_arrow_points_the_way_its_coordinate_grows(drawn, gid, point, change):
    """An arc's arrowhead is tangent to the arc: within a few degrees of the motion."""
    arrows, _ = drawn
    assert direction(arrows[gid]) @ motion(point, **change) > math.cos(math.radians(10))


def test_gamma_is_measured_from_the_world_vertical_and_grows_with_phi(drawn):
    arrows, _ = drawn
    assert direction(arrows["gamma_front"]) @ motion("toe1", phi1=1e-6) > math.cos(math.radians(10))
    tail, head = arrows["gamma_front"]
    _, hips, _ = spec_points(POSE.x, POSE.y, POSE.theta, POSE.phi, POSE.l, POSE.com_offset)
    r = head - hips[1]
    # the arc ends on the leg: at gamma = theta + phi from the downward vertical
    assert math.atan2(r[0], -r[1]) == pytest.approx(POSE.theta + POSE.phi[1], abs=1e-9)


@pytest.mark.parametrize("leg", [0, 1])
def test_a_positive_hip_torque_turns_the_leg_forward(drawn, leg):
    """The torque's arc turns about its hip in the sense in which phi grows (the toe's
    motion for a growing phi is counter-clockwise about the hip)."""
    arrows, _ = drawn
    tail, head = arrows[("tau_back", "tau_front")[leg]]
    _, hips, toes = spec_points(POSE.x, POSE.y, POSE.theta, POSE.phi, POSE.l, POSE.com_offset)
    turn = cross(head - hips[leg], head - tail)
    leg_turn = cross(toes[leg] - hips[leg], motion(f"toe{leg}", **{f"phi{leg}": 1e-6}))
    assert turn * leg_turn > 0


def test_gravity_points_down(drawn):
    arrows, _ = drawn
    assert direction(arrows["gravity"]) @ np.array([0.0, -1.0]) == pytest.approx(1.0)


def test_the_figure_is_written(tmp_path):
    path = tmp_path / "conventions.png"
    plot_conventions(path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
