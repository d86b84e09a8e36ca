"""What the derivatives carried with a run cost, against what they replace, in one run.

    python benchmarks/bench_jacobian.py [--repeats 5] [--columns 4 8 16]

1. The stride map's Jacobian at the default Model II orbit (Table I, the orbit's
   integrator: DOPRI5 at rtol 1e-11): carried with one run of the stride
   (``StrideMap.crossing(exact=True)``) against forward differences of whole strides
   (``difference_jacobian``: one stride per coordinate). Target: exact <= 0.5 x differences.
2. Sensitivities along a 10 s run of Model II (default start, floor and integrator) with
   the sensitivities to n robot parameters carried (``HybridEngine.carry_sensitivities``
   with parameter rows: leg and belt springs and dampers, motor constants, the current
   limit, the battery, the masses), against the plain run. Target: <= 1 + n / 4 plain
   runs.
3. Plain runs no slower: the plain 10 s run of this checkout against an earlier commit is
   ``benchmarks/bench_inprocess.py --base COMMIT`` (a run carries no sensitivities unless
   asked: the same compiled loop skips them).
4. The hip-unit identification's exact Jacobian (``Residuals.jacobian``: the six Model II
   hip parameters, both rigs of ``scoutsim identify --example``, at Table II) against
   one evaluation of its residuals (both rigs replayed); forward differences cost six
   evaluations more than the residuals they difference.

Medians of ``--repeats`` timings, after one warm-up. Prints the machine. Asserts nothing.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine  # noqa: E402

from scoutsim.analysis.controlled_orbit import controlled_fixed_point, difference_jacobian  # noqa: E402
from scoutsim.analysis.stride_map import StrideMap  # noqa: E402
from scoutsim.simulation.engine import start_engine  # noqa: E402
from scoutsim.simulation.parameter_rows import robot_parameter_derivatives  # noqa: E402


def _median(f, repeats: int) -> float:
    f()
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


#: the robot parameters whose sensitivities part 2 carries, in this order
PARAMETERS = (
    "leg_stiffness",
    "leg_damping",
    "belt_stiffness",
    "belt_damping",
    "torque_constant",
    "speed_constant",
    "armature_resistance",
    "current_limit",
    "battery_voltage",
    "torso_mass",
    "torso_inertia",
    "leg_mass",
    "leg_inertia",
    "gearbox_efficiency",
    "planetary_ratio",
    "hip_spacing",
)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--columns", type=int, nargs="+", default=[4, 8, 16])
    args = ap.parse_args()
    print(f"machine: {machine()}")

    orbit = controlled_fixed_point(settle_duration=8.0)
    m = StrideMap(integrator=orbit.setting["integrator"])
    base = m.crossing(orbit.state)
    n = orbit.z.size
    t_exact = _median(lambda: m.crossing(orbit.state, exact=True), args.repeats)
    t_fd = _median(
        lambda: difference_jacobian(m, orbit.z, orbit.state, base, 1e-6, 1), args.repeats
    )
    print(f"\n1. stride-map Jacobian at the default Model II orbit ({n} coordinates)")
    print(f"   carried with the run   {t_exact * 1e3:8.1f} ms")
    print(f"   forward differences    {t_fd * 1e3:8.1f} ms")
    print(f"   ratio exact / fd       {t_exact / t_fd:8.2f}   (target <= 0.5)")

    derivatives = robot_parameter_derivatives(PARAMETERS[: max(args.columns)], model="II")

    def run(columns: int):
        e = start_engine(None, 10.0, model="II")
        if columns:
            nx = e.sensitivities.shape[0]
            seed = np.zeros((nx + columns, columns))
            seed[nx:, :] = np.eye(columns)
            e.carry_sensitivities(seed, tuple(d[:columns] for d in derivatives))
        e.advance(10_001)

    t_plain = _median(lambda: run(0), args.repeats)
    print("\n2. sensitivities along 10 s of Model II (default integrator)")
    print(f"   plain run              {t_plain * 1e3:8.1f} ms")
    for k in args.columns:
        t = _median(lambda k=k: run(k), max(1, args.repeats // 2))
        print(
            f"   {k:2d} parameters          {t * 1e3:8.1f} ms   {t / t_plain:6.1f} plain runs"
            f"   (target <= {1 + k / 4:.1f})"
        )
    print("\n3. plain runs against an earlier commit: benchmarks/bench_inprocess.py --base COMMIT")

    from scoutsim.identification.example import example_logs
    from scoutsim.identification.fit import fitted_names
    from scoutsim.identification.residuals import Residuals
    from scoutsim.identification.rig_data import prepare_logs
    from scoutsim.parameters import RobotParameters

    robot = RobotParameters()
    data = prepare_logs(example_logs(), None, robot, None)
    names = fitted_names(None, data)
    res = Residuals(data, robot, names, None)
    x = np.log([float(getattr(robot, n)) for n in names])
    t_r = _median(lambda: res(x), args.repeats)
    t_j = _median(lambda: res.jacobian(x), args.repeats)
    print(f"\n4. the identification's exact Jacobian ({len(names)} hip parameters, two rigs)")
    print(f"   residuals              {t_r * 1e3:8.1f} ms")
    print(
        f"   exact Jacobian         {t_j * 1e3:8.1f} ms   {t_j / t_r:6.1f} residual evaluations"
        f"   (forward differences: {len(names)})"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
