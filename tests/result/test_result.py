"""Tests of scoutsim.result.simulation_result: the table and figure views of a run."""

import numpy as np
import pytest

import scoutsim
from scoutsim._core.model import layout as L
from scoutsim.result.columns import column_unit


@pytest.fixture(scope="module")
def run():
    return scoutsim.simulate(duration=0.3, model="II")


def test_every_column_has_a_unit_or_is_a_mode_code(run):
    for name in run.columns():
        unit = column_unit(name)
        is_mode = (
            name.startswith(("leg_state_", "contact_mode_", "motor_joint_mode_"))
            or name == "dynamics_solved"
        )
        assert (unit is None) == is_mode, name


def test_to_dataframe_holds_every_sample_losslessly(run):
    pd = pytest.importorskip("pandas")
    df = run.to_dataframe()
    assert isinstance(df, pd.DataFrame)
    assert df.index.name == "t" and np.array_equal(df.index.to_numpy(), run.t)
    assert len(df) == run.t.size
    for i, n in enumerate(L.STATE_NAMES):
        assert np.array_equal(df[n].to_numpy(), run.state[:, i])
    assert np.array_equal(df["leg_state_back"].to_numpy(), run.leg_state("back"))
    assert df.attrs["units"]["theta"] == "rad" and df.attrs["units"]["leg_state_back"] is None


def test_plot_is_the_run_figure(run, tmp_path, png_draws_each_axes_data):
    fig = run.plot(tmp_path / "run.png")
    assert len(fig.get_axes()) >= 4
    assert "Model II" in fig._suptitle.get_text()
    np.testing.assert_array_equal(fig.get_axes()[0].get_lines()[0].get_xdata(), run.t)
    png_draws_each_axes_data(tmp_path / "run.png", fig)


def test_a_window_of_a_saved_run_loads_the_same_from_tables_and_npz(tmp_path):
    import scoutsim
    from scoutsim import SimulationResult

    r = scoutsim.simulate(duration=3.0)
    r.save_tables(tmp_path)
    r.save(tmp_path / "r.npz")
    ref = r.window(1.0, 2.0)
    assert ref.t[0] == 1.0 and ref.t[-1] == 2.0 and len(ref.t) == 1001
    assert np.all((ref.events[:, 0] >= 1.0) & (ref.events[:, 0] <= 2.0))
    for loaded in (
        SimulationResult.load(tmp_path, t_range=(1.0, 2.0)),
        SimulationResult.load(tmp_path / "r.npz", t_range=(1.0, 2.0)),
    ):
        assert np.array_equal(loaded.state, ref.state)
        np.testing.assert_array_equal(loaded.events, ref.events)
        assert loaded.t_end == r.t_end and loaded.outcome == r.outcome
