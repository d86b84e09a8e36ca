"""A sweep's checkpoint (:mod:`scoutsim.analysis.sweep`): the file in its output directory
that a resumed sweep (or tuning) goes on from, one JSON record per finished point, and how
its records are read back and written (JSON's fallback for a record's NumPy values:
:func:`~scoutsim.io.run_directory.json_default`).
"""

from __future__ import annotations

import json
from pathlib import Path

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
