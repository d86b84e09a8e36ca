"""Run many independent simulations: serially, on all local cores, or on a Dask cluster.

One mechanism for the basin grid and parameter sweeps. Local parallel runs use a
``ProcessPoolExecutor`` with *spawn* workers (no fork of a process that may hold threads);
``scheduler`` sends the tasks to a Dask distributed cluster instead (``dask[distributed]``
must be installed). Results come back in task order whatever the completion order, and
``on_result`` sees each one as soon as it arrives (checkpointing), so an interrupted run
keeps what it finished.
"""

from __future__ import annotations

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
    scheduler : Dask scheduler address (str) or ``distributed.Client``; overrides workers.
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
        if scheduler is not None:
            _map_dask(func, tasks, scheduler, done, failed)
        elif (workers or os.cpu_count() or 1) == 1 or n <= 1:
            for i, task in enumerate(tasks):
                done(i, func(task))
        else:
            import concurrent.futures as cf
            import multiprocessing
            ctx = multiprocessing.get_context("spawn")
            with cf.ProcessPoolExecutor(max_workers=min(workers or os.cpu_count() or 1, n),
                                        mp_context=ctx) as pool:
                futures = {pool.submit(func, task): i for i, task in enumerate(tasks)}
                try:
                    for fut in cf.as_completed(futures):
                        i = futures[fut]
                        try:
                            res = fut.result()
                        except Exception as exc:  # noqa: BLE001 - e.g. a worker died
                            failed(i, exc)
                        else:
                            done(i, res)
                except BaseException:
                    pool.shutdown(wait=False, cancel_futures=True)
                    raise
    finally:
        bar.close()
    return out


def _map_dask(func, tasks, scheduler, done, failed):
    try:
        from distributed import Client, as_completed
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise RuntimeError("scheduler given but dask.distributed is not installed: "
                           "pip install 'dask[distributed]'") from exc
    own = not isinstance(scheduler, Client)
    client = Client(scheduler) if own else scheduler
    try:
        futures = client.map(func, tasks, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        for fut in as_completed(futures):
            i = index[fut.key]
            try:
                res = fut.result()
            except Exception as exc:  # noqa: BLE001
                failed(i, exc)
            else:
                done(i, res)
    finally:
        if own:
            client.close()
