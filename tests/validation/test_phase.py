"""Tests of scoutsim.validation.phase: the phase-normalized comparison."""

import math

import numpy as np
import pytest

from scoutsim import RobotParameters, simulate
from scoutsim.presentation.phase_plots import plot_phase
from scoutsim.state import InitialState
from scoutsim.validation import to_log
from scoutsim.validation.phase import (
    SIGNALS,
    PhaseComparison,
    as_source,
    phase_compare,
    resample_strides,
)

#: scoutsim's earlier default start (4 deg nose-up, no pitch motion), at the edge of the
#: basin: Model I falls from it at about 1.4 s (the fallen-model paths of the comparison)
FALLING_START = InitialState(theta=math.radians(4.0), dtheta=0.0)


@pytest.fixture(scope="module")
def sim():
    return simulate(duration=6.0, model="II", friction_coefficient=0.8)


@pytest.fixture(scope="module")
def perturbed():
    robot = RobotParameters()
    robot = robot.replace(
        leg_damping=1.2 * robot.leg_damping, torso_inertia=0.9 * robot.torso_inertia
    )
    return simulate(robot, duration=6.0, model="II", friction_coefficient=0.8)


@pytest.fixture(scope="module")
def fallen():
    return simulate(initial_state=FALLING_START, duration=2.0, model="I", friction_coefficient=0.8)


def test_self_comparison_is_zero(sim):
    c = phase_compare(sim, {"II": sim})
    assert isinstance(c, PhaseComparison)
    assert c.n_strides["II"] == c.n_strides["experiment"] > 3
    for sig in SIGNALS:
        assert c.rms["II"][sig] == 0.0
        assert np.all(c.error["II"][sig] == 0.0)
    # a log of the run is the same thing
    c2 = phase_compare([to_log(sim)], {"II": to_log(sim)})
    assert all(v == 0.0 for v in c2.rms["II"].values())


def test_perturbed_run_differs(sim, perturbed):
    c = phase_compare(sim, {"perturbed": perturbed, "same": sim})
    for sig in SIGNALS:
        assert c.rms["perturbed"][sig] > 0.0
        assert c.rms["same"][sig] == 0.0
        assert math.isfinite(c.rms_percent["perturbed"][sig])
    # the pitch error is a sensible fraction of a degree or more, not noise
    assert c.rms["perturbed"]["pitch"] > math.radians(0.05)


def test_model_without_steady_strides(sim, fallen):
    c = phase_compare(sim, {"I": fallen, "II": sim})
    assert c.n_strides["I"] == 0
    assert "fell" in c.status["I"]
    assert all(math.isnan(v) for v in c.rms["I"].values())
    assert "I" not in c.mean
    text = c.format()
    assert "fell" in text and "Model II" in text


def test_resample_hits_stride_ends(sim):
    src = as_source(sim)
    pairs = src.steady[:3]
    v = resample_strides(pairs, "height", 11)
    assert v.shape == (3, 11)
    for (lg, st), row in zip(pairs, v):
        assert row[0] == pytest.approx(np.interp(st.t_start, lg.t, lg.height))
        assert row[-1] == pytest.approx(np.interp(st.t_end, lg.t, lg.height))


def test_csv_and_figure(sim, perturbed, fallen, tmp_path, png_draws_each_axes_data):
    c = phase_compare(sim, {"I": fallen, "II": perturbed}, n_phase=51)
    p = c.to_csv(tmp_path / "rms.csv")
    lines = p.read_text().splitlines()
    assert lines[0] == (
        "model,signal,unit,rms_error,rms_error_percent_of_range,"
        "n_strides_model,n_strides_experiment,status"
    )
    assert len(lines) == 1 + 2 * len(SIGNALS)
    fig = plot_phase(c, tmp_path / "phase.png")
    axes = [ax for ax in fig.get_axes() if ax.get_visible()]
    assert len(axes) == len(SIGNALS)
    assert all("[" in ax.get_ylabel() for ax in axes)
    png_draws_each_axes_data(tmp_path / "phase.png", fig)  # (last: it draws again)
    assert "fell" in fig._suptitle.get_text()


def test_bad_arguments(sim):
    with pytest.raises(ValueError, match="n_phase"):
        phase_compare(sim, {"II": sim}, n_phase=1)
    with pytest.raises(ValueError, match="signals"):
        phase_compare(sim, {"II": sim}, signals=("speed",))
    with pytest.raises(ValueError, match="empty"):
        phase_compare([], {"II": sim})
    with pytest.raises(ValueError, match="experiment"):
        phase_compare(sim, {"experiment": sim})
    with pytest.raises(TypeError, match="cannot use"):
        phase_compare(sim, {"II": "not a run"})
