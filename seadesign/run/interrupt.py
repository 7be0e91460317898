"""Stopping a long job when asked: SIGINT (Ctrl-C, sent to the whole process group) and SIGTERM
(what a job scheduler sends to the main process) both end it within about a second.

`stop_on_signals` turns either signal in the main process into `Interrupted`; the executors then
cancel what is pending, kill their worker processes and everything those started (meshers), and
remove the temporary files the killed processes were writing, so no half-written row or cache
entry is left (finished rows and entries are written by rename, whole or not at all).
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from pathlib import Path

import psutil

EXIT_CODES = {"SIGINT": 130, "SIGTERM": 143}  # 128 + signal number, as shells report them


class Interrupted(KeyboardInterrupt):
    """The job was asked to stop by a signal (name in `.signal`)."""

    def __init__(self, signal_name: str) -> None:
        super().__init__(signal_name)
        self.signal = signal_name

    @property
    def exit_code(self) -> int:
        return EXIT_CODES.get(self.signal, 1)


@contextlib.contextmanager
def stop_on_signals():
    """Within the block, SIGINT and SIGTERM raise `Interrupted` in the main thread (no-op elsewhere)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        raise Interrupted(signal.Signals(signum).name)

    previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def ignore_sigint() -> None:
    """Worker-process initializer: Ctrl-C reaches the whole process group, but only the main process
    decides; it stops the workers itself."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def kill_trees(pids: list[int], timeout_s: float = 1.0) -> list[int]:
    """Kill processes and all their descendants (SIGKILL) and wait until each is dead; returns
    every pid killed. Dead children are left for their owners to reap (multiprocessing and Dask
    wait on them; reaping here would leave those waits hanging)."""
    procs = []
    for pid in pids:
        with contextlib.suppress(psutil.NoSuchProcess):
            root = psutil.Process(pid)
            procs += root.children(recursive=True) + [root]
    for p in procs:
        with contextlib.suppress(psutil.NoSuchProcess):
            p.kill()
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and any(_running(p) for p in procs):
        time.sleep(0.01)
    return [p.pid for p in procs]


def _running(p: psutil.Process) -> bool:
    try:
        return p.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def remove_partial_files(folders: list[Path], pids: list[int]) -> int:
    """Delete `*.<pid>.tmp` files (an atomic write in progress) of killed processes; returns the count."""
    removed = 0
    for folder in folders:
        for pid in pids:
            for tmp in Path(folder).rglob(f"*.{pid}.tmp"):
                with contextlib.suppress(FileNotFoundError):
                    tmp.unlink()
                    removed += 1
    return removed
