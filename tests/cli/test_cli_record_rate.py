"""``scoutsim run --record-rate`` and ``--memory-budget`` (scoutsim/cli/run.py): a thinned
timeseries table with the full-rate run's summary; a run that would take more than the
memory budget streams on its own and says so; a bad rate is refused naming the option."""

import json

import pytest

from scoutsim.cli import main
from scoutsim.result.simulation_result import SimulationResult

pytest.importorskip("pyarrow")


def test_record_rate_thins_the_table_and_keeps_the_summary(tmp_path, capsys):
    base = ["run", "--duration", "4", "--no-progress"]
    assert main([*base, "--out", str(tmp_path / "full")]) == 0
    assert main([*base, "--record-rate", "50", "--out", str(tmp_path / "thin")]) == 0
    full, thin = (SimulationResult.load(tmp_path / d) for d in ("full", "thin"))
    assert len(full.t) == 4001 and len(thin.t) == 201
    assert thin.provenance["record_rate_hz"] == 50
    a, b = (json.loads((tmp_path / d / "summary.json").read_text()) for d in ("full", "thin"))
    for key in ("n_strides", "mean_speed_m_s", "pitch_max_deg", "cost_of_transport"):
        assert a[key] == b[key], key
    assert main([*base, "--record-rate", "300", "--out", str(tmp_path / "bad")]) == 2
    err = capsys.readouterr().err
    assert "--record-rate = 300" in err and "divided by a whole number" in err


def test_a_run_over_the_memory_budget_streams_and_says_so(tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["run", "--duration", "3", "--no-progress", "--memory-budget", "0.001"]
    assert main([*argv, "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "more than the memory budget of 0.001 GB: streaming" in err
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["streamed"] is True
    summary = json.loads((out / "summary.json").read_text())
    assert summary["n_strides"] >= 8  # the whole run's strides
