"""The spring as a measured or computed torque-rotation curve (large-deflection FEA) instead of k.

spring.json (schema 2) may carry `torque_curve`: `rotation_rad` and `torque_Nm` (monotone from
(0, 0), positive rotation only; the spring is symmetric, T(-theta) = -T(theta)), the `source`, why the
computation stopped (`stop_reason`) and whether the end (the last point) is a `hard_stop`.
`design.spring.TorqueCurve` reads, checks and interpolates it; `SpringCurve` here is the effect.

Interpolation: T(theta) is the monotone piecewise-cubic Hermite interpolant (PCHIP, Fritsch-Carlson,
`scipy.interpolate.PchipInterpolator`) through the points, which keeps the curve monotone between
them; the inverse theta(T) is that same interpolant solved exactly on its interval (bracketed
Newton), so T(theta(T)) = T to round-off. Past the curve's last point nothing is extrapolated:
a clear `CurveRangeError`, or with `hard_stop` the rotation held at the end (the stop carries the rest).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from seadesign.design.spring import TorqueCurve
from seadesign.effects.base import EXACT, Effect, Param
from seadesign.effects.spring import LinearSpring


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

    def __init__(self, curve: TorqueCurve, name: str | None = None, clamp: bool = False, **options: Any) -> None:
        self.curve = curve
        self.clamp = clamp  # past the curve's end: the end torque (the loop's trial values), else CurveRangeError
        super().__init__(name, **options)

    def replace(self, *, enabled: bool | None = None, clamp: bool | None = None, **values: float) -> "SpringCurve":
        return SpringCurve(self.curve, self.name, self.clamp if clamp is None else clamp,
                           enabled=self.enabled if enabled is None else enabled, bind=self.bind,
                           **{**self.values, **values})

    def _map(self, x, p, rng, xp=np, options=EXACT):
        return x["torque"] + p["scale"] * self.curve.torque(x["deflection"], clamp=self.clamp, xp=xp)

    def rotation(self, torque_Nm: np.ndarray, scale: float | None = None, clamp: bool = False) -> np.ndarray:
        """Deflection (rad) at which the scaled curve carries `torque_Nm` (`clamp`: see `TorqueCurve.rotation`)."""
        return self.curve.rotation(np.asarray(torque_Nm) / (self.values["scale"] if scale is None else scale),
                                   clamp=clamp)

    def describe(self) -> dict[str, Any]:
        out = super().describe()
        out["curve"] = {"rotation_rad": list(self.curve.rotation_rad), "torque_Nm": list(self.curve.torque_Nm),
                        "source": self.curve.source, "stop_reason": self.curve.stop_reason,
                        "hard_stop": self.curve.hard_stop}
        return out


def spring_law(k_Nm_per_rad: float, curve: TorqueCurve | None = None, name: str = "spring") -> Effect:
    """The spring's law: the large-deflection `curve` when there is one (never extrapolated: a rotation past
    its end is a CurveRangeError, or the end stop when the curve has one), else k (Nm/rad)."""
    return SpringCurve(curve, name) if curve is not None else LinearSpring(name, k_Nm_per_rad=k_Nm_per_rad)
