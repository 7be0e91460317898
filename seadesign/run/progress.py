"""A one-line progress display for sweeps: running candidates and their stage, done/total, ETA."""

from __future__ import annotations

import sys
import time
from typing import TextIO


class ProgressDisplay:
    """Prints to `stream` (stderr): redraws one line on a terminal, one line per finished
    candidate otherwise. The ETA extrapolates the mean time per candidate computed in this run."""

    def __init__(self, total: int, done: int, labels: dict[int, str], quiet: bool = False,
                 stream: TextIO | None = None) -> None:
        self.total, self.done, self.start_done = total, done, done
        self.labels = labels
        self.quiet = quiet
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.running: dict[int, str] = {}
        self.t0 = time.perf_counter()
        if not quiet and done:
            self._print(f"resuming: {done} of {total} candidates already have results")

    def _print(self, text: str) -> None:
        self.stream.write(("\r\033[K" if self.tty else "") + text + ("" if self.tty else "\n"))
        self.stream.flush()

    def eta_s(self) -> float | None:
        computed = self.done - self.start_done
        if computed == 0:
            return None
        return (time.perf_counter() - self.t0) / computed * (self.total - self.done)

    def line(self) -> str:
        eta = self.eta_s()
        eta_text = "ETA --" if eta is None else f"ETA {eta:.0f} s"
        running = ", ".join(f"{self.labels[i]}: {s}" for i, s in sorted(self.running.items()))
        return f"[{self.done}/{self.total} done, {time.perf_counter() - self.t0:.0f} s, {eta_text}] {running}"

    def add_reused(self, n: int) -> None:
        """`n` more tasks done from stored results (not counted in the ETA's time per task)."""
        self.done += n
        self.start_done += n

    def stage(self, index: int, stage: str) -> None:
        self.running[index] = stage
        if not self.quiet and self.tty:
            self._print(self.line())

    def tick(self) -> None:
        if not self.quiet and self.tty:
            self._print(self.line())

    def finished(self, index: int, status: str) -> None:
        self.running.pop(index, None)
        self.done += 1
        if not self.quiet:
            self._print(f"{self.labels.get(index, index)}: {status}  " + self.line())
            if self.tty:
                self.stream.write("\n")

    def close(self) -> None:
        if not self.quiet and self.tty:
            self.stream.write("\n")
