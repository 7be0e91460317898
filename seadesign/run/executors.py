"""Where sweep tasks run: in this process, in a local process pool, or on a Dask cluster.

Every executor takes a task function `fn(task, sink)` and yields `(task, result)` as results
arrive. `sink.put((task_id, stage))` reports the stage a task has started; each executor carries
it back to `on_stage` (a callback, a process queue, or a Dask distributed Queue).
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import queue
import time
import uuid
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Callable, Iterator

from seadesign.errors import SeadesignError

POLL_S = 0.5  # how often stage messages are drained while waiting for results


class ExecutorError(SeadesignError):
    """An executor option is invalid or the cluster cannot be reached."""


class _CallbackSink:
    """A sink that forwards stage messages straight to a callback (same process)."""

    def __init__(self, on_stage: Callable[[Any, str], None]) -> None:
        self.on_stage = on_stage

    def put(self, message: tuple[Any, str]) -> None:
        self.on_stage(*message)


def run_serial(fn, tasks: list, on_stage: Callable[[Any, str], None], on_tick: Callable[[], None]) -> Iterator:
    """Tasks one after another in this process (jobs=1; exceptions propagate as raised)."""
    sink = _CallbackSink(on_stage)
    for task in tasks:
        yield task, fn(task, sink)
        on_tick()


def run_processes(fn, tasks: list, jobs: int, on_stage: Callable[[Any, str], None],
                  on_tick: Callable[[], None]) -> Iterator:
    """Tasks in a pool of `jobs` fresh ("spawn") processes; stage messages through a managed queue."""
    ctx = mp.get_context("spawn")
    threads = str(max(1, default_jobs() // jobs))  # solver threads per worker: no oversubscription
    with _environment(MKL_NUM_THREADS=threads, OMP_NUM_THREADS=threads), ctx.Manager() as manager, \
            ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
        sink = manager.Queue()
        pending = {pool.submit(fn, task, sink): task for task in tasks}
        try:
            while pending:
                done, _ = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
                _drain(sink, on_stage)
                for fut in done:
                    yield pending.pop(fut), fut.result()
                on_tick()
        finally:
            for fut in pending:
                fut.cancel()


@contextlib.contextmanager
def _environment(**values: str):
    """Environment variables set while worker processes are spawned (they inherit them); the
    caller's own values are respected."""
    added = {k: v for k, v in values.items() if k not in os.environ}
    os.environ.update(added)
    try:
        yield
    finally:
        for k in added:
            os.environ.pop(k, None)


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
             on_tick: Callable[[], None]) -> Iterator:
    """Tasks on a Dask distributed cluster at `scheduler` (host:port), or on a LocalCluster of
    `jobs` single-threaded worker processes when no address is given; stage messages come back
    through a distributed Queue."""
    try:
        from distributed import Client, LocalCluster, Queue
    except ImportError:
        raise ExecutorError("--executor dask needs the 'distributed' package: pip install 'dask[distributed]'") from None
    cluster = None
    try:
        if scheduler:
            client = Client(scheduler, timeout="10s")
        else:
            cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, dashboard_address=None)
            client = Client(cluster)
    except OSError as exc:
        raise ExecutorError(f"--scheduler {scheduler}: cannot connect ({exc}); check the address (host:port)") from None
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
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def default_jobs() -> int:
    """All cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def execute(fn, tasks: list, executor: str, jobs: int, scheduler: str | None,
            on_stage: Callable[[Any, str], None], on_tick: Callable[[], None]) -> Iterator:
    """Dispatch to the chosen executor ("local" or "dask")."""
    if jobs < 1:
        raise ExecutorError(f"--jobs must be >= 1 (got {jobs})")
    if executor == "dask":
        return run_dask(fn, tasks, scheduler, jobs, on_stage, on_tick)
    if executor != "local":
        raise ExecutorError(f"--executor must be 'local' or 'dask' (got {executor!r})")
    if scheduler:
        raise ExecutorError("--scheduler is only used with --executor dask")
    if jobs == 1 or len(tasks) <= 1:
        return run_serial(fn, tasks, on_stage, on_tick)
    return run_processes(fn, tasks, min(jobs, len(tasks)), on_stage, on_tick)
