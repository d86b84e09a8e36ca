"""The files ``scoutsim run`` writes beyond the run's tables, and what it does when the
disk refuses them: the plain ``timeseries.csv`` (:func:`write_timeseries_csv`), Ctrl-C held
while the outputs are written (:func:`ctrl_c_deferred`), and a run whose directory could not
be written saved elsewhere (:func:`rescue`, :func:`streamed_write_failed`; exit status
:data:`EXIT_WRITE_FAILED`).
"""

from __future__ import annotations

import signal
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace

from ..result.columns import column_unit

#: exit status of a run whose outputs could not be written (BSD sysexits EX_IOERR)
EXIT_WRITE_FAILED = 74


@contextmanager
def ctrl_c_deferred():
    """While the outputs are written, a first Ctrl-C is held until they are whole (the
    command then exits 130); a second one abandons them (KeyboardInterrupt: the directory
    keeps saying "writing"). Writing a run takes a fraction of its computing."""
    state = SimpleNamespace(asked=False)
    if threading.current_thread() is not threading.main_thread():
        yield state
        return

    def handler(signum, frame):
        if state.asked:
            raise KeyboardInterrupt
        state.asked = True
        print(
            "scoutsim run: writing the outputs; they will be complete in a moment "
            "(Ctrl-C again to abandon them)",
            file=sys.stderr,
            flush=True,
        )

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield state
    finally:
        signal.signal(signal.SIGINT, previous)


def streamed_write_failed(result, out, rd) -> int:
    """A streamed run whose tables the disk refused: say what the directory kept, mark it
    partial, save the kept end of the run elsewhere."""
    info = result.provenance["stream"]
    print(
        f"scoutsim run: error: could not write the run's tables to {out}/: "
        f"{info['write_error']}; the run stopped at t = {result.t_end:g} s",
        file=sys.stderr,
    )
    kept = ", ".join(info["tables_kept"]) or "no table"
    until = info["written_until_s"]
    print(
        f"scoutsim run: {out}/ keeps {kept}"
        + (f" (samples up to t = {until:g} s)" if until is not None else ""),
        file=sys.stderr,
    )
    try:
        rd.finish(outcome=result.outcome, partial=True)
    except OSError:
        pass  # (the manifest keeps saying "writing")
    print(rescue(result, f"the run's last {info['keep_seconds']:g} s"), file=sys.stderr)
    return EXIT_WRITE_FAILED


def rescue(result, what: str = "the run's data") -> str:
    """Save a run whose output directory failed somewhere else (the system's temporary
    directory, then the home directory): what was computed is not lost. The message."""
    import os
    import tempfile

    name = f"scoutsim_rescued_{os.getpid()}_{int(time.time())}.npz"
    for d in (Path(tempfile.gettempdir()), Path.home()):
        try:
            path = result.save(d / name)
        except OSError:
            continue
        return f"scoutsim run: {what} saved instead to {path} (SimulationResult.load reads it)"
    return f"scoutsim run: {what} could not be saved anywhere (no space left?)"


def write_timeseries_csv(result, path) -> Path:
    """Write ``result.columns()`` as CSV, one row per sample, header ``name [unit]``; floats
    with 17 significant digits, so ``np.loadtxt`` reads every value back bit for bit."""
    import numpy as np

    cols = result.columns()
    names = list(cols)
    header = ",".join(f"{n} [{u}]" if (u := column_unit(n)) else n for n in names)
    data = (
        np.column_stack([np.asarray(cols[n], dtype=float) for n in names])
        if names
        else np.zeros((0, 0))
    )
    path = Path(path)
    # 17 significant digits: every float64 reads back to the same bits
    np.savetxt(path, data, delimiter=",", header=header, comments="", fmt="%.17g")
    return path
