"""Wall time of `explain` on a 10-minute, 100 Hz recording (goal: under 30 s).

Two recordings of the thesis spring (k = 9.106 Nm/rad), each explained with the plain model:

- bench: a 0.05 Hz sine bench test simulated with a stiffness error (x 0.8) and a 0.03 rad
  dead-band; torque predicted from deflection (stiffness direction);
- robot: the knee simulator walking forward at 0.2 m/s on the ground (left knee) with a
  stiffness error (x 0.8) and a 0.02 rad Hall offset; Hall angle predicted from motor angle and
  effort with the declared backlash and gear friction, refitted (compliance direction).

Also: the change-point search of a sensor step (`best_split`) against the ruptures library's Binseg
(L2 cost, one break) on the same number of samples, in the same process.

Prints one table with the machine and settings. Run:
python benchmarks/explain.py [--duration-s 600] [--rate-hz 100] [--kind bench|robot|both]
"""

from __future__ import annotations

import argparse
import time

from seadesign.calibration import LoopData, explain
from seadesign.calibration.changepoint import best_split
from seadesign.calibration.sea import bench_loop_data, robot_declared, robot_loop_data
from seadesign.twin import BenchProtocol, KneeConfig, Trial, bench_effects, knee_effects, simulate, simulate_bench
from simulate import SPRING  # the benchmarks' spring.json payload (thesis spring, Wolfgang-OP knee)
from record import machine

K = SPRING["k_Nm_per_rad"]


def bench(duration_s: float, rate_hz: float) -> tuple[LoopData, list]:
    chain = bench_effects(K).configure("stiffness_scale", enabled=True, scale=0.8).configure(
        "dead_band", enabled=True, width_rad=0.03)
    table, _ = simulate_bench({"k_Nm_per_rad": K}, BenchProtocol(duration_s=duration_s, rate_hz=rate_hz),
                              effects=chain, seed=0)
    return bench_loop_data(table, {"k_Nm_per_rad": K}), []


def robot(duration_s: float, rate_hz: float) -> tuple[LoopData, list]:
    chain = knee_effects(KneeConfig.from_spring(SPRING), ground=True).configure(
        "stiffness_scale", enabled=True, scale=0.8).configure("hall_offset", enabled=True, offset_rad=0.02)
    table, _ = simulate(SPRING, [Trial("front", 0.2, duration_s)], ground=True, effects=chain, rate_hz=rate_hz, seed=0)
    return robot_loop_data(table, SPRING, "l"), robot_declared(SPRING)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration-s", type=float, default=600.0, help="recording length (s)")
    ap.add_argument("--rate-hz", type=float, default=100.0, help="sample rate (Hz)")
    ap.add_argument("--kind", choices=["bench", "robot", "both"], default="both")
    args = ap.parse_args()
    print(f"machine: {machine()}; {args.duration_s:g} s at {args.rate_hz:g} Hz; "
          f"load reference (a 1500 x 1500 matrix product, same process): {reference():.3f} s")
    print(f"{'recording':<10} {'samples':>8} {'candidates':>10}  {'effects found':<32} {'held-out RMSE':<26} "
          f"{'wall time (s), goal < 30':>24}")
    for kind in (["bench", "robot"] if args.kind == "both" else [args.kind]):
        data, declared = (bench if kind == "bench" else robot)(args.duration_s, args.rate_hz)
        t0 = time.perf_counter()
        ex = explain(data, declared)
        wall = time.perf_counter() - t0
        rmse = (f"{ex.plain.errors['held_out']['rmse']:.4g} -> {ex.final.errors['held_out']['rmse']:.4g} "
                f"{data.measured_unit}")
        print(f"{kind:<10} {data.n:>8} {len(ex.settings['candidates']):>10}  {', '.join(ex.found) or 'none':<32} "
              f"{rmse:<26} {wall:>24.2f}")
    changepoints(int(args.duration_s * args.rate_hz))


def reference() -> float:
    """Wall time (s) of a fixed matrix product: how busy the machine is (the explain times scale with it)."""
    import numpy as np
    a = np.random.default_rng(0).normal(size=(1500, 1500))
    t0 = time.perf_counter()
    a @ a
    return time.perf_counter() - t0


def changepoints(n: int) -> None:
    """best_split against ruptures' Binseg (one break, L2) on n samples: same index, wall times."""
    import numpy as np
    try:
        import ruptures
    except ImportError:
        print("change points: ruptures is not installed (pip install ruptures) - comparison skipped")
        return
    x = np.random.default_rng(0).normal(0, 0.01, n)
    x[n // 3:] += 0.02
    t0 = time.perf_counter()
    ours = best_split(x, min_size=50)
    t1 = time.perf_counter()
    ref = ruptures.Binseg(model="l2", min_size=50, jump=1).fit(x).predict(n_bkps=1)[0]
    t2 = time.perf_counter()
    print(f"change point on {n} samples: best_split index {ours} in {t1 - t0:.4f} s, ruptures Binseg index {ref} in "
          f"{t2 - t1:.2f} s ({(t2 - t1) / max(t1 - t0, 1e-9):.0f}x)")


if __name__ == "__main__":
    main()
