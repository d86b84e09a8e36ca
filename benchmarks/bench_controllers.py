"""How fast each kind of controller runs, and what writing one costs in compile time.

    python benchmarks/bench_controllers.py [--runs 7] [--duration 10] [--no-core]

In one process, alternating, ``--runs`` runs each of ``--duration`` s of Model II (the
default integrator, default start and floor) under

* the built-in Table I controller (compiled into the loop),
* the compiled user example (``examples/compiled_controller.py``: a bounding controller
  written from scratch as a Numba function and wrapped in ``CompiledController``; with its
  pitch-rate gain at 0 it makes the same run as Table I, bit for bit, which is checked),
* a trivial Python PD controller (a Python object with ``command(t, sensors)``, called from
  the compiled loop at every sample);
* a learned policy (``PolicyController``) of Stable-Baselines3's default size: set-point
  actions, ``MlpPolicy`` 64-64 tanh, VecNormalize statistics, evaluated every 10 ms, the
  Table I law at every sample (random weights with a small output layer, so that it
  bounds for the whole run, as a trained set-point policy does);

and prints each one's median wall time, real-time factor and ratio to the built-in
controller (targets: compiled example <= 1.3x; Python PD real-time factor >= 50; learned
policy real-time factor >= 0.5 x the built-in's, i.e. <= 2x its wall time).

Then, each in a new process: the compile time of a fresh edit of the example controller
(its source changed, so nothing of it is cached) with the core's cache warm, and, unless
``--no-core``, the compile time of the simulator core itself (an empty Numba cache: what
any edit of the core costs). Asserts nothing.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))


class PythonPD:
    """A trivial Python controller: hip servos to the Table I touchdown angles."""

    control_period = 1e-3

    def command(self, t, sensors):
        a, r = sensors.hip_angle, sensors.hip_rate
        return (250.0 * (0.33 - a[0]) - 5.0 * r[0], 250.0 * (0.37 - a[1]) - 5.0 * r[1])


def learned_policy():
    """A set-point policy of Stable-Baselines3's default MlpPolicy size (64-64 tanh) with
    VecNormalize statistics; seeded random weights, the output layer small (the Table I
    set-points, moved by a few mrad)."""
    from scoutsim.control.bounding import SCHEDULABLE
    from scoutsim.control.policy import PolicyAction, PolicyController, PolicyObservation
    from scoutsim.control.sensors import N_SENSORS
    from scoutsim.parameters import ControllerParameters

    rng = np.random.default_rng(0)
    widths = [N_SENSORS, 64, 64, 4]
    layers = [
        (rng.normal(size=(o, i)) / np.sqrt(i) * (0.01 if o == 4 else 1.0), np.zeros(o))
        for i, o in zip(widths[:-1], widths[1:])
    ]
    table_i = ControllerParameters()
    high = np.full(N_SENSORS, 1e3, dtype=np.float32)
    return PolicyController(
        layers,
        PolicyObservation(
            low=-high,
            high=high,
            mean=rng.normal(size=N_SENSORS),
            var=rng.uniform(0.5, 2.0, size=N_SENSORS),
        ),
        PolicyAction(
            type="setpoints",
            center=[getattr(table_i, name) for name in SCHEDULABLE],
            half_width=np.full(4, 0.44),
        ),
    )


def speeds(runs: int, duration: float):
    from compiled_controller import make_controller

    import scoutsim

    scoutsim.simulation.simulator.warm_up()
    example = make_controller()
    kinds = {
        "built-in Table I (compiled)": None,
        "compiled user example": example,
        "trivial Python PD": PythonPD(),
        "learned policy (64-64, set-points)": learned_policy(),
    }
    ref = scoutsim.simulate(duration=duration)
    same = scoutsim.simulate(controller=example, duration=duration)
    print(
        f"compiled example's run == built-in run, bit for bit: "
        f"{np.array_equal(ref.state, same.state)}"
    )
    for c in kinds.values():  # warm every path once
        scoutsim.simulate(controller=c, duration=0.1)
    walls = {k: [] for k in kinds}
    t_end = {}
    outcome = {}
    for _ in range(runs):
        for name, c in kinds.items():
            t0 = time.perf_counter()
            r = scoutsim.simulate(controller=c, duration=duration)
            walls[name].append(time.perf_counter() - t0)
            t_end[name] = r.t_end
            outcome[name] = r.outcome
    base = statistics.median(walls["built-in Table I (compiled)"])
    print(f"\n{duration:g} s of Model II, median of {runs} alternating runs:")
    print(
        f"{'controller':36s} {'wall [ms]':>10s} {'min-max':>15s} {'RTF':>6s} {'x built-in':>10s} "
        "outcome"
    )
    for name, w in walls.items():
        med = statistics.median(w)
        print(
            f"{name:36s} {med * 1e3:10.1f} {min(w) * 1e3:7.1f}-{max(w) * 1e3:<7.1f} "
            f"{t_end[name] / med:6.0f} {med / base:10.2f} {outcome[name]}"
        )


EDIT = textwrap.dedent("""
    import time, sys
    sys.path.insert(0, {examples!r})
    import scoutsim
    scoutsim.simulation.simulator.warm_up()
    import compiled_controller as ex
    src = open(ex.__file__).read().replace("return 0\\n", "return 0  # edited {stamp}\\n", 1)
    ns = {{"__name__": "edited_{stamp}"}}
    exec(compile(src, "edited_{stamp}.py", "exec"), ns)
    t0 = time.perf_counter()
    c = ns["make_controller"]()
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    r = scoutsim.simulate(controller=c, duration=1.0)
    print(compile_s, time.perf_counter() - t0, r.outcome)
""")

CORE = textwrap.dedent("""
    import time
    t0 = time.perf_counter()
    import scoutsim
    from scoutsim._numba.jit import core_is_compiled
    assert not core_is_compiled()
    t1 = time.perf_counter()
    scoutsim.simulation.simulator.warm_up()
    print(t1 - t0, time.perf_counter() - t1)
""")


def compile_times(core: bool):
    stamp = str(time.time_ns())
    out = subprocess.run(
        [sys.executable, "-c", EDIT.format(examples=str(ROOT / "examples"), stamp=stamp)],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    ).stdout.split()
    print(
        f"\nfresh edit of the example controller (core cache warm, new process): compiled "
        f"in {float(out[0]):.2f} s; its first 1 s run then took {float(out[1]):.3f} s "
        f"({out[2]})"
    )
    if not core:
        return
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        t0 = time.perf_counter()
        out = subprocess.run(
            [sys.executable, "-c", CORE],
            capture_output=True,
            text=True,
            check=True,
            cwd=ROOT,
            env=env,
        ).stdout.split()
        total = time.perf_counter() - t0
    print(
        f"the simulator core with an empty cache (new process; what an edit of the core "
        f"costs): import {float(out[0]):.1f} s, compile {float(out[1]):.1f} s, "
        f"{total:.1f} s in all"
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--duration", type=float, default=10.0, help="simulated time [s]")
    ap.add_argument("--no-core", action="store_true", help="skip the core's compile time")
    args = ap.parse_args(argv)
    speeds(args.runs, args.duration)
    compile_times(not args.no_core)


if __name__ == "__main__":
    main()
