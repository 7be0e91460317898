"""Train / validation / test splits of a corrector dataset.

- ``time_blocks``: each recording's time axis is cut into contiguous blocks; whole blocks go to
  train, validation or test, and a guard gap of (history + 2) samples is dropped at every block
  edge so no input window or t+1 output straddles two sets. Both knees at the same instant go to
  the same set.
- ``by_recording``: whole recordings are held out (names given, or the last ones).
- ``random``: the thesis's shuffled 80/20 split (validation doubles as test). Neighbouring
  samples land on both sides, so its numbers are optimistic (leakage); kept for comparison.

Every split carries its name and settings, recorded next to every number it produced.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from seadesign.corrector.dataset import CorrectorDataset
from seadesign.errors import SeadesignError

SPLITS = ("time_blocks", "by_recording", "random")


@dataclass(frozen=True)
class Split:
    """Row indices of each set plus the settings that produced them."""

    name: str
    train: np.ndarray
    val: np.ndarray
    test: np.ndarray
    settings: dict = field(default_factory=dict)

    def describe(self) -> dict:
        """JSON-ready summary (sizes and settings)."""
        return {"split": self.name, "n_train": int(len(self.train)), "n_val": int(len(self.val)),
                "n_test": int(len(self.test)), **self.settings}


def time_block_split(ds: CorrectorDataset, n_blocks: int = 10, val_blocks: int = 2, test_blocks: int = 2,
                     seed: int = 0) -> Split:
    """Assign contiguous time blocks of every recording to train/val/test (seeded), with guard gaps."""
    if val_blocks + test_blocks >= n_blocks or val_blocks < 1:
        raise SeadesignError(
            f"time_blocks needs at least one train and one validation block: n_blocks={n_blocks}, "
            f"val_blocks={val_blocks}, test_blocks={test_blocks}"
        )
    gap = ds.spec.history + 2
    rng = np.random.default_rng(seed)
    role = np.full(len(ds), -1)
    for r in np.unique(ds.recording):
        rows = np.flatnonzero(ds.recording == r)
        steps = ds.step[rows]
        lo, hi = steps.min(), steps.max() + 1
        edges = np.linspace(lo, hi, n_blocks + 1).round().astype(int)
        block_role = rng.permutation(np.repeat([0, 1, 2], [n_blocks - val_blocks - test_blocks, val_blocks,
                                                           test_blocks]))
        block = np.clip(np.searchsorted(edges, steps, side="right") - 1, 0, n_blocks - 1)
        near_edge = np.zeros(len(rows), bool)
        for b in range(n_blocks):
            if b > 0 and block_role[b] != block_role[b - 1]:
                near_edge |= np.abs(steps - edges[b]) < gap
        role[rows] = np.where(near_edge, -1, block_role[block])
    return Split("time_blocks", *(np.flatnonzero(role == i) for i in range(3)),
                 {"n_blocks": n_blocks, "val_blocks": val_blocks, "test_blocks": test_blocks, "guard_gap_samples": gap,
                  "seed": seed})


def recording_split(ds: CorrectorDataset, test: list[str] | None = None, val_fraction: float = 0.2,
                    seed: int = 0) -> Split:
    """Hold out whole recordings for test (default: the last one); validation = time blocks of the rest."""
    names = list(ds.recordings)
    if len(names) < 2:
        raise SeadesignError("by_recording needs at least two recordings (--data); use time_blocks for one file")
    test = list(test) if test else [names[-1]]
    missing = [t for t in test if t not in names]
    if missing:
        raise SeadesignError(f"held-out recording(s) {missing} are not among the data files {names}")
    test_ids = [names.index(t) for t in test]
    is_test = np.isin(ds.recording, test_ids)
    rest = np.flatnonzero(~is_test)
    n_blocks = 10
    val_blocks = max(1, round(val_fraction * n_blocks))
    inner = time_block_split(ds.subset(rest), n_blocks=n_blocks, val_blocks=val_blocks, test_blocks=0, seed=seed)
    return Split("by_recording", rest[inner.train], rest[inner.val], np.flatnonzero(is_test),
                 {"test_recordings": test, "val": f"{val_blocks}/{n_blocks} time blocks of the others",
                  "guard_gap_samples": inner.settings["guard_gap_samples"], "seed": seed})


def random_split(ds: CorrectorDataset, train_fraction: float = 0.8, seed: int = 0) -> Split:
    """The thesis's shuffled split: train_fraction train, the rest validation and test (leaks)."""
    perm = np.random.default_rng(seed).permutation(len(ds))
    n_train = int(round(train_fraction * len(ds)))
    held = np.sort(perm[n_train:])
    return Split("random", np.sort(perm[:n_train]), held, held,
                 {"train_fraction": train_fraction, "seed": seed, "note": "shuffled neighbours leak; thesis comparison only"})


def make_split(ds: CorrectorDataset, name: str, seed: int = 0, test_recordings: list[str] | None = None) -> Split:
    """Split by name: time_blocks, by_recording or random."""
    if name == "time_blocks":
        return time_block_split(ds, seed=seed)
    if name == "by_recording":
        return recording_split(ds, test=test_recordings, seed=seed)
    if name == "random":
        return random_split(ds, seed=seed)
    raise SeadesignError(f"unknown split '{name}' (--split); choose one of {', '.join(SPLITS)}")
