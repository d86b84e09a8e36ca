"""The arrays and records one run produced (:class:`RunData`): the fields of
:class:`~scoutsim.result.SimulationResult`, whose docstring says what each holds, in one
place for the class and for each of its accessor mixins."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["RunData"]


@dataclass
class RunData:
    """The fields of a run's result (:class:`~scoutsim.result.SimulationResult`)."""

    t: np.ndarray
    state: np.ndarray
    aux: np.ndarray
    modes: np.ndarray
    events: np.ndarray
    outcome: str
    t_end: float
    stats: dict
    provenance: dict
    event_states: np.ndarray | None = None
    steps: np.ndarray | None = None
    energy_flows: dict | None = None
    energy_series: np.ndarray | None = None
    stride_record: Any = field(default=None, repr=False, compare=False)
    _cache: dict = field(default_factory=dict, repr=False, compare=False)
