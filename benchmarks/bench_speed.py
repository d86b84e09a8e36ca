"""Speed benchmark: 10 s of Model II bounding; real-time factor; SciPy baseline.

    python benchmarks/bench_speed.py [--baseline-seconds 0.3]

Measures in one run, on one core:
* first-call compile time (fresh Numba cache in a new process);
* cached start-up: wall time of ``scoutsim run --duration 1`` in a new process;
* wall time of 10 s of Model II bounding (default start, default floor mu = 1.0) with the
  default integrator settings (best of 3) -> real-time factor, and with the DOPRI5
  reference at its default tolerance;
* the same model in plain Python integrated by SciPy solve_ivp (benchmarks/scipy_baseline.py,
  NUMBA_DISABLE_JIT=1), over the first ``--baseline-seconds`` of the same run, and scoutsim
  over the same span -> speed ratio per simulated second.
The targets (docs/explanation/performance.md) are printed next to the measurements; nothing here
asserts.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
MU = 1.0  # the default floor (scoutsim.parameters.DEFAULT_FRICTION_COEFFICIENT)


def sub(cmd, env=None):
    t0 = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True)
    return time.perf_counter() - t0, out.stdout


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline-seconds", type=float, default=0.3)
    args = ap.parse_args()
    import scoutsim

    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        t_compile, _ = sub(
            [sys.executable, "-c", "import scoutsim; scoutsim.simulate(duration=0.01, model='II')"],
            env,
        )
    scoutsim.simulate(duration=0.01, model="II")  # warm the normal cache
    with tempfile.TemporaryDirectory() as out:
        t_start, _ = sub(
            [
                sys.executable,
                "-m",
                "scoutsim",
                "run",
                "--duration",
                "1",
                "--out",
                out,
                "--no-progress",
            ]
        )
    default = scoutsim.IntegratorSettings().resolve("II")
    reference = scoutsim.IntegratorSettings(method="dopri5").resolve("II")

    def best10(integ, n=3):
        walls = []
        for _ in range(n):
            t0 = time.perf_counter()
            res = scoutsim.simulate(
                duration=10.0, model="II", friction_coefficient=MU, integrator=integ
            )
            walls.append(time.perf_counter() - t0)
        return min(walls), res

    w10, r = best10(default)
    w10_ref, r_ref = best10(reference)
    # scoutsim over the baseline span
    span = args.baseline_seconds
    ws = []
    for _ in range(5):
        t0 = time.perf_counter()
        scoutsim.simulate(duration=span, model="II", friction_coefficient=MU)
        ws.append(time.perf_counter() - t0)
    w_span = min(ws)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    # the baseline at the default run's own tolerances (RK45 = the same Dormand-Prince pair)
    _, out = sub(
        [
            sys.executable,
            str(HERE / "scipy_baseline.py"),
            str(span),
            "II",
            str(MU),
            str(default.rtol),
            str(default.atol),
        ],
        env,
    )
    base = json.loads(out.strip().splitlines()[-1])
    rows = [
        ("first-call compile (new process, empty cache)", f"{t_compile:.1f} s", "reported"),
        ("cached start-up: scoutsim run --duration 1", f"{t_start:.2f} s", "< 3 s"),
        (
            f"10 s Model II, default ({default.method} rtol {default.rtol:g}), best of 3",
            f"{w10 * 1000:.0f} ms",
            "<= 50 ms",
        ),
        ("real-time factor", f"{10.0 / w10:.1f}", ">= 200"),
        (
            f"10 s Model II, reference (dopri5 rtol {reference.rtol:g}), best of 3",
            f"{w10_ref * 1000:.0f} ms",
            "",
        ),
        ("default / reference speed ratio", f"{w10_ref / w10:.1f}x", ""),
        (
            f"SciPy solve_ivp (RK45, rtol {default.rtol:g}), {span} s simulated",
            f"{base['wall_s']:.2f} s",
            "",
        ),
        (f"scoutsim, same {span} s", f"{w_span * 1000:.1f} ms", ""),
        ("speed-up over SciPy baseline", f"{base['wall_s'] / w_span:.1f}x", ">= 20x"),
    ]
    print(
        f"scoutsim {scoutsim.__version__}  outcome of the 10 s run: {r.outcome} "
        f"(t_end {r.t_end:.2f} s, {int(r.stats['rhs_evaluations'])} RHS evaluations; "
        f"reference {int(r_ref.stats['rhs_evaluations'])}); mean speed "
        f"{r.summary()['mean_speed_m_s']:.5f} m/s (reference "
        f"{r_ref.summary()['mean_speed_m_s']:.5f})"
    )
    for name, val, target in rows:
        print(f"{name:<52} {val:>12}   target {target}")


if __name__ == "__main__":
    main()
