"""The figure of an assumption study (:mod:`scoutsim.analysis.assumptions`): per case, the
percent difference of each gait metric from the reference as grouped bars, in the style
of the paper's Fig. 12; a case that does not bound, or that was not run, is marked with
its verdict instead of bars."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .style import save_figure

__all__ = ["plot_assumptions"]

#: how the figure names the metrics (the table's names, shortened)
_SHORT = {
    "mean_speed_m_s": "speed",
    "stride_frequency_hz": "stride freq.",
    "duty_factor_back": "duty back",
    "duty_factor_front": "duty front",
    "pitch_max_deg": "pitch max",
    "pitch_min_deg": "pitch min",
    "height_max_m": "height max",
    "height_min_m": "height min",
    "cost_of_transport": "cost of transport",
    "basin_fraction": "basin fraction",
}


def plot_assumptions(result, path=None, *, tolerance_percent: float | None = 25.0, title=None):
    """Grouped bars of ``result``'s percent differences (an
    :class:`~scoutsim.analysis.assumptions.AssumptionResult`): one group per case, one bar
    per metric; a case without bars is labelled with its verdict (fell, no steady
    bounding, absent, not switchable). Dotted lines at +-``tolerance_percent`` (the paper's
    Fig. 12 bound, 25 %; None: none). Saves to ``path`` (.png / .pdf / .svg) if given;
    returns the Figure."""
    from ..analysis.assumptions import METRICS

    metrics = list(METRICS)
    cases = [r for r in result.rows if r["case"] != result.reference]
    fig = Figure(figsize=(max(8.0, 0.9 * len(cases) + 2.0), 5.0), layout="constrained")
    ax = fig.add_subplot()
    width = 0.8 / len(metrics)
    colors = [f"C{i}" for i in range(len(metrics))]
    x = np.arange(len(cases))
    top = 5.0
    for j, m in enumerate(metrics):
        vals = [r.get(f"pct_{m}") for r in cases]
        ys = np.array([np.nan if v is None else v for v in vals], dtype=float)
        if np.isfinite(ys).any():
            top = max(top, float(np.nanmax(np.abs(ys))))
        ax.bar(
            x - 0.4 + (j + 0.5) * width,
            np.nan_to_num(ys),
            width,
            color=colors[j],
            label=_SHORT.get(m, m),
        )
    for i, r in enumerate(cases):
        if r.get("verdict") != "bounds":
            ax.text(
                x[i],
                0.05 * top,
                r.get("verdict", "")[:40],
                rotation=90,
                ha="center",
                va="bottom",
                fontsize=8,
                color="0.25",
            )
            ax.axvspan(x[i] - 0.45, x[i] + 0.45, color="0.92", zorder=0)
    if tolerance_percent is not None:
        for s in (-1.0, 1.0):
            ax.axhline(s * tolerance_percent, color="0.4", ls=":", lw=1.0)
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xticks(x, [r["case"] for r in cases], rotation=30, ha="right")
    ax.set_ylabel(f"difference from {result.reference} [%]")
    ax.set_ylim(-1.1 * top, 1.1 * top)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    controller = result.settings.get("controller", "")
    ax.set_title(
        title or f"{controller}: each case against {result.reference} (grey: no bars, see label)",
        fontsize=10,
    )
    save_figure(fig, path)
    return fig
