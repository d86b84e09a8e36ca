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
3. The floor the right-hand side's derivative sets under parts 1 and 2: one evaluation
   (``evaluate_ws``) and the derivative for m columns (``evaluate_t``) timed per call at
   one Model II state (2.6 s into the default run), times the derivative calls the runs
   of parts 1 and 2 make (their accepted steps times the stages whose derivative a step
   takes: 6 for DOPRI5 and ARK4, 4 for ARK3; the step's end's projection, the stages'
   evaluations again, the events and samples not counted): what carrying the columns
   costs at the least with the derivative as it is, against the targets. Every time of
   this part (also its own plain runs, stride and forward-difference Jacobian) is the
   shortest of its repeats, so that a busy machine does not lower the floor.
4. Plain runs no slower: the plain 10 s run of this checkout against an earlier commit is
   ``benchmarks/bench_inprocess.py --base COMMIT`` (a run carries no sensitivities unless
   asked: the same compiled loop skips them).
5. The hip-unit identification's exact Jacobian (``Residuals.jacobian``: the six Model II
   hip parameters, both rigs of ``scoutsim identify --example``, at Table II) against
   one evaluation of its residuals (both rigs replayed); forward differences cost six
   evaluations more than the residuals they difference.

Medians of ``--repeats`` timings (but part 3's), after one warm-up. Prints the machine. Asserts nothing.
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
from numba import njit  # noqa: E402

from scoutsim._core.model.derivative.evaluate import derivative_workspace, evaluate_t  # noqa: E402
from scoutsim._core.model.evaluate import evaluate_ws  # noqa: E402
from scoutsim._core.model.layout import NAUX, NMF, NS  # noqa: E402
from scoutsim._core.numerics.dopri5 import eval_workspace  # noqa: E402
from scoutsim._core.numerics.stats import S_NSTEP  # noqa: E402
from scoutsim._core.numerics.stepper import METHOD_ARK3  # noqa: E402
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


@njit
def _evaluations(n, s, P, mi, mf, cmd, ds, aux, ew):
    for _ in range(n):
        evaluate_ws(s, P, mi, mf, cmd, ds, aux, ew, False, ew[3], False)


@njit
def _derivatives(n, P, mi, cmd, ew, dw, tangents, out):
    for _ in range(n):
        evaluate_t(P, mi, cmd, ew, dw, tangents, out)


def _per_call(f, n: int, repeats: int = 7) -> float:
    """The shortest time [s] of one call of ``f(n)`` over ``repeats``, per iteration."""
    f(1)
    return min(_timed(lambda: f(n)) for _ in range(repeats)) / n


def _timed(f) -> float:
    t = time.perf_counter()
    f()
    return time.perf_counter() - t


def _derivative_calls(eng) -> int:
    """The right-hand side's derivatives the flow takes over the run of ``eng`` so far:
    its accepted steps times the stages (6 for DOPRI5 and ARK4, 4 for ARK3)."""
    stages = 4 if eng._method == METHOD_ARK3 else 6
    return int(eng.stats[S_NSTEP]) * stages


def derivative_floor(columns, stride, plain_10s, repeats) -> None:
    """Part 3 (module docstring). ``stride`` = (StrideMap, orbit, the stride at the orbit
    (a Crossing)); ``plain_10s``: a function running 10 s of Model II."""
    smap, orbit, base = stride
    n_z, samples = orbit.z.size, base.samples
    t_plain = min(_timed(plain_10s) for _ in range(repeats))
    t_stride_plain = min(_timed(lambda: smap.crossing(orbit.state)) for _ in range(repeats))
    t_fd = min(
        _timed(lambda: difference_jacobian(smap, orbit.z, orbit.state, base, 1e-6, 1))
        for _ in range(repeats)
    )
    e = start_engine(None, 10.0, model="II")
    e.advance(2_601)
    s, P, mi, mf, cmd = e.s.copy(), e.P, e.mi.copy(), e.mf.copy(), e.cmd.copy()
    ew, ds, aux = eval_workspace(), np.zeros(NS), np.zeros(NAUX)
    n = 100_000
    t_eval = _per_call(lambda k: _evaluations(k, s, P, mi, mf, cmd, ds, aux, ew), n, repeats)
    rng = np.random.default_rng(0)
    t_der = {}
    for m in sorted({1, *columns, n_z}):
        tangents = (
            rng.standard_normal((NS, m)),
            np.zeros((NMF, m)),
            np.zeros((2, m)),
            np.zeros((m, len(P))),
        )
        dw, out = derivative_workspace(m), np.zeros((NS, m))
        t_der[m] = _per_call(
            lambda k, dw=dw, tangents=tangents, out=out: _derivatives(
                k, P, mi, cmd, ew, dw, tangents, out
            ),
            n,
            repeats,
        )
    print("\n3. the floor the right-hand side's derivative sets (one Model II state, per call)")
    print(f"   evaluation             {t_eval * 1e9:8.0f} ns")
    for m, t in t_der.items():
        print(f"   derivative, {m:2d} column{'s' if m > 1 else ' '} {t * 1e9:7.0f} ns")
    run = start_engine(None, 10.0, model="II")
    run.advance(10_001)
    calls = _derivative_calls(run)
    print(f"   10 s of Model II: {calls} derivative calls, the plain run {t_plain * 1e3:.1f} ms")
    for k in columns:
        floor = 1 + calls * t_der[k] / t_plain
        print(
            f"   {k:2d} parameters: at least {floor:5.1f} plain runs   (target <= {1 + k / 4:.1f})"
        )
    eng = smap.engine(orbit.state, smap.max_period)
    eng.advance(samples)
    calls = _derivative_calls(eng)
    floor = (t_stride_plain + calls * t_der[n_z]) / t_fd
    print(
        f"   the stride: {calls} derivative calls, the plain stride {t_stride_plain * 1e3:.1f} ms, "
        f"forward differences {t_fd * 1e3:.1f} ms"
    )
    print(f"   the exact Jacobian: at least {floor:.2f} x differences   (target <= 0.5)")


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
    derivative_floor(args.columns, (m, orbit, base), lambda: run(0), args.repeats)
    print("\n4. plain runs against an earlier commit: benchmarks/bench_inprocess.py --base COMMIT")

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
    print(f"\n5. the identification's exact Jacobian ({len(names)} hip parameters, two rigs)")
    print(f"   residuals              {t_r * 1e3:8.1f} ms")
    print(
        f"   exact Jacobian         {t_j * 1e3:8.1f} ms   {t_j / t_r:6.1f} residual evaluations"
        f"   (forward differences: {len(names)})"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
