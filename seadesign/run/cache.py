"""Content-addressed cache of sweep stages (geometry, mesh, unit FEA response).

A key is the SHA-256 of the canonical JSON of everything a stage's output depends on: its
inputs, the key of the stage before it, the fingerprint of the project code that computes it
(`run/fingerprint.py`) and the versions of the third-party packages that do.
Entries are pickles written atomically (`atomic.py`), so an interrupted write never leaves a bad entry.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import pickle
from importlib import metadata
from pathlib import Path
from typing import Any

from seadesign.errors import ConfigError
from seadesign.run.atomic import atomic_write


CACHE_ENV = "SEADESIGN_CACHE"  # the one cache root: stages, meshes and exported CAD
RETIRED_CACHE_ENV = "SEADESIGN_CACHE_DIR"  # the meshes' own root before they joined the stage cache


def default_cache_dir() -> Path:
    """$SEADESIGN_CACHE as set now, else ~/.cache/seadesign; ConfigError while the retired
    $SEADESIGN_CACHE_DIR is set (it is no longer read, and a silently ignored root would surprise)."""
    retired = os.environ.get(RETIRED_CACHE_ENV)
    if retired:
        raise ConfigError(
            f"{RETIRED_CACHE_ENV}={retired} is no longer read: meshes now live in the one stage cache. "
            f"Set {CACHE_ENV}={retired} instead (or unset {RETIRED_CACHE_ENV} to use ~/.cache/seadesign)")
    return Path(os.environ.get(CACHE_ENV, Path.home() / ".cache" / "seadesign"))

TRACKED_PACKAGES = ("seadesign", "numpy", "scipy", "cadquery", "gmsh", "pytetwild", "mkl")


def _plain(obj: Any) -> Any:
    """JSON-ready form of dataclasses, paths, tuples and floats (floats by repr: exact)."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: _plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in sorted(obj.items())}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, float):
        return repr(obj)
    if isinstance(obj, Path):
        return str(obj)
    return obj


def digest(*parts: Any, length: int = 32) -> str:
    """Hex SHA-256 of the canonical JSON of `parts` (dataclasses by field, floats by repr: exact).

    Parameters
    ----------
    *parts : Any
        Everything a stage's output depends on.
    length : int
        Characters of the hex digest kept.

    Returns
    -------
    str
        The key.

    Examples
    --------
    >>> digest("mesh", 1.5, length=8) == digest("mesh", 1.5, length=8)
    True
    """
    text = json.dumps(_plain(list(parts)), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:length]


def package_versions(packages: tuple[str, ...] = TRACKED_PACKAGES) -> dict[str, str]:
    """Installed versions of third-party packages, part of the keys of the stages they compute.

    Parameters
    ----------
    packages : tuple of str
        Distribution names.

    Returns
    -------
    dict of str to str
        Name -> version ("absent" when not installed).

    Examples
    --------
    >>> package_versions(("numpy",))["numpy"] != "absent"
    True
    """
    out = {}
    for name in packages:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "absent"
    return out


@dataclasses.dataclass(frozen=True)
class Cache:
    """Pickled stage outputs under root/<stage>/<key[:2]>/<key>.pkl; `enabled=False` stores nothing."""

    root: Path = dataclasses.field(default_factory=default_cache_dir)
    enabled: bool = True

    def path(self, stage: str, key: str) -> Path:
        """Where the output of `stage` under `key` is stored.

        Parameters
        ----------
        stage : str
            The stage's name (geometry, fea, coarse_k, path).
        key : str
            Its key (`digest`).

        Returns
        -------
        Path
            ``root/<stage>/<key[:2]>/<key>.pkl``.

        Examples
        --------
        >>> Cache(Path("/tmp/c")).path("fea", "abcd").as_posix()
        '/tmp/c/fea/ab/abcd.pkl'
        """
        return Path(self.root) / stage / key[:2] / f"{key}.pkl"

    def get(self, stage: str, key: str) -> Any | None:
        """The stored output of a stage.

        Parameters
        ----------
        stage : str
            The stage's name.
        key : str
            Its key (`digest`).

        Returns
        -------
        Any or None
            The output, or None when absent, unreadable or the cache is disabled (then it is recomputed).

        Examples
        --------
        >>> Cache(Path("/tmp/c"), enabled=False).get("fea", "abcd") is None
        True
        """
        if not self.enabled:
            return None
        try:
            with self.path(stage, key).open("rb") as fh:
                return pickle.load(fh)
        except Exception:  # noqa: BLE001 - missing, truncated, or pickled by other code: recompute
            return None

    def put(self, stage: str, key: str, value: Any) -> None:
        """Store a stage's output atomically (nothing when the cache is disabled).

        Parameters
        ----------
        stage : str
            The stage's name.
        key : str
            Its key (`digest`).
        value : Any
            The output; it must pickle.

        Examples
        --------
        >>> Cache(Path("/tmp/c")).put("fea", "abcd", {"k_Nm_per_rad": 9.1})
        """
        if not self.enabled:
            return
        atomic_write(self.path(stage, key), lambda tmp: tmp.write_bytes(pickle.dumps(value, pickle.HIGHEST_PROTOCOL)))


def default_cache(cache_dir: str | Path | None = None) -> Cache:
    """The stage cache the commands use.

    Parameters
    ----------
    cache_dir : str or Path, optional
        Its folder; None: $SEADESIGN_CACHE as set now, else ~/.cache/seadesign.

    Returns
    -------
    Cache
        An enabled cache rooted there.

    Examples
    --------
    >>> default_cache("/tmp/seadesign-cache").root
    PosixPath('/tmp/seadesign-cache')
    """
    return Cache(Path(cache_dir) if cache_dir else default_cache_dir())
