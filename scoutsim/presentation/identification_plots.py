"""Figures of a hip-unit identification (docs/identification.md): a rig log against the
fitted model, with the residuals.

    res = identify(logs)                 # scoutsim.identification.fit
    res.plot("out/")                     # one fit_<n>.png per log, through plot_fit

Degrees appear only here, on the axes.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .style import LEG_NAMES, save_figure

__all__ = ["plot_fit"]


def plot_fit(data, fitted_angle, fitted_current, start_angle, path=None) -> Figure:
    """Logged against fitted encoder angle (and motor current), and the angle residuals, of
    one rig log.

    Parameters
    ----------
    data : :class:`scoutsim.identification.rig_data.RigData` (``log.t`` [s], ``angle`` (n, 2)
        [rad], ``current`` (n, 2) [A] or None, ``legs``, ``rig.name``, ``name``).
    fitted_angle, start_angle : (n, 2) encoder angle [rad] simulated with the fitted and the
        starting parameters.
    fitted_current : (n, 2) motor current [A] simulated with the fitted parameters (used
        when the log has current).
    path : save there by suffix (.png, .pdf, .svg) if given.
    """
    t = data.log.t - data.log.t[0]
    has_current = data.current is not None
    nrow = 3 if has_current else 2
    fig = Figure(figsize=(8, 2.6 * nrow), layout="constrained")
    axs = fig.subplots(nrow, 1, sharex=True)
    for leg in data.legs:
        nm = LEG_NAMES[leg]
        axs[0].plot(t, np.degrees(data.angle[:, leg]), ".", ms=1.5, alpha=0.5, label=f"{nm}: log")
        axs[0].plot(t, np.degrees(fitted_angle[:, leg]), "-", lw=1, label=f"{nm}: fitted")
        axs[0].plot(t, np.degrees(start_angle[:, leg]), ":", lw=1, label=f"{nm}: start")
        axs[1].plot(t, np.degrees(data.angle[:, leg] - fitted_angle[:, leg]), lw=0.6, label=f"{nm}")
        if has_current:
            axs[2].plot(t, data.current[:, leg], ".", ms=1.5, alpha=0.5, label=f"{nm}: log")
            axs[2].plot(t, fitted_current[:, leg], "-", lw=1, label=f"{nm}: fitted")
    axs[0].set_ylabel("encoder angle [deg]")
    axs[1].set_ylabel("residual [deg]")
    axs[0].legend(fontsize=7, ncol=2)
    axs[1].legend(fontsize=7)
    if has_current:
        axs[2].set_ylabel("motor current [A]")
        axs[2].legend(fontsize=7, ncol=2)
    axs[-1].set_xlabel("t [s]")
    axs[0].set_title(f"{data.rig.name}: {data.name}", fontsize=9)
    save_figure(fig, path)
    return fig
