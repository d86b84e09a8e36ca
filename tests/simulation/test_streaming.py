"""Runs streamed to disk (scoutsim.simulation.streaming): the same tables as the run held in memory,
bit for bit; the returned result is the run's kept end; interrupts and falls write what
was computed; memory does not grow with the duration; disk space is checked first."""

import json
import tracemalloc

import numpy as np
import pytest

import scoutsim
from scoutsim.io.run_directory import check_run_directory
from scoutsim.io.tables import FORMATS, read_table
from scoutsim.result.simulation_result import SimulationResult
from scoutsim.simulation.budgets import check_stream_disk
from scoutsim.simulation.engine import HybridEngine
from scoutsim.simulation.simulator import simulate

pytest.importorskip("pyarrow")


def _same_tables(d1, d2, names=("timeseries", "events")):
    for name in names:
        p1 = next(d1.glob(f"{name}.*"))
        p2 = next(d2.glob(f"{name}.*"))
        a, ma = read_table(p1)
        b, mb = read_table(p2)
        assert list(a) == list(b), name
        for n in a:
            assert a[n].dtype == b[n].dtype and a[n].tobytes() == b[n].tobytes(), (name, n)
        if name == "timeseries":
            for m in (ma, mb):
                m["provenance"].pop("stream", None)
                m["stats"].pop("wall_time_s")
            assert json.dumps(ma, sort_keys=True) == json.dumps(mb, sort_keys=True)


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_streamed_run_writes_the_tables_of_the_run_held_in_memory(tmp_path, fmt):
    """25 s in three 10 s pieces (STREAM_CHUNK_SECONDS) with the steps recorded."""
    kw = dict(duration=25.0, model="II", record_steps=True)
    whole = simulate(**kw)
    (tmp_path / "memory").mkdir()
    whole.save_tables(tmp_path / "memory", fmt=fmt)
    kept = simulate(**kw, stream_to=tmp_path / "streamed", keep_seconds=4.0, table_format=fmt)
    _same_tables(tmp_path / "memory", tmp_path / "streamed", ("timeseries", "events", "steps"))
    manifest = check_run_directory(tmp_path / "streamed")
    assert manifest["status"] == "complete" and len(manifest["files"]) == 3
    # the returned result: the last 4 s, and the whole run's outcome, end and statistics
    i0 = int(np.searchsorted(whole.t, whole.t[-1] - 4.0))
    assert kept.t[0] == whole.t[i0] == 21.0 and np.array_equal(kept.state, whole.state[i0:])
    assert np.array_equal(kept.aux, whole.aux[i0:]) and np.array_equal(kept.modes, whole.modes[i0:])
    j0 = int(np.searchsorted(whole.events[:, 0], kept.t[0]))
    np.testing.assert_array_equal(kept.events, whole.events[j0:])
    np.testing.assert_array_equal(kept.event_states, whole.event_states[j0:])
    assert kept.steps[0, 0] >= kept.t[0] and np.array_equal(kept.steps[-1], whole.steps[-1])
    assert (kept.outcome, kept.t_end) == (whole.outcome, whole.t_end)
    assert {k: v for k, v in kept.stats.items() if k != "wall_time_s"} == {
        k: v for k, v in whole.stats.items() if k != "wall_time_s"
    }
    assert kept.provenance["stream"]["n_samples"] == len(whole.t) == 25001
    back = SimulationResult.load(tmp_path / "streamed")
    assert np.array_equal(back.state, whole.state) and back.t_end == whole.t_end


def test_a_streamed_fall_ends_where_the_run_in_memory_ends(tmp_path):
    import math

    from scoutsim import InitialState

    # a start pitched 4 deg nose-up on a mu = 0.8 floor: Model I falls (as in
    # tests/validation/test_validation.py)
    kw = dict(
        duration=30.0,
        model="I",
        friction_coefficient=0.8,
        initial_state=InitialState(theta=math.radians(4.0), dtheta=0.0),
    )
    whole = simulate(**kw)
    assert whole.outcome == "fell"
    kept = simulate(**kw, stream_to=tmp_path / "s")
    assert (kept.outcome, kept.t_end) == (whole.outcome, whole.t_end)
    assert np.array_equal(kept.state[-1], whole.state[-1])
    back = SimulationResult.load(tmp_path / "s")
    assert np.array_equal(back.t, whole.t) and back.outcome == "fell"
    assert check_run_directory(tmp_path / "s")["status"] == "complete"


def test_ctrl_c_in_a_streamed_run_writes_what_was_computed_as_partial(tmp_path, monkeypatch):
    whole = simulate(duration=40.0)
    real = HybridEngine.advance
    calls = []

    def advance(self, *args):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(self, *args)

    monkeypatch.setattr(HybridEngine, "advance", advance)
    kept = simulate(duration=40.0, stream_to=tmp_path / "s")
    assert kept.outcome == "interrupted"
    assert check_run_directory(tmp_path / "s")["status"] == "partial"
    back = SimulationResult.load(tmp_path / "s")
    n = len(back.t)
    assert n == 20000  # two 10 s pieces: samples k = 0 .. 19 999
    assert np.array_equal(back.state, whole.state[:n]) and back.outcome == "interrupted"


def test_memory_of_a_streamed_run_does_not_grow_with_its_duration(tmp_path):
    simulate(duration=0.1)

    def peak(duration, **kw):
        tracemalloc.start()
        simulate(duration=duration, **kw)
        out = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        return out

    streamed = {d: peak(d, stream_to=tmp_path / f"s{d:g}", keep_seconds=2.0) for d in (40.0, 160.0)}
    in_memory = {d: peak(d) for d in (40.0, 160.0)}
    # streamed, the peak is that of one 10 s piece and its tables (about 20 MB on
    # the machine it was measured on) whatever the duration; held in memory it grows with the
    # duration (about 20 MB for 40 s, 80 MB for 160 s)
    assert streamed[160.0] - streamed[40.0] < 0.1 * (in_memory[160.0] - in_memory[40.0])
    assert streamed[160.0] < 1.2 * streamed[40.0]


def test_disk_space_is_checked_before_a_streamed_run_starts(tmp_path):
    with pytest.raises(
        ValueError,
        match=r"duration = 1e\+09 s is not allowed here: .* on "
        r"disk.* GB free; at most about",
    ):
        check_stream_disk(1e9, tmp_path / "not yet")
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "keep.txt").write_text("an earlier run")
    with pytest.raises(ValueError, match="on disk"):
        scoutsim.simulate(duration=1e9, stream_to=tmp_path / "old")
    assert [p.name for p in (tmp_path / "old").iterdir()] == ["keep.txt"]


def test_keep_seconds_only_with_stream_to():
    with pytest.raises(ValueError, match="only allowed with stream_to"):
        simulate(duration=0.1, keep_seconds=3.0)


def test_cli_stream_writes_the_tables_of_the_run_in_memory(tmp_path, capsys):
    from scoutsim.cli import main

    base = ["run", "--duration", "12", "--no-progress"]
    assert main([*base, "--out", str(tmp_path / "memory")]) == 0
    assert main([*base, "--stream", "--keep", "3", "--out", str(tmp_path / "streamed")]) == 0
    out = capsys.readouterr().out
    assert "the sample-based figures t = 9 - 12 s" in out
    _same_tables(tmp_path / "memory", tmp_path / "streamed")
    # the streamed run's strides and energy are the whole run's, not its kept end's
    memory, streamed = (
        json.loads((tmp_path / d / "summary.json").read_text()) for d in ("memory", "streamed")
    )
    for key in ("n_strides", "mean_speed_m_s", "cost_of_transport", "electrical_energy_j"):
        assert streamed[key] == memory[key], key
    manifest = check_run_directory(tmp_path / "streamed")
    assert manifest["status"] == "complete" and manifest["streamed"] is True
    assert {"timeseries.parquet", "events.parquet", "summary.json"} <= set(manifest["files"])
    assert main([*base, "--stream", "--csv", "--out", str(tmp_path / "x")]) == 2
    assert "--csv is not allowed with a streamed run" in capsys.readouterr().err
    assert main([*base, "--keep", "3", "--out", str(tmp_path / "x")]) == 2


@pytest.mark.parametrize("streamed", [False, True])
def test_ctrl_c_before_the_first_sample_returns_an_empty_interrupted_run(
    tmp_path, monkeypatch, streamed
):
    """Ctrl-C as the run starts (found by a sweep's process test: it raised TypeError)."""

    def advance(self, *args):
        raise KeyboardInterrupt

    monkeypatch.setattr(HybridEngine, "advance", advance)
    kw = {"stream_to": tmp_path / "s"} if streamed else {}
    r = simulate(duration=5.0, **kw)
    assert r.outcome == "interrupted" and r.t_end == 0.0 and len(r.t) == 0
    assert r.summary()["outcome"] == "interrupted"
    if streamed:
        assert check_run_directory(tmp_path / "s")["status"] == "partial"


def _disk_full_at_the_second_piece(monkeypatch):
    """TableWriter.append fails as a full disk does at the time series' second piece."""
    import errno

    from scoutsim.io.tables import TableWriter

    real = TableWriter.append
    calls = {"timeseries": 0}

    def append(self, columns):
        if self.path.name.startswith("timeseries"):
            calls["timeseries"] += 1
            if calls["timeseries"] == 2:
                raise OSError(errno.ENOSPC, "No space left on device", str(self._tmp))
        return real(self, columns)

    monkeypatch.setattr(TableWriter, "append", append)


def test_a_full_disk_stops_a_streamed_run_and_keeps_what_was_written(tmp_path, monkeypatch):
    whole = simulate(duration=40.0)
    _disk_full_at_the_second_piece(monkeypatch)
    with pytest.warns(RuntimeWarning, match="could not be written"):
        kept = simulate(duration=40.0, stream_to=tmp_path / "s", keep_seconds=15.0)
    # the run stopped after its second 10 s piece; the result holds it
    assert kept.outcome == "write_failed" and kept.t_end == pytest.approx(19.999)
    i0 = int(np.searchsorted(whole.t, 19.999 - 15.0 - 1e-9))  # the last 15 s, 4.999 on
    assert kept.t[0] == pytest.approx(4.999) and np.array_equal(kept.state, whole.state[i0:20000])
    info = kept.provenance["stream"]
    assert info["write_error"] == "No space left on device"
    assert info["written_until_s"] == pytest.approx(9.999)
    assert sorted(info["tables_kept"]) == ["events.parquet", "timeseries.parquet"]
    manifest = check_run_directory(tmp_path / "s")
    assert manifest["status"] == "partial" and manifest["outcome"] == "write_failed"
    back = SimulationResult.load(tmp_path / "s")  # the first piece, whole
    assert np.array_equal(back.state, whole.state[:10000]) and back.t_end == pytest.approx(9.999)


def test_cli_full_disk_in_a_streamed_run_exits_74_and_saves_the_kept_end(
    tmp_path, monkeypatch, capsys
):
    import re
    import tempfile

    from scoutsim.cli import main

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    _disk_full_at_the_second_piece(monkeypatch)
    out = tmp_path / "out"
    with pytest.warns(RuntimeWarning):
        code = main(
            [
                "run",
                "--duration",
                "40",
                "--stream",
                "--keep",
                "5",
                "--no-progress",
                "--out",
                str(out),
            ]
        )
    assert code == 74
    err = capsys.readouterr().err
    assert "No space left on device; the run stopped at t = 19.999 s" in err
    assert re.search(
        r"keeps (events|timeseries)\.parquet, (events|timeseries)\.parquet "
        r"\(samples up to t = 9\.999 s\)",
        err,
    )
    rescued = SimulationResult.load(re.search(r"saved instead to (\S+\.npz)", err).group(1))
    assert rescued.t[0] == pytest.approx(14.999) and rescued.t_end == pytest.approx(19.999)
    assert check_run_directory(out)["status"] == "partial"


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_window_of_a_streamed_run_loads_without_the_rest(tmp_path, fmt):
    """SimulationResult.load(DIR, t_range=...) of a streamed run (Parquet: one row group per
    10 s piece, only those the window touches are read) equals the window of the run."""
    whole = simulate(duration=35.0, record_steps=True)
    simulate(duration=35.0, record_steps=True, stream_to=tmp_path / "s", table_format=fmt)
    win = SimulationResult.load(tmp_path / "s", t_range=(12.25, 13.5))
    ref = whole.window(12.25, 13.5)
    assert win.t[0] == pytest.approx(12.25) and win.t[-1] == pytest.approx(13.5)
    for name in ("t", "state", "aux", "modes", "steps"):
        assert np.array_equal(getattr(win, name), getattr(ref, name)), name
    np.testing.assert_array_equal(win.events, ref.events)
    np.testing.assert_array_equal(win.event_states, ref.event_states)
    assert len(ref.events) > 0 and win.t_end == whole.t_end


def test_plot_of_a_streamed_run_draws_its_kept_end_unless_told(tmp_path, capsys):
    from scoutsim.cli import main

    simulate(duration=30.0, stream_to=tmp_path / "s", keep_seconds=4.0)
    assert main(["plot", str(tmp_path / "s"), "--out", str(tmp_path / "end.png")]) == 0
    assert "streamed run: plotting its last 4 s (t = 26 - 30 s" in capsys.readouterr().out
    assert (
        main(
            [
                "plot",
                str(tmp_path / "s"),
                "--t0",
                "3",
                "--t1",
                "5",
                "--out",
                str(tmp_path / "early.png"),
            ]
        )
        == 0
    )
    assert (tmp_path / "end.png").stat().st_size > 0 and (tmp_path / "early.png").exists()
    assert main(["plot", str(tmp_path / "s"), "--t0", "40", "--t1", "50"]) == 2
