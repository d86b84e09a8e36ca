"""What the figures of one run share: the model's display name and the title (what the run
did), the legend above its axes, and the controller leg states drawn as shaded bands over
time (paper Sec. II, Table I: flight,
stance-retraction, stance-brake; colours of :mod:`scoutsim.presentation.style`). Times in
seconds.
"""

from __future__ import annotations

import numpy as np
from matplotlib.collections import PolyCollection

from ..names import LegState
from .style import LEG_STATE_COLORS, model_label


def run_model_label(result) -> str:
    """Display name of the run's model ("Model II"; :func:`~.style.model_label`)."""
    return model_label((result.provenance or {}).get("model"))


def is_part_of_run(result) -> bool:
    """Whether ``result`` holds only a window of its run (:meth:`SimulationResult.window
    <scoutsim.result.simulation_result.SimulationResult.window>`, a window loaded from a saved run): its
    samples end before the run's end, or start after t = 0 (a streamed run's kept end, whose
    summary covers the kept end, is taken whole)."""
    t = np.asarray(result.t, dtype=float)
    if t.size == 0:
        return False
    streamed = "stream" in (result.provenance or {})
    return bool(t[-1] < float(result.t_end) - 1e-9 or (t[0] > 1e-9 and not streamed))


def behaviour_text(result, behaviour: str | None = None) -> str:
    """What the run did (:meth:`SimulationResult.behaviour
    <scoutsim.result.simulation_result.SimulationResult.behaviour>`: "steady bounding at 1.39 m/s, ...",
    "fell at t = 0.66 s: ..."), or ``behaviour`` if given (e.g. a saved run's summary). A
    window of a run says its outcome and the window shown instead, as its strides are not
    the run's; a run whose strides cannot be analysed, its outcome (with the time [s] of a
    fall or failure)."""
    outcome = result.outcome
    outcome = outcome if outcome == "completed" else f"{outcome} at t = {result.t_end:.2f} s"
    t = np.asarray(result.t, dtype=float)
    shown = (
        f"t = {t[0]:.2f} - {t[-1]:.2f} s shown of the run's 0 - {result.t_end:.2f} s"
        if t.size
        else ""
    )
    if behaviour is not None:
        return behaviour + (f" ({shown})" if is_part_of_run(result) else "")
    if is_part_of_run(result):
        return f"run {outcome} ({shown})"
    try:
        return result.behaviour().text
    except Exception:  # a result too broken for the stride analysis: its outcome
        return outcome


def run_title(result, width: int = 110, behaviour: str | None = None) -> str:
    """The title of a run's figure: the model and what the run did (:func:`behaviour_text`),
    wrapped at ``width`` characters."""
    import textwrap

    return "\n".join(
        textwrap.wrap(
            f"Scout II, {run_model_label(result)}: {behaviour_text(result, behaviour)}",
            width,
            break_on_hyphens=False,
        )
    )


def legend_above(ax, handles=None, labels=None, fontsize: float = 8) -> None:
    """The axes' legend in one row above the axes at their right end, outside the data (as
    many columns as entries; the left end keeps the axis' offset text)."""
    if handles is None:
        handles, labels = ax.get_legend_handles_labels()
    ax.legend(
        handles,
        labels,
        loc="lower right",
        bbox_to_anchor=(1.0, 1.0),
        ncol=len(labels),
        fontsize=fontsize,
        frameon=False,
        borderaxespad=0.15,
        handlelength=1.8,
        columnspacing=1.2,
    )


def _runs(values: np.ndarray):
    """(start index, stop index, value) of the runs of equal consecutive values."""
    if values.size == 0:
        return []
    edges = np.flatnonzero(np.diff(values)) + 1
    starts = np.concatenate([[0], edges])
    stops = np.concatenate([edges, [values.size]])
    return [(int(a), int(b), int(values[a])) for a, b in zip(starts, stops)]


def state_bands(ax, t: np.ndarray, states: np.ndarray, y0: float, y1: float) -> None:
    """Shade the controller leg state over time in the axes-fraction strip [y0, y1].

    A sample's state holds from its time until the next sample (zero-order hold, as the
    1 kHz controller does)."""
    verts: dict[int, list] = {state: [] for state in LegState}
    for a, b, k in _runs(states):
        ta = t[a]
        tb = t[b] if b < t.size else t[-1]
        if k in verts and tb > ta:
            verts[k].append([(ta, y0), (tb, y0), (tb, y1), (ta, y1)])
    for k, v in verts.items():
        if v:
            ax.add_collection(
                PolyCollection(
                    v,
                    facecolors=LEG_STATE_COLORS[k],
                    edgecolors="none",
                    transform=ax.get_xaxis_transform(),
                    zorder=0,
                )
            )
