"""The bench format for torque-deflection tests of a spring: read, validate, write.

A CSV with header `time_s, torque_Nm, deflection_rad` and optionally `temperature_C`
(time s strictly increasing, torque on the spring Nm, spring deflection rad, spring
temperature degC). Other columns are refused, so a typo in a unit suffix is caught.
Metadata (what a simulator declared) lives in the sidecar (see `metadata.py`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from seadesign.data._parse import check_increasing, numeric_column, read_raw_csv, require_columns
from seadesign.data.metadata import read_metadata, write_metadata
from seadesign.errors import DataError

BENCH_REQUIRED = ["time_s", "torque_Nm", "deflection_rad"]
BENCH_OPTIONAL = ["temperature_C"]


def read_bench(path: str | Path) -> pd.DataFrame:
    """Read and validate a bench file; float columns, `attrs['metadata']` from the sidecar or None."""
    path = Path(path)
    raw = read_raw_csv(path)
    require_columns(raw, BENCH_REQUIRED, path, "bench")
    _refuse_unknown(list(raw.columns), path)
    columns = BENCH_REQUIRED + [c for c in BENCH_OPTIONAL if c in raw.columns]
    df = pd.DataFrame({c: numeric_column(raw, c, path) for c in columns})
    check_increasing(df["time_s"].to_numpy(), "time_s", path)
    df.attrs["source"] = str(path)
    df.attrs["metadata"] = read_metadata(path)
    return df


def write_bench(df: pd.DataFrame, path: str | Path, metadata: dict[str, Any] | None = None) -> Path:
    """Validate `df` and write it in the bench format (sidecar when `metadata`)."""
    path = Path(path)
    missing = [c for c in BENCH_REQUIRED if c not in df.columns]
    if missing:
        raise DataError(f"{path}: bench table lacks column(s) {', '.join(missing)}")
    _refuse_unknown(list(df.columns), path)
    columns = BENCH_REQUIRED + [c for c in BENCH_OPTIONAL if c in df.columns]
    for column in columns:
        values = df[column].to_numpy(dtype=float)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise DataError(f"{path}: data row {int(bad[0])}, column '{column}' is not finite")
    check_increasing(df["time_s"].to_numpy(dtype=float), "time_s", path)
    path.parent.mkdir(parents=True, exist_ok=True)
    df[columns].to_csv(path, index=False, float_format="%.17g")
    if metadata is not None:
        write_metadata(path, metadata)
    return path


def _refuse_unknown(columns: list[str], source: str | Path) -> None:
    unknown = [c for c in columns if c not in BENCH_REQUIRED + BENCH_OPTIONAL]
    if unknown:
        raise DataError(
            f"{source}: unknown column(s) {', '.join(repr(c) for c in unknown)} in a bench file; "
            f"allowed: {', '.join(BENCH_REQUIRED + BENCH_OPTIONAL)} (units in the names)"
        )
