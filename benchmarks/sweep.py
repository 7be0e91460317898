"""Cold and warm wall time of a full sweep (default study) and peak memory.

Cold: empty cache and no stored rows. Warm: the same command again (rows reused). Each run is
the `seadesign sweep` command in a child process, so its import time is counted, and its peak resident memory
is sampled every 0.2 s (a shorter peak can be missed) three ways: the largest single process (the command or one of
its workers, resident set), the resident sets summed over the command and all its descendants (which counts the
pages of shared libraries once per process), and their proportional set sizes summed (each shared page split among
the processes that map it: the memory the run takes from the machine).

Usage: python benchmarks/sweep.py [STUDY] [--jobs N] [--keep DIR]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import psutil

from record import machine


def timed_sweep(study: str, jobs: int, out: Path, cache: Path) -> tuple[float, float, float, float]:
    """(wall s, peak RSS MiB of one process, peak of the RSS MiB and of the PSS MiB summed over the command and its
    descendants) of one `seadesign sweep` run."""
    t0 = time.perf_counter()
    run = subprocess.Popen([str(Path(sys.executable).parent / "seadesign"), "sweep", study, "--jobs", str(jobs),
                            "--quiet", "--out", str(out), "--cache-dir", str(cache)], stdout=subprocess.DEVNULL)
    command, one, total, share = psutil.Process(run.pid), 0.0, 0.0, 0.0
    while run.poll() is None:
        rss, pss = _tree_memory(command)
        one, total, share = max([one, *rss]), max(total, sum(rss)), max(share, sum(pss))
        time.sleep(0.2)
    wall = time.perf_counter() - t0
    if run.returncode:
        raise SystemExit(f"seadesign sweep failed with exit code {run.returncode}")
    return wall, one / 2**20, total / 2**20, share / 2**20


def _tree_memory(command: psutil.Process) -> tuple[list[float], list[float]]:
    """Resident and proportional set sizes (bytes) of the command and each of its descendants now (those that end
    while read are left out)."""
    rss, pss = [], []
    try:
        processes = [command] + command.children(recursive=True)
    except psutil.NoSuchProcess:
        return rss, pss
    for p in processes:
        try:
            m = p.memory_full_info()
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
        rss.append(float(m.rss))
        pss.append(float(m.pss))
    return rss, pss


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", nargs="?", default="wolfgang_knee")
    ap.add_argument("--jobs", type=int, default=len(os.sched_getaffinity(0)), help="worker processes (count)")
    ap.add_argument("--keep", type=Path, default=None, help="an empty or new directory that keeps the outputs "
                    "(exports/) and the stage cache (cache/); default: a temporary one, removed")
    args = ap.parse_args()
    if args.keep is not None and args.keep.exists() and any(args.keep.iterdir()):
        raise SystemExit(f"--keep {args.keep} is not empty: a cold run needs an empty cache; give a new directory")
    with tempfile.TemporaryDirectory(prefix="seadesign-bench-") as d:
        root = Path(d) if args.keep is None else args.keep
        out, cache = root / "exports", root / "cache"
        cold = timed_sweep(args.study, args.jobs, out, cache)
        warm = timed_sweep(args.study, args.jobs, out, cache)
    print(f"machine: {machine()}")
    print(f"settings: study {args.study}, jobs {args.jobs}")
    print(f"{'run':<6} {'wall_s':>8} {'peak_rss_one_process_MiB':>25} {'peak_rss_all_processes_MiB':>27} "
          f"{'peak_pss_all_processes_MiB':>27}")
    for name, (wall, rss, total, share) in (("cold", cold), ("warm", warm)):
        print(f"{name:<6} {wall:>8.1f} {rss:>25.0f} {total:>27.0f} {share:>27.0f}")


if __name__ == "__main__":
    main()
