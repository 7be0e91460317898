"""Inputs of the feed-forward corrector: a window of the reference trajectory, never a measurement.

At control step t the network sees, in knee flexion (the right knee mirrored, so both knees
look alike), with `past` and `preview` steps at the control rate:

- `target_rad`: the target at t;
- `target_rad@t-i` - target(t) for i = past ... 1 and `target_rad@t+i` - target(t) for i = 1 ... preview
  (the walk engine's trajectory around t, relative to now);
- `load_share@t+i` for i = -past ... preview: the leg's expected share of the body weight (0 in
  swing and whenever the robot hangs), from the walk engine's support phase;
- `k_Nm_per_rad`: the spring's stiffness from spring.json.

Before a trial's start the window holds the first value, after its end the last one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from seadesign.errors import SeadesignError


@dataclass(frozen=True)
class ReferenceWindow:
    """How much trajectory the network sees: `past` and `preview` steps at the control rate."""

    past: int = 5
    preview: int = 10

    def __post_init__(self) -> None:
        if self.past < 0 or self.preview < 0:
            raise SeadesignError(f"reference window past/preview must be >= 0 steps, got {self.past}/{self.preview}")

    @property
    def offsets(self) -> np.ndarray:
        """Step offsets of the window, -past ... preview."""
        return np.arange(-self.past, self.preview + 1)

    def feature_names(self) -> tuple[str, ...]:
        """Input names in order."""
        rel = [f"target_rad@t{o:+d}" for o in self.offsets if o != 0]
        load = [f"load_share@t{o:+d}" if o else "load_share" for o in self.offsets]
        return ("target_rad", *rel, *load, "k_Nm_per_rad")

    def to_dict(self) -> dict[str, int]:
        return {"past": self.past, "preview": self.preview}


def _windows(x: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """x (..., n) -> (..., n, len(offsets)): x[t + o], clamped to the ends."""
    n = x.shape[-1]
    idx = np.clip(np.arange(n)[:, None] + offsets[None, :], 0, n - 1)
    return x[..., idx]


def reference_features(target_rad: np.ndarray, load_share: np.ndarray, k_Nm_per_rad: float,
                       window: ReferenceWindow) -> np.ndarray:
    """Inputs for every step of whole trajectories: target and load share (..., n) in flexion -> (..., n, d)."""
    off = window.offsets
    tw, lw = _windows(target_rad, off), _windows(load_share, off)
    rel = tw[..., off != 0] - target_rad[..., None]
    k = np.full(target_rad.shape + (1,), float(k_Nm_per_rad))
    return np.concatenate([target_rad[..., None], rel, lw, k], axis=-1)


@dataclass(frozen=True)
class Preview:
    """What the walk engine knows ahead, robot frame: the next targets t+1 ... (rad) and this leg's load share
    at t, t+1, ... (1)."""

    target_rad: np.ndarray
    load_share: np.ndarray


_NO_LOAD = np.zeros(1)


class ReferenceBuffer:
    """One knee's window built online: `features` at each step with the preview ahead.

    The preview arrives with each step (the walk engine's next `preview` targets and the load share
    at t ... t+preview); past targets and load shares are kept here. Values in flexion. Preallocated
    (one control step: a few microseconds besides the network).
    """

    def __init__(self, window: ReferenceWindow, k_Nm_per_rad: float) -> None:
        self.window, self.k = window, float(k_Nm_per_rad)
        p, f = window.past, window.preview
        self._x = np.empty(len(window.feature_names()))
        self._x[-1] = self.k
        self._past_t, self._past_l = np.empty(p), np.empty(p)
        self._started = False
        self._rel = slice(1, 1 + p + f)
        self._load = slice(1 + p + f, 2 + 2 * p + 2 * f)

    def features(self, target_rad: float, preview_rad: np.ndarray, load_share: np.ndarray) -> np.ndarray:
        """Input vector at this step; `preview_rad` (t+1 ..., up to `preview` values used) and `load_share`
        (t, t+1, ...; none: 0, no load known), each padded with its last value to the window. The returned
        array is reused by the next call."""
        p, f = self.window.past, self.window.preview
        x = self._x
        if not len(load_share):
            load_share = _NO_LOAD
        if not self._started:
            self._past_t[:], self._past_l[:] = target_rad, load_share[0]
            self._started = True
        rel, load = x[self._rel], x[self._load]
        rel[:p] = self._past_t
        n = min(len(preview_rad), f)
        rel[p: p + n] = preview_rad[:n]
        rel[p + n:] = preview_rad[n - 1] if n else target_rad
        rel -= target_rad
        load[:p] = self._past_l
        m = min(len(load_share), f + 1)
        load[p: p + m] = load_share[:m]
        load[p + m:] = load_share[m - 1]
        x[0] = target_rad
        if p:
            self._past_t[:-1], self._past_t[-1] = self._past_t[1:], target_rad
            self._past_l[:-1], self._past_l[-1] = self._past_l[1:], load_share[0]
        return x


def knee_window(buffer: ReferenceBuffer, sign: float, target_rad: float, preview: Preview | None,
                name: str) -> tuple[float, np.ndarray]:
    """A corrector's step in flexion: the target (rad, robot frame x `sign`) and the window's features from the
    walk engine's `preview` (robot frame); a clear error naming corrector `name` when there is none."""
    if preview is None:
        raise SeadesignError(f"corrector '{name}' needs the walk engine's preview of {buffer.window.preview} "
                             "steps; drive it through the closed loop")
    target = sign * target_rad
    return target, buffer.features(target, sign * np.asarray(preview.target_rad), preview.load_share)
