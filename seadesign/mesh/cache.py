"""Content-addressed on-disk store of raw tetrahedral meshes: identical input -> identical mesh."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np

from seadesign.run.atomic import atomic_write
from seadesign.run.fingerprint import code_fingerprint

CACHE_ENV = "SEADESIGN_CACHE_DIR"


def default_cache_dir() -> Path:
    """$SEADESIGN_CACHE_DIR, else .cache/ at the repository root (source checkout), else ./.cache."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    repo = Path(__file__).resolve().parents[2]
    return (repo if (repo / "pyproject.toml").is_file() else Path.cwd()) / ".cache"


def mesh_key(settings: dict, payload: bytes) -> str:
    """sha256 of the meshing settings, the geometry bytes (tessellation or BREP) and the mesher's code."""
    h = hashlib.sha256()
    h.update(json.dumps({"code": code_fingerprint("seadesign.mesh.worker"), **settings}, sort_keys=True).encode())
    h.update(payload)
    return h.hexdigest()


def _path(cache_dir: Path, key: str) -> Path:
    return Path(cache_dir) / "meshes" / f"{key}.npz"


def load(cache_dir: Path, key: str) -> tuple[np.ndarray, np.ndarray] | None:
    """Cached (points_mm, tets) or None."""
    path = _path(cache_dir, key)
    if not path.is_file():
        return None
    try:
        with np.load(path) as d:
            return d["points"], d["tets"]
    except (OSError, ValueError, KeyError):
        return None  # unreadable entry: remesh and overwrite it


def store(cache_dir: Path, key: str, points: np.ndarray, tets: np.ndarray) -> Path:
    """Write atomically (temporary file + rename) so parallel runs never see half a file."""

    def write(tmp: Path) -> None:
        with tmp.open("wb") as f:
            np.savez(f, points=points, tets=tets)

    return atomic_write(_path(cache_dir, key), write)
