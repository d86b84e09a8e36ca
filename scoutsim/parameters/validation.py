"""Validation: the checks a parameter set runs when it is made, and those of one made
otherwise.

The parameter dataclasses run these checks when they are constructed (also through
``dataclasses.replace``: :func:`check_robot`, :func:`check_controller`), so a parameter set
that exists is valid; its values outside their plausible ranges are warned of
(:mod:`.plausibility`). The checks read the schema only, not the dataclasses, which are
built on top of them.

The parts have their own modules: :mod:`.field_rules` (the allowed range of every field,
sign rules and physical bounds, and the type and range check of each field by itself),
:mod:`.field_couplings` (the rules that couple fields) and :mod:`.quick_scan` (the
single-field checks by comparison alone, for a set that passes them). This module
re-exports their public names."""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import typing
from functools import cache
from types import MappingProxyType

from .field_couplings import (
    check_controller_couplings,
    check_pair_couplings,
    check_robot_couplings,
)
from .field_rules import allowed_range, check_fields, closed_range, coerce_value, physical_limit
from .plausibility import warn_implausible
from .quick_scan import quick_scan, scan_plan
from .schema import CONTROLLER_SECTIONS, ROBOT_SECTIONS, field_schema, fields_of

__all__ = [
    "allowed_range",
    "closed_range",
    "physical_limit",
    "coerce_value",
    "check_robot",
    "check_controller",
    "check_pair_couplings",
    "reporting_origins",
    "validate_robot",
    "validate_controller",
    "validate_parameters",
]


#: Where the values being checked came from: field -> (where, note) as in
#: :func:`~scoutsim.parameters.field_rules.reject` (``files`` sets it while it builds a
#: parameter set from a file, so the messages of the checks run by the constructor name the
#: file and the unit the value was given in).
_ORIGINS: contextvars.ContextVar[typing.Mapping] = contextvars.ContextVar(
    "parameter_origins", default=MappingProxyType({})
)


@contextlib.contextmanager
def reporting_origins(origins: typing.Mapping):
    """Within the block, the checks' errors and warnings name the origins of the values
    (``field -> (where, note)``)."""
    token = _ORIGINS.set(origins)
    try:
        yield
    finally:
        _ORIGINS.reset(token)


def _check(obj, couplings, warn: bool = True) -> None:
    """Every single-field rule of ``obj``'s fields, then ``couplings(obj, origins)``; then
    (if ``warn``) a warning for each value outside its plausible range."""
    cls: typing.Any = type(obj)
    plan = scan_plan(cls)
    origins = _ORIGINS.get()
    implausible = quick_scan(obj.__dict__, plan)
    if implausible is None:
        # a value the comparison alone does not pass: the full check raises, naming the
        # field, or the value is valid (e.g. a NumPy number)
        check_fields(obj, origins)
        specs = fields_of(cls)
        implausible = quick_scan({n: coerce_value(specs[n], getattr(obj, n)) for n in specs}, plan)
    couplings(obj, origins)
    for name, value, leg in (implausible or []) if warn else ():
        warn_implausible(field_schema()[name], value, origins, leg)


def check_robot(p) -> None:
    """The checks of a robot's parameters (:class:`RobotParameters` runs them when it is
    constructed): ParameterError naming the field (and the leg) and its allowed range."""
    _check(p, check_robot_couplings)


def check_controller(c) -> None:
    """The checks of a controller's parameters (run by :class:`ControllerParameters` when it
    is constructed)."""
    _check(c, check_controller_couplings)


@cache
def _sections_of(cls: type) -> tuple | None:
    """The TOML sections whose fields the dataclass ``cls`` has (None: not a parameter
    class)."""
    if not dataclasses.is_dataclass(cls):
        return None
    names = set(fields_of(cls))
    for sections in (ROBOT_SECTIONS, CONTROLLER_SECTIONS):
        if names == {n for n, s in field_schema().items() if s.section in sections}:
            return sections
    return None


def _require(obj, sections: tuple, expected: str) -> None:
    cls: typing.Any = type(obj)
    if isinstance(obj, type) or _sections_of(cls) != sections:
        raise TypeError(f"expected {expected}, got {type(obj).__name__}")


def validate_robot(p):
    """Check every field of a :class:`RobotParameters` (its constructor does; this checks
    one made otherwise, e.g. unpickled). It raises only: the plausibility warnings are the
    constructor's.

    Parameters
    ----------
    p : RobotParameters
        Parameters to check (SI units).

    Returns
    -------
    RobotParameters
        ``p`` itself, unchanged.

    Raises
    ------
    ParameterError
        On a wrong type, a NaN/infinite value or a value outside its allowed range (its
        sign rule, or a physical bound far beyond any legged robot: a mass above 100 t, a
        length above 100 m, ...; :func:`physical_limit`); the message names the field (and
        the leg, for a value given per leg), the value (in the paper's unit) and the allowed
        range.
    """
    _require(p, ROBOT_SECTIONS, "RobotParameters")
    _check(p, check_robot_couplings, warn=False)  # (its constructor warned)
    return p


def validate_controller(c):
    """Check every field of a :class:`ControllerParameters`, and liftoff < touchdown
    compression (its constructor does; this checks one made otherwise).

    Parameters
    ----------
    c : ControllerParameters
        Parameters to check (SI units); angle messages are reported in degrees.

    Returns
    -------
    ControllerParameters
        ``c`` itself, unchanged.

    Raises
    ------
    ParameterError
        As :func:`validate_robot`.
    """
    _require(c, CONTROLLER_SECTIONS, "ControllerParameters")
    _check(c, check_controller_couplings, warn=False)
    return c


def validate_parameters(robot, controller) -> None:
    """Check both parameter sets and the rules that couple them.

    Besides :func:`validate_robot` and :func:`validate_controller`, requires
    ``touchdown_compression < robot.leg_rest_length``.

    Raises
    ------
    ParameterError
        On any violation.
    """
    validate_robot(robot)
    validate_controller(controller)
    check_pair_couplings(robot, controller, _ORIGINS.get())
