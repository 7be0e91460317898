"""Where sweep tasks run: in this process, in a local process pool, or on a Dask cluster.

Every executor takes a task function `fn(task, sink)` and yields `(task, result)` as results
arrive. `sink.put((task_id, stage))` reports the stage a task has started; each executor carries
it back to `on_stage` (a callback, a process queue, or a Dask distributed Queue). Closing the
generator early (the caller was interrupted) stops the work at once: pending tasks are
cancelled and local worker processes killed, their pids added to `killed`.
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing as mp
import os
import queue
import time
import uuid
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Callable, Iterator

import psutil

from seadesign.errors import SeadesignError
from seadesign.run.heavy_stage import install as install_heavy_lock
from seadesign.run.interrupt import ignore_sigint, kill_trees

POLL_S = 0.25  # how often stage messages are drained while waiting for results
EXECUTORS = ("local", "dask", "serial")


class ExecutorError(SeadesignError):
    """An executor option is invalid or the cluster cannot be reached."""


class _CallbackSink:
    """A sink that forwards stage messages straight to a callback (same process)."""

    def __init__(self, on_stage: Callable[[Any, str], None]) -> None:
        self.on_stage = on_stage

    def put(self, message: tuple[Any, str]) -> None:
        self.on_stage(*message)


def run_serial(fn, tasks: list, on_stage: Callable[[Any, str], None], on_tick: Callable[[], None]) -> Iterator:
    """Tasks one after another in this process (exceptions propagate as raised)."""
    sink = _CallbackSink(on_stage)
    for task in tasks:
        yield task, fn(task, sink)
        on_tick()


_kept: dict[int, tuple] | None = None  # worker count -> (manager, pool) while `keeping_workers` is open


@contextlib.contextmanager
def keeping_workers():
    """Keep the local worker processes between calls (the explorer's rounds: a fresh pool costs each round the
    workers' start and imports, about 4 s); they are shut down on leaving."""
    global _kept
    if _kept is not None:  # nested: the outer block keeps them
        yield
        return
    _kept = {}
    try:
        yield
    finally:
        kept, _kept = _kept, None
        for manager, pool in kept.values():
            pool.shutdown()
            manager.shutdown()


def _pool(jobs: int) -> tuple:
    """A managed-queue manager and a pool of `jobs` "spawn" processes: kept ones when `keeping_workers` is open."""
    if _kept is not None and jobs in _kept:
        return _kept[jobs]
    ctx = mp.get_context("spawn")
    threads = max(1, default_jobs() // jobs)  # solver threads per worker: no oversubscription
    made = (ctx.Manager(), ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=_init_worker,
                                               initargs=(threads, ctx.Lock())))
    if _kept is not None:
        _kept[jobs] = made
    return made


def run_processes(fn, tasks: list, jobs: int, on_stage: Callable[[Any, str], None],
                  on_tick: Callable[[], None], killed: list[int]) -> Iterator:
    """Tasks in a pool of `jobs` processes (fresh, or kept by `keeping_workers`); stage messages through a
    managed queue.

    When the caller stops (Ctrl-C, SIGTERM, an error), pending tasks are cancelled and the worker
    processes are killed with everything they started, without waiting for running tasks."""
    manager, pool = _pool(jobs)
    finished = False
    try:
        sink = manager.Queue()
        pending = {pool.submit(fn, task, sink): task for task in tasks}
        while pending:
            done, _ = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
            _drain(sink, on_stage)
            for fut in done:
                yield pending.pop(fut), fut.result()
            on_tick()
        finished = True
    finally:
        if finished and _kept is None:
            pool.shutdown()
            manager.shutdown()
        elif not finished:
            if _kept is not None:
                _kept.pop(jobs, None)
            workers = [p.pid for p in (pool._processes or {}).values()]  # noqa: SLF001 - no public accessor
            pool.shutdown(wait=False, cancel_futures=True)
            killed.extend(kill_trees(workers + [manager._process.pid]))  # noqa: SLF001


THREAD_VARIABLES = ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")


def _init_worker(threads: int, heavy_lock) -> None:
    """A local worker: Ctrl-C is the parent's to handle, the math libraries use `threads` threads (unless the
    caller's environment sets their variables): in the environment for MKL, which loads later, and through
    threadpoolctl for what the worker's imports already loaded (NumPy's OpenBLAS); and the pool's workers share
    `heavy_lock`, so that one of them at a time runs a memory-heavy stage (`run.heavy_stage`)."""
    from threadpoolctl import threadpool_limits

    ignore_sigint()
    install_heavy_lock(heavy_lock)
    unset = [name for name in THREAD_VARIABLES if name not in os.environ]
    os.environ.update({name: str(threads) for name in unset})
    if unset:
        threadpool_limits(threads)


def _drain(sink, on_stage: Callable[[Any, str], None]) -> None:
    while True:
        try:
            on_stage(*sink.get_nowait())
        except queue.Empty:
            return


class _DaskSink:
    """Stage messages from Dask workers through a distributed Queue held by the scheduler."""

    def __init__(self, queue) -> None:
        self.queue = queue

    def put(self, message) -> None:
        self.queue.put(list(message))

    def drain(self, on_stage: Callable[[Any, str], None]) -> None:
        if self.queue.qsize():
            for task_id, stage in self.queue.get(batch=True):
                on_stage(task_id, stage)


def run_dask(fn, tasks: list, scheduler: str | None, jobs: int, on_stage: Callable[[Any, str], None],
             on_tick: Callable[[], None], killed: list[int]) -> Iterator:
    """Tasks on a Dask distributed cluster at `scheduler` (host:port), or on a LocalCluster of
    `jobs` single-threaded worker processes when no address is given; stage messages come back
    through a distributed Queue. When the caller stops, pending futures are cancelled and a
    LocalCluster's processes are killed (a remote cluster finishes the tasks it is running)."""
    try:
        from distributed import Client, LocalCluster, Queue
    except ImportError:
        raise ExecutorError("--executor dask needs the 'distributed' package: pip install 'dask[distributed]'") from None
    logging.getLogger("distributed").setLevel(logging.WARNING)  # the sweep's progress is what users read
    cluster = None
    before = {p.pid for p in psutil.Process().children()}
    try:
        if scheduler:
            client = Client(scheduler, timeout="10s")
        else:
            cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, dashboard_address=None)
            client = Client(cluster)
    except OSError as exc:
        raise ExecutorError(f"--scheduler {scheduler}: cannot connect ({exc}); check the address (host:port)") from None
    futures: dict = {}
    finished = False
    try:
        sink = _DaskSink(Queue(f"seadesign-stages-{uuid.uuid4().hex}", client=client))
        futures = {client.submit(fn, task, sink, pure=False): task for task in tasks}
        pending = list(futures)
        while pending:
            done = [f for f in pending if f.done()]
            pending = [f for f in pending if not f.done()]
            sink.drain(on_stage)
            for fut in done:
                yield futures[fut], fut.result()
            if pending:
                time.sleep(POLL_S)
            on_tick()
        finished = True
    finally:
        if finished or cluster is None:
            if not finished:
                client.cancel(list(futures), force=True)
            client.close()
            if cluster is not None:
                cluster.close()
        else:  # a LocalCluster's worker processes are ours: kill them rather than wait for a clean close
            killed.extend(kill_trees([p.pid for p in psutil.Process().children()
                                      if p.pid not in before and not _is_resource_tracker(p)]))
            with contextlib.suppress(Exception):
                client.close(timeout=0.5)


def _is_resource_tracker(p: psutil.Process) -> bool:
    """multiprocessing's resource tracker (it must outlive the workers to clean up after them)."""
    with contextlib.suppress(psutil.Error):
        return any("resource_tracker" in part for part in p.cmdline())
    return False


def default_jobs() -> int:
    """All cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def execute(fn, tasks: list, executor: str, jobs: int, scheduler: str | None,
            on_stage: Callable[[Any, str], None], on_tick: Callable[[], None], killed: list[int]) -> Iterator:
    """Dispatch to the chosen executor: "local" (a pool of `jobs` worker processes, at most one per
    task), "dask", or "serial" (this process: for debugging; a signal waits for the running C call)."""
    if jobs < 1:
        raise ExecutorError(f"--jobs must be >= 1 (got {jobs})")
    if executor not in EXECUTORS:
        raise ExecutorError(f"--executor must be one of {', '.join(EXECUTORS)} (got {executor!r})")
    if scheduler and executor != "dask":
        raise ExecutorError("--scheduler is only used with --executor dask")
    if executor == "dask":
        return run_dask(fn, tasks, scheduler, jobs, on_stage, on_tick, killed)
    if executor == "serial" or not tasks:
        return run_serial(fn, tasks, on_stage, on_tick)
    return run_processes(fn, tasks, min(jobs, len(tasks)), on_stage, on_tick, killed)
