"""Parameter files and dicts: loading (packaged defaults, then a user's TOML file, then Python
overrides; units converted once, every value validated), the parameter table, and the
JSON-safe dict of both parameter sets."""

from __future__ import annotations

import dataclasses
import tomllib
import typing
from os import PathLike

from .controller import ControllerParameters
from .field_couplings import check_pair_couplings
from .parameter_error import ParameterError, format_value, unknown_name_error
from .robot import RobotParameters
from .schema import CONTROLLER_SECTIONS, ROBOT_SECTIONS, FieldSpec, field_schema, fields_of
from .units import UNIT_INDEX, UNITS
from .validation import coerce_value, reporting_origins, validate_parameters

#: TOML section -> dataclass whose fields it holds.
SECTIONS: dict[str, type] = {
    **dict.fromkeys(ROBOT_SECTIONS, RobotParameters),
    **dict.fromkeys(CONTROLLER_SECTIONS, ControllerParameters),
}

#: sections of a robot file read by other loaders: name -> the function that reads them
SEPARATE_SECTIONS: dict[str, str] = {
    "sensors": "scoutsim.control.sensors.load_sensors",
    "controller_law": "scoutsim.analysis.controller_file.read_controller_file",
    "uncertainty": "scoutsim.analysis.uncertainty.read_uncertainty",
}


def _convert_entry(spec: FieldSpec, entry: object, where: str) -> tuple[object, str | None]:
    """Convert one TOML entry (plain value or ``{value, unit, source}``) to SI.

    Returns the SI value and, when the user's unit differs from the display unit, a note
    ``"(given as ...)"`` for later messages.
    """
    unit = spec.unit
    if isinstance(entry, dict):
        if extra := sorted(set(entry) - {"value", "unit", "source"}):
            raise ParameterError(
                f"{spec.label}: unknown key(s) {extra} in entry; allowed keys are "
                f"value, unit, source{where}",
                spec.name,
            )
        if "value" not in entry:
            raise ParameterError(f"{spec.label}: entry has no 'value'{where}", spec.name)
        unit = entry.get("unit", spec.unit)
        entry = entry["value"]
        if not isinstance(unit, str) or unit.strip() not in UNIT_INDEX:
            raise ParameterError(
                f"{spec.label}: unknown unit {unit!r}; allowed units: "
                f"{', '.join(UNITS[spec.dimension])}{where}",
                spec.name,
            )
        unit = unit.strip()
    dim, factor = UNIT_INDEX[unit]
    if dim != spec.dimension:
        raise ParameterError(
            f"{spec.label}: unit '{unit}' is a {dim} unit, but {spec.name} is a "
            f"{spec.dimension}; allowed units: {', '.join(UNITS[spec.dimension])}{where}",
            spec.name,
        )
    value = coerce_value(spec, entry, where)
    note = None if unit == spec.unit else f"given as {format_value(entry)} {unit}"
    return _scaled(spec, value, factor), note


def _scaled(spec: FieldSpec, value, factor: float):
    """``value`` (one value or a (back, front) pair) times the unit factor (floats only)."""
    if spec.kind != "float":
        return value
    return tuple(v * factor for v in value) if isinstance(value, tuple) else value * factor


def _default_si(spec: FieldSpec) -> float | int | bool:
    """SI value of the packaged default of one field."""
    return spec.default_si


def _read_file(path: str | PathLike) -> tuple[dict[str, object], dict[str, tuple[str, str | None]]]:
    """Read a user's parameter file; return SI values and origins of every entry it sets."""
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"malformed TOML in parameter file '{path}': {exc}") from exc
    schema = field_schema()
    values: dict[str, object] = {}
    origins: dict[str, tuple[str, str | None]] = {}
    for section, entries in data.items():
        if section in SEPARATE_SECTIONS:
            continue
        if section not in SECTIONS:
            raise unknown_name_error(
                section, f"in parameter file '{path}'", SECTIONS, kind="section"
            )
        if not isinstance(entries, dict):
            raise ParameterError(
                f"[{section}] in parameter file '{path}' must be a table, got {entries!r}"
            )
        where = f" (in [{section}] of file '{path}')"
        for name, entry in entries.items():
            spec = schema.get(name)
            if spec is None or spec.section != section:
                if spec is not None:
                    raise ParameterError(
                        f"parameter '{name}' in [{section}] of file '{path}' belongs in "
                        f"section [{spec.section}]",
                        name,
                    )
                in_section = [n for n, s in schema.items() if s.section == section]
                raise unknown_name_error(name, f"in [{section}] of file '{path}'", in_section)
            values[name], note = _convert_entry(spec, entry, where)
            origins[name] = (where, note)
    return values, origins


def _build(
    cls: type,
    path: str | PathLike | None,
    overrides: typing.Mapping | None,
    where_overrides: str = " (from overrides)",
):
    """Defaults -> user file -> overrides; return the instance (checked by its constructor,
    whose messages name the values' origins) and the origins."""
    specs = fields_of(cls)
    values: dict[str, typing.Any] = {name: _default_si(spec) for name, spec in specs.items()}
    origins: dict[str, tuple[str, str | None]] = {}
    if path is not None:
        file_values, file_origins = _read_file(path)
        values.update({k: v for k, v in file_values.items() if k in specs})
        origins.update({k: v for k, v in file_origins.items() if k in specs})
    for name, value in (overrides or {}).items():
        if name not in specs:
            other = field_schema().get(name)
            if other is not None:
                raise ParameterError(
                    f"'{name}' is a [{other.section}] parameter, not a "
                    f"{cls.__name__} field{where_overrides}",
                    name,
                )
            raise unknown_name_error(name, f"for {cls.__name__}{where_overrides}", specs)
        spec = specs[name]
        values[name] = coerce_value(spec, value, where_overrides)
        note = f"given as {format_value(value)} {spec.si_unit}" if spec.factor != 1.0 else None
        origins[name] = (where_overrides, note)
    with reporting_origins(origins):
        return cls(**values), origins


def load_robot(
    path: str | PathLike | None = None, overrides: typing.Mapping[str, object] | None = None
) -> RobotParameters:
    """Load robot parameters: packaged defaults, then a user's TOML file, then overrides.

    Parameters
    ----------
    path : str or os.PathLike, optional
        User TOML file with the layout of ``scout2.toml``. An entry is a plain value (in the
        unit ``scout2.toml`` uses for that field) or ``{ value = ..., unit = "..." }`` with any
        unit of :data:`UNITS` of the right dimension (``source`` is allowed and ignored). The
        whole file is checked, including its ``[controller]`` section.
    overrides : mapping, optional
        Field name -> value in SI units, applied last.

    Returns
    -------
    RobotParameters
        Validated parameters (SI units).

    Raises
    ------
    ParameterError
        Malformed TOML, unknown section or key, wrong unit dimension, wrong type, or a value
        out of range (see :func:`validate_robot`).
    """
    return _build(RobotParameters, path, overrides)[0]


def load_controller(
    path: str | PathLike | None = None, overrides: typing.Mapping[str, object] | None = None
) -> ControllerParameters:
    """Load controller parameters; as :func:`load_robot` but for ``[controller]``.

    Parameters
    ----------
    path : str or os.PathLike, optional
        User TOML file (see :func:`load_robot`).
    overrides : mapping, optional
        Field name -> value in SI units (angles in rad), applied last.

    Returns
    -------
    ControllerParameters
        Validated parameters (SI units). The coupling ``touchdown_compression <
        leg_rest_length`` is only checked by :func:`load_parameters`.
    """
    return _build(ControllerParameters, path, overrides)[0]


def load_parameters(
    path: str | PathLike | None = None,
    robot_overrides: typing.Mapping[str, object] | None = None,
    controller_overrides: typing.Mapping[str, object] | None = None,
) -> tuple[RobotParameters, ControllerParameters]:
    """Load robot and controller parameters together and check the rules coupling them.

    Parameters
    ----------
    path : str or os.PathLike, optional
        User TOML file (see :func:`load_robot`).
    robot_overrides, controller_overrides : mapping, optional
        Field name -> SI value, applied last.

    Returns
    -------
    tuple of (RobotParameters, ControllerParameters)
        Validated parameters.
    """
    robot, _ = _build(RobotParameters, path, robot_overrides)
    controller, c_origins = _build(ControllerParameters, path, controller_overrides)
    check_pair_couplings(robot, controller, c_origins)
    return robot, controller


def parameter_table() -> list[dict]:
    """Every parameter with its default, unit and provenance (for documentation).

    Returns
    -------
    list of dict
        One dict per field of :class:`RobotParameters` then :class:`ControllerParameters`,
        with keys ``section``, ``name``, ``value`` and ``unit`` (as written in
        ``scout2.toml``), ``si_value``, ``si_unit`` and ``source``.
    """
    rows = []
    for cls in (RobotParameters, ControllerParameters):
        for name, spec in fields_of(cls).items():
            rows.append(
                {
                    "section": spec.section,
                    "name": name,
                    "value": spec.written,
                    "unit": spec.unit,
                    "si_value": _default_si(spec),
                    "si_unit": spec.si_unit,
                    "source": spec.source,
                }
            )
    return rows


_DICT_FORMAT = "scoutsim.parameters/1"


def to_dict(robot: RobotParameters, controller: ControllerParameters) -> dict:
    """JSON-safe dict of both parameter sets (SI units), e.g. for result-file provenance.

    Parameters
    ----------
    robot : RobotParameters
    controller : ControllerParameters
        Both are validated first, so every number is finite.

    Returns
    -------
    dict
        ``{"format": ..., "units": "SI", "robot": {...}, "controller": {...}}``; see
        :func:`from_dict` for the inverse.
    """
    validate_parameters(robot, controller)
    return {
        "format": _DICT_FORMAT,
        "units": "SI",
        "robot": dataclasses.asdict(robot),
        "controller": dataclasses.asdict(controller),
    }


def from_dict(d: typing.Mapping) -> tuple[RobotParameters, ControllerParameters]:
    """Inverse of :func:`to_dict` (exact round trip, also through JSON).

    Parameters
    ----------
    d : mapping
        As produced by :func:`to_dict`; every field of both dataclasses must be present.

    Returns
    -------
    tuple of (RobotParameters, ControllerParameters)
        Validated parameters.

    Raises
    ------
    ParameterError
        Wrong format tag, unknown or missing keys, wrong types or invalid values.
    """
    if d.get("format", _DICT_FORMAT) != _DICT_FORMAT or d.get("units", "SI") != "SI":
        raise ParameterError(
            f"unsupported parameter dict format {d.get('format')!r} "
            f"(units {d.get('units')!r}); expected {_DICT_FORMAT!r} in SI"
        )
    if extra := sorted(set(d) - {"format", "units", "robot", "controller"}):
        raise ParameterError(f"unknown key(s) {extra} in parameter dict")
    out, origins = [], {}
    for key, cls in (("robot", RobotParameters), ("controller", ControllerParameters)):
        part = d.get(key, {})
        if missing := sorted(set(fields_of(cls)) - set(part)):
            raise ParameterError(f"parameter dict [{key}] lacks {missing}")
        obj, o = _build(cls, None, part, where_overrides=" (from parameter dict)")
        out.append(obj)
        origins.update(o)
    robot, controller = out
    check_pair_couplings(robot, controller, origins)
    return robot, controller
