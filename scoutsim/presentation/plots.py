"""Figures of a bounding run: time histories, the torque-speed plane (paper Fig. 11), the
basin map and sweep maps (presentation layer: angles in degrees only here, on the axes).

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
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from ..parameters import RobotParameters, floor_label

from .style import (LEG_COLORS, LEG_NAMES, LEG_STATE_COLORS, LEG_STATE_LINE_COLORS,
                    LEG_STATE_NAMES, leg_index, model_label, save_figure)

__all__ = ["plot_run", "plot_torque_speed", "plot_stride_power", "plot_basin_map",
           "plot_sweep_map", "motor_limits", "draw_motor_limits"]


def _model_label(result) -> str:
    return model_label((result.provenance or {}).get("model"))


def _title(result) -> str:
    outcome = result.outcome
    if outcome != "completed":
        outcome = f"{outcome} at t = {result.t_end:.2f} s"
    return f"Scout II bounding, {_model_label(result)}: {outcome}"


def _runs(values: np.ndarray):
    """(start index, stop index, value) of the runs of equal consecutive values."""
    if values.size == 0:
        return []
    edges = np.flatnonzero(np.diff(values)) + 1
    starts = np.concatenate([[0], edges])
    stops = np.concatenate([edges, [values.size]])
    return [(int(a), int(b), int(values[a])) for a, b in zip(starts, stops)]


def _state_bands(ax, t: np.ndarray, states: np.ndarray, y0: float, y1: float) -> None:
    """Shade the controller leg state over time in the axes-fraction strip [y0, y1].

    A sample's state holds from its time until the next sample (zero-order hold, as the
    1 kHz controller does)."""
    verts = {k: [] for k in range(len(LEG_STATE_COLORS))}
    for a, b, k in _runs(states):
        ta = t[a]
        tb = t[b] if b < t.size else t[-1]
        if k in verts and tb > ta:
            verts[k].append([(ta, y0), (tb, y0), (tb, y1), (ta, y1)])
    for k, v in verts.items():
        if v:
            ax.add_collection(PolyCollection(v, facecolors=LEG_STATE_COLORS[k], edgecolors="none",
                                             transform=ax.get_xaxis_transform(), zorder=0))


#: runs longer than this [s] get an overview (``plot_run(..., overview="auto")``)
LONG_RUN_S = 4.0
#: strides the detail panels of an overview figure show (the last ones of the run)
DETAIL_STRIDES = 3


def plot_run(result, path=None, t_range=None, overview=False) -> Figure:
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

    With an overview, two panels above them show pitch and COM height over the whole run
    and the four panels show the last :data:`DETAIL_STRIDES` strides (the last second if
    the run has fewer), shaded in the overview.

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

    Returns
    -------
    matplotlib.figure.Figure
    """
    if overview not in (True, False, "auto"):
        raise ValueError(f"overview = {overview!r} is not allowed: must be True, False or "
                         "'auto'")
    t = np.asarray(result.t, dtype=float)
    if overview == "auto":
        overview = t_range is None and t.size > 1 and float(t[-1] - t[0]) > LONG_RUN_S
    if overview and t_range is None and t.size:
        t_range = (_last_strides_start(result), float(t[-1]))
    if t_range is not None:
        try:
            t0, t1 = (float(v) for v in t_range)
        except (TypeError, ValueError):
            raise ValueError(f"t_range = {t_range!r} is not allowed: must be (t0, t1) in s") from None
        if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
            raise ValueError(f"t_range = {t_range!r} is not allowed: must be finite with t1 > t0")
        sel = np.flatnonzero((t >= t0) & (t <= t1))
        if sel.size:  # keep one sample either side so lines and bands reach the edges
            sel = np.arange(max(sel[0] - 1, 0), min(sel[-1] + 2, t.size))
    else:
        sel = np.arange(t.size)
        t0, t1 = (float(t[0]), float(t[-1])) if t.size else (0.0, 1.0)

    if overview:
        fig = Figure(figsize=(10, 12.5), layout="constrained")
        top, bottom = fig.subfigures(2, 1, height_ratios=[2.6, 9.5])
        _draw_overview(top.subplots(1, 2), result, t, t0, t1)
        axes = bottom.subplots(4, 1, sharex=True)
        bottom.suptitle(f"last {DETAIL_STRIDES} strides", fontsize=10)
    else:
        fig = Figure(figsize=(10, 9.5), layout="constrained")
        axes = fig.subplots(4, 1, sharex=True)
    _draw_run_panels(axes, result, t[sel], sel, t0, t1)
    fig.suptitle(_title(result))
    save_figure(fig, path)
    return fig


def _last_strides_start(result) -> float:
    """Start [s] of the last DETAIL_STRIDES strides of a run (1 s before its end if it has
    fewer)."""
    t_end = float(result.t[-1])
    try:
        strides = result.strides
    except Exception:   # a run too short or too broken for stride analysis
        strides = []
    if len(strides) >= DETAIL_STRIDES:
        return float(strides[-DETAIL_STRIDES]["t_start"])
    return max(float(result.t[0]), t_end - 1.0)


def _draw_overview(axes, result, t, t0, t1) -> None:
    """Pitch and COM height over the whole run, the detail window [t0, t1] shaded."""
    ax_p, ax_h = axes
    ax_p.plot(t, np.degrees(np.asarray(result.pitch)), color="k", lw=0.6)
    ax_p.set_ylabel("pitch [deg]")
    ax_h.plot(t, np.asarray(result.height), color="k", lw=0.6)
    ax_h.set_ylabel("COM height [m]")
    for ax in axes:
        ax.axvspan(t0, t1, color="tab:blue", alpha=0.15, lw=0, label="detail below")
        if result.outcome == "fell":
            ax.axvline(result.t_end, color="crimson", lw=1.0, ls=":")
        ax.set_xlabel("time [s]")
        ax.grid(True, lw=0.4, alpha=0.5)
        if t.size:
            ax.set_xlim(float(t[0]), float(t[-1]))
    ax_p.legend(loc="upper right", fontsize=8)
    ax_p.set_title("whole run", fontsize=10)


def _draw_run_panels(axes, result, ts, sel, t0, t1) -> None:
    """The four stacked panels of :func:`plot_run` for the samples ``sel`` (times ``ts``)."""
    ax_pitch, ax_height, ax_leg, ax_tau = axes
    ax_pitch.plot(ts, np.degrees(np.asarray(result.pitch)[sel]), color="k", lw=1.2,
                  label="pitch theta")
    ax_pitch.axhline(0.0, color="0.6", lw=0.6)
    ax_pitch.set_ylabel("pitch [deg]")

    ax_height.plot(ts, np.asarray(result.height)[sel], color="k", lw=1.2,
                   label="torso COM height y")
    ax_height.set_ylabel("COM height [m]")

    has_controller = (result.provenance or {}).get("controller") is not None
    for li, name in enumerate(LEG_NAMES):
        ax_leg.plot(ts, np.degrees(np.asarray(result.leg_angle(li))[sel]), color=LEG_COLORS[li],
                    lw=1.2, label=f"phi {name}")
        if has_controller:
            _state_bands(ax_leg, ts, np.asarray(result.leg_state(li))[sel],
                         0.5 * li, 0.5 * (li + 1))
    ax_leg.set_ylabel("leg angle phi [deg]")
    handles, labels = ax_leg.get_legend_handles_labels()
    if has_controller:
        for k, name in enumerate(LEG_STATE_NAMES):
            handles.append(Patch(facecolor=LEG_STATE_COLORS[k], edgecolor="0.5", lw=0.5))
            labels.append(name)
        for li, name in enumerate(LEG_NAMES):
            ax_leg.text(1.005, 0.25 + 0.5 * li, f"{name}\nstate", transform=ax_leg.transAxes,
                        fontsize=7, va="center", ha="left", color=LEG_COLORS[li])
    ax_leg.legend(handles, labels, loc="upper left", fontsize=8, ncol=5, framealpha=0.85,
                  bbox_to_anchor=(0.0, 1.0))

    for li, name in enumerate(LEG_NAMES):
        ax_tau.plot(ts, np.asarray(result.hip_torque_commanded(li))[sel], color=LEG_COLORS[li],
                    lw=1.0, ls="--", label=f"{name} commanded")
        ax_tau.plot(ts, np.asarray(result.hip_torque_applied(li))[sel], color=LEG_COLORS[li],
                    lw=1.2, label=f"{name} applied")
    ax_tau.axhline(0.0, color="0.6", lw=0.6)
    ax_tau.set_ylabel("hip torque per leg [N m]")
    ax_tau.set_xlabel("time [s]")
    ax_tau.legend(loc="upper left", fontsize=8, ncol=4, framealpha=0.85)

    if result.outcome == "fell" and t0 <= result.t_end <= t1:
        for ax in axes:
            ax.axvline(result.t_end, color="crimson", lw=1.0, ls=":")
        ax_pitch.plot([], [], color="crimson", lw=1.0, ls=":", label="fall")
    ax_pitch.legend(loc="upper left", fontsize=8)
    ax_height.legend(loc="upper left", fontsize=8)

    for ax in axes:
        ax.grid(True, lw=0.4, alpha=0.5)
    ax_tau.set_xlim(t0, t1)


def motor_limits(robot: dict, leg=None) -> dict:
    """Actuator limits at one physical leg (docs/specification.md section 4; paper Sec. II, eq. (3)).

    Parameters
    ----------
    robot : dict
        Robot parameters as in ``result.provenance["robot"]`` (SI units).
    leg : "back" / 0, "front" / 1 or None
        Whose actuator (None: both legs', which must then agree).

    Returns
    -------
    dict
        ``N`` gear ratio [-], ``eta`` efficiency [-], ``tau_current`` = N eta K_T i_max
        [N m] (current limit), ``tau_stall`` = N eta K_T V / R_A [N m] (torque-speed line at
        zero speed), ``w_no_load`` = V / (K_w N) [rad/s] (leg speed where the line crosses
        zero torque) and ``slope`` = N eta K_T K_w N / R_A [N m s/rad] (torque lost per unit
        leg speed).
    """
    r = robot if isinstance(robot, RobotParameters) else RobotParameters(**robot)
    if leg is not None:
        r = r.leg(leg)
    return {"N": r.gear_ratio, "eta": r.efficiency, "tau_current": r.max_leg_torque,
            "tau_stall": r.stall_torque, "w_no_load": r.no_load_speed,
            "slope": r.torque_speed_slope}


def _torque_speed_axes(ax, result, li: int) -> None:
    robot = (result.provenance or {}).get("robot")
    model = (result.provenance or {}).get("model")
    tau = np.asarray(result.hip_torque_applied(li), dtype=float)
    lim = motor_limits(robot, li) if robot else None
    # leg-side speed of the actuator: w_m / N = dphi (ideal, Model I) or dalpha (Model II)
    if lim is not None:
        w = np.asarray(result.motor_speed(li), dtype=float) / lim["N"]
    else:
        w = np.asarray(result.leg_rate(li), dtype=float)
    states = np.asarray(result.leg_state(li))
    has_controller = (result.provenance or {}).get("controller") is not None
    if has_controller:
        for k, name in enumerate(LEG_STATE_NAMES):
            m = states == k
            if np.any(m):
                ax.plot(tau[m], w[m], ls="none", marker=".", ms=2.0, alpha=0.6,
                        color=LEG_STATE_LINE_COLORS[k], label=name)
    else:
        ax.plot(tau, w, ls="none", marker=".", ms=2.0, alpha=0.6, color="tab:gray",
                label="samples")

    tmax = float(np.max(np.abs(tau))) if tau.size else 0.0
    wmax = float(np.max(np.abs(w))) if w.size else 0.0
    if lim is not None:
        tmax = max(tmax, lim["tau_current"])
        wmax = max(wmax, lim["w_no_load"])
    xl, yl = 1.15 * max(tmax, 1e-3), 1.15 * max(wmax, 1e-3)
    note = "" if model != "ideal" else " (not applied in the ideal model)"
    draw_motor_limits(ax, lim, xl, yl, note=note)
    ax.set_xlabel("applied hip torque per leg [N m]")
    ax.set_ylabel("leg angular speed [rad/s]")
    ax.set_title(f"{LEG_NAMES[li]} leg")


def draw_motor_limits(ax, lim, xl, yl, *, note="", current_ls="--", line_ls="-."):
    """Draw the current limit (+-N eta K_T i_max) and the torque-speed lines
    tau = N eta K_T (+-V - K_w N w) / R_A on a torque [N m] / leg-speed [rad/s] axes, set
    the limits to +-xl, +-yl, and add the zero lines, grid and legend (paper Fig. 11)."""
    if lim is not None:
        ic = lim["tau_current"]
        ax.axvline(ic, color="k", lw=1.0, ls=current_ls, label=f"current limit ±{ic:.1f} N m")
        ax.axvline(-ic, color="k", lw=1.0, ls=current_ls)
        ww = np.array([-yl, yl])
        for sign in (1.0, -1.0):
            ax.plot(sign * lim["tau_stall"] - lim["slope"] * ww, ww, color="0.35", lw=1.0,
                    ls=line_ls, label=(f"torque-speed lines ±V{note}" if sign > 0 else None))
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.axvline(0.0, color="0.6", lw=0.5)
    ax.set_xlim(-xl, xl)
    ax.set_ylim(-yl, yl)
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.legend(loc="upper right", fontsize=7, markerscale=4, framealpha=0.85)


def plot_torque_speed(result, leg="both", path=None) -> Figure:
    """Leg angular speed against applied hip torque, with the motor limits (paper Fig. 11).

    Every sample of the run is a dot, coloured by the controller leg state. The speed is
    the actuator's leg-side speed w = w_m / N (the leg rate dphi/dt for the ideal actuator
    and Model I, the driven-gear rate dalpha/dt for Model II) [rad/s]; the torque is what
    the actuator delivers per physical leg, N eta K_T i [N m]. Lines show the actuator's
    limits (docs/specification.md section 4): the current limit tau = +-N eta K_T i_max (dashed) and the
    torque-speed lines tau = N eta K_T (+-V - K_w N w) / R_A at the battery voltage V
    (dash-dotted), with the parameters from ``result.provenance["robot"]``.

    Parameters
    ----------
    result : SimulationResult
        The run.
    leg : {"back", "front", 0, 1, "both"} or a sequence of legs
        One panel per leg (default both, side by side).
    path : str or path-like, optional
        Save the figure there (.png, .pdf, .svg).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if isinstance(leg, str) and leg == "both":
        legs = [0, 1]
    elif isinstance(leg, (list, tuple)):
        legs = [leg_index(x) for x in leg]
        if not legs:
            raise ValueError("leg = [] is not allowed: give at least one leg")
    else:
        legs = [leg_index(leg)]
    fig = Figure(figsize=(5.5 * len(legs), 5.0), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(legs), sharey=True, squeeze=False)[0])
    for ax, li in zip(axes, legs):
        _torque_speed_axes(ax, result, li)
    fig.suptitle(f"Torque-speed, {_model_label(result)} ({result.outcome})")
    save_figure(fig, path)
    return fig


def plot_basin_map(rows, path=None, default_start=None, controller: str | None = None) -> Figure:
    """The basin of the bounding cycle as a map: one panel per model (rows) and floor
    (columns) over initial forward speed x pitch rate [deg/s]; a cell's colour is the share
    of the grid's start heights from which the run reaches steady bounding (green: all,
    yellow: some, red: none), its label the mean speed of the cycle reached [m/s].
    ``rows``: :attr:`scoutsim.analysis.basin.BasinResult.rows` (or the CLI's basin.csv rows);
    ``default_start``: (speed [m/s], pitch rate [deg/s]) marked with a star;
    ``controller``: its name, in the title."""
    from matplotlib.colors import ListedColormap
    models = list(dict.fromkeys(r["model"] for r in rows))
    floors = list(dict.fromkeys(float(r["friction"]) for r in rows))
    speeds = sorted({float(r["speed"]) for r in rows})
    rates = sorted({float(r["pitch_rate_deg_s"]) for r in rows})
    heights = sorted({float(r["height"]) for r in rows})
    cmap = ListedColormap(["#d9544d", "#f2c14e", "#4caf50"])
    fig = Figure(figsize=(3.4 * len(floors) + 1.0, 2.9 * len(models) + 0.6), layout="constrained")
    axes = fig.subplots(len(models), len(floors), squeeze=False, sharex=True, sharey=True)
    for i, m in enumerate(models):
        for j, mu in enumerate(floors):
            ax = axes[i, j]
            share = np.full((len(rates), len(speeds)), np.nan)
            vel = [[[] for _ in speeds] for _ in rates]
            cnt = np.zeros_like(share)
            for r in rows:
                if r["model"] != m or float(r["friction"]) != mu or r["outcome"] == "invalid_start":
                    continue
                a, b = rates.index(float(r["pitch_rate_deg_s"])), speeds.index(float(r["speed"]))
                ok = str(r["steady_bounding"]) in ("True", "true", "1")
                share[a, b] = (0.0 if np.isnan(share[a, b]) else share[a, b]) + ok
                cnt[a, b] += 1
                if ok and r["mean_speed_m_s"] not in (None, ""):
                    vel[a][b].append(float(r["mean_speed_m_s"]))
            frac = np.where(cnt > 0, share / np.maximum(cnt, 1), np.nan)
            level = np.where(np.isnan(frac), np.nan, np.where(frac >= 1.0, 2, np.where(frac > 0, 1, 0)))
            ds, dr = (speeds[1] - speeds[0] if len(speeds) > 1 else 0.2,
                      rates[1] - rates[0] if len(rates) > 1 else 50.0)
            ax.imshow(level, origin="lower", cmap=cmap, vmin=0, vmax=2, aspect="auto",
                      extent=(speeds[0] - ds / 2, speeds[-1] + ds / 2, rates[0] - dr / 2,
                              rates[-1] + dr / 2))
            for a in range(len(rates)):
                for b in range(len(speeds)):
                    if vel[a][b]:
                        ax.text(speeds[b], rates[a], f"{np.mean(vel[a][b]):.2f}", ha="center",
                                va="center", fontsize=6)
            if default_start is not None:
                ax.plot([default_start[0]], [default_start[1]], marker="*", ms=12, mfc="white",
                        mec="black")
            valid = cnt.sum()
            n_ok = np.nansum(share)
            ax.set_title(f"{model_label(m)}, {floor_label(mu)}: "
                         f"{n_ok / valid if valid else float('nan'):.2f}", fontsize=9)
            if i == len(models) - 1:
                ax.set_xlabel("initial forward speed [m/s]")
            if j == 0:
                ax.set_ylabel("initial pitch rate [deg/s]")
    fig.legend(handles=[Patch(color=cmap(2), label="bounds (every height)"),
                        Patch(color=cmap(1), label="bounds (some heights)"),
                        Patch(color=cmap(0), label="falls / no steady bound")],
               loc="outside lower center", ncol=3 if len(floors) > 1 else 1, fontsize=8)
    fig.suptitle(("" if controller is None else f"{controller} controller\n")
                 + "Basin of the bounding cycle" + (" " if len(floors) > 1 else "\n")
                 + "(heights " + ", ".join(f"{h:g}" for h in heights)
                 + " m; labels: cycle speed m/s)", fontsize=10)
    save_figure(fig, path)
    return fig


def plot_sweep_map(sweep, x: str, y: str, value: str = "mean_speed_m_s", path=None) -> Figure:
    """Map of ``value`` over two swept parameters of a grid sweep
    (:class:`scoutsim.analysis.sweep.SweepResult`); points that do not reach steady bounding
    are marked x. Angles (names ending in 'angle' / 'limit') are shown in degrees;
    saved by suffix if ``path`` is given."""
    xs = sweep.column(x)
    ys = sweep.column(y)
    vs = sweep.column(value)
    ux, uy = np.unique(xs), np.unique(ys)
    Z = np.full((len(uy), len(ux)), np.nan)
    steady = np.zeros_like(Z, dtype=bool)
    for xi, yi, v, r in zip(xs, ys, vs, sweep.rows):
        j, i = np.searchsorted(ux, xi), np.searchsorted(uy, yi)
        Z[i, j] = v
        steady[i, j] = bool(r.get("steady_bounding"))

    def edge(name, vals):
        deg = name.endswith(("angle_front", "angle_back", "limit_front", "limit_back"))
        return (np.degrees(vals), f"{name} [deg]") if deg else (vals, name + " [SI]")
    gx, lx = edge(x, ux)
    gy, ly = edge(y, uy)
    fig = Figure(figsize=(6.5, 5), layout="constrained")
    ax = fig.add_subplot()
    m = ax.pcolormesh(gx, gy, Z, shading="nearest", cmap="viridis")
    fig.colorbar(m, ax=ax, label=value)
    for i in range(len(uy)):
        for j in range(len(ux)):
            if not steady[i, j]:
                ax.plot(gx[j], gy[i], "x", color="w", ms=5)
    ax.set_xlabel(lx)
    ax.set_ylabel(ly)
    ax.set_title(f"{value} (x: not steady bounding)")
    save_figure(fig, path)
    return fig


def plot_tune_convergence(tuning, path=None) -> Figure:
    """Convergence of a tuning (:class:`scoutsim.analysis.tune.TuneResult`): every
    evaluation's score (feasible ones filled, penalised ones open, on a log axis above the
    penalty) and the best so far, against the evaluation number; below, each tuned
    parameter of every evaluation and of the best so far, in the unit its name gives.
    Saved by suffix if ``path`` is given."""
    rows = tuning.rows
    n = np.arange(len(rows))
    score = np.array([r["score"] for r in rows], dtype=float)
    feasible = np.array([bool(r["feasible"]) for r in rows])
    best = tuning.best_so_far()
    k = len(tuning.parameters)
    fig = Figure(figsize=(7.5, 3.2 + 1.6 * k), layout="constrained")
    axes = fig.subplots(1 + k, 1, sharex=True, squeeze=False)[:, 0]
    ax = axes[0]
    ax.plot(n[feasible], score[feasible], "o", ms=3, color="tab:blue", label="feasible")
    ax.plot(n[~feasible], np.minimum(score[~feasible], 3e4), "o", ms=3, mfc="none",
            color="tab:red", label="penalised (a constraint broken)")
    ax.step(n, best, where="post", color="k", lw=1.2, label="best so far")
    if np.all(score > 0):
        ax.set_yscale("log")
    else:
        ax.set_yscale("symlog", linthresh=1e-3)
    goal = tuning.settings.get("goal", {})
    what = goal.get("objective", "")
    if goal.get("target") is not None:
        what += f" (|v - {goal['target']:g} m/s|)"
    ax.set_ylabel("score")
    ax.set_title(f"tuning: {what}, best {tuning.best['score']:.4g} at evaluation "
                 f"{tuning.best['evaluation']}")
    ax.legend(fontsize=7, loc="upper right")
    order = np.array([r["score"] for r in rows], dtype=float)
    best_idx = np.array([int(np.argmin(order[:i + 1])) for i in range(len(rows))])
    for a, p in zip(axes[1:], tuning.parameters):
        v = np.array([r[p.name] for r in rows], dtype=float)
        a.plot(n, v, ".", ms=3, color="0.6")
        a.step(n, v[best_idx], where="post", color="k", lw=1.2)
        a.set_ylabel(p.name.replace("controller.", "").replace("robot.", ""), fontsize=7)
    axes[-1].set_xlabel("evaluation")
    save_figure(fig, path)
    return fig


#: destinations of :func:`plot_stride_power`: (name for ``result.power``, label, colour)
STRIDE_POWER_SOURCES = (("battery", "battery output", "k"),
                        ("copper", "copper losses R_A i^2", "tab:orange"),
                        ("transmission", "transmission losses (signed)", "tab:purple"),
                        ("hip_work", "hip work (mechanical)", "tab:green"))
STRIDE_POWER_SINKS = (("hip_work", "hip work", "tab:green"),
                      ("friction", "friction and dampers", "tab:brown"))


def plot_stride_power(result, path=None, stride=None) -> Figure:
    """Power over one stride by destination (needs ``simulate(energy=True)``; ``scoutsim
    run --plots`` draws it as stride_power.png).

    Two panels share the time axis [s], the power [W] of both virtual legs together, each
    the mean over a control period (``result.power``: exact, from the energy integrated on
    every integrator step):

    1. the battery's output and where it goes: motor copper losses, transmission losses
       (the paper's constant efficiency, signed: negative while a leg back-drives its
       motor) and the hip work, which add up to the electrical power into the motors
       (docs/model.md "Work-energy balance"); the ideal actuator has the hip work only;
    2. where the hip work goes: every friction and damper of the mechanism, and the rate of
       change of the mechanical energy (kinetic, gravity, springs); touchdowns are marked,
       with their impact losses [J] (none where the toes land sliding).

    The legend gives each destination's energy over the stride [J]; the background shows
    each leg's controller state (back leg in the lower half, front in the upper).

    Parameters
    ----------
    result : SimulationResult
        A run made with the energy accounting.
    path : str or path-like, optional
        Save the figure there (.png, .pdf, .svg).
    stride : int, optional
        Index into ``result.strides`` (default: the last steady stride, or the last stride
        if none is steady).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if result.energy_series is None:
        raise ValueError("plot_stride_power needs a run made with simulate(..., energy=True)")
    model = (result.provenance or {}).get("model")
    if model == "passive":
        raise ValueError("plot_stride_power: the passive model has no actuators (no power "
                         "input)")
    strides = result.strides
    if not strides:
        raise ValueError("plot_stride_power: the run has no complete stride")
    if stride is None:
        steady = [s for s in strides if s.steady]
        st = steady[-1] if steady else strides[-1]
    else:
        if not (isinstance(stride, (int, np.integer)) and -len(strides) <= stride < len(strides)):
            raise ValueError(f"stride = {stride!r} is not allowed: must be an index into the "
                             f"run's {len(strides)} strides")
        st = strides[stride]
    if st.energy_t_start is None:
        raise ValueError("plot_stride_power: the stride has no energy (too short a run?)")
    t = np.asarray(result.t, dtype=float)
    i, j = (int(np.searchsorted(t, v)) for v in (st.energy_t_start, st.energy_t_end))
    k = np.arange(i, j + 1)         # the periods i .. j-1, drawn as steps to t[j]
    tk = t[k]

    def steps(p):
        return np.append(p[i:j], p[j - 1])

    fig = Figure(figsize=(10, 7.5), layout="constrained")
    ax_in, ax_out = fig.subplots(2, 1, sharex=True)
    electrical = model in ("I", "II")
    sources = STRIDE_POWER_SOURCES if electrical else STRIDE_POWER_SOURCES[-1:]
    for name, label, color in sources:
        e = float(result.cumulative_energy(name)[j] - result.cumulative_energy(name)[i])
        ax_in.step(tk, steps(result.power(name)), where="post", color=color,
                   lw=2.0 if name == "battery" else 1.2, label=f"{label}: {e:.1f} J")
    mech = np.full(len(t), np.nan)
    mech[:-1] = np.diff(np.asarray(result.energy, dtype=float)) / np.diff(t)
    for name, label, color in STRIDE_POWER_SINKS:
        e = float(result.cumulative_energy(name)[j] - result.cumulative_energy(name)[i])
        ax_out.step(tk, steps(result.power(name)), where="post", color=color, lw=1.2,
                    label=f"{label}: {e:.1f} J")
    ax_out.step(tk, steps(mech), where="post", color="tab:gray", lw=1.2,
                label=f"rate of change of mechanical energy: "
                      f"{st.mechanical_energy_change_j:+.1f} J")
    imp = result.impacts()
    imp = imp[(imp[:, 0] >= t[i]) & (imp[:, 0] < t[j])]
    for n, row in enumerate(imp):
        ax_out.axvline(row[0], color="tab:red", ls=":", lw=1.0,
                       label=(f"touchdowns (impact losses {imp[:, 4].sum():.2f} J)"
                              if n == 0 else None))
        if row[4] >= 0.005:
            ax_out.annotate(f"{row[4]:.2f} J", (row[0], 0.95),
                            xycoords=("data", "axes fraction"), fontsize=8, color="tab:red",
                            ha="left", va="top")
    for ax in (ax_in, ax_out):
        ax.axhline(0.0, color="k", lw=0.5)
        for leg, (y0, y1) in enumerate(((0.0, 0.5), (0.5, 1.0))):
            _state_bands(ax, t[i:j + 1], result.leg_state(leg)[i:j + 1], y0, y1)
        ax.legend(loc="upper right", fontsize=8, framealpha=0.9)
        ax.grid(alpha=0.3)
    ax_in.set_ylabel("power from the battery [W]")
    ax_out.set_ylabel("power of the hip work [W]")
    ax_out.set_xlabel("time [s]")
    ax_out.set_xlim(tk[0], tk[-1])
    cot = "" if st.cost_of_transport is None else f", cost of transport {st.cost_of_transport:.2f}"
    fig.suptitle(f"Power over stride {st.index} ({tk[0]:.3f} - {tk[-1]:.3f} s), "
                 f"{_model_label(result)}{cot}\n(background: leg states; back leg below, "
                 "front leg above)", fontsize=10)
    save_figure(fig, path)
    return fig
