"""A family of periodic gaits along one parameter (:mod:`scoutsim.analysis.passive_family`):
touchdown angles, period and mean speed, and the multipliers' moduli along the branch, with
the located bifurcations marked."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .style import save_figure

__all__ = ["plot_family"]

#: the bifurcations drawn as lines, and their colours (a change of the number of strides
#: per period of a sampled loop is written at its point instead)
_MARK = {"fold": "tab:red", "branch point": "tab:purple", "period doubling": "tab:orange",
         "torus": "tab:green"}  # fmt: skip


def plot_family(
    rows, parameter: str, *, title: str = "", marks=(), path=None, label: str | None = None
) -> Figure:
    """The branch ``rows`` (dicts with ``parameter``, ``touchdown_angle_back_deg``,
    ``touchdown_angle_front_deg``, ``period_s``, ``strides``, ``mean_speed_m_s``,
    ``stable``, ``bifurcation``, ``multipliers`` as (real, imag) pairs of the period map
    and ``status``), in the order of the branch
    (:class:`~scoutsim.analysis.gait_family.GaitFamily`).

    Top: the touchdown angles from the world vertical [deg]; middle: the stride period
    (period / strides) [s] and the mean speed [m/s]; bottom: the multipliers' moduli per
    stride (to the power 1/strides; filled where the orbit is stable, open where not)
    against the unit circle. A located bifurcation is a dashed line through all three,
    labelled; a change of the number of strides per period is the number written at the
    point; a value without an orbit a grey cross on the unit line. ``marks``:
    (parameter value, label) pairs drawn as dotted lines (e.g. orbits documented
    elsewhere). ``label``: the parameter axis's label, with its unit (default: the
    parameter's name). Saved by suffix if ``path`` is given."""
    lost = [r for r in rows if r.get("status", "ok") != "ok"]
    rows = [r for r in rows if r.get("status", "ok") == "ok"]
    p = np.array([r[parameter] for r in rows], dtype=float)
    fig = Figure(figsize=(7.5, 7.2), layout="constrained")
    ax_td, ax_t, ax_m = fig.subplots(3, 1, sharex=True)
    for key, label, color in (
        ("touchdown_angle_back_deg", "back", "tab:blue"),
        ("touchdown_angle_front_deg", "front", "tab:orange"),
    ):
        ax_td.plot(p, [r[key] for r in rows], ".-", ms=3, color=color, label=label)
    ax_td.set_ylabel("touchdown angle [deg]\nfrom the world vertical")
    ax_td.legend(fontsize=8, loc="lower right")
    strides = np.array([max(1, int(r.get("strides", 1))) for r in rows])
    period = np.array([r["period_s"] for r in rows], dtype=float)
    ax_t.plot(p, period / strides, ".-", ms=3, color="k")
    for x, y, n in zip(p, period / strides, strides):
        if n > 1:
            ax_t.annotate(f"{n}", (x, y), xytext=(0, 4), textcoords="offset points",
                          ha="center", fontsize=6, color="tab:brown")  # fmt: skip
    if np.any(strides > 1):
        ax_t.set_title("numbers: strides per period of a cycle of several strides", fontsize=7)
    ax_t.set_ylabel("stride period [s]\n(period / strides)")
    ax_v = ax_t.twinx()
    ax_v.plot(p, [r["mean_speed_m_s"] for r in rows], "--", color="tab:gray")
    ax_v.set_ylabel("mean speed [m/s] (dashed)")
    width = max((len(r["multipliers"]) for r in rows), default=0)
    stable = np.array([bool(r["stable"]) for r in rows])
    for k in range(width):
        mod = np.array(
            [abs(complex(*r["multipliers"][k])) ** (1.0 / n) if k < len(r["multipliers"])
             else np.nan for r, n in zip(rows, strides)]
        )  # fmt: skip
        ax_m.plot(p, mod, "-", color="0.75", lw=0.8)
        ax_m.plot(p[stable], mod[stable], "o", ms=3, color="k")
        ax_m.plot(p[~stable], mod[~stable], "o", ms=3, mfc="none", color="k")
    ax_m.axhline(1.0, color="tab:red", lw=0.8)
    if lost:
        ax_m.plot([r[parameter] for r in lost], [1.0] * len(lost), "x", color="0.5",
                  label="no orbit")  # fmt: skip
        ax_m.legend(fontsize=7, loc="lower right")
    ax_m.set_yscale("log")
    ax_m.set_ylabel("|multiplier| per stride\n(filled: stable orbit)")
    ax_m.set_xlabel(label or parameter)
    for i, r in enumerate(x for x in rows if x["bifurcation"] in _MARK):
        color = _MARK[r["bifurcation"]]
        for ax in (ax_td, ax_t, ax_m):
            ax.axvline(r[parameter], color=color, ls="--", lw=1.0)
        ax_td.annotate(
            f"{r['bifurcation']}\n{r[parameter]:.4g}",
            (r[parameter], 1.0 - 0.18 * (i % 3)),
            xycoords=("data", "axes fraction"),
            xytext=(3, -3),
            textcoords="offset points",
            va="top",
            fontsize=7,
            color=color,
        )
    for value, label in marks:
        for ax in (ax_td, ax_t, ax_m):
            ax.axvline(value, color="0.5", ls=":", lw=0.8)
        ax_m.annotate(
            label, (value, 0.0), xycoords=("data", "axes fraction"), xytext=(2, 3),
            textcoords="offset points", fontsize=6, color="0.4", rotation=90,
        )  # fmt: skip
    if title:
        ax_td.set_title(title, fontsize=9)
    save_figure(fig, path)
    return fig
