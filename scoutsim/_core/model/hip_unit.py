"""The hip units (compiled): which transmission sits between each motor and its leg, the
registry of the units, and the hooks through which the rest of the model reaches a run's
unit.

A hip unit is a module of ``scoutsim._core.model`` that declares

``NAME``
    its name (``str``);
``GEARED``
    whether it has a gear train of its own: the driven-gear angles alpha become
    coordinates, and the gear pair, the motor joint's friction and stick/slip, the stuck
    joint's row and the rigid belt of the impact come with it (shared by every geared unit,
    :mod:`scoutsim._core.model.transmission`); a unit without one drives the leg directly
    (alpha copies phi);
``spring(delta, leg, P)``
    (geared units; compiled, inlined) the (deflection [rad], engaged) of the belt spring
    of virtual leg ``leg`` at the gear/leg angle difference ``delta`` = alpha - phi [rad]:
    the deflection its torque k_b x deflection and potential energy
    1/2 k_b deflection^2 follow, and whether its stiffness counts in the stiff Jacobian of
    the ARK methods;
``applies(model, robot)``
    whether a robot (:class:`~scoutsim.parameters.RobotParameters`) in ``model``
    ("ideal", "I", "II", "passive") runs on it.

:data:`UNITS` registers them; a unit's code (``P[P_HIP_UNIT]``) is its place in it. A robot
runs on the last registered unit that applies to it (:func:`hip_unit_code`), so a variant
of a unit is registered after it. The compiled hooks :func:`geared` and :func:`belt_spring`
dispatch on the code with one branch per unit; their source is written from the registry
when this module is imported (:func:`_dispatch_source`), so adding a unit is its module and
its entry in :data:`UNITS`.
"""

from __future__ import annotations

from ..._numba.jit import kernel
from . import backlash, belt, rigid_hip
from .layout import P_HIP_UNIT  # noqa: F401 (read by the hooks generated below)

#: the registered hip units; a unit's code is its index (the rigid unit is code 0, the one
#: a parameter array without a unit gets)
UNITS = (rigid_hip, belt, backlash)

#: name of each unit, by code
NAMES = tuple(unit.NAME for unit in UNITS)


def _check_registry():
    for code, unit in enumerate(UNITS):
        for attr in ("NAME", "GEARED", "applies") + (("spring",) if unit.GEARED else ()):
            if not hasattr(unit, attr):
                raise TypeError(f"hip unit {unit.__name__} (code {code}) has no {attr}")
    if UNITS[0].GEARED:
        raise TypeError("hip unit code 0 must be a unit without a gear train")


_check_registry()


def hip_unit_code(model: str, robot) -> int:
    """The code of the hip unit a robot (``RobotParameters``) runs on in ``model``: the
    last registered unit that applies to it."""
    for code in reversed(range(len(UNITS))):
        if UNITS[code].applies(model, robot):
            return code
    raise ValueError(f"no hip unit applies to model {model!r}")


def is_geared(code: int) -> bool:
    """Whether the hip unit of code ``code`` has a gear train of its own (Python-level)."""
    return bool(UNITS[int(code)].GEARED)


def _dispatch_source() -> str:
    """The source of the compiled hooks :func:`geared` and :func:`belt_spring` for the
    registered units: ``geared`` compares the code with the codes of the units without a
    gear train; ``belt_spring`` has a branch for each geared unit but the first, which is
    the fallback (the only codes that reach it are geared ones)."""
    rigid = [c for c, u in enumerate(UNITS) if not u.GEARED]
    springs = [c for c, u in enumerate(UNITS) if u.GEARED]
    test = " and ".join(f"unit != {c}" for c in rigid)
    lines = [
        "def geared(P):",
        "    unit = int(P[P_HIP_UNIT])",
        f"    return {test}",
        "",
        "def belt_spring(delta, leg, P):",
    ]
    if len(springs) > 1:
        lines.append("    unit = int(P[P_HIP_UNIT])")
    for c in reversed(springs[1:]):
        lines += [f"    if unit == {c}:", f"        return _unit_{c}.spring(delta, leg, P)"]
    lines.append(f"    return _unit_{springs[0]}.spring(delta, leg, P)")
    return "\n".join(lines) + "\n"


def _compile_dispatch():
    """Define the hooks' Python functions in this module from :func:`_dispatch_source`,
    with the units under the names ``_unit_<code>`` they call them by."""
    namespace = globals()
    namespace.update({f"_unit_{c}": u for c, u in enumerate(UNITS)})
    # compiled with this file's name: the on-disk cache of the compiled core files the
    # hooks with this module, and Numba finds their globals by the module's name
    exec(compile(_dispatch_source(), __file__, "exec"), namespace)
    return namespace["geared"], namespace["belt_spring"]


_geared, _belt_spring = _compile_dispatch()

#: geared(P): True for a hip unit with a gear train of its own (the driven-gear angles
#: alpha are coordinates, Model II); False for a unit that drives the leg directly (alpha
#: copies phi). Compiled, inlined.
geared = kernel(inline="always")(_geared)

#: belt_spring(delta, leg, P): (deflection [rad], engaged) of virtual leg ``leg``'s belt
#: spring at the gear/leg angle difference ``delta`` = alpha - phi [rad], by the run's
#: unit's ``spring``. Compiled, inlined.
belt_spring = kernel(inline="always")(_belt_spring)
