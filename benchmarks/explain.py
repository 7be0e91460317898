"""Wall time of `explain` on a 10-minute, 100 Hz recording (goal: under 30 s).

A bench test of the thesis spring (k = 9.106 Nm/rad, 0.05 Hz sine) simulated with a stiffness
error and a dead-band, explained with the plain linear spring. Prints a table with the machine
and settings. Run: python benchmarks/explain.py [--duration-s 600] [--rate-hz 100]
"""

from __future__ import annotations

import argparse
import os
import platform
import time

from seadesign.loop import explain
from seadesign.loop.sea import bench_loop_data
from seadesign.twin import BenchProtocol, bench_effects, simulate_bench

K = 9.106


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration-s", type=float, default=600.0, help="recording length (s)")
    ap.add_argument("--rate-hz", type=float, default=100.0, help="sample rate (Hz)")
    args = ap.parse_args()
    chain = bench_effects(K).configure("stiffness_scale", enabled=True, scale=0.8).configure(
        "dead_band", enabled=True, width_rad=0.03)
    protocol = BenchProtocol(duration_s=args.duration_s, rate_hz=args.rate_hz)
    table, _ = simulate_bench({"k_Nm_per_rad": K}, protocol, effects=chain, seed=0)
    data = bench_loop_data(table, {"k_Nm_per_rad": K})
    t0 = time.perf_counter()
    ex = explain(data)
    wall = time.perf_counter() - t0
    rows = [
        ("machine", f"{platform.machine()} {platform.processor() or ''}".strip()),
        ("cpus visible", str(os.cpu_count())),
        ("python", platform.python_version()),
        ("samples", f"{data.n} ({args.duration_s:g} s at {args.rate_hz:g} Hz)"),
        ("candidates", str(len(ex.settings["candidates"]))),
        ("effects found", ", ".join(ex.found) or "none"),
        ("held-out RMSE (Nm)", f"{ex.plain.errors['held_out']['rmse']:.4g} -> {ex.final.errors['held_out']['rmse']:.4g}"),
        ("wall time (s)", f"{wall:.2f} (goal < 30)"),
    ]
    width = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"{k:<{width}}  {v}")


if __name__ == "__main__":
    main()
