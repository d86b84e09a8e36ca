"""The configuration of ``scoutsim/Bound-v0`` (:class:`~scoutsim.envs.bound.BoundEnv`): what
an action is (:data:`ACTION_TYPES`, :data:`SETPOINTS`) and the observation and action
spaces (:func:`observation_space`, :func:`action_space`), the starts (:data:`STARTS`,
:data:`RANDOM_START_HALF_WIDTHS`, :func:`start_state`), the rendering's options
(:data:`RENDER_MODES`, :data:`RENDER_SIZE`), the plant's (:data:`PLANT_OPTIONS`), and the
robot and Table I parameters made from the constructor's keywords
(:func:`split_options`, :func:`environment_parameters`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from gymnasium import spaces

from ..control.dispatch import plan_controller
from ..control.factory import FactoryError, controller_from_spec, is_factory_spec
from ..control.sensors import CHANNELS, N_SENSORS, SLOT_NAMES
from ..parameters import (
    ControllerParameters,
    RobotParameters,
    closed_range,
    load_parameters,
    validate_parameters,
    validate_robot,
)
from ..simulation.simulator import PLANT_OPTIONS as SIMULATE_PLANT_OPTIONS
from ..state import HybridState, InitialState
from .reward import Reward

#: what an action is: the hip torques, or the set-points of the Table I controller
ACTION_TYPES = ("torque", "setpoints")
#: the set-points a "setpoints" action gives, in its order (fields of
#: :class:`~scoutsim.parameters.ControllerParameters`, [rad] relative to the torso)
SETPOINTS = (
    "touchdown_angle_back",
    "touchdown_angle_front",
    "sweep_limit_back",
    "sweep_limit_front",
)
#: the starts known by name
STARTS = ("random", "flight", "standing")
#: the "random" start, the default: InitialState field -> half-width [SI] of the uniform
#: interval about the flight start (:class:`~scoutsim.state.InitialState`), drawn from the
#: episode's seed, times ``reset_noise_scale`` (1 by default). Height 0.315-0.345 m,
#: forward speed 1.0-1.4 m/s, pitch rate 100-200 deg/s: the neighbourhood of the flight
#: start from which ideal, Model I and Model II all bound under the Table I controller
#: (docs/model.md "Default start and floor"); pitch +-3 deg and each leg's angle +-3 deg
#: about its touchdown angle, so that a policy meets the torso and legs in more than one
#: attitude (the Table I controller still bounds from all of them: tests/envs)
RANDOM_START_HALF_WIDTHS = {
    "y": 0.015,
    "dx": 0.2,
    "dtheta": math.radians(50.0),
    "theta": math.radians(3.0),
    "phi_back": math.radians(3.0),
    "phi_front": math.radians(3.0),
}
#: the half-width [rad] of a "setpoints" action's range about the controller's own
#: set-points (Table I's by default): a normalised action of 0 runs the controller as it
#: is, +-1 moves each set-point by 25 deg (within the parameter schema's range)
SETPOINT_HALF_WIDTH = math.radians(25.0)
#: what :meth:`~scoutsim.envs.bound.BoundEnv.render` can draw (Gymnasium's ``render_mode``)
RENDER_MODES = ("rgb_array",)
#: the frame's size keywords [pixels] with their defaults (None: the default of
#: :func:`scoutsim.presentation.frames.draw_pose`, 480 x 240)
RENDER_SIZE = {"render_width": None, "render_height": None}


#: the observation's names, in its order: the sensor slots' names
#: (:data:`~scoutsim.control.sensors.SLOT_NAMES`)
OBSERVATION_NAMES = SLOT_NAMES
#: pitch rate range [rad/s]: 4 times the bound's largest (about 5 rad/s, 290 deg/s)
_PITCH_RATE_RANGE = 20.0
#: accelerometer range [m/s^2]: 20 g of standard gravity, 9.80665 m/s^2 (touchdowns on
#: stiff legs peak near 10 g)
_ACCELERATION_RANGE = 20.0 * 9.80665
#: laser range [m]: 0 to 2 m (the torso's ends at the simulator's 60 deg fall are below 1 m)
_LASER_RANGE = 2.0
#: hip rate range as a multiple of the motors' no-load leg speed (the ideal actuator has
#: no torque-speed line; its legs swing faster in flight)
_HIP_RATE_SPAN = 4.0


def observation_bounds(
    robot: RobotParameters, pitch_limit_deg: float
) -> tuple[np.ndarray, np.ndarray]:
    """The observation box (low, high), float32, from the robot's physical ranges, in the
    order of :data:`OBSERVATION_NAMES`: hip angles +-pi [rad]; hip rates +-4 x the no-load
    leg speed V / (K_w N) [rad/s]; leg lengths 0 to 1.25 l0 [m]; pitch within the
    simulator's fall limit ``pitch_limit_deg`` (converted to rad); pitch rate +-20 rad/s;
    accelerations +-20 g [m/s^2]; laser ranges 0-2 m; motor currents within the
    amplifier's current limit [A]; battery voltage 0 to 1.25 x its nominal voltage [V].
    A reading outside (sensor noise, a fall's last sample) is clipped to the box."""
    low = np.empty(N_SENSORS)
    high = np.empty(N_SENSORS)
    legs = [robot.leg(leg) for leg in (0, 1)]
    for name, (slot, n, _unit) in CHANNELS.items():
        for i in range(n):
            lo, hi = _channel_range(name, legs[i], robot, pitch_limit_deg)
            low[slot + i], high[slot + i] = lo, hi
    return low.astype(np.float32), high.astype(np.float32)


def _channel_range(name: str, leg: RobotParameters, robot: RobotParameters, pitch_limit_deg):
    """(low, high) of one slot of channel ``name`` (``leg``: that slot's leg)."""
    if name == "hip_angle":
        return -math.pi, math.pi
    if name == "hip_rate":
        w = _HIP_RATE_SPAN * leg.no_load_speed
        return -w, w
    if name == "leg_length":
        return 0.0, 1.25 * leg.leg_rest_length
    if name == "pitch":
        p = math.radians(pitch_limit_deg)
        return -p, p
    if name == "pitch_rate":
        return -_PITCH_RATE_RANGE, _PITCH_RATE_RANGE
    if name == "acceleration":
        return -_ACCELERATION_RANGE, _ACCELERATION_RANGE
    if name == "laser_range":
        return 0.0, _LASER_RANGE
    if name == "motor_current":
        return -leg.current_limit, leg.current_limit
    if name == "battery_voltage":
        return 0.0, 1.25 * robot.battery_voltage
    raise KeyError(name)  # pragma: no cover - every channel is listed above


def observation_space(robot: RobotParameters, pitch_limit_deg: float) -> spaces.Box:
    """The observation's box: the sensor readings in their order, float32, within
    :func:`observation_bounds`."""
    low, high = observation_bounds(robot, pitch_limit_deg)
    return spaces.Box(low, high, (N_SENSORS,), np.float32)


def action_scale(
    robot: RobotParameters, controller: ControllerParameters, action_type: str
) -> tuple[np.ndarray, np.ndarray]:
    """(centre, half-width) of the physical action, float64: a normalised action ``a`` in
    [-1, 1] is ``centre + half_width * a``. "torque": the hip torques (back, front) [N m],
    centre 0, half-width the robot's current-limited torque ``max_leg_torque`` of each
    leg. "setpoints": :data:`SETPOINTS` [rad], centre the controller's own set-points,
    half-width :data:`SETPOINT_HALF_WIDTH`, narrowed (on both sides) where the parameter
    schema's range (:func:`~scoutsim.parameters.closed_range`) is nearer."""
    if action_type == "torque":
        tau = np.array([robot.leg(leg).max_leg_torque for leg in (0, 1)])
        return np.zeros(2), tau
    centre = np.array([float(getattr(controller, name)) for name in SETPOINTS])
    lo, hi = (np.array(v, dtype=float) for v in zip(*(closed_range(n) for n in SETPOINTS)))
    # symmetric about the controller's own values, so that the action 0 is them exactly
    return centre, np.minimum(SETPOINT_HALF_WIDTH, np.minimum(centre - lo, hi - centre))


def action_space(
    robot: RobotParameters,
    controller: ControllerParameters,
    action_type: str,
    normalize_actions: bool = True,
) -> spaces.Box:
    """The action's box, float32: ``Box(-1, 1)`` (``normalize_actions``, the default), or
    the physical range centre +- half-width of :func:`action_scale`."""
    centre, half = action_scale(robot, controller, action_type)
    if normalize_actions:
        return spaces.Box(-1.0, 1.0, centre.shape, np.float32)
    return spaces.Box(
        (centre - half).astype(np.float32),
        (centre + half).astype(np.float32),
        centre.shape,
        np.float32,
    )


def start_state(start, reset_noise_scale: float, rng, robot=None, controller=None):
    """The start of an episode from the environment's ``start`` (:data:`STARTS`, a state or
    a callable ``start(np_random)``) and ``reset_noise_scale``, drawn with ``rng``: a
    HybridState or InitialState (``rng`` None: the start without its draws, None for a
    callable). The "random" start draws the legs' angles about ``controller``'s touchdown
    angles (default Table I) and is raised where needed so that both of ``robot``'s toes
    (default Scout II) start :data:`START_TOE_CLEARANCE` or more above the ground."""
    if isinstance(start, (InitialState, HybridState)):
        return start
    if start == "flight":
        return InitialState()
    if start == "random":
        controller = controller if controller is not None else ControllerParameters()
        init = InitialState(
            phi_back=controller.touchdown_angle_back, phi_front=controller.touchdown_angle_front
        )
        if rng is None:
            return init
        changes = {
            name: getattr(init, name) + reset_noise_scale * half * float(rng.uniform(-1.0, 1.0))
            for name, half in RANDOM_START_HALF_WIDTHS.items()
        }
        return _above_ground(init.replace(**changes), robot or RobotParameters())
    if rng is None:  # (a user's distribution: drawn at reset only)
        return None
    state = start(rng)
    if not isinstance(state, (InitialState, HybridState)):
        raise TypeError(
            f"start(np_random) returned {type(state).__name__}: must be an "
            "InitialState or a HybridState"
        )
    return state


#: the least height [m] of a "random" start's toes above the ground
START_TOE_CLEARANCE = 0.005


def _above_ground(init: InitialState, robot: RobotParameters) -> InitialState:
    """``init`` raised, if needed, until both toes are :data:`START_TOE_CLEARANCE` above the
    ground (toe height y + s_leg sin(theta) - l0 cos(theta + phi), s_leg the hip's signed
    offset along the torso, phi the leg's angle from the torso)."""
    lowest = min(
        init.y
        + robot.hip_offset(leg) * math.sin(init.theta)
        - robot.leg(leg).leg_rest_length * math.cos(init.theta + phi)
        for leg, phi in ((0, _given(init.phi_back)), (1, _given(init.phi_front)))
    )
    if lowest >= START_TOE_CLEARANCE:
        return init
    return init.replace(y=init.y + START_TOE_CLEARANCE - lowest)


def _given(angle: float | None) -> float:
    """A leg angle the "random" start has set (never None there)."""
    assert angle is not None
    return angle


#: the environment's keywords for the plant beyond the robot, with their defaults: the floor's
#: friction and the pitch limit as :func:`scoutsim.simulate` has them, and the integrator
PLANT_OPTIONS = {
    **{k: SIMULATE_PLANT_OPTIONS[k] for k in ("friction_coefficient", "pitch_limit_deg")},
    "integrator": None,
}


def split_options(reward: Reward | None, options: dict) -> tuple[Reward, dict, dict]:
    """The environment's :class:`Reward` (with the keywords of its fields applied), its
    plant options (:data:`PLANT_OPTIONS`) and the rest: robot and controller fields."""
    fields = {f.name for f in dataclasses.fields(Reward)}
    rew = {k: options.pop(k) for k in list(options) if k in fields}
    plant = {k: options.pop(k, default) for k, default in PLANT_OPTIONS.items()}
    return dataclasses.replace(reward or Reward(), **rew), plant, options


def environment_parameters(robot, controller, robot_file, overrides, model):
    """(RobotParameters, ControllerParameters) from the constructor's arguments."""
    robot_fields = {f.name for f in dataclasses.fields(RobotParameters)}
    ctrl_fields = {f.name for f in dataclasses.fields(ControllerParameters)}
    unknown = set(overrides) - robot_fields - ctrl_fields
    if unknown:
        import difflib

        name = sorted(unknown)[0]
        close = difflib.get_close_matches(name, sorted(robot_fields | ctrl_fields), n=1)
        raise TypeError(
            f"BoundEnv got an unexpected keyword {name!r}: not an option nor a "
            "field of RobotParameters or ControllerParameters"
            + (f"; did you mean {close[0]!r}?" if close else "")
        )
    r_over = {k: v for k, v in overrides.items() if k in robot_fields}
    c_over = {k: v for k, v in overrides.items() if k in ctrl_fields}
    spec = controller if isinstance(controller, str) else None
    if spec is not None:
        controller = None
        if not is_factory_spec(spec):
            raise ValueError(
                f"controller = {spec!r} is not allowed: a string must be "
                "'MODULE:FACTORY' (e.g. 'my_gaits:make', a function in "
                "my_gaits.py returning ControllerParameters)"
            )
    if robot_file is not None:
        if robot is not None or controller is not None:
            raise ValueError("robot_file is not allowed together with robot or controller")
        robot, controller = load_parameters(robot_file, r_over, c_over)
    else:
        robot = (robot if robot is not None else RobotParameters()).replace(**r_over)
        controller = (controller if controller is not None else ControllerParameters()).replace(
            **c_over
        )
        validate_robot(robot)
    if spec is not None:
        controller = _from_factory(spec, robot, controller, model).replace(**c_over)
    validate_parameters(robot, controller)
    return robot, controller


def _from_factory(
    spec: str, robot: RobotParameters, params: ControllerParameters, model: str
) -> ControllerParameters:
    """The Table I parameters the factory ``spec`` makes for ``robot`` from ``params``."""
    made = controller_from_spec(spec, robot, params)
    # what simulate() would run it as: the built-in law (with these parameters) or not
    plan = plan_controller(made, model, robot)
    if plan.kind != "builtin":
        raise FactoryError(
            f"controller {spec!r} returned {type(made).__name__}, a controller "
            "with a command() of its own: BoundEnv runs the Table I law (the "
            "agent sets its set-points) or the agent's hip torques, so its "
            "factory must return ControllerParameters (or a "
            "BoundingController with the built-in law)"
        )
    assert plan.parameters is not None  # (the built-in law runs with parameters)
    return plan.parameters
