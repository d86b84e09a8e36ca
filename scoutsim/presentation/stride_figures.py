"""Paper Figs. 8-10: one stride of each source over time. Fig. 8: pitch [deg] and COM
height [m] from the back-leg lift-off; Fig. 9: leg angles [deg] and rates [deg/s], and
Fig. 10: hip torques [N m], each leg over one step from its own lift-off, with the
leg-state square wave.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..names import LEG_NAMES
from .figure_parts import (
    DEG,
    Extent,
    clip_note,
    figure_notes,
    finish_figure,
    leg_window,
    line_kw,
    prepare_sources,
    select_window,
    shown_sources,
    source_tag,
    state_axis,
    state_wave,
)

__all__ = ["fig8", "fig9", "fig10"]


def fig8(logs, models=None, path=None, transient_s: float = 2.0) -> Figure:
    """Pitch [deg] and COM height [m] over one stride, experiment and each model, time from
    the back-leg lift-off that starts the stride [s] (paper Fig. 8)."""
    exp, mods = prepare_sources(logs, models, transient_s)
    fig = Figure(figsize=(11, 4.5), layout="constrained")
    ax_p, ax_h = fig.subplots(1, 2)
    ext = Extent()
    for i, src, lg, st, steady in shown_sources(exp, mods):
        k = select_window(lg, st.t_start, st.t_end)
        tt = lg.t[k] - st.t_start
        lab = f"{source_tag(src, steady)}, period {st.period_s:.3f} s"
        th = np.asarray(lg.pitch)[k] * DEG
        y = np.asarray(lg.height)[k]
        ax_p.plot(tt, th, label=lab, **line_kw(src, i, steady))
        ax_h.plot(tt, y, label=lab, **line_kw(src, i, steady))
        if steady:
            ext.add(ax_p, tt, th)
            ext.add(ax_h, tt, y)
    ext.apply()
    ax_p.set_ylabel("pitch [deg]")
    ax_h.set_ylabel("COM height [m]")
    for ax in (ax_p, ax_h):
        ax.set_xlabel("time from back-leg lift-off [s]")
        ax.grid(True, lw=0.4, alpha=0.5)
    ax_p.legend(loc="best", fontsize=8)
    return finish_figure(
        fig,
        "Pitch and COM height over one stride (Fig. 8)",
        figure_notes(exp, mods, clip_note(exp, mods)),
        path,
    )


def _step_figure(exp, mods, rows, title, path):
    """Columns back / front; ``rows`` = list of (ylabel, getter(lg, leg) -> values); plus
    the leg-state square wave row."""
    fig = Figure(figsize=(11, 2.6 * len(rows) + 2.0), layout="constrained")
    nr = len(rows) + 1
    axes = fig.subplots(nr, 2, sharex="col", gridspec_kw={"height_ratios": [3] * len(rows) + [1.4]})
    missing = []
    ext = Extent()
    for i, src, lg, st, steady in shown_sources(exp, mods):
        kw = line_kw(src, i, steady)
        for c, leg in enumerate(LEG_NAMES):
            win = leg_window(lg, st, leg)
            if win is None:
                missing.append(f"{src.label}: no complete {leg} step")
                continue
            k = select_window(lg, *win)
            tt = lg.t[k] - win[0]
            for r, (_, get) in enumerate(rows):
                v = np.asarray(get(lg, leg))[k]
                axes[r, c].plot(tt, v, label=source_tag(src, steady) if (r == 0) else None, **kw)
                if steady:
                    ext.add(axes[r, c], tt, v)
            state_wave(axes[-1, c], tt, lg.leg_state(leg)[k], kw)
            if steady:
                ext.add(axes[-1, c], tt)
    ext.apply()
    for c, leg in enumerate(LEG_NAMES):
        axes[0, c].set_title(f"{leg} leg")
        for r, (ylab, _) in enumerate(rows):
            axes[r, c].set_ylabel(ylab)
            axes[r, c].grid(True, lw=0.4, alpha=0.5)
            axes[r, c].axhline(0.0, color="0.6", lw=0.5)
        state_axis(axes[-1, c])
        axes[-1, c].grid(True, lw=0.4, alpha=0.5)
        axes[-1, c].set_xlabel(f"time from {leg}-leg lift-off [s]")
    axes[0, 0].legend(loc="best", fontsize=7)
    return finish_figure(fig, title, figure_notes(exp, mods, missing + clip_note(exp, mods)), path)


def fig9(logs, models=None, path=None, transient_s: float = 2.0) -> Figure:
    """Back (left) and front (right) leg angles [deg] and rates [deg/s] relative to the
    torso over one step, each leg from its own lift-off, with the leg-state square wave
    (flight high, stance-retraction low, stance-brake medium) (paper Fig. 9). Angles are as
    the hip encoders log them (motor-side angle for Model II)."""
    exp, mods = prepare_sources(logs, models, transient_s)
    rows = [
        ("leg angle [deg]", lambda lg, leg: np.asarray(lg.leg_angle(leg)) * DEG),
        ("leg angular rate [deg/s]", lambda lg, leg: np.asarray(lg.leg_rate(leg)) * DEG),
    ]
    return _step_figure(exp, mods, rows, "Leg angles and rates over one step (Fig. 9)", path)


def fig10(logs, models=None, path=None, transient_s: float = 2.0) -> Figure:
    """Back and front hip torques per physical leg [N m] over one step: the experiment's
    estimated from motor current (N eta K_T i), the models' likewise; with the leg-state
    square wave (paper Fig. 10)."""
    exp, mods = prepare_sources(logs, models, transient_s)
    rows = [("hip torque per leg [N m]", lambda lg, leg: np.asarray(lg.hip_torque(leg)))]
    return _step_figure(
        exp, mods, rows, "Hip torques over one step, from motor current (Fig. 10)", path
    )
