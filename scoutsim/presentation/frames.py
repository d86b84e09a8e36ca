"""One picture of the robot as an RGB array: the torso, both virtual legs, their toes and the
ground, rasterised with plain NumPy (no figure, no font; a fraction of a millisecond at
480 x 240 pixels, so a learning environment can render every step).

    from scoutsim.presentation.frames import RobotPose, draw_pose
    pose = RobotPose.of(robot, x=0.4, height=0.32, pitch=0.05,
                        toes=((0.2, 0.0), (0.62, 0.03)), contact=(True, False))
    frame = draw_pose(pose)                 # (240, 480, 3) uint8

A side view, x forward to the right, y up, one metre the same number of pixels both ways;
the view follows the torso's COM horizontally (:data:`VIEW_HALF_WIDTH_M` either side of it)
and keeps the ground at a fixed row :data:`GROUND_MARGIN_M` above the bottom edge. As in
:mod:`scoutsim.presentation.animation`: the torso is a grey box (``torso_length`` x
``torso_height``, rotated by the pitch), each virtual leg a line from its hip
(``RobotParameters.hip_offset`` along the torso axis) to its toe, coloured by the
controller's leg state (:data:`~scoutsim.presentation.style.LEG_STATE_LINE_COLORS`: flight
blue, stance-retraction orange, stance-brake green; dark grey without a controller), and the
ground line carries tick marks every :data:`TICK_SPACING_M` so the forward motion shows.
A toe in contact with the ground is a filled disc, a toe in flight a ring.

The toe positions are given, not computed here: they come from the model's own evaluation
(``SimulationResult.toe_position``, ``HybridEngine.toe_position``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..names import LegState
from .style import LEG_STATE_LINE_COLORS

__all__ = [
    "RobotPose",
    "draw_pose",
    "VIEW_HALF_WIDTH_M",
    "GROUND_MARGIN_M",
    "TICK_SPACING_M",
    "FRAME_WIDTH",
    "FRAME_HEIGHT",
]

#: the view's half width about the torso COM [m] (that of the animation)
VIEW_HALF_WIDTH_M = 0.75
#: the height of the view's bottom edge below the ground [m]
GROUND_MARGIN_M = 0.06
#: the spacing of the ground's tick marks [m]
TICK_SPACING_M = 0.25
#: the default frame size [pixels]: 320 pixels per metre, 0.69 m above the ground
FRAME_WIDTH, FRAME_HEIGHT = 480, 240

_TICK_LENGTH_M = 0.03
_LEG_WIDTH_M = 0.012
_TOE_RADIUS_M = 0.014
_RING_WIDTH_M = 0.005
_OUTLINE_WIDTH_M = 0.004


def _rgb(color) -> np.ndarray:
    from matplotlib.colors import to_rgb

    return np.round(255.0 * np.array(to_rgb(color))).astype(np.uint8)


#: grey levels (one number for the three channels: filled fastest)
_WHITE_LEVEL, _BELOW_GROUND_LEVEL, _GROUND_LEVEL = 255, 236, 77
_TORSO = np.array([191, 191, 191], np.uint8)
_INK = np.array([0, 0, 0], np.uint8)
_NO_CONTROLLER = np.array([90, 90, 90], np.uint8)
_LEG_STATE_RGB = None  # the leg-state colours as RGB, made on first use


def _leg_color(state) -> np.ndarray:
    global _LEG_STATE_RGB
    if state is None:
        return _NO_CONTROLLER
    if _LEG_STATE_RGB is None:
        _LEG_STATE_RGB = tuple(_rgb(c) for c in LEG_STATE_LINE_COLORS)
    return _LEG_STATE_RGB[int(LegState(int(state)))]


@dataclass(frozen=True)
class RobotPose:
    """What one frame shows (SI).

    x, height, pitch : the torso COM's forward position and height [m], its pitch [rad]
        (nose up positive).
    hip_offsets : (back, front) positions of the hips along the torso axis from the COM [m]
        (``RobotParameters.hip_offset``).
    torso_length, torso_height : the torso box [m].
    toes : ((x, y) back, (x, y) front) the toes in the world [m].
    contact : (back, front) True for a toe on the ground.
    leg_states : (back, front) the controller's leg states (codes of
        :class:`~scoutsim.names.LegState`), or None without a controller.
    """

    x: float
    height: float
    pitch: float
    hip_offsets: tuple
    torso_length: float
    torso_height: float
    toes: tuple
    contact: tuple
    leg_states: tuple | None = None

    @classmethod
    def of(
        cls, robot, x: float, height: float, pitch: float, toes, contact, leg_states=None
    ) -> RobotPose:
        """The pose of ``robot`` (:class:`~scoutsim.parameters.RobotParameters`: its hips and
        torso box) with the torso at (``x``, ``height``) [m], pitched by ``pitch`` [rad]."""
        return cls(
            float(x),
            float(height),
            float(pitch),
            (robot.hip_offset(0), robot.hip_offset(1)),
            float(robot.torso_length),
            float(robot.torso_height),
            tuple((float(tx), float(ty)) for tx, ty in toes),
            tuple(bool(c) for c in contact),
            None if leg_states is None else tuple(int(s) for s in leg_states),
        )


class _Raster:
    """An RGB image with the view's world-to-pixel map and filled shapes (pixel centres
    inside a shape take its colour)."""

    def __init__(self, width: int, height: int, x_centre: float):
        self.img = np.full((height, width, 3), _WHITE_LEVEL, np.uint8)
        self.scale = width / (2.0 * VIEW_HALF_WIDTH_M)  # [pixel/m]
        self.x0 = x_centre - VIEW_HALF_WIDTH_M
        self.y_top = -GROUND_MARGIN_M + height / self.scale

    def px(self, x, y) -> tuple[float, float]:
        """Pixel coordinates (column, row) of the world point (x, y) [m]."""
        return (x - self.x0) * self.scale, (self.y_top - y) * self.scale

    def _box(self, u0, u1, v0, v1):
        """Pixel-centre grids (rows, columns) of the image within [u0, u1] x [v0, v1], or
        None if that is off the image."""
        h, w = self.img.shape[:2]
        j0, j1 = max(int(math.floor(u0)), 0), min(int(math.ceil(u1)) + 1, w)
        i0, i1 = max(int(math.floor(v0)), 0), min(int(math.ceil(v1)) + 1, h)
        if j0 >= j1 or i0 >= i1:
            return None
        return (
            slice(i0, i1),
            slice(j0, j1),
            np.arange(i0, i1)[:, None] + 0.5,
            np.arange(j0, j1)[None, :] + 0.5,
        )

    def row(self, y: float) -> int:
        """The image row whose pixel centres are nearest world height ``y`` [m]."""
        return int(math.floor(self.px(0.0, y)[1]))

    def column(self, x: float) -> int:
        """The image column whose pixel centres are nearest world position ``x`` [m]."""
        return int(math.floor(self.px(x, 0.0)[0]))

    def segment(self, a, b, width_m: float, color):
        """A line from world point ``a`` to ``b`` [m], ``width_m`` wide, round ends."""
        (ua, va), (ub, vb) = self.px(*a), self.px(*b)
        r = max(0.5 * width_m * self.scale, 0.75)
        box = self._box(min(ua, ub) - r, max(ua, ub) + r, min(va, vb) - r, max(va, vb) + r)
        if box is None:
            return
        rows, cols, v, u = box
        du, dv = ub - ua, vb - va
        n2 = du * du + dv * dv
        t = np.clip(((u - ua) * du + (v - va) * dv) / n2, 0.0, 1.0) if n2 > 0 else 0.0
        d2 = (u - ua - t * du) ** 2 + (v - va - t * dv) ** 2
        self.img[rows, cols][d2 <= r * r] = color

    def disc(self, c, radius_m: float, color, ring_m: float | None = None):
        """A filled disc at world point ``c`` [m], or a ring ``ring_m`` wide."""
        uc, vc = self.px(*c)
        r = radius_m * self.scale
        box = self._box(uc - r, uc + r, vc - r, vc + r)
        if box is None:
            return
        rows, cols, v, u = box
        d2 = (u - uc) ** 2 + (v - vc) ** 2
        inside = d2 <= r * r
        if ring_m is not None:
            inner = max(r - max(ring_m * self.scale, 1.0), 0.0)
            inside &= d2 >= inner * inner
        self.img[rows, cols][inside] = color

    def convex(self, corners, color):
        """Fill the convex polygon of world points ``corners`` [m] (either orientation)."""
        p = np.array([self.px(x, y) for x, y in corners])
        box = self._box(p[:, 0].min(), p[:, 0].max(), p[:, 1].min(), p[:, 1].max())
        if box is None:
            return
        rows, cols, v, u = box
        q = np.roll(p, -1, axis=0)
        cross = [
            (q[k, 0] - p[k, 0]) * (v - p[k, 1]) - (q[k, 1] - p[k, 1]) * (u - p[k, 0])
            for k in range(len(p))
        ]
        pos = np.logical_and.reduce([c >= 0 for c in cross])
        neg = np.logical_and.reduce([c <= 0 for c in cross])
        self.img[rows, cols][pos | neg] = color


def draw_pose(pose: RobotPose, width: int = FRAME_WIDTH, height: int = FRAME_HEIGHT) -> np.ndarray:
    """The frame of ``pose`` (module docstring): a new (``height``, ``width``, 3) uint8 RGB
    array."""
    if not (isinstance(width, int) and isinstance(height, int) and width >= 16 and height >= 16):
        raise ValueError(
            f"frame size {width} x {height} is not allowed: width and height "
            "must be whole numbers of pixels >= 16"
        )
    drawn = all(math.isfinite(v) for v in (pose.x, pose.height, pose.pitch))
    x_view = pose.x if drawn else 0.0  # (a state that is not finite: the ground only)
    ras = _Raster(width, height, x_view)
    # the ground (rows and columns of the image: filled directly), its line and ticks
    img = ras.img
    ground = ras.row(0.0)
    img[max(ground, 0) :] = _BELOW_GROUND_LEVEL
    img[max(ground - 1, 0) : max(ground + 1, 0)] = _GROUND_LEVEL
    tick_end = max(ras.row(-_TICK_LENGTH_M), 0)
    x0, x1 = x_view - VIEW_HALF_WIDTH_M, x_view + VIEW_HALF_WIDTH_M
    for k in range(math.floor(x0 / TICK_SPACING_M), math.ceil(x1 / TICK_SPACING_M) + 1):
        j = ras.column(k * TICK_SPACING_M)
        if 0 <= j < width:
            img[max(ground, 0) : tick_end, j] = _GROUND_LEVEL
    if not drawn:
        return ras.img
    # the torso box
    c, s = math.cos(pose.pitch), math.sin(pose.pitch)
    u, n = np.array([c, s]), np.array([-s, c])  # the torso axis and its upward normal
    com = np.array([pose.x, pose.height])
    hl, hh = 0.5 * pose.torso_length, 0.5 * pose.torso_height
    corners = [
        com + hl * u + hh * n,
        com - hl * u + hh * n,
        com - hl * u - hh * n,
        com + hl * u - hh * n,
    ]
    ras.convex(corners, _TORSO)
    for k in range(4):
        ras.segment(corners[k], corners[(k + 1) % 4], _OUTLINE_WIDTH_M, _INK)
    # the legs (over the torso) and their toes
    for leg in (0, 1):
        hip = com + pose.hip_offsets[leg] * u
        toe = pose.toes[leg]
        if not all(math.isfinite(v) for v in toe):
            continue
        state = None if pose.leg_states is None else pose.leg_states[leg]
        ras.segment(hip, toe, _LEG_WIDTH_M, _leg_color(state))
        ras.disc(hip, 0.5 * _TOE_RADIUS_M, _INK)
        ras.disc(toe, _TOE_RADIUS_M, _INK, None if pose.contact[leg] else _RING_WIDTH_M)
    return ras.img
