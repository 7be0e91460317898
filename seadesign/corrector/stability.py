"""Small-signal loop gain of a corrector in the knee simulator, measured as on hardware: break the loop.

1. The knee (noise effects off) is driven open loop by the walk engine's commands u0, the operating
   point, while a copy of the corrector reads its observations (and preview); its commands c0 are
   recorded but not applied.
2. Again with u0 + d, d a seeded random binary sequence of +-`INJECTION_RAD` per trial and knee; the
   corrector's commands c. With the loop broken at the command, c - c0 is the corrector's answer to
   what d did to the knee: the loop's own transfer, -L d.
3. L(f) = -S_dc(f) / S_dd(f) (Welch cross and auto spectra pooled over trials and knees).

The closed loop is stable with margin when 1 + L stays away from 0: the modulus margin
min_f |1 + L(f)| is the distance of the Nyquist curve from -1 (a margin m guarantees a gain margin of at
least 1 / (1 - m) and a phase margin of at least 2 asin(m / 2)). A corrector whose margin is below
`MIN_MODULUS_MARGIN` (0.5: gain margin >= 2, phase margin >= 29 deg) is flagged. A feed-forward corrector
reads no measurement: c = c0, L = 0, margin 1. The gain where L crosses the negative real axis must
stay below `MIN_MODULUS_MARGIN` too (gain margin >= 2): a high-gain loop can circle -1 at a distance.
The coherence at the worst frequency says how linear the corrector's answer is (1: fully).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from scipy.signal import csd, welch

from seadesign.corrector.closedloop import Driver, needs_aux
from seadesign.corrector.ilc import NOISE_EFFECTS
from seadesign.corrector.runtime import Corrector
from seadesign.effects import effect_rng
from seadesign.twin import KneeConfig, KneeSession, Trial, knee_effects

INJECTION_RAD = 0.01
MIN_MODULUS_MARGIN = 0.5
SEGMENT_STEPS = 128  # Welch segment: 0.78 Hz resolution at 100 Hz


@dataclass
class LoopGain:
    """L(f) at `frequency_hz` (complex, 1) and the coherence of its estimate (1)."""

    name: str
    frequency_hz: np.ndarray
    loop_gain: np.ndarray
    coherence: np.ndarray

    @property
    def modulus_margin(self) -> float:
        """min_f |1 + L(f)| over frequencies above 0 (1)."""
        return float(np.min(np.abs(1.0 + self.loop_gain[1:])))

    @property
    def peak_gain(self) -> float:
        """max_f |L(f)| (1)."""
        return float(np.max(np.abs(self.loop_gain[1:])))

    @property
    def crossover_gain(self) -> float:
        """Largest |L| where L crosses the negative real axis (1; 0 if it never does): 1 / gain margin."""
        L = self.loop_gain[1:]
        i = np.flatnonzero((np.sign(L.imag[:-1]) != np.sign(L.imag[1:])) & (L.real[:-1] < 0) & (L.real[1:] < 0))
        if not len(i):
            return 0.0
        w = L.imag[i] / (L.imag[i] - L.imag[i + 1])
        return float(np.max(np.abs(L[i] + w * (L[i + 1] - L[i]))))

    @property
    def flagged(self) -> bool:
        """True unless the modulus margin is at least `MIN_MODULUS_MARGIN` and the gain margin at least
        1 / MIN_MODULUS_MARGIN (an L that passes -1 on the wrong side can keep its distance from it)."""
        return not (self.modulus_margin >= MIN_MODULUS_MARGIN and self.crossover_gain <= MIN_MODULUS_MARGIN)

    def row(self) -> dict[str, Any]:
        i = int(np.argmin(np.abs(1.0 + self.loop_gain[1:]))) + 1
        return {"modulus_margin": self.modulus_margin, "margin_at_hz": float(self.frequency_hz[i]),
                "margin_coherence": float(self.coherence[i]), "crossover_gain": self.crossover_gain,
                "loop_gain_peak": self.peak_gain, "loop_gain_flag": self.flagged}


def measure_loop_gain(corrector: Corrector, spring: dict[str, Any], trials: list[Trial], ground: bool = False,
                      rate_hz: float = 100.0, seed: int = 0, **session: Any) -> LoopGain:
    """Break the loop at the command and measure L(f) (module doc); `session` as KneeSession takes it."""
    chain = session.pop("effects", None) or knee_effects(KneeConfig.from_spring(spring), ground)
    for name in NOISE_EFFECTS:
        chain = chain.configure(name, enabled=False)
    sims = [KneeSession(spring, trials, ground=ground, rate_hz=rate_hz, seed=seed, effects=chain, **session)
            for _ in range(2)]
    c0 = sims[0].target.copy()  # the operating point: the knee driven by the walk engine's commands
    d = INJECTION_RAD * np.sign(effect_rng(seed, "loop_gain_injection").uniform(-1.0, 1.0, c0.shape))
    answers = []
    for sim, injected in zip(sims, (np.zeros_like(c0), d)):
        driver, answer = Driver(corrector, sim), np.empty_like(c0)
        obs = sim.observe()
        while obs is not None:
            answer[:, obs.step] = driver.commands(obs)
            obs = sim.step(c0[:, obs.step] + injected[:, obs.step])
        answers.append(answer)
    n = c0.shape[1]
    answer, c0 = answers[1], answers[0]
    dd = d.transpose(0, 2, 1).reshape(-1, n)
    dc = (answer - c0).transpose(0, 2, 1).reshape(-1, n)
    f, s_dc = csd(dd, dc, fs=rate_hz, nperseg=SEGMENT_STEPS, axis=-1)
    _, s_dd = welch(dd, fs=rate_hz, nperseg=SEGMENT_STEPS, axis=-1)
    _, s_cc = welch(dc, fs=rate_hz, nperseg=SEGMENT_STEPS, axis=-1)
    s_dc, s_dd, s_cc = s_dc.sum(0), s_dd.sum(0), s_cc.sum(0)
    coherence = np.abs(s_dc) ** 2 / np.maximum(s_dd * s_cc, 1e-300)
    return LoopGain(corrector.name, f, -s_dc / s_dd, np.where(s_cc > 0, coherence, 1.0))


def loop_gain_table(correctors: list[Corrector], spring: dict[str, Any], settings: tuple[str, ...],
                    trials: list[Trial], rate_hz: float = 100.0, seed: int = 0) -> pd.DataFrame:
    """One row per corrector and setting: modulus margin, its frequency and coherence, crossover gain, flag
    (correctors that need IMU or foot-pressure inputs, which the simulator lacks, are left out)."""
    rows = [{"candidate": c.name, "setting": setting,
             **measure_loop_gain(c, spring, trials, setting == "ground", rate_hz, seed).row()}
            for setting in settings for c in correctors if not needs_aux(c)]
    return pd.DataFrame(rows)
