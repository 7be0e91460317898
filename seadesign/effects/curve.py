"""The spring as a measured or computed torque-rotation curve (large-deflection FEA) instead of k.

spring.json (schema 2) may carry `torque_curve`: `rotation_rad` and `torque_Nm` (monotone from
(0, 0), positive rotation only; the spring is symmetric, T(-theta) = -T(theta)), the `source`, why the
computation stopped (`stop_reason`) and whether the end (the last point) is a `hard_stop`. `TorqueCurve` reads and checks it; `SpringCurve` is the effect.

Interpolation: T(theta) is the monotone piecewise-cubic Hermite interpolant (PCHIP, Fritsch-Carlson,
`scipy.interpolate.PchipInterpolator`) through the points, which keeps the curve monotone between
them; the inverse theta(T) is that same interpolant solved exactly on its interval (bracketed
Newton), so T(theta(T)) = T to round-off. Past the curve's last point nothing is extrapolated:
a clear `CurveRangeError`, or with `hard_stop` the rotation held at the end (the stop carries the rest).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
from scipy.interpolate import PchipInterpolator

from seadesign.effects.base import Effect, Param, Scales, Search
from seadesign.errors import ConfigError, DataError

STOP_REASONS = ("target_reached", "limit_point", "bifurcation", "contact", "strain_limit", "unconverged")


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
                              f"points; got {th.size} and {tq.size}")
        if not (np.isfinite(th).all() and np.isfinite(tq).all()):
            raise ConfigError(f"{field}: rotation_rad and torque_Nm must be finite numbers")
        if th[0] != 0.0 or tq[0] != 0.0:
            raise ConfigError(f"{field}: the curve must start at (0, 0); it starts at ({th[0]}, {tq[0]}) rad, Nm")
        for name, v in (("rotation_rad", th), ("torque_Nm", tq)):
            bad = np.flatnonzero(np.diff(v) <= 0)
            if bad.size:
                raise ConfigError(f"{field}/{name} must strictly increase (positive rotation only; a flat or falling "
                                  f"part has no inverse); it does not at index {int(bad[0]) + 1}")
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

    def torque(self, rotation_rad: np.ndarray) -> np.ndarray:
        """T(theta) (Nm), odd in theta; past the end: the end torque with a hard stop, else CurveRangeError."""
        th = np.asarray(rotation_rad, dtype=float)
        a = np.abs(th)
        past = a > self.end_rotation_rad
        if past.any() and not self.hard_stop:
            raise CurveRangeError(f"rotation {float(a.max()):.4g} rad is past the spring's torque curve: {self._end()}")
        return np.sign(th) * self._pchip()(np.minimum(a, self.end_rotation_rad))

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


class SpringCurve(Effect):
    """The spring as a torque curve: torque += s T(deflection), s a calibration of the torque axis.

    Replaces `LinearSpring` where spring.json carries the large-deflection curve; `scale` plays the
    part of `StiffnessScale` for it (the curve's shape is kept, its torques scaled).
    """

    key = "spring_curve"
    summary = "torque += s T(d), T the large-deflection torque curve (PCHIP)"
    parameters = (Param("scale", "1", 1.0, 0.01, 100.0, "calibration: measured over computed torque at equal rotation"),)
    reads = ("deflection",)
    writes = "torque"

    def __init__(self, curve: TorqueCurve, name: str | None = None, **options: Any) -> None:
        self.curve = curve
        super().__init__(name, **options)

    def replace(self, *, enabled: bool | None = None, **values: float) -> "SpringCurve":
        return SpringCurve(self.curve, self.name, enabled=self.enabled if enabled is None else enabled,
                           bind=self.bind, **{**self.values, **values})

    def _map(self, x, p, rng):
        return x["torque"] + p["scale"] * self.curve.torque(x["deflection"])

    def rotation(self, torque_Nm: np.ndarray, scale: float | None = None, clamp: bool = False) -> np.ndarray:
        """Deflection (rad) at which the scaled curve carries `torque_Nm` (`clamp`: see `TorqueCurve.rotation`)."""
        return self.curve.rotation(np.asarray(torque_Nm) / (self.values["scale"] if scale is None else scale),
                                   clamp=clamp)

    def search(self, s: Scales) -> Search:
        lowest = max(0.01, s.torque_Nm / self.curve.end_torque_Nm) if not self.curve.hard_stop else 0.01
        return {"scale": (lowest, 100.0)}, [{"scale": max(1.0, lowest)}]

    def describe(self) -> dict[str, Any]:
        out = super().describe()
        out["curve"] = {"rotation_rad": list(self.curve.rotation_rad), "torque_Nm": list(self.curve.torque_Nm),
                        "source": self.curve.source, "stop_reason": self.curve.stop_reason,
                        "hard_stop": self.curve.hard_stop}
        return out
