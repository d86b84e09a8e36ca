"""Paper Fig. 11, motor saturation: leg angular speed [rad/s] against hip torque per leg
[N m], the experiment's steady-stride samples, each source's representative step, and the
actuator limits (current limit, torque-speed lines at the battery voltage).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from matplotlib.figure import Figure

from ..names import LEG_NAMES
from ..parameters import RobotParameters
from ..validation.phase import Source
from .figure_parts import (
    figure_notes,
    finish_figure,
    leg_window,
    line_kw,
    prepare_sources,
    select_window,
    shown_sources,
    source_tag,
)
from .torque_speed import draw_motor_limits, motor_limits

__all__ = ["fig11"]


def _robot_dict(robot, mods: dict, exp: Source) -> dict:
    if robot is not None:
        return robot if isinstance(robot, dict) else dataclasses.asdict(robot)
    for src in mods.values():
        if src.result is not None and (src.result.provenance or {}).get("robot"):
            return src.result.provenance["robot"]
    for lg in exp.logs:
        r = (lg.meta.get("simulation") or {}).get("robot")
        if r:
            return r
    return dataclasses.asdict(RobotParameters())


def fig11(logs, models=None, path=None, robot=None, transient_s: float = 2.0) -> Figure:
    """Leg angular speed [rad/s] against hip torque per leg [N m] (paper Fig. 11): the
    experiment's steady-stride samples as dots, each source's representative step as a
    line, and the actuator limits of
    :func:`scoutsim.presentation.torque_speed.motor_limits` (current limit, torque-speed
    lines at the battery voltage). ``robot``: RobotParameters or dict for the limits
    (default: the models' parameters, else Scout II)."""
    exp, mods = prepare_sources(logs, models, transient_s)
    robot_dict = _robot_dict(robot, mods, exp)
    lims = [motor_limits(robot_dict, leg) for leg in (0, 1)]
    fig = Figure(figsize=(11, 5.0), layout="constrained")
    axes = fig.subplots(1, 2, sharey=True)
    missing = []
    tmax = max(lim["tau_current"] for lim in lims)
    wmax = max(lim["w_no_load"] for lim in lims)
    for c, leg in enumerate(LEG_NAMES):
        ax = axes[c]
        pts = [(lg, s) for lg, s in exp.steady]
        if pts:
            xs = np.concatenate(
                [
                    np.asarray(lg.hip_torque(leg))[select_window(lg, s.t_start, s.t_end)]
                    for lg, s in pts
                ]
            )
            ys = np.concatenate(
                [
                    np.asarray(lg.leg_rate(leg))[select_window(lg, s.t_start, s.t_end)]
                    for lg, s in pts
                ]
            )
            ax.plot(
                xs,
                ys,
                ls="none",
                marker=".",
                ms=1.5,
                color="0.65",
                alpha=0.5,
                label=f"experiment, all {len(pts)} steady strides",
            )
        for i, src, lg, st, steady in shown_sources(exp, mods):
            win = leg_window(lg, st, leg)
            if win is None:
                missing.append(f"{src.label}: no complete {leg} step")
                continue
            k = select_window(lg, *win)
            x = np.asarray(lg.hip_torque(leg))[k]
            y = np.asarray(lg.leg_rate(leg))[k]
            ax.plot(x, y, label=f"{source_tag(src, steady)}, one step", **line_kw(src, i, steady))
        xl, yl = 1.15 * tmax, 1.15 * wmax
        draw_motor_limits(ax, lims[c], xl, yl, current_ls=(0, (5, 2)), line_ls=(0, (6, 2, 1, 2)))
        ax.set_xlabel("hip torque per leg [N m]")
        ax.set_ylabel("leg angular speed (encoder) [rad/s]")
        ax.set_title(f"{leg} leg")
    return finish_figure(
        fig,
        "Motor saturation: leg speed against hip torque (Fig. 11)",
        figure_notes(exp, mods, missing),
        path,
    )
