"""Uncertainty-study benchmark: what the study's machinery costs per run, and its
throughput on one and two local workers.

    python benchmarks/bench_uncertainty.py [--samples 16] [--duration 6] [--model II]

In this one run: a plain :func:`scoutsim.simulate` of ``--duration`` s (the median of a
few, warm), then a study of two parameters (``N (d + 2)`` runs of the same duration) with
one worker (in this process, warm) and with two worker processes (a spawn pool started
for the study: its time includes each worker's start-up); prints the study's wall time
per run against the plain run (the overhead of sampling, the sweep task, the checkpoint
and the indices), runs per second on one and two workers, their ratio, and whether the
two studies' indices are identical. No asserts: numbers to read.
"""

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import scoutsim
from scoutsim.analysis.uncertainty import parse_parameter, uncertainty_study

PARAMS = ("controller.touchdown_angle_front_deg=20:22", "robot.leg_stiffness=3300:3700")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=16, help="base sample size N (power of 2)")
    ap.add_argument("--duration", type=float, default=6.0, help="simulated time per run [s]")
    ap.add_argument("--model", default="II", help="model (default II)")
    args = ap.parse_args()
    scoutsim.simulate(model=args.model, duration=0.05)  # (compiled / cache loaded)
    plain = []
    for _ in range(5):
        t0 = time.perf_counter()
        scoutsim.simulate(model=args.model, duration=args.duration)
        plain.append(time.perf_counter() - t0)
    t_plain = statistics.median(plain)
    params = [parse_parameter(p) for p in PARAMS]
    n_runs = args.samples * (len(params) + 2)
    walls, tables = {}, {}
    for workers in (1, 2):
        with tempfile.TemporaryDirectory() as d:
            t0 = time.perf_counter()
            uncertainty_study(
                params,
                n=args.samples,
                model=args.model,
                duration=args.duration,
                workers=workers,
                out=d,
            )
            walls[workers] = time.perf_counter() - t0
            tables[workers] = (Path(d) / "indices.csv").read_bytes()
    per_run = walls[1] / n_runs
    print(
        f"model {args.model}, {args.duration:g} s runs, {len(params)} parameters, "
        f"N = {args.samples}: {n_runs} runs"
    )
    print(f"  plain simulate:            {t_plain * 1e3:8.1f} ms per run (median of 5)")
    print(
        f"  study, 1 worker:           {per_run * 1e3:8.1f} ms per run "
        f"(x{per_run / t_plain:.3f} of a plain run); {n_runs / walls[1]:.2f} runs/s"
    )
    print(
        f"  study, 2 workers (cold):   {walls[2] / n_runs * 1e3:8.1f} ms per run; "
        f"{n_runs / walls[2]:.2f} runs/s, x{walls[1] / walls[2]:.2f} of 1 worker"
    )
    print(f"  indices.csv identical on 1 and 2 workers: {tables[1] == tables[2]}")


if __name__ == "__main__":
    main()
