"""Atomic file writes: a file is written whole under a temporary name and renamed into place, so
a reader (or a rerun after Ctrl-C) sees the old file or the new one, never half of one.

The temporary name ends in `.<pid>.tmp`; the writer removes it when it fails or is interrupted,
and `interrupt.remove_partial_files` removes those of processes that were killed.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable


def atomic_write(path: str | Path, write: Callable[[Path], object]) -> Path:
    """Call `write(tmp)` to write the content, then rename tmp onto `path` (parents created)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        write(tmp)
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)
    return path
