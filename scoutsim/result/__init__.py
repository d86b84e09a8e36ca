"""The result of a run: :class:`SimulationResult` (:mod:`.simulation_result`) and its
accessors by name: time series (:mod:`.series`), the event log (:mod:`.event_log`), the
energy accounts (:mod:`.energy_accounts`), column views (:mod:`.columns`), the run's files
(:mod:`.run_files`), and why a run failed numerically (:mod:`.failure`)."""

from .failure import FailureDiagnosis, diagnose_failure
from .simulation_result import SimulationResult

__all__ = ["SimulationResult", "FailureDiagnosis", "diagnose_failure"]
