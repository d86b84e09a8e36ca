"""What a point that fails means for a study (basin map, sweep, tuning): the robot's
physics, a point that is not allowed, or an error of the study.

Every row of a study has a ``status``:

- ``"ok"``: the run was made. Its ``outcome`` is the physics' (completed, fell, ...) or
  the controller's own stop, ``"controller_error"``: the user's controller returned hip
  torques that are not finite, or a compiled controller a nonzero status (a
  :class:`~scoutsim.control.protocol.ControllerError` without a cause). Such a point did
  not bound.
- ``"invalid"``: the point itself is not allowed: a parameter outside its allowed range,
  a start with a toe below the ground (a ``ValueError`` of :func:`scoutsim.simulate` or of
  the parameters). It is left out of fractions, as a basin map's invalid starts are.
- ``"error"``: the study could not run the point, so the point says nothing about the
  robot and is never counted as "did not bound": the controller could not be made (its
  factory could not be imported, or raised), it raised inside the run or inside the
  periodic-orbit search of the point (a ControllerError whose cause is the controller's
  own exception: a bug in its code), the
  task could not be loaded in the worker (an ImportError or AttributeError on
  unpickling), the worker died twice, or any other exception.

What a study does with errors (``on_error``):

- ``"raise"`` (the default of :func:`~scoutsim.analysis.basin.basin_of_attraction`,
  :func:`~scoutsim.analysis.sweep.sweep` and :func:`~scoutsim.analysis.tune.tune`): the
  first error stops the study (points in flight finish, the rest are cancelled; the rows
  that arrived are kept, in the checkpoint of a sweep or a tuning, where a resumed study
  runs the failed points again) and :class:`StudyError` lists the errors that arrived;
- ``"record"``: every point runs; an error is a row with ``status = "error"`` and the
  message in ``error``, counted apart (``n_errors``), and the study warns once
  (RuntimeWarning) when it ends with errors.
"""

from __future__ import annotations

import warnings

from ..control.factory import FactoryError
from ..control.protocol import ControllerError

__all__ = [
    "StudyError",
    "ON_ERROR",
    "STATUSES",
    "check_on_error",
    "run_failure",
    "error_fields",
    "is_error",
    "end_of_study",
]

#: what a study can do with an error of the study (module docstring)
ON_ERROR = ("raise", "record")
#: the statuses of a study's rows (module docstring)
STATUSES = ("ok", "invalid", "error")
#: how many errors a StudyError's message shows
SHOWN_ERRORS = 3


class StudyError(RuntimeError):
    """A study could not run some of its points (module docstring): not a result about the
    robot. The message lists the first errors.

    Attributes
    ----------
    errors : the rows of the points that errored (``status = "error"``, message in
        ``error``), in point order.
    result : the study's result with the rows that arrived (a BasinResult, SweepResult
        or None for a tuning: its finished evaluations are in its checkpoint).
    """

    def __init__(self, message: str, errors=(), result=None):
        super().__init__(message)
        self.errors = list(errors)
        self.result = result


def check_on_error(on_error: str) -> str:
    """``on_error`` if it is one of :data:`ON_ERROR`; ValueError naming it otherwise."""
    if on_error not in ON_ERROR:
        raise ValueError(
            f"on_error = {on_error!r} is not allowed: must be 'raise' (stop at "
            "the first error of the study) or 'record' (record it as a row "
            "with status 'error')"
        )
    return on_error


def error_fields(exc: BaseException) -> dict:
    """``status``, ``outcome`` and ``error`` of a point the study could not run."""
    return {"status": "error", "outcome": "error", "error": f"{type(exc).__name__}: {exc}"}


def run_failure(exc: Exception, invalid_outcome: str) -> dict:
    """``status``, ``outcome`` and ``error`` of a point whose run raised ``exc`` (module
    docstring): the controller's own stop (ok, ``"controller_error"``), a point not
    allowed (invalid, ``invalid_outcome``) or an error of the study."""
    if isinstance(exc, ControllerError):
        cause = exc.__cause__
        if cause is None:
            return {"status": "ok", "outcome": "controller_error", "error": str(exc)}
        return {
            "status": "error",
            "outcome": "error",
            "error": f"ControllerError: {exc} ({type(cause).__name__}: {cause})",
        }
    if isinstance(exc, ValueError) and not isinstance(exc, FactoryError):
        return {"status": "invalid", "outcome": invalid_outcome, "error": str(exc)}
    return error_fields(exc)


def is_error(row) -> bool:
    """Whether ``row`` is a point the study could not run."""
    return isinstance(row, dict) and row.get("status") == "error"


def end_of_study(
    rows: list, on_error: str, what: str, where, result=None, n_points: int | None = None
) -> None:
    """Apply the ``on_error`` policy to a study's ``rows`` (None: a point that did not
    arrive): :class:`StudyError` if one errored and ``on_error`` is "raise", a
    RuntimeWarning if "record". ``what`` names the study ("basin map", "sweep"), ``where``
    (row -> str) a point; ``n_points`` the study's points (default: ``len(rows)``)."""
    errors = [r for r in rows if is_error(r)]
    if not errors:
        return
    n = len(rows) if n_points is None else n_points
    shown = "; ".join(f"{where(r)}: {r['error']}" for r in errors[:SHOWN_ERRORS])
    more = f" (and {len(errors) - SHOWN_ERRORS} more)" if len(errors) > SHOWN_ERRORS else ""
    if on_error == "raise":
        raise StudyError(
            f"the {what} stopped: {len(errors)} of its {n} points could not be "
            f"run (an error of the study, not a result about the robot): "
            f"{shown}{more}. Fix the cause and run it again, or pass "
            "on_error='record' to record such points as rows with status "
            "'error' and go on",
            errors,
            result,
        )
    warnings.warn(
        f"the {what}: {len(errors)} of its {n} points could not be run and are "
        f"recorded with status 'error' (left out of every fraction): "
        f"{shown}{more}",
        RuntimeWarning,
        stacklevel=3,
    )
