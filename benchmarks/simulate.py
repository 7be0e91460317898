"""Wall time of the knee simulator for one hour of 100 Hz data, both knees (goal: < 10 s).

Run: python benchmarks/simulate.py [--hours H]. Prints a table with the machine and settings.
The hour is split into parallel trials (the thesis protocol repeated); each layout simulates
the same number of samples.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path


from seadesign import __version__
from seadesign.design.spring import load_spring
from seadesign.twin import KneeSession, thesis_protocol
from record import machine

SPRING = load_spring(Path(__file__).resolve().parents[1] / "studies" / "thesis_measured_spring.json")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--hours", type=float, default=1.0, help="simulated hours per layout")
    parser.add_argument("--rate-hz", type=float, default=100.0, help="sample rate, Hz")
    args = parser.parse_args()
    total_s = args.hours * 3600.0
    print(f"machine: {machine()}; seadesign {__version__}")
    print(f"settings: {args.hours:g} h at {args.rate_hz:g} Hz, both knees, default effects; ground and hanging")
    print(f"{'layout':32s} {'mode':8s} {'samples/knee':>12s} {'substeps':>8s} {'wall s':>8s} {'x real time':>11s}")
    for trial_s in (10.0, 50.0, 200.0):
        repeats = max(1, round(total_s / (18 * trial_s)))
        for ground in (False, True):
            session = KneeSession(SPRING, thesis_protocol(trial_s, repeats), ground=ground, rate_hz=args.rate_hz, seed=0)
            start = time.perf_counter()
            df = session.run()
            wall = time.perf_counter() - start
            layout = f"{18 * repeats} trials x {trial_s:g} s"
            sim_s = len(df) / args.rate_hz
            print(f"{layout:32s} {'ground' if ground else 'hanging':8s} {len(df):12d} {session.n_sub:8d} "
                  f"{wall:8.2f} {sim_s / wall:11.0f}")


if __name__ == "__main__":
    main()
