"""The family of controlled periodic gaits along one robot, controller or floor parameter:
the orbit followed from value to value, its multipliers along the way, and where it changes
stability, its number of strides or its sample-phase cell (docs/orbits.md, "Families of
gaits").

The closed loop is sampled at 1 kHz, so its stride map is only piecewise smooth: a family
of orbits breaks into sample-phase cells (a lift-off or a controller switch moves to the
next sample; at the Table I operating point a step of 0.06 deg of front touchdown angle
already crosses a border), and an orbit predicted from its neighbour's tangent lands in
the wrong cell.
:func:`controlled_family` therefore follows the orbit by natural-parameter steps that let
the robot settle: at each value the closed loop runs on from the previous orbit's hybrid
state with the new parameter (:func:`~scoutsim.analysis.controlled_orbit.likely_strides`,
at least 80 strides) and Newton's method (exact Jacobians where the controller runs in
the compiled loop, differences for a Python controller) finds the orbit it settled on.
This follows the attracting orbit only: where the orbit loses stability the row says so,
and the next value shows where the robot went (another cycle, or a fall).

Units: the parameter as named (SI, or degrees for a ``_deg`` angle, as in ``sweep``).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .continuation import crossing_kind
from .controlled_orbit import ControlledOrbit, NewtonSettings, controlled_fixed_point
from .gait_family import FAMILY_COLUMNS, GaitFamily
from .orbit_sensitivity import FRICTION, parameter_value, setting_with
from .poincare import MapError
from .sweep_points import check_name, si_name

__all__ = ["controlled_family"]

#: multipliers kept in a row (the largest by modulus)
_KEPT_MULTIPLIERS = 4


def controlled_family(
    name: str,
    values,
    *,
    model: str = "II",
    friction_coefficient: float | None = 1.0,
    robot=None,
    controller=None,
    settle_duration: float = 12.0,
    newton: NewtonSettings | None = None,
    progress: Callable[[str], None] | None = None,
) -> GaitFamily:
    """The controlled orbit followed through ``values`` of parameter ``name``
    (``robot.<field>``, ``controller.<field>`` of the Table I law, a ``_deg`` suffix on an
    angle for degrees, or ``friction_coefficient``), in the order given.

    The seed is the value nearest the parameter's own value in the setting at which an
    orbit is found after ``settle_duration`` [s] from the default start; from it the
    family is followed up the values and down them, each orbit from its neighbour's hybrid
    state, the closed loop settling under the new value first (module docstring). A value
    where no orbit is found gets a row whose ``status`` says why; the next value starts
    again from the last orbit found. Rows are in the order of ``values``.

    Returns a :class:`~scoutsim.analysis.gait_family.GaitFamily` (method
    "natural-parameter"); a row's ``bifurcation`` names what changed from the orbit at the
    previous value that has one: a multiplier crossing the unit circle
    (:func:`~scoutsim.analysis.continuation.crossing_kind`), a change of the number of
    strides per period ("strides k -> k'": the sampled loop locking into another cycle,
    not a smooth bifurcation).
    """
    base, scale = _si(name)
    values = [float(v) for v in values]
    if not values:
        raise ValueError("values: give at least one value")
    say = progress or (lambda message: None)
    setting = {
        "model": model,
        "friction_coefficient": friction_coefficient,
        "robot": robot,
        "controller": controller,
    }
    fam = GaitFamily(
        parameter=name,
        stopped="values",
        setting={"model": model, "friction_coefficient": friction_coefficient},
        method="natural-parameter",
    )
    rows: dict[int, dict] = {}
    orbits: dict[int, ControlledOrbit] = {}

    def solve(i: int, prev: ControlledOrbit | None) -> ControlledOrbit | None:
        st = setting_with(setting, base, values[i] * scale)
        common = {k: st[k] for k in ("model", "friction_coefficient", "robot", "controller")}
        try:
            if prev is None:
                orbit = controlled_fixed_point(
                    settle_duration=settle_duration, newton=newton, **common
                )
            else:
                orbit = controlled_fixed_point(
                    prev.state,
                    integrator=prev.setting["integrator"],
                    section=prev.setting["section"],
                    newton=newton,
                    **common,
                )
        except MapError as exc:
            rows[i] = _lost(name, values[i], str(exc))
            say(f"{name} = {values[i]:.6g}: no orbit ({exc})")
            return None
        rows[i], orbits[i] = _row(name, values[i], orbit), orbit
        say(
            f"{name} = {values[i]:.6g}: {orbit.strides} stride(s) in {orbit.period:.3f} s, "
            f"spectral radius per stride {rows[i]['spectral_radius']:.4f}"
            + ("" if prev is None else f" ({_what_changed(prev, orbit) or 'no change'})")
        )
        return orbit

    # the seed: the value nearest the setting's own that has an orbit from a settled run
    own = parameter_value(setting, base) / scale
    seed, orbit0 = None, None
    for i in sorted(range(len(values)), key=lambda i: (abs(values[i] - own), i)):
        orbit0 = solve(i, None)
        if orbit0 is not None:
            seed = i
            break
    if seed is None:
        fam.stopped = "lost: no orbit at any value"
    else:
        for path in (range(seed + 1, len(values)), range(seed - 1, -1, -1)):
            prev = orbit0
            for i in path:
                prev = solve(i, prev) or prev
    last = None  # what changed, in the order of the values, from the last orbit found
    for i in sorted(orbits):
        if last is not None:
            rows[i]["bifurcation"] = _what_changed(orbits[last], orbits[i])
        last = i
    fam.rows = [rows[i] for i in range(len(values))]
    return fam


def _si(name: str) -> tuple[str, float]:
    """The field ``name`` sets (SI) and the SI value per unit of ``name``'s values."""
    if name == FRICTION:
        return name, 1.0
    check_name(name)
    return si_name(name)


def _what_changed(prev: ControlledOrbit, orbit: ControlledOrbit) -> str:
    if orbit.strides != prev.strides:
        # the sampled loop locking into another cycle: not a smooth bifurcation (the
        # multipliers of the two maps are not comparable), so named by what it is
        return f"strides {prev.strides} -> {orbit.strides}"
    return crossing_kind(prev.multipliers, orbit.multipliers)


def _row(name: str, v: float, orbit: ControlledOrbit) -> dict:
    m = np.asarray(orbit.multipliers)
    m = m[np.argsort(-np.abs(m), kind="stable")][:_KEPT_MULTIPLIERS]
    # per stride, comparable across cycles of different numbers of strides
    rho = float(np.max(np.abs(orbit.multipliers))) ** (1.0 / orbit.strides)
    back, front = orbit.touchdown_angles_world
    return {
        name: v,
        "touchdown_angle_back_deg": math.degrees(back),
        "touchdown_angle_front_deg": math.degrees(front),
        "period_s": orbit.period,
        "strides": orbit.strides,
        "mean_speed_m_s": orbit.mean_speed,
        "spectral_radius": rho,
        "stable": bool(rho < 1.0),
        "bifurcation": "",
        "multipliers": [(float(x.real), float(x.imag)) for x in m],
        "status": "ok",
    }


def _lost(name: str, v: float, why: str) -> dict:
    row: dict = {k: math.nan for k in FAMILY_COLUMNS}
    row.update(
        {name: v, "strides": 0, "stable": False, "bifurcation": "", "multipliers": [],
         "status": f"no orbit: {why}"}
    )  # fmt: skip
    return row
