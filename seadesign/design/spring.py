"""spring.json: the handoff between the design sweep and the simulator, training and loop, and
the one `TorqueCurve` type that reads, checks and interpolates its large-deflection curve.

The file is the only thing the downstream half reads. It is validated against
`schemas/spring.schema.json` on read and on write, so a bad file is refused with the
offending field named. Schema 3 (written) carries the spring's large-deflection torque curve through
frictionless self-contact (`torque_curve`, read with `torque_curve`), so contact is never where it ends;
schema 2 files (whose curve may end at first contact, possibly as a hard stop) and schema 1 files (k only)
are still read.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import jsonschema
import numpy as np
from scipy.interpolate import PchipInterpolator

from seadesign.errors import ConfigError, DataError, SpringFileError

STOP_REASONS = (
    "target_reached", "limit_point", "bifurcation", "contact", "strain_limit", "rotation_limit", "unconverged")

SCHEMA_VERSION = 3  # what the sweep writes; readers take every version the schema lists


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
            why = (f"{err.instance!r} is not allowed: {err.schema['description']}" if err.validator == "not"
                   else err.message)
            lines.append(f"  field '{field}': {why}")
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


class CurveRangeError(DataError):
    """A rotation or torque lies past the end of the spring's torque curve (nothing is extrapolated)."""


@dataclass(frozen=True)
class TorqueCurve:
    """Monotone torque-rotation points from (0, 0) (rad, Nm) and where and why they end."""

    rotation_rad: tuple[float, ...]
    torque_Nm: tuple[float, ...]
    source: str = "fea_large_deflection"
    stop_reason: str = "target_reached"
    hard_stop: bool = False

    def __post_init__(self) -> None:
        th, tq = np.asarray(self.rotation_rad, float), np.asarray(self.torque_Nm, float)
        field = "torque_curve"
        if th.ndim != 1 or th.shape != tq.shape or th.size < 2:
            raise ConfigError(f"{field}: rotation_rad and torque_Nm must be lists of equal length, at least 2 "
                              f"points; rotation_rad has {th.size} points, torque_Nm {tq.size}")
        if not (np.isfinite(th).all() and np.isfinite(tq).all()):
            raise ConfigError(f"{field}: rotation_rad and torque_Nm must be finite numbers")
        if th[0] != 0.0 or tq[0] != 0.0:
            raise ConfigError(f"{field}: the curve must start at (0, 0); it starts at ({th[0]}, {tq[0]}) rad, Nm")
        for name, v in (("rotation_rad", th), ("torque_Nm", tq)):
            bad = np.flatnonzero(np.diff(v) <= 0)
            if bad.size:
                raise ConfigError(f"{field}/{name} must increase strictly (positive rotation only; a curve past a "
                                  f"torque maximum has no inverse: it ends at the limit point); it does not at index "
                                  f"{int(bad[0]) + 1}")
        if self.stop_reason not in STOP_REASONS:
            raise ConfigError(f"{field}/stop_reason '{self.stop_reason}' is unknown; use one of {', '.join(STOP_REASONS)}")

    @classmethod
    def from_handoff(cls, curve: Mapping[str, Any]) -> "TorqueCurve":
        """From spring.json's `torque_curve` object (the end point is the last listed point)."""
        missing = [k for k in ("rotation_rad", "torque_Nm") if k not in curve]
        if missing:
            raise ConfigError(f"torque_curve lacks {', '.join(missing)}")
        return cls(tuple(map(float, curve["rotation_rad"])), tuple(map(float, curve["torque_Nm"])),
                   str(curve.get("source", "fea_large_deflection")), str(curve.get("stop_reason", "target_reached")),
                   bool(curve.get("hard_stop", False)))

    @property
    def end_rotation_rad(self) -> float:
        return self.rotation_rad[-1]

    @property
    def end_torque_Nm(self) -> float:
        return self.torque_Nm[-1]

    def _end(self) -> str:
        return (f"the curve ends at {self.end_rotation_rad:.4g} rad, {self.end_torque_Nm:.4g} Nm "
                f"(source {self.source}, stop reason {self.stop_reason}) and is not extrapolated")

    def _pchip(self) -> PchipInterpolator:
        if "_p" not in self.__dict__:
            object.__setattr__(self, "_p", PchipInterpolator(self.rotation_rad, self.torque_Nm, extrapolate=False))
        return self.__dict__["_p"]

    def slope_at_zero(self) -> float:
        """Initial stiffness dT/dtheta at 0 (Nm/rad)."""
        return float(self._pchip().derivative()(0.0))

    @property
    def energy_J(self) -> float:
        """The energy (J) the whole curve stores when loaded from rest, int_0^end T dtheta."""
        return float(self._pchip().antiderivative()(self.rotation_rad[-1]))

    def torque_at_energy(self, energy_J: float) -> float | None:
        """The torque (Nm) where the curve, loaded from rest, has stored `energy_J` (J): int_0^theta T dtheta
        = energy; None when the whole curve stores less (a load that reaches its end)."""
        stored = self._pchip().antiderivative()
        theta = np.asarray(self.rotation_rad)
        total = stored(theta)
        if total[-1] < energy_J:
            return None
        i = max(int(np.searchsorted(total, energy_J)), 1)
        lo, hi = theta[i - 1], theta[i]
        for _ in range(60):  # bisection on the increasing stored energy
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if stored(mid) < energy_J else (lo, mid)
        return float(self._pchip()(0.5 * (lo + hi)))

    def torque(self, rotation_rad: Any, clamp: bool = False, xp: Any = np) -> Any:
        """T(theta) (Nm), odd in theta; past the end: the end torque with a hard stop or `clamp` (a fitter's trial
        values, samples the fit leaves out), else CurveRangeError. `xp`: the namespace of `rotation_rad` (NumPy, or
        `array_api_compat`'s torch, through which it differentiates)."""
        th = np.asarray(rotation_rad, dtype=float) if xp is np else rotation_rad
        a = xp.abs(th)
        if not (self.hard_stop or clamp) and bool(xp.any(a > self.end_rotation_rad)):
            raise CurveRangeError(f"rotation {float(xp.max(a)):.4g} rad is past the spring's torque curve: {self._end()}")
        end = self.end_rotation_rad
        return xp.sign(th) * self._interpolate(xp.where(a > end, end, a), xp)  # at the end: the slope from the left

    def _interpolate(self, a: Any, xp: Any) -> Any:
        """The PCHIP interpolant at 0 <= a <= end (rad): its polynomial pieces summed in the order scipy's `PPoly`
        sums them, so that NumPy gives scipy's values to the last digit (tested) and any namespace differentiates."""
        pchip = self._pchip()
        key = (xp.__name__, str(a.dtype), str(getattr(a, "device", "cpu")))
        cache = self.__dict__.setdefault("_pieces", {})
        if key not in cache:
            cache[key] = (xp.asarray(pchip.x, dtype=a.dtype, device=getattr(a, "device", None)),
                          xp.asarray(pchip.c, dtype=a.dtype, device=getattr(a, "device", None)))
        breaks, coef = cache[key]
        i = xp.minimum(xp.searchsorted(breaks, a, side="right") - 1, coef.shape[1] - 1)
        c, s = coef[:, i], a - breaks[i]
        s2 = s * s
        return ((c[3] + c[2] * s) + c[1] * s2) + c[0] * (s2 * s)

    def rotation(self, torque_Nm: np.ndarray, iterations: int = 60, clamp: bool = False) -> np.ndarray:
        """theta(T) (rad), the exact inverse of `torque`; past the end torque: the end rotation with a hard
        stop or `clamp` (a fitter's trial values), else CurveRangeError."""
        tq = np.asarray(torque_Nm, dtype=float)
        a = np.abs(tq)
        past = a > self.end_torque_Nm
        if past.any() and not (self.hard_stop or clamp):
            raise CurveRangeError(f"torque {float(a.max()):.4g} Nm is past the spring's torque curve: {self._end()}")
        a = np.minimum(a, self.end_torque_Nm)
        nodes, p = np.asarray(self.torque_Nm), self._pchip()
        i = np.clip(np.searchsorted(nodes, a, side="right") - 1, 0, nodes.size - 2)
        c = p.c[:, i]
        lo, hi = np.zeros_like(a), np.diff(self.rotation_rad)[i]
        u = hi * (a - nodes[i]) / (nodes[i + 1] - nodes[i])  # start from the chord
        for _ in range(iterations):  # Newton kept inside a shrinking bracket (bisection when it would leave)
            f = ((c[0] * u + c[1]) * u + c[2]) * u + c[3] - a
            if np.all(np.abs(f) <= 1e-14 * self.end_torque_Nm):
                break
            lo, hi = np.where(f < 0, u, lo), np.where(f > 0, u, hi)
            df = (3 * c[0] * u + 2 * c[1]) * u + c[2]
            with np.errstate(divide="ignore", invalid="ignore"):
                newton = u - f / df
            u = np.where((df > 0) & (newton > lo) & (newton < hi), newton, 0.5 * (lo + hi))
        return np.sign(tq) * (np.asarray(self.rotation_rad)[i] + u)


def torque_curve(spring: dict[str, Any], source: str = "spring.json") -> TorqueCurve | None:
    """The spring's torque curve (schema 2), or None when it has only k; refuses a curve that is
    not strictly increasing from (0, 0), naming the field."""
    block = spring.get("torque_curve")
    if block is None:
        return None
    try:
        return TorqueCurve.from_handoff(block)
    except ConfigError as exc:
        raise SpringFileError(f"{source}: field {exc}") from None
