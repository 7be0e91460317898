"""spring.json: the handoff between the design sweep and the simulator, training and loop.

The file is the only thing the downstream half reads. It is validated against
`schemas/spring.schema.json` on read and on write, so a bad file is refused with the
offending field named. Schema 2 may carry the spring's large-deflection torque curve
(`torque_curve`, read with `torque_curve`); schema 1 files (k only) are still read.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema

from seadesign.errors import SpringFileError

SCHEMA_VERSION = 2  # what the sweep writes; readers take every version the schema lists


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
    if "torque_curve" in data:
        torque_curve(data, source)  # monotone from (0, 0), equal lengths
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


@dataclass(frozen=True)
class TorqueCurve:
    """A spring's torque-rotation law for positive rotation (T(-theta) = -T(theta)): rotation in
    rad and torque in Nm, both strictly increasing from (0, 0); where and why it ends."""

    rotation_rad: tuple[float, ...]
    torque_Nm: tuple[float, ...]
    source: str
    stop_reason: str
    hard_stop: bool  # True: an end stop at the last point; False: past it is outside the model


def torque_curve(spring: dict[str, Any], source: str = "spring.json") -> TorqueCurve | None:
    """The spring's torque curve (schema 2), or None when it has only k; refuses a curve that is
    not strictly increasing from (0, 0)."""
    block = spring.get("torque_curve")
    if block is None:
        return None
    theta, torque = block["rotation_rad"], block["torque_Nm"]
    problems = []
    if len(theta) != len(torque):
        problems.append(f"rotation_rad has {len(theta)} points, torque_Nm {len(torque)}")
    elif theta[0] != 0 or torque[0] != 0:
        problems.append(f"it starts at ({theta[0]:g} rad, {torque[0]:g} Nm), not at (0, 0)")
    elif any(b <= a for a, b in zip(theta, theta[1:])) or any(b <= a for a, b in zip(torque, torque[1:])):
        problems.append("rotation and torque must both increase strictly (a curve past a torque maximum "
                        "has no inverse; it ends at the limit point)")
    if problems:
        raise SpringFileError(f"{source}: field 'torque_curve': {'; '.join(problems)}")
    return TorqueCurve(tuple(map(float, theta)), tuple(map(float, torque)), block["source"], block["stop_reason"],
                       bool(block["hard_stop"]))
