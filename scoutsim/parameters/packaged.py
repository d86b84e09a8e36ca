"""The packaged defaults: ``scoutsim/data/scout2.toml`` (the one home of every default value),
read once through importlib.resources, and the class decorator that makes its values the
defaults of the parameter dataclasses."""

from __future__ import annotations

import tomllib
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

from .units import UNIT_INDEX

PACKAGED_NAME = "scout2.toml"

#: the package that ships ``data/scout2.toml``: ``scoutsim``, the parent of this one
_DATA_PACKAGE = (__package__ or "scoutsim.parameters").rpartition(".")[0]


@lru_cache(maxsize=1)
def packaged_table() -> dict:
    """Parsed packaged ``scout2.toml`` (importlib.resources, with a file-system fallback)."""
    try:
        text = resources.files(_DATA_PACKAGE).joinpath("data", PACKAGED_NAME).read_text("utf-8")
    except (OSError, TypeError, ValueError, ModuleNotFoundError):
        # e.g. a namespace package under an editable install
        text = (Path(__file__).resolve().parents[1] / "data" / PACKAGED_NAME).read_text("utf-8")
    return tomllib.loads(text)


class _Packaged:
    """The placeholder default of a field whose default is read from the packaged file."""

    def __repr__(self) -> str:
        return "<default from the packaged scout2.toml>"


#: what a parameter dataclass writes as each field's default (``torso_mass: float =
#: PACKAGED``): :func:`packaged_defaults` replaces it by the file's value, and a type
#: checker sees that the field has a default
PACKAGED: Any = _Packaged()


def packaged_defaults(*sections: str):
    """Class decorator: every annotated field of the class (declared ``= PACKAGED``) gets,
    as its default, the SI value of its entry in the packaged ``scout2.toml`` (in one of
    ``sections``), converted with the entry's unit. The dataclass field list and the file
    must name the same parameters, and each value must be written with its field's type
    (``2``, ``2.0``, ``true``)."""

    def fill(cls):
        data = packaged_table()
        entries = {n: e for sec in sections for n, e in data[sec].items()}
        if extra := sorted(set(entries) - set(cls.__annotations__)):
            raise RuntimeError(f"packaged {PACKAGED_NAME}: {cls.__name__} has no field {extra}")
        for name, kind in cls.__annotations__.items():
            if name not in entries:
                raise RuntimeError(f"packaged {PACKAGED_NAME} lacks {name} (sections {sections})")
            if cls.__dict__.get(name) is not PACKAGED:
                raise RuntimeError(
                    f"{cls.__name__}.{name} must be declared with the default "
                    f"PACKAGED (its value is read from {PACKAGED_NAME})"
                )
            entry = entries[name]
            value = entry["value"]
            if type(value).__name__ != kind:  # the schema reads each field's type from the file
                raise RuntimeError(
                    f"packaged {PACKAGED_NAME}: {name} = {value!r} is not a "
                    f"{kind}, the type of {cls.__name__}.{name}"
                )
            if kind == "bool":
                default = bool(value)
            elif kind == "int":
                default = int(value)
            else:
                default = float(value) * UNIT_INDEX[entry["unit"]][1]
            setattr(cls, name, default)
        return cls

    return fill
