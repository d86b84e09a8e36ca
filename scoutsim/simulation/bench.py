"""The hybrid model on a bench: :func:`run_bench` runs the engine with the rig options a
hip-unit identification needs (:mod:`scoutsim.identification.rigs`)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .._version import __version__
from ..control.block import control_block
from ..control.bounding import SCHEDULABLE, controller_array
from ..control.sensors import SensorParameters
from .._core.model import layout as L
from .._core.model.packing import robot_array
from ..parameters import ControllerParameters, RobotParameters
from ..result.simulation_result import SimulationResult
from .engine import HybridEngine
from .integrator import IntegratorSettings
from .initial_conditions import fresh_modes

__all__ = ["run_bench", "Bench"]


@dataclass(frozen=True)
class Bench:
    """How the robot is mounted and wired on the bench (:func:`run_bench`).

    clamp_torso : the torso is held at rest (extra constraint rows of the KKT system).
    clamp_legs : the legs are held at their angles relative to the torso too (a stall
        test; needs ``clamp_torso``).
    motor_circuit : "amplifier" (the current amplifier), "open" or "short" (the motor
        leads open or shorted: no amplifier).
    """

    clamp_torso: bool = False
    clamp_legs: bool = False
    motor_circuit: str = "amplifier"


def run_bench(robot: RobotParameters, model: str, start_state, duration: float, *,
              bench: Bench = Bench(), controller: ControllerParameters | None = None,
              held_torques=None, schedule=None, dt: float = 1e-3,
              integrator: IntegratorSettings | None = None,
              provenance: dict | None = None) -> SimulationResult:
    """Run the hybrid model on a bench: the engine of :func:`~scoutsim.simulation.simulator.simulate` with the rig options
    a hip-unit identification needs (:mod:`scoutsim.identification.rigs`).

    Parameters
    ----------
    robot, model : as for :func:`~scoutsim.simulation.simulator.simulate`.
    start_state : (16,) state vector (layout ``STATE_NAMES``, SI); the modes are derived
        from it (no toe in contact; Model II joints stuck unless their gear turns).
    duration : simulated time [s]; dt : control / sample period [s].
    bench : :class:`Bench`: the clamps and the motor circuit (default: free, amplifier).
    controller : ControllerParameters: the compiled Table I law sets the commands; None:
        ``held_torques`` (back, front) [N m per physical leg, at the leg] are held for the
        whole run (zero if not given).
    schedule : optional list of (k, {field: value}): from control sample k on, the
        controller's set-points ``field`` (a key of ``control.bounding.SCHEDULABLE``:
        touchdown angles, sweep limits) [rad] take these values.
    integrator : IntegratorSettings (default: the reference, DOPRI5).
    """
    P = robot_array(robot, model, clamp_torso=bench.clamp_torso, clamp_legs=bench.clamp_legs,
                    motor_circuit=bench.motor_circuit)
    C = controller_array(controller, robot)
    s = np.array(start_state, dtype=float)
    mi, mf = fresh_modes(s, P)
    integrator = (integrator or IntegratorSettings(method="dopri5")).resolve(model)
    eng = HybridEngine(P, C, (s, mi, mf, np.zeros(2, dtype=np.int64)), duration, dt,
                       integrator, block=control_block(
                           L.CTRL_BUILTIN if controller is not None else L.CTRL_HELD,
                           geom=SensorParameters().geometry_array(
                               robot, controller is not None and controller.sense_motor_angle)))
    if held_torques is not None:
        eng.cmd[:] = held_torques
    chunk = max(1, int(round(1.0 / dt)))
    sched = sorted(schedule or [], key=lambda e: e[0])
    for _, changes in sched:
        for field in changes:
            if field not in SCHEDULABLE:
                raise ValueError(f"schedule field {field!r} is not allowed: must be one of "
                                 f"{sorted(SCHEDULABLE)}")
    si = 0
    while eng.running:
        while si < len(sched) and sched[si][0] <= eng.k:
            for field, value in sched[si][1].items():
                eng.C[SCHEDULABLE[field]] = value
            si += 1
        k_stop = eng.k + chunk
        if si < len(sched):
            k_stop = min(k_stop, int(sched[si][0]))
        eng.advance(k_stop)
    return eng.result(dict(provenance or {}, model=model, robot=asdict(robot),
                           control_period_s=dt, integrator=asdict(integrator),
                           scoutsim_version=__version__, duration_s=duration))
