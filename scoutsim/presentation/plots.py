"""Figures of a bounding run: time histories (this module), the torque-speed plane (paper
Fig. 11; :mod:`~scoutsim.presentation.torque_speed`), the power over a stride
(:mod:`~scoutsim.presentation.stride_power`), the basin and sweep maps
(:mod:`~scoutsim.presentation.maps`) and a tuning's convergence
(:mod:`~scoutsim.presentation.tune_plots`), all importable from here (presentation layer:
angles in degrees only here, on the axes).

    fig = plot_run(result, "run.png")            # pitch, height, leg angles, hip torques
    fig = plot_torque_speed(result, "both", "ts.png")   # paper Fig. 11, with motor limits
    fig = plot_stride_power(result, "power.png")  # power over a stride by destination

The functions build :class:`matplotlib.figure.Figure` objects directly, without
``matplotlib.pyplot``: nothing is registered with a GUI backend, no global figure state is
kept (no figure leak in long sweeps), ``plt.show`` is never called, and saving renders with
the Agg (PNG) / PDF / SVG canvas chosen from the file suffix, so everything works headless.
In Jupyter, ``display(fig)`` (or a figure as the last expression of a cell) shows it.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from ..names import LegState
from .maps import plot_basin_map, plot_sweep_map
from .run_overview import draw_overview, overview_strides
from .run_parts import legend_above, run_title, state_bands
from .stride_power import STRIDE_POWER_SINKS, STRIDE_POWER_SOURCES, plot_stride_power
from .style import LEG_COLORS, LEG_NAMES, LEG_STATE_COLORS, save_figure
from .torque_speed import draw_motor_limits, motor_limits, plot_torque_speed
from .tune_plots import plot_tune_convergence

__all__ = [
    "plot_run",
    "plot_torque_speed",
    "plot_stride_power",
    "plot_basin_map",
    "plot_sweep_map",
    "plot_tune_convergence",
    "motor_limits",
    "draw_motor_limits",
    "STRIDE_POWER_SOURCES",
    "STRIDE_POWER_SINKS",
    "LONG_RUN_S",
    "DETAIL_STRIDES",
]


#: runs longer than this [s] get an overview (``plot_run(..., overview="auto")``)
LONG_RUN_S = 4.0
#: strides the detail panels of an overview figure show (the last ones of the run)
DETAIL_STRIDES = 3
#: smallest span of the pitch [deg] and COM height [m] axes of the time histories (a bound
#: swings about 11 deg and 8 mm; a robot at rest is drawn flat, not its round-off)
MIN_PITCH_SPAN_DEG = 2.0
MIN_HEIGHT_SPAN_M = 0.005


def plot_run(result, path=None, t_range=None, overview=False, behaviour=None) -> Figure:
    """Time histories of a run: pitch, COM height, leg angles with leg states, hip torques.

    Four stacked panels share the time axis [s]:

    1. torso pitch theta [deg] (nose up positive);
    2. torso COM height y [m];
    3. leg angles phi (relative to the torso, toe ahead of the hip positive) of the back
       and front virtual legs [deg]; the background shows each leg's controller state
       (paper Sec. II, Table I: flight / stance-retraction / stance-brake), the back leg
       in the lower half of the panel, the front leg in the upper half;
    4. hip torque per physical leg [N m]: commanded (dashed) and delivered by the actuator,
       N eta K_T i (solid).

    With an overview, three panels above them show the whole run
    (:mod:`~scoutsim.presentation.run_overview`): the range of the pitch and of the COM
    height over one stride (running maximum and minimum, readable over hundreds of strides)
    and every stride's period, the steady ones filled; the four panels show the last
    :data:`DETAIL_STRIDES` strides (the last second if the run has fewer), shaded in the
    overview.

    The title says what the run did (:meth:`SimulationResult.behaviour
    <scoutsim.result.simulation_result.SimulationResult.behaviour>`: steady bounding at its speed, or what
    instead); the legends sit above their panels, off the traces.

    Parameters
    ----------
    result : SimulationResult
        The run.
    path : str or path-like, optional
        Save the figure there; the format follows the suffix (.png, .pdf, .svg).
    t_range : (t0, t1), optional
        Time window to show [s] (default: the whole run; with an overview: the last
        strides).
    overview : bool or "auto"
        Add the whole-run overview; "auto": for runs longer than :data:`LONG_RUN_S`
        when no ``t_range`` is given.
    behaviour : str, optional
        What the run did, for the title (default: ``result.behaviour()``; a result that
        holds only a window of its run says its outcome and the window, unless given its
        run's, e.g. the ``"behaviour"`` of the run's summary.json).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if overview not in (True, False, "auto"):
        raise ValueError(f"overview = {overview!r} is not allowed: must be True, False or 'auto'")
    t = np.asarray(result.t, dtype=float)
    if overview == "auto":
        overview = t_range is None and t.size > 1 and float(t[-1] - t[0]) > LONG_RUN_S
    detail = "the window asked for"
    if overview and t_range is None and t.size:
        t_range = (_last_strides_start(result), float(t[-1]))
        detail = (
            f"the last {DETAIL_STRIDES} strides"
            if len(overview_strides(result)) >= DETAIL_STRIDES
            else "the last second"
        )
    if t_range is not None:
        try:
            t0, t1 = (float(v) for v in t_range)
        except (TypeError, ValueError):
            raise ValueError(
                f"t_range = {t_range!r} is not allowed: must be (t0, t1) in s"
            ) from None
        if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
            raise ValueError(f"t_range = {t_range!r} is not allowed: must be finite with t1 > t0")
        sel = np.flatnonzero((t >= t0) & (t <= t1))
        if sel.size:  # keep one sample either side so lines and bands reach the edges
            sel = np.arange(max(sel[0] - 1, 0), min(sel[-1] + 2, t.size))
    else:
        sel = np.arange(t.size)
        t0, t1 = (float(t[0]), float(t[-1])) if t.size else (0.0, 1.0)

    if overview:
        fig = Figure(figsize=(11, 13.5), layout="constrained")
        top, bottom = fig.subfigures(2, 1, squeeze=False, height_ratios=[3.0, 10.0])[:, 0]
        draw_overview(top, result, t0, t1)
        axes = bottom.subplots(4, 1, sharex=True)
        bottom.suptitle(f"detail: t = {t0:.2f} - {t1:.2f} s ({detail})", fontsize=10)
    else:
        fig = Figure(figsize=(10, 10), layout="constrained")
        axes = fig.subplots(4, 1, sharex=True)
    _draw_run_panels(axes, result, t[sel], sel, t0, t1)
    fig.suptitle(run_title(result, behaviour=behaviour))
    save_figure(fig, path)
    return fig


def _last_strides_start(result) -> float:
    """Start [s] of the last DETAIL_STRIDES strides of a run (1 s before its end if it has
    fewer)."""
    t_end = float(result.t[-1])
    strides = overview_strides(result)
    if len(strides) >= DETAIL_STRIDES:
        return float(strides[-DETAIL_STRIDES]["t_start"])
    return max(float(result.t[0]), t_end - 1.0)


def _draw_run_panels(axes, result, ts, sel, t0, t1) -> None:
    """The four stacked panels of :func:`plot_run` for the samples ``sel`` (times ``ts``)."""
    ax_pitch, ax_height, ax_leg, ax_tau = axes
    ax_pitch.plot(
        ts, np.degrees(np.asarray(result.pitch)[sel]), color="k", lw=1.2, label="pitch theta"
    )
    ax_pitch.axhline(0.0, color="0.6", lw=0.6)
    ax_pitch.set_ylabel("pitch [deg]")

    ax_height.plot(
        ts, np.asarray(result.height)[sel], color="k", lw=1.2, label="torso COM height y"
    )
    ax_height.set_ylabel("COM height [m]")

    has_controller = (result.provenance or {}).get("controller") is not None
    for li, name in enumerate(LEG_NAMES):
        ax_leg.plot(
            ts,
            np.degrees(np.asarray(result.leg_angle(li))[sel]),
            color=LEG_COLORS[li],
            lw=1.2,
            label=f"phi {name}",
        )
        if has_controller:
            state_bands(ax_leg, ts, np.asarray(result.leg_state(li))[sel], 0.5 * li, 0.5 * (li + 1))
    ax_leg.set_ylabel("leg angle phi [deg]")
    handles, labels = ax_leg.get_legend_handles_labels()
    if has_controller:
        for state in LegState:
            handles.append(Patch(facecolor=LEG_STATE_COLORS[state], edgecolor="0.5", lw=0.5))
            labels.append(state.label)
        for li, name in enumerate(LEG_NAMES):
            ax_leg.text(
                1.005,
                0.25 + 0.5 * li,
                f"{name}\nstate",
                transform=ax_leg.transAxes,
                fontsize=7,
                va="center",
                ha="left",
                color=LEG_COLORS[li],
            )
    legend_above(ax_leg, handles, labels)

    for li, name in enumerate(LEG_NAMES):
        ax_tau.plot(
            ts,
            np.asarray(result.hip_torque_commanded(li))[sel],
            color=LEG_COLORS[li],
            lw=1.0,
            ls="--",
            label=f"{name} commanded",
        )
        ax_tau.plot(
            ts,
            np.asarray(result.hip_torque_applied(li))[sel],
            color=LEG_COLORS[li],
            lw=1.2,
            label=f"{name} applied",
        )
    ax_tau.axhline(0.0, color="0.6", lw=0.6)
    ax_tau.set_ylabel("hip torque per leg [N m]")
    ax_tau.set_xlabel("time [s]")
    legend_above(ax_tau)

    if result.outcome == "fell" and t0 <= result.t_end <= t1:
        for ax in axes:
            ax.axvline(result.t_end, color="crimson", lw=1.0, ls=":")
        ax_pitch.plot([], [], color="crimson", lw=1.0, ls=":", label="fall")
    legend_above(ax_pitch)
    legend_above(ax_height)

    for ax in axes:
        ax.grid(True, lw=0.4, alpha=0.5)
    ax_tau.set_xlim(t0, t1)
    # a torso at rest: its sub-micrometre motion is not zoomed into a bound's swing
    _min_span(ax_pitch, MIN_PITCH_SPAN_DEG)
    _min_span(ax_height, MIN_HEIGHT_SPAN_M)


def _min_span(ax, span: float) -> None:
    """Widen the y-limits of ``ax`` to at least ``span`` about their middle."""
    lo, hi = ax.get_ylim()
    if hi - lo < span:
        mid = 0.5 * (lo + hi)
        ax.set_ylim(mid - 0.5 * span, mid + 0.5 * span)
