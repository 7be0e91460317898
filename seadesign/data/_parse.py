"""Column parsing with errors that name the file, line, data row and column.

Line numbers count the header as line 1, so data row r (0-based) is on line r + 2.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from seadesign.errors import DataError


def where(source: str | Path, row: int, column: str) -> str:
    """'file, line L (data row R), column C' for error messages."""
    return f"{source}, line {row + 2} (data row {row}), column '{column}'"


def read_raw_csv(path: str | Path) -> pd.DataFrame:
    """Read a CSV with every cell as a string (no type guessing); DataError when unreadable."""
    path = Path(path)
    if not path.exists():
        raise DataError(f"{path} does not exist; check the path")
    try:
        return pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
    except pd.errors.EmptyDataError:
        raise DataError(f"{path} is empty; a header line and at least one data row are required") from None
    except (pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise DataError(f"{path} is not a readable CSV file: {exc}") from None


def require_columns(raw: pd.DataFrame, required: list[str], source: str | Path, fmt: str) -> None:
    """DataError naming every missing column."""
    missing = [c for c in required if c not in raw.columns]
    if missing:
        raise DataError(
            f"{source}: missing column(s) {', '.join(repr(c) for c in missing)} of the {fmt} format; "
            f"found {', '.join(repr(c) for c in raw.columns)}. The header must name: {', '.join(required)}"
        )
    if len(raw) == 0:
        raise DataError(f"{source}: no data rows below the header")


def numeric_column(raw: pd.DataFrame, column: str, source: str | Path) -> np.ndarray:
    """The column as float64; DataError at the first empty, non-numeric or non-finite cell."""
    text = raw[column].str.strip()
    values = pd.to_numeric(text, errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(values)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        cell = text.iloc[row]
        what = "is empty" if cell == "" else f"value {cell!r} is not a finite number"
        raise DataError(f"{where(source, row, column)}: {what}; {int(bad.sum())} such cell(s) in this column")
    return values


def list_column(
    raw: pd.DataFrame, column: str, lengths: tuple[int, ...], source: str | Path
) -> tuple[np.ndarray, np.ndarray]:
    """Parse '[a, b, ...]' cells into an (n_rows, max(lengths)) float array (NaN-padded) and the lengths.

    Every cell must be a bracketed list of finite numbers whose length is one of `lengths`.
    """
    width = max(lengths)
    out = np.full((len(raw), width), np.nan)
    counts = np.zeros(len(raw), dtype=int)
    for row, cell in enumerate(raw[column].tolist()):
        cell = cell.strip()
        if len(cell) < 2 or cell[0] != "[" or cell[-1] != "]":
            raise DataError(f"{where(source, row, column)}: {cell!r} is not a list '[v1, v2, ...]'")
        body = cell[1:-1].strip()
        items = body.split(",") if body else []
        if len(items) not in lengths:
            expected = " or ".join(str(n) for n in lengths)
            raise DataError(
                f"{where(source, row, column)}: list has {len(items)} value(s), expected {expected}"
            )
        try:
            vals = [float(x) for x in items]
        except ValueError:
            raise DataError(f"{where(source, row, column)}: {cell!r} holds a non-numeric value") from None
        if not all(np.isfinite(vals)):
            raise DataError(f"{where(source, row, column)}: {cell!r} holds a non-finite value")
        out[row, : len(vals)] = vals
        counts[row] = len(vals)
    return out, counts


def check_increasing(time: np.ndarray, column: str, source: str | Path) -> None:
    """DataError at the first sample whose time does not strictly increase."""
    bad = np.flatnonzero(np.diff(time) <= 0)
    if bad.size:
        row = int(bad[0]) + 1
        raise DataError(
            f"{where(source, row, column)}: time {time[row]!r} s does not increase (previous row: {time[row - 1]!r} s); "
            f"{bad.size} such row(s). Sort the file by time and drop duplicate samples"
        )


def format_lists(values: np.ndarray) -> list[str]:
    """Rows of a 2-D array as '[v1, v2, ...]' with the shortest round-tripping float text."""
    return ["[" + ", ".join(map(repr, row)) + "]" for row in values.tolist()]
