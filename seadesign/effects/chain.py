"""An ordered list of named effects applied one after another to a table of signals.

`run` maps whole arrays (fitting, post-processing); `start` + `step` advance batch-shaped
samples in time (simulators). Only enabled effects act, so a disabled effect leaves no trace:
the result is identical to a chain without it (its random stream is its own, see `effect_rng`).
"""

from __future__ import annotations

import zlib
from typing import Any, Iterable, Mapping

import numpy as np

from seadesign.effects.base import Effect, Signals
from seadesign.errors import ConfigError

Params = Mapping[str, Mapping[str, float]]


def effect_rng(seed: int, name: str) -> np.random.Generator:
    """The random stream of effect `name` under `seed`: independent of every other effect."""
    return np.random.default_rng([int(seed), zlib.crc32(name.encode())])


class EffectChain:
    """Named effects in order. Names are unique; `[name]` gets one."""

    def __init__(self, effects: Iterable[Effect]) -> None:
        self.effects = list(effects)
        names = [e.name for e in self.effects]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise ConfigError(f"effect names must be unique in a chain; repeated: {', '.join(dupes)}")

    def __getitem__(self, name: str) -> Effect:
        for e in self.effects:
            if e.name == name:
                return e
        raise ConfigError(f"no effect named '{name}'; this chain has: {', '.join(self.names())}")

    def __iter__(self):
        return iter(self.effects)

    def names(self) -> list[str]:
        return [e.name for e in self.effects]

    def enabled(self) -> list[Effect]:
        return [e for e in self.effects if e.enabled]

    def configure(self, name: str, enabled: bool | None = None, **values: float) -> "EffectChain":
        """A copy with effect `name` switched and/or re-parameterised."""
        self[name]  # raises with the list of names
        return EffectChain(e.replace(enabled=enabled, **values) if e.name == name else e for e in self.effects)

    def describe(self) -> list[dict[str, Any]]:
        """Every effect (on and off) with its parameters, for metadata."""
        return [e.describe() for e in self.effects]

    def _selected(self, targets: Iterable[str] | None) -> list[Effect]:
        wanted = None if targets is None else set(targets)
        return [e for e in self.enabled() if wanted is None or e.target() in wanted]

    def run(self, signals: Signals, targets: Iterable[str] | None = None, params: Params | None = None,
            seed: int = 0) -> dict[str, np.ndarray]:
        """Apply the enabled effects (those writing one of `targets`, or all) to whole arrays.

        `params` maps effect name -> parameter overrides. Returns a new signal dict.
        """
        out = dict(signals)
        params = params or {}
        for e in self._selected(targets):
            out[e.target()] = e.apply(out, params.get(e.name), effect_rng(seed, e.name) if e.random else None)
        return out

    def start(self, sample: Signals, targets: Iterable[str] | None = None, params: Params | None = None,
              seed: int = 0) -> dict[str, dict[str, Any]]:
        """Per-effect state for time stepping, from the first sample; holds the random streams too."""
        params = params or {}
        states: dict[str, dict[str, Any]] = {}
        for e in self._selected(targets):
            bound = e.replace(**params[e.name]) if e.name in params else e
            states[e.name] = {"effect": bound,
                              "state": bound.init_state(sample) if e.stateful else {},
                              "rng": effect_rng(seed, e.name) if e.random else None}
        return states

    def step(self, states: dict[str, dict[str, Any]], sample: dict[str, np.ndarray], target: str, dt: float) -> np.ndarray:
        """Advance every started effect writing `target` by one step; updates `sample[target]` and returns it."""
        for slot in states.values():
            e = slot["effect"]
            if e.target() == target:
                sample[target] = e.step(slot["state"], sample, dt, None, slot["rng"])
        return sample[target]

    @staticmethod
    def stage(states: dict[str, dict[str, Any]], target: str) -> list[tuple[Any, dict[str, Any], Any]]:
        """(effect, state, rng) of the started effects writing `target`, in order: for tight loops."""
        return [(s["effect"], s["state"], s["rng"]) for s in states.values() if s["effect"].target() == target]
