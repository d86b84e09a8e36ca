"""The paper's simulation-against-experiment figures (Figs. 5, 8-12) for any data set.

    from scoutsim.validation import load_dataset
    from scoutsim.validation.errors import compare
    from scoutsim.presentation import paper_figures as figures
    logs = load_dataset(["run1.csv", "run2.csv"])
    table = compare(logs)                         # simulates the models (ErrorTable)
    figures.fig8(logs, table, "fig8.png")         # models from table.models
    figures.write_figures(logs, table, "out/")    # fig5 ... fig12 and phase

Every function takes the experiment data set (a list of
:class:`~scoutsim.validation.ExperimentLog`) and/or the models - a dict name ->
:class:`~scoutsim.SimulationResult` / :class:`~scoutsim.validation.errors.ModelRun` /
ExperimentLog, or an :class:`~scoutsim.validation.errors.ErrorTable` (its simulated
models) - and returns a :class:`matplotlib.figure.Figure` (no pyplot, headless), saved to
``path`` if given, in the format of its suffix (.png, .pdf, .svg).

Models are measured through the same chain as the logs (lasers, 15 Hz low-pass, encoder
angles, torque from current; :func:`~scoutsim.validation.measurement.to_log` with the first
log's geometry), so what is drawn is what the robot would have logged.

Which stride is shown (Figs. 5 and 8-11): per source, the steady stride whose period is
closest to the median steady period (:meth:`~scoutsim.validation.phase.Source.representative`).
A model with no steady strides (e.g. ideal and Model I fall from the default start) is drawn
with its last complete stride, marked "not steady" in the legend; without any stride it is
left out and the figure says why. Styles follow the paper: experiment solid, Model I
dotted, Model II dashed (ideal dash-dotted).

All computation is SI; degrees appear only here, on the axes.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..parameters import RobotParameters
from ..validation.phase import Source, as_source, as_sources, phase_compare
from .phase_plots import plot_phase
from .plots import draw_motor_limits, motor_limits
from .style import LEG_STATE_LINE_COLORS, LEG_STATE_NAMES, model_label, model_style, save_figure

__all__ = ["robot_pose", "fig5", "fig8", "fig9", "fig10", "fig11", "fig12", "fig_phase", "plot_log",
           "write_figures", "FIGURE_NAMES", "STATE_LEVELS"]

#: Level of each controller leg state in the square wave of Figs. 9 and 10 (paper: flight
#: high, stance-retraction low, stance-brake medium), indexed by the state code.
STATE_LEVELS = (1.0, 0.0, 0.5)
#: File stems written by :func:`write_figures`.
FIGURE_NAMES = ("fig5", "fig8", "fig9", "fig10", "fig11", "fig12", "phase")
_DEG = math.degrees(1.0)
_LEGS = ("back", "front")


# -----------------------------------------------------------------------------------------
# helpers
# -----------------------------------------------------------------------------------------
def _experiment(logs, transient_s: float) -> Source:
    if isinstance(logs, Source):
        return logs
    if logs is None or (isinstance(logs, (list, tuple)) and not logs):
        raise ValueError("no experiment logs given: pass a list of ExperimentLog")
    src = as_source(logs, "experiment", transient_s=transient_s)
    src.name = "experiment"
    return src


def _prepare(logs, models, transient_s: float):
    exp = _experiment(logs, transient_s)
    like = exp.logs[0] if exp.logs else None
    return exp, as_sources(models, like, transient_s)


def _sources(exp: Source, models: dict) -> list:
    return [exp] + list(models.values())


def _shown(exp: Source, models: dict):
    """(index, source, log, stride, steady) of every source that has a stride to show."""
    for i, src in enumerate(_sources(exp, models)):
        rep = src.representative()
        if rep is not None:
            yield (i, src) + tuple(rep)


def _tag(src: Source, steady: bool) -> str:
    if steady:
        return src.label
    why = src.status.replace("no steady strides", "").strip().strip("()")
    return f"{src.label} (transient stride{': ' + why if why else ''})"


def _line_kw(src: Source, i: int, steady: bool) -> dict:
    """Style of a source's curve: the paper's styles; a non-steady (transient) stride thin
    and faint."""
    col, ls = model_style(src.name, i)
    lw = 1.6 if src.name == "experiment" else 1.4
    return dict(color=col, ls=ls, lw=lw if steady else 0.9, alpha=1.0 if steady else 0.55)


class _Extent:
    """Data range of the steady curves of each axes; the view is limited to it so that a
    long transient stride of a model that fell does not squash the steady ones."""

    def __init__(self):
        self.r = {}

    def add(self, ax, x, y=None):
        x = np.asarray(x, dtype=float)
        if x.size == 0:
            return
        lo = self.r.setdefault(id(ax), [ax, math.inf, -math.inf, math.inf, -math.inf])
        lo[1], lo[2] = min(lo[1], float(np.min(x))), max(lo[2], float(np.max(x)))
        if y is not None:
            y = np.asarray(y, dtype=float)
            lo[3], lo[4] = min(lo[3], float(np.min(y))), max(lo[4], float(np.max(y)))

    def apply(self, pad: float = 0.06):
        for ax, x0, x1, y0, y1 in self.r.values():
            if x1 > x0:
                ax.set_xlim(x0, x0 + (x1 - x0) * (1 + pad / 2))
            if math.isfinite(y0) and y1 > y0:
                d = (y1 - y0) * pad
                ax.set_ylim(y0 - d, y1 + d)


def _sel(lg, a: float, b: float) -> np.ndarray:
    t = lg.t
    return np.arange(int(np.searchsorted(t, a, side="left")),
                     int(np.searchsorted(t, b, side="right")))


def _notes(exp: Source, models: dict, extra=()) -> list[str]:
    out = []
    if exp.synthetic:
        out.append("experiment data are SYNTHETIC (generated by scoutsim, not robot data)")
    for src in _sources(exp, models):
        rep = src.representative()
        if rep is None:
            out.append(f"{src.label}: no complete stride to show "
                       f"({src.status if src.status != 'ok' else 'record too short'})")
    out += list(extra)
    return out


def _finish(fig: Figure, title: str, notes: list[str], path):
    import textwrap
    text = "\n".join(textwrap.wrap("; ".join(notes), 140)) if notes else ""
    fig.suptitle(title + ("\n" + text if text else ""), fontsize=10)
    save_figure(fig, path)
    return fig


def _leg_window(lg, stride, leg: str):
    """(t_a, t_b) of one step of ``leg``: back = the stride; front = from the first front
    lift-off at or after the stride's start to the next front lift-off (None if absent)."""
    if leg == "back":
        return stride.t_start, stride.t_end
    lo = lg.liftoff_times("front")
    k = int(np.searchsorted(lo, stride.t_start - 1e-12))
    if k + 1 < len(lo):
        return float(lo[k]), float(lo[k + 1])
    if k >= 2:  # the record ends: the step before
        return float(lo[k - 2]), float(lo[k - 1])
    return None


def _state_wave(ax, t, states, kw, label=None):
    lv = np.asarray(STATE_LEVELS)[np.clip(np.asarray(states, dtype=int), 0, 2)]
    ax.plot(t, lv, drawstyle="steps-post", label=label, **kw)


def _clip_note(exp: Source, mods: dict) -> list[str]:
    srcs = _sources(exp, mods)
    if not any((r := s.representative()) is not None and r[2] for s in srcs):
        return []
    faint = [s.label for s in srcs if (r := s.representative()) is not None and not r[2]]
    if not faint:
        return []
    return [f"{', '.join(faint)}: no steady stride, the last (transient) stride drawn faint "
            "and clipped to the steady strides' range"]


def _state_axis(ax):
    ax.set_yticks([0.0, 0.5, 1.0], ["retraction", "brake", "flight"], fontsize=7)
    ax.set_ylim(-0.2, 1.2)
    ax.set_ylabel("leg state [-]")


# -----------------------------------------------------------------------------------------
# Fig. 5
# -----------------------------------------------------------------------------------------
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
    torso = np.column_stack([corners[:, 0] * c - corners[:, 1] * s,
                             y + corners[:, 0] * s + corners[:, 1] * c])
    legs = {}
    for i, name in enumerate(_LEGS):
        sl = (2 * i - 1) * rob.half_hip_spacing
        hx, hy = sl * c, y + sl * s
        g = th + float(np.asarray(log.leg_angle(name))[k])
        state = int(np.asarray(log.leg_state(name))[k])
        if log.has(f"leg_length_{name}_m"):
            ll = float(np.asarray(log.leg_length(name))[k])
        elif state != 0 and math.cos(g) > 0.2:
            ll = min(hy / math.cos(g), rob.leg_rest_length)
        else:
            ll = rob.leg_rest_length
        legs[name] = dict(hip=(hx, hy), toe=(hx + ll * math.sin(g), hy - ll * math.cos(g)),
                          state=state)
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
            ax.plot([hx + x0, tx + x0], [hy, ty], color=state_colors[leg["state"] % 3],
                    lw=2.2 if name == "back" else 1.6, ls="-" if name == "back" else "--",
                    solid_capstyle="round")
            ax.plot([tx + x0], [ty], "o", color="k", ms=2.5)
        ax.text(x0, float(np.max(pose["torso"][:, 1])) + 0.04, f"({chr(97 + j)})",
                ha="center", fontsize=8)
    ax.axhline(0.0, color="k", lw=0.8)
    for lab, col in zip(LEG_STATE_NAMES, state_colors):
        ax.plot([], [], color=col, lw=2, label=lab)
    ax.plot([], [], color="0.3", lw=2, label="back leg")
    ax.plot([], [], color="0.3", lw=1.6, ls="--", label="front leg")
    ax.set_aspect("equal")
    ax.set_xlim(-0.5 * spacing, (len(times) - 0.5) * spacing)
    ax.set_ylim(-0.03, 0.52)
    ax.set_xticks([])
    ax.set_xlabel("robot at the marked times, laid side by side (forward travel not to "
                  "scale) [m]", fontsize=8)
    ax.set_ylabel("height [m]")
    ax.legend(loc="upper left", fontsize=7, ncol=1, frameon=False,
              bbox_to_anchor=(1.0, 1.0))


def fig5(logs, path=None, transient_s: float = 2.0, robot=None,
         n_snapshots: int = 6) -> Figure:
    """Experiment over a run with the studied stride (paper Fig. 5): snapshots of the robot
    through the stride (top, drawn from the logged pitch, height, leg angles and leg states,
    legs coloured by controller state), pitch [deg] and COM height [m] of the run holding
    the representative steady stride, that stride shaded and the snapshot times marked.
    ``robot``: geometry for the drawing (default Scout II)."""
    if not (isinstance(n_snapshots, int) and 1 <= n_snapshots <= 12):
        raise ValueError(f"n_snapshots = {n_snapshots!r} is not allowed: must be an integer "
                         "in [1, 12]")
    exp = _experiment(logs, transient_s)
    rep = exp.representative()
    lg = rep[0] if rep is not None else exp.logs[0]
    fig = Figure(figsize=(11, 7), layout="constrained")
    gs = fig.add_gridspec(3, 2, height_ratios=[0.9, 1, 1], width_ratios=[1.7, 1])
    ax_s = fig.add_subplot(gs[0, :])
    ax_p = fig.add_subplot(gs[1, 0])
    ax_h = fig.add_subplot(gs[2, 0], sharex=ax_p)
    ax_pz = fig.add_subplot(gs[1, 1])
    ax_hz = fig.add_subplot(gs[2, 1], sharex=ax_pz)
    pitch = np.asarray(lg.pitch) * _DEG
    height = np.asarray(lg.height)
    for ax_a, ax_b in ((ax_p, ax_h), (ax_pz, ax_hz)):
        ax_a.plot(lg.t, pitch, color="k", lw=1.0)
        ax_b.plot(lg.t, height, color="k", lw=1.0)
    notes = []
    if rep is not None:
        _, st, steady = rep
        for ax in (ax_p, ax_h, ax_pz, ax_hz):
            ax.axvspan(st.t_start, st.t_end, color="tab:orange", alpha=0.3, lw=0,
                       label=f"{'steady' if steady else 'not steady'} stride studied "
                             f"({st.t_start:.3f}-{st.t_end:.3f} s)")
        ax_p.legend(loc="upper right", fontsize=8)
        times = st.t_start + (st.t_end - st.t_start) * np.arange(n_snapshots) / n_snapshots
        _draw_snapshots(ax_s, lg, times, robot)
        for j, tj in enumerate(times):
            for ax in (ax_pz, ax_hz):
                ax.axvline(tj, color="0.4", lw=0.6, ls=":")
            ax_pz.annotate(f"({chr(97 + j)})", (tj, 1.0), xycoords=("data", "axes fraction"),
                           ha="center", va="bottom", fontsize=7)
        # the zoom: the studied stride and a stride either side
        T = st.t_end - st.t_start
        a, b = max(lg.t[0], st.t_start - T), min(lg.t[-1], st.t_end + T)
        k = _sel(lg, a, b)
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
    return _finish(fig, f"Experiment run {lg.name}: snapshots of one stride, pitch and COM "
                        "height (measured, 15 Hz low-pass; right: zoom)", notes, path)


# -----------------------------------------------------------------------------------------
# Fig. 8
# -----------------------------------------------------------------------------------------
def fig8(logs, models=None, path=None, transient_s: float = 2.0) -> Figure:
    """Pitch [deg] and COM height [m] over one stride, experiment and each model, time from
    the back-leg lift-off that starts the stride [s] (paper Fig. 8)."""
    exp, mods = _prepare(logs, models, transient_s)
    fig = Figure(figsize=(11, 4.5), layout="constrained")
    ax_p, ax_h = fig.subplots(1, 2)
    ext = _Extent()
    for i, src, lg, st, steady in _shown(exp, mods):
        k = _sel(lg, st.t_start, st.t_end)
        tt = lg.t[k] - st.t_start
        lab = f"{_tag(src, steady)}, period {st.period_s:.3f} s"
        th = np.asarray(lg.pitch)[k] * _DEG
        y = np.asarray(lg.height)[k]
        ax_p.plot(tt, th, label=lab, **_line_kw(src, i, steady))
        ax_h.plot(tt, y, label=lab, **_line_kw(src, i, steady))
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
    return _finish(fig, "Pitch and COM height over one stride (Fig. 8)",
                   _notes(exp, mods, _clip_note(exp, mods)), path)


# -----------------------------------------------------------------------------------------
# Figs. 9 and 10
# -----------------------------------------------------------------------------------------
def _step_figure(exp, mods, rows, title, path):
    """Columns back / front; ``rows`` = list of (ylabel, getter(lg, leg) -> values); plus
    the leg-state square wave row."""
    fig = Figure(figsize=(11, 2.6 * len(rows) + 2.0), layout="constrained")
    nr = len(rows) + 1
    axes = fig.subplots(nr, 2, sharex="col",
                        gridspec_kw={"height_ratios": [3] * len(rows) + [1.4]})
    missing = []
    ext = _Extent()
    for i, src, lg, st, steady in _shown(exp, mods):
        kw = _line_kw(src, i, steady)
        for c, leg in enumerate(_LEGS):
            win = _leg_window(lg, st, leg)
            if win is None:
                missing.append(f"{src.label}: no complete {leg} step")
                continue
            k = _sel(lg, *win)
            tt = lg.t[k] - win[0]
            for r, (_, get) in enumerate(rows):
                v = np.asarray(get(lg, leg))[k]
                axes[r, c].plot(tt, v, label=_tag(src, steady) if (r == 0) else None, **kw)
                if steady:
                    ext.add(axes[r, c], tt, v)
            _state_wave(axes[-1, c], tt, lg.leg_state(leg)[k], kw)
            if steady:
                ext.add(axes[-1, c], tt)
    ext.apply()
    for c, leg in enumerate(_LEGS):
        axes[0, c].set_title(f"{leg} leg")
        for r, (ylab, _) in enumerate(rows):
            axes[r, c].set_ylabel(ylab)
            axes[r, c].grid(True, lw=0.4, alpha=0.5)
            axes[r, c].axhline(0.0, color="0.6", lw=0.5)
        _state_axis(axes[-1, c])
        axes[-1, c].grid(True, lw=0.4, alpha=0.5)
        axes[-1, c].set_xlabel(f"time from {leg}-leg lift-off [s]")
    axes[0, 0].legend(loc="best", fontsize=7)
    return _finish(fig, title, _notes(exp, mods, missing + _clip_note(exp, mods)), path)


def fig9(logs, models=None, path=None, transient_s: float = 2.0) -> Figure:
    """Back (left) and front (right) leg angles [deg] and rates [deg/s] relative to the
    torso over one step, each leg from its own lift-off, with the leg-state square wave
    (flight high, stance-retraction low, stance-brake medium) (paper Fig. 9). Angles are as
    the hip encoders log them (motor-side angle for Model II)."""
    exp, mods = _prepare(logs, models, transient_s)
    rows = [("leg angle [deg]", lambda lg, leg: np.asarray(lg.leg_angle(leg)) * _DEG),
            ("leg angular rate [deg/s]", lambda lg, leg: np.asarray(lg.leg_rate(leg)) * _DEG)]
    return _step_figure(exp, mods, rows, "Leg angles and rates over one step (Fig. 9)", path)


def fig10(logs, models=None, path=None, transient_s: float = 2.0) -> Figure:
    """Back and front hip torques per physical leg [N m] over one step: the experiment's
    estimated from motor current (N eta K_T i), the models' likewise; with the leg-state
    square wave (paper Fig. 10)."""
    exp, mods = _prepare(logs, models, transient_s)
    rows = [("hip torque per leg [N m]", lambda lg, leg: np.asarray(lg.hip_torque(leg)))]
    return _step_figure(exp, mods, rows, "Hip torques over one step, from motor current "
                                         "(Fig. 10)", path)


# -----------------------------------------------------------------------------------------
# Fig. 11
# -----------------------------------------------------------------------------------------
def _robot_dict(robot, mods: dict, exp: Source) -> dict:
    if robot is not None:
        return robot if isinstance(robot, dict) else dataclasses.asdict(robot)
    for src in mods.values():
        if src.result is not None and (src.result.provenance or {}).get("robot"):
            return src.result.provenance["robot"]
    for lg in exp.logs:
        r = ((lg.meta.get("simulation") or {}).get("robot"))
        if r:
            return r
    return dataclasses.asdict(RobotParameters())


def fig11(logs, models=None, path=None, robot=None, transient_s: float = 2.0) -> Figure:
    """Leg angular speed [rad/s] against hip torque per leg [N m] (paper Fig. 11): the
    experiment's steady-stride samples as dots, each source's representative step as a
    line, and the actuator limits of :func:`scoutsim.presentation.plots.motor_limits` (current limit,
    torque-speed lines at the battery voltage). ``robot``: RobotParameters or dict for the
    limits (default: the models' parameters, else Scout II)."""
    exp, mods = _prepare(logs, models, transient_s)
    lim = motor_limits(_robot_dict(robot, mods, exp))
    fig = Figure(figsize=(11, 5.0), layout="constrained")
    axes = fig.subplots(1, 2, sharey=True)
    missing = []
    tmax, wmax = lim["tau_current"], lim["w_no_load"]
    for c, leg in enumerate(_LEGS):
        ax = axes[c]
        pts = [(lg, s) for lg, s in exp.steady]
        if pts:
            xs = np.concatenate([np.asarray(lg.hip_torque(leg))[_sel(lg, s.t_start, s.t_end)]
                                 for lg, s in pts])
            ys = np.concatenate([np.asarray(lg.leg_rate(leg))[_sel(lg, s.t_start, s.t_end)]
                                 for lg, s in pts])
            ax.plot(xs, ys, ls="none", marker=".", ms=1.5, color="0.65", alpha=0.5,
                    label=f"experiment, all {len(pts)} steady strides")
        for i, src, lg, st, steady in _shown(exp, mods):
            win = _leg_window(lg, st, leg)
            if win is None:
                missing.append(f"{src.label}: no complete {leg} step")
                continue
            k = _sel(lg, *win)
            x = np.asarray(lg.hip_torque(leg))[k]
            y = np.asarray(lg.leg_rate(leg))[k]
            ax.plot(x, y, label=f"{_tag(src, steady)}, one step", **_line_kw(src, i, steady))
        xl, yl = 1.15 * tmax, 1.15 * wmax
        draw_motor_limits(ax, lim, xl, yl, current_ls=(0, (5, 2)), line_ls=(0, (6, 2, 1, 2)))
        ax.set_xlabel("hip torque per leg [N m]")
        ax.set_ylabel("leg angular speed (encoder) [rad/s]")
        ax.set_title(f"{leg} leg")
    return _finish(fig, "Motor saturation: leg speed against hip torque (Fig. 11)",
                   _notes(exp, mods, missing), path)


# -----------------------------------------------------------------------------------------
# Fig. 12
# -----------------------------------------------------------------------------------------
def fig12(table, path=None) -> Figure:
    """Bar chart of the mean (solid) and max (light) percent error per metric and model,
    from an :class:`~scoutsim.validation.errors.ErrorTable` (paper Fig. 12). Models without
    errors (no steady strides) are marked n/a and the figure says why."""
    from ..validation.errors import ERROR_METRICS, METRIC_LABELS, ErrorTable
    if not isinstance(table, ErrorTable):
        raise TypeError(f"fig12 needs an ErrorTable (from errors.compare), not "
                        f"{type(table).__name__}")
    models = list(dict.fromkeys(r.model for r in table.rows))
    metrics = [m for m in ERROR_METRICS if any(r.metric == m for r in table.rows)]
    fig = Figure(figsize=(11, 5.0), layout="constrained")
    ax = fig.subplots()
    n = max(len(models), 1)
    width = 0.8 / n
    x = np.arange(len(metrics))
    top = 0.0
    notes, na = [], []
    for i, m in enumerate(models):
        col, _ = model_style(m, i)
        mean = np.array([table.row(m, k).mean_percent_error for k in metrics], dtype=float)
        mx = np.array([table.row(m, k).max_percent_error for k in metrics], dtype=float)
        xi = x - 0.4 + width * (i + 0.5)
        ok = np.isfinite(mean)
        if ok.any():
            ax.bar(xi[ok], mx[ok], width * 0.9, color=col, alpha=0.3, edgecolor=col, lw=0.8,
                   label=f"{model_label(m)} max")
            ax.bar(xi[ok], mean[ok], width * 0.9, color=col, label=f"{model_label(m)} mean")
            top = max(top, float(np.nanmax(np.where(np.isfinite(mx[ok]), mx[ok], 0.0))))
        else:
            from matplotlib.patches import Patch
            na.append(Patch(facecolor="none", edgecolor=col, hatch="//",
                            label=f"{model_label(m)}: n/a (no steady strides)"))
        for xx in xi[~ok]:
            ax.text(xx, 0.0, "n/a", rotation=90, ha="center", va="bottom", fontsize=7,
                    color=col)
        if not ok.any():
            st = next((r.status for r in table.rows if r.model == m), "")
            notes.append(f"{model_label(m)}: {st}")
    ax.set_xticks(x, [METRIC_LABELS.get(k, k) for k in metrics], rotation=15)
    ax.set_xlabel("gait metric [-]")
    ax.set_ylabel("percent error vs experiment [%]")
    ax.set_ylim(0, max(1.0, 1.15 * top))
    ax.grid(True, axis="y", lw=0.4, alpha=0.5)
    h, _ = ax.get_legend_handles_labels()
    ax.legend(handles=h + na, loc="upper left", fontsize=8, ncol=max(1, len(models)))
    if table.synthetic:
        notes.insert(0, "experiment data are SYNTHETIC (generated by scoutsim)")
    return _finish(fig, f"Percent errors, mean and max over {table.n_experiment_strides} "
                        f"experimental steady strides from {table.n_runs} run(s) (Fig. 12)",
                   notes, path)


# -----------------------------------------------------------------------------------------
# phase comparison, single logs, everything
# -----------------------------------------------------------------------------------------
def fig_phase(logs, models=None, path=None, transient_s: float = 2.0, n_phase: int = 101):
    """Figure of the phase-normalized comparison
    (:func:`scoutsim.validation.phase.phase_compare` + :func:`~.phase_plots.plot_phase`)."""
    exp, mods = _prepare(logs, models, transient_s)
    return plot_phase(phase_compare(exp, mods, n_phase=n_phase, transient_s=transient_s),
                      path)


def plot_log(log, path=None, t_range=None) -> Figure:
    """Time histories of one log: measured pitch [deg], COM height [m], leg angles [deg]
    with the leg-state square waves, hip torques [N m] (from current)."""
    t = np.asarray(log.t)
    if t_range is not None:
        t0, t1 = (float(v) for v in t_range)
        if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
            raise ValueError(f"t_range = {t_range!r} is not allowed: must be finite with "
                             "t1 > t0")
        k = np.flatnonzero((t >= t0) & (t <= t1))
        if k.size == 0:
            raise ValueError(f"t_range = {t_range!r} holds no samples (the log covers "
                             f"{t[0]:.3f}-{t[-1]:.3f} s)")
    else:
        k = np.arange(t.size)
    tt = t[k]
    fig = Figure(figsize=(10, 10), layout="constrained")
    ax_p, ax_h, ax_a, ax_s, ax_tau = fig.subplots(
        5, 1, sharex=True, gridspec_kw={"height_ratios": [3, 3, 3, 1.6, 3]})
    ax_p.plot(tt, np.asarray(log.pitch)[k] * _DEG, color="k", lw=1.0)
    ax_p.set_ylabel("pitch [deg]")
    ax_h.plot(tt, np.asarray(log.height)[k], color="k", lw=1.0)
    ax_h.set_ylabel("COM height [m]")
    for li, (leg, col) in enumerate(zip(_LEGS, ("tab:blue", "tab:red"))):
        ax_a.plot(tt, np.asarray(log.leg_angle(leg))[k] * _DEG, color=col, lw=1.0,
                  label=f"{leg}")
        lv = np.asarray(STATE_LEVELS)[log.leg_state(leg)[k]] + (0.04 if li else -0.04)
        ax_s.plot(tt, lv, color=col, lw=1.0, drawstyle="steps-post", label=leg)
        ax_tau.plot(tt, np.asarray(log.hip_torque(leg))[k], color=col, lw=1.0, label=leg)
    ax_a.set_ylabel("leg angle [deg]")
    ax_a.legend(loc="upper right", fontsize=8)
    _state_axis(ax_s)
    ax_tau.set_ylabel("hip torque per leg [N m]")
    ax_tau.set_xlabel("time [s]")
    for ax in (ax_p, ax_h, ax_a, ax_s, ax_tau):
        ax.grid(True, lw=0.4, alpha=0.5)
    ax_tau.set_xlim(tt[0], tt[-1])
    title = f"Log {log.name}"
    if log.synthetic:
        title += " (SYNTHETIC: generated by scoutsim)"
    fig.suptitle(title, fontsize=10)
    save_figure(fig, path)
    return fig


def write_figures(logs, models=None, out_dir=".", table=None, fmt: str = "png",
                  transient_s: float = 2.0) -> dict:
    """Write fig5, fig8, fig9, fig10, fig11, fig12 (needs an ErrorTable: ``table``, or
    ``models`` being one) and phase (+ phase_rms.csv) to ``out_dir`` in format ``fmt``
    (png, pdf, svg). Returns name -> path of what was written."""
    from ..validation.errors import ErrorTable
    if fmt not in ("png", "pdf", "svg"):
        raise ValueError(f"fmt = {fmt!r} is not allowed: must be png, pdf or svg")
    if table is None and isinstance(models, ErrorTable):
        table = models
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    exp, mods = _prepare(logs, models, transient_s)
    paths = {}

    def emit(name, fn, *a, **kw):
        p = out / f"{name}.{fmt}"
        fn(*a, path=p, **kw)
        paths[name] = p

    emit("fig5", fig5, exp, transient_s=transient_s)
    emit("fig8", fig8, exp, mods, transient_s=transient_s)
    emit("fig9", fig9, exp, mods, transient_s=transient_s)
    emit("fig10", fig10, exp, mods, transient_s=transient_s)
    emit("fig11", fig11, exp, mods, transient_s=transient_s)
    if table is not None:
        emit("fig12", fig12, table)
    cmp = phase_compare(exp, mods, transient_s=transient_s)
    p = out / f"phase.{fmt}"
    plot_phase(cmp, p)
    paths["phase"] = p
    paths["phase_rms"] = cmp.to_csv(out / "phase_rms.csv")
    return paths

