"""The result of a simulation: time series, events, outcome, statistics and provenance.

Arrays are sampled at the controller's sample times (1 kHz by default; a run that falls
or fails ends with one extra off-grid sample at that moment). Events are located in
continuous time. Saved losslessly as a single ``.npz`` file (arrays bit-exact, metadata as
JSON).

:class:`SimulationResult` is one class: its arrays and records are the fields of
:class:`~.run_data.RunData`, and its accessors are grouped by concept in mixins (each a
:class:`~.run_data.RunData`), one module each: :mod:`.series` (the time series by name
[SI]), :mod:`.event_log` (the event log), :mod:`.energy_accounts` (the energy accounting
[J, W]), :mod:`.columns` (named columns with units, tables, DataFrame) and
:mod:`.run_files` (saving and loading). This module holds the class (the analysis
computed on demand, windows) and re-exports the mixin modules' constants.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .._core.model import layout as L
from .columns import COLUMN_UNITS, ColumnViews, column_unit
from .energy_accounts import ENERGY_COLUMNS, ENERGY_GROUPS, ENERGY_WHOLE_ROBOT, EnergyAccessors
from .event_log import EventAccessors
from .failure import diagnose_failure
from .run_files import TABLES_FORMAT, ResultFiles
from .series import SeriesAccessors

__all__ = [
    "SimulationResult",
    "COLUMN_UNITS",
    "column_unit",
    "ENERGY_GROUPS",
    "ENERGY_WHOLE_ROBOT",
    "ENERGY_COLUMNS",
    "TABLES_FORMAT",
]


@dataclass
class SimulationResult(SeriesAccessors, EventAccessors, EnergyAccessors, ColumnViews, ResultFiles):
    """Everything one run produced.

    Attributes
    ----------
    t : (n,) sample times [s].
    state : (n, 16) states [x, y, theta, phi_b, phi_f, alpha_b, alpha_f, their rates,
        l_b, l_f] (SI; see ``scoutsim._core.model.layout.STATE_NAMES``).
    aux : (n, NAUX) outputs: ground forces, torques, currents, motor speeds, belt
        deflection, battery voltage, energy (``layout.A_*``).
    modes : (n, 6) int8: controller leg states (back, front), plant contact modes (back,
        front), motor-joint stiction modes (back, front); columns ``layout.RM_*``.
    events : (m, NEVREC) [t, kind, leg, v1, v2, v3, energy before / after, violations]
        (``layout.EVR_*``, kinds ``layout.EK_*``).
    outcome : "completed", "fell", "numerical_failure", "interrupted", "controller_error"
        (a user controller raised or returned bad torques: ``scoutsim.ControllerError``) or,
        for a run streamed to a disk that refused its tables, "write_failed" (:attr:`failure`
        says why a run failed numerically).
    t_end : time the run reached [s].
    stats : integrator statistics and contact diagnostics.
    provenance : parameters, model variant, tolerances, initial state, package version.
    event_states : (m, 2, 16) the exact state of each event record just before its
        transition and after its modes settled (``[:, layout.EVS_BEFORE]``,
        ``[:, layout.EVS_AFTER]``; controller records: the state at their sample), or
        None for results saved before it was recorded.
    steps : (k, NSTEPREC) every integrator step (time, state, plant modes; ``layout.STP_*``)
        if the run recorded them (``simulate(record_steps=True)``), else None.
    energy_flows : the whole run's energies [J] by name if it accounted for them
        (``simulate(energy=True)``), else None: per leg (``_back``, ``_front``) every power
        flow of ``layout.EN_LEG_NAMES`` integrated over the run, ``battery_loss``, the
        touchdown ``impacts``' losses and the mechanical energy at the first sample and at
        the end (``mechanical_start``, ``mechanical_end``); :meth:`energy_balance` reads
        them.
    energy_series : (n, NEN) the energy of every power flow (layout ``EN_*``: per leg the
        flows of ``layout.EN_LEG_NAMES``, then the battery's loss) accumulated from the
        start of the run to each sample [J], if the run accounted for its energy, else
        None. Read it with :meth:`cumulative_energy` and :meth:`power`. A window of a run
        (:meth:`window`, a streamed run's kept end) keeps the values since the run's start.
    stride_record : what the strides of the whole run need, taken from every sample as the
        run was computed (:class:`~scoutsim.result.stride_record.StrideRecord`), for a
        run recorded at a lower rate (``simulate(record_rate=...)``) or streamed; its
        strides and gait metrics come from it. None for a run held whole at the full rate
        (its strides come from its samples) and for a :meth:`window`.
    """

    # -- analysis (computed on demand) -----------------------------------------------------
    def gait(self, **kwargs):
        """Strides and gait metrics (:func:`scoutsim.analysis.gait.gait_metrics`)."""
        from ..analysis.gait import gait_metrics

        key = ("gait", tuple(sorted(kwargs.items())))
        if key not in self._cache:
            self._cache[key] = gait_metrics(self, **kwargs)
        return self._cache[key]

    @property
    def strides(self):
        """Per-stride metrics (list of dicts) of all strides."""
        return self.gait().strides

    def behaviour(self):
        """What the run did: steady bounding (at what speed), or what instead: fell, stood,
        slid, hopped in place, too short to tell, irregular strides, failed
        (:class:`~scoutsim.analysis.behaviour.Behaviour`: ``kind``, ``text``, ``t_s``,
        ``advice``, ``counts``; :func:`~scoutsim.analysis.behaviour.classify_behaviour`)."""
        key = ("behaviour",)
        if key not in self._cache:
            self._cache[key] = self.gait().behaviour(self)
        return self._cache[key]

    def summary(self) -> dict:
        """The run summary (outcome, what the run did: ``behaviour``, a sentence, with
        ``behaviour_kind`` and ``behaviour_detail``, :meth:`behaviour`; steady-state gait
        metrics and what the gait costs:
        ``electrical_energy_j`` [J] over the run, ``cost_of_transport`` [-] over the steady
        strides, ...; None without the energy accounting,
        :meth:`~scoutsim.analysis.gait.GaitMetrics.energy_summary`), JSON-safe; a run that
        failed numerically also has ``"failure"``: :attr:`failure` as a dict (kind, time,
        what happened, parameters far from the Scout II defaults, advice); a run started
        standing (``simulate(initial_state="standing")``) also has ``"startup_duration_s"``:
        the time [s] from t = 0 to the start-up's hand-over to the bounding controller
        (None if it timed out)."""
        out = self.gait().summary(self)
        startup = (self.provenance or {}).get("startup")
        if startup is not None:
            # a start from standing: t = 0 to the hand-over to the bounding controller
            out["startup_duration_s"] = startup.get("handover_s")
        if self.failure is not None:
            out["failure"] = self.failure.to_dict()
        return out

    @property
    def failure(self):
        """Why the run failed numerically (:class:`~scoutsim.result.failure.FailureDiagnosis`:
        ``kind``, ``t``, ``what``, ``parameters`` far from the Scout II defaults,
        ``message()``), or None if it did not (outcome other than "numerical_failure")."""
        key = ("failure", self.outcome)
        if key not in self._cache:
            self._cache[key] = diagnose_failure(self)
        return self._cache[key]

    def window(self, t0: float, t1: float) -> SimulationResult:
        """The samples (and their cumulative energies), events and steps with
        t0 <= t <= t1 [s], as views (all are in time order); outcome, end time, statistics,
        provenance and the run's energy totals stay the whole run's."""

        def rows(t):
            return slice(
                int(np.searchsorted(t, t0, side="left")), int(np.searchsorted(t, t1, side="right"))
            )

        j = rows(self.events[:, L.EVR_T])
        return self.with_samples(
            rows(self.t),
            events=self.events[j],
            event_states=None if self.event_states is None else self.event_states[j],
            steps=None if self.steps is None else self.steps[rows(self.steps[:, L.STP_T])],
            stride_record=None,
        )

    def with_samples(self, rows, **changes) -> SimulationResult:
        """This result with only the samples ``rows`` (a slice, indices or a boolean mask)
        of its time series and cumulative energies, and the fields ``changes`` replaced
        (its events and steps are kept whole unless replaced)."""
        return dataclasses.replace(
            self,
            t=self.t[rows],
            state=self.state[rows],
            aux=self.aux[rows],
            modes=self.modes[rows],
            energy_series=None if self.energy_series is None else self.energy_series[rows],
            **changes,
            _cache={},
        )

    @property
    def fell(self) -> bool:
        return self.outcome == "fell"

    def plot(self, path=None, t_range=None):
        """Time histories of the run (pitch, height, leg angles and states, hip torques) as a
        Matplotlib figure, saved to ``path`` if given: a convenience for
        :func:`scoutsim.presentation.plots.plot_run`."""
        from ..presentation.plots import plot_run

        return plot_run(self, path, t_range)
