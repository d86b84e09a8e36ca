"""Run many independent simulations: serially, on all local cores, or on a Dask cluster.

One mechanism for the basin grid and parameter sweeps. Local parallel runs use a
``ProcessPoolExecutor`` with *spawn* workers (no fork of a process that may hold threads),
started for the call; ``scheduler`` sends the tasks to a Dask distributed cluster instead
(``dask[distributed]`` must be installed), or to a ``concurrent.futures.Executor`` the
caller keeps open across calls. A fresh spawn worker pays about a second to import
scoutsim and load its compiled code before its first run; once a 2 s Model II run takes
~7 ms that is most of a 400-point sweep, so repeated sweeps in one program should share
a pool (``benchmarks/bench_sweep.py`` measures both). Tasks travel to the workers in small
batches (:data:`MAX_BATCH`). Results come back in task order whatever the completion
order, and ``on_result`` sees each one as soon as its batch returns (checkpointing), so an
interrupted run keeps what it finished.

What the local pool survives (``tests/analysis/test_parallel.py`` and the process tests
of ``tests/analysis/test_sweep_processes.py``):

- **Ctrl-C** (SIGINT to the parent, or to the whole process group from a terminal): the
  workers ignore SIGINT (they are spawned with it blocked, then ignore it); the parent
  keeps the results that had already arrived, stops the workers at once and raises
  ``KeyboardInterrupt``. A task whose run was cut is never
  reported as done.
- **A killed worker** (SIGKILL, the out-of-memory killer, a crash) breaks the pool: the
  tasks that had not started are run again without penalty, and the tasks of the batches
  that were running in a worker when it died are retried once, each alone in a worker of
  its own; a task whose worker dies again is reported as failed with the reason
  (:class:`WorkerDiedError`), the others complete.
- **On a Dask cluster** Dask reschedules a dead worker's tasks and gives a task up after
  ``distributed.scheduler.allowed-failures`` deaths (KilledWorker); since the tasks held by a
  worker die with the one that kills it, each task given up is run once more alone, and
  only a second KilledWorker fails it.
- **A killed parent**: each worker watches its parent and exits within
  :data:`PARENT_POLL_S` seconds of the parent's death (plus the rest of the compiled call
  it is in); no worker outlives the sweep.

**What can be sent.** Tasks reach other processes by pickle, so everything in them (a
user's controller above all) must pickle, and every function and class pickled by
reference must be importable by name where it lands. Before the first task leaves this
process, :func:`map_tasks` pickles ``func`` and every task once as a trial
(:func:`check_sendable`) and refuses with :class:`NotSendableError` what would fail in a
worker: a closure or a lambda, a class defined inside a function, an object holding a
lock, a file or a compiled callback, a function of a module that cannot be imported by
name (one loaded from a file path, or ``__main__`` of an interactive session). A local
pool's spawn workers get this process's ``sys.path``; a Dask worker has its own
environment, which must have scoutsim (the same version) and the user's modules
importable (on its ``PYTHONPATH`` or installed), something no trial here can check. (Dask
could send some closures by value; the rule is the same for every pool, so a study that
runs on a cluster runs on local workers too.)
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import functools
import io
import multiprocessing
import os
import pickle
import signal
import sys
import threading
import types

__all__ = [
    "map_tasks",
    "worker_pool",
    "WorkerDiedError",
    "SchedulerUnreachableError",
    "NotSendableError",
    "check_sendable",
    "leaves_process",
    "MAX_BATCH",
    "SCHEDULER_TIMEOUT_S",
]

#: seconds a worker waits between looks at its parent (it exits when the parent is gone)
PARENT_POLL_S = 0.5
#: seconds to wait for a Dask scheduler to answer before giving up with a clear message
SCHEDULER_TIMEOUT_S = 10.0


class WorkerDiedError(RuntimeError):
    """The worker process running a task died (killed, out of memory, crashed) while
    running it, on the first try and on the retry."""


class SchedulerUnreachableError(ConnectionError):
    """The Dask scheduler given did not answer within :data:`SCHEDULER_TIMEOUT_S`."""


class NotSendableError(TypeError):
    """Something a parallel run must send to its workers (a task, a user's controller) does
    not pickle, or names a function or class the workers cannot import; raised before the
    first task runs (the message says what, why, and what to do instead)."""


#: what to do with something that cannot be sent (the end of NotSendableError's message)
SEND_ADVICE = (
    "define it at the top level of a module the workers can import (a file on "
    "sys.path / PYTHONPATH, or an installed package), or run with workers=1"
)


def leaves_process(workers: int | None, scheduler, n_tasks: int) -> bool:
    """Whether :func:`map_tasks` with these arguments sends its tasks to other processes
    (a local pool or Dask cluster; not: one worker, one task, a thread pool)."""
    if isinstance(scheduler, cf.ThreadPoolExecutor):
        return False
    if scheduler is not None:
        return True
    return (workers or os.cpu_count() or 1) > 1 and n_tasks > 1


class _RecordingPickler(pickle.Pickler):
    """A pickler that notes the module of every function and class it pickles."""

    def __init__(self, file):
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self.modules: set = set()

    def reducer_override(self, obj):
        if isinstance(obj, (type, types.FunctionType)):
            self.modules.add(getattr(obj, "__module__", None))
        return NotImplemented


def is_importable(module: str) -> bool:
    """Whether a fresh process could import ``module`` by name (its top-level package
    found by the import system on this ``sys.path``, not only present in ``sys.modules``)."""
    top = module.partition(".")[0]
    if top in sys.builtin_module_names:
        return True
    for finder in sys.meta_path:
        find = getattr(finder, "find_spec", None)
        if find is None:
            continue
        try:
            if find(top, None) is not None:
                return True
        except Exception:  # noqa: BLE001 - a finder that cannot answer is no answer
            continue
    return False


def unsendable_reason(obj) -> str | None:
    """Why ``obj`` cannot be sent to a worker process (None if it can): the error of a
    trial pickle, or a module of a function / class in it that a worker cannot import."""
    pickler = _RecordingPickler(io.BytesIO())
    try:
        pickler.dump(obj)
    except Exception as exc:  # noqa: BLE001 - any failure to pickle is the answer
        text = str(exc)
        if "local object" in text or "<locals>" in text:
            why = "it is, or holds, a function or class defined inside a function"
        elif "<lambda>" in text:
            why = "it is, or holds, a lambda"
        else:
            why = "it does not pickle"
        return f"{why} ({type(exc).__name__}: {text})"
    for module in sorted(m for m in pickler.modules if m):
        if module == "__main__":
            main = sys.modules.get("__main__")
            if getattr(main, "__file__", None) is None:
                return (
                    "it is, or holds, a function or class defined in an interactive "
                    "session (__main__ has no file a worker process could import)"
                )
        elif not is_importable(module):
            return (
                f"it is, or holds, a function or class of module {module!r}, which a "
                "worker process cannot import by name (not found on sys.path)"
            )
    return None


def check_sendable(obj, what: str, advice: str = SEND_ADVICE) -> None:
    """:class:`NotSendableError` naming ``what`` if ``obj`` cannot be sent to a worker
    process (:func:`unsendable_reason`), with ``advice`` on what to do instead."""
    reason = unsendable_reason(obj)
    if reason is not None:
        raise NotSendableError(f"{what} cannot be sent to the worker processes: {reason}; {advice}")


class _Stopped(Exception):
    """Raised inside :func:`map_tasks` when a result asks to stop (``stop_when``)."""


def map_tasks(
    func,
    tasks: list,
    *,
    workers: int | None = None,
    scheduler=None,
    progress: bool = False,
    desc: str = "runs",
    on_result=None,
    error_row=None,
    stop_when=None,
) -> list:
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
        (an exception raised by ``func``, or :class:`WorkerDiedError`; default: re-raise).
    stop_when : callable(result) -> bool; the first result for which it is true stops the
        run: the tasks not yet started are cancelled (a local pool's workers stopped),
        the results that had arrived are kept, and the others are None in the list
        returned.

    Raises
    ------
    NotSendableError : ``func`` or a task cannot be sent to the workers (checked before
        the first task runs, when the tasks leave this process; :func:`check_sendable`).
    KeyboardInterrupt : Ctrl-C; the results that had arrived went to ``on_result``.
    SchedulerUnreachableError : a scheduler address that does not answer.
    """
    from tqdm import tqdm

    n = len(tasks)
    out: list = [None] * n
    if leaves_process(workers, scheduler, n):
        check_sendable(func, f"the function {getattr(func, '__qualname__', func)!r}")
        if unsendable_reason(tasks) is not None:
            for i, task in enumerate(tasks):
                check_sendable(task, f"task {i} of the {desc}")
    bar = tqdm(total=n, unit="run", desc=desc, file=sys.stderr, disable=not progress, leave=False)
    stopping: list[int] = []

    def done(i, res):
        out[i] = res
        if on_result is not None:
            on_result(i, res)
        bar.update(1)
        if stop_when is not None and not stopping and stop_when(res):
            stopping.append(i)
            raise _Stopped

    def failed(i, exc):
        if error_row is None:
            raise exc
        done(i, error_row(tasks[i], exc))

    try:
        if isinstance(scheduler, cf.Executor):
            _map_executor(scheduler, func, tasks, list(range(n)), done, failed)
        elif scheduler is not None:
            _map_dask(func, tasks, scheduler, done, failed)
        elif (workers or os.cpu_count() or 1) == 1 or n <= 1:
            for i, task in enumerate(tasks):
                done(i, func(task))
        else:
            _map_local(func, tasks, min(workers or os.cpu_count() or 1, n), done, failed)
    except _Stopped:
        pass
    finally:
        bar.close()
    return out


# Tasks go to the workers in batches: enough batches that each worker gets several (load
# balance, progress, checkpoints), few enough that the cost of one submission (pickling,
# scheduling: a few ms on Dask) stays small next to the runs. Measured on the 400-point
# 2 s sweep (~7 ms a run; benchmarks/bench_sweep.py), 2 warm workers: one task per
# submission 1.86x (local pool) and 1.10x (Dask) over one worker.
BATCHES_PER_WORKER = 8
MAX_BATCH = 16


def _batches(indices: list[int], workers: int) -> list[list[int]]:
    n = len(indices)
    size = max(1, min(MAX_BATCH, n // (BATCHES_PER_WORKER * max(1, workers))))
    return [indices[i : i + size] for i in range(0, n, size)]


# -----------------------------------------------------------------------------------------
# in a worker
# -----------------------------------------------------------------------------------------
#: shared array (one slot per batch of the current pool): the pid of the worker that
#: started the batch, 0 before (set in the workers of a pool started by _map_local)
_STARTED = None


def _worker_init(started) -> None:
    """Initialiser of every local pool worker: ignore SIGINT (the parent decides what an
    interruption stops), watch the parent, remember where to say which batch it runs."""
    global _STARTED
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _STARTED = started
    parent = multiprocessing.parent_process()
    if parent is not None:
        threading.Thread(
            target=_exit_when_orphaned, args=(parent,), daemon=True, name="scoutsim-parent-watch"
        ).start()


def _exit_when_orphaned(parent) -> None:
    """Exit this worker at once when its parent process has died (SIGKILL of a sweep
    leaves no worker behind). The parent's sentinel becomes ready when it dies; the
    ``getppid`` check covers a sentinel that cannot be waited on."""
    ppid = os.getppid()
    while True:
        parent.join(PARENT_POLL_S)
        if not parent.is_alive() or os.getppid() != ppid:
            os._exit(1)


def _run_batch(func, batch_id, batch):
    """Run a batch in a worker; each task's result or exception, in order."""
    if batch_id is not None and _STARTED is not None:
        _STARTED[batch_id] = os.getpid()
    out = []
    for task in batch:
        try:
            out.append((True, func(task)))
        except Exception as exc:  # noqa: BLE001 - reported per task by the caller
            out.append((False, exc))
    return out


# -----------------------------------------------------------------------------------------
# in the parent
# -----------------------------------------------------------------------------------------
def _collect(indices, fut, done, failed):
    """Hand the results of a finished batch (``fut``, of the tasks ``indices``) to ``done``
    and its failures to ``failed``; a stop asked by one (``stop_when``) is raised after
    the whole batch is handed over."""
    try:
        results = fut.result()
    except Exception as exc:  # noqa: BLE001 - the whole batch failed (e.g. a worker died)
        results = [(False, exc)] * len(indices)
    stop = None
    for i, (ok, val) in zip(indices, results):
        try:
            if ok:
                done(i, val)
            else:
                failed(i, val)
        except _Stopped as exc:  # the rest of the batch has arrived: keep it too
            stop = exc
    if stop is not None:
        raise stop


def _map_executor(pool, func, tasks, indices, done, failed):
    """Submit the tasks in batches to a caller's ``concurrent.futures`` executor; results as
    they complete. On an interruption the batches not yet started are cancelled (the pool
    stays the caller's); a batch whose worker died fails its tasks."""
    nw = getattr(pool, "_max_workers", None) or os.cpu_count() or 1
    futures = {
        pool.submit(_run_batch, func, None, [tasks[i] for i in b]): b for b in _batches(indices, nw)
    }
    try:
        for fut in cf.as_completed(futures):
            _collect(futures[fut], fut, done, failed)
    except BaseException:
        for fut in futures:
            fut.cancel()
        raise


def _new_pool(workers: int, started=None):
    """A spawn pool whose workers run :func:`_worker_init` (``started``: the shared array
    where they note which batch they run, see :data:`_STARTED`)."""
    ctx = multiprocessing.get_context("spawn")
    if started is None:
        started = ctx.Array("q", 1, lock=False)
    return cf.ProcessPoolExecutor(
        max_workers=workers, mp_context=ctx, initializer=_worker_init, initargs=(started,)
    )


@contextlib.contextmanager
def _sigint_held_while_spawning():
    """Hold SIGINT while the pool spawns its workers (in ``submit``), and deliver it when
    the block ends, so that a Ctrl-C is never lost and never cuts a spawn in half.

    Two things are held. The signal mask of this thread: a spawned process keeps it
    through ``exec``, so a Ctrl-C can never reach a worker still importing, before its
    initialiser ignores SIGINT (the threads the pool starts here keep it blocked too).
    And the Python-level handler: SIGINT sent to the process (Ctrl-C in a terminal signals
    the whole group) is delivered to any thread that does not block it (threads of the
    numerical libraries, started earlier), and Python would then raise
    ``KeyboardInterrupt`` here in the main thread anyway, possibly between a worker's
    ``exec`` and the write of its start-up data, leaving the worker to fail on an empty
    pipe. The handler installed here only notes the signal; on leaving the block the
    previous handler is restored and the noted signal raised again through it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    noted = []
    previous_handler = signal.signal(signal.SIGINT, lambda signum, frame: noted.append(signum))
    previous_mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous_mask)
        signal.signal(signal.SIGINT, previous_handler)
        if noted:
            signal.raise_signal(signal.SIGINT)


def _stop_pool(pool) -> None:
    """End a pool at once: cancel what has not started and kill the workers (they ignore
    SIGINT, and a run in compiled code would otherwise finish its batch first). Python
    3.11's executor has no public call for it (3.14 adds ``kill_workers``)."""
    for p in list((getattr(pool, "_processes", None) or {}).values()):
        try:
            p.kill()
        except (OSError, AttributeError, ValueError):
            pass
    pool.shutdown(wait=True, cancel_futures=True)


@contextlib.contextmanager
def worker_pool(workers: int):
    """A pool of ``workers`` spawn processes kept open for many :func:`map_tasks` calls
    (pass it as ``scheduler``), so that worker start-up is paid once: its workers ignore
    SIGINT and exit with their parent, as the pools :func:`map_tasks` starts. On leaving
    the block by an exception (Ctrl-C) the workers are killed at once; otherwise the pool
    is shut down. A pool whose worker died is broken: :func:`pool_is_broken` says so, and
    the caller starts another."""
    with _sigint_held_while_spawning():
        pool = _new_pool(workers)
        # start every worker now, SIGINT held (the pool spawns them as tasks arrive)
        started = [pool.submit(os.getpid) for _ in range(workers)]
    try:
        cf.wait(started)
        yield pool
    except BaseException:
        _stop_pool(pool)
        raise
    pool.shutdown(wait=True)


def pool_is_broken(pool) -> bool:
    """Whether a worker of ``pool`` (from :func:`worker_pool`) died, which breaks it."""
    return bool(getattr(pool, "_broken", False))


def _map_local(func, tasks, workers, done, failed):
    """Batches on a pool of ``workers`` spawn processes, surviving dead workers (module
    docstring). Each round runs what is left on a fresh pool; when a worker dies, the
    batches that had not started go to the next round and the tasks of the batches that
    were running are retried one at a time (:func:`_retry_alone`)."""
    todo = list(range(len(tasks)))
    ctx = multiprocessing.get_context("spawn")
    while todo:
        batches = _batches(todo, workers)
        started = ctx.Array("q", len(batches), lock=False)
        pool = _new_pool(min(workers, len(batches)), started)
        futures: dict = {}
        finished: set[int] = set()
        try:
            with _sigint_held_while_spawning():
                for b, batch in enumerate(batches):
                    futures[pool.submit(_run_batch, func, b, [tasks[i] for i in batch])] = b
            for fut in cf.as_completed(futures):
                b = futures[fut]
                if isinstance(fut.exception(), cf.process.BrokenProcessPool):
                    continue  # sorted out below, once every future has settled
                finished.add(b)
                _collect(batches[b], fut, done, failed)
        except BaseException:
            # Ctrl-C: keep what has arrived, then stop the workers at once
            for fut, b in futures.items():
                if (
                    b not in finished
                    and fut.done()
                    and not fut.cancelled()
                    and fut.exception() is None
                ):
                    finished.add(b)
                    _collect(batches[b], fut, done, failed)
            _stop_pool(pool)
            raise
        pool.shutdown(wait=True)
        lost = [b for b in range(len(batches)) if b not in finished]
        suspects = [i for b in lost if started[b] != 0 for i in batches[b]]
        todo = [i for b in lost if started[b] == 0 for i in batches[b]]
        if suspects:
            _retry_alone(func, tasks, suspects, done, failed)


def _retry_alone(func, tasks, indices, done, failed):
    """Run each task whose batch was in a worker when it died once more, alone in a one-
    worker pool (so a second death is that task's own); a second death fails it."""
    pool = _new_pool(1)
    try:
        for i in indices:
            with _sigint_held_while_spawning():
                fut = pool.submit(_run_batch, func, None, [tasks[i]])
            try:
                fut.result()
            except cf.process.BrokenProcessPool:
                pool.shutdown(wait=True)
                failed(
                    i,
                    WorkerDiedError(
                        "the worker process running this task died twice (killed by a signal, "
                        "out of memory or crashed); it was retried once, alone"
                    ),
                )
                pool = _new_pool(1)
                continue
            except Exception:  # noqa: BLE001 - reported by _collect
                pass
            _collect([i], fut, done, failed)
    except BaseException:
        _stop_pool(pool)
        raise
    pool.shutdown(wait=True)


def _map_dask(func, tasks, scheduler, done, failed):
    try:
        from distributed import Client, as_completed
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise RuntimeError(
            "scheduler given but dask.distributed is not installed: pip install 'dask[distributed]'"
        ) from exc
    own = not isinstance(scheduler, Client)
    if own:
        try:
            client = Client(scheduler, timeout=SCHEDULER_TIMEOUT_S)
        except (OSError, TimeoutError) as exc:
            raise SchedulerUnreachableError(
                f"scheduler = {scheduler!r}: no Dask scheduler answered there within "
                f"{SCHEDULER_TIMEOUT_S:g} s ({type(exc).__name__}); start one with "
                "`dask scheduler` (and workers with `dask worker ADDRESS`), and give its "
                "address as tcp://HOST:PORT"
            ) from None
    else:
        client = scheduler
    from distributed import KilledWorker

    futures = []
    try:
        nw = max(1, len(client.scheduler_info().get("workers", {})))
        batches = _batches(list(range(len(tasks))), nw)
        futures = client.map(
            functools.partial(_run_batch, func, None),
            [[tasks[i] for i in b] for b in batches],
            pure=False,
        )
        index = {f.key: b for f, b in zip(futures, batches)}
        suspects = []
        for fut in as_completed(futures):
            if fut.status == "error" and isinstance(fut.exception(), KilledWorker):
                suspects += index[fut.key]  # sorted out below, one at a time
                continue
            _collect(index[fut.key], fut, done, failed)
        # Dask gave these up because workers died while they were there; but a worker
        # runs or holds several tasks, and the others die with the one that kills it. Each
        # runs once more alone, nothing else in flight: a KilledWorker now is its own.
        for i in suspects:
            futures = [client.submit(_run_batch, func, None, [tasks[i]], pure=False)]
            try:
                futures[0].result()
            except KilledWorker:
                pass
            except Exception:  # noqa: BLE001 - reported by _collect
                pass
            _collect([i], futures[0], done, failed)
    except BaseException:
        if futures:
            client.cancel(futures)
        raise
    finally:
        if own:
            client.close()
