"""Sweep benchmark: a 400-point touchdown-angle sweep of Model II, 2 s each.

    python benchmarks/bench_sweep.py [--points-per-axis 20] [--duration 2]

Runs the same sweep with one worker, with all local cores, and on a local Dask cluster
(one worker process per core), in this one run; prints wall times, the parallel speed-up
over one worker, and whether the tables are identical.

All local cores are measured twice: ``workers=N`` (a spawn pool started for the sweep, so
the time includes each worker's ~1 s of importing scoutsim and loading its compiled
code), and a pool kept open and warmed first (``scheduler=executor``), which is how the
Dask cluster is measured too. The one-worker run is warm as well (same process, cache
loaded). Since a 2 s run takes ~7 ms the whole sweep is a few seconds, so the start-up
is a large share of the cold figure; the warm figure is the sweep's throughput.
"""

import argparse
import concurrent.futures as cf
import json
import multiprocessing
import os
import time

import numpy as np

from scoutsim.analysis.sweep import grid_points, sweep


def _one_run(_):
    import scoutsim

    scoutsim.simulate(duration=0.1, model="II", friction_coefficient=0.8)
    t0 = time.perf_counter()
    scoutsim.simulate(duration=10.0, model="II", friction_coefficient=0.8)
    return time.perf_counter() - t0


def _warm(_):
    # load scoutsim and its compiled code in a pool worker, and hold the worker long
    # enough that every worker of the pool gets one of these
    import scoutsim

    scoutsim.simulate(duration=0.05, model="II", friction_coefficient=0.8)
    time.sleep(0.5)
    return 0


def machine_ceiling(cores):
    """The machine's own parallel ceiling: the same 10 s run alone and in ``cores``
    concurrent processes (no scoutsim machinery in between): cores * t_alone / t_together."""
    import multiprocessing

    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(1) as p:
        alone = p.map(_one_run, [0])[0]
    with ctx.Pool(cores) as p:
        together = max(p.map(_one_run, range(cores)))
    return cores * alone / together


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--points-per-axis", type=int, default=20)
    ap.add_argument("--duration", type=float, default=2.0)
    args = ap.parse_args()
    n = args.points_per_axis
    grid = {
        "controller.touchdown_angle_front": np.radians(np.linspace(15, 27, n)),
        "controller.touchdown_angle_back": np.radians(np.linspace(13, 25, n)),
    }
    pts = grid_points(grid)
    sweep(pts[:2], duration=0.05, workers=1)  # compile / load the cache first
    cores = os.cpu_count() or 1
    t0 = time.perf_counter()
    one = sweep(pts, duration=args.duration, workers=1)
    w1 = time.perf_counter() - t0
    t0 = time.perf_counter()
    many = sweep(pts, duration=args.duration, workers=cores)
    wn = time.perf_counter() - t0
    ctx = multiprocessing.get_context("spawn")
    with cf.ProcessPoolExecutor(cores, mp_context=ctx) as pool:
        list(pool.map(_warm, range(cores)))
        t0 = time.perf_counter()
        kept = sweep(pts, duration=args.duration, scheduler=pool)
        wk = time.perf_counter() - t0
    import distributed

    with (
        distributed.LocalCluster(
            n_workers=cores, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        client.run(lambda: __import__("scoutsim").simulate(duration=0.05))  # warm workers
        t0 = time.perf_counter()
        dk = sweep(pts, duration=args.duration, scheduler=client)
        wd = time.perf_counter() - t0
    ceiling = machine_ceiling(cores)
    tables = [json.dumps(t.rows, sort_keys=True) for t in (one, many, kept, dk)]
    same = all(t == tables[0] for t in tables)
    steady = sum(r["steady_bounding"] for r in one.rows)
    print(f"{len(pts)} points x {args.duration:g} s of Model II ({steady} steady bounding)")
    print(f"one worker                {w1:7.2f} s")
    print(
        f"{cores} local workers, pool kept (warm) {wk:7.2f} s   speed-up {w1 / wk:.2f}x   "
        "target >= 1.7x"
    )
    print(
        f"{cores} local workers, pool started for the sweep {wn:7.2f} s   speed-up "
        f"{w1 / wn:.2f}x   (includes worker start-up)"
    )
    print(f"local Dask cluster ({cores} workers, warm) {wd:7.2f} s   speed-up {w1 / wd:.2f}x")
    print(
        f"machine ceiling: {cores} concurrent independent runs give {ceiling:.2f}x "
        "(vCPUs sharing a physical core give well under 2x)"
    )
    print(f"tables identical (1 worker / {cores} workers cold and kept / Dask): {same}")


if __name__ == "__main__":
    main()
