"""Cold and warm wall time of a full sweep (default study) and peak memory.

Cold: empty cache and no stored rows. Warm: the same command again (rows reused). Each run is
the `seadesign sweep` command in a child process, so its import time is counted and its peak
resident memory (the largest of the process and its workers) is measured.

Usage: python benchmarks/sweep.py [STUDY] [--jobs N]
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from record import machine


def timed_sweep(study: str, jobs: int, out: Path, cache: Path) -> tuple[float, float]:
    """(wall s, peak RSS MiB of the largest child) of one `seadesign sweep` run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.perf_counter()
    subprocess.run([str(Path(sys.executable).parent / "seadesign"), "sweep", study, "--jobs", str(jobs), "--quiet",
                    "--out", str(out), "--cache-dir", str(cache)], check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return wall, max(peak, before) / 1024.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", nargs="?", default="wolfgang_knee")
    ap.add_argument("--jobs", type=int, default=len(os.sched_getaffinity(0)), help="worker processes (count)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="seadesign-bench-") as d:
        out, cache = Path(d) / "exports", Path(d) / "cache"
        cold = timed_sweep(args.study, args.jobs, out, cache)
        warm = timed_sweep(args.study, args.jobs, out, cache)
    print(f"machine: {machine()}")
    print(f"settings: study {args.study}, jobs {args.jobs}")
    print(f"{'run':<6} {'wall_s':>8} {'peak_rss_MiB':>13}")
    for name, (wall, rss) in (("cold", cold), ("warm", warm)):
        print(f"{name:<6} {wall:>8.1f} {rss:>13.0f}")


if __name__ == "__main__":
    main()
