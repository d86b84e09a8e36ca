"""One home for how scoutsim's figures look and are saved: colours of the legs and of the
controller leg states, display names and line styles of the models, and the file writer.

Every figure module of :mod:`scoutsim.presentation` uses these, so a run plot, an animation,
the paper's figures and the phase plots colour a leg state or a model the same way.
"""

from __future__ import annotations

from pathlib import Path

from .. import names as _names
from ..names import leg_index

__all__ = [
    "LEG_NAMES",
    "LEG_COLORS",
    "LEG_STATE_NAMES",
    "LEG_STATE_LINE_COLORS",
    "LEG_STATE_COLORS",
    "MODEL_LABELS",
    "MODEL_STYLES",
    "PNG_DPI",
    "FIGURE_SUFFIXES",
    "model_label",
    "model_style",
    "save_figure",
    "leg_index",
]

#: Virtual legs, in the order of their index (:class:`scoutsim.names.Leg`).
LEG_NAMES = _names.LEG_NAMES
#: Line colour of each virtual leg (back, front).
LEG_COLORS = ("tab:blue", "tab:red")

#: Controller leg states (paper Sec. II), indexed by the state code of ``result.leg_state``.
LEG_STATE_NAMES = _names.LEG_STATE_NAMES
#: Colour of each leg state as a line (legs in the animation, film strips, square waves).
LEG_STATE_LINE_COLORS = ("tab:blue", "tab:orange", "tab:green")
#: The same hues, pale, as time-axis backgrounds (run plots).
LEG_STATE_COLORS = ("#d6e9ff", "#ffd9a8", "#c9efc4")

#: Display name of each model variant and of the experiment.
MODEL_LABELS = {**_names.MODEL_LABELS, "experiment": "experiment"}
#: Line colour and style per source: experiment solid, Model I dotted, Model II dashed, as
#: the paper's Figs. 8-10 (ideal and passive dash-dotted).
MODEL_STYLES = {
    "experiment": ("k", "-"),
    "ideal": ("tab:green", "-."),
    "I": ("tab:blue", ":"),
    "II": ("tab:red", "--"),
    "passive": ("tab:purple", "-."),
}
_EXTRA_STYLES = (("tab:orange", "--"), ("tab:brown", ":"), ("tab:olive", "-."), ("tab:cyan", "--"))

#: Resolution of PNG output [dots per inch]: legible, and quick to render.
PNG_DPI = 110
#: File formats :func:`save_figure` writes (chosen by the path's suffix).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def model_label(name) -> str:
    """Display name of a model (``"II"`` -> ``"Model II"``); other names unchanged."""
    return MODEL_LABELS.get(name, f"model {name}" if name is None else str(name))


def model_style(name, i: int = 0) -> tuple[str, str]:
    """(colour, line style) of a model; names without a style get the ``i``-th extra one."""
    return MODEL_STYLES.get(name, _EXTRA_STYLES[i % len(_EXTRA_STYLES)])


def save_figure(fig, path, dpi: float | None = None) -> Path | None:
    """Save ``fig`` to ``path`` in the format of its suffix (.png, .pdf, .svg), creating the
    directory; nothing if ``path`` is None. PNGs at ``dpi`` (default :data:`PNG_DPI`).

    Returns the path written (or None). ValueError for any other suffix."""
    if path is None:
        return None
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FIGURE_SUFFIXES:
        raise ValueError(f"path = '{path}' is not allowed: the suffix must be .png, .pdf or .svg")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=(dpi or PNG_DPI) if suffix == ".png" else None)
    return path
