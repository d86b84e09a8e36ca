"""The uncertain parameters of an uncertainty study (:mod:`scoutsim.analysis.uncertainty`):
their names, distributions and allowed ranges, from the command line and from a robot
file's ``[uncertainty]`` section.

Names are a sweep's (:mod:`scoutsim.analysis.sweep_points`): ``robot.<field>`` and
``controller.<field>`` in the field's SI unit, ``<name>_deg`` in degrees for an angle
field, and ``friction_coefficient``, the toe's Coulomb coefficient mu [-] of the floor.

Distributions, in the unit of the name:

- uniform, ``NAME=LOW:HIGH``: LOW < HIGH, both inside the field's allowed range
  (:func:`scoutsim.parameters.allowed_range`; mu > 0), else refused;
- normal, ``NAME=normal:MEAN:SD``: SD > 0 and MEAN inside the allowed range, else
  refused; the normal is truncated at the ends of the allowed range (a touchdown angle
  stays inside (-90, 90) deg, a stiffness above 0), its mass renormalised, so a sample
  outside the range is never drawn. Where the range cuts off little of it the
  truncation changes nothing a study can see.

A robot file's ``[uncertainty]`` section names fields as the file's other sections do
(bare names, plus ``friction_coefficient``), each an inline table ``{ low = ..., high =
... }`` or ``{ mean = ..., sd = ... }`` with an optional ``unit`` (default: the unit the
packaged ``scout2.toml`` writes the field in; any unit of its dimension)::

    [uncertainty]
    leg_stiffness = { low = 3000.0, high = 3800.0, unit = "N/m" }
    touchdown_angle_front = { mean = 21.0, sd = 0.5, unit = "deg" }
    friction_coefficient = { low = 0.6, high = 1.0 }

A field in degrees becomes ``<section>.<field>_deg`` (kept in degrees); any other unit
is converted to SI and named ``<section>.<field>``.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from os import PathLike

import numpy as np
from scipy import stats

from ...parameters import ParameterError, allowed_range
from ...parameters.schema import CONTROLLER_SECTIONS, field_schema
from ...parameters.units import UNIT_INDEX, UNITS
from ..sweep_points import check_name, section_and_field, si_name

__all__ = [
    "FRICTION",
    "DISTRIBUTIONS",
    "UncertainParameter",
    "parse_parameter",
    "read_uncertainty",
]

#: the name of the floor's Coulomb coefficient mu [-] among the uncertain parameters
FRICTION = "friction_coefficient"
#: the distributions an uncertain parameter may have
DISTRIBUTIONS = ("uniform", "normal")


def _range_of(name: str) -> tuple[float, float, bool, bool]:
    """The allowed range of ``name`` in its own unit: (low, high, low_closed, high_closed)."""
    if name == FRICTION:
        return 0.0, math.inf, False, False
    check_name(name)
    _, scale = si_name(name)
    # (one leg of a per-leg field, robot.<field>.back / .front, has the field's range)
    lo, hi, lo_closed, hi_closed = allowed_range(section_and_field(name)[1])
    return (
        -math.inf if lo is None else lo / scale,
        math.inf if hi is None else hi / scale,
        lo is not None and lo_closed,
        hi is not None and hi_closed,
    )


def _describe_range(name: str) -> str:
    lo, hi, lo_closed, hi_closed = _range_of(name)
    return f"{'[' if lo_closed else '('}{lo:.12g}, {hi:.12g}{']' if hi_closed else ')'}"


def _inside(name: str, x: float) -> bool:
    lo, hi, lo_closed, hi_closed = _range_of(name)
    return (x > lo or (lo_closed and x == lo)) and (x < hi or (hi_closed and x == hi))


@dataclass(frozen=True)
class UncertainParameter:
    """One uncertain parameter: its ``name`` (module docstring) and its distribution,
    ``"uniform"`` on [a, b) or ``"normal"`` with mean a and standard deviation b,
    truncated at the ends of the allowed range; a and b in the unit of the name."""

    name: str
    distribution: str
    a: float
    b: float

    def __post_init__(self):
        n = self.name
        if self.distribution not in DISTRIBUTIONS:
            raise ValueError(
                f"{n}: distribution {self.distribution!r} is not allowed: one of {DISTRIBUTIONS}"
            )
        if not (math.isfinite(self.a) and math.isfinite(self.b)):
            raise ValueError(f"{n}: the distribution's numbers must be finite")
        allowed = f"the allowed range of {n} is {_describe_range(n)}"
        if self.distribution == "uniform":
            if not self.a < self.b:
                raise ValueError(f"{n}: low = {self.a:g} must be below high = {self.b:g}")
            for what, x in (("low", self.a), ("high", self.b)):
                if not _inside(n, x):
                    raise ValueError(f"{n}: {what} = {x:g} is not allowed: {allowed}")
        else:
            if not self.b > 0:
                raise ValueError(f"{n}: sd = {self.b:g} is not allowed: must be > 0")
            if not _inside(n, self.a):
                raise ValueError(
                    f"{n}: mean = {self.a:g} is not allowed: {allowed} (the normal is "
                    "truncated at its ends)"
                )

    @property
    def field(self) -> str:
        """The field the parameter sets (``robot.<field>``, ``controller.<field>``, or
        ``friction_coefficient``), without a ``_deg`` suffix."""
        return si_name(self.name)[0]

    def describe(self) -> str:
        """The distribution as the command line gives it (``uniform:LOW:HIGH`` or
        ``normal:MEAN:SD``, in the name's unit)."""
        return f"{self.distribution}:{self.a:.12g}:{self.b:.12g}"

    def values(self, u: np.ndarray) -> np.ndarray:
        """The parameter's values at the points ``u`` of the unit interval (its inverse
        cumulative distribution): a Sobol' sample of the unit cube becomes a sample of
        the parameters."""
        u = np.asarray(u, dtype=float)
        if self.distribution == "uniform":
            return self.a + (self.b - self.a) * u
        lo, hi, _, _ = _range_of(self.name)
        lo_z, hi_z = (lo - self.a) / self.b, (hi - self.a) / self.b
        # (a point of the scrambled sequence is never exactly 0 or 1; kept inside anyway)
        u = np.clip(u, np.finfo(float).tiny, 1.0 - np.finfo(float).eps)
        x = stats.truncnorm.ppf(u, lo_z, hi_z, loc=self.a, scale=self.b)
        # an open end of the allowed range: stay strictly inside it
        return np.clip(x, np.nextafter(lo, math.inf), np.nextafter(hi, -math.inf))


def parse_parameter(text: str) -> UncertainParameter:
    """``NAME=LOW:HIGH`` (uniform) or ``NAME=normal:MEAN:SD`` (truncated normal) ->
    :class:`UncertainParameter`; ValueError naming what is wrong."""
    name, sep, spec = text.partition("=")
    name = name.strip()
    parts = spec.split(":")
    form = "NAME=LOW:HIGH or NAME=normal:MEAN:SD"
    if not sep or len(parts) not in (2, 3) or (len(parts) == 3 and parts[0] != "normal"):
        raise ValueError(f"{text!r} is not allowed: must be {form}")
    if name != FRICTION:
        check_name(name)
    try:
        a, b = (float(v) for v in parts[-2:])
    except ValueError:
        raise ValueError(f"{text!r}: the numbers of {form} must be numbers") from None
    return UncertainParameter(name, "normal" if len(parts) == 3 else "uniform", a, b)


def _from_entry(key: str, entry: object, where: str) -> UncertainParameter:
    """One entry of ``[uncertainty]`` -> :class:`UncertainParameter` (module docstring)."""
    schema = field_schema()
    if key != FRICTION and key not in schema:
        import difflib

        near = difflib.get_close_matches(key, [*schema, FRICTION], n=1)
        hint = f"; did you mean '{near[0]}'?" if near else ""
        raise ParameterError(
            f"[uncertainty] {key}{where}: not a parameter (a field of the robot file's "
            f"sections, or {FRICTION}){hint}",
            key,
        )
    if not isinstance(entry, dict):
        raise ParameterError(
            f"[uncertainty] {key}{where}: must be a table {{ low = ..., high = ... }} or "
            f"{{ mean = ..., sd = ... }}, got {entry!r}",
            key,
        )
    keys = set(entry) - {"unit", "source"}
    if keys not in ({"low", "high"}, {"mean", "sd"}):
        raise ParameterError(
            f"[uncertainty] {key}{where}: keys {sorted(entry)} are not allowed: give low "
            "and high (uniform) or mean and sd (normal), and optionally unit",
            key,
        )
    spec = schema.get(key)
    dimension, default_unit = (
        ("dimensionless", "1") if spec is None else (spec.dimension, spec.unit)
    )
    unit = entry.get("unit", default_unit)
    if not isinstance(unit, str) or UNIT_INDEX.get(unit.strip(), (None,))[0] != dimension:
        raise ParameterError(
            f"[uncertainty] {key}{where}: unit {unit!r} is not allowed: one of "
            f"{', '.join(UNITS[dimension])}",
            key,
        )
    unit = unit.strip()
    factor = UNIT_INDEX[unit][1]
    name = (
        key
        if spec is None
        else f"{'controller' if spec.section in CONTROLLER_SECTIONS else 'robot'}.{key}"
    )
    if dimension == "angle" and unit == "deg":
        name, factor = name + "_deg", 1.0
    a, b = (entry["low"], entry["high"]) if "low" in entry else (entry["mean"], entry["sd"])
    for x in (a, b):
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            raise ParameterError(f"[uncertainty] {key}{where}: {x!r} is not a number", key)
    try:
        return UncertainParameter(
            name, "uniform" if "low" in entry else "normal", a * factor, b * factor
        )
    except ValueError as exc:
        raise ParameterError(f"[uncertainty] {key}{where}: {exc}", key) from None


def read_uncertainty(path: str | PathLike) -> list[UncertainParameter]:
    """The uncertain parameters of a robot file's ``[uncertainty]`` section (module
    docstring), in the file's order; an empty list if it has none.

    Raises
    ------
    ParameterError : malformed TOML, an unknown field, a wrong unit or a distribution
        outside the field's allowed range (the message names the field and its range).
    """
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"malformed TOML in parameter file '{path}': {exc}") from exc
    section = data.get("uncertainty", {})
    if not isinstance(section, dict):
        raise ParameterError(f"[uncertainty] in parameter file '{path}' must be a table")
    where = f" (in file '{path}')"
    return [_from_entry(k, v, where) for k, v in section.items()]
