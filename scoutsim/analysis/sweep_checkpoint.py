"""A sweep's checkpoint (:mod:`scoutsim.analysis.sweep`): the file in its output directory
that a resumed sweep (or tuning, or uncertainty study) goes on from, one JSON record per
finished point, and how its records are read back and written (JSON's fallback for a
record's NumPy values: :func:`~scoutsim.io.run_directory.json_default`); the study's
directory opened with it (:func:`open_study_directory`) and its tasks mapped with every
finished row checkpointed as it arrives (:func:`map_with_checkpoint`).
"""

from __future__ import annotations

import json
from pathlib import Path

from ..io.run_directory import RunDirectory, json_default
from .parallel import map_tasks

#: name of the checkpoint file in a sweep's output directory: one JSON record per finished
#: point, appended and flushed as each point arrives
CHECKPOINT = "points.jsonl"


def read_checkpoint(path) -> dict:
    """The finished points of a checkpoint file, ``{key: row}`` (empty if there is none).

    A last line cut by a kill (no newline at its end) is skipped and cut off the file, so
    that the records appended next start on a line of their own."""
    path = Path(path)
    if not path.exists():
        return {}
    data = path.read_bytes()
    whole = data[: data.rfind(b"\n") + 1]
    if len(whole) != len(data):
        with open(path, "r+b") as f:
            f.truncate(len(whole))
    done = {}
    for line in whole.decode("utf-8", errors="replace").splitlines():
        try:
            rec = json.loads(line)
            done[rec["key"]] = rec["row"]
        except (json.JSONDecodeError, KeyError, TypeError):
            continue  # a damaged record: that point runs again
    return done


def was_error(row: dict) -> bool:
    """Whether a checkpoint's row is a point the study could not run (a row written
    before statuses existed: outcome "error")."""
    return row.get("status", "error" if row.get("outcome") == "error" else "ok") == "error"


def open_study_directory(out, *, command: str, info: dict, resume: bool):
    """A checkpointed study's output directory: ``(run directory, checkpoint path, finished
    rows {key: row})``, all None / empty without ``out``. Entering the directory removes an
    earlier study's tables (never the checkpoint), so none looks current; with ``resume``
    the finished rows are read back (a row the study could not run is run again), without
    it the checkpoint is removed."""
    if out is None:
        return None, None, {}
    out = Path(out)
    kind, rest = info["kind"], {k: v for k, v in info.items() if k != "kind"}
    rd = RunDirectory(
        out, command=command, info={"kind": kind, "checkpoint": CHECKPOINT, **rest}
    ).open()
    ck = out / CHECKPOINT
    done: dict = {}
    if resume:
        done = {k: r for k, r in read_checkpoint(ck).items() if not was_error(r)}
    elif ck.exists():
        ck.unlink()
    return rd, ck, done


def map_with_checkpoint(fn, tasks: list, keys: list, *, ck, rd, **map_options) -> list:
    """:func:`~scoutsim.analysis.parallel.map_tasks` of ``fn`` over ``tasks``, each
    finished row appended to the checkpoint ``ck`` (if any) under its task's key
    (``keys[j]`` for ``tasks[j]``) and flushed as it arrives. Ctrl-C marks the run
    directory ``rd`` interrupted (no table: the same call again goes on from the
    checkpoint) and is raised on. ``map_options``: those of ``map_tasks``."""
    fh = open(ck, "a") if ck is not None else None

    def on_result(j, row):
        if fh is not None:
            fh.write(json.dumps({"key": keys[j], "row": row}, default=json_default) + "\n")
            fh.flush()

    try:
        return map_tasks(fn, tasks, on_result=on_result, **map_options)
    except KeyboardInterrupt:
        if rd is not None:
            rd.finish(outcome="interrupted", partial=True)
        raise
    finally:
        if fh is not None:
            fh.close()
