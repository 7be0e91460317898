"""Strict reading of TOML tables: every key known, present, of the right type and in range.

Errors name the file and the dotted key and say what is expected, e.g.
"studies/x.toml: geometry.hub_radius_mm must be > 0 (got -3.0)".
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

from seadesign.errors import ConfigError


def read_toml(path: Path) -> dict[str, Any]:
    """Parse a TOML file, turning syntax errors into ConfigError."""
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ConfigError(f"{path}: file not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML ({exc})") from None


class Table:
    """A TOML table read key by key; `done()` rejects keys nobody asked for."""

    def __init__(self, data: Any, file: Path | str, where: str = "", origins: dict[str, str] | None = None) -> None:
        self.file = str(file)
        self.where = where
        self.origins = origins or {}  # dotted path -> the name to report (a value merged in from elsewhere)
        if not isinstance(data, dict):
            raise self.error(where or "(top level)", f"must be a table, got {type(data).__name__}")
        self.data = data
        self.seen: set[str] = set()

    def key(self, name: str) -> str:
        """The dotted name of `name` in the file (where a merged-in value came from, if it did)."""
        path = f"{self.where}.{name}" if self.where else name
        return self.origins.get(path, path)

    def error(self, key: str, problem: str) -> ConfigError:
        return ConfigError(f"{self.file}: {key} {problem}")

    def _get(self, name: str, default: Any) -> Any:
        self.seen.add(name)
        if name not in self.data:
            if default is _REQUIRED:
                raise self.error(self.key(name), "is missing; add it (see the default study or material files for an example)")
            return default
        return self.data[name]

    def number(self, name: str, default: Any = None, *, gt: float | None = None, ge: float | None = None,
               lt: float | None = None, le: float | None = None, required: bool = True) -> float:
        """A finite number (int or float) with optional bounds."""
        value = self._get(name, _REQUIRED if required and default is None else default)
        if value is None:
            return None  # type: ignore[return-value]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(self.key(name), f"must be a number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            raise self.error(self.key(name), f"must be finite, got {value}")
        for bound, ok, word in ((gt, lambda b: value > b, ">"), (ge, lambda b: value >= b, ">="),
                                (lt, lambda b: value < b, "<"), (le, lambda b: value <= b, "<=")):
            if bound is not None and not ok(bound):
                raise self.error(self.key(name), f"must be {word} {bound:g} (got {value:g})")
        return value

    def integer(self, name: str, default: Any = None, *, gt: int | None = None, ge: int | None = None,
                le: int | None = None) -> int:
        value = self._get(name, _REQUIRED if default is None else default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(self.key(name), f"must be an integer, got {value!r}")
        if gt is not None and not value > gt:
            raise self.error(self.key(name), f"must be > {gt} (got {value})")
        if ge is not None and value < ge:
            raise self.error(self.key(name), f"must be >= {ge} (got {value})")
        if le is not None and value > le:
            raise self.error(self.key(name), f"must be <= {le} (got {value})")
        return value

    def string(self, name: str, default: Any = None) -> str:
        value = self._get(name, _REQUIRED if default is None else default)
        if not isinstance(value, str) or not value.strip():
            raise self.error(self.key(name), f"must be a non-empty string, got {value!r}")
        return value

    def boolean(self, name: str, default: Any = None) -> bool:
        value = self._get(name, _REQUIRED if default is None else default)
        if not isinstance(value, bool):
            raise self.error(self.key(name), f"must be true or false, got {value!r}")
        return value

    def number_list(self, name: str, *, gt: float | None = None, integer: bool = False) -> tuple:
        """A non-empty list of numbers (integers with integer=True), each > gt."""
        value = self._get(name, _REQUIRED)
        kind = "integers" if integer else "numbers"
        if not isinstance(value, list) or not value:
            raise self.error(self.key(name), f"must be a non-empty list of {kind}, got {value!r}")
        out = []
        for i, item in enumerate(value):
            bad_type = isinstance(item, bool) or not isinstance(item, int if integer else (int, float))
            if bad_type:
                raise self.error(f"{self.key(name)}[{i}]", f"must be one of the {kind}, got {item!r}")
            if gt is not None and not item > gt:
                raise self.error(f"{self.key(name)}[{i}]", f"must be > {gt:g} (got {item})")
            out.append(item if integer else float(item))
        if len(set(out)) != len(out):
            raise self.error(self.key(name), f"has repeated values {value!r}")
        return tuple(out)

    def string_list(self, name: str) -> tuple[str, ...]:
        """A non-empty list of distinct non-empty strings."""
        value = self._get(name, _REQUIRED)
        if not isinstance(value, list) or not value or not all(isinstance(v, str) and v.strip() for v in value):
            raise self.error(self.key(name), f"must be a non-empty list of names, got {value!r}")
        if len(set(value)) != len(value):
            raise self.error(self.key(name), f"has repeated values {value!r}")
        return tuple(value)

    def table(self, name: str, optional: bool = False) -> "Table | None":
        value = self._get(name, None if optional else _REQUIRED)
        if value is None:
            return None
        path = f"{self.where}.{name}" if self.where else name
        return Table(value, self.file, path, self.origins)

    def raw(self, name: str, default: Any = None) -> Any:
        return self._get(name, default)

    def done(self) -> None:
        """Reject unknown keys (typos must not be silently ignored)."""
        unknown = sorted(set(self.data) - self.seen)
        if unknown:
            with_unit = [k for k in sorted(self.seen) if k.startswith(unknown[0] + "_")]
            if with_unit:
                raise self.error(self.key(unknown[0]), f"has no unit in its name; write {self.key(with_unit[0])} "
                                                       "(the key says the value's unit)")
            known = ", ".join(sorted(self.seen))
            raise self.error(self.key(unknown[0]), f"is not a known key; known keys here: {known}")


_REQUIRED = object()
