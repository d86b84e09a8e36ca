"""A sweep's points (:mod:`scoutsim.analysis.sweep`): the names it can vary and their units,
points on a grid or drawn at random, and a point's identity within a sweep.

Names and units: a point's names are ``robot.<field>`` / ``controller.<field>`` in SI
units, or, for an angle field, ``<name>_deg`` in degrees (converted to SI for the run); the
table's column of a parameter holds its values as named, so a ``_deg`` column holds
degrees and every other column its field's SI unit (:func:`axis_label`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math

import numpy as np

from ..parameters import UNITS, ControllerParameters, RobotParameters, field_dimension
from ..parameters.robot_fields import field_of

#: suffix of a name that gives an angle field in degrees
DEG = "_deg"

_SECTIONS = {"robot": RobotParameters, "controller": ControllerParameters}


def parameter_names() -> list[str]:
    """All names a sweep can vary."""
    return [f"{sec}.{f.name}" for sec, cls in _SECTIONS.items() for f in dataclasses.fields(cls)]


def si_name(name: str) -> tuple[str, float]:
    """The field a point's ``name`` sets and the SI value per unit of its values:
    ``(name without _deg, pi / 180)`` for a degrees name, else ``(name, 1)``."""
    if name.endswith(DEG):
        return name[: -len(DEG)], math.pi / 180.0
    return name, 1.0


def section_and_field(name: str) -> tuple[str, str]:
    """The section (``robot``, ``controller``) and the field a name sets: its ``_deg``
    suffix dropped and, for one leg of a per-leg field (``robot.leg_stiffness.front``),
    its leg (ValueError for a leg on a field that is not per leg)."""
    base, _ = si_name(name)
    sec, _, fld = base.partition(".")
    if sec == "robot" and "." in fld:
        fld = field_of(fld, "robot.")[0]
    return sec, fld


def axis_label(name: str) -> tuple[float, str]:
    """How a plot shows a sweep column: ``(factor, label)``, the column's values times
    ``factor`` in the unit the label gives. An angle in SI is shown in degrees, a ``_deg``
    column as it is, another field in its SI unit ("-" for a pure number); any other
    column by its name (its unit is in the name: ``mean_speed_m_s``)."""
    base, scale = si_name(name)
    sec, _, fld = base.partition(".")
    if sec == "robot" and "." in fld:
        fld = fld.partition(".")[0]  # one leg of a per-leg field: the field's unit
    dim = field_dimension(fld) if sec in _SECTIONS else None
    if dim is None:
        return 1.0, name
    if scale != 1.0:
        return 1.0, f"{name} [deg]"
    if dim == "angle":
        return 180.0 / math.pi, f"{name} [deg]"
    unit = next(iter(UNITS[dim]))
    return 1.0, f"{name} [{'-' if unit == '1' else unit}]"


def check_name(name: str):
    """ValueError for a name a sweep cannot vary (naming the nearest that it can)."""
    base, scale = si_name(name)
    sec, fld = section_and_field(name)
    cls = _SECTIONS.get(sec)
    if cls is None or fld not in {f.name for f in dataclasses.fields(cls)}:
        import difflib

        near = difflib.get_close_matches(name, parameter_names() + _deg_names(), n=1)
        hint = f"; did you mean {near[0]!r}?" if near else ""
        raise ValueError(
            f"sweep parameter {name!r} is not allowed: must be robot.<field> or "
            f"controller.<field> of RobotParameters / ControllerParameters (a "
            f"_deg suffix on an angle takes degrees){hint}"
        )
    if scale != 1.0 and field_dimension(fld) != "angle":
        raise ValueError(
            f"sweep parameter {name!r} is not allowed: the _deg suffix takes "
            f"degrees for an angle; {base!r} is not an angle (give it in SI "
            "units, without the suffix)"
        )


def _deg_names() -> list[str]:
    """The names of the angle fields in degrees (``<name>_deg``)."""
    return [n + DEG for n in parameter_names() if field_dimension(n.partition(".")[2]) == "angle"]


def grid_points(grid: dict) -> list[dict]:
    """Cartesian product of ``{name: values}`` as a list of points (last name fastest)."""
    for name in grid:
        check_name(name)
    names = list(grid)
    return [
        dict(zip(names, map(float, vals)))
        for vals in itertools.product(*(list(grid[n]) for n in names))
    ]


def random_points(bounds: dict, n: int, seed: int = 0) -> list[dict]:
    """``n`` points drawn uniformly within ``{name: (low, high)}`` (seeded, reproducible)."""
    for name in bounds:
        check_name(name)
    rng = np.random.default_rng(seed)
    names = list(bounds)
    lo = np.array([bounds[k][0] for k in names], dtype=float)
    hi = np.array([bounds[k][1] for k in names], dtype=float)
    u = rng.random((n, len(names)))
    return [dict(zip(names, map(float, lo + (hi - lo) * row))) for row in u]


def point_key(point: dict, settings: dict) -> str:
    """Stable identity of a point within a sweep (for resuming)."""
    blob = json.dumps({"point": point, "settings": settings}, sort_keys=True, default=repr)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]
