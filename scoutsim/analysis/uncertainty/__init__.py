"""Uncertainty studies: what uncertain robot, controller and floor parameters do to the
gait, by global sensitivity analysis (first-order and total Sobol' indices).

The parts: :mod:`.uncertain_parameters` (the parameters, their distributions and allowed
ranges, the robot file's ``[uncertainty]`` section), :mod:`.sobol` (the Saltelli design
and :func:`sobol_indices`, the estimator of :func:`scipy.stats.sobol_indices` with
bootstrap confidence intervals) and :mod:`.study` (:func:`uncertainty_study`: the runs
through the sweep's machinery, the metrics, how runs that do not bound are treated, the
output files). This package re-exports their public names.
"""

from .sobol import (
    CONFIDENCE_LEVEL,
    N_RESAMPLES,
    SobolIndices,
    design_rows,
    sobol_design,
    sobol_from_evaluations,
    sobol_indices,
)
from .study import (
    BOUNDS,
    GAIT_METRICS,
    INDEX_COLUMNS,
    METRICS,
    UncertaintyResult,
    check_parameters,
    uncertainty_study,
    uncertainty_task,
)
from .uncertain_parameters import (
    DISTRIBUTIONS,
    FRICTION,
    UncertainParameter,
    parse_parameter,
    read_uncertainty,
)

__all__ = [
    "uncertainty_study",
    "uncertainty_task",
    "UncertaintyResult",
    "UncertainParameter",
    "parse_parameter",
    "check_parameters",
    "read_uncertainty",
    "sobol_indices",
    "sobol_design",
    "sobol_from_evaluations",
    "design_rows",
    "SobolIndices",
    "CONFIDENCE_LEVEL",
    "N_RESAMPLES",
    "METRICS",
    "GAIT_METRICS",
    "BOUNDS",
    "INDEX_COLUMNS",
    "FRICTION",
    "DISTRIBUTIONS",
]
