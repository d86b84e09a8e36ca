"""Orbit sensitivities: how a periodic gait and its stability move with each robot,
controller or floor parameter, by the implicit function theorem on the fixed point.

At a fixed point z* = P(z*, p) of the stride map (:mod:`scoutsim.analysis.controlled_orbit`;
its ``strides``-th iterate for a cycle of several strides),

    dz*/dp = (I - dP/dz)^+ dP/dp,

with dP/dz the orbit's Jacobian and dP/dp by central differences of the map at z*
(relative step ``relative_step``; least squares, since the dependent coordinates of
pinned legs and stuck joints make I - dP/dz singular). A metric m(z, p) of the orbit (its
mean speed, duty factors, extremes, electrical power, cost of transport, spectral
radius) then moves by

    dm/dp = [m(z* + h dz*/dp, p + h) - m(z* - h dz*/dp, p - h)] / (2 h),

one period simulated from each end, without solving for the orbit again (the spectral
radius's ends take one Newton step from the prediction, at tighter tolerances: see
RADIUS_TOLERANCE_FACTOR). The elasticity is (dm/dp) p / m [% per %]. The stride
frequency of a sampled orbit is locked to the control period (a whole number of samples
per period), so within a sample-phase cell its derivative is 0; a step that leaves the cell (another number of samples,
controller switches on other samples, another sequence of plant events) is reported
instead of differenced.

Units: SI; metrics as named (``*_m_s``, ``*_hz``, ``*_rad``, ``*_m``, ``*_w``, ``-``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..control.pitch_feedback import PitchFeedbackController
from ..parameters import ControllerParameters, RobotParameters
from ..parameters.robot_fields import leg_names_where_legs_differ, robot_value, robot_with_value
from ..simulation.integrator import IntegratorSettings
from ..simulation.simulator import simulate
from ..state import HybridState
from .controlled_orbit import ControlledOrbit, cell_change, newton_step, stride_jacobian
from .poincare import MapError
from .stride_map import StrideMap

__all__ = [
    "SENSITIVITY_METRICS",
    "ParameterSensitivity",
    "orbit_metrics",
    "orbit_sensitivities",
    "parameter_value",
    "radius_integrator",
    "sensitivity_parameter_names",
    "setting_with",
]

#: the metrics of an orbit whose sensitivities are computed (SI, as named)
SENSITIVITY_METRICS = (
    "mean_speed_m_s",
    "stride_frequency_hz",
    "duty_factor_back",
    "duty_factor_front",
    "pitch_max_rad",
    "pitch_min_rad",
    "height_max_m",
    "height_min_m",
    "electrical_power_w",
    "cost_of_transport",
    "spectral_radius",
)
#: the floor parameter's name
FRICTION = "friction_coefficient"
#: absolute step of a parameter whose value is 0 (SI)
ZERO_STEP = 1e-6
#: the spectral radius's ends are integrated at this times the orbit's tolerances, down
#: to RADIUS_RTOL_FLOOR (DOPRI5 in double precision: tighter gains nothing). The radius's
#: derivative is a difference of two Jacobians of the map, whose integration error (it
#: depends on the run's steps) and the rounding of its events' central differences both
#: change with the parameter: on the default Model II orbit the radius scatters along a
#: parameter by about 3.5e-7 at rtol 1e-11 and 3.5e-8 to 7e-8 (single values up to 2e-7)
#: at rtol 1e-13 (docs/explanation/derivatives.md), so over the metrics' own step h its
#: derivative is resolved to about 1e-7 / h
RADIUS_TOLERANCE_FACTOR = 1e-2
RADIUS_RTOL_FLOOR = 1e-13


@dataclass
class ParameterSensitivity:
    """How an orbit's metrics move with one parameter.

    name : the parameter ("robot.<field>", "controller.<field>" or "friction_coefficient").
    value : its value at the orbit (SI).
    derivative : {metric: d metric / d parameter} (SI per SI).
    elasticity : {metric: (d metric / d parameter) value / metric} [% per %] (NaN where
        the value or the metric is 0).
    status : "ok", or why there is none (the step leaves the sample-phase cell, ...).
    radius_step : the parameter step of the spectral radius's derivative (SI; the
        metrics' step); NaN without it.
    """

    name: str
    value: float
    derivative: dict = field(default_factory=dict)
    elasticity: dict = field(default_factory=dict)
    status: str = "ok"
    radius_step: float = math.nan

    def to_dict(self) -> dict:
        return {
            "value": self.value,
            "derivative": self.derivative,
            "elasticity": self.elasticity,
            "status": self.status,
            "spectral_radius_step": self.radius_step,
        }


def sensitivity_parameter_names(controller=None, robot: RobotParameters | None = None) -> list[str]:
    """The parameters whose sensitivities can be computed: every float field of
    RobotParameters (on a ``robot`` whose legs differ in a per-leg field, that field's
    two legs, ``robot.<field>.back`` and ``robot.<field>.front``; see
    :mod:`scoutsim.parameters.robot_fields`), of the Table I ControllerParameters (when the
    controller is the built-in law; not its control period or torso-feedback gains) and
    the floor's friction coefficient."""
    fields = [
        f.name
        for f in dataclasses.fields(RobotParameters)
        if isinstance(getattr(RobotParameters(), f.name), float)
    ]
    names = [f"robot.{n}" for n in leg_names_where_legs_differ(robot or RobotParameters(), fields)]
    if controller is None or isinstance(controller, ControllerParameters):
        names += [
            f"controller.{f.name}"
            for f in dataclasses.fields(ControllerParameters)
            if isinstance(getattr(ControllerParameters(), f.name), float)
            and f.name not in _NOT_SMOOTH
        ]
    return names + [FRICTION]


#: controller fields without a sensitivity: the control period (it moves the sample grid
#: itself) and the torso-feedback gains (the Table I law does not use them)
_NOT_SMOOTH = (
    "control_period",
    "pitch_gain_front",
    "pitch_gain_back",
    "pitch_rate_gain_front",
    "pitch_rate_gain_back",
)


def setting_with(setting: dict, name: str, value: float) -> dict:
    """The orbit's setting (model, floor, robot, controller) with parameter ``name`` set
    to ``value`` (SI). ``controller.<field>`` sets a field of the Table I law's
    ControllerParameters, or of those a PitchFeedbackController runs on (a new controller
    is built from them)."""
    out = dict(setting)
    if name == FRICTION:
        out["friction_coefficient"] = value
        return out
    sec, _, fld = name.partition(".")
    changes: dict[str, Any] = {fld: value}
    if sec == "robot":
        out["robot"] = robot_with_value(setting["robot"] or RobotParameters(), fld, value, "robot.")
    elif sec == "controller" and (
        setting["controller"] is None or isinstance(setting["controller"], ControllerParameters)
    ):
        base = setting["controller"] or ControllerParameters()
        out["controller"] = dataclasses.replace(base, **changes)
    elif sec == "controller" and isinstance(setting["controller"], PitchFeedbackController):
        law = setting["controller"].controller_parameters or ControllerParameters()
        out["controller"] = PitchFeedbackController(dataclasses.replace(law, **changes))
    else:
        raise ValueError(
            f"parameter {name!r} is not allowed: must be one of "
            "sensitivity_parameter_names() (robot.<field>, controller.<field> of the "
            "built-in law or of pitch feedback, friction_coefficient)"
        )
    return out


def parameter_value(setting: dict, name: str) -> float:
    """The value (SI) of parameter ``name`` in an orbit's setting."""
    if name == FRICTION:
        return float(setting["friction_coefficient"])
    sec, _, fld = name.partition(".")
    if sec == "robot":
        return robot_value(setting["robot"] or RobotParameters(), fld, "robot.")
    obj = setting["controller"]
    if obj is None:
        obj = ControllerParameters()
    if isinstance(obj, PitchFeedbackController):
        obj = obj.controller_parameters
    return float(getattr(obj, fld))


def orbit_metrics(hs, period: float, setting: dict, integrator, jacobian=None) -> dict:
    """The metrics (:data:`SENSITIVITY_METRICS`) of one period ``period`` [s] from the
    section state ``hs`` in ``setting`` (model, friction_coefficient, robot, controller);
    ``jacobian``: the period map's Jacobian there, for the spectral radius (NaN without)."""
    robot = setting["robot"] or RobotParameters()
    model = setting["model"]
    r = simulate(
        robot,
        setting["controller"],
        hs,
        period,
        model=model,
        integrator=integrator,
        friction_coefficient=setting["friction_coefficient"],
        energy=model in ("I", "II"),
    )
    travel = float(r.x[-1] - r.x[0])
    out = {
        "mean_speed_m_s": travel / period,
        "stride_frequency_hz": len(r.event_times("liftoff", "back")) / period,
        "pitch_max_rad": float(np.max(r.pitch)),
        "pitch_min_rad": float(np.min(r.pitch)),
        "height_max_m": float(np.max(r.height)),
        "height_min_m": float(np.min(r.height)),
    }
    for leg in ("back", "front"):
        out[f"duty_factor_{leg}"] = _stance_time(r, leg, period) / period
    if model in ("I", "II"):
        e = float(r.cumulative_energy("electrical")[-1] - r.cumulative_energy("electrical")[0])
        out["electrical_power_w"] = e / period
        out["cost_of_transport"] = e / (robot.total_mass * 9.81 * travel)
    else:
        out["electrical_power_w"] = out["cost_of_transport"] = math.nan
    out["spectral_radius"] = (
        math.nan if jacobian is None else float(np.max(np.abs(np.linalg.eigvals(jacobian))))
    )
    return {k: out[k] for k in SENSITIVITY_METRICS}


def _stance_time(r, leg: str, period: float) -> float:
    """Time [s] leg ``leg`` spends on the ground within [0, period] (its touchdown and
    lift-off events, located in continuous time)."""
    events = sorted(
        [(t, True) for t in r.event_times("touchdown", leg)]
        + [(t, False) for t in r.event_times("liftoff", leg)]
    )
    down = r.hybrid_state(0).contact_modes[0 if leg == "back" else 1] != 0
    t_down, total = 0.0, 0.0
    for t, touchdown in events:
        if touchdown:
            down, t_down = True, t
        elif down:
            total += t - t_down
            down = False
    if down:
        total += period - t_down
    return total


def orbit_sensitivities(
    orbit: ControlledOrbit,
    names,
    *,
    relative_step: float = 1e-4,
    spectral_radius: bool = True,
    progress=None,
    workers: int | None = 1,
    scheduler=None,
) -> tuple[dict[str, ParameterSensitivity], dict]:
    """The sensitivities of the metrics of ``orbit`` (found by
    :func:`~scoutsim.analysis.controlled_orbit.controlled_fixed_point`, which keeps its
    setting) to each parameter of ``names`` (see :func:`sensitivity_parameter_names`;
    "all": every one), by the implicit function theorem (module docstring) with steps
    ``relative_step`` |p| (a forward step of :data:`ZERO_STEP` for a parameter at 0).
    ``spectral_radius``: also the spectral radius's, a difference of the map's Jacobians
    (the orbit's method) at the two ends, each at the orbit solved again there and
    integrated at :func:`radius_integrator`'s tolerances (see RADIUS_TOLERANCE_FACTOR).
    ``progress``: optional callable(str), told each parameter as it is done.
    ``workers``: local processes, one parameter each at a time (None: all cores; 1: in
    this process); ``scheduler``: a Dask scheduler address or client, or an open
    ``concurrent.futures.Executor``, instead (:func:`~scoutsim.analysis.parallel.map_tasks`;
    the orbit's controller must then be one that can be sent to another process). Each
    parameter's sensitivities are the same, bit for bit, wherever they are computed; a
    parameter whose worker failed says so in its ``status``. Returns
    ``({name: ParameterSensitivity}, the metrics at the orbit)``."""
    from .parallel import map_tasks
    from .study_controller import check_controller_travels

    setting = orbit.setting
    if not setting:
        raise ValueError("orbit has no setting: find it with controlled_fixed_point()")
    if names == "all" or names == ["all"]:
        names = sensitivity_parameter_names(setting["controller"], setting["robot"])
    names = list(names)
    check_controller_travels(setting["controller"], workers, scheduler, len(names))
    integ = setting["integrator"]
    base_values = orbit_metrics(orbit.state, orbit.period, setting, integ, orbit.jacobian)
    tasks = [
        _SensitivityTask(orbit, name, relative_step, spectral_radius, base_values) for name in names
    ]
    say = progress or (lambda message: None)

    def told(i: int, sens: ParameterSensitivity) -> None:
        if sens.status != "ok":
            say(f"{sens.name}: {sens.status}")
        else:
            d = sens.derivative["mean_speed_m_s"]
            say(f"{sens.name} = {sens.value:.6g}: d speed / d p = {d:.4g}")

    def failed(task: _SensitivityTask, exc: BaseException) -> ParameterSensitivity:
        return ParameterSensitivity(
            name=task.name,
            value=parameter_value(setting, task.name),
            status=f"no sensitivity: its computation failed ({type(exc).__name__}: {exc})",
        )

    results = map_tasks(
        parameter_sensitivity,
        tasks,
        workers=workers,
        scheduler=scheduler,
        desc="sensitivities",
        on_result=told,
        error_row=failed,
    )
    return dict(zip(names, results)), base_values


@dataclass(frozen=True)
class _SensitivityTask:
    """One parameter's part of :func:`orbit_sensitivities` (sent to a worker as is)."""

    orbit: ControlledOrbit
    name: str
    relative_step: float
    spectral_radius: bool
    base_values: dict


def parameter_sensitivity(task: _SensitivityTask) -> ParameterSensitivity:
    """One parameter's sensitivities (:func:`orbit_sensitivities`, whose task it is): a
    step that leaves the sample-phase cell or an orbit that cannot be solved again is its
    ``status``, not an exception."""
    orbit, name, base_values = task.orbit, task.name, task.base_values
    setting = orbit.setting
    integ, k = setting["integrator"], orbit.strides
    like = orbit.state
    assert isinstance(like, HybridState), "an orbit's state is a HybridState"
    p = parameter_value(setting, name)
    h = task.relative_step * abs(p) if p != 0.0 else ZERO_STEP
    sens = ParameterSensitivity(name=name, value=p)
    if not math.isfinite(p):
        sens.status = f"no sensitivity: {name} = {p} is not finite"
        return sens
    # central differences; forward ones for a parameter at 0 (most such parameters are
    # bounded below by 0: a friction, a loss, a backlash)
    signs = (1.0, -1.0) if p != 0.0 else (1.0,)
    try:
        base_map = StrideMap(integrator=integ, section=setting["section"], **_common(setting))
        base = base_map.crossing(orbit.state, strides=k)
        ends, dz = _tangent(orbit, base, base_map, name, h, signs)
        values = []
        for s_p, m, _, sign in ends:
            hs = m.hs_of(orbit.z + sign * h * dz, like)
            values.append(orbit_metrics(hs, orbit.period, s_p, integ))
        if len(values) == 1:
            values.append(dict(base_values))
        if task.spectral_radius:
            radii = _radii(orbit, ends, dz, h)
            sens.radius_step = h
            for i, r in enumerate(radii):
                values[i]["spectral_radius"] = r
    except (MapError, ValueError) as exc:
        sens.status = f"no sensitivity: {exc}"
        return sens
    for metric in SENSITIVITY_METRICS:
        step = sens.radius_step if metric == "spectral_radius" else h
        d = (values[0][metric] - values[1][metric]) / (len(signs) * step)
        sens.derivative[metric] = d
        mv = base_values.get(metric, math.nan)
        sens.elasticity[metric] = d * p / mv if p != 0.0 and mv != 0.0 else math.nan
    return sens


def radius_integrator(integrator: IntegratorSettings) -> IntegratorSettings:
    """The integrator of the spectral radius's ends: ``integrator`` with its tolerances
    RADIUS_TOLERANCE_FACTOR times as tight (rtol not below RADIUS_RTOL_FLOOR; unset
    tolerances stay the method's defaults)."""
    rtol, atol = integrator.rtol, integrator.atol
    if rtol is None or atol is None:
        return integrator
    tight = max(rtol * RADIUS_TOLERANCE_FACTOR, RADIUS_RTOL_FLOOR)
    return dataclasses.replace(integrator, rtol=tight, atol=atol * tight / rtol)


def _radii(orbit: ControlledOrbit, ends, dz, h: float):
    """The spectral radius of the stride map's Jacobian (the orbit's method, integrated
    with :func:`radius_integrator`) at the orbit moved to each end of ``ends`` (from
    :func:`_tangent`: the parameter at sign ``h``) along ``dz`` = dz*/dp (and at the
    orbit, for a forward step)."""
    tight = radius_integrator(orbit.setting["integrator"])
    out = [_radius_at(orbit, s_p, orbit.z + sign * h * dz, tight) for s_p, _, _, sign in ends]
    if len(ends) == 1:
        out.append(_radius_at(orbit, orbit.setting, orbit.z, tight))
    return out


def _radius_at(orbit: ControlledOrbit, setting: dict, z, integrator) -> float:
    """The spectral radius of the Jacobian of the stride map of ``setting`` (integrated
    with ``integrator``) at its fixed point near the section state ``z`` of ``orbit``:
    ``z`` (the orbit moved along dz*/dp) corrected by one Newton step, which removes the
    predictor's second-order error (the radius is curved in the state: without it the
    derivative over the friction's step was off by 1e-2)."""
    k, like = orbit.strides, orbit.state
    assert isinstance(like, HybridState), "an orbit's state is a HybridState"
    how = (orbit.jacobian_method, 1e-6)
    m = StrideMap(integrator=integrator, section=setting["section"], **_common(setting))
    c = m.crossing(m.hs_of(z, like), strides=k)
    assert c.start is not None, "a crossing from a HybridState keeps its start"
    z0 = m.z_of(c.start)
    J, _ = stride_jacobian(m, z0, c.start, c, how, k)
    step = newton_step(J, m.z_of(c.state) - z0)
    c1 = m.crossing(m.hs_of(z0 + step, like), strides=k)
    if not cell_change(c, c1):
        assert c1.start is not None, "a crossing from a HybridState keeps its start"
        J, _ = stride_jacobian(m, m.z_of(c1.start), c1.start, c1, how, k)
    return float(np.max(np.abs(np.linalg.eigvals(J))))


def _tangent(orbit: ControlledOrbit, base, base_map: StrideMap, name: str, h: float, signs):
    """dz*/dp of ``orbit`` (whose stride map ``base_map`` gives the crossing ``base``) for
    parameter ``name`` with step ``h``, central (``signs`` (1, -1)) or forward ((1,)):
    (the ends: (setting, map, P(z*), sign) at p + sign h; dz*/dp). MapError if a step
    leaves the sample-phase cell."""
    setting, k = orbit.setting, orbit.strides
    p = parameter_value(setting, name)
    ends = []
    for sign in signs:
        s_p = setting_with(setting, name, p + sign * h)
        m = StrideMap(integrator=setting["integrator"], section=setting["section"], **_common(s_p))
        c = m.crossing(orbit.state, strides=k)
        why = cell_change(base, c)
        if why:
            raise MapError(f"a step of {sign * h:+.2e} in {name}: {why}")
        ends.append((s_p, m, m.z_of(c.state), sign))
    z_back = ends[1][2] if len(ends) > 1 else base_map.z_of(base.state)
    dPdp = (ends[0][2] - z_back) / (len(ends) * h)
    n = orbit.z.size
    return ends, np.linalg.lstsq(np.eye(n) - orbit.jacobian, dPdp, rcond=1e-12)[0]


def _common(setting: dict) -> dict:
    return {k: setting[k] for k in ("model", "friction_coefficient", "robot", "controller")}
