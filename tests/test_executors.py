"""The local process pool: each worker's math libraries get their share of the cores."""

from __future__ import annotations

import ctypes

from seadesign.run.executors import default_jobs, execute


def _threads(task, sink) -> tuple[int, int]:
    """(MKL's threads, OpenBLAS's threads) as a worker sees them."""
    from threadpoolctl import threadpool_info

    from seadesign.fea.pardiso import _library

    mkl = _library()
    mkl.MKL_Get_Max_Threads.restype = ctypes.c_int
    blas = [i["num_threads"] for i in threadpool_info() if i["internal_api"] == "openblas"]
    return mkl.MKL_Get_Max_Threads(), min(blas)


def test_local_workers_use_their_share_of_the_cores(monkeypatch):
    for name in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        monkeypatch.delenv(name, raising=False)
    share = max(1, default_jobs() // 2)
    results = [r for _, r in execute(_threads, [0, 1], "local", 2, None, lambda *a: None, lambda: None, [])]
    assert results == [(share, share), (share, share)]


def _pid(task, sink) -> int:
    import os

    return os.getpid()


def _pids() -> set[int]:
    return {r for _, r in execute(_pid, [0, 1, 2, 3], "local", 2, None, lambda *a: None, lambda: None, [])}


def test_workers_are_kept_between_calls_only_while_asked():
    import psutil

    from seadesign.run import executors

    assert _pids().isdisjoint(_pids())  # a fresh pool each call
    with executors.keeping_workers():
        used = _pids() | _pids()
        kept = set(executors._kept[2][1]._processes)  # the kept pool's worker processes
        assert used <= kept and len(kept) == 2
    assert not any(psutil.pid_exists(p) and psutil.Process(p).status() != psutil.STATUS_ZOMBIE for p in kept)


def _heavy(task, sink) -> tuple[float, float, bool]:
    """(start, end) of a heavy stage held 0.4 s (monotonic clock, shared by the processes), and whether another
    worker was in one when this one arrived."""
    import time

    from seadesign.run.heavy_stage import heavy_stage, heavy_stage_busy

    time.sleep(0.1 * task)  # the second task arrives while the first holds the stage
    busy = heavy_stage_busy()
    with heavy_stage():
        start = time.monotonic()
        time.sleep(0.4)
        return start, time.monotonic(), busy


def test_local_workers_take_heavy_stages_one_at_a_time():
    results = sorted(r for _, r in execute(_heavy, [0, 1], "local", 2, None, lambda *a: None, lambda: None, []))
    (s0, e0, busy0), (s1, e1, busy1) = results
    assert s1 >= e0  # the second waited for the first
    assert (busy0, busy1) == (False, True)


def test_heavy_stages_run_freely_outside_a_local_pool():
    results = [r for _, r in execute(_heavy, [0], "serial", 1, None, lambda *a: None, lambda: None, [])]
    assert results[0][2] is False
