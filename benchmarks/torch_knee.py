"""Speed of the differentiable torch knee in training windows: simulated steps per second.

Run: python benchmarks/torch_knee.py [--windows 100 200] [--threads 1 2] [--repeats 3]. Prints a table with
the machine and settings. One step = one 10 ms sample of the whole batch (36 knees: the thesis protocol's
18 trials x 2 knees) with all substeps, default effects on the ground (noise drawn, quantisation straight-through),
the command = the walk target plus a learnable offset per knee; forward = the window's rollout without a graph,
forward+backward = the rollout with its graph and the backward pass of the mean squared Hall error.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import torch

from seadesign import __version__
from seadesign.design.spring import load_spring
from seadesign.twin import KneeConfig, knee_effects, thesis_protocol
from seadesign.twin.torch_knee import TorchKnee, protocol_tensors, rollout
from record import machine

SPRING = load_spring(Path(__file__).resolve().parents[1] / "studies" / "thesis_measured_spring.json")


def steps_per_s(knee: TorchKnee, target: torch.Tensor, stance: torch.Tensor, window: int, backward: bool,
                repeats: int) -> float:
    """Best of `repeats` windows starting at sample 100 (walking): simulated steps per second."""
    offset = torch.zeros(2, dtype=target.dtype, requires_grad=backward)
    knee.reset(target[:, 0], stance[:, 0])
    with torch.no_grad():
        rollout(knee, lambda obs, k: target[:, k], stance, 100)
    start = knee.state()
    best = float("inf")
    for _ in range(repeats):
        knee.load_state(start)
        t0 = time.perf_counter()
        with torch.set_grad_enabled(backward):
            out = rollout(knee, lambda obs, k: target[:, k] + offset, stance, window)
            if backward:
                ((out["hall_rad"] - target[:, 100:100 + window]) ** 2).mean().backward()
        best = min(best, time.perf_counter() - t0)
    return window / best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--windows", type=int, nargs="+", default=[100, 200], help="window lengths, samples")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="torch intra-op threads")
    parser.add_argument("--repeats", type=int, default=3, help="timed windows per setting (best is kept)")
    args = parser.parse_args()
    trials = thesis_protocol(10.0)
    cfg = KneeConfig.from_spring(SPRING)
    print(f"machine: {machine()}; torch {torch.__version__}, seadesign {__version__}")
    print(f"settings: batch {len(trials)} trials x 2 knees, 100 Hz, ground, default effects, noise on; "
          f"best of {args.repeats}")
    print(f"{'dtype':>8} {'threads':>7} {'window':>6} {'forward steps/s':>16} {'fwd+bwd steps/s':>16}")
    for dtype in (torch.float32, torch.float64):
        _, target, stance = protocol_tensors(trials, dtype=dtype)
        knee = TorchKnee(cfg, knee_effects(cfg, ground=True), dtype=dtype, noise=True)
        for threads in args.threads:
            torch.set_num_threads(threads)
            for window in args.windows:
                fwd = steps_per_s(knee, target, stance, window, False, args.repeats)
                both = steps_per_s(knee, target, stance, window, True, args.repeats)
                print(f"{str(dtype).removeprefix('torch.'):>8} {threads:>7} {window:>6} {fwd:>16.0f} {both:>16.0f}",
                      flush=True)


if __name__ == "__main__":
    main()
