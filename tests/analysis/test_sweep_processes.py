"""Real ``scoutsim sweep`` processes stopped by SIGINT and SIGKILL at several moments
(workers starting, between points), and a worker killed mid-sweep: the checkpoint keeps
every finished point and no interrupted one, no table is left that looks complete, every
worker exits by itself when its parent is gone, and the resumed sweep's tables equal an
uninterrupted sweep's byte for byte. Each signal is sent at a state the sweep shows (its
workers spawned, a number of points in its checkpoint), never after a guessed delay; the
time limits below only keep a broken test from hanging."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import scoutsim
from scoutsim.io.run_directory import IncompleteRunError, check_run_directory

# 20 points of 40 s (about 0.2 s of computing each): long enough to stop between points,
# short enough for the test suite
ARGS = [
    "sweep",
    "--grid",
    "controller.touchdown_angle_front_deg=19:21:4",
    "--grid",
    "controller.touchdown_angle_back_deg=17:19:5",
    "--duration",
    "40",
    "--no-progress",
    "--quiet",
]
N_POINTS = 20
#: hang guard [s] for the workers of a dead parent to exit by themselves (they look every
#: PARENT_POLL_S = 0.5 s, plus the rest of a run): generous, not a claim about speed
ORPHAN_GUARD_S = 60.0
#: hang guard [s] for a waited-for state of the sweep, and for its exit
HANG_GUARD_S = 300.0


def _start(out, workers):
    return subprocess.Popen(
        [sys.executable, "-m", "scoutsim", *ARGS, "--out", str(out), "--workers", str(workers)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )


def _run(out, workers):
    proc = _start(out, workers)
    stdout, stderr = proc.communicate(timeout=HANG_GUARD_S)
    assert proc.returncode == 0, stderr.decode()
    return stdout.decode()


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    scoutsim.simulate(model="II", duration=0.01)  # the core is compiled before any clock
    out = tmp_path_factory.mktemp("reference")
    _run(out, 2)
    return out


def _descendants(pid: int) -> set[int]:
    """Every process below ``pid`` (from /proc), the spawned workers and the
    multiprocessing resource tracker."""
    found, todo = set(), [pid]
    while todo:
        p = todo.pop()
        for task in Path(f"/proc/{p}/task").glob("*"):
            try:
                kids = (task / "children").read_text().split()
            except OSError:
                continue
            for k in map(int, kids):
                if k not in found:
                    found.add(k)
                    todo.append(k)
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state not in ("Z", "X")  # a zombie has exited (nobody has reaped it yet)


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return ""


def _spawned_workers(pid: int) -> list[int]:
    """The pool workers below ``pid``: processes running multiprocessing's spawn_main (so
    past their exec; the resource tracker runs something else)."""
    return [p for p in _descendants(pid) if "spawn_main" in _cmdline(p)]


def _assert_no_survivors(pids: set[int]):
    """Every process of ``pids`` exits by itself (the parent is gone)."""
    deadline = time.monotonic() + ORPHAN_GUARD_S
    while time.monotonic() < deadline and any(map(_alive, pids)):
        time.sleep(0.1)
    survivors = [p for p in pids if _alive(p)]
    for p in survivors:
        os.kill(p, signal.SIGKILL)
    assert not survivors, (
        f"processes {survivors} were still running {ORPHAN_GUARD_S} s after their parent ended"
    )


def _checkpoint_rows(out) -> list[dict]:
    p = out / "points.jsonl"
    lines = p.read_bytes().split(b"\n") if p.exists() else []
    rows = []
    for line in lines:
        try:
            rows.append(json.loads(line)["row"])
        except ValueError:
            pass  # a last line cut by SIGKILL (skipped on resume)
    return rows


def _wait_for_points(out, n: int, proc, timeout=HANG_GUARD_S):
    """Wait until the checkpoint holds ``n`` finished points (a moment between points)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if len(_checkpoint_rows(out)) >= n:
            return
        assert proc.poll() is None, proc.stderr.read().decode()
        time.sleep(0.02)
    raise AssertionError(f"the sweep did not finish {n} points in {timeout} s")


def _wait_for_workers_starting(proc, workers: int, timeout=HANG_GUARD_S):
    """Wait until the parent has spawned its ``workers`` pool workers (each past its exec
    into multiprocessing's spawn_main), which then import scoutsim before their first
    point."""
    deadline = time.monotonic() + timeout
    while len(_spawned_workers(proc.pid)) < workers:
        assert proc.poll() is None, proc.stderr.read().decode()
        assert time.monotonic() < deadline, "the sweep never started its workers"
        time.sleep(0.005)


def _assert_stopped_consistently(out):
    """After a stop: every recorded point finished (none "interrupted"), fewer than all;
    no table that could be taken for the sweep's result."""
    rows = _checkpoint_rows(out)
    assert all(r["outcome"] in ("completed", "fell") for r in rows), rows
    try:
        manifest = check_run_directory(out)
    except IncompleteRunError:  # a sweep killed while it ran: "writing"
        manifest = None
    if manifest is None or manifest["status"] != "complete":
        assert not (out / "sweep.csv").exists() and not (out / "sweep.parquet").exists()
    return rows


def _assert_resumes_to(out, reference):
    _run(out, 2)
    for name in ("sweep.csv", "sweep.parquet"):
        assert (out / name).read_bytes() == (reference / name).read_bytes(), name
    assert check_run_directory(out)["status"] == "complete"


def test_the_reference_sweep_is_complete(reference):
    assert len(_checkpoint_rows(reference)) == N_POINTS
    manifest = check_run_directory(reference)
    assert manifest["status"] == "complete" and {"sweep.csv", "sweep.parquet", "map.png"} <= set(
        manifest["files"]
    )


@pytest.mark.parametrize(
    "workers,moment", [(1, "between points"), (2, "workers starting"), (2, "between points")]
)
def test_ctrl_c_stops_keeps_finished_points_and_resumes(tmp_path, reference, workers, moment):
    out = tmp_path / "out"
    proc = _start(out, workers)
    if moment == "workers starting":
        _wait_for_workers_starting(proc, workers)
        assert not _checkpoint_rows(out)  # (no point finished yet: the workers start)
    else:
        _wait_for_points(out, 3, proc)
    kids = _descendants(proc.pid)
    os.killpg(proc.pid, signal.SIGINT)  # as Ctrl-C in a terminal: the whole group
    code = proc.wait(timeout=HANG_GUARD_S)
    stderr = proc.stderr.read().decode()
    assert code == 130, stderr
    assert "Traceback" not in stderr, stderr
    rows = _assert_stopped_consistently(out)
    assert len(rows) < N_POINTS
    if moment == "between points":
        assert len(rows) >= 3 and f"{len(rows)} of {N_POINTS} points are done" in stderr
    _assert_no_survivors(kids)
    _assert_resumes_to(out, reference)


@pytest.mark.parametrize("moment", ["workers starting", "between points"])
def test_sigkill_of_the_parent_leaves_no_orphans_and_the_sweep_resumes(tmp_path, reference, moment):
    out = tmp_path / "out"
    proc = _start(out, 2)
    if moment == "workers starting":
        _wait_for_workers_starting(proc, 2)
        assert not _checkpoint_rows(out)
    else:
        _wait_for_points(out, 3, proc)
    kids = _descendants(proc.pid)
    assert len(kids) >= 2  # two workers (+ the tracker)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=HANG_GUARD_S)
    _assert_no_survivors(kids)
    _assert_stopped_consistently(out)
    _assert_resumes_to(out, reference)


def test_a_killed_worker_costs_nothing_and_the_table_is_the_same(tmp_path, reference):
    out = tmp_path / "out"
    proc = _start(out, 2)
    _wait_for_points(out, 3, proc)
    workers = _spawned_workers(proc.pid)
    assert workers
    os.kill(workers[0], signal.SIGKILL)
    stdout, stderr = proc.communicate(timeout=HANG_GUARD_S)
    assert proc.returncode == 0, stderr.decode()
    rows = _checkpoint_rows(out)
    assert len(rows) == N_POINTS and all(r["error"] == "" for r in rows)
    for name in ("sweep.csv", "sweep.parquet"):
        assert (out / name).read_bytes() == (reference / name).read_bytes(), name


def test_a_torn_checkpoint_line_is_skipped_and_the_next_record_starts_its_own_line(
    tmp_path, reference
):
    out = tmp_path / "out"
    out.mkdir()
    lines = (reference / "points.jsonl").read_bytes().splitlines(keepends=True)
    # five whole records, then half of the sixth: what SIGKILL mid-write leaves
    (out / "points.jsonl").write_bytes(b"".join(lines[:5]) + lines[5][:40])
    _assert_resumes_to(out, reference)
    resumed = (out / "points.jsonl").read_bytes().splitlines()
    assert len(resumed) == N_POINTS and all(json.loads(x) for x in resumed)
