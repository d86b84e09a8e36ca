"""The robot's torso sensors and the filter of the paper's measurement chain (paper Sec.
IV.B): the two laser range finders at the torso ends (:class:`LaserGeometry`, from
torso pose to ranges and back) and the zero-phase FFT low-pass applied to the laser data
after the fact (:func:`fft_lowpass`; its shape and edge effects are described in
:mod:`scoutsim.validation.measurement`). Used both to read a log
(:mod:`scoutsim.validation.experiment_log`) and to simulate what the robot would have logged
(:mod:`scoutsim.validation.measurement`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "LaserGeometry",
    "laser_ranges",
    "pitch_height_from_lasers",
    "fft_lowpass",
    "lowpass_gain",
    "EDGE_S",
]

#: Time [s] at each end of a record within which the low-pass has edge effects.
EDGE_S = 0.3


@dataclass(frozen=True)
class LaserGeometry:
    """Where the two laser range finders are (see :mod:`scoutsim.validation.log_format`).

    half_spacing_m : distance of each laser from the torso COM along the torso axis [m]
        (default 0.35 = torso_length / 2, the torso ends).
    mount_offset_m : offset of the laser aperture below the torso axis, along the torso's
        downward normal [m] (default 0).
    """

    half_spacing_m: float = 0.35
    mount_offset_m: float = 0.0

    def __post_init__(self):
        if not (math.isfinite(self.half_spacing_m) and self.half_spacing_m > 0):
            raise ValueError(
                f"half_spacing_m = {self.half_spacing_m!r} is not allowed: must "
                "be a finite number > 0"
            )
        if not math.isfinite(self.mount_offset_m):
            raise ValueError(
                f"mount_offset_m = {self.mount_offset_m!r} is not allowed: must be finite"
            )


def laser_ranges(height, pitch, geometry: LaserGeometry | None = None):
    """(front, back) ranges [m] of the two lasers for COM height ``height`` [m] and pitch
    ``pitch`` [rad] over flat ground ``y = 0``."""
    g = geometry or LaserGeometry()
    y = np.asarray(height, dtype=float)
    th = np.asarray(pitch, dtype=float)
    c = np.cos(th)
    s = np.sin(th)
    d = g.half_spacing_m
    return (y + d * s) / c - g.mount_offset_m, (y - d * s) / c - g.mount_offset_m


def pitch_height_from_lasers(front, back, geometry: LaserGeometry | None = None):
    """(pitch [rad], COM height [m]) from the two laser ranges (exact inverse of
    :func:`laser_ranges`)."""
    g = geometry or LaserGeometry()
    rf = np.asarray(front, dtype=float) + g.mount_offset_m
    rb = np.asarray(back, dtype=float) + g.mount_offset_m
    th = np.arctan((rf - rb) / (2.0 * g.half_spacing_m))
    return th, 0.5 * (rf + rb) * np.cos(th)


def lowpass_gain(f, cutoff_hz: float = 15.0, transition_hz: float = 5.0):
    """Gain of :func:`fft_lowpass` at frequencies ``f`` [Hz]."""
    f = np.abs(np.asarray(f, dtype=float))
    if transition_hz <= 0:
        return (f <= cutoff_hz).astype(float)
    lo = cutoff_hz - 0.5 * transition_hz
    g = np.where(f <= lo, 1.0, 0.0)
    m = (f > lo) & (f < lo + transition_hz)
    g[m] = 0.5 * (1.0 + np.cos(math.pi * (f[m] - lo) / transition_hz))
    return g


def fft_lowpass(
    x, fs: float, cutoff_hz: float = 15.0, transition_hz: float = 5.0, pad_s: float = 1.0
) -> np.ndarray:
    """Zero-phase FFT low-pass of a uniformly sampled record (see the module docstring).

    Parameters
    ----------
    x : (n,) array
    fs : sample rate [Hz]
    cutoff_hz : half-gain frequency [Hz] (default 15, as in the paper)
    transition_hz : width of the raised-cosine roll-off [Hz]; 0 = brick-wall
    pad_s : length of the odd-reflection extension at each end [s]
    """
    if not (cutoff_hz > 0 and transition_hz >= 0 and transition_hz < 2 * cutoff_hz):
        raise ValueError(
            f"cutoff_hz = {cutoff_hz}, transition_hz = {transition_hz} are not "
            "allowed: need cutoff > 0 and 0 <= transition < 2 cutoff"
        )
    x = np.asarray(x, dtype=float)
    n = x.shape[0]
    if n < 3:
        return x.copy()
    p = min(n - 1, int(round(pad_s * fs)))
    ext = np.concatenate([2 * x[0] - x[p:0:-1], x, 2 * x[-1] - x[-2 : -p - 2 : -1]])
    spec = np.fft.rfft(ext)
    f = np.fft.rfftfreq(ext.shape[0], 1.0 / fs)
    return np.fft.irfft(spec * lowpass_gain(f, cutoff_hz, transition_hz), ext.shape[0])[p : p + n]
