"""The schema of every parameter: its TOML section, type, unit, dimension, packaged default
and source, taken from the packaged ``scout2.toml`` and checked against both dataclasses."""

from __future__ import annotations

import dataclasses
import typing
from dataclasses import dataclass
from functools import lru_cache

from .controller import ControllerParameters
from .packaged import _PACKAGED_NAME, _packaged
from .robot import RobotParameters
from .units import _UNIT_INDEX, UNITS


#: TOML section -> dataclass whose fields it holds.
SECTIONS: dict[str, type] = {
    "robot": RobotParameters,
    "transmission": RobotParameters,
    "motor": RobotParameters,
    "controller": ControllerParameters,
}


@dataclass(frozen=True)
class _Spec:
    """Schema of one field, taken from the packaged TOML and the dataclass annotation."""

    name: str
    section: str
    kind: str  # "float", "int" or "bool"
    unit: str  # unit as written in scout2.toml
    dimension: str
    factor: float
    written: object  # value as written in scout2.toml
    source: str

    @property
    def label(self) -> str:
        return f"{self.section}.{self.name}"

    @property
    def si_unit(self) -> str:
        return next(iter(UNITS[self.dimension]))


def field_dimension(name: str) -> str | None:
    """Physical dimension ("angle", "mass", ...) of a RobotParameters / ControllerParameters
    field (from the packaged scout2.toml), or None for an unknown name."""
    spec = _schema().get(name)
    return None if spec is None else spec.dimension


@lru_cache(maxsize=1)
def _schema() -> dict[str, _Spec]:
    """Field name -> :class:`_Spec`, checked against both dataclasses."""
    data = _packaged()
    if set(data) != set(SECTIONS):
        raise RuntimeError(f"packaged {_PACKAGED_NAME} has sections {sorted(data)}, expected {sorted(SECTIONS)}")
    kinds = {}
    for cls in (RobotParameters, ControllerParameters):
        hints = typing.get_type_hints(cls)
        kinds.update({f.name: (cls, hints[f.name].__name__) for f in dataclasses.fields(cls)})
    schema: dict[str, _Spec] = {}
    for section, entries in data.items():
        for name, entry in entries.items():
            if name not in kinds or kinds[name][0] is not SECTIONS[section] or name in schema:
                raise RuntimeError(f"packaged {_PACKAGED_NAME}: unexpected entry [{section}] {name}")
            dim, factor = _UNIT_INDEX[entry["unit"]]
            schema[name] = _Spec(name, section, kinds[name][1], entry["unit"], dim, factor,
                                 entry["value"], entry["source"])
    if missing := set(kinds) - set(schema):
        raise RuntimeError(f"packaged {_PACKAGED_NAME} lacks {sorted(missing)}")
    return schema


def _fields_of(cls: type) -> dict[str, _Spec]:
    names = [f.name for f in dataclasses.fields(cls)]
    return {n: _schema()[n] for n in names}
