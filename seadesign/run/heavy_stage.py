"""One memory-heavy stage at a time across a local pool's workers.

The linear load cases on the result mesh hold the largest factorization of a sweep (about 1.1 GiB for the 462k
unknowns of the default study's 8 x 4 mm part, in mixed precision); two workers factoring at once double it. A
local pool gives each worker one shared lock (`install`); `heavy_stage` holds it around such a stage, and
`heavy_stage_busy` lets a worker do other work first while another one holds it. Outside a local pool (serial
runs, Dask workers) there is no lock and both are no-ops.
"""

from __future__ import annotations

import contextlib
from typing import Iterator

_lock = None  # the pool's shared lock, installed in each worker by the executor


def install(lock) -> None:
    """Share `lock` (a multiprocessing lock, or None) among this process's heavy stages."""
    global _lock
    _lock = lock


@contextlib.contextmanager
def heavy_stage() -> Iterator[None]:
    """Hold the pool's lock while the block runs (waiting for another worker's heavy stage to end)."""
    if _lock is None:
        yield
        return
    with _lock:
        yield


def heavy_stage_busy() -> bool:
    """Whether another worker is in a heavy stage now (a hint for ordering work: it may change at once)."""
    if _lock is None:
        return False
    if _lock.acquire(block=False):
        _lock.release()
        return False
    return True
