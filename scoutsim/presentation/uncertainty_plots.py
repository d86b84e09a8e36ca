"""The figures of an uncertainty study (:mod:`scoutsim.analysis.uncertainty`): the Sobol'
indices of each metric as bars with their confidence intervals as whiskers, and each
metric's distribution over the runs as a histogram."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..io.run_directory import atomic_write
from .style import save_figure

__all__ = ["plot_indices", "plot_distributions", "plot_uncertainty"]


def _grid(k: int, width: float, height: float):
    cols = min(k, 3)
    rows = -(-k // cols)
    fig = Figure(figsize=(width * cols, height * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for ax in axes[k:]:
        ax.set_visible(False)
    return fig, axes


def plot_indices(study, path=None) -> Figure:
    """First-order (S1) and total (ST) Sobol' indices of every metric whose indices were
    computed, one panel per metric, a pair of bars per parameter with the confidence
    interval as whiskers; a metric not computed is named with its reason in the title.
    Saved by suffix if ``path`` is given."""
    metrics = list(study.indices)
    names = study.names
    # horizontal bars, a row per parameter: the names stay readable however many there are
    fig, axes = _grid(max(len(metrics), 1), 4.6, max(2.6, 0.5 + 0.32 * len(names)))
    y = np.arange(len(names))
    for ax, metric in zip(axes, metrics):
        ix = study.indices[metric]
        for off, key, color in ((-0.18, "S1", "tab:blue"), (0.18, "ST", "tab:orange")):
            v = getattr(ix, key)[0]
            lo, hi = getattr(ix, f"{key}_low")[0], getattr(ix, f"{key}_high")[0]
            err = np.vstack([np.maximum(v - lo, 0.0), np.maximum(hi - v, 0.0)])
            ax.barh(y + off, v, 0.36, color=color, label=key, xerr=err, capsize=2)
        ax.axvline(0.0, color="k", lw=0.6)
        ax.set_yticks(y, names, fontsize=7)
        ax.invert_yaxis()  # the first parameter on top
        ax.set_title(metric, fontsize=9)
        ax.set_xlabel("Sobol' index [-]")
    if metrics:
        axes[0].legend(fontsize=7)
    else:
        axes[0].text(0.5, 0.5, "no indices computed", ha="center", transform=axes[0].transAxes)
    if study.not_computed:
        fig.suptitle(
            f"indices not computed for {len(study.not_computed)} metrics (summary.json: why)",
            fontsize=8,
            color="0.3",
        )
    save_figure(fig, path)
    return fig


def plot_distributions(study, path=None) -> Figure:
    """A histogram of every metric: ``bounds`` over every run (1: it bounds, 0: it does
    not), a gait metric over the runs that bound. Saved by suffix if ``path`` is given."""
    metrics = study.metrics
    fig, axes = _grid(len(metrics), 3.2, 2.4)
    for ax, metric in zip(axes, metrics):
        v = study.metric(metric)
        v = v[np.isfinite(v)]
        if v.size:
            ax.hist(v, bins=min(20, max(v.size // 2, 2)), color="tab:blue", alpha=0.8)
        else:
            ax.text(0.5, 0.5, "no values", ha="center", transform=ax.transAxes)
        ax.set_xlabel(metric, fontsize=8)
        ax.set_ylabel("runs")
    save_figure(fig, path)
    return fig


def plot_uncertainty(study, out=None) -> list[Path]:
    """Both figures, ``indices.png`` and ``distributions.png``, written atomically into the
    directory ``out``; returns their paths (none without ``out``)."""
    if out is None:
        return []
    out = Path(out)
    return [
        atomic_write(out / "indices.png", lambda p: plot_indices(study, p)),
        atomic_write(out / "distributions.png", lambda p: plot_distributions(study, p)),
    ]
