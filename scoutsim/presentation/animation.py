"""Stick-figure animation of a bounding run.

    from scoutsim.presentation.animation import animate, save_animation
    save_animation(result, "run.gif", fps=25, t0=3.0, t1=4.0)     # GIF via Pillow
    save_animation(result, "run.mp4", fps=30)                      # needs ffmpeg
    anim = animate(result, fps=25)      # matplotlib.animation.FuncAnimation (Jupyter: HTML)

Each frame shows the torso as a box (length ``torso_length``, height ``torso_height``,
rotated by the pitch), the two virtual legs from hip to toe, the ground reaction force on
each toe in contact as an arrow (:data:`FORCE_SCALE_M_PER_N`), the ground line with tick
marks every 0.25 m (so the forward motion shows while the view follows the torso) and the
time stamp. Two different things are drawn apart, with a legend for each:

* what the **controller** thinks, the leg's colour: its leg state (paper Sec. II, Table I;
  :data:`LEG_STATE_COLORS`: flight blue, stance-retraction orange, stance-brake green; the
  same colours as the dots of :func:`scoutsim.presentation.torque_speed.plot_torque_speed`);
* what the **simulated toe** does, its marker (:data:`TOE_MARKERS`): on the ground, pinned
  (filled circle), on the ground sliding (filled diamond), in the air (open circle), from
  the plant's contact mode.

A controller that detects touchdown late shows a leg standing on the ground in its flight
colour, with a filled toe; the status lines right of the view spell out both for each leg,
and the title says what the run did (steady bounding, or what instead).

Frames are taken at ``t0 + k / fps`` for ``k = 0 .. floor((t1 - t0) * fps)``, so a window
gives ``floor((t1 - t0) * fps) + 1`` frames (both ends included when ``(t1 - t0) * fps`` is
an integer) and plays back in real time. Each frame shows the sample at or just before its
time (zero-order hold of the 1 kHz record).

The figure is built without ``matplotlib.pyplot`` (headless; no GUI). GIFs are written
with :class:`matplotlib.animation.PillowWriter` (Pillow ships with matplotlib); MP4 needs
the ``ffmpeg`` program on the PATH and raises :class:`RuntimeError` saying so otherwise.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

from ..names import ContactMode, Leg, LegState
from .run_parts import behaviour_text, run_model_label
from .style import LEG_STATE_LINE_COLORS, LEG_STATE_NAMES

__all__ = [
    "animate",
    "RunAnimation",
    "save_animation",
    "frame_times",
    "LEG_STATE_COLORS",
    "TOE_MARKERS",
    "toe_contact",
    "FORCE_SCALE_M_PER_N",
    "ANIMATION_SUFFIXES",
]

#: Leg colour per controller leg state (0 flight, 1 stance-retraction, 2 stance-brake).
LEG_STATE_COLORS = LEG_STATE_LINE_COLORS
_STATE_NAMES = LEG_STATE_NAMES
#: Toe marker per simulated contact: (marker, filled, legend label), by the names of
#: :func:`toe_contact`.
TOE_MARKERS = {
    "ground": ("o", True, "toe on the ground"),
    "sliding": ("D", True, "toe on the ground, sliding"),
    "air": ("o", False, "toe in the air"),
}
#: Length of a ground-force arrow per newton [m/N] (the robot's weight, about 203 N, is
#: drawn 0.2 m long).
FORCE_SCALE_M_PER_N = 1.0e-3
ANIMATION_SUFFIXES = (".gif", ".mp4")
_VIEW_HALF_WIDTH_M = 0.75
_TICK_SPACING_M = 0.25


class RunAnimation(FuncAnimation):
    """The :class:`~matplotlib.animation.FuncAnimation` of a run (:func:`animate`), with the
    frames' times and the parts it draws."""

    frame_times: np.ndarray  #: the frames' times [s]
    artists: dict  #: the drawn parts by name (:func:`animate`)


def frame_times(
    result, fps: float = 25.0, t0: float | None = None, t1: float | None = None
) -> np.ndarray:
    """Times [s] of the frames: ``t0 + k / fps``, ``k = 0 .. floor((t1 - t0) * fps)``.

    ``t0``/``t1`` default to the start and end of the run; they must lie within it and
    t1 > t0. ValueError otherwise."""
    t = np.asarray(result.t, dtype=float)
    if t.size < 1:
        raise ValueError("the result holds no samples")
    if not (isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps = {fps!r} is not allowed: must be a finite number > 0")
    a = float(t[0]) if t0 is None else float(t0)
    b = float(t[-1]) if t1 is None else float(t1)
    if not (math.isfinite(a) and math.isfinite(b)):
        raise ValueError(f"t0 = {t0!r}, t1 = {t1!r} are not allowed: must be finite")
    eps = 1e-9
    if a < t[0] - eps or b > t[-1] + eps:
        raise ValueError(
            f"t0 = {a:g} s, t1 = {b:g} s are not allowed: the run covers {t[0]:g}-{t[-1]:g} s"
        )
    if not b > a:
        raise ValueError(f"t0 = {a:g} s, t1 = {b:g} s are not allowed: need t1 > t0")
    n = int(math.floor((b - a) * fps + 1e-9)) + 1
    return a + np.arange(n) / float(fps)


def toe_contact(result, leg) -> np.ndarray:
    """Per sample, what the simulated toe of ``leg`` does: "ground" (pinned: the plant's
    contact mode stick or strut), "sliding" (slide) or "air" (flight); the keys of
    :data:`TOE_MARKERS`."""
    mode = np.asarray(result.contact_mode(leg))
    out = np.full(mode.shape, "ground", dtype=object)
    out[mode == ContactMode.SLIDE] = "sliding"
    out[mode == ContactMode.FLIGHT] = "air"
    return out


def _geometry(result) -> tuple[tuple[float, float], float, float]:
    """The hips' positions along the torso axis from the COM (back, front) [m], the torso's
    length and height [m], of the run's robot (Scout II if the run does not say)."""
    from ..parameters import RobotParameters

    robot = (result.provenance or {}).get("robot") or {}
    robot = RobotParameters(**robot) if robot else RobotParameters()
    return (
        (robot.hip_offset(0), robot.hip_offset(1)),
        float(robot.torso_length),
        float(robot.torso_height),
    )


def animate(
    result,
    fps: float = 25.0,
    t0: float | None = None,
    t1: float | None = None,
    figsize=(8.0, 4.0),
    dpi: int = 80,
) -> RunAnimation:
    """A :class:`~matplotlib.animation.FuncAnimation` of ``result`` (module docstring).

    Parameters
    ----------
    result : SimulationResult
    fps : frames per second of simulated time (playback in real time)
    t0, t1 : time window [s] (default: the whole run)
    figsize, dpi : size of the frames (default 640 x 320 pixels)

    The animation's ``frame_times`` are the frames' times [s], its ``artists`` the drawn
    parts by name ("torso", "legs" and "toes" (back, front), "forces", the per-leg
    "status" lines, the time "stamp").
    """
    times = frame_times(result, fps, t0, t1)
    t = np.asarray(result.t, dtype=float)
    idx = np.clip(np.searchsorted(t, times + 1e-9, side="right") - 1, 0, t.size - 1)
    x_com, y_com, pitch = (
        np.asarray(v, dtype=float) for v in (result.x, result.height, result.pitch)
    )
    phis = [np.asarray(result.leg_angle(leg), dtype=float) for leg in Leg]
    lengths = [np.asarray(result.leg_length(leg), dtype=float) for leg in Leg]
    toe_xy = [
        np.column_stack([np.asarray(v, dtype=float) for v in result.toe_position(leg)])
        for leg in Leg
    ]
    ground = [
        np.column_stack([np.asarray(v, dtype=float) for v in result.ground_force(leg)])
        for leg in Leg
    ]
    has_ctrl = (result.provenance or {}).get("controller") is not None
    states = [
        np.asarray(result.leg_state(leg)) if has_ctrl else np.full(t.size, LegState.FLIGHT, int)
        for leg in Leg
    ]
    contact = [toe_contact(result, leg) for leg in Leg]
    hips, length, height = _geometry(result)

    fig = Figure(figsize=figsize, dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.08, 0.13, 0.62, 0.74))
    ax.set_aspect("equal")
    ax.set_xlabel("forward position x [m]")
    ax.set_ylabel("height y [m]")
    ytop = max(0.65, float(np.max(y_com)) + 0.25)
    ax.set_ylim(-0.08, ytop)
    (floor,) = ax.plot([], [], color="0.3", lw=1.5)
    (ticks,) = ax.plot([], [], color="0.3", lw=1.0)
    torso = Polygon(
        np.zeros((4, 2)), closed=True, facecolor="0.75", edgecolor="k", lw=1.2, zorder=3
    )
    ax.add_patch(torso)
    legs = [ax.plot([], [], lw=3.0, solid_capstyle="round", zorder=4)[0] for _ in range(2)]
    toes = [
        ax.plot([], [], marker="o", ms=6, color="k", mec="k", mew=1.2, zorder=5)[0]
        for _ in range(2)
    ]
    forces = [
        ax.annotate(
            "",
            xy=(0, 0),
            xytext=(0, 0),
            zorder=6,
            arrowprops=dict(arrowstyle="-|>", color="crimson", lw=1.5),
        )
        for _ in range(2)
    ]
    stamp = ax.text(
        0.02, 0.95, "", transform=ax.transAxes, va="top", fontsize=10, family="monospace"
    )
    status = fig.text(0.715, 0.05, "", va="bottom", ha="left", fontsize=7, family="monospace")
    _legends(fig, has_ctrl)
    import textwrap

    fig.suptitle(
        "\n".join(
            textwrap.wrap(f"Scout II, {run_model_label(result)}: {behaviour_text(result)}", 100)
        ),
        fontsize=8,
        y=0.99,
        va="top",
    )

    def draw(i):
        k = int(idx[i])
        x, y, th = x_com[k], y_com[k], pitch[k]
        c, s = math.cos(th), math.sin(th)
        u, n = np.array([c, s]), np.array([-s, c])  # torso axis, its upward normal
        com = np.array([x, y])
        hl, hh = 0.5 * length, 0.5 * height
        torso.set_xy(
            np.array(
                [
                    com + hl * u + hh * n,
                    com - hl * u + hh * n,
                    com - hl * u - hh * n,
                    com + hl * u - hh * n,
                ]
            )
        )
        x0, x1 = x - _VIEW_HALF_WIDTH_M, x + _VIEW_HALF_WIDTH_M
        ax.set_xlim(x0, x1)
        floor.set_data([x0, x1], [0.0, 0.0])
        tk = np.arange(math.floor(x0 / _TICK_SPACING_M), math.ceil(x1 / _TICK_SPACING_M) + 1)
        tx = np.repeat(tk * _TICK_SPACING_M, 3)
        ty = np.tile([0.0, -0.03, np.nan], tk.size)
        ticks.set_data(tx, ty)
        lines = [f"{'':<6s}{'toe':<10s}" + ("controller" if has_ctrl else "")]
        for leg in Leg:
            hip = com + hips[leg] * u
            toe = toe_xy[leg][k].copy()
            if not np.all(np.isfinite(toe)):  # fall back to the leg geometry
                phi = phis[leg][k]
                ll = lengths[leg][k]
                toe = hip + ll * np.array([math.sin(th + phi), -math.cos(th + phi)])
            state = LegState(int(states[leg][k]))
            legs[leg].set_data([hip[0], toe[0]], [hip[1], toe[1]])
            legs[leg].set_color(LEG_STATE_COLORS[state])
            what = contact[leg][k]
            marker, filled, _ = TOE_MARKERS[what]
            toes[leg].set_data([toe[0]], [toe[1]])
            toes[leg].set_marker(marker)
            toes[leg].set_markerfacecolor("k" if filled else "white")
            f = ground[leg][k].copy()  # tangential, normal [N]
            on = what != "air" and np.all(np.isfinite(f)) and np.hypot(*f) > 1.0
            tip = toe + FORCE_SCALE_M_PER_N * f if on else toe
            forces[leg].xy = (tip[0], tip[1])
            forces[leg].set_position((toe[0], toe[1]))
            forces[leg].set_visible(bool(on))
            lines.append(
                f"{leg.label:<6s}{_TOE_WORDS[what]:<10s}" + (state.label if has_ctrl else "")
            )
        status.set_text("\n".join(lines))
        stamp.set_text(f"t = {times[i]:7.3f} s")
        return [torso, floor, ticks, stamp, status, *legs, *toes, *forces]

    anim = RunAnimation(
        fig, draw, frames=len(times), interval=1000.0 / fps, blit=False, repeat=False
    )
    anim.frame_times = times
    # the drawn parts by name, each updated by every frame
    anim.artists = {
        "torso": torso,
        "legs": legs,
        "toes": toes,
        "forces": forces,
        "status": status,
        "stamp": stamp,
    }
    return anim


#: The toe's contact in the status lines, by the names of :func:`toe_contact`.
_TOE_WORDS = {"ground": "on ground", "sliding": "sliding", "air": "in air"}


def _legends(fig, has_ctrl: bool) -> None:
    """The two legends right of the view: the leg's colour (the controller's leg state) and
    the toe's marker (the simulated contact), with the ground-force arrow."""
    from matplotlib.lines import Line2D

    if has_ctrl:
        handles = [Line2D([], [], color=c, lw=3) for c in LEG_STATE_COLORS]
        names, title = list(_STATE_NAMES), "leg colour: controller state"
    else:
        handles = [Line2D([], [], color=LEG_STATE_COLORS[LegState.FLIGHT], lw=3)]
        names, title = ["leg (no controller)"], "leg"
    fig.legend(
        handles,
        names,
        loc="upper left",
        bbox_to_anchor=(0.72, 0.88),
        fontsize=7,
        title=title,
        title_fontsize=7,
        alignment="left",
        frameon=False,
    )
    handles = [
        Line2D(
            [], [], marker=m, ms=6, ls="none", color="k", mec="k", mfc="k" if filled else "white"
        )
        for m, filled, _ in TOE_MARKERS.values()
    ]
    names = [label for _, _, label in TOE_MARKERS.values()]
    handles.append(Line2D([], [], color="crimson", lw=1.5))
    names.append(f"ground force ({FORCE_SCALE_M_PER_N * 1e3:g} m/kN)")
    fig.legend(
        handles,
        names,
        loc="upper left",
        bbox_to_anchor=(0.72, 0.56),
        fontsize=7,
        title="toe: simulated contact",
        title_fontsize=7,
        alignment="left",
        frameon=False,
    )


def save_animation(
    result,
    path,
    fps: float = 25.0,
    t0: float | None = None,
    t1: float | None = None,
    dpi: int = 80,
    progress=None,
) -> Path:
    """Write the animation of ``result`` to ``path``: ``.gif`` (Pillow) or ``.mp4``
    (ffmpeg; RuntimeError if it is not installed). Returns the path. ``progress``: optional
    callback ``(frame, n_frames)``."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in ANIMATION_SUFFIXES:
        raise ValueError(f"path = '{path}' is not allowed: the suffix must be .gif or .mp4")
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise RuntimeError(
            "writing .mp4 needs the ffmpeg program, which is not on the PATH; "
            "install ffmpeg (e.g. `apt-get install ffmpeg` or `conda install "
            "ffmpeg`) or write a .gif instead"
        )
    anim = animate(result, fps=fps, t0=t0, t1=t1, dpi=dpi)
    path.parent.mkdir(parents=True, exist_ok=True)
    # Matplotlib's stubs say fps: int; both writers take a float fps as it is
    writer: PillowWriter | FFMpegWriter
    if suffix == ".gif":
        writer = PillowWriter(fps=fps)  # type: ignore[arg-type]
    else:
        writer = FFMpegWriter(fps=fps)  # type: ignore[arg-type]
    cb = None if progress is None else (lambda i, n: progress(i, n))
    anim.save(str(path), writer=writer, dpi=dpi, progress_callback=cb)
    return path
