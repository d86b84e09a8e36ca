"""Figures and animation: everything scoutsim draws (the top layer; nothing below imports it
except the deferred convenience accessors ``SimulationResult.plot``,
``SweepResult.plot_map``, ``IdentificationResult.plot`` and ``BoundEnv.render``).

Modules
-------
style                 colours of legs, leg states and models; model names; the file writer
plots                 run time histories; re-exports the run figures below
run_overview          a long run's whole-run panels: pitch and height ranges, stride periods
torque_speed          the torque-speed plane of a run (paper Fig. 11) and the motor limits
stride_power          the power over one stride by destination
maps                  the basin map and sweep maps over a grid of runs
tune_plots            a tuning's convergence
run_parts             what the run figures share (title: what the run did, legends above
                      their panels, leg-state bands)
animation             stick-figure animation of a run (GIF / MP4)
frames                one picture of the robot as an RGB array, rasterised with NumPy (the
                      learning environment's ``render``)
paper_figures         the paper's Figs. 5, 8-12 for an experiment and models, all written at
                      once; one module per figure group: experiment_figure (Fig. 5),
                      stride_figures (Figs. 8-10), saturation_figure (Fig. 11),
                      error_figure (Fig. 12), log_figure (one log), figure_parts (shared)
phase_plots           the phase-normalized mean-stride comparison
identification_plots  a rig log against the fitted hip-unit model

Every function returns a :class:`matplotlib.figure.Figure` built without ``pyplot`` (no GUI
backend, no global figure state, headless), saved to ``path`` in the format of its suffix
(.png, .pdf, .svg) if given. Angles are shown in degrees here and nowhere else.

The submodules are imported on first use (``scoutsim.presentation.plot_run`` works), so
importing the package costs nothing until a figure is drawn.
"""

from __future__ import annotations

import importlib

#: public name -> submodule that defines it
_EXPORTS = {
    "plot_run": "plots",
    "plot_torque_speed": "torque_speed",
    "plot_basin_map": "maps",
    "plot_sweep_map": "maps",
    "motor_limits": "torque_speed",
    "plot_stride_power": "stride_power",
    "plot_tune_convergence": "tune_plots",
    "animate": "animation",
    "save_animation": "animation",
    "fig5": "experiment_figure",
    "fig8": "stride_figures",
    "fig9": "stride_figures",
    "fig10": "stride_figures",
    "fig11": "saturation_figure",
    "fig12": "error_figure",
    "fig_phase": "paper_figures",
    "plot_log": "log_figure",
    "write_figures": "paper_figures",
    "plot_phase": "phase_plots",
    "plot_fit": "identification_plots",
    "save_figure": "style",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name):
    if name in _EXPORTS:
        return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
