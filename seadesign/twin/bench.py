"""The bench simulator: a torque-deflection test of a spring, written in the bench format.

The bench drives the spring's deflection (servo position control against a fixed
force/torque sensor, thesis sec. 6.4) along a slow sine or triangular ramp whose amplitude
is chosen so that the plain linear spring would reach `torque_amplitude_Nm`; the sensor
records the torque the spring (with its effects) transmits plus the bench's friction. The
Hall-side sensor effects act on the recorded deflection, `torque_noise` on the torque.
Everything is vectorised over the whole record (`EffectChain.run`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from seadesign import __version__
from seadesign.effects import EffectChain
from seadesign.errors import ConfigError
from seadesign.design.spring import TorqueCurve, load_spring, torque_curve
from seadesign.twin.config import bench_effects

PROFILES = ("sine", "ramp")


@dataclass(frozen=True)
class BenchProtocol:
    """Drive profile: `sine` or `ramp` (triangle), peak torque (Nm) of the linear spring,
    frequency (Hz), duration (s), sample rate (Hz)."""

    profile: str = "sine"
    torque_amplitude_Nm: float = 4.8
    frequency_hz: float = 0.05
    duration_s: float = 120.0
    rate_hz: float = 100.0

    def __post_init__(self) -> None:
        if self.profile not in PROFILES:
            raise ConfigError(f"bench profile '{self.profile}' is unknown; use one of {', '.join(PROFILES)}")
        for name in ("torque_amplitude_Nm", "frequency_hz", "duration_s", "rate_hz"):
            if not getattr(self, name) > 0:
                raise ConfigError(f"bench {name} = {getattr(self, name)} must be positive")


def drive(protocol: BenchProtocol, k_Nm_per_rad: float, curve: TorqueCurve | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Time (s) and driven deflection (rad) of the protocol: the amplitude is the rotation at which the spring
    (the torque curve when given, else k) carries the torque amplitude (a CurveRangeError past the curve's end)."""
    time = np.arange(int(round(protocol.duration_s * protocol.rate_hz))) / protocol.rate_hz
    phase = protocol.frequency_hz * time
    if protocol.profile == "sine":
        shape = np.sin(2 * np.pi * phase)
    else:
        shape = 2.0 / np.pi * np.arcsin(np.sin(2 * np.pi * phase))  # triangle, same peaks and zeros
    amplitude = protocol.torque_amplitude_Nm / k_Nm_per_rad if curve is None else \
        float(curve.rotation(protocol.torque_amplitude_Nm))
    return time, amplitude * shape


def simulate_bench(spring: dict[str, Any] | str | Path, protocol: BenchProtocol = BenchProtocol(), *,
                   effects: EffectChain | None = None, seed: int = 0) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Simulate a bench test of the spring in `spring` (dict or spring.json path); return (table, metadata).

    The table has the bench format's columns `time_s, torque_Nm, deflection_rad`.
    """
    spring = load_spring(spring) if isinstance(spring, (str, Path)) else spring
    k, curve = float(spring["k_Nm_per_rad"]), torque_curve(spring)
    chain = effects if effects is not None else bench_effects(k, curve)
    time, deflection = drive(protocol, k, curve)
    signals = {"time": time, "deflection": deflection, "deflection_rate": np.gradient(deflection, time)}
    path = chain.run(signals, targets=("deflection", "torque"), seed=seed)
    sensed = chain.run({"time": time, "hall": deflection, "torque_sensor": path["torque"]},
                       targets=("hall", "torque_sensor"), seed=seed)
    table = pd.DataFrame({"time_s": time, "torque_Nm": sensed["torque_sensor"], "deflection_rad": sensed["hall"]})
    meta = {
        "format": "seadesign simulated bench test",
        "simulator": "seadesign.twin.bench",
        "versions": {"seadesign": __version__, "numpy": np.__version__, "pandas": pd.__version__},
        "seed": seed,
        "protocol": asdict(protocol),
        "spring": {"study": spring.get("study"), "k_Nm_per_rad": k, "k_source": spring.get("k_source"),
                   "inputs_hash": spring.get("inputs_hash")},
        "effects": chain.describe(),
        "effects_enabled": [e.name for e in chain.enabled()],
    }
    return table, meta
