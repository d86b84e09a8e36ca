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

All computation is SI; degrees appear only in these figure modules, on the axes.

Modules (``scoutsim.presentation.``), by figure group
-----------------------------------------------------
experiment_figure   Fig. 5: snapshots of the robot, pitch and height over the run
stride_figures      Figs. 8-10: pitch and height over one stride; leg angles, rates and hip
                    torques over one step, with the leg-state square wave
saturation_figure   Fig. 11: leg speed against hip torque, with the motor limits
error_figure        Fig. 12: percent errors per gait metric and model
log_figure          :func:`plot_log`: time histories of one log
figure_parts        what they share (sources, the stride shown, styles, notes)

This module holds the phase figure and :func:`write_figures` (all of them), and re-exports
the figures above.
"""

from __future__ import annotations

from pathlib import Path

from ..validation.phase import phase_compare
from .error_figure import fig12
from .experiment_figure import fig5, robot_pose
from .figure_parts import STATE_LEVELS, prepare_sources
from .log_figure import plot_log
from .phase_plots import plot_phase
from .saturation_figure import fig11
from .stride_figures import fig8, fig9, fig10

__all__ = [
    "robot_pose",
    "fig5",
    "fig8",
    "fig9",
    "fig10",
    "fig11",
    "fig12",
    "fig_phase",
    "plot_log",
    "write_figures",
    "FIGURE_NAMES",
    "STATE_LEVELS",
]

#: File stems written by :func:`write_figures`.
FIGURE_NAMES = ("fig5", "fig8", "fig9", "fig10", "fig11", "fig12", "phase")


def fig_phase(logs, models=None, path=None, transient_s: float = 2.0, n_phase: int = 101):
    """Figure of the phase-normalized comparison
    (:func:`scoutsim.validation.phase.phase_compare` + :func:`~.phase_plots.plot_phase`)."""
    exp, mods = prepare_sources(logs, models, transient_s)
    return plot_phase(phase_compare(exp, mods, n_phase=n_phase, transient_s=transient_s), path)


def write_figures(
    logs, models=None, out_dir=".", table=None, fmt: str = "png", transient_s: float = 2.0
) -> dict:
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
    exp, mods = prepare_sources(logs, models, transient_s)
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
