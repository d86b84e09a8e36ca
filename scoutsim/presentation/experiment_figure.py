"""Paper Fig. 5: the experiment over a run with the studied stride: snapshots of the robot
through the stride drawn from what the log holds (:func:`robot_pose`: torso, hips and toes
[m] from the logged pitch, height, leg angles and leg states), pitch [deg] and COM height
[m] over the run with the stride shaded, and a zoom on it.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from ..names import LEG_NAMES
from ..parameters import RobotParameters
from .figure_parts import DEG, experiment_source, finish_figure, select_window
from .style import LEG_STATE_LINE_COLORS, LEG_STATE_NAMES

__all__ = ["robot_pose", "fig5"]


def robot_pose(log, k: int, robot=None) -> dict:
    """The planar robot drawn from what a log holds at sample ``k`` (SI, world frame with
    the torso COM at x = 0): torso corners, hips and toes.

    Leg length: the logged one if present; otherwise, in a stance state, the length that
    puts the toe on the ground (hip height / cos of the leg's world angle), in flight the
    rest length l0 (docs/specification.md section 1: the leg is at its stop in flight)."""
    rob = robot if robot is not None else RobotParameters()
    if isinstance(rob, dict):
        rob = RobotParameters(**rob)
    th = float(np.asarray(log.pitch)[k])
    y = float(np.asarray(log.height)[k])
    c, s = math.cos(th), math.sin(th)
    a, b = 0.5 * rob.torso_length, 0.5 * rob.torso_height
    corners = np.array([[-a, -b], [a, -b], [a, b], [-a, b], [-a, -b]])
    torso = np.column_stack(
        [corners[:, 0] * c - corners[:, 1] * s, y + corners[:, 0] * s + corners[:, 1] * c]
    )
    legs = {}
    for i, name in enumerate(LEG_NAMES):
        sl = rob.hip_offset(i)
        l0 = rob.per_leg("leg_rest_length")[i]
        hx, hy = sl * c, y + sl * s
        g = th + float(np.asarray(log.leg_angle(name))[k])
        state = int(np.asarray(log.leg_state(name))[k])
        if log.has(f"leg_length_{name}_m"):
            ll = float(np.asarray(log.leg_length(name))[k])
        elif state != 0 and math.cos(g) > 0.2:
            ll = min(hy / math.cos(g), l0)
        else:
            ll = l0
        legs[name] = dict(
            hip=(hx, hy), toe=(hx + ll * math.sin(g), hy - ll * math.cos(g)), state=state
        )
    return dict(torso=torso, legs=legs)


def _draw_snapshots(ax, lg, times, robot, spacing: float = 0.95):
    """A film strip: the robot at ``times`` laid side by side (``spacing`` [m] apart)."""
    state_colors = LEG_STATE_LINE_COLORS
    for j, tj in enumerate(times):
        k = int(np.clip(np.searchsorted(lg.t, tj), 0, len(lg.t) - 1))
        pose = robot_pose(lg, k, robot)
        x0 = j * spacing
        ax.fill(pose["torso"][:, 0] + x0, pose["torso"][:, 1], color="0.75", ec="k", lw=0.8)
        for name, leg in pose["legs"].items():
            (hx, hy), (tx, ty) = leg["hip"], leg["toe"]
            ax.plot(
                [hx + x0, tx + x0],
                [hy, ty],
                color=state_colors[leg["state"] % 3],
                lw=2.2 if name == "back" else 1.6,
                ls="-" if name == "back" else "--",
                solid_capstyle="round",
            )
            ax.plot([tx + x0], [ty], "o", color="k", ms=2.5)
        ax.text(
            x0,
            float(np.max(pose["torso"][:, 1])) + 0.04,
            f"({chr(97 + j)})",
            ha="center",
            fontsize=8,
        )
    ax.axhline(0.0, color="k", lw=0.8)
    for lab, col in zip(LEG_STATE_NAMES, state_colors):
        ax.plot([], [], color=col, lw=2, label=lab)
    ax.plot([], [], color="0.3", lw=2, label="back leg")
    ax.plot([], [], color="0.3", lw=1.6, ls="--", label="front leg")
    ax.set_aspect("equal")
    ax.set_xlim(-0.5 * spacing, (len(times) - 0.5) * spacing)
    ax.set_ylim(-0.03, 0.52)
    ax.set_xticks([])
    ax.set_xlabel(
        "robot at the marked times, laid side by side (forward travel not to scale) [m]", fontsize=8
    )
    ax.set_ylabel("height [m]")
    ax.legend(loc="upper left", fontsize=7, ncol=1, frameon=False, bbox_to_anchor=(1.0, 1.0))


def fig5(logs, path=None, transient_s: float = 2.0, robot=None, n_snapshots: int = 6) -> Figure:
    """Experiment over a run with the studied stride (paper Fig. 5): snapshots of the robot
    through the stride (top, drawn from the logged pitch, height, leg angles and leg states,
    legs coloured by controller state), pitch [deg] and COM height [m] of the run holding
    the representative steady stride, that stride shaded and the snapshot times marked.
    ``robot``: geometry for the drawing (default Scout II)."""
    if not (isinstance(n_snapshots, int) and 1 <= n_snapshots <= 12):
        raise ValueError(
            f"n_snapshots = {n_snapshots!r} is not allowed: must be an integer in [1, 12]"
        )
    exp = experiment_source(logs, transient_s)
    rep = exp.representative()
    lg = rep[0] if rep is not None else exp.logs[0]
    fig = Figure(figsize=(11, 7), layout="constrained")
    gs = fig.add_gridspec(3, 2, height_ratios=[0.9, 1, 1], width_ratios=[1.7, 1])
    ax_s = fig.add_subplot(gs[0, :])
    ax_p = fig.add_subplot(gs[1, 0])
    ax_h = fig.add_subplot(gs[2, 0], sharex=ax_p)
    ax_pz = fig.add_subplot(gs[1, 1])
    ax_hz = fig.add_subplot(gs[2, 1], sharex=ax_pz)
    pitch = np.asarray(lg.pitch) * DEG
    height = np.asarray(lg.height)
    for ax_a, ax_b in ((ax_p, ax_h), (ax_pz, ax_hz)):
        ax_a.plot(lg.t, pitch, color="k", lw=1.0)
        ax_b.plot(lg.t, height, color="k", lw=1.0)
    notes = []
    if rep is not None:
        _, st, steady = rep
        for ax in (ax_p, ax_h, ax_pz, ax_hz):
            ax.axvspan(
                st.t_start,
                st.t_end,
                color="tab:orange",
                alpha=0.3,
                lw=0,
                label=f"{'steady' if steady else 'not steady'} stride studied "
                f"({st.t_start:.3f}-{st.t_end:.3f} s)",
            )
        ax_p.legend(loc="upper right", fontsize=8)
        times = st.t_start + (st.t_end - st.t_start) * np.arange(n_snapshots) / n_snapshots
        _draw_snapshots(ax_s, lg, times, robot)
        for j, tj in enumerate(times):
            for ax in (ax_pz, ax_hz):
                ax.axvline(tj, color="0.4", lw=0.6, ls=":")
            ax_pz.annotate(
                f"({chr(97 + j)})",
                (tj, 1.0),
                xycoords=("data", "axes fraction"),
                ha="center",
                va="bottom",
                fontsize=7,
            )
        # the zoom: the studied stride and a stride either side
        T = st.t_end - st.t_start
        a, b = max(lg.t[0], st.t_start - T), min(lg.t[-1], st.t_end + T)
        k = select_window(lg, a, b)
        ax_pz.set_xlim(a, b)
        for ax, yy in ((ax_pz, pitch[k]), (ax_hz, height[k])):
            pad = 0.08 * (np.ptp(yy) or 1.0)
            ax.set_ylim(float(np.min(yy)) - pad, float(np.max(yy)) + pad)
    else:
        notes.append("no stride to highlight")
        ax_s.set_axis_off()
        ax_pz.set_axis_off()
        ax_hz.set_axis_off()
    for ax in (ax_p, ax_pz):
        ax.set_ylabel("pitch [deg]")
        ax.set_xlabel("time [s]")
    for ax in (ax_h, ax_hz):
        ax.set_ylabel("COM height [m]")
        ax.set_xlabel("time [s]")
    for ax in (ax_p, ax_h, ax_pz, ax_hz):
        ax.grid(True, lw=0.4, alpha=0.5)
    ax_h.set_xlim(lg.t[0], lg.t[-1])
    if exp.synthetic:
        notes.insert(0, "SYNTHETIC data (generated by scoutsim, not robot data)")
    return finish_figure(
        fig,
        f"Experiment run {lg.name}: snapshots of one stride, pitch and COM "
        "height (measured, 15 Hz low-pass; right: zoom)",
        notes,
        path,
    )
