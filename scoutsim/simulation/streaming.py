"""A run streamed to disk as it is computed: memory bounded whatever the duration.

``simulate(..., stream_to=DIR)`` hands each piece of the run
(:data:`scoutsim.simulation.budgets.STREAM_CHUNK_SECONDS` of control samples) to a
:class:`RunStream` as soon as the compiled loop has computed it: the samples, events
and (with ``record_steps``) integrator steps go to the tables of DIR
(:class:`scoutsim.io.tables.TableWriter`: the same ``timeseries``, ``events`` and ``steps``
tables, column for column and bit for bit, as :meth:`SimulationResult.save_tables` of the
same run held in memory), and the engine's buffers are emptied for the next chunk. Only
the last ``keep_seconds`` of the run stay in memory: :func:`simulate` returns them as its
result (``result.t[0]`` is where the kept window starts; outcome, end time and statistics
are the whole run's), and ``result.provenance["stream"]`` says where the rest is.

The tables are written under temporary names until the run ends, then renamed and listed
in the directory's manifest (:class:`scoutsim.io.run_directory.RunDirectory`): a run cut off
by a kill leaves no table that looks whole; a run interrupted by Ctrl-C, or one that fell
or failed, writes everything it computed. ``SimulationResult.load(DIR)`` reads the whole
run back (it must then fit in memory).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._core.model import layout as L
from ..io.run_directory import RunDirectory
from ..io.tables import TableWriter
from ..result.run_files import TABLES_FORMAT
from ..result.simulation_result import SimulationResult

__all__ = ["RunStream", "DEFAULT_KEEP_SECONDS", "take_piece", "join_pieces"]

#: seconds of the end of a streamed run kept in memory (and returned) by default: enough
#: for the steady-state gait metrics of the summary (a stride is about 0.3 s)
DEFAULT_KEEP_SECONDS = 60.0


def take_piece(eng) -> SimulationResult:
    """What the engine ``eng`` computed since the last call (samples, events and, with
    ``record_steps``, steps) as a result of its own (outcome "running"), the engine's
    buffers emptied for the next piece."""
    n, m = eng.n_out, min(eng.nev, eng.ev.shape[0])
    nst = int(eng.stepc[0]) if eng.stepc[1] else 0
    piece = SimulationResult(
        t=eng.out_t[:n].copy(),
        state=eng.out_s[:n].copy(),
        aux=eng.out_aux[:n].copy(),
        modes=eng.out_ls[:n].copy(),
        events=eng.ev[:m, : L.NEVREC].copy(),
        event_states=eng.ev[:m, L.NEVREC :].reshape(m, 2, L.NS).copy(),
        steps=eng.steps[:nst].copy() if eng.stepc[1] else None,
        energy_series=eng.out_energy[:n].copy() if eng.energy.size else None,
        outcome="running",
        t_end=float(eng.t_now),
        stats={},
        provenance={},
    )
    eng.n_out = eng.nev = 0
    eng.stepc[0] = 0
    return piece


def join_pieces(pieces: list, whole: SimulationResult) -> SimulationResult:
    """The pieces of a run (:func:`take_piece`, in time order) joined into one result
    with the whole run's outcome, end, statistics, provenance and energy totals
    (``whole``)."""
    steps = [c.steps for c in pieces if c.steps is not None]
    energy = [c.energy_series for c in pieces if c.energy_series is not None]
    return SimulationResult(
        t=np.concatenate([c.t for c in pieces]),
        state=np.concatenate([c.state for c in pieces]),
        aux=np.concatenate([c.aux for c in pieces]),
        modes=np.concatenate([c.modes for c in pieces]),
        events=np.concatenate([c.events for c in pieces]),
        event_states=np.concatenate([c.event_states for c in pieces]),
        steps=np.concatenate(steps) if steps else None,
        energy_series=np.concatenate(energy) if energy else None,
        outcome=whole.outcome,
        t_end=whole.t_end,
        stats=whole.stats,
        provenance=whole.provenance,
        energy_flows=whole.energy_flows,
    )


class RunStream:
    """The destination of a streamed run (module docstring).

    Parameters
    ----------
    directory : the run directory (created; an earlier run's files there are removed when
        the first rows arrive), or a :class:`~scoutsim.io.run_directory.RunDirectory` (not yet
        entered) that the caller finishes itself (the command line adds its summary and
        figures to the same run).
    fmt : table format, "parquet" or "csv" (default: Parquet if pyarrow is installed).
    keep_seconds : seconds at the end of the run kept in memory for the returned result.
    command : the command line recorded in the manifest.
    """

    def __init__(
        self,
        directory,
        *,
        fmt: str | None = None,
        keep_seconds: float = DEFAULT_KEEP_SECONDS,
        command: str = "",
    ):
        if not (np.isfinite(keep_seconds) and keep_seconds >= 0):
            raise ValueError(
                f"keep_seconds = {keep_seconds!r} s is not allowed: must be a finite number >= 0"
            )
        self._own = not isinstance(directory, RunDirectory)
        self._opened = False
        self._rd: RunDirectory | None = None if self._own else directory
        self.dir = Path(directory) if self._own else directory.dir
        self.fmt = fmt
        self.keep_seconds = float(keep_seconds)
        self.command = command
        self._writers: dict[str, TableWriter] = {}
        self._kept: list[SimulationResult] = []  # chunks within the kept window
        self.n_samples = 0
        #: time of the last sample computed [s] (None before the first)
        self.last_sample_t: float | None = None
        #: time of the last sample handed to the time-series table [s]
        self.written_until_s: float | None = None
        #: the OSError that stopped the writing (a full disk), or None
        self.write_error: OSError | None = None

    # -- while the run goes -----------------------------------------------------------
    def _open(self) -> None:
        """Enter the run directory (an earlier run's files there go) when the first rows
        arrive: a run refused before it starts leaves the directory as it was."""
        if self._own:
            self._rd = RunDirectory(
                self.dir, command=self.command, info={"kind": "run", "streamed": True}
            )
        self._run_dir.open()
        self._opened = True

    @property
    def _run_dir(self) -> RunDirectory:
        """The run directory (this stream's own is made when the first rows arrive)."""
        if self._rd is None:
            raise RuntimeError("the stream's run directory is opened by its first take()")
        return self._rd

    def take(self, eng) -> bool:
        """Write what the engine computed since the last call and empty its buffers; False
        if the disk refused it (a full disk: :attr:`write_error`, the run should stop)."""
        return self.write(take_piece(eng))

    def write(self, chunk: SimulationResult) -> bool:
        """Write the piece ``chunk`` of the run (:func:`take_piece`); False if the disk
        refused it (a full disk: :attr:`write_error`, the run should stop)."""
        if not self._opened:
            self._open()
        n = len(chunk.t)
        if n == 0 and len(chunk.events) == 0 and (chunk.steps is None or len(chunk.steps) == 0):
            return True
        self._keep(chunk)
        if n:
            self.last_sample_t = float(chunk.t[-1])
        tables = chunk.tables()
        # the time series last: if the disk refuses a piece, the events and steps tables
        # may hold it while the time series (whose metadata says where the run got to)
        # does not
        for name in sorted(tables, key=lambda name: name == "timeseries"):
            cols, units = tables[name]
            w = self._writers.get(name)
            if w is None:
                w = self._writers[name] = TableWriter(self.dir / name, units=units, fmt=self.fmt)
            try:
                w.append(cols)
            except OSError as exc:
                self.write_error = exc
                return False
        self.n_samples += n
        self.written_until_s = self.last_sample_t
        return True

    def _keep(self, chunk: SimulationResult) -> None:
        self._kept.append(chunk)
        t_last = next((c.t[-1] for c in reversed(self._kept) if len(c.t)), None)
        if t_last is None:
            return
        start = t_last - self.keep_seconds
        # drop whole chunks that end before the window (the first kept one is cut later)
        while len(self._kept) > 1 and (
            len(self._kept[0].t) == 0 or self._kept[1].t.size and self._kept[1].t[0] <= start
        ):
            self._kept.pop(0)

    # -- at the end ---------------------------------------------------------------------
    def finish(self, whole: SimulationResult, *, partial: bool) -> SimulationResult:
        """Close the tables with the whole run's metadata (``whole``: outcome, end time,
        statistics, provenance, no rows), complete the manifest, and return the kept end of
        the run as a result."""
        whole.provenance["stream"] = {
            "directory": str(self.dir),
            "n_samples": self.n_samples,
            "keep_seconds": self.keep_seconds,
        }
        if not self._opened:  # stopped before its first rows: a directory that says so
            self._open()
        if self.write_error is not None:
            self._salvage(whole)
            return self._kept_result(whole)
        try:
            for name, w in self._writers.items():
                meta = (
                    whole.series_metadata() if name == "timeseries" else {"format": TABLES_FORMAT}
                )
                w.close(metadata=meta)
                self._run_dir.add(w.path.name)
        except BaseException:
            self.abort()
            raise
        if self._own:
            self._run_dir.finish(outcome=whole.outcome, partial=partial)
        return self._kept_result(whole)

    def _salvage(self, whole: SimulationResult) -> None:
        """After a write error (``whole.outcome`` "write_failed"): close each table with
        the rows it has, as far as the disk allows (a table that cannot be closed is
        removed), and mark the directory partial; what happened goes into the provenance.
        Nothing here raises: the caller still gets the kept end of the run."""
        info = whole.provenance["stream"]
        error = self.write_error
        assert error is not None, "salvaged only after a write error"
        info["write_error"] = f"{error.strerror or error}"
        info["written_until_s"] = self.written_until_s
        info["tables_kept"] = []
        for name, w in self._writers.items():
            meta = whole.series_metadata() if name == "timeseries" else {"format": TABLES_FORMAT}
            if name == "timeseries":
                meta["t_end"] = self.written_until_s  # where its samples end
            try:
                w.close(metadata=meta)
            except Exception:  # noqa: BLE001 - the disk's or pyarrow's error: close() removed
                continue  # the table's files, the others may still be kept
            self._run_dir.add(w.path.name)
            info["tables_kept"].append(w.path.name)
        if self._own:
            try:
                self._run_dir.finish(outcome=whole.outcome, partial=True)
            except OSError:
                pass  # the manifest keeps saying "writing"

    def abort(self) -> None:
        """Give the tables up (their temporary files are removed; the manifest keeps
        saying "writing")."""
        for w in self._writers.values():
            w.abort()

    def _kept_result(self, whole: SimulationResult) -> SimulationResult:
        """The last ``keep_seconds`` of the kept pieces (from their first sample in the
        window on), with the whole run's outcome, end, statistics and provenance."""
        info = whole.provenance["stream"]
        ch = self._kept
        if not any(len(c.t) for c in ch):  # nothing computed (stopped before a sample)
            info["kept_from_s"] = None
            return whole
        joined = join_pieces(ch, whole)
        t0 = float(joined.t[np.searchsorted(joined.t, joined.t[-1] - self.keep_seconds)])
        info["kept_from_s"] = t0
        return joined.window(t0, np.inf)
