"""Run many independent simulations: serially, on all local cores, or on a Dask cluster.

One mechanism for the basin grid and parameter sweeps. Local parallel runs use a
``ProcessPoolExecutor`` with *spawn* workers (no fork of a process that may hold threads),
started for the call; ``scheduler`` sends the tasks to a Dask distributed cluster instead
(``dask[distributed]`` must be installed), or to a ``concurrent.futures.Executor`` the
caller keeps open across calls. A fresh spawn worker pays about a second to import
scoutsim and load its compiled code before its first run; once a 2 s Model II run takes
~7 ms that is most of a 400-point sweep, so repeated sweeps in one session should share
a pool (``benchmarks/bench_sweep.py`` measures both). Tasks travel to the workers in small
batches (:data:`MAX_BATCH`). Results come back in task order whatever the completion
order, and ``on_result`` sees each one as soon as its batch returns (checkpointing), so an
interrupted run keeps what it finished.
"""

from __future__ import annotations

import concurrent.futures as cf
import functools
import multiprocessing
import os
import sys


def map_tasks(func, tasks: list, *, workers: int | None = None, scheduler=None,
              progress: bool = False, desc: str = "runs", on_result=None,
              error_row=None) -> list:
    """Apply ``func`` to every task and return the results in task order.

    Parameters
    ----------
    func : picklable top-level function task -> result.
    tasks : list of picklable tasks.
    workers : local processes (default: all cores; 1 = in this process).
    scheduler : Dask scheduler address (str), ``distributed.Client``, or a
        ``concurrent.futures.Executor`` (e.g. a ``ProcessPoolExecutor`` kept open by the
        caller, left open here); overrides workers.
    progress : show a tqdm bar on stderr.
    on_result : callable(index, result), called as each result arrives.
    error_row : callable(task, exception) -> result for a task whose worker failed
        (default: re-raise).
    """
    from tqdm import tqdm
    n = len(tasks)
    out: list = [None] * n
    bar = tqdm(total=n, unit="run", desc=desc, file=sys.stderr, disable=not progress,
               leave=False)

    def done(i, res):
        out[i] = res
        if on_result is not None:
            on_result(i, res)
        bar.update(1)

    def failed(i, exc):
        if error_row is None:
            raise exc
        done(i, error_row(tasks[i], exc))

    try:
        if isinstance(scheduler, cf.Executor):
            _map_executor(scheduler, func, tasks, done, failed)
        elif scheduler is not None:
            _map_dask(func, tasks, scheduler, done, failed)
        elif (workers or os.cpu_count() or 1) == 1 or n <= 1:
            for i, task in enumerate(tasks):
                done(i, func(task))
        else:
            ctx = multiprocessing.get_context("spawn")
            with cf.ProcessPoolExecutor(max_workers=min(workers or os.cpu_count() or 1, n),
                                        mp_context=ctx) as pool:
                try:
                    _map_executor(pool, func, tasks, done, failed)
                except BaseException:
                    pool.shutdown(wait=False, cancel_futures=True)
                    raise
    finally:
        bar.close()
    return out


def _map_executor(pool, func, tasks, done, failed):
    """Submit the tasks in batches to a ``concurrent.futures`` executor; results as they
    complete. On an interruption the batches not yet started are cancelled (the pool
    stays the caller's)."""
    nw = getattr(pool, "_max_workers", None) or os.cpu_count() or 1
    batches = _batches(len(tasks), nw)
    runner = functools.partial(_run_batch, func)
    futures = {pool.submit(runner, [tasks[i] for i in b]): b for b in batches}
    try:
        for fut in cf.as_completed(futures):
            _collect(futures[fut], fut, done, failed)
    except BaseException:
        for fut in futures:
            fut.cancel()
        raise


# Tasks go to the workers in batches: enough batches that each worker gets several (load
# balance, progress, checkpoints), few enough that the cost of one submission (pickling,
# scheduling: a few ms on Dask) stays small next to the runs. Measured on the 400-point
# 2 s sweep (~7 ms a run; benchmarks/bench_sweep.py), 2 warm workers: one task per
# submission 1.86x (local pool) and 1.10x (Dask) over one worker.
BATCHES_PER_WORKER = 8
MAX_BATCH = 16


def _batches(n: int, workers: int) -> list[list[int]]:
    size = max(1, min(MAX_BATCH, n // (BATCHES_PER_WORKER * max(1, workers))))
    return [list(range(i, min(i + size, n))) for i in range(0, n, size)]


def _run_batch(func, batch):
    """Run a batch in a worker; each task's result or exception, in order."""
    out = []
    for task in batch:
        try:
            out.append((True, func(task)))
        except Exception as exc:  # noqa: BLE001 - reported per task by the caller
            out.append((False, exc))
    return out


def _collect(indices, fut, done, failed):
    try:
        results = fut.result()
    except Exception as exc:  # noqa: BLE001 - the whole batch failed (e.g. a worker died)
        for i in indices:
            failed(i, exc)
        return
    for i, (ok, val) in zip(indices, results):
        if ok:
            done(i, val)
        else:
            failed(i, val)


def _map_dask(func, tasks, scheduler, done, failed):
    try:
        from distributed import Client, as_completed
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise RuntimeError("scheduler given but dask.distributed is not installed: "
                           "pip install 'dask[distributed]'") from exc
    own = not isinstance(scheduler, Client)
    client = Client(scheduler) if own else scheduler
    try:
        nw = max(1, len(client.scheduler_info().get("workers", {})))
        batches = _batches(len(tasks), nw)
        futures = client.map(functools.partial(_run_batch, func),
                             [[tasks[i] for i in b] for b in batches], pure=False)
        index = {f.key: b for f, b in zip(futures, batches)}
        for fut in as_completed(futures):
            _collect(index[fut.key], fut, done, failed)
    finally:
        if own:
            client.close()
