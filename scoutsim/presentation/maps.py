"""Maps over a grid of runs: the basin of the bounding cycle over initial forward speed and
pitch rate (:mod:`scoutsim.analysis.basin`), and a swept quantity over two swept
parameters (:mod:`scoutsim.analysis.sweep`). Speeds in m/s, rates in deg/s, angles in
degrees on the axes.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from ..parameters import floor_label
from .style import model_label, save_figure

__all__ = ["plot_basin_map", "plot_sweep_map"]


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
            vel: list[list[list[float]]] = [[[] for _ in speeds] for _ in rates]
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
            level = np.where(
                np.isnan(frac), np.nan, np.where(frac >= 1.0, 2, np.where(frac > 0, 1, 0))
            )
            ds, dr = (
                speeds[1] - speeds[0] if len(speeds) > 1 else 0.2,
                rates[1] - rates[0] if len(rates) > 1 else 50.0,
            )
            ax.imshow(
                level,
                origin="lower",
                cmap=cmap,
                vmin=0,
                vmax=2,
                aspect="auto",
                extent=(
                    speeds[0] - ds / 2,
                    speeds[-1] + ds / 2,
                    rates[0] - dr / 2,
                    rates[-1] + dr / 2,
                ),
            )
            for a in range(len(rates)):
                for b in range(len(speeds)):
                    if vel[a][b]:
                        ax.text(
                            speeds[b],
                            rates[a],
                            f"{np.mean(vel[a][b]):.2f}",
                            ha="center",
                            va="center",
                            fontsize=6,
                        )
            if default_start is not None:
                ax.plot(
                    [default_start[0]],
                    [default_start[1]],
                    marker="*",
                    ms=12,
                    mfc="white",
                    mec="black",
                )
            valid = cnt.sum()
            n_ok = np.nansum(share)
            ax.set_title(
                f"{model_label(m)}, {floor_label(mu)}: "
                f"{n_ok / valid if valid else float('nan'):.2f}",
                fontsize=9,
            )
            if i == len(models) - 1:
                ax.set_xlabel("initial forward speed [m/s]")
            if j == 0:
                ax.set_ylabel("initial pitch rate [deg/s]")
    fig.legend(
        handles=[
            Patch(color=cmap(2), label="bounds (every height)"),
            Patch(color=cmap(1), label="bounds (some heights)"),
            Patch(color=cmap(0), label="falls / no steady bound"),
        ],
        loc="outside lower center",
        ncol=3 if len(floors) > 1 else 1,
        fontsize=8,
    )
    fig.suptitle(
        ("" if controller is None else f"{controller} controller\n")
        + "Basin of the bounding cycle"
        + (" " if len(floors) > 1 else "\n")
        + "(heights "
        + ", ".join(f"{h:g}" for h in heights)
        + " m; labels: cycle speed m/s)",
        fontsize=10,
    )
    save_figure(fig, path)
    return fig


def plot_sweep_map(sweep, x: str, y: str, value: str = "mean_speed_m_s", path=None) -> Figure:
    """Map of ``value`` over two swept parameters of a grid sweep
    (:class:`scoutsim.analysis.sweep.SweepResult`); points that do not reach steady bounding
    are marked x, and on a map of an orbit column (``orbit_*``) the bounding points without
    a periodic orbit ?, their reason in the table's ``orbit_status``. Each axis in its unit (``sweep.axis_label``: an angle in degrees);
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
        factor, label = sweep.axis_label(name)
        return vals * factor, label

    gx, lx = edge(x, ux)
    gy, ly = edge(y, uy)
    fig = Figure(figsize=(6.5, 5), layout="constrained")
    ax = fig.add_subplot()
    m = ax.pcolormesh(gx, gy, Z, shading="nearest", cmap="viridis")
    fig.colorbar(m, ax=ax, label=value)
    orbit_value = value.startswith("orbit_")
    n_missing = 0
    for i in range(len(uy)):
        for j in range(len(ux)):
            if not steady[i, j]:
                ax.plot(gx[j], gy[i], "x", color="0.4", ms=6)
            elif orbit_value and np.isnan(Z[i, j]):
                # bounds steadily, but no periodic orbit was found: the table's
                # orbit_status says why
                ax.plot(gx[j], gy[i], "o", mfc="none", mec="k", ms=9)
                ax.annotate("?", (gx[j], gy[i]), ha="center", va="center", fontsize=8)
                n_missing += 1
    ax.set_xlabel(lx)
    ax.set_ylabel(ly)
    note = "x: not steady bounding"
    if orbit_value:
        note += f"; ?: bounding, no periodic orbit ({n_missing}; why: orbit_status)"
    ax.set_title(f"{value}\n({note})", fontsize=9)
    save_figure(fig, path)
    return fig
