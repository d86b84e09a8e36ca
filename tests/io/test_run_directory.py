"""A run's output directory: one run per directory, files written whole or not at all, a
manifest that says whether the run's files are all there (scoutsim/io/run_directory.py)."""

import json
import signal
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

import scoutsim
from scoutsim import SimulationResult
from scoutsim.cli import main
from scoutsim.io.run_directory import (
    MANIFEST,
    IncompleteRunError,
    RunDirectory,
    atomic_write,
    check_run_directory,
    read_manifest,
)


def test_atomic_write_leaves_no_trace_when_the_writer_fails(tmp_path):
    target = tmp_path / "data.json"
    target.write_text("old")

    def failing(p):
        p.write_text("half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(target, failing)
    assert target.read_text() == "old"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["data.json"]


def test_a_directory_holds_one_run(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    with RunDirectory(tmp_path, command="first") as rd:
        rd.write("a.txt", lambda p: p.write_text("1"))
        rd.write("b.txt", lambda p: p.write_text("22"))
        rd.finish(outcome="completed", partial=False)
    m = check_run_directory(tmp_path)
    assert m["status"] == "complete" and m["files"] == {
        "a.txt": {"bytes": 1},
        "b.txt": {"bytes": 2},
    }
    with RunDirectory(tmp_path, command="second") as rd:
        assert read_manifest(tmp_path)["status"] == "writing"
        with pytest.raises(IncompleteRunError, match="cut off"):
            check_run_directory(tmp_path)
        rd.write("a.txt", lambda p: p.write_text("333"))
        rd.finish(outcome="interrupted", partial=True)
    # the first run's b.txt is gone, the user's file stays
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.txt", MANIFEST, "notes.txt"]
    assert check_run_directory(tmp_path)["status"] == "partial"
    (tmp_path / "a.txt").write_text("")  # a listed file that changed size
    with pytest.raises(IncompleteRunError, match="a.txt"):
        check_run_directory(tmp_path)


def test_writing_cut_off_by_ctrl_c_is_never_taken_for_a_run(tmp_path, monkeypatch, capsys):
    import scoutsim.cli.run as run_cli

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(run_cli, "write_json", interrupted)
    assert main(["run", "--duration", "0.1", "--out", str(tmp_path), "--no-progress"]) == 130
    assert read_manifest(tmp_path)["status"] == "writing"
    assert not list(tmp_path.glob("*.partial*"))
    with pytest.raises(IncompleteRunError):
        SimulationResult.load(tmp_path)
    capsys.readouterr()
    assert main(["plot", str(tmp_path), "--out", str(tmp_path / "x.png")]) == 2
    assert "cut off" in capsys.readouterr().err


def test_an_interrupted_simulation_is_written_as_partial_with_exit_130(tmp_path, force_outcome):
    force_outcome("interrupted")
    assert main(["run", "--duration", "0.2", "--out", str(tmp_path), "--no-progress"]) == 130
    m = check_run_directory(tmp_path)
    assert m["status"] == "partial" and m["outcome"] == "interrupted"
    assert SimulationResult.load(tmp_path).outcome == "interrupted"
    assert json.loads((tmp_path / "summary.json").read_text())["outcome"] == "interrupted"


#: generous bound on any wait for a child process (a hang guard, not a claim about speed)
HANG_GUARD_S = 300.0

#: ``python -c _HELD_RUN MOMENT RELEASE run ...``: ``scoutsim run`` held once at MOMENT
#: until the file RELEASE exists, after saying so on stderr ("held: MOMENT"), so that a test
#: signals the process at a moment it knows instead of after a guessed delay:
#: "simulating": after the first piece of the run, more to come (not in the 1 ms warm-up
#: run, which ends in its first piece); "writing": in the write of timeseries.csv (--csv),
#: its temporary file whole, the manifest saying "writing".
_HELD_RUN = r"""
import sys, time
from pathlib import Path
moment, release = sys.argv[1], Path(sys.argv[2])
del sys.argv[1:3]


def hold():
    print(f"held: {moment}", file=sys.stderr, flush=True)
    while not release.exists():
        time.sleep(0.01)


if moment == "simulating":
    from scoutsim.simulation.engine import HybridEngine
    advance = HybridEngine.advance

    def advance_then_hold(self, *args, **kwargs):
        out = advance(self, *args, **kwargs)
        if self.running and not release.exists():
            hold()
        return out
    HybridEngine.advance = advance_then_hold
elif moment == "writing":
    import scoutsim.cli.run as run
    write = run.write_timeseries_csv

    def write_then_hold(result, path):
        out = write(result, path)
        hold()
        return out
    run.write_timeseries_csv = write_then_hold
else:
    raise SystemExit(f"unknown moment {moment!r}")

from scoutsim.cli import console_main
console_main()
"""


class _Run:
    """A ``scoutsim run`` process writing to ``out`` (held at ``hold``, see
    :data:`_HELD_RUN`), its stderr read as it comes."""

    def __init__(self, out, duration, *options, hold=None):
        self.release = Path(out).parent / "release"
        start = (
            [sys.executable, "-c", _HELD_RUN, hold, str(self.release)]
            if hold
            else [sys.executable, "-m", "scoutsim"]
        )
        self.proc = subprocess.Popen(
            start
            + ["run", "--duration", str(duration), "--out", str(out), "--no-progress", *options],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        self._lines: list[str] = []
        self._ended = False
        self._cond = threading.Condition()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        for line in self.proc.stderr:
            with self._cond:
                self._lines.append(line)
                self._cond.notify_all()
        with self._cond:
            self._ended = True
            self._cond.notify_all()

    @property
    def stderr(self) -> str:
        with self._cond:
            return "".join(self._lines)

    def wait_for(self, text: str) -> None:
        """Wait until the process has said ``text`` on stderr."""
        with self._cond:
            self._cond.wait_for(lambda: self._ended or text in "".join(self._lines), HANG_GUARD_S)
        assert text in self.stderr, f"the run never said {text!r}; stderr:\n{self.stderr}"

    def signal(self, signum) -> None:
        self.proc.send_signal(signum)

    def wait(self) -> int:
        code = self.proc.wait(timeout=HANG_GUARD_S)
        self._reader.join(timeout=HANG_GUARD_S)
        return code


def _assert_consistent(out):
    """Whatever moment a run was stopped at: either the directory says its files are not
    all there (and loading refuses it), or every file is whole and the run loads."""
    try:
        manifest = check_run_directory(out)
    except IncompleteRunError:
        with pytest.raises(IncompleteRunError):
            SimulationResult.load(out)
        return "incomplete"
    if manifest is None:
        assert not list(out.glob("*.parquet")) and not (out / "summary.json").exists()
        return "nothing"
    r = SimulationResult.load(out)
    assert np.all(np.diff(r.t) > 0) and r.t[-1] == pytest.approx(r.t_end)
    return manifest["status"]


@pytest.mark.parametrize(
    "moment, expected",
    [
        ("starting", "nothing"),  # at once: the interpreter starts, nothing written
        ("simulating", "nothing"),  # the run is computed in memory, nothing written yet
        ("writing", "incomplete"),  # tables and summary written, the CSV not yet renamed
    ],
)
def test_sigkill_at_any_moment_leaves_a_consistent_directory(tmp_path, moment, expected):
    """SIGKILL cannot be caught: at each moment of a run the directory it leaves is either
    refused as incomplete or holds nothing that could pass for a run."""
    scoutsim.simulate(duration=0.01)  # the core is compiled before the child starts
    out = tmp_path / "out"
    run = _Run(out, 3, "--csv", hold=None if moment == "starting" else moment)
    if moment != "starting":
        run.wait_for(f"held: {moment}")
    if moment == "writing":
        assert (out / "timeseries.csv.partial.csv").exists()  # under its temporary name
    run.signal(signal.SIGKILL)
    assert run.wait() == -signal.SIGKILL
    assert _assert_consistent(out) == expected


def test_sigint_while_simulating_writes_the_data_so_far_as_partial(tmp_path):
    scoutsim.simulate(duration=0.01)
    out = tmp_path / "out"
    run = _Run(out, 5, hold="simulating")
    run.wait_for("held: simulating")
    run.signal(signal.SIGINT)
    assert run.wait() == 130, run.stderr
    assert _assert_consistent(out) == "partial"
    r = SimulationResult.load(out)
    assert r.outcome == "interrupted" and 0 < r.t_end < 5


@pytest.mark.parametrize("fault", ["directory in the way", "disk full"])
def test_outputs_that_cannot_be_written_exit_74_and_the_run_is_saved_elsewhere(
    tmp_path, monkeypatch, capsys, fault
):
    """A directory where summary.json goes, or a full disk: a clear message instead of a
    traceback, and the computed run saved to the temporary directory (not lost)."""
    import errno
    import re
    import tempfile

    import scoutsim.io.tables
    from scoutsim.cli import main

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    out = tmp_path / "out"
    if fault == "directory in the way":
        (out / "summary.json").mkdir(parents=True)
    else:

        def full(*args, **kwargs):
            raise OSError(errno.ENOSPC, "No space left on device", str(out / "x"))

        monkeypatch.setattr(scoutsim.io.tables, "write_table", full)
    assert main(["run", "--duration", "0.5", "--no-progress", "--out", str(out)]) == 74
    err = capsys.readouterr().err
    assert "could not write the run's files" in err and "Traceback" not in err
    assert ("Is a directory" if fault == "directory in the way" else "No space left") in err
    rescued = Path(re.search(r"saved instead to (\S+\.npz)", err).group(1))
    r = SimulationResult.load(rescued)
    assert r.t_end == pytest.approx(0.5) and r.outcome == "completed"
    with pytest.raises(IncompleteRunError):  # the directory does not pass for a run
        check_run_directory(out)


@pytest.mark.parametrize("content", [b"", b"PK\x03\x04 cut here"])
def test_plot_of_an_empty_or_truncated_npz_is_a_clear_error(tmp_path, capsys, content):
    from scoutsim.cli import main

    bad = tmp_path / "result.npz"
    bad.write_bytes(content)
    assert main(["plot", str(bad), "--out", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert "not a readable scoutsim result" in err and "Traceback" not in err
    assert ("empty" if not content else "cut off or damaged") in err


def test_ctrl_c_while_writing_completes_the_outputs_then_exits_130(tmp_path):
    """A real process: SIGINT while the outputs are written holds until they are whole."""
    scoutsim.simulate(duration=0.01)
    out = tmp_path / "out"
    run = _Run(out, 3, "--csv", hold="writing")
    run.wait_for("held: writing")
    run.signal(signal.SIGINT)
    run.wait_for("they will be complete in a moment")
    run.release.touch()
    assert run.wait() == 130, run.stderr
    assert _assert_consistent(out) == "complete"
    assert SimulationResult.load(out).t_end == pytest.approx(3.0)
    assert (out / "timeseries.csv").exists()


def test_a_second_ctrl_c_while_writing_abandons_the_outputs_cleanly(tmp_path):
    scoutsim.simulate(duration=0.01)
    out = tmp_path / "out"
    run = _Run(out, 3, "--csv", hold="writing")
    run.wait_for("held: writing")
    run.signal(signal.SIGINT)
    run.wait_for("they will be complete in a moment")
    run.signal(signal.SIGINT)
    assert run.wait() == 130, run.stderr
    assert _assert_consistent(out) == "incomplete"
    assert not [p for p in out.glob("*") if ".partial" in p.name]
