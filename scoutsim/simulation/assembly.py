"""A run put together: the robot packed for the compiled core, the floor and the fall
limit, the start state and its modes, the controller's arrays and the integrator, in one
place (:func:`assemble`) for every caller that runs the hybrid model:
:func:`~scoutsim.simulation.simulator.simulate`, :func:`~scoutsim.simulation.engine.start_engine`
(the learning environment) and the identification bench (:mod:`scoutsim.identification.bench`).

The plant beyond the robot is one bundle, :class:`PlantOptions` (the floor's friction, the
pitch limit that counts as a fall, the massless legs' placement and the bench rig's clamps
and motor circuit, :class:`Bench`); the pitch limit is checked there, in degrees as the
user gives it, and converted to radians for the core there only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._core.model import layout as L
from .._core.model.hip_unit import NAMES as HIP_UNIT_NAMES
from .._core.model.hip_unit import hip_unit_code
from .._core.model.packing import robot_array
from ..control.block import control_block
from ..control.bounding import controller_array
from ..control.dispatch import ControllerPlan, plan_controller
from ..control.sensors import SensorParameters
from ..parameters import ControllerParameters, Environment, RobotParameters
from ..state import HybridState, InitialState
from .initial_conditions import (
    default_initial_state,
    fresh_modes,
    initial_state_vector,
    resumed_modes,
)
from .integrator import IntegratorSettings

__all__ = [
    "assemble",
    "RunSetup",
    "PlantOptions",
    "Bench",
    "bench_plan",
    "DEFAULT_PITCH_LIMIT_DEG",
    "PITCH_LIMIT_RANGE_DEG",
]

#: |pitch| [deg] that counts as a fall unless a run says otherwise (docs/specification.md
#: section 3)
DEFAULT_PITCH_LIMIT_DEG = 60.0
#: the open interval [deg] a pitch limit must lie in: a torso past 90 deg is upside down
PITCH_LIMIT_RANGE_DEG = (0.0, 90.0)


@dataclass(frozen=True)
class Bench:
    """How the robot is mounted and wired on the bench (the identification rigs,
    :mod:`scoutsim.identification.rigs`; docs/identification.md).

    clamp_torso : the torso is held at rest (extra constraint rows of the KKT system).
    clamp_legs : the legs are held at their angles relative to the torso too (a stall
        test; needs ``clamp_torso``).
    motor_circuit : "amplifier" (the current amplifier), "open" or "short" (the motor
        leads open or shorted: no amplifier).
    """

    clamp_torso: bool = False
    clamp_legs: bool = False
    motor_circuit: str = "amplifier"


@dataclass(frozen=True)
class PlantOptions:
    """The plant beyond the robot (keywords of :func:`~scoutsim.simulation.simulator.simulate`
    but ``bench``).

    friction_coefficient : Coulomb coefficient of the toe (``inf`` = no slip); None = the
        default floor for the robot (:meth:`~scoutsim.parameters.Environment.friction_for`).
    pitch_limit_deg : |pitch| [deg] that counts as a fall, in (0, 90)
        (:data:`PITCH_LIMIT_RANGE_DEG`; docs/specification.md section 3).
    passive_touchdown_angles : (back, front) [rad], massless legs only: where the legs are
        placed in flight.
    passive_touchdown_world : massless legs only: those angles from the world vertical
        (True) or relative to the torso (False).
    bench : the bench rig's clamps and motor circuit (default: free, amplifier).
    """

    friction_coefficient: float | None = None
    pitch_limit_deg: float = DEFAULT_PITCH_LIMIT_DEG
    passive_touchdown_angles: tuple = (0.0, 0.0)
    passive_touchdown_world: bool = True
    bench: Bench = field(default_factory=Bench)

    def __post_init__(self):
        lo, hi = PITCH_LIMIT_RANGE_DEG
        v = self.pitch_limit_deg
        if isinstance(v, bool) or not (isinstance(v, (int, float, np.floating)) and lo < v < hi):
            raise ValueError(
                f"pitch_limit_deg = {v!r} is not allowed: must be a number of "
                f"degrees in ({lo:g}, {hi:g})"
            )

    @property
    def pitch_limit(self) -> float:
        """The pitch limit [rad], as the compiled core takes it."""
        return math.radians(self.pitch_limit_deg)


@dataclass(frozen=True)
class RunSetup:
    """An assembled run (:func:`assemble`), ready for an engine
    (:meth:`HybridEngine.assembled <scoutsim.simulation.engine.HybridEngine.assembled>`).

    P : the packed robot, floor, fall limit and bench options (the core's parameter array).
    plan : the controller's plan (:class:`~scoutsim.control.dispatch.ControllerPlan`: the
        Table I array ``C``, the control block, the control period).
    start : (s, mi, mf, ls): the state, the plant's modes and the controller's leg states
        the run starts from (the engine advances them in place).
    control_period : [s].
    integrator : the resolved :class:`~scoutsim.simulation.integrator.IntegratorSettings`.
    hip_unit : the name of the hip unit the robot runs on in this model (its registry).
    """

    P: np.ndarray
    plan: ControllerPlan
    start: tuple
    control_period: float
    integrator: IntegratorSettings
    hip_unit: str


def bench_plan(
    robot: RobotParameters, model: str, controller: ControllerParameters | None
) -> ControllerPlan:
    """The control of a bench run: the compiled Table I law with ideal sensors, or
    (``controller`` None) no controller: the hip torques are held as the caller sets them
    (``engine.cmd``), the hip encoders read the legs."""
    if controller is not None:
        return plan_controller(controller, model, robot)
    block = control_block(L.CTRL_HELD, geom=SensorParameters().geometry_array(robot, False))
    return ControllerPlan(
        kind="none",
        controller=None,
        parameters=None,
        control_period=ControllerParameters().control_period,
        C=controller_array(None),
        block=block,
        label="held",
    )


def _start(
    start,
    model: str,
    robot: RobotParameters,
    plan: ControllerPlan,
    plant: PlantOptions,
    P: np.ndarray,
) -> tuple:
    """(s, mi, mf, ls) of a run from ``start`` (see :func:`assemble`)."""
    if start is None:
        start = default_initial_state(model, robot, plant.passive_touchdown_angles)
    if isinstance(start, HybridState):
        s = np.array(start.state)
        mi, mf, ls = resumed_modes(start)
        return s, mi, mf, ls
    if isinstance(start, InitialState):
        ctrl = (
            None
            if model == "passive"
            else (plan.parameters if plan.parameters is not None else ControllerParameters())
        )
        s = initial_state_vector(
            start, robot, ctrl, plant.passive_touchdown_angles, plant.passive_touchdown_world
        )
    elif isinstance(start, np.ndarray):
        s = np.array(start, dtype=float)
    else:
        raise TypeError(
            "initial_state must be an InitialState, a HybridState, a state "
            f"vector or None, not {type(start).__name__}"
        )
    mi, mf = fresh_modes(s, P)
    return s, mi, mf, np.zeros(2, dtype=np.int64)


def assemble(
    robot: RobotParameters,
    model: str,
    start,
    plan: ControllerPlan,
    *,
    plant: PlantOptions = PlantOptions(),
    integrator: IntegratorSettings | None = None,
    hold_commands: bool = False,
    control_period: float | None = None,
) -> RunSetup:
    """Put a run together (its callers check the robot and the controller's parameters).

    Parameters
    ----------
    robot : RobotParameters (validated).
    model : "ideal", "I", "II" or "passive".
    start : InitialState (a start in flight, the legs at ``plan``'s touchdown angles unless
        it sets them), HybridState (a run resumed with its modes), a state vector (layout
        ``STATE_NAMES``, SI; a start in flight, the modes derived from it) or None (the
        model's default start,
        :func:`~scoutsim.simulation.initial_conditions.default_initial_state`).
    plan : how the run is controlled (:func:`~scoutsim.control.dispatch.plan_controller`,
        :func:`bench_plan`).
    plant : the floor, the fall limit, the massless legs' placement, the bench rig.
    integrator : IntegratorSettings (default ``IntegratorSettings()``), resolved for
        ``model``.
    hold_commands : no controller runs: the hip torques ``engine.cmd`` are held as the
        caller sets them.
    control_period : [s]; None: the plan's.
    """
    mu = Environment(friction_coefficient=plant.friction_coefficient).friction_for(robot)
    bench = plant.bench
    P = robot_array(
        robot,
        model,
        friction_coefficient=mu,
        passive_touchdown_angles=plant.passive_touchdown_angles,
        passive_touchdown_world=plant.passive_touchdown_world,
        pitch_limit=plant.pitch_limit,
        clamp_torso=bench.clamp_torso,
        clamp_legs=bench.clamp_legs,
        motor_circuit=bench.motor_circuit,
    )
    if hold_commands:
        plan.block.ints[L.CB_KIND] = L.CTRL_HELD
    return RunSetup(
        P=P,
        plan=plan,
        start=_start(start, model, robot, plan, plant, P),
        control_period=plan.control_period if control_period is None else float(control_period),
        integrator=(integrator or IntegratorSettings()).resolve(model),
        hip_unit=HIP_UNIT_NAMES[hip_unit_code(model, robot)],
    )
