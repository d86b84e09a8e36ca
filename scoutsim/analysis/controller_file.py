"""Controller files: a bounding controller's law and every one of its parameters in one
TOML file, as ``scoutsim tune`` writes its best parameters and ``scoutsim run --controller
FILE`` reads them.

The file is a robot file (the layout of ``scoutsim/data/scout2.toml``) with a
``[controller_law]`` section naming the law; ``[controller]`` gives every field of
:class:`~scoutsim.parameters.ControllerParameters` in SI units, written with 17
significant digits so the values read back bit for bit (angles carry their degrees in a
comment); a tuned robot adds its ``[robot]``, ``[transmission]`` and ``[motor]`` sections::

    [controller_law]
    name = "table-i"                    # or "pitch-feedback"

    [controller]
    touchdown_angle_front = { value = 0.38397243543875248, unit = "rad" }   # 22.000 deg
    ...

Because it is a robot file, ``--robot FILE`` reads the same file (``load_parameters``
skips ``[controller_law]``).
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path

from ..parameters import (
    ControllerParameters,
    ParameterError,
    RobotParameters,
    load_controller,
    load_parameters,
    parameter_table,
)

__all__ = ["CONTROLLER_LAWS", "write_controller_file", "read_controller_file", "ControllerFile"]

#: the laws a controller file may name: the paper's Table I controller, and Table I with
#: torso feedback at touchdown (:class:`~scoutsim.control.PitchFeedbackController`)
CONTROLLER_LAWS = ("table-i", "pitch-feedback")


@dataclasses.dataclass(frozen=True)
class ControllerFile:
    """What a controller file holds: the law's name, its parameters, and the robot's if
    the file gives them (else None)."""

    law: str
    controller: ControllerParameters
    robot: RobotParameters | None = None


def _value(v) -> str:
    """``v`` in TOML: a per-leg field's (back, front) pair as an array."""
    if isinstance(v, tuple):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    return repr(float(v))  # shortest repr: reads back to the same float


def write_controller_file(
    path,
    law: str,
    controller: ControllerParameters,
    robot: RobotParameters | None = None,
    *,
    header: str = "",
) -> Path:
    """Write a controller file (module docstring) to ``path``: ``law`` (one of
    :data:`CONTROLLER_LAWS`), every field of ``controller`` and, if given, of ``robot``, in
    SI units; ``header``: comment lines at the top (provenance)."""
    if law not in CONTROLLER_LAWS:
        raise ValueError(
            f"law = {law!r} is not allowed: must be one of {', '.join(CONTROLLER_LAWS)}"
        )
    rows = parameter_table()
    lines = [f"# {h}" if h else "#" for h in header.splitlines()]
    lines += ["", "[controller_law]", f'name = "{law}"']
    sections: dict[str, list[str]] = {}
    for row in rows:
        obj = controller if row["section"] == "controller" else robot
        if obj is None:
            continue
        v = getattr(obj, row["name"])
        unit = row["si_unit"]
        entry = f'{row["name"]} = {{ value = {_value(v)}, unit = "{unit}" }}'
        if unit == "rad":
            pair = v if isinstance(v, tuple) else (v,)
            entry += "   # " + ", ".join(f"{math.degrees(x):.4f}" for x in pair) + " deg"
        sections.setdefault(row["section"], []).append(entry)
    for name, entries in sections.items():
        lines += ["", f"[{name}]"] + entries
    text = "\n".join(lines) + "\n"
    path = Path(path)
    path.write_text(text)
    return path


def read_controller_file(path) -> ControllerFile:
    """Read a controller file: its law, its controller parameters (validated; fields it
    does not give keep the Scout II defaults) and, if it has a ``[robot]`` section, the
    robot's parameters.

    Raises
    ------
    ParameterError : the file is not TOML, has no ``[controller_law]`` or ``[controller]``
        section, names an unknown law, or holds a bad parameter (the message names the
        file and the field).
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text("utf-8"))
    except OSError as exc:
        raise ParameterError(
            f"controller file '{path}' cannot be read: {exc.strerror or exc}"
        ) from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"controller file '{path}' is not TOML: {exc}") from None
    law_section = data.get("controller_law")
    if not isinstance(law_section, dict) or "name" not in law_section:
        raise ParameterError(
            f"controller file '{path}' has no [controller_law] section with "
            f"a name (one of {', '.join(CONTROLLER_LAWS)}); a file written "
            "by scoutsim tune has one",
            "controller_law",
        )
    if extra := sorted(set(law_section) - {"name"}):
        raise ParameterError(
            f"[controller_law] of controller file '{path}': unknown key(s) {extra}; allowed: name",
            "controller_law",
        )
    law = law_section["name"]
    if law not in CONTROLLER_LAWS:
        raise ParameterError(
            f"[controller_law] name = {law!r} in controller file '{path}' is "
            f"not allowed: must be one of {', '.join(CONTROLLER_LAWS)}",
            "controller_law",
        )
    if "controller" not in data:
        raise ParameterError(f"controller file '{path}' has no [controller] section", "controller")
    if "robot" in data:
        robot, controller = load_parameters(path)
    else:
        robot, controller = None, load_controller(path)
    return ControllerFile(law=law, controller=controller, robot=robot)
