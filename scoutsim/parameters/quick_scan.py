"""The quick scan of a parameter set: every field's single-field checks by comparison alone,
with the plausible ranges, so a valid set (every ``simulate()`` checks every field) passes
without composing a message; a value it does not pass goes to the full checks of
:mod:`.field_rules`, which say why."""

from __future__ import annotations

import math
import sys
import typing
from functools import cache

from .field_rules import closed_range
from .schema import PER_LEG_FIELDS, fields_of

_FLOAT_MAX = sys.float_info.max
_ACCEPTED_TYPES = {"float": (float, int), "int": (int,), "bool": (bool,)}


@cache
def scan_plan(cls: type) -> tuple:
    """Per field of the dataclass ``cls``, what :func:`quick_scan` compares: (name, accepted
    types, whether a (back, front) pair is, allowed range, plausible range, whether 0 is
    plausible), the ranges closed, in SI and
    finite (so the comparison also refuses nan and inf): :func:`closed_range` and the
    schema's plausible range, read once."""
    plan = []
    for name, spec in fields_of(cls).items():
        lo, hi = closed_range(name)
        p = spec.plausible
        p_lo, p_hi = (-math.inf, math.inf) if p is None else p.bounds
        plan.append(
            (
                name,
                _ACCEPTED_TYPES[spec.kind],
                name in PER_LEG_FIELDS,
                max(lo, -_FLOAT_MAX),
                min(hi, _FLOAT_MAX),
                p_lo,
                p_hi,
                p is not None and p.zero,
            )
        )
    return tuple(plan)


def quick_scan(values: typing.Mapping, plan: tuple) -> list | None:
    """The fields' single-field checks by comparison alone: None if a value is not of its
    field's plain type (``float`` or a subclass, ``int``, ``bool``, or a (back, front) tuple
    of them) or is outside its allowed range
    (:func:`~scoutsim.parameters.field_rules.check_fields` then says why), else the
    implausible values as (name, value, leg)."""
    implausible: list[tuple[str, typing.Any, int | None]] = []
    for name, types, per_leg, lo, hi, p_lo, p_hi, p_zero in plan:
        v = values[name]
        if type(v) in types:
            if not lo <= v <= hi:
                return None
            if not p_lo <= v <= p_hi and not (p_zero and v == 0):
                implausible.append((name, v, None))
        elif type(v) is tuple and per_leg and len(v) == 2:
            for leg, x in enumerate(v):
                if type(x) not in types or not lo <= x <= hi:
                    return None
                if not p_lo <= x <= p_hi and not (p_zero and x == 0):
                    implausible.append((name, x, leg))
        elif float in types and isinstance(v, float):  # a subclass: NumPy's float64
            if not lo <= v <= hi:
                return None
            if not p_lo <= v <= p_hi and not (p_zero and v == 0):
                implausible.append((name, v, None))
        else:
            return None
    return implausible
