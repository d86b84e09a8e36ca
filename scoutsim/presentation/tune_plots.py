"""The convergence of a tuning (:mod:`scoutsim.analysis.tune`): every evaluation's score
and the best so far, and each tuned parameter, against the evaluation number."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .style import save_figure

__all__ = ["plot_tune_convergence"]


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
    ax.plot(
        n[~feasible],
        np.minimum(score[~feasible], 3e4),
        "o",
        ms=3,
        mfc="none",
        color="tab:red",
        label="penalised (a constraint broken)",
    )
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
    ax.set_title(
        f"tuning: {what}, best {tuning.best['score']:.4g} at evaluation {tuning.best['evaluation']}"
    )
    ax.legend(fontsize=7, loc="upper right")
    order = np.array([r["score"] for r in rows], dtype=float)
    best_idx = np.array([int(np.argmin(order[: i + 1])) for i in range(len(rows))])
    for a, p in zip(axes[1:], tuning.parameters):
        v = np.array([r[p.name] for r in rows], dtype=float)
        a.plot(n, v, ".", ms=3, color="0.6")
        a.step(n, v[best_idx], where="post", color="k", lw=1.2)
        a.set_ylabel(p.name.replace("controller.", "").replace("robot.", ""), fontsize=7)
    axes[-1].set_xlabel("evaluation")
    save_figure(fig, path)
    return fig
