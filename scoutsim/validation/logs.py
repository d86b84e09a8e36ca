"""Experiment logs: one bounding run of the robot (or a synthetic stand-in) sampled at the
control rate (1 kHz on Scout II), stored as CSV, gzip-compressed CSV or Parquet, in SI
units (the unit is part of every column name).

Modules (``scoutsim.validation.``)
----------------------------------
log_format       the file format: the columns and their units [s, m, rad, rad/s, A, N m],
                 the metadata keys and defaults, the laser geometry, the file suffixes,
                 :class:`LogError`
log_checks       the checks of a loaded file's header and values
log_spikes       the isolated-spike test, its window, threshold and floors
experiment_log   :class:`ExperimentLog`: a log read by name
log_reading      :func:`load_log`, :func:`load_dataset`
log_writing      :func:`save_log`

Their public names are importable from here too
(``from scoutsim.validation.logs import load_log``).
"""

from __future__ import annotations

from .experiment_log import LEGS, ExperimentLog
from .log_checks import UNIFORM_TOLERANCE
from .log_format import (
    ALTERNATIVE_COLUMNS,
    COLUMN_UNITS,
    DEFAULT_META,
    LOG_SUFFIXES,
    OPTIONAL_COLUMNS,
    REQUIRED_COLUMNS,
    LogError,
)
from .log_reading import load_dataset, load_log
from .log_spikes import SPIKE_FLOOR, SPIKE_HALF_WINDOW, SPIKE_K, isolated_spikes
from .log_writing import save_log

__all__ = [
    "ExperimentLog",
    "LogError",
    "load_log",
    "load_dataset",
    "save_log",
    "REQUIRED_COLUMNS",
    "OPTIONAL_COLUMNS",
    "COLUMN_UNITS",
    "DEFAULT_META",
    "LOG_SUFFIXES",
    "SPIKE_HALF_WINDOW",
    "SPIKE_K",
    "SPIKE_FLOOR",
    "isolated_spikes",
    "ALTERNATIVE_COLUMNS",
    "UNIFORM_TOLERANCE",
    "LEGS",
]
