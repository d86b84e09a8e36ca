"""Tests of scoutsim.presentation.conventions: the figure of the coordinates draws each
coordinate's arrow in its positive direction as docs/specification.md section 1 defines it.

The reference is the specification's kinematics written out here (hip at h along the torso
axis from the COM, h = -L - e back, L - e front; toe = hip + l (sin gamma, -cos gamma),
gamma = theta + phi): the direction in which a point moves when a coordinate grows is its
finite difference, and every drawn arrow must point that way.

The figure must also read: the renderer's boxes of the labels (each arrow's symbol, the
COM's name, the legend, the title) overlap neither each other nor any drawn curve, each
symbol lies nearer its own arrow than any other, and none is cut off by the figure's edge."""

import math

import numpy as np
import pytest

from scoutsim.parameters import RobotParameters
from scoutsim.presentation.conventions import ARROWS, ConventionsPose, plot_conventions

ROBOT = RobotParameters()
POSE = ConventionsPose()

#: the least clearance between a label's box and another label or a drawn curve [px at the
#: figure's own dpi]: text that touches a line is as hard to read as text on it
CLEARANCE_PX = 2.0


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
    arrows = {
        a.get_gid(): (np.array(a.xyann), np.array(a.xy))
        for a in ax.texts
        if not (a.get_gid() or "label_").startswith("label_")
    }
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


@pytest.fixture(scope="module")
def rendered():
    """The figure drawn by Agg: every label's box and every drawn curve in pixels."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = plot_conventions(pose=POSE, robot=ROBOT)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    ax = fig.axes[0]
    labels = {
        t.get_gid() or t.get_text(): t.get_window_extent(renderer)
        for t in [*ax.texts, *fig.texts]
        if t.get_text()
    }
    legend = ax.get_legend()
    if legend is not None:
        labels["legend"] = legend.get_window_extent(renderer)

    def dense(points, step=1.0):
        """The polyline through ``points`` [px], with a vertex at least every ``step`` px."""
        out = [points[:1]]
        for a, b in zip(points[:-1], points[1:]):
            n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
            out.append(a + np.outer(np.arange(1, n + 1) / n, b - a))
        return np.concatenate(out)

    curves = {}
    for gid in ARROWS:
        (arrow,) = [a for a in ax.texts if a.get_gid() == gid]
        tail, head = np.array(arrow.xyann), np.array(arrow.xy)
        curves[gid] = dense(ax.transData.transform(np.array([tail, head])))
    for i, line in enumerate(ax.lines):
        xy = ax.transData.transform(np.column_stack(line.get_data()))
        curves[line.get_gid() or f"line {i}"] = dense(xy)
    for i, patch in enumerate(ax.patches):
        path = patch.get_path()
        xy = patch.get_patch_transform().transform(path.vertices)
        xy = patch.get_data_transform().transform(xy)
        curves[f"patch {i} ({type(patch).__name__})"] = dense(xy)
    return fig, renderer, labels, curves


def test_every_arrow_has_its_symbol(rendered):
    _, _, labels, _ = rendered
    assert {f"label_{gid}" for gid in ARROWS} <= set(labels)


def test_no_two_labels_overlap(rendered):
    """The boxes the renderer gives the labels (and the legend), each grown by
    :data:`CLEARANCE_PX`, are pairwise disjoint."""
    _, _, labels, _ = rendered
    names = sorted(labels)
    clashes = [
        (a, b)
        for i, a in enumerate(names)
        for b in names[i + 1 :]
        if labels[a].padded(CLEARANCE_PX).overlaps(labels[b])
    ]
    assert clashes == []


def test_no_label_sits_on_a_line_or_an_arrow(rendered):
    """No drawn curve (arrow, arc, leg, reference line, tick, the torso's outline, the
    COM's symbol) passes through a label's box or within :data:`CLEARANCE_PX` of it."""
    _, _, labels, curves = rendered
    hits = [
        (name, curve)
        for name, label in labels.items()
        for box in [label.padded(CLEARANCE_PX)]
        for curve, xy in curves.items()
        if np.any(
            (xy[:, 0] > box.x0) & (xy[:, 0] < box.x1) & (xy[:, 1] > box.y0) & (xy[:, 1] < box.y1)
        )
    ]
    assert hits == []


def test_each_symbol_is_nearest_its_own_arrow(rendered):
    """A reader pairs a symbol with the nearest arrow: the centre of ``label_<gid>`` lies
    nearer the curve of arrow ``gid`` (its arc and head) than any other arrow's."""
    _, _, labels, curves = rendered

    def path(gid):
        return np.concatenate([curves[gid], curves.get(f"{gid}_arc", curves[gid])])

    for gid in ARROWS:
        box = labels[f"label_{gid}"]
        centre = np.array([0.5 * (box.x0 + box.x1), 0.5 * (box.y0 + box.y1)])
        distance = {g: np.min(np.linalg.norm(path(g) - centre, axis=1)) for g in ARROWS}
        assert min(distance, key=distance.get) == gid, (gid, distance)


def test_every_label_lies_inside_the_figure(rendered):
    fig, renderer, labels, _ = rendered
    frame = fig.bbox
    for name, box in labels.items():
        assert frame.x0 <= box.x0 and box.x1 <= frame.x1, name
        assert frame.y0 <= box.y0 and box.y1 <= frame.y1, name
