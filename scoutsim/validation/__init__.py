"""Simulation against experiment (paper Sec. IV.C, Fig. 12; docs/specification.md section 8).

- :mod:`.logs`: experiment logs (re-exports :mod:`.log_format`, the file format and
  :class:`LogError`; :mod:`.log_checks` and :mod:`.log_spikes`, the checks of a loaded
  file; :mod:`.experiment_log`, :class:`ExperimentLog`; :mod:`.log_reading`,
  :func:`load_log`, :func:`load_dataset`; :mod:`.log_writing`, :func:`save_log`).
- :mod:`.measurement`: the robot's measurement chain simulated (lasers, 15 Hz FFT
  low-pass, torque from current); :func:`to_log` turns a simulation into a log.
- :mod:`.strides`: strides and per-stride metrics of a log.
- :mod:`.errors`: the Fig. 12 error assessment, :func:`compare`.

See docs/validation.md.
"""

from .experiment_log import ExperimentLog
from .log_format import LogError
from .log_reading import load_dataset, load_log
from .log_strides import log_strides
from .log_writing import save_log
from .measurement import LaserGeometry, SensorNoise, fft_lowpass, to_log

__all__ = [
    "ExperimentLog",
    "LogError",
    "load_log",
    "load_dataset",
    "save_log",
    "LaserGeometry",
    "SensorNoise",
    "fft_lowpass",
    "to_log",
    "log_strides",
]
