"""A run recorded at a lower rate (scoutsim/simulation/record_rate.py) and the strides read
from every sample as the run is computed (scoutsim/result/stride_record.py): the thinned
tables hold every k-th control sample and the last, while the events, the energy balance
and the strides are those of the full-rate run, bit for bit; a streamed run's strides are
the whole run's, not only those of the end it keeps in memory."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import scoutsim
from scoutsim.result.stride_record import StrideRecorder


def _strides(r):
    return [s.to_dict() for s in r.strides]


@pytest.fixture(scope="module")
def full():
    return scoutsim.simulate(duration=4.0, energy=True)


@pytest.mark.parametrize("rate", [500, 100, 10])
def test_record_rate_keeps_events_strides_and_energy_of_the_full_rate_run(full, rate):
    """Thinning the recorded samples changes no event, no stride metric, no per-stride or
    whole-run energy: they are integrated or read at the full rate inside the run."""
    r = scoutsim.simulate(duration=4.0, energy=True, record_rate=rate)
    k = 1000 // rate
    assert np.array_equal(r.t, np.concatenate([full.t[::k], full.t[-1:]])[: len(r.t)])
    assert r.t[-1] == full.t[-1]  # the run's last sample is kept
    assert np.array_equal(r.state, full.state[np.searchsorted(full.t, r.t)])
    assert np.array_equal(r.events, full.events, equal_nan=True)
    assert np.array_equal(r.event_states, full.event_states, equal_nan=True)
    assert len(r.strides) >= 10
    assert _strides(r) == _strides(full)
    assert r.energy_flows == full.energy_flows
    assert r.energy_balance().residual_J == full.energy_balance().residual_J
    # the whole summary: its sample-based figures (saturation, belt deflection, toe slide)
    # are counted from every sample too
    assert r.summary() == full.summary()
    assert r.provenance["record_rate_hz"] == rate


def test_strides_taken_in_pieces_of_any_size_equal_those_taken_at_once(full):
    """The stride record taken sample by sample, or in pieces that split the samples
    around a lift-off, gives the strides of the record taken in one piece."""
    n, ev = len(full.t), full.events
    for size in (1, 3, 250):
        rec = StrideRecorder()
        for i0 in range(0, n, size):
            i1 = min(n, i0 + size)
            lo = full.t[i0] if i0 else -np.inf
            hi = full.t[i1] if i1 < n else np.inf
            mine = (ev[:, 0] >= lo) & (ev[:, 0] < hi)
            rec.feed(
                dataclasses.replace(
                    full,
                    t=full.t[i0:i1],
                    state=full.state[i0:i1],
                    aux=full.aux[i0:i1],
                    modes=full.modes[i0:i1],
                    energy_series=full.energy_series[i0:i1],
                    events=ev[mine],
                    _cache={},
                )
            )
        pieced = dataclasses.replace(full, stride_record=rec.finish(), _cache={})
        assert _strides(pieced) == _strides(full), size


def test_a_streamed_run_has_the_strides_of_the_whole_run(tmp_path, full):
    """A streamed run keeps only its end in memory; its strides, gait metrics and the
    rest of its summary are still the whole run's."""
    r = scoutsim.simulate(duration=4.0, energy=True, stream_to=tmp_path / "run", keep_seconds=1.0)
    assert r.t[0] > 2.5 and r.provenance["stream"]["kept_from_s"] > 2.5  # the end only
    assert _strides(r) == _strides(full)
    assert r.summary() == full.summary()


def test_record_rate_must_divide_the_control_rate():
    """A record rate that is not the control rate over a whole number is refused, naming
    the field and the allowed rates."""
    for bad in (300.0, 0.0, -10.0, float("nan"), 2000.0):
        with pytest.raises(ValueError, match="record_rate"):
            scoutsim.simulate(duration=0.01, record_rate=bad)
