"""A run's output directory: one run per directory, every file written whole or not at all,
and a manifest that says which files belong to the run and whether it completed.

    with RunDirectory(out, command="scoutsim run ...") as rd:   # the old run's files go
        rd.write("summary.json", lambda path: path.write_text(text))
        ...
        rd.finish(outcome="completed", partial=False)             # manifest: complete

``manifest.json`` is written first with ``"status": "writing"`` and rewritten last with
``"complete"`` (or ``"partial"``: the run was interrupted and the files hold the data up to
that moment), listing every file with its size in bytes. A directory whose manifest
still says ``"writing"`` was cut off while it was written; :func:`check_run_directory`
refuses it. Each file is written under a temporary name (``NAME.partial.SUFFIX``) and
renamed into place when complete, so no file is ever seen half-written.

:func:`json_safe` makes a value fit for the strict JSON files of a run (summaries, best
parameters): no NaN or Infinity, no NumPy scalars.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

__all__ = [
    "MANIFEST",
    "json_default",
    "RunDirectory",
    "atomic_write",
    "read_manifest",
    "check_run_directory",
    "add_to_manifest",
    "IncompleteRunError",
    "json_safe",
]

#: name of the manifest file
MANIFEST = "manifest.json"
FORMAT = "scoutsim.run-directory/1"
#: suffix of a file being written
PARTIAL_SUFFIX = ".partial"


class IncompleteRunError(ValueError):
    """A run directory whose writing was cut off (its manifest says "writing")."""


def atomic_write(path, write) -> Path:
    """Call ``write(tmp_path)`` to write a temporary file next to ``path``, then rename it to
    ``path`` (atomic on one file system). The temporary file is removed if ``write``
    fails or is interrupted."""
    path = Path(path)
    # NAME.partial.SUFFIX: writers that go by the suffix (figures, .npz) still see theirs
    tmp = path.with_name(path.name + PARTIAL_SUFFIX + path.suffix)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        try:
            tmp.unlink()
        except OSError:
            pass
        raise
    return path


def json_safe(v):
    """``v`` for strict JSON (no NaN / Infinity): every non-finite float becomes None, NumPy
    scalars become Python numbers, tuples lists; dicts and lists are converted item by
    item, anything else is returned as it is."""
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, dict):
        return {k: json_safe(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [json_safe(x) for x in v]
    if isinstance(v, (np.floating, np.integer)):
        return json_safe(v.item())
    return v


def json_default(v):
    """JSON's fallback (``json.dumps(..., default=json_default)``) for a value it does not
    take: a NumPy scalar as its number, anything else as its repr (a study's checkpoint
    records, a tuning's files)."""
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    return repr(v)


def read_manifest(directory) -> dict | None:
    """The manifest of a run directory, or None if it has none."""
    p = Path(directory) / MANIFEST
    if not p.exists():
        return None
    try:
        manifest = json.loads(p.read_text())
    except (OSError, ValueError) as exc:
        raise IncompleteRunError(f"{p}: unreadable manifest ({exc})") from None
    if manifest.get("format") != FORMAT:
        raise IncompleteRunError(f"{p}: not a scoutsim run manifest")
    return manifest


def check_run_directory(directory) -> dict | None:
    """The manifest of ``directory`` if its run was written completely (status "complete"
    or "partial", every listed file present with its size); None without a manifest.
    IncompleteRunError otherwise, naming what is wrong."""
    manifest = read_manifest(directory)
    if manifest is None:
        return None
    d = Path(directory)
    if manifest.get("status") not in ("complete", "partial"):
        raise IncompleteRunError(
            f"{d}: the run's files were not all written (the manifest "
            f"says '{manifest.get('status')}'): writing was cut off"
        )
    for name, info in manifest.get("files", {}).items():
        p = d / name
        if not p.exists() or p.stat().st_size != info["bytes"]:
            raise IncompleteRunError(f"{d}: {name} is missing or not the file the manifest lists")
    return manifest


def add_to_manifest(directory, names) -> None:
    """List files written (atomically) after the run's manifest was finished, e.g. figures
    made from a finished sweep's table; the manifest is rewritten atomically."""
    d = Path(directory)
    manifest = read_manifest(d)
    if manifest is None:
        raise IncompleteRunError(f"{d}: no manifest to add {list(names)} to")
    for name in names:
        manifest["files"][name] = {"bytes": (d / name).stat().st_size}
    text = json.dumps(manifest, indent=2, allow_nan=True) + "\n"
    atomic_write(d / MANIFEST, lambda p: p.write_text(text))


class RunDirectory:
    """The output directory of one run (see the module docstring). Entering it removes the
    files an earlier run listed in its manifest (and stale ``.partial`` files) and marks the
    directory as being written."""

    def __init__(self, directory, *, command: str = "", info: dict | None = None):
        self.dir = Path(directory)
        self.command = command
        self.info = dict(info or {})
        self.files: list[str] = []

    def __enter__(self) -> RunDirectory:
        return self.open()

    def open(self) -> RunDirectory:
        """Start writing the run (what entering the ``with`` block does, for writers whose
        run spans more than one block): the old run's files go, the manifest says
        "writing"."""
        self.dir.mkdir(parents=True, exist_ok=True)
        try:
            old = read_manifest(self.dir)
        except IncompleteRunError:
            old = None
        for name in (old or {}).get("files", {}):
            try:
                (self.dir / name).unlink()
            except OSError:
                pass
        stale_files = set(self.dir.glob("*" + PARTIAL_SUFFIX))
        stale_files |= set(self.dir.glob("*" + PARTIAL_SUFFIX + ".*"))
        for stale in stale_files:
            try:
                stale.unlink()
            except OSError:
                pass
        self._write_manifest("writing")
        return self

    def __exit__(self, *exc) -> None:
        return None  # the manifest keeps saying "writing" unless finish() was reached

    def write(self, name: str, write) -> Path:
        """Write the run's file ``name`` atomically with ``write(tmp_path)``."""
        path = atomic_write(self.dir / name, write)
        self.add(name)
        return path

    def add(self, name: str) -> None:
        """Count an already written file (written atomically by its own writer) as the
        run's."""
        if name not in self.files:
            self.files.append(name)

    def finish(self, *, outcome: str, partial: bool) -> Path:
        """Rewrite the manifest last: "partial" if the run was interrupted, else "complete",
        with every file's size."""
        return self._write_manifest("partial" if partial else "complete", outcome=outcome)

    def _write_manifest(self, status: str, outcome: str | None = None) -> Path:
        files = {}
        if status != "writing":
            for name in self.files:
                p = self.dir / name
                files[name] = {"bytes": p.stat().st_size}
        manifest = {
            "format": FORMAT,
            "status": status,
            "command": self.command,
            "outcome": outcome,
            **self.info,
            "files": files,
        }
        text = json.dumps(manifest, indent=2, allow_nan=True) + "\n"
        return atomic_write(self.dir / MANIFEST, lambda p: p.write_text(text))
