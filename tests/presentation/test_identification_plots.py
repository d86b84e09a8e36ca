"""Tests of scoutsim.presentation.identification_plots on a hand-built rig log."""

from types import SimpleNamespace

import numpy as np

from scoutsim.presentation.identification_plots import plot_fit


def _data(current):
    t = np.linspace(10.0, 11.0, 201)
    angle = np.column_stack([np.sin(t), 0.5 * np.cos(t)])
    return SimpleNamespace(
        log=SimpleNamespace(t=t),
        angle=angle,
        current=(np.ones_like(angle) if current else None),
        legs=(0, 1),
        rig=SimpleNamespace(name="free-swing"),
        name="log 1",
    )


def test_fit_figure_shows_log_fit_and_residual_in_degrees(tmp_path, png_draws_each_axes_data):
    d = _data(current=True)
    fitted = d.angle + 0.01
    fig = plot_fit(d, fitted, 2.0 * d.current, d.angle, tmp_path / "fit_1.png")
    ax_angle, ax_res, ax_cur = fig.get_axes()
    assert "[deg]" in ax_angle.get_ylabel() and "[deg]" in ax_res.get_ylabel()
    assert "[A]" in ax_cur.get_ylabel()
    png_draws_each_axes_data(tmp_path / "fit_1.png", fig)
    # time from the log's start; residual = log - fitted, in degrees
    res = ax_res.get_lines()[0]
    assert res.get_xdata()[0] == 0.0
    assert np.allclose(res.get_ydata(), np.degrees(-0.01))
    assert "free-swing" in ax_angle.get_title()


def test_fit_figure_without_current_has_two_panels():
    d = _data(current=False)
    fig = plot_fit(d, d.angle, None, d.angle)
    assert len(fig.get_axes()) == 2
