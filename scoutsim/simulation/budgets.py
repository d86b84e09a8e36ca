"""What a run needs before it starts: memory for its time series
(:func:`check_run_memory`), disk for a streamed run's tables (:func:`check_stream_disk`)
and wall time (:func:`expected_wall_time`), with the sizes they count."""

from __future__ import annotations

import os
from pathlib import Path

from .._core.model import layout as L

__all__ = [
    "check_run_memory",
    "time_series_bytes",
    "check_stream_disk",
    "expected_wall_time",
    "physical_memory_bytes",
    "STREAM_CHUNK_SECONDS",
    "PEAK_PER_SERIES",
    "WALL_S_PER_SIMULATED_S",
]


#: bytes a run holds per control sample: time, state, outputs (float64) and modes (int8)
BYTES_PER_SAMPLE = 8 * (1 + L.NS + L.NAUX) + L.NRM
#: ... per integrator step when steps are recorded, and steps per sample counted for it
#: (measured 1.3 for Model II at the default tolerance and for Model I; 3 leaves room)
BYTES_PER_STEP = 8 * L.NSTEPREC
STEPS_PER_SAMPLE = 3
#: the event buffer: rows per second of run and bytes per row (HybridEngine)
EVENT_ROWS_PER_S = 200
BYTES_PER_EVENT = 8 * L.NEVBUF


def physical_memory_bytes() -> int | None:
    """This machine's physical memory [bytes], or None where the OS does not say."""
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None


def _bytes_per_sample(record_steps: bool, dt: float, record_every: int) -> float:
    return (
        BYTES_PER_SAMPLE / record_every
        + (STEPS_PER_SAMPLE * BYTES_PER_STEP if record_steps else 0)
        + EVENT_ROWS_PER_S * dt * BYTES_PER_EVENT
    )


def time_series_bytes(
    duration: float, *, record_steps: bool = False, dt: float = 1e-3, record_every: int = 1
) -> int:
    """The memory [bytes] the time series of a run of ``duration`` [s] takes held in
    memory: every ``record_every``-th control sample of period ``dt`` [s], the events
    and, with ``record_steps``, the integrator steps."""
    return int(int(duration / dt + 2) * _bytes_per_sample(record_steps, dt, record_every))


def check_run_memory(
    duration: float,
    *,
    record_steps: bool = False,
    dt: float = 1e-3,
    memory_bytes: int | None = None,
    record_every: int = 1,
) -> int:
    """The memory a run of ``duration`` [s] needs for its time series [bytes] (every
    ``record_every``-th control sample of period ``dt`` [s] recorded); ValueError if that
    is more than half of this machine's memory (``memory_bytes``, default: the physical
    memory), saying how long a run can be (a longer one can be split: resume from
    ``result.hybrid_state(-1)``)."""
    per_sample = _bytes_per_sample(record_steps, dt, record_every)
    need = time_series_bytes(duration, record_steps=record_steps, dt=dt, record_every=record_every)
    have = physical_memory_bytes() if memory_bytes is None else memory_bytes
    if have is not None and need > have // 2:
        longest = (have // 2) / per_sample * dt
        raise ValueError(
            f"duration = {duration:g} s is not allowed on this machine: the run's "
            f"time series would need {need / 1e9:.3g} GB of memory, more than half "
            f"of its {have / 1e9:.3g} GB; at most about {longest:.4g} s per run "
            "(stream it to disk: simulate(..., stream_to=DIR), scoutsim run "
            "--stream; simulate(..., check_memory=False) tries anyway)"
        )
    return need


#: a run held in memory and written by ``scoutsim run`` peaks at about this many times
#: the memory of its time series (:func:`check_run_memory`): the tables' columns while
#: they are written, the analysis; measured on Model II with the energy accounting
#: (``benchmarks/bench_scaling.py``): 3.7x at 600 s, 2.8x at 3600 s
PEAK_PER_SERIES = 4.0

#: bytes per control sample of a streamed run's tables on disk (time series and events),
#: with a margin: Parquet (zstd) of a 12 s Model II run takes 370 B per sample (the
#: doubles hardly compress), 536 B with the energy accounting's cumulative energies (10 s:
#: time series 506 B, events 30 B)
BYTES_PER_SAMPLE_ON_DISK = 700
#: simulated seconds per piece a streamed run writes (memory: about 4 MB per 10 s)
STREAM_CHUNK_SECONDS = 10.0


#: wall seconds per simulated second of each model with the default integrator: an upper
#: estimate for refusing absurd requests (measured on a 2-core virtual machine, one
#: core busy:
#: Model II 4.0-6.6 ms, Model I 2-3.6 ms, ideal 2-2.9 ms, passive 4.3 ms; the slower
#: figure doubled for a slower machine; benchmarks/bench_speed.py measures the speed)
WALL_S_PER_SIMULATED_S = {"II": 13e-3, "I": 7e-3, "ideal": 6e-3, "passive": 9e-3}


def expected_wall_time(duration: float, model: str = "II") -> float:
    """An upper estimate of the wall time [s] a run of ``duration`` [s] of ``model`` takes
    with the default integrator (:data:`WALL_S_PER_SIMULATED_S`)."""
    return duration * WALL_S_PER_SIMULATED_S.get(model, max(WALL_S_PER_SIMULATED_S.values()))


def check_stream_disk(
    duration: float, directory, *, record_steps: bool = False, dt: float = 1e-3
) -> int:
    """The disk space a streamed run of ``duration`` [s] needs for its tables [bytes] (an
    upper bound); ValueError if the file system of ``directory`` has less free space,
    saying how long a run fits."""
    import shutil

    per_sample = BYTES_PER_SAMPLE_ON_DISK * (1 + (STEPS_PER_SAMPLE if record_steps else 0))
    need = int((duration / dt + 2) * per_sample)
    d = Path(directory)
    while not d.exists() and d != d.parent:
        d = d.parent
    free = shutil.disk_usage(d).free
    if need > free:
        raise ValueError(
            f"duration = {duration:g} s is not allowed here: the streamed run's "
            f"tables would need up to {need / 1e9:.3g} GB on disk, and {d} has "
            f"{free / 1e9:.3g} GB free; at most about {free / per_sample * dt:.4g} "
            "s fit (simulate(..., check_memory=False), scoutsim run "
            "--no-size-check, tries anyway)"
        )
    return need
