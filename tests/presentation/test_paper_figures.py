"""Tests of scoutsim.presentation.paper_figures (paper Figs. 5, 8-12 for any data set) and the
figure writing of `scoutsim compare`: figures render headless, are non-empty, label every
axis with a unit, and say so when a model has no steady strides."""

import math
import re
import sys

import numpy as np
import pytest
from matplotlib.figure import Figure

from scoutsim import RobotParameters, simulate
from scoutsim.presentation import paper_figures as figures
from scoutsim.state import InitialState
from scoutsim.validation import SensorNoise, save_log, to_log
from scoutsim.validation.errors import ModelRun, assess_errors
from scoutsim.validation.log_strides import log_strides

#: scoutsim's earlier default start (4 deg nose-up, no pitch motion), at the edge of the
#: basin: Model I falls from it at about 1.4 s (the fallen-model paths of the comparison)
FALLING_START = InitialState(theta=math.radians(4.0), dtheta=0.0)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
UNIT = re.compile(r"\[[^\]]+\]")


@pytest.fixture(scope="module")
def sims():
    """Model II (6 s, bounds) and Model I from the earlier default start (falls at
    about 1.4 s) at mu = 0.8."""
    return {
        "II": simulate(duration=6.0, model="II", friction_coefficient=0.8),
        "I": simulate(
            initial_state=FALLING_START, duration=2.0, model="I", friction_coefficient=0.8
        ),
    }


@pytest.fixture(scope="module")
def exp_logs():
    """A synthetic 'experiment': a perturbed robot through the noisy measurement chain."""
    robot = RobotParameters()
    robot = robot.replace(leg_damping=1.2 * robot.leg_damping)
    res = simulate(robot, duration=6.0, model="II", friction_coefficient=0.8)
    return [to_log(res, noise=SensorNoise(), seed=1)]


@pytest.fixture(scope="module")
def table(sims, exp_logs):
    runs = {}
    for m, r in sims.items():
        lg = to_log(r)
        runs[m] = ModelRun(m, r.outcome, r.t_end, log_strides(lg), result=r)
    exp = [s for lg in exp_logs for s in log_strides(lg).steady_strides]
    return assess_errors(exp, runs, n_runs=1, synthetic=True)


def _check_labels(fig):
    axes = [ax for ax in fig.get_axes() if ax.get_visible()]
    assert axes
    for ax in axes:
        assert UNIT.search(ax.get_ylabel()), ax.get_ylabel()
    xl = [ax.get_xlabel() for ax in axes if ax.get_xlabel()]
    assert xl and all(UNIT.search(x) for x in xl)


def _lines(fig):
    return sum(len(ax.get_lines()) for ax in fig.get_axes())


def _pyplot_fignums():
    plt = sys.modules.get("matplotlib.pyplot")
    return None if plt is None else list(plt.get_fignums())


@pytest.mark.parametrize("name", ["fig8", "fig9", "fig10", "fig11", "fig_phase"])
def test_comparison_figures_render_with_units(
    name, exp_logs, sims, tmp_path, png_draws_each_axes_data
):
    before = _pyplot_fignums()
    path = tmp_path / f"{name}.png"
    fig = getattr(figures, name)(exp_logs, sims, path=path)
    assert isinstance(fig, Figure)
    _check_labels(fig)
    assert _lines(fig) >= 3
    assert path.read_bytes().startswith(PNG_MAGIC)
    title = fig._suptitle.get_text()
    assert "SYNTHETIC" in title
    # Model I fell: the figure says so (title or legend)
    texts = title + " ".join(
        t.get_text()
        for ax in fig.get_axes()
        if ax.get_legend()
        for t in ax.get_legend().get_texts()
    )
    assert "fell" in texts
    assert _pyplot_fignums() == before  # no pyplot figure registered
    png_draws_each_axes_data(path, fig)  # (last: it draws the figure again)


def test_fig5_highlights_one_stride(exp_logs, tmp_path):
    fig = figures.fig5(exp_logs, tmp_path / "fig5.svg", n_snapshots=5)
    _check_labels(fig)
    assert (tmp_path / "fig5.svg").read_text().lstrip().startswith("<?xml")
    ax_s, ax_p, ax_h, ax_pz, ax_hz = fig.get_axes()
    spans = [p for ax in (ax_p, ax_h, ax_pz, ax_hz) for p in ax.patches]
    assert len(spans) == 4  # the highlighted stride in the run and in the zoom
    legend = ax_p.get_legend().get_texts()[0].get_text()
    assert "steady stride" in legend
    # the snapshot strip: one torso per snapshot, marked in the zoomed time series
    assert len(ax_s.patches) == 5
    assert len([ln for ln in ax_pz.get_lines() if ln.get_linestyle() == ":"]) == 5
    lo, hi = ax_pz.get_xlim()
    assert hi - lo < 1.0 < ax_p.get_xlim()[1] - ax_p.get_xlim()[0]
    with pytest.raises(ValueError, match="n_snapshots"):
        figures.fig5(exp_logs, n_snapshots=0)


@pytest.mark.parametrize("with_length", [True, False])
def test_robot_pose_puts_stance_toes_on_the_ground(exp_logs, with_length):
    from scoutsim.validation import ExperimentLog

    lg = exp_logs[0]
    if not with_length:
        lg = ExperimentLog(
            {k: v for k, v in lg.columns.items() if not k.startswith("leg_length")}, dict(lg.meta)
        )
    rob = RobotParameters()
    checked = 0
    for k in range(0, len(lg.t), 97):
        pose = figures.robot_pose(lg, k)
        for name, leg in pose["legs"].items():
            (hx, hy), (tx, ty) = leg["hip"], leg["toe"]
            length = math.hypot(tx - hx, ty - hy)
            if with_length:
                # a logged length is drawn as logged (filtered pitch and height need not
                # put that toe exactly on the ground)
                assert length == pytest.approx(lg.leg_length(name)[k], abs=1e-12)
                checked += 1
            else:
                assert length <= rob.leg_rest_length + 1e-12
                if leg["state"] != 0 and length < rob.leg_rest_length:
                    # a stance leg's length derived from the hip height: toe on the ground
                    assert ty == pytest.approx(0.0, abs=1e-12)
                    checked += 1
        # hips are the torso's hip spacing apart
        hb, hf = pose["legs"]["back"]["hip"], pose["legs"]["front"]["hip"]
        assert math.hypot(hf[0] - hb[0], hf[1] - hb[1]) == pytest.approx(rob.hip_spacing)
    assert checked > 0


def test_fig9_has_leg_state_square_wave(exp_logs, sims):
    fig = figures.fig9(exp_logs, sims)
    axes = fig.get_axes()
    assert len(axes) == 6
    state_axes = [ax for ax in axes if ax.get_ylabel() == "leg state [-]"]
    assert len(state_axes) == 2
    for ax in state_axes:
        labels = [t.get_text() for t in ax.get_yticklabels()]
        assert labels == ["retraction", "brake", "flight"]
        ys = np.concatenate([ln.get_ydata() for ln in ax.get_lines()])
        assert set(np.unique(ys)) <= set(figures.STATE_LEVELS)
    ylabels = " ".join(ax.get_ylabel() for ax in axes)
    assert "[deg]" in ylabels and "[deg/s]" in ylabels


def test_fig11_draws_motor_limits(exp_logs, sims):
    from scoutsim.presentation.plots import motor_limits

    fig = figures.fig11(exp_logs, sims)
    lim = motor_limits(sims["II"].provenance["robot"])
    ax = fig.get_axes()[0]
    xs = [tuple(ln.get_xdata()) for ln in ax.get_lines()]
    assert (lim["tau_current"], lim["tau_current"]) in xs
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("current limit" in s for s in labels)
    assert any("torque-speed" in s for s in labels)
    assert "[N m]" in ax.get_xlabel() and "[rad/s]" in ax.get_ylabel()


def test_fig12_bars_and_missing_model(table, tmp_path):
    fig = figures.fig12(table, tmp_path / "fig12.pdf")
    assert (tmp_path / "fig12.pdf").read_bytes().startswith(b"%PDF")
    _check_labels(fig)
    ax = fig.get_axes()[0]
    assert "[%]" in ax.get_ylabel()
    # Model II: a mean and a max bar per metric; Model I fell: n/a, no bars
    n_metrics = len(ax.get_xticks())
    assert len(ax.patches) == 2 * n_metrics
    assert any(t.get_text() == "n/a" for t in ax.texts)
    assert "Model I" in fig._suptitle.get_text() and "fell" in fig._suptitle.get_text()
    heights = sorted(p.get_height() for p in ax.patches)
    r = table.row("II", "stride_frequency_hz")
    assert any(abs(h - r.mean_percent_error) < 1e-12 for h in heights)


def test_write_figures_writes_everything(exp_logs, table, tmp_path):
    paths = figures.write_figures(exp_logs, table, tmp_path / "figs")
    for name in figures.FIGURE_NAMES:
        assert paths[name].name == f"{name}.png"
        assert paths[name].read_bytes().startswith(PNG_MAGIC)
    assert paths["phase_rms"].read_text().startswith("model,signal,unit,rms_error")


def test_experiment_without_strides_is_drawn_and_said(sims, tmp_path):
    short = [to_log(sims["I"])]  # falls before any steady stride
    fig = figures.fig8(short, {"II": sims["II"]})
    assert "transient" in " ".join(t.get_text() for t in fig.get_axes()[0].get_legend().get_texts())
    fig5 = figures.fig5(short)
    _check_labels(fig5)


def test_bad_inputs(exp_logs, sims, tmp_path):
    with pytest.raises(ValueError, match="no experiment logs"):
        figures.fig8([], sims)
    with pytest.raises(TypeError, match="ErrorTable"):
        figures.fig12({"II": sims["II"]})
    with pytest.raises(TypeError, match="cannot use"):
        figures.fig8(exp_logs, {"II": 42})
    with pytest.raises(ValueError, match="suffix"):
        figures.fig8(exp_logs, sims, tmp_path / "f.jpg")
    with pytest.raises(ValueError, match="fmt"):
        figures.write_figures(exp_logs, sims, tmp_path, fmt="jpg")


def test_plot_log(exp_logs, tmp_path):
    fig = figures.plot_log(exp_logs[0], tmp_path / "log.png", t_range=(2.0, 3.0))
    _check_labels(fig)
    assert (tmp_path / "log.png").read_bytes().startswith(PNG_MAGIC)
    with pytest.raises(ValueError, match="no samples"):
        figures.plot_log(exp_logs[0], t_range=(100.0, 101.0))


def test_cli_compare_writes_figures(exp_logs, tmp_path, capsys):
    from scoutsim.cli import main

    p = save_log(exp_logs[0], tmp_path / "exp.csv.gz")
    out = tmp_path / "cmp"
    code = main(["compare", str(p), "--models", "II", "--out", str(out), "--no-progress"])
    stdout = capsys.readouterr().out
    assert code == 0
    for name in figures.FIGURE_NAMES:
        assert (out / f"{name}.png").read_bytes().startswith(PNG_MAGIC)
    assert (out / "phase_rms.csv").exists()
    assert "Phase-normalized" in stdout and "fig8.png" in stdout
