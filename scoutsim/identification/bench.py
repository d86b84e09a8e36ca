"""The hybrid model on a bench: :func:`run_bench` runs the engine of a run
(:func:`scoutsim.simulation.assembly.assemble`) with the rig options a hip-unit
identification needs (:mod:`scoutsim.identification.rigs`): the clamps and the motor
circuit (:class:`Bench`), held torques or a schedule of the Table I set-points."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from .._version import __version__
from ..control.bounding import SCHEDULABLE
from ..parameters import ControllerParameters, RobotParameters
from ..result.simulation_result import SimulationResult
from ..simulation.assembly import Bench, PlantOptions, assemble, bench_plan
from ..simulation.engine import HybridEngine
from ..simulation.integrator import IntegratorSettings
from ..simulation.sample_derivatives import SampleDerivatives

__all__ = ["run_bench", "Bench"]


def run_bench(
    robot: RobotParameters,
    model: str,
    start_state,
    duration: float,
    *,
    bench: Bench | None = None,
    controller: ControllerParameters | None = None,
    held_torques=None,
    schedule=None,
    dt: float = 1e-3,
    integrator: IntegratorSettings | None = None,
    provenance: dict | None = None,
    derivatives: SampleDerivatives | None = None,
) -> SimulationResult:
    """Run the hybrid model on a bench: the engine of
    :func:`~scoutsim.simulation.simulator.simulate` with the rig options a hip-unit
    identification needs (:mod:`scoutsim.identification.rigs`).

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
    derivatives : a :class:`~scoutsim.simulation.sample_derivatives.SampleDerivatives` to fill: the run carries the derivatives of
        its state with respect to those robot fields and records, sample by sample, those
        of the driven-gear angles and the motor currents (the run itself is unchanged).
    """
    integrator = integrator or IntegratorSettings(method="dopri5")

    def engine(rob):
        setup = assemble(
            rob,
            model,
            np.asarray(start_state, dtype=float),
            bench_plan(rob, model, controller),
            plant=PlantOptions(bench=bench or Bench()),
            integrator=integrator,
            control_period=dt,
        )
        eng = HybridEngine.assembled(setup, duration)
        if held_torques is not None:
            eng.cmd[:] = held_torques
        return eng, setup.integrator

    eng, integrator = engine(robot)
    if derivatives is not None:
        derivatives.start(eng, robot, engine)
    chunk = 1 if derivatives is not None else max(1, int(round(1.0 / dt)))
    sched = sorted(schedule or [], key=lambda e: e[0])
    for _, changes in sched:
        for field in changes:
            if field not in SCHEDULABLE:
                raise ValueError(
                    f"schedule field {field!r} is not allowed: must be one of {sorted(SCHEDULABLE)}"
                )
    si = 0
    while eng.running:
        while si < len(sched) and sched[si][0] <= eng.k:
            eng.retune(**sched[si][1])
            si += 1
        k_stop = eng.k + chunk
        if si < len(sched):
            k_stop = min(k_stop, int(sched[si][0]))
        eng.advance(k_stop)
        if derivatives is not None:
            derivatives.record(eng)
    if derivatives is not None:
        derivatives.finish(eng)
    return eng.result(
        dict(
            provenance or {},
            model=model,
            robot=asdict(robot),
            control_period_s=dt,
            integrator=asdict(integrator),
            scoutsim_version=__version__,
            duration_s=duration,
        )
    )
