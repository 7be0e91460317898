"""spring.json: the handoff between the design sweep and the simulator, training and loop.

The file is the only thing the downstream half reads. It is validated against
`schemas/spring.schema.json` on read and on write, so a bad file is refused with the
offending field named.
"""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema

from seadesign.errors import SpringFileError

SCHEMA_VERSION = 1


def spring_schema() -> dict[str, Any]:
    """The JSON Schema of spring.json."""
    text = resources.files("seadesign.design").joinpath("schemas/spring.schema.json").read_text()
    return json.loads(text)


def validate_spring(data: Any, source: str = "spring.json") -> dict[str, Any]:
    """Check `data` against the schema; raise SpringFileError naming the field and problem."""
    validator = jsonschema.Draft202012Validator(spring_schema())
    errors = sorted(validator.iter_errors(data), key=lambda e: list(e.absolute_path))
    if errors:
        lines = []
        for err in errors:
            path = [str(p) for p in err.absolute_path]
            if err.validator == "required":  # name the missing key itself
                path.append(err.message.split("'")[1])
            field = "/".join(path) or "(top level)"
            lines.append(f"  field '{field}': {err.message}")
        raise SpringFileError(
            f"{source} does not match the spring.json schema (seadesign/design/schemas/spring.schema.json):\n"
            + "\n".join(lines)
            + "\nRegenerate it with `seadesign sweep` or fix the listed fields."
        )
    return data


def load_spring(path: str | Path) -> dict[str, Any]:
    """Read and validate a spring.json file."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise SpringFileError(f"spring file {path} does not exist; run `seadesign sweep` to create one") from None
    except json.JSONDecodeError as exc:
        raise SpringFileError(f"{path} is not valid JSON (line {exc.lineno}, column {exc.colno}): {exc.msg}") from None
    return validate_spring(data, str(path))


def write_spring(data: dict[str, Any], path: str | Path) -> Path:
    """Validate and write a spring.json file atomically."""
    validate_spring(data, str(path))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, sort_keys=True) + "\n")
    tmp.replace(path)
    return path
