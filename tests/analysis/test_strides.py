"""The split of a run into strides (scoutsim/analysis/strides.py, stride_energy.py) costs
time linear in the run's length: a run twice as long reads its impact log as often (once)
and hands the stance overlaps twice as many stance rows, not four times as many; and the
per-stride windows give the same numbers as scanning every stance and impact."""

import numpy as np
import pytest

import scoutsim
from scoutsim.analysis import stances as stances_module
from scoutsim.analysis import strides as strides_module
from scoutsim.analysis.gait import gait_metrics
from scoutsim.result.stride_record import StrideRecord


@pytest.fixture(scope="module")
def runs():
    """Model II bounding for 6 s and for 12 s, with the energy accounting."""
    return {d: scoutsim.simulate(duration=d, model="II", energy=True) for d in (6.0, 12.0)}


def _counted(result, monkeypatch):
    """(gait metrics, reads of the run's impacts, stance rows handed to the overlaps) of
    ``result``."""
    counts = {"impact_log": 0, "stance_rows": 0}
    real_impact_log = StrideRecord.impacts
    real_overlap = stances_module.stance_overlap

    def impact_log(self, *args, **kwargs):
        counts["impact_log"] += 1
        return real_impact_log(self, *args, **kwargs)

    def overlap(intervals, a, b):
        counts["stance_rows"] += intervals.shape[0]
        return real_overlap(intervals, a, b)

    with monkeypatch.context() as m:
        m.setattr(StrideRecord, "impacts", impact_log)
        m.setattr(strides_module, "stance_overlap", overlap)
        metrics = gait_metrics(result)
    return metrics, counts


def test_the_work_of_the_split_grows_linearly_with_the_run(runs, monkeypatch):
    short, long_ = (_counted(runs[d], monkeypatch) for d in (6.0, 12.0))
    n_short, n_long = len(short[0].strides), len(long_[0].strides)
    assert n_long >= 1.8 * n_short > 0
    # the impact log is read once per run, however many strides it has
    assert short[1]["impact_log"] == long_[1]["impact_log"] == 1
    # each stride's overlaps see the few stances that meet it (a bound has one or two per
    # leg per stride): rows in proportion to the strides, not to strides x stances
    for metrics, counts in (short, long_):
        assert counts["stance_rows"] <= 6 * len(metrics.strides)


def test_the_windows_give_what_scanning_everything_gives(runs):
    r = runs[12.0]
    metrics = gait_metrics(r)
    back, front = metrics.stance["back"], metrics.stance["front"]
    for st in metrics.strides:
        period = st.t_end - st.t_start
        assert (
            st.duty_factor_back
            == stances_module.stance_overlap(back, st.t_start, st.t_end) / period
        )
        assert (
            st.duty_factor_front
            == stances_module.stance_overlap(front, st.t_start, st.t_end) / period
        )
        log = r.impact_log(st.energy_t_start, st.energy_t_end)
        assert st.impact_loss_j == float(log["energy_lost"].sum())
    assert np.isfinite([st.impact_loss_j for st in metrics.strides]).all()
