"""Uncertainty-study benchmark: what the study's machinery costs per run, and its
throughput on one and two local workers.

    python benchmarks/bench_uncertainty.py [--samples 32] [--duration 6] [--model II]

In this one run, warm, in one process:

* a plain :func:`scoutsim.simulate` of ``--duration`` s, and the same run with its summary
  (the gait metrics every study run must measure), medians of 5;
* a study of two parameters with one worker at ``N`` and at ``2 N`` (``N (d + 2)`` runs):
  the difference of their wall times over the difference of their runs is the study's
  cost per run, free of its fixed costs (the bootstrap intervals and writing the tables,
  once per study); what it adds to a measured run (simulate + summary) is the machinery's
  overhead per run (sampling, the sweep task, the checkpoint), printed in percent of the
  plain run; the fixed costs are the rest of the wall time;
* the ``2 N`` study on two worker processes, once with a pool started for the study (its
  start-up included) and once on a pool kept open (as a series of studies runs): runs per
  second against one worker, and whether the ``indices.csv`` are identical.

No asserts: numbers to read.
"""

import argparse
import multiprocessing
import statistics
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import scoutsim
from scoutsim.analysis.uncertainty import parse_parameter, uncertainty_study

PARAMS = ("controller.touchdown_angle_front_deg=20:22", "robot.leg_stiffness=3300:3700")


def median_time(fn, repeat=5) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def study(params, n, args, workers, scheduler=None):
    """(wall time [s], indices.csv bytes) of one study."""
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        uncertainty_study(
            params,
            n=n,
            model=args.model,
            duration=args.duration,
            workers=workers,
            scheduler=scheduler,
            out=d,
        )
        wall = time.perf_counter() - t0
        return wall, (Path(d) / "indices.csv").read_bytes()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=32, help="base sample size N (power of 2)")
    ap.add_argument("--duration", type=float, default=6.0, help="simulated time per run [s]")
    ap.add_argument("--model", default="II", help="model (default II)")
    args = ap.parse_args()
    scoutsim.simulate(model=args.model, duration=0.05)  # (compiled / cache loaded)
    t_plain = median_time(lambda: scoutsim.simulate(model=args.model, duration=args.duration))
    t_measured = median_time(
        lambda: scoutsim.simulate(model=args.model, duration=args.duration).summary()
    )
    params = [parse_parameter(p) for p in PARAMS]
    n1, n2 = args.samples, 2 * args.samples
    runs1, runs2 = n1 * (len(params) + 2), n2 * (len(params) + 2)
    w1, _ = study(params, n1, args, workers=1)
    w2, table_1 = study(params, n2, args, workers=1)
    w2_two, table_2 = study(params, n2, args, workers=2)
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        study(params, 2, args, workers=2, scheduler=pool)  # the workers load scoutsim
        w2_warm, table_3 = study(params, n2, args, workers=2, scheduler=pool)
    per_run = (w2 - w1) / (runs2 - runs1)
    fixed = w2 - per_run * runs2
    print(
        f"model {args.model}, {args.duration:g} s runs, {len(params)} parameters, "
        f"N = {n1} and {n2}: {runs1} and {runs2} runs"
    )
    print(f"  plain simulate:              {t_plain * 1e3:8.1f} ms per run (median of 5)")
    print(f"  simulate + summary:          {t_measured * 1e3:8.1f} ms per run (median of 5)")
    print(f"  study, 1 worker, per run:    {per_run * 1e3:8.1f} ms (marginal, N -> 2 N)")
    print(
        f"  machinery overhead per run:  {(per_run - t_measured) * 1e3:8.1f} ms = "
        f"{100 * (per_run - t_measured) / t_plain:.1f} % of a plain run"
    )
    print(f"  fixed costs per study:       {fixed:8.2f} s (intervals, tables)")
    print(
        f"  2 N on 1 worker:  {runs2 / w2:6.1f} runs/s; on 2 workers (cold pool): "
        f"{runs2 / w2_two:6.1f} runs/s, x{w2 / w2_two:.2f}"
    )
    print(
        f"  2 N on 2 warm workers (a pool kept open): {runs2 / w2_warm:6.1f} runs/s, "
        f"x{w2 / w2_warm:.2f}"
    )
    print(f"  indices.csv identical on 1 and 2 workers: {table_1 == table_2 == table_3}")


if __name__ == "__main__":
    main()
