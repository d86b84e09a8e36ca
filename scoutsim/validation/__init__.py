"""Simulation against experiment (paper Sec. IV.C, Fig. 12; docs/specification.md section 8).

- :mod:`.logs`: the experiment log format, :func:`load_log`, :func:`load_dataset`,
  :class:`ExperimentLog`.
- :mod:`.measurement`: the robot's measurement chain simulated (lasers, 15 Hz FFT
  low-pass, torque from current); :func:`to_log` turns a simulation into a log.
- :mod:`.strides`: strides and per-stride metrics of a log.
- :mod:`.errors`: the Fig. 12 error assessment, :func:`compare`.

See docs/validation.md.
"""

from .logs import ExperimentLog, LogError, load_dataset, load_log, save_log
from .measurement import LaserGeometry, SensorNoise, fft_lowpass, to_log
from .strides import log_strides

__all__ = ["ExperimentLog", "LogError", "load_log", "load_dataset", "save_log",
           "LaserGeometry", "SensorNoise", "fft_lowpass", "to_log", "log_strides"]
