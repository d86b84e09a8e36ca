"""Isolated spikes in a log's position-like signals (laser ranges, pitch, height, leg
angles, leg lengths): the Hampel test :func:`isolated_spikes`, its window, threshold and
per-column floors [the column's unit], and what loading does with a spike (refuse the log
naming the sample, or replace it by its neighbours' median and report it).
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from .log_format import COLUMN_UNITS, LogError, row_text

__all__ = ["SPIKE_HALF_WINDOW", "SPIKE_K", "SPIKE_FLOOR", "isolated_spikes"]

# Isolated-spike test (a Hampel filter; :func:`isolated_spikes`). A sample is a spike when
# it lies farther from the median of its 2 * SPIKE_HALF_WINDOW neighbours than both
# SPIKE_K of their scaled MADs (the neighbours agree among themselves, the sample does not
# agree with them) and the column's floor in SPIKE_FLOOR (a deviation large enough to be
# physically impossible for that signal within a few samples, and to matter).
#
# Window: 3 neighbours on each side (7 ms at the 1 kHz control rate). The median of six
# neighbours is unmoved by up to two other bad samples among them, so bursts of up to three
# bad samples are caught, while a plateau of four or more samples (a real step, an obstacle
# under a laser) is not "isolated" and is left alone. 7 ms is short against everything the
# comparison resolves (the 15 Hz low-pass has a 67 ms period; a stride lasts about 230 ms),
# so over the window the signals are close to straight lines, which a median follows.
#
# k = 5: at a clean step inside the window half the neighbours sit on each side, their
# scaled MAD is about 0.74 of the step and no sample deviates by more than the step, so any
# k > 1.4 leaves steps alone (the step changes of leg angles and rates at touchdown and
# lift-off); the classic k = 3 is meant for cleaning data, where a false alarm costs little,
# but here it would refuse the whole log, and the MAD of only six samples is often far below
# the noise level by chance (ratios |x - median| / MAD of 20-45 occur in the clean example
# logs), which is why the floor below does most of the work against noise.
#
# Floors: the largest single-sample error the comparison can ignore. A one-sample laser
# error of 2 cm moves a stride's filtered pitch extreme by at most 1 % and its height
# extremes by 0.1 % (measured on the example logs: the 15 Hz low-pass passes about 3 % of a
# one-sample impulse), well below the 5-15 % model errors Fig. 12 resolves; 2 cm is 20
# times the 1 mm laser noise of SensorNoise and 4 times the largest deviation of any
# sample from its neighbours' median in the shipped, make_example and noisy to_log logs of
# all three models (5 mm). Pitch and height floors are what a 2 cm error of one laser does
# to them (theta: 2 cm / (2 x 0.35 m) = 0.03 rad; height: 1 cm). Leg angles: 0.1 rad, 4
# times the largest deviation seen at touchdown/lift-off kinks in those logs (0.025 rad);
# a leg cannot swing 6 deg away and back within a few ms (its fastest motion is about
# 0.02 rad per 1 ms sample). Leg lengths: 2 cm, like the lasers (largest seen 2.3 mm).
#
# Not checked: leg rates (dphi), motor currents and torques. They are not positions:
# currents follow the controller's commands, which switch within one control period (a
# clean Model I simulation has a one-sample 15 A current pulse at a state change), and
# rates from encoder differences jump at impacts and with backlash; a one-sample pulse
# there is plausible, and none of them enters the Fig. 12 stride metrics.
SPIKE_HALF_WINDOW = 3
SPIKE_K = 5.0
#: column -> (floor in the column's unit, what the signal is)
SPIKE_FLOOR = {
    "laser_front_m": (0.02, "laser range"),
    "laser_back_m": (0.02, "laser range"),
    "pitch_rad": (0.03, "torso pitch"),
    "height_m": (0.01, "torso height"),
    "phi_back_rad": (0.1, "leg angle"),
    "phi_front_rad": (0.1, "leg angle"),
    "leg_length_back_m": (0.02, "leg length"),
    "leg_length_front_m": (0.02, "leg length"),
}
#: scaled MAD = 1.4826 MAD estimates the standard deviation of Gaussian noise
_MAD_TO_SIGMA = 1.4826
#: rows per block of the spike test (bounds its memory to a few MB per block)
_SPIKE_BLOCK = 1 << 16


def isolated_spikes(x, floor: float, half_window: int = SPIKE_HALF_WINDOW, k: float = SPIKE_K):
    """Hampel test for isolated spikes (see the comment at :data:`SPIKE_K`).

    Parameters
    ----------
    x : (n,) float array, finite
        One signal sampled uniformly.
    floor : float
        Smallest deviation from the neighbours' median that counts as a spike [unit of x].
    half_window : int
        Neighbours on each side (at the ends the record is mirrored, without repeating the
        end sample, so a first or last sample is tested against real neighbours).
    k : float
        Threshold in scaled MADs (1.4826 x MAD) of the neighbours.

    Returns
    -------
    flagged : (n,) bool array
        ``|x - median| > max(k * scaled MAD, floor)``.
    median, allowed : (n,) float arrays
        Median of the 2 * half_window neighbours (the sample itself excluded) and the
        allowed deviation from it [unit of x].
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    h = int(half_window)
    if n < 2 * h + 1:  # too few samples to have neighbours on both sides: nothing to test
        return np.zeros(n, bool), x.copy(), np.full(n, np.inf)
    windows = sliding_window_view(np.pad(x, h, mode="reflect"), 2 * h + 1)  # a view
    median = np.empty(n)
    scale = np.empty(n)
    for a in range(0, n, _SPIKE_BLOCK):
        nb = np.delete(windows[a : a + _SPIKE_BLOCK], h, axis=1)  # the neighbours only
        m = np.median(nb, axis=1)
        median[a : a + m.size] = m
        scale[a : a + m.size] = _MAD_TO_SIGMA * np.median(np.abs(nb - m[:, None]), axis=1)
    allowed = np.maximum(k * scale, floor)
    return np.abs(x - median) > allowed, median, allowed


def check_spikes(path, cols: dict, header_line: int | None, repairs: list | None = None):
    """LogError at the first isolated spike of a :data:`SPIKE_FLOOR` column; with a list
    ``repairs`` instead, every spike is replaced by its neighbours' median and listed there
    (column, row, value, median)."""
    h = SPIKE_HALF_WINDOW
    for c, (floor, what) in SPIKE_FLOOR.items():
        if c not in cols:
            continue
        v = cols[c]
        flagged, median, allowed = isolated_spikes(v, floor)
        if not flagged.any():
            continue
        if repairs is not None:
            rows = np.flatnonzero(flagged)
            repairs.extend((c, int(k) + 1, float(v[k]), float(median[k])) for k in rows)
            cols[c] = np.where(flagged, median, v)
            continue
        k = int(np.argmax(flagged))
        u = COLUMN_UNITS[c]
        count = int(flagged.sum())
        raise LogError(
            f"{path}: column '{c}', {row_text(k + 1, header_line)}: value {v[k]:.6g} {u} is "
            f"an isolated spike: the {2 * h} neighbouring samples ({h} on each side) agree on "
            f"a median of {median[k]:.6g} {u} and it lies {abs(v[k] - median[k]):.4g} {u} "
            f"from it; allowed: within {allowed[k]:.4g} {u} of the neighbours' median (the "
            f"larger of {SPIKE_K:g} scaled MADs of the neighbours and {floor:g} {u}) "
            f"({count} such sample(s) in the column). A {what} cannot jump away and back "
            "within a few samples: fix the sample (e.g. replace it by the neighbours' median "
            f"{median[k]:.6g} {u}; deleting the row would break the uniform time grid), cut "
            "the log before or after it, or load it with repair_spikes=True (scoutsim "
            "compare / plot --repair-spikes), which does that replacement and reports it",
            path,
            c,
            k + 1,
        )
