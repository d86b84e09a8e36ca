"""Plausibility: a value that validation allows but that lies far outside what a robot of
Scout II's kind has (its field's plausible range, :func:`.schema.plausible_range`) is warned
of with an :class:`ImplausibleParameterWarning` naming the field, the value with its unit,
Scout II's value and, when the two differ by a factor a unit slip gives (1000, 57.3 for
degrees and radians, 9.81 for kgf, 2.2 for lb, ...), the likely slip.

Each distinct message is shown once in a process (the warnings module's default action:
a sweep that builds one robot thousands of times prints it once); the standard filters
silence it (``warnings.filterwarnings("ignore", category=ImplausibleParameterWarning)``),
turn it into an error or show every occurrence."""

from __future__ import annotations

import contextlib
import math
import warnings

from ..names import LEG_NAMES
from .parameter_error import format_bound, format_value
from .schema import FieldSpec
from .units import UNITS


class ImplausibleParameterWarning(UserWarning):
    """A parameter value far outside what a robot of Scout II's kind has: allowed (a
    researcher may explore it), but most such values are a unit slip. The message names the
    field, the value with its unit, Scout II's value and the likely slip."""


#: Units people slip into that :data:`~.units.UNITS` does not accept, by dimension: unit ->
#: SI factor (SI value = value * factor). Only for naming a slip.
_OTHER_UNITS: dict[str, dict[str, float]] = {
    "mass": {"lb": 0.45359237, "t": 1.0e3},
    "length": {"in": 0.0254, "ft": 0.3048, "km": 1.0e3},
    "inertia": {"lb in^2": 0.45359237 * 0.0254**2, "g mm^2": 1.0e-9},
    "acceleration": {"g (9.81 m/s^2)": 9.80665},
    "force": {"kgf": 9.80665, "lbf": 4.4482216152605, "kN": 1.0e3},
    "torque": {
        "kgf cm": 0.0980665,
        "lbf in": 0.1129848290276,
        "oz in": 0.0070615518,
        "N mm": 1.0e-3,
    },
    "stiffness": {"N/cm": 1.0e2, "kN/m": 1.0e3, "kgf/mm": 9806.65, "lbf/in": 175.12683524647},
    "damping": {"N s/cm": 1.0e2, "kgf s/mm": 9806.65},
    "time": {"us": 1.0e-6},
    "current": {"kA": 1.0e3},
    "voltage": {"mV": 1.0e-3, "kV": 1.0e3},
    "resistance": {"mohm": 1.0e-3, "kohm": 1.0e3},
    "dimensionless": {"%": 1.0e-2},
}

#: a slip is named when the ratio to Scout II's value is within this factor of the slip's
#: (a robot up to 1.5 times Scout II's value either way, given in the wrong unit)
_SLIP_TOLERANCE = math.log(1.5)
#: ... and only for a value more than this factor from Scout II's (closer, it is another
#: robot, not a slip)
_SLIP_MIN_RATIO = 3.0


def _ratio_text(r: float) -> str:
    """``1000x`` / ``57.3x`` / ``1e+300x`` for r >= 1, ``1/1000 of`` for r < 1."""
    x = r if r >= 1.0 else 1.0 / r
    shown = str(round(float(f"{x:.3g}"))) if 100.0 <= x < 1.0e7 else f"{x:.3g}"
    return f"{shown}x" if r >= 1.0 else f"1/{shown} of"


def likely_slip(spec: FieldSpec, ratio: float, given_unit: str | None = None) -> str | None:
    """The unit slip that best explains a value ``ratio`` times Scout II's, as text ("a slip
    between N/mm and N/m?"), or None if no slip is near (within a factor 1.5) or the value
    is within a factor 3 of Scout II's. Candidates: the field's units in ``scout2.toml``,
    in SI and as the user gave it, each against every unit of the dimension; then a bare
    power of 1000."""
    if 1.0 / _SLIP_MIN_RATIO <= ratio <= _SLIP_MIN_RATIO:
        return None
    units = {**UNITS[spec.dimension], **_OTHER_UNITS.get(spec.dimension, {})}
    anchors = dict.fromkeys(u for u in (spec.unit, spec.si_unit, given_unit) if u in units)
    best, best_distance = None, _SLIP_TOLERANCE
    for a in anchors:
        for b, fb in units.items():
            fa = units[a]
            if fa == fb:
                continue
            for r in (fa / fb, fb / fa):
                distance = abs(math.log(ratio / r))
                if distance < best_distance:
                    best, best_distance = f"a slip between {b} and {a}?", distance
    if best is None:
        for k in (1, 2, 3):
            for r in (1000.0**k, 1000.0**-k):
                if abs(math.log(ratio / r)) < _SLIP_TOLERANCE:
                    return f"a unit-prefix slip (a factor {format_bound(1000.0**k)})?"
    return best


def _given_unit(spec: FieldSpec, note: str | None) -> str | None:
    """The unit a value was given in, from its origin's note ("given as 3520 N/mm")."""
    if not note:
        return None
    return next(
        (u for u in sorted(UNITS[spec.dimension], key=len, reverse=True) if note.endswith(f" {u}")),
        None,
    )


def slip_hint(spec: FieldSpec, value: float, note: str | None = None) -> str | None:
    """:func:`likely_slip` of ``value`` [SI] against Scout II's value, or None (a value or
    a Scout II value that is not > 0, or no slip near)."""
    scout = spec.default_si
    if spec.kind != "float" or not (value > 0.0 and scout > 0.0 and math.isfinite(value)):
        return None
    return likely_slip(spec, value / scout, _given_unit(spec, note))


def implausible_message(spec: FieldSpec, value: float, origins, leg: int | None = None) -> str:
    """The warning's text for ``value`` [SI] of the field ``spec`` (of leg ``leg`` when the
    legs differ); ``origins`` as in validation (the file and the unit it was given in)."""
    where, note = origins.get(spec.name, ("", None))
    unit = "" if spec.unit in ("1", "bool") else f" {spec.unit}"
    scale = spec.factor if spec.kind == "float" else 1.0
    label = spec.label if leg is None else f"{spec.label} ({LEG_NAMES[leg]} leg)"
    shown = f"{label} = {format_value(value / scale)}{unit}{f' ({note})' if note else ''}"
    p = spec.plausible
    assert p is not None, "only a field with a plausible range warns"
    span = f"{p.low / scale:.6g} to {p.high / scale:.6g}{unit}"
    if p.zero and p.low > 0.0:
        span += ", or 0"
    scout = spec.default_si
    if value > 0.0 and scout > 0.0:
        text = (
            f"{shown} is {_ratio_text(value / scout)} Scout II's {spec.written:.4g}{unit}, "
            f"outside the plausible range for a robot of its kind ({span})"
        )
        slip = slip_hint(spec, value, note)
        if slip:
            text += f": {slip}"
    else:
        text = (
            f"{shown} is outside the plausible range for a robot of its kind ({span}; "
            f"Scout II: {spec.written:.4g}{unit})"
        )
    return text + where


#: (field, leg, value [SI]) of the values already warned of with the file they came from:
#: the same value when the library makes the parameter set again (from a result's
#: provenance, per leg, ...) is not warned of again without it
_WARNED_FROM_A_FILE: set = set()


def warn_implausible(spec: FieldSpec, value: float, origins, leg: int | None = None) -> None:
    """Warn of an implausible value (:func:`implausible_message`). The warning is issued
    from this line for every caller, so the default filter shows each distinct message once
    per process; a value warned of with its file is not warned of again without one."""
    key = (spec.name, leg, float(value))
    from_a_file = bool(origins.get(spec.name, ("", None))[0])
    if not from_a_file and key in _WARNED_FROM_A_FILE:
        return
    if from_a_file:
        _WARNED_FROM_A_FILE.add(key)
    message = implausible_message(spec, value, origins, leg)
    warnings.warn(message, ImplausibleParameterWarning, stacklevel=1)


@contextlib.contextmanager
def plausibility_warnings_off():
    """No :class:`ImplausibleParameterWarning` inside the block: what the points of a study
    use, which warns of its range's ends once, before its points run (a worker process
    would otherwise print one line per value it meets)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ImplausibleParameterWarning)
        yield
