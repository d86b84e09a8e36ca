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
from ..control.sensors import N_SENSORS
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
STARTS = ("flight", "standing", "random")
#: the "random" start: InitialState field -> half-width [SI] of the uniform interval about
#: the flight start (``reset_noise_scale`` = 1): height 0.32-0.35 m, forward speed
#: 1.0-1.4 m/s, pitch rate 100-200 deg/s, the neighbourhood of the flight start from which
#: ideal, Model I and Model II all bound under the Table I controller (docs/model.md
#: "Default start and floor"; the height interval is centred on 0.33 m: 0.315-0.345 m)
RANDOM_START_HALF_WIDTHS = {"y": 0.015, "dx": 0.2, "dtheta": math.radians(50.0)}
#: what :meth:`~scoutsim.envs.bound.BoundEnv.render` can draw (Gymnasium's ``render_mode``)
RENDER_MODES = ("rgb_array",)
#: the frame's size keywords [pixels] with their defaults (None: the default of
#: :func:`scoutsim.presentation.frames.draw_pose`, 480 x 240)
RENDER_SIZE = {"render_width": None, "render_height": None}


def observation_space() -> spaces.Box:
    """The observation's box: the sensor readings in their order, float64, unbounded."""
    return spaces.Box(-np.inf, np.inf, (N_SENSORS,), np.float64)


def action_space(robot: RobotParameters, action_type: str) -> spaces.Box:
    """The action's box for ``action_type``: the hip torques within the robot's
    current-limited torque, or the set-points within the parameter schema's ranges."""
    if action_type == "torque":
        tau = np.array([robot.leg(leg).max_leg_torque for leg in (0, 1)])
        return spaces.Box(-tau, tau, (2,), np.float64)
    lo, hi = zip(*(closed_range(name) for name in SETPOINTS))
    return spaces.Box(np.array(lo), np.array(hi), (len(SETPOINTS),), np.float64)


def start_state(start, reset_noise_scale: float, rng):
    """The start of an episode from the environment's ``start`` (:data:`STARTS`, a state or
    a callable ``start(np_random)``) and ``reset_noise_scale``, drawn with ``rng``: a
    HybridState or InitialState (``rng`` None: the start without its draws, None for a
    callable)."""
    if isinstance(start, (InitialState, HybridState)):
        return start
    if start == "flight":
        return InitialState()
    if start == "random":
        init = InitialState()
        if rng is None:
            return init
        changes = {
            name: getattr(init, name) + reset_noise_scale * half * float(rng.uniform(-1.0, 1.0))
            for name, half in RANDOM_START_HALF_WIDTHS.items()
        }
        return init.replace(**changes)
    if rng is None:  # (a user's distribution: drawn at reset only)
        return None
    state = start(rng)
    if not isinstance(state, (InitialState, HybridState)):
        raise TypeError(
            f"start(np_random) returned {type(state).__name__}: must be an "
            "InitialState or a HybridState"
        )
    return state


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
