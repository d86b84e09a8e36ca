"""The tuned parameters of a tuning (:mod:`scoutsim.analysis.tune`): names, bounds and
units, and a candidate's values set on the robot, the controller parameters and a
compiled controller's parameter array.

A name is ``controller.<field>`` (a :class:`~scoutsim.parameters.ControllerParameters`
field: Table I and the torso-feedback gains), ``robot.<field>`` (a
:class:`~scoutsim.parameters.RobotParameters` field, for design studies) or
``controller.params[i]`` (entry i of a :class:`~scoutsim.CompiledController`'s parameter
array). A ``_deg`` suffix on an angle field takes degrees at the edge, converted here,
once; bounds and values inside are SI (angles in rad). Without a range a parameter is
searched over its default search range (:data:`DEFAULT_SEARCH`, around the base robot's
or controller's value, within the field's allowed range); a field without one needs a
range.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass

import numpy as np

from ..parameters import ControllerParameters, RobotParameters, allowed_range, field_dimension
from ..parameters.robot_fields import robot_value, robot_with_values
from .sweep_points import check_name, parameter_names, section_and_field

__all__ = ["TuneParameter", "parse_parameter", "DEFAULT_SEARCH", "default_search_range"]

#: half-width [rad] of the default search of a set-point angle around its base value
ANGLE_HALF_SPAN = math.radians(20.0)


def _around(half: float):
    return lambda base: (base - half, base + half)


def _scaled(low: float, high: float):
    return lambda base: (base * low, base * high)


#: The default search range of a parameter given without one, SI, as a function of its
#: base value (the base controller's or robot's field; Scout II's by default). A tuning
#: searches near a working controller: the allowed range of an angle, +-90 deg, puts most
#: touchdowns where the legs cannot catch the body, so that nearly every early evaluation
#: falls and CMA-ES has no feasible candidate to learn from.
#:
#: - touchdown angles and sweep limits: the base value +-20 deg. Table I's touchdown
#:   angles (21 and 19 deg) then range over about 0 to 40 deg, from a leg that lands
#:   vertical to one whose toe lands l0 sin 40 deg = 0.21 m ahead of the hip (Scout II,
#:   l0 = 0.323 m); the sweep limits (0 deg) over +-20 deg about the vertical;
#: - torso-feedback gains: k_theta the base +-1 rad/rad, k_omega the base +-0.1 s (the
#:   ranges scanned for the pitch-feedback controller, docs/model.md "Torso feedback");
#: - control period: half to twice the base (the paper's loop runs at 1 kHz);
#: - efficiencies: the base +-0.2 (within (0, 1]); the gearbox's load-dependent loss
#:   coefficient 0 to 0.2.
#:
#: Every other field needs a range (``NAME=LOW:HIGH``): gains, masses and stiffnesses have
#: no scale a default could guess.
DEFAULT_SEARCH = {
    "controller.touchdown_angle_front": _around(ANGLE_HALF_SPAN),
    "controller.touchdown_angle_back": _around(ANGLE_HALF_SPAN),
    "controller.sweep_limit_front": _around(ANGLE_HALF_SPAN),
    "controller.sweep_limit_back": _around(ANGLE_HALF_SPAN),
    "controller.pitch_gain_front": _around(1.0),
    "controller.pitch_gain_back": _around(1.0),
    "controller.pitch_rate_gain_front": _around(0.1),
    "controller.pitch_rate_gain_back": _around(0.1),
    "controller.control_period": _scaled(0.5, 2.0),
    "robot.gearbox_efficiency": _around(0.2),
    "robot.sprocket_efficiency": _around(0.2),
    "robot.gearbox_load_loss_coefficient": lambda base: (0.0, 0.2),
}


def default_search_range(key: str, base: float) -> tuple[float, float] | None:
    """The default search range [SI] of the field ``key`` (``robot.<field>`` /
    ``controller.<field>``) around its ``base`` value, cut to the field's allowed range
    (an open end moved inside by one part in 1e9 of the range); None if it has none."""
    rule = DEFAULT_SEARCH.get(key)
    if rule is None:
        return None
    lo, hi = sorted(rule(base))
    lo_r, hi_r, lo_closed, hi_closed = allowed_range(key.partition(".")[2])
    eps = 1e-9 * (hi - lo)
    if lo_r is not None and (lo < lo_r or (lo == lo_r and not lo_closed)):
        lo = lo_r if lo_closed else lo_r + eps
    if hi_r is not None and (hi > hi_r or (hi == hi_r and not hi_closed)):
        hi = hi_r if hi_closed else hi_r - eps
    return lo, hi


_PARAMS_NAME = re.compile(r"^controller\.params\[(\d+)\]$")


@dataclass(frozen=True)
class TuneParameter:
    """One tuned parameter.

    Attributes
    ----------
    name : the name as given (``controller.touchdown_angle_front_deg``, ``robot.leg_stiffness``,
        ``controller.params[3]``); the table's column of its values in the given unit.
    key : where it goes: ``controller.<field>``, ``robot.<field>`` (SI) or ``params[i]``.
    low, high : bounds [SI].
    scale : SI value per unit of the given value (pi / 180 for a ``_deg`` name, else 1).
    """

    name: str
    key: str
    low: float
    high: float
    scale: float = 1.0

    def shown(self, si: float) -> float:
        """The SI value ``si`` in the unit the name gives."""
        return si / self.scale


def parse_parameter(
    text: str,
    controller=None,
    robot: RobotParameters | None = None,
    cparams: ControllerParameters | None = None,
) -> TuneParameter:
    """``NAME`` or ``NAME=LOW:HIGH`` (LOW, HIGH in the name's unit: degrees for a ``_deg``
    name) as a :class:`TuneParameter`; without a range, the field's default search range
    around its value in ``robot`` / ``cparams`` (default: Scout II's;
    :data:`DEFAULT_SEARCH`). A ``controller.params[i]`` needs a range and a
    :class:`~scoutsim.CompiledController` ``controller`` with at least i + 1 parameters.
    ValueError naming the parameter otherwise."""
    name, sep, rng = text.partition("=")
    name = name.strip()
    bounds = None
    if sep:
        parts = rng.split(":")
        try:
            bounds = [float(v) for v in parts]
        except ValueError:
            bounds = None
        if bounds is None or len(bounds) != 2:
            raise ValueError(
                f"parameter {text!r} is not allowed: give NAME or NAME=LOW:HIGH with two numbers"
            )
        if not all(math.isfinite(b) for b in bounds):
            raise ValueError(f"parameter {text!r}: LOW and HIGH must be finite numbers")
        if not bounds[0] < bounds[1]:
            raise ValueError(f"parameter {text!r} is not allowed: LOW must be below HIGH")
    m = _PARAMS_NAME.match(name)
    if m:
        i = int(m.group(1))
        n = getattr(controller, "params", None)
        if n is None or not has_tunable_array(controller):
            raise ValueError(
                f"parameter {name!r} is not allowed: controller.params[i] tunes "
                "the parameter array of a CompiledController given as the "
                "controller (Table I and pitch feedback: tune their "
                "controller.<field> instead)"
            )
        if i >= len(n):
            raise ValueError(
                f"parameter {name!r} is not allowed: the controller has "
                f"{len(n)} parameters (params[0] .. params[{len(n) - 1}])"
            )
        if bounds is None:
            raise ValueError(f"parameter {name!r} needs a range: {name}=LOW:HIGH")
        return TuneParameter(name, f"params[{i}]", bounds[0], bounds[1])
    scale = 1.0
    base = name[:-4] if name.endswith("_deg") else name
    _check_tuned_name(name, base)
    # (a per-leg field's one leg, robot.<field>.back / .front, has the field's rules)
    section, field = section_and_field(name)
    if name.endswith("_deg"):
        if field_dimension(field) != "angle":
            raise ValueError(
                f"parameter {name!r} is not allowed: the _deg suffix takes "
                f"degrees for an angle; {base!r} is not an angle (give it in SI "
                "units, without the suffix)"
            )
        scale = math.pi / 180.0
    if field in ("legs_per_virtual_leg", "sense_motor_angle"):
        raise ValueError(
            f"parameter {name!r} is not allowed: tuning varies continuous "
            "parameters, and this one is a whole number or a switch"
        )
    lo_r, hi_r, lo_closed, hi_closed = allowed_range(field)
    # (read even with a range: a per-leg field without a leg is refused here, before the
    # tuning starts, where the legs differ)
    value = _value_of(base, robot or RobotParameters(), cparams or ControllerParameters())
    if bounds is None:
        found = default_search_range(f"{section}.{field}", value)
        if found is None:
            raise ValueError(
                f"parameter {name!r} needs a range: it has no default search "
                f"range; give {name}=LOW:HIGH"
            )
        lo, hi = found
    else:
        lo, hi = bounds[0] * scale, bounds[1] * scale
        ok_lo = lo_r is None or lo > lo_r or (lo == lo_r and lo_closed)
        ok_hi = hi_r is None or hi < hi_r or (hi == hi_r and hi_closed)
        if not (ok_lo and ok_hi):

            def show(v):
                return "unbounded" if v is None else f"{v / scale:.9g}"

            raise ValueError(
                f"parameter {text!r} is not allowed: the range must lie within "
                f"the field's allowed values, {'[' if lo_closed else '('}"
                f"{show(lo_r)}, {show(hi_r)}{']' if hi_closed else ')'}"
            )
    return TuneParameter(name, base, lo, hi, scale)


def has_tunable_array(controller) -> bool:
    """Whether ``controller`` is a CompiledController whose parameter array a run uses as
    it is (not one that packs it again from its parameters for each run's robot, as
    :class:`~scoutsim.control.PitchFeedbackController` does: tune its fields)."""
    from ..control.compiled import CompiledController

    return (
        isinstance(controller, CompiledController)
        and type(controller).params_for is CompiledController.params_for
    )


def _check_tuned_name(name: str, base: str) -> None:
    """ValueError naming ``name`` (``base``: without its _deg suffix) unless it is a field
    of RobotParameters / ControllerParameters, with the nearest name as a hint."""
    try:
        check_name(base)
    except ValueError:
        import difflib

        names = parameter_names()
        names += [n + "_deg" for n in names if field_dimension(n.partition(".")[2]) == "angle"]
        near = difflib.get_close_matches(name, names, n=1)
        hint = f"; did you mean {near[0]!r}?" if near else ""
        raise ValueError(
            f"parameter {name!r} is not allowed: must be robot.<field> or "
            "controller.<field> of RobotParameters / ControllerParameters "
            "(a _deg suffix on an angle takes degrees), or controller.params[i] "
            f"of a CompiledController{hint}"
        ) from None


def apply_values(values: dict, robot, cparams, params):
    """The robot, controller parameters and parameter array with the tuned ``values``
    ({key: SI}) set."""
    rob = {k.partition(".")[2]: v for k, v in values.items() if k.startswith("robot.")}
    ctl = {k.partition(".")[2]: v for k, v in values.items() if k.startswith("controller.")}
    robot = robot_with_values(robot, rob, "robot.")
    cparams = dataclasses.replace(cparams, **ctl) if ctl else cparams
    if params is not None:
        params = np.array(params, dtype=float)
        for k, v in values.items():
            if k.startswith("params["):
                params[int(k[7:-1])] = v
    return robot, cparams, params


def base_value(p: TuneParameter, robot, cparams, spec) -> float:
    """The base value of ``p`` [SI]: its field of ``robot`` or ``cparams``, or its entry of
    the compiled controller's parameter array (``spec["params"]``)."""
    if p.key.startswith("params["):
        return float(spec["params"][int(p.key[7:-1])])
    return _value_of(p.key, robot, cparams)


def _value_of(key: str, robot, cparams) -> float:
    """The value [SI] of ``key`` (``robot.<field>``, a per-leg field's
    ``robot.<field>.<leg>``, or ``controller.<field>``) in ``robot`` / ``cparams``; a
    per-leg field named without a leg is refused where the legs differ (ValueError naming
    the two legs' names)."""
    section, _, fld = key.partition(".")
    if section == "robot":
        return robot_value(robot, fld, "robot.")
    return float(getattr(cparams, fld))


def warn_of_box_ends(params, robot, cparams) -> None:
    """Make the parameter sets at each tuned parameter's bounds once, here, so a search box
    that reaches far from a robot of this kind is warned of once for the tuning
    (:class:`~scoutsim.parameters.ImplausibleParameterWarning`), not per candidate; bounds
    that are not allowed are the candidates' own business."""
    for p in params:
        if p.key.startswith("params["):
            continue
        for v in (p.low, p.high):
            try:
                apply_values({p.key: v}, robot, cparams, None)
            except (ValueError, TypeError):
                pass
