"""The planar model's coordinates and their signs as a figure (docs/specification.md
section 1; paper eq. 1): the torso with its centre of mass (COM), the two virtual legs with
their hips and toes, and every coordinate drawn with an arrow in its positive direction.

* ``x`` forward, ``y`` up (world frame), gravity down;
* ``theta``: torso pitch, counter-clockwise positive (nose up);
* ``phi_back``, ``phi_front``: leg angles relative to the torso, from the torso's downward
  normal, positive with the toe ahead of the hip;
* ``gamma = theta + phi``: the leg's angle from the world's downward vertical;
* ``l``: leg length, hip to toe;
* ``tau``: hip torque, positive rotating the leg forward (counter-clockwise) relative to the
  torso, the torso feeling the reaction;
* the rates (``dx``, ``dy``, ``dtheta``, ``dphi``, ``dl``) are positive in the direction of
  their coordinate;
* ``e`` (``com_offset``): the COM's distance ahead of the hips' midpoint; the hips lie on the
  torso axis at ``-L - e`` (back) and ``L - e`` (front) from the COM, ``L = hip_spacing / 2``.

:func:`robot_points` computes the drawn points from these definitions;
:func:`plot_conventions` draws them. Every arrow of the figure is an annotation whose
``gid`` names what it shows (:data:`ARROWS`), its head ``xy`` and its tail ``xyann``, so
a test can read the directions drawn.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..names import LEG_NAMES
from ..parameters import RobotParameters
from .style import LEG_COLORS, save_figure

__all__ = ["ConventionsPose", "robot_points", "plot_conventions", "ARROWS"]

#: the ``gid`` of every arrow the figure draws, in drawing order
ARROWS = (
    "x",
    "y",
    "gravity",
    "theta",
    "com_offset",
    "phi_back",
    "phi_front",
    "gamma_front",
    "l_back",
    "l_front",
    "tau_back",
    "tau_front",
)


@dataclass(frozen=True)
class ConventionsPose:
    """The pose drawn (SI: m, rad). The default tilts the torso nose up and swings both
    legs forward, so that every drawn angle is positive and its arrow shows its positive
    direction; ``com_offset`` is larger than Scout II's (0) so that it can be seen.

    Attributes
    ----------
    x, y : float
        Torso COM [m].
    theta : float
        Torso pitch [rad].
    phi : (back, front)
        Leg angles relative to the torso [rad].
    l : (back, front)
        Leg lengths [m].
    com_offset : float
        The COM's distance ahead of the hips' midpoint [m].
    """

    x: float = 0.0
    y: float = 0.33
    theta: float = math.radians(10.0)
    phi: tuple[float, float] = (math.radians(20.0), math.radians(28.0))
    l: tuple[float, float] = (0.29, 0.323)
    com_offset: float = 0.04


def robot_points(pose: ConventionsPose, robot: RobotParameters | None = None) -> dict:
    """The drawn points [m] of ``pose`` (docs/specification.md section 1): ``com``,
    ``axis`` (unit vector along the torso, forward), ``normal`` (the torso's upward
    normal), ``midpoint`` (of the hips), and per leg ``hip_<leg>``, ``toe_<leg>``,
    ``gamma_<leg>`` [rad]. ``robot`` gives the hip spacing (default Scout II)."""
    robot = robot if robot is not None else RobotParameters()
    half = 0.5 * robot.hip_spacing
    com = np.array([pose.x, pose.y])
    axis = np.array([math.cos(pose.theta), math.sin(pose.theta)])
    normal = np.array([-math.sin(pose.theta), math.cos(pose.theta)])
    out: dict[str, np.ndarray | float] = {
        "com": com,
        "axis": axis,
        "normal": normal,
        "midpoint": com - pose.com_offset * axis,
    }
    for leg, name in enumerate(LEG_NAMES):
        along = (-half if leg == 0 else half) - pose.com_offset
        hip = com + along * axis
        gamma = pose.theta + pose.phi[leg]
        out[f"hip_{name}"] = hip
        out[f"gamma_{name}"] = gamma
        out[f"toe_{name}"] = hip + pose.l[leg] * np.array([math.sin(gamma), -math.cos(gamma)])
    return out


def _arc(centre, radius: float, start: float, stop: float, n: int = 40) -> np.ndarray:
    """Points of a circular arc [m], angles [rad] counter-clockwise from the world's +x."""
    a = np.linspace(start, stop, n)
    return np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)])


def _down_angle(gamma: float) -> float:
    """Direction [rad from +x] of a leg at absolute angle ``gamma`` (from the downward
    vertical, counter-clockwise positive)."""
    return gamma - 0.5 * math.pi


def plot_conventions(
    path=None, pose: ConventionsPose | None = None, robot: RobotParameters | None = None
):
    """Draw the planar robot with its coordinates and their positive directions; save it to
    ``path`` (.png, .pdf, .svg) if given. Returns the Matplotlib figure."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon

    pose = pose if pose is not None else ConventionsPose()
    robot = robot if robot is not None else RobotParameters()
    p = robot_points(pose, robot)
    fig = Figure(figsize=(8.0, 5.6))
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    ax.axis("off")
    com, axis, normal = p["com"], p["axis"], p["normal"]
    arrow = {"arrowstyle": "-|>", "color": "black", "lw": 1.2, "shrinkA": 0, "shrinkB": 0}

    def draw_arrow(gid, tail, head, label=None, label_at=None, color="black", **text):
        ann = ax.annotate(
            "",
            xy=tuple(head),
            xytext=tuple(tail),
            arrowprops={**arrow, "color": color},
        )
        ann.set_gid(gid)
        if label is not None:
            where = label_at if label_at is not None else head
            ax.text(where[0], where[1], label, color=color, fontsize=12, **text)

    def draw_arc(gid, centre, radius, start, stop, label, label_at, color="black"):
        pts = _arc(centre, radius, start, stop)
        ax.plot(pts[:-1, 0], pts[:-1, 1], color=color, lw=1.2)
        draw_arrow(gid, pts[-3], pts[-1], label, label_at, color=color)

    # ground and world frame
    ax.plot([-0.62, 0.62], [0.0, 0.0], color="0.4", lw=1.0)
    ax.fill_between([-0.62, 0.62], [-0.03, -0.03], [0.0, 0.0], color="0.88", lw=0)
    origin = np.array([-0.58, 0.04])
    draw_arrow("x", origin, origin + [0.14, 0.0], r"$x$", origin + [0.15, -0.01])
    draw_arrow("y", origin, origin + [0.0, 0.14], r"$y$", origin + [-0.03, 0.15])
    g0 = np.array([-0.50, 0.52])
    draw_arrow("gravity", g0, g0 + [0.0, -0.1], r"$g$", g0 + [0.015, -0.08])

    # torso: a box along its axis, the axis, the COM, the hips' midpoint
    half_len, half_h = 0.5 * robot.torso_length, 0.5 * robot.torso_height
    corners = [
        com + sa * half_len * axis + sn * half_h * normal
        for sa, sn in ((-1, -1), (1, -1), (1, 1), (-1, 1))
    ]
    ax.add_patch(Polygon(corners, closed=True, fc="#eeeeee", ec="0.3", lw=1.2))
    ends = [com - (half_len + 0.06) * axis, com + (half_len + 0.06) * axis]
    ax.plot([e[0] for e in ends], [e[1] for e in ends], color="0.5", lw=0.8, ls="--")
    ax.plot([com[0], com[0] + 0.3], [com[1], com[1]], color="0.5", lw=0.8, ls=":")
    ax.plot(*com, "o", ms=9, mfc="white", mec="black", zorder=5)
    ax.plot(*com, "o", ms=3, color="black", zorder=6)
    ax.text(com[0] - 0.02, com[1] + 0.075, "COM", fontsize=10, ha="center")
    draw_arc(
        "theta",
        com,
        0.17,
        0.0,
        pose.theta,
        r"$\theta,\ \dot\theta$",
        com + [0.185, -0.045],
    )
    mid = p["midpoint"]
    ax.plot(*mid, "|", ms=10, color="black")
    draw_arrow("com_offset", mid - 0.028 * normal, com - 0.028 * normal, color="0.25")
    e_label = mid - 0.075 * normal - 0.01 * axis
    ax.text(e_label[0], e_label[1], r"$e$", fontsize=11, color="0.25")

    for leg, name in enumerate(LEG_NAMES):
        color = LEG_COLORS[leg]
        hip, toe, gamma = p[f"hip_{name}"], p[f"toe_{name}"], p[f"gamma_{name}"]
        (line,) = ax.plot([hip[0], toe[0]], [hip[1], toe[1]], color=color, lw=3.0)
        line.set_gid(f"leg_{name}")
        ax.plot(*hip, "o", ms=7, color=color, zorder=5)
        ax.plot(*toe, "o", ms=6, mfc="white", mec=color, mew=2, zorder=5)
        inward = 0.03 if leg == 0 else -0.1
        hip_label = hip + inward * axis + 0.025 * normal
        ax.text(hip_label[0], hip_label[1], "hip", fontsize=9, color=color)
        ax.text(toe[0] + 0.015, toe[1] - 0.005, "toe", fontsize=9, color=color)
        sub = name[0]
        # the torso's downward normal at the hip, and phi from it to the leg
        down = _down_angle(pose.theta)
        ref = hip + 0.2 * np.array([math.cos(down), math.sin(down)])
        ax.plot([hip[0], ref[0]], [hip[1], ref[1]], color="0.5", lw=0.8, ls="--")
        radius = 0.13
        draw_arc(
            f"phi_{name}",
            hip,
            radius,
            down,
            _down_angle(gamma),
            rf"$\phi_{sub},\ \dot\phi_{sub}$",
            hip
            + (radius + 0.02)
            * np.array([math.cos(down + 0.5 * pose.phi[leg]), math.sin(down + 0.5 * pose.phi[leg])])
            + [0.0, -0.03],
            color=color,
        )
        # leg length: a dimension arrow beside the leg, hip to toe
        u = (toe - hip) / np.linalg.norm(toe - hip)
        side = np.array([u[1], -u[0]]) * (0.035 if leg == 0 else -0.035)
        draw_arrow(
            f"l_{name}",
            hip + side + 0.05 * u,
            toe + side,
            rf"$l_{sub}$",
            hip + 2.2 * side + 0.55 * (toe - hip),
            color=color,
        )
        # hip torque: counter-clockwise around the hip
        start = pose.theta + 0.9 * math.pi
        draw_arc(
            f"tau_{name}",
            hip,
            0.05,
            start,
            start + 1.4 * math.pi,
            rf"$\tau_{sub}$",
            hip + [-0.085, 0.03] if leg == 0 else hip + [0.055, 0.03],
            color=color,
        )
    # gamma of the front leg: from the world's downward vertical
    hip, gamma = p["hip_front"], p["gamma_front"]
    ref = hip + [0.0, -0.26]
    ax.plot([hip[0], ref[0]], [hip[1], ref[1]], color="0.5", lw=0.8, ls=":")
    draw_arc(
        "gamma_front",
        hip,
        0.22,
        -0.5 * math.pi,
        _down_angle(gamma),
        r"$\gamma_f = \theta + \phi_f$",
        hip + [-0.05, -0.3],
        color="0.25",
    )
    ax.set_xlim(-0.65, 0.65)
    ax.set_ylim(-0.05, 0.62)
    ax.set_title(
        "Coordinates and positive directions (docs/specification.md section 1); "
        f"e drawn as {pose.com_offset * 100:g} cm",
        fontsize=10,
    )
    fig.tight_layout()
    save_figure(fig, path)
    return fig
