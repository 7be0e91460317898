"""Sidecar metadata of a recording or bench file: `<name>.meta.json` next to `<name>.csv`.

The robot format is fixed (the thesis's tools read it), so nothing is added to the CSV
itself; what a simulator declared (effects, parameters, seed, versions, trials) goes into
the sidecar. A real recording has no sidecar; `read_metadata` then returns None.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from seadesign.errors import DataError


def sidecar_path(csv_path: str | Path) -> Path:
    """The sidecar of `csv_path`: same folder and stem, suffix `.meta.json`."""
    path = Path(csv_path)
    return path.with_name(path.stem + ".meta.json")


def write_metadata(csv_path: str | Path, metadata: dict[str, Any]) -> Path:
    """Write `metadata` as the sidecar of `csv_path` (sorted keys, indented JSON)."""
    path = sidecar_path(csv_path)
    path.write_text(json.dumps(metadata, indent=2, sort_keys=True, default=_jsonable) + "\n")
    return path


def read_metadata(csv_path: str | Path) -> dict[str, Any] | None:
    """The sidecar of `csv_path` as a dict, or None when there is none."""
    path = sidecar_path(csv_path)
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise DataError(
            f"{path}: metadata sidecar is not valid JSON (line {exc.lineno}, column {exc.colno}): {exc.msg}; "
            "fix or delete the sidecar"
        ) from None
    if not isinstance(data, dict):
        raise DataError(f"{path}: metadata sidecar must hold a JSON object, found {type(data).__name__}")
    return data


def _jsonable(value: Any) -> Any:
    """numpy scalars and arrays, Paths -> plain JSON values."""
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"cannot write {type(value).__name__} to a metadata sidecar")
