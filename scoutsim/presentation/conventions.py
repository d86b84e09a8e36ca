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
a test can read the directions drawn; an arc's curve is the line ``<gid>_arc`` ending at
the arrow, and the symbol of arrow ``<gid>`` is the text ``label_<gid>``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

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
    y: float = 0.36
    theta: float = math.radians(20.0)
    phi: tuple[float, float] = (math.radians(24.0), math.radians(28.0))
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


def _arc(centre, radius: float, start: float, stop: float, n: int = 60) -> np.ndarray:
    """Points of a circular arc [m], angles [rad] counter-clockwise from the world's +x."""
    a = np.linspace(start, stop, n)
    return np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)])


def _down_angle(gamma: float) -> float:
    """Direction [rad from +x] of a leg at absolute angle ``gamma`` (from the downward
    vertical, counter-clockwise positive)."""
    return gamma - 0.5 * math.pi


def _polar(centre, radius: float, angle: float) -> np.ndarray:
    """The point at ``radius`` [m] from ``centre`` in the direction ``angle`` [rad from +x]."""
    return np.asarray(centre) + radius * np.array([math.cos(angle), math.sin(angle)])


#: figure size [in] and PNG resolution [dots per inch]
FIGURE_SIZE = (8.0, 5.2)
FIGURE_DPI = 150
#: a reference line of the world (horizontal, vertical) and of the torso (axis, normal)
_WORLD_REF: dict[str, Any] = {"color": "0.45", "lw": 0.9, "ls": (0, (1.5, 2.0))}
_TORSO_REF: dict[str, Any] = {"color": "0.45", "lw": 0.9, "ls": (0, (5.0, 3.0))}
_LABEL_SIZE = 13


def plot_conventions(
    path=None, pose: ConventionsPose | None = None, robot: RobotParameters | None = None
):
    """Draw the planar robot with its coordinates and their positive directions; save it to
    ``path`` (.png, .pdf, .svg) if given. Returns the Matplotlib figure.

    Every symbol is a label beside its arrow: ``x``, ``y`` and ``g`` in the lower and upper
    left corners; the pitch ``theta`` an arc at the COM from the horizontal to the torso
    axis; per leg the leg angle ``phi`` an arc at the hip from the torso's downward normal
    (dashed) to the leg, the hip torque ``tau`` an arc around the hip and the leg length
    ``l`` a dimension arrow beside the leg; ``gamma_f`` an arc from the downward vertical
    (dotted) to the front leg; ``e`` a dimension arrow from the hips' midpoint to the COM
    along the torso axis. A legend names the legs, the hips and the toes."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Polygon, Wedge

    pose = pose if pose is not None else ConventionsPose()
    robot = robot if robot is not None else RobotParameters()
    p = robot_points(pose, robot)
    fig = Figure(figsize=FIGURE_SIZE)
    ax = fig.add_axes((0.01, 0.01, 0.98, 0.92))
    ax.set_aspect("equal")
    ax.axis("off")
    com, axis, normal = p["com"], p["axis"], p["normal"]

    def torso(along: float, up: float) -> np.ndarray:
        """The point ``along`` the torso axis and ``up`` its normal from the COM [m]."""
        return com + along * axis + up * normal

    def draw_arrow(gid, tail, head, color="black", lw=1.3):
        ann = ax.annotate(
            "",
            xy=tuple(head),
            xytext=tuple(tail),
            arrowprops={
                "arrowstyle": "-|>,head_length=0.55,head_width=0.22",
                "color": color,
                "lw": lw,
                "shrinkA": 0,
                "shrinkB": 0,
            },
        )
        ann.set_gid(gid)

    def draw_arc(gid, centre, radius, start, stop, color="black"):
        """An arc from ``start`` to ``stop`` [rad from +x], its arrowhead at ``stop``."""
        pts = _arc(centre, radius, start, stop)
        (arc,) = ax.plot(pts[:-1, 0], pts[:-1, 1], color=color, lw=1.3)
        arc.set_gid(f"{gid}_arc")
        draw_arrow(gid, pts[-3], pts[-1], color=color)

    def label(gid, at, text, color="black", size=_LABEL_SIZE, **align):
        t = ax.text(at[0], at[1], text, color=color, fontsize=size, **align)
        t.set_gid(gid)

    # ground and world frame (lower left), gravity (upper left)
    ax.plot([-0.56, 0.6], [0.0, 0.0], color="0.35", lw=1.0)
    ax.fill_between([-0.56, 0.6], [-0.025, -0.025], [0.0, 0.0], color="0.88", lw=0)
    origin = np.array([-0.52, 0.04])
    draw_arrow("x", origin, origin + [0.13, 0.0])
    draw_arrow("y", origin, origin + [0.0, 0.13])
    label("label_x", origin + [0.14, 0.0], r"$x$", va="center")
    label("label_y", origin + [0.0, 0.14], r"$y$", ha="center", va="bottom")
    g0 = np.array([-0.52, 0.62])
    draw_arrow("gravity", g0, g0 + [0.0, -0.12])
    label("label_gravity", g0 + [0.02, -0.06], r"$g$", va="center")

    # torso: a box along its axis, the axis (dashed), the COM
    half_len, half_h = 0.5 * robot.torso_length, 0.5 * robot.torso_height
    corners = [torso(sa * half_len, sn * half_h) for sa, sn in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    ax.add_patch(Polygon(corners, closed=True, fc="#f0f0f0", ec="0.25", lw=1.3, zorder=1))
    ends = [torso(-half_len - 0.05, 0.0), torso(half_len + 0.05, 0.0)]
    ax.plot([e[0] for e in ends], [e[1] for e in ends], **_TORSO_REF)
    r_com = 0.017
    ax.add_patch(Circle(tuple(com), r_com, fc="white", ec="black", lw=1.2, zorder=6))
    for q in (0.0, 180.0):
        start = math.degrees(pose.theta) + q
        ax.add_patch(Wedge(tuple(com), r_com, start, start + 90.0, fc="black", lw=0, zorder=7))
    label("label_com", com + [0.004, 0.024], "COM", size=10, ha="center", va="bottom")

    # pitch: from the horizontal at the COM to the torso axis
    r_theta = 0.17
    ax.plot([com[0] + r_com, com[0] + r_theta + 0.012], [com[1], com[1]], **_WORLD_REF)
    draw_arc("theta", com, r_theta, 0.0, pose.theta)
    label(
        "label_theta",
        _polar(com, r_theta + 0.012, 0.5 * pose.theta),
        r"$\theta$",
        ha="left",
        va="center",
    )

    # COM offset: a dimension arrow from the hips' midpoint to the COM, below the axis
    mid = p["midpoint"]
    off = -0.035
    for end in (mid, com):
        a0 = (end - com) @ axis
        tick = [torso(a0, off - 0.01), torso(a0, off + 0.01)]
        ax.plot([t[0] for t in tick], [t[1] for t in tick], color="0.2", lw=0.8)
    draw_arrow("com_offset", mid + off * normal, com + off * normal, color="0.2", lw=1.1)
    label(
        "label_com_offset",
        torso(-pose.com_offset - 0.012, off),
        r"$e$",
        color="0.2",
        ha="right",
        va="center",
    )

    for leg, name in enumerate(LEG_NAMES):
        color = LEG_COLORS[leg]
        sub = name[0]
        hip, toe, gamma = p[f"hip_{name}"], p[f"toe_{name}"], p[f"gamma_{name}"]
        (line,) = ax.plot([hip[0], toe[0]], [hip[1], toe[1]], color=color, lw=3.2, zorder=3)
        line.set_gid(f"leg_{name}")
        ax.plot(*hip, "o", ms=7, color=color, zorder=5)
        ax.plot(*toe, "o", ms=7, mfc="white", mec=color, mew=2, zorder=5)
        # the torso's downward normal at the hip (dashed), and phi from it to the leg
        down = _down_angle(pose.theta)
        leg_dir = _down_angle(gamma)
        ref = _polar(hip, 0.2, down)
        ax.plot([hip[0], ref[0]], [hip[1], ref[1]], **_TORSO_REF)
        r_phi = 0.14
        draw_arc(f"phi_{name}", hip, r_phi, down, leg_dir, color=color)
        label(
            f"label_phi_{name}",
            _polar(hip, r_phi + 0.05, 0.5 * (down + leg_dir)),
            rf"$\phi_{sub}$",
            color=color,
            ha="center",
            va="center",
        )
        # leg length: a dimension arrow ahead of the leg, hip to toe
        u = (toe - hip) / np.linalg.norm(toe - hip)
        side = 0.065 * np.array([-u[1], u[0]])  # the leg's forward side
        for end in (hip, toe):
            tick = [end + 0.75 * side, end + 1.25 * side]
            ax.plot([t[0] for t in tick], [t[1] for t in tick], color=color, lw=0.8)
        draw_arrow(f"l_{name}", hip + side, toe + side, color=color, lw=1.1)
        label(
            f"label_l_{name}",
            hip + 1.4 * side + 0.55 * (toe - hip),
            rf"$l_{sub}$",
            color=color,
            ha="left",
            va="center",
        )
        # hip torque: counter-clockwise around the hip, over its top
        r_tau = 0.038
        draw_arc(
            f"tau_{name}",
            hip,
            r_tau,
            pose.theta - math.radians(30.0),
            pose.theta + math.radians(140.0),
            color=color,
        )
        label(
            f"label_tau_{name}",
            hip + [0.0, 0.08],
            rf"$\tau_{sub}$",
            color=color,
            ha="center",
            va="bottom",
        )

    # gamma of the front leg: from the world's downward vertical (dotted)
    hip, gamma = p["hip_front"], p["gamma_front"]
    r_gamma = 0.25
    ref = hip + [0.0, -(r_gamma + 0.025)]
    ax.plot([hip[0], ref[0]], [hip[1], ref[1]], **_WORLD_REF)
    draw_arc("gamma_front", hip, r_gamma, -0.5 * math.pi, _down_angle(gamma), color="0.2")
    label(
        "label_gamma_front",
        hip + [0.0, -(r_gamma + 0.04)],
        r"$\gamma_f = \theta + \phi_f$",
        color="0.2",
        ha="center",
        va="top",
    )

    handles = [
        Line2D([], [], color=LEG_COLORS[0], lw=3.2, label=r"back leg ($b$)"),
        Line2D([], [], color=LEG_COLORS[1], lw=3.2, label=r"front leg ($f$)"),
        Line2D([], [], ls="", marker="o", ms=7, color="0.3", label="hip"),
        Line2D([], [], ls="", marker="o", ms=7, mfc="white", mec="0.3", mew=2, label="toe"),
    ]
    ax.legend(handles=handles, loc="upper right", fontsize=10, frameon=False)
    ax.set_xlim(-0.56, 0.6)
    ax.set_ylim(-0.03, 0.64)
    fig.suptitle("Coordinates and their positive directions", fontsize=12, y=0.975)
    save_figure(fig, path, dpi=FIGURE_DPI)
    return fig
