"""The torque-speed plane of a run (paper Fig. 11): leg angular speed [rad/s] against the
applied hip torque per physical leg [N m], every sample a dot coloured by the controller
leg state, with the actuator's limits (docs/specification.md section 4): the current limit
and the torque-speed lines at the battery voltage.

    fig = plot_torque_speed(result, "both", "ts.png")

:func:`motor_limits` and :func:`draw_motor_limits` are shared with the paper's Fig. 11
(:mod:`scoutsim.presentation.saturation_figure`).
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..names import Leg, LegState
from ..parameters import RobotParameters
from .run_parts import behaviour_text, run_model_label
from .style import LEG_NAMES, LEG_STATE_LINE_COLORS, leg_index, save_figure

__all__ = ["plot_torque_speed", "motor_limits", "draw_motor_limits"]


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
    return {
        "N": r.gear_ratio,
        "eta": r.efficiency,
        "tau_current": r.max_leg_torque,
        "tau_stall": r.stall_torque,
        "w_no_load": r.no_load_speed,
        "slope": r.torque_speed_slope,
    }


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
        for state in LegState:
            m = states == state
            if np.any(m):
                ax.plot(
                    tau[m],
                    w[m],
                    ls="none",
                    marker=".",
                    ms=2.0,
                    alpha=0.6,
                    color=LEG_STATE_LINE_COLORS[state],
                    label=state.label,
                )
    else:
        ax.plot(tau, w, ls="none", marker=".", ms=2.0, alpha=0.6, color="tab:gray", label="samples")

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
            ax.plot(
                sign * lim["tau_stall"] - lim["slope"] * ww,
                ww,
                color="0.35",
                lw=1.0,
                ls=line_ls,
                label=(f"torque-speed lines ±V{note}" if sign > 0 else None),
            )
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
        legs: list[int] = list(Leg)
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
    import textwrap

    fig.suptitle(
        "\n".join(
            textwrap.wrap(
                f"Torque-speed, {run_model_label(result)}: {behaviour_text(result)}", 50 * len(legs)
            )
        ),
        fontsize=10,
    )
    save_figure(fig, path)
    return fig
