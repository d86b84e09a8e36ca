"""The whole-run overview of a long run's figure (:func:`~scoutsim.presentation.plots.plot_run`
with ``overview``): torso pitch [deg] and COM height [m] as their range over one stride
(running maximum and minimum: how the oscillation settles, readable over hundreds of
strides where the trace itself fills a solid band), and the period [s] of every stride,
the steady ones filled; the detail window and a fall marked on each. Times in seconds.
"""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from scipy.ndimage import maximum_filter1d, minimum_filter1d

__all__ = ["running_range", "draw_overview", "DEFAULT_WINDOW_S"]

#: Window [s] of the running range of a run without two strides (about a Scout II stride).
DEFAULT_WINDOW_S = 0.25
_BAND = "0.82"
_DETAIL = "tab:blue"
_FALL = "crimson"


def running_range(t, values, window_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Running minimum and maximum of ``values`` over a centred window of ``window_s``
    [s] (in samples at the median sample spacing of ``t``; at least one sample)."""
    t = np.asarray(t, dtype=float)
    v = np.asarray(values, dtype=float)
    if v.size < 2:
        return v.copy(), v.copy()
    dt = float(np.median(np.diff(t)))
    size = max(1, int(round(window_s / dt))) if dt > 0 else 1
    return (minimum_filter1d(v, size, mode="nearest"), maximum_filter1d(v, size, mode="nearest"))


def overview_strides(result):
    try:
        return list(result.strides)
    except Exception:  # a run too short or too broken for stride analysis
        return []


def draw_overview(fig, result, t0: float, t1: float) -> list:
    """Draw the overview in ``fig`` (a figure or subfigure): pitch and COM height ranges
    over one stride and the stride periods over the whole run, the detail window [t0, t1]
    [s] shaded; its legend above the panels. Returns the three axes."""
    axes = fig.subplots(1, 3, sharex=True)
    ax_p, ax_h, ax_s = axes
    t = np.asarray(result.t, dtype=float)
    strides = overview_strides(result)
    periods = np.array([s.period_s for s in strides])
    window = float(np.median(periods)) if periods.size >= 2 else DEFAULT_WINDOW_S
    for ax, v, label in (
        (ax_p, np.degrees(np.asarray(result.pitch, dtype=float)), "pitch [deg]"),
        (ax_h, np.asarray(result.height, dtype=float), "COM height [m]"),
    ):
        lo, hi = running_range(t, v, window)
        ax.fill_between(t, lo, hi, color=_BAND, lw=0)
        ax.plot(t, hi, color="k", lw=0.7)
        ax.plot(t, lo, color="k", lw=0.7)
        ax.set_ylabel(label)
    if strides:
        ts = np.array([s.t_start for s in strides])
        steady = np.array([bool(s.steady) for s in strides])
        ax_s.plot(
            ts[~steady], periods[~steady], "o", ms=3.5, mfc="none", mec="0.35", mew=0.8, ls="none"
        )
        ax_s.plot(ts[steady], periods[steady], "o", ms=3.5, color="k", ls="none")
    else:
        ax_s.text(
            0.5,
            0.5,
            "no complete stride",
            transform=ax_s.transAxes,
            ha="center",
            va="center",
            fontsize=9,
            color="0.3",
        )
    ax_s.set_ylabel("stride period [s]")
    fell = result.outcome == "fell"
    for ax in axes:
        ax.axvspan(t0, t1, color=_DETAIL, alpha=0.15, lw=0)
        if fell:
            ax.axvline(result.t_end, color=_FALL, lw=1.0, ls=":")
        ax.set_xlabel("time [s]")
        ax.grid(True, lw=0.4, alpha=0.5)
        if t.size:
            ax.set_xlim(float(t[0]), float(t[-1]))
    handles = [
        Patch(facecolor=_BAND, edgecolor="k", lw=0.7),
        Patch(facecolor=_DETAIL, alpha=0.15),
        Line2D([], [], marker="o", ms=4, color="k", ls="none"),
        Line2D([], [], marker="o", ms=4, mfc="none", mec="0.35", ls="none"),
    ]
    labels = [
        f"range over one stride ({window:.3f} s running max / min)",
        "detail window (below)",
        "steady stride",
        "other stride",
    ]
    if fell:
        handles.append(Line2D([], [], color=_FALL, lw=1.0, ls=":"))
        labels.append("fall")
    fig.legend(
        handles,
        labels,
        loc="outside upper center",
        ncol=len(labels),
        fontsize=8,
        frameon=False,
        title="whole run",
        title_fontsize=9,
    )
    return list(axes)
