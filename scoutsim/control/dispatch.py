"""Which controller runs, and how: from what :func:`scoutsim.simulate` is given to what the
compiled loop calls (:class:`ControllerPlan`).

* ``None`` (the Table I defaults), :class:`~scoutsim.parameters.ControllerParameters`, or a
  :class:`~scoutsim.control.bounding.BoundingController` whose ``command`` is not
  overridden: the built-in Table I law, compiled into the loop (``layout.CTRL_BUILTIN``);
* a :class:`~scoutsim.control.compiled.CompiledController`: its compiled function, called
  by the loop through its address (``layout.CTRL_POINTER``);
* any other object with ``command(t, sensors)`` (the protocol of
  :mod:`scoutsim.control.protocol`): called by the loop through a ``ctypes`` callback
  (:class:`PythonBridge`), which hands it a :class:`~scoutsim.control.sensors.Sensors` at
  every sample and checks what it returns;
* the passive model: no controller (the built-in law disabled: zero torques).

The sensors' measurement model (:class:`~scoutsim.control.sensors.SensorParameters`) is the
same for every kind.
"""

from __future__ import annotations

import ctypes
import math
import numbers
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._core.model import layout as L
from ..parameters import ControllerParameters, RobotParameters
from .block import ControlBlock, control_block
from .bounding import BoundingController, controller_array
from .compiled import CompiledController
from .protocol import DEFAULT_CONTROL_PERIOD, controller_name
from .sensors import SensorParameters, Sensors

__all__ = [
    "ControllerPlan",
    "ControllerStateError",
    "PythonBridge",
    "check_state_access",
    "plan_controller",
    "read_controller_state",
    "write_controller_state",
]


@dataclass
class ControllerPlan:
    """How a run is controlled.

    kind : "builtin", "compiled", "python" or "none".
    controller : the user's controller object (None for the built-in law).
    parameters : the Table I parameters the built-in law runs with, those a compiled
        controller builds on (its ``controller_parameters``), or those a Python
        controller carries as ``params`` (they set the legs' angles at a start in flight);
        None otherwise.
    control_period : [s].
    C : the built-in law's parameter array (:func:`~scoutsim.control.bounding.controller_array`;
        disabled unless ``kind`` is "builtin").
    block : the loop's :class:`~scoutsim.control.block.ControlBlock`.
    bridge : the :class:`PythonBridge` of a Python controller.
    label : what the provenance calls it ("builtin", "none" or the controller's name).
    """

    kind: str
    controller: Any
    parameters: ControllerParameters | None
    control_period: float
    C: np.ndarray
    block: ControlBlock
    bridge: PythonBridge | None = None
    label: str = "builtin"


def _runs_builtin(controller) -> bool:
    """A BoundingController (or a subclass) that does not override ``command``."""
    return (
        isinstance(controller, BoundingController)
        and type(controller).command is BoundingController.command
    )


def _period(controller) -> float:
    """The controller's control period [s]: its ``control_period``; else, for an object with
    Table I ``params``, theirs; else the paper's 1 ms."""
    dt = getattr(controller, "control_period", None)
    if dt is None:
        params = getattr(controller, "params", None)
        dt = (
            params.control_period
            if isinstance(params, ControllerParameters)
            else DEFAULT_CONTROL_PERIOD
        )
    if (
        isinstance(dt, bool)
        or not isinstance(dt, numbers.Real)
        or not (math.isfinite(dt) and 1e-6 <= float(dt) <= 1.0)
    ):
        raise ValueError(
            f"controller.control_period = {dt!r} s is not allowed: must be in "
            f"[1e-6, 1] s ({controller_name(controller)})"
        )
    return float(dt)


#: the default sensors (every channel ideal), made once: a frozen set, shared by every run
_IDEAL_SENSORS = SensorParameters()


def plan_controller(
    controller, model: str, robot: RobotParameters, sensors: SensorParameters | None = None
) -> ControllerPlan:
    """The plan of a run of ``model`` on ``robot`` controlled by ``controller`` (see the
    module docstring) with the sensors ``sensors`` (default: ideal)."""
    sensors = sensors if sensors is not None else _IDEAL_SENSORS
    if not isinstance(sensors, SensorParameters):
        raise TypeError(f"sensors must be SensorParameters, not {type(sensors).__name__}")
    user = None
    if model == "passive":
        cparams = None
        if controller is not None and not isinstance(controller, ControllerParameters):
            user = controller
    elif controller is None:
        cparams = ControllerParameters()
    elif isinstance(controller, ControllerParameters):
        cparams = controller
    elif _runs_builtin(controller):
        cparams = controller.params
    elif callable(getattr(controller, "command", None)):
        user = controller
        cparams = getattr(controller, "params", None)
        if not isinstance(cparams, ControllerParameters):
            cparams = getattr(controller, "controller_parameters", None)
        if not isinstance(cparams, ControllerParameters):
            cparams = None
    else:
        raise TypeError(
            "controller must be ControllerParameters, a BoundingController, a "
            "CompiledController or an object with a command(t, sensors) method "
            "(scoutsim.control.protocol)"
        )
    if user is not None and not callable(getattr(user, "command", None)):
        raise TypeError(f"controller {controller_name(user)} has no command(t, sensors) method")
    # the hip encoders read the motor side (Model II: alpha) as the Table I controller is
    # set to (sense_motor_angle); a controller without Table I parameters: the default
    motor_side = (cparams if cparams is not None else ControllerParameters()).sense_motor_angle
    if model == "passive" and user is None:
        motor_side = False
    geom = sensors.geometry_array(robot, motor_side)
    spec = sensors.spec_array()
    if user is None:
        dt = cparams.control_period if cparams is not None else DEFAULT_CONTROL_PERIOD
        block = control_block(L.CTRL_BUILTIN, spec=spec, geom=geom, seed=sensors.seed)
        return ControllerPlan(
            kind="builtin" if cparams is not None else "none",
            controller=None,
            parameters=cparams,
            control_period=dt,
            C=controller_array(cparams, robot),
            block=block,
            label="builtin" if cparams is not None else "none",
        )
    dt = _period(user)
    if isinstance(user, CompiledController):
        params = np.array(user.params_for(robot), dtype=np.float64).ravel()
        block = control_block(
            L.CTRL_POINTER,
            address=user.address,
            spec=spec,
            geom=geom,
            seed=sensors.seed,
            params=params,
            state=user.initial_state.copy(),
        )
        return ControllerPlan(
            kind="compiled",
            controller=user,
            parameters=cparams,
            control_period=dt,
            C=controller_array(None),
            block=block,
            label=controller_name(user),
        )
    block = control_block(L.CTRL_POINTER, spec=spec, geom=geom, seed=sensors.seed)
    return ControllerPlan(
        kind="python",
        controller=user,
        parameters=cparams,
        control_period=dt,
        C=controller_array(None),
        block=block,
        label=controller_name(user),
    )


class ControllerStateError(TypeError):
    """The controller's own state cannot be read or set: a Python controller without
    ``get_state()`` / ``set_state(values)`` (:mod:`scoutsim.control.protocol`), or a state of
    the wrong size."""


def check_state_access(plan: ControllerPlan) -> None:
    """ControllerStateError unless scoutsim can read and set the own state of the
    controller of ``plan`` (the built-in law and compiled controllers: always; a Python
    controller: with ``get_state()`` and ``set_state(values)``)."""
    if plan.kind != "python":
        return
    c = plan.controller
    if not callable(getattr(c, "get_state", None)) or not callable(getattr(c, "set_state", None)):
        raise ControllerStateError(
            f"controller {controller_name(c)} offers no state: give it get_state() and "
            "set_state(values) (scoutsim.control.protocol; a stateless controller "
            "returns ()), or make it a CompiledController"
        )


def read_controller_state(plan: ControllerPlan) -> tuple[float, ...]:
    """The controller's own state now (:attr:`~scoutsim.state.HybridState.controller_state`):
    a compiled controller's state array (as the loop left it), a Python controller's
    ``get_state()``, nothing for the built-in law (its leg states are the plan's ``ls``).
    ControllerStateError for a Python controller that offers no state."""
    if plan.kind == "compiled":  # (an empty state has a one-slot placeholder array)
        n = plan.controller.initial_state.size
        return tuple(float(v) for v in plan.block.state[:n])
    if plan.kind != "python":
        return ()
    check_state_access(plan)
    values = np.asarray(plan.controller.get_state(), dtype=float).ravel()
    if not np.all(np.isfinite(values)):
        raise ControllerStateError(
            f"controller {controller_name(plan.controller)}: get_state() returned "
            f"{values!r}, not finite numbers"
        )
    return tuple(float(v) for v in values)


def write_controller_state(plan: ControllerPlan, values) -> None:
    """Put the controller's own state ``values`` (a sequence of floats, as
    :func:`read_controller_state` gives it) back before a run resumes; an empty ``values``
    leaves the controller as its ``reset`` left it. ControllerStateError if the controller
    keeps no such state or ``values`` has the wrong size."""
    values = np.asarray(values, dtype=float).ravel()
    if values.size == 0:
        return
    name = controller_name(plan.controller) if plan.controller is not None else "Table I"
    if plan.kind == "compiled":
        n = plan.controller.initial_state.size
        if values.size != n:
            raise ControllerStateError(
                f"controller_state has {values.size} values; controller {name} keeps {n}"
            )
        plan.block.state[:n] = values
        return
    if plan.kind == "python" and callable(getattr(plan.controller, "set_state", None)):
        plan.controller.set_state(values.copy())
        return
    raise ControllerStateError(
        f"controller_state has {values.size} values, but controller {name} keeps no "
        "state of its own that scoutsim can set (the built-in law: leg_states; a Python "
        "controller: set_state(values), scoutsim.control.protocol)"
    )


def _torque(v) -> float | None:
    """``v`` as a hip torque [N m] if it is a finite real number (not a bool or a string)."""
    if type(v) is float or type(v) is np.float64:
        return float(v) if math.isfinite(v) else None
    if isinstance(v, bool) or not isinstance(v, numbers.Real):
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def torques(returned) -> tuple[float, float] | None:
    """The two hip torques (back, front) [N m] a controller returned, or None if it
    returned anything but two finite numbers."""
    if isinstance(returned, np.ndarray):
        if returned.shape != (2,):
            return None
    elif not isinstance(returned, (tuple, list)) or len(returned) != 2:
        return None
    a, b = returned
    a, b = _torque(a), _torque(b)
    return None if a is None or b is None else (a, b)


#: the ctypes form of :data:`scoutsim.control.compiled.CONTROLLER_SIGNATURE`
_CALLBACK = ctypes.CFUNCTYPE(
    ctypes.c_int64,
    ctypes.c_double,
    ctypes.c_void_p,
    ctypes.c_void_p,
    ctypes.c_int64,
    ctypes.c_void_p,
    ctypes.c_int64,
    ctypes.c_void_p,
    ctypes.c_void_p,
)


class PythonBridge:
    """A Python controller as a controller function the compiled loop can call.

    At each sample the loop writes the readings into ``block.y`` and calls the bridge's
    ``ctypes`` callback (:attr:`address`); the bridge gives the controller a copy as
    :class:`~scoutsim.control.sensors.Sensors`, checks what ``command`` returns, writes the
    torques into the loop's command array ``cmd`` and the controller's ``leg_states`` (if
    any) into ``ls``. If ``command`` raises or returns anything but two finite numbers, the
    bridge keeps ``failure`` = (sample, returned, exception) and tells the loop to stop; a
    KeyboardInterrupt sets ``interrupted``.
    """

    def __init__(self, controller, block: ControlBlock, cmd: np.ndarray, ls: np.ndarray, dt: float):
        self.controller = controller
        self._command = controller.command
        self._y, self._cmd, self._ls, self._dt = block.y, cmd, ls, dt
        self.failure = None
        self.interrupted = False
        self._cb = _CALLBACK(self._call)
        self.address = ctypes.cast(self._cb, ctypes.c_void_p).value
        block.ints[L.CB_ADDRESS] = self.address

    def _call(self, t, y, params, n_params, state, n_state, torque, leg_states):
        try:
            returned = self._command(t, Sensors.from_vector(self._y))
            tau = torques(returned)
            if tau is None:
                self.failure = (int(round(t / self._dt)), returned, None)
                return 1
            self._cmd[0], self._cmd[1] = tau
            states = getattr(self.controller, "leg_states", None)
            if states is not None:
                self._ls[:] = states
            return 0
        except KeyboardInterrupt:
            self.interrupted = True
            return 2
        except BaseException as exc:  # noqa: BLE001 - raised by simulate as ControllerError
            self.failure = (int(round(t / self._dt)), None, exc)
            return 1
