"""Simulators that make data from a spring.json: the knee (robot format) and the bench.

Public API (stable):

- `KneeSession(spring, trials, ground=, rate_hz=, seed=, effects=, config=)`: step-wise knee
  simulation of a batch of trials; closed loop via `observe()` / `step(command)` / `run(controller)`;
  `recording()` returns the robot-format table, `metadata()` the sidecar dict (effects declared).
- `simulate(spring, trials, **options) -> (table, metadata)`: the same, walk target relayed.
- `Trial`, `thesis_protocol(duration_s, repeats)`, `DIRECTIONS`, `SPEEDS`, `Gait`: the walk protocol.
- `KneeConfig`, `knee_effects(cfg, ground)`, `bench_effects(k, curve)`, `configure_chain(chain, options)`.
- `BenchProtocol`, `simulate_bench(spring, protocol, effects=, seed=) -> (table, metadata)`.
- `seadesign.twin.torch_knee` (imported from its module, it loads torch): `TorchKnee`, the knee simulator
  in differentiable PyTorch built from the same config and effect chain, with `rollout` and `protocol_tensors`
  for training through the closed loop.

Simulated tables are written with `seadesign.data.write_recording` / `write_bench` and the
metadata as the `<name>.meta.json` sidecar.
"""

from seadesign.twin.bench import BenchProtocol, simulate_bench
from seadesign.twin.config import KneeConfig, bench_effects, configure_chain, knee_effects, parse_effect_option
from seadesign.twin.knee import Controller, KneeSession, Observation, simulate
from seadesign.twin.walk import DIRECTIONS, SPEEDS, Gait, Trial, knee_targets, thesis_protocol

__all__ = [
    "DIRECTIONS", "SPEEDS", "BenchProtocol", "Controller", "Gait", "KneeConfig", "KneeSession", "Observation",
    "Trial", "bench_effects", "configure_chain", "knee_effects", "knee_targets", "parse_effect_option",
    "simulate", "simulate_bench", "thesis_protocol",
]
