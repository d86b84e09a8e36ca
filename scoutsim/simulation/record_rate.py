"""A run's time series recorded at a lower rate than its control rate, its strides exact.

``simulate(record_rate=HZ)`` keeps every ``k``-th control sample (``k`` = control rate /
``HZ``, a whole number), counted from the run's first sample, and the run's last sample;
the events (their times and exact states), the integrator steps, the energy accounts
(``result.energy_flows``, integrated on every integrator step inside the core) are
not thinned. The strides need more than the kept samples (the torso at each back-leg
lift-off, the extremes between two): a :class:`~scoutsim.result.stride_record.StrideRecorder`
reads them from every sample, piece by piece as the compiled loop computes them, so that
the strides, gait metrics and per-stride energies of the thinned run are those of the same
run recorded at the full rate, bit for bit. A streamed run (``stream_to``) takes its pieces
through the same :class:`RecordedPieces`, so that its strides are the whole run's,
whatever it keeps in memory.
"""

from __future__ import annotations

import math

import numpy as np

from ..result.simulation_result import SimulationResult
from ..result.stride_record import StrideRecorder
from .streaming import RunStream, join_pieces, take_piece

__all__ = ["RecordedPieces", "samples_per_record"]


def samples_per_record(record_rate: float | None, control_period: float) -> int:
    """Control samples per recorded sample for ``record_rate`` [Hz] (None: every sample)
    at ``control_period`` [s]; ValueError naming the allowed rates if ``record_rate`` is
    not the control rate divided by a whole number."""
    if record_rate is None:
        return 1
    control_rate = 1.0 / control_period
    ok = isinstance(record_rate, (int, float)) and math.isfinite(record_rate) and record_rate > 0
    k = round(control_rate / record_rate) if ok else 0
    if not ok or k < 1 or abs(k * record_rate - control_rate) > 1e-9 * control_rate:
        examples = ", ".join(f"{control_rate / d:g}" for d in (1, 2, 4, 5, 10, 20, 100, 1000))
        raise ValueError(
            f"record_rate = {record_rate!r} Hz is not allowed: must be the control rate "
            f"{control_rate:g} Hz divided by a whole number ({examples}, ... Hz)"
        )
    return int(k)


def _last_sample(piece: SimulationResult) -> SimulationResult:
    """The last sample of ``piece`` alone (its events and steps go with the kept rows)."""
    last = np.zeros(len(piece.t), dtype=bool)
    last[-1] = True
    return piece.with_samples(
        last,
        events=piece.events[:0],
        event_states=None if piece.event_states is None else piece.event_states[:0],
        steps=None if piece.steps is None else piece.steps[:0],
    )


class RecordedPieces:
    """Takes a run's pieces from the engine: the stride recorder reads every sample, and
    every ``every``-th sample goes on, with the events and steps, to the ``stream``
    (:class:`~scoutsim.simulation.streaming.RunStream`) or, without one, into memory.

    Parameters
    ----------
    every : control samples per recorded sample (:func:`samples_per_record`).
    stream : the streamed run's destination, or None to keep the pieces in memory.
    robot : the run's :class:`~scoutsim.parameters.RobotParameters` (the motors'
        saturation counts of the summary).
    """

    def __init__(self, every: int, stream: RunStream | None, robot=None):
        self.every = int(every)
        self.stream = stream
        self.recorder = StrideRecorder(robot)
        self._pieces: list[SimulationResult] = []
        self._n = 0  # samples taken so far
        self._last: SimulationResult | None = None  # the last sample, if not recorded
        self._record = None
        #: time of the last sample taken [s] (None before the first)
        self.last_sample_t: float | None = None

    def take(self, eng) -> bool:
        """Take what the engine computed since the last call (its buffers emptied); False
        if a stream's disk refused it."""
        piece = take_piece(eng)
        self.recorder.feed(piece)
        n = len(piece.t)
        keep = (self._n + np.arange(n)) % self.every == 0
        self._n += n
        if n:
            self.last_sample_t = float(piece.t[-1])
            self._last = None if keep[-1] else _last_sample(piece)
        return self._put(piece.with_samples(keep) if self.every > 1 else piece)

    def close(self) -> bool:
        """Record the run's last sample if it was not (once, at the end of the run)."""
        last, self._last = self._last, None
        return True if last is None else self._put(last)

    def _put(self, piece: SimulationResult) -> bool:
        if self.stream is not None:
            return self.stream.write(piece)
        self._pieces.append(piece)
        return True

    def result(self, whole: SimulationResult) -> SimulationResult:
        """The run kept in memory (no stream): the recorded samples with every event and
        step, the whole run's outcome, statistics and energy totals (``whole``), and its
        stride record."""
        out = join_pieces(self._pieces, whole) if self._pieces else whole
        out.stride_record = self.stride_record()
        return out

    def stride_record(self):
        """The run's :class:`~scoutsim.result.stride_record.StrideRecord` (after its
        last piece)."""
        if self._record is None:
            self._record = self.recorder.finish()
        return self._record
