"""A learned policy from the shell: ``--controller FILE.npz`` (scoutsim.cli._common,
scoutsim.control.policy). ``scoutsim run`` runs the policy of the file (the run's
provenance names it, and its set-point policy bounds from the default start); a policy file
that cannot be read is a usage error naming the file and the field, before anything
runs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from scoutsim import SimulationResult
from scoutsim.cli import main

POLICY = Path(__file__).resolve().parents[1] / "data" / "policy_setpoints.npz"


def test_run_takes_a_policy_file(tmp_path):
    out = tmp_path / "o"
    code = main(
        ["run", "--controller", str(POLICY), "--duration", "2", "--out", str(out), "--quiet"]
    )
    assert code == 0
    run = SimulationResult.load(out)
    assert run.provenance["controller_kind"] == "PolicyController(policy_setpoints.npz)"
    assert run.outcome == "completed" and run.t_end == pytest.approx(2.0)


def test_a_policy_file_that_cannot_be_read_is_a_usage_error(tmp_path, capsys):
    """A missing field and a missing file: exit 2, the message names the file and what is
    wrong; no run directory is written."""
    with np.load(POLICY) as data:
        fields = {k: data[k] for k in data.files if k != "action_center"}
    bad = tmp_path / "bad.npz"
    np.savez(bad, **fields)
    out = tmp_path / "o"
    assert main(["run", "--controller", str(bad), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "'action_center' is missing" in err
    assert not (out / "summary.json").exists()
    missing = tmp_path / "none.npz"
    assert main(["basin", "--controller", str(missing), "--out", str(out), "--quiet"]) == 2
    assert "no such file" in capsys.readouterr().err
