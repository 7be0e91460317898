"""Check the simulator a corrector trains in against the user's recordings, with the loop (`explain`).

The feed-forward family learns in the knee simulator built from spring.json, so the recordings of the
robot it is for say whether that simulator is the robot: for each recording and knee the loop refits the
declared model (k as a stiffness scale, backlash, gear friction) and traces what else the data needs.
The check passes when the stiffness scale lies in the range the corrector was shown robust to
(`goal.robustness_cases`: k x0.7 ... x1.4); a scale outside it, or effects beyond the declared ones, are
reported so that the spring.json can be calibrated first (`seadesign explain`, then the sweep).

The recordings are cleaned without the Hall-offset step (`clean(remove_offset=False)`): that step takes the
median deflection at unloaded rest for the sensor's offset, but a hanging shank at rest in the walk pose
still bends the spring under its own weight (0.048 rad with the thesis spring), so the step would put an
offset into a recording that had none, and the loop would find it. The loop traces a Hall offset itself,
with the spring's deflection under the measured effort taken into account.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from seadesign.data import clean, is_hanging, read_recording
from seadesign.design.spring import CurveRangeError
from seadesign.calibration.engine import SCALE, explain
from seadesign.calibration.sea import robot_declared, robot_loop_data

#: the k scales the corrector is tested robust to (goal.robustness_cases)
ROBUST_SCALE = (0.7, 1.4)


@dataclass(frozen=True)
class SimulatorCheck:
    """One recording and knee: the data's stiffness scale (1) with its uncertainty, the effects found, the verdict."""

    recording: str
    knee: str
    stiffness_scale: float
    stiffness_scale_u: float
    found: tuple[str, ...]
    verdict: str

    @property
    def within_robust_range(self) -> bool:
        return ROBUST_SCALE[0] <= self.stiffness_scale <= ROBUST_SCALE[1]

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "within_robust_range": self.within_robust_range}

    def text(self) -> str:
        if math.isnan(self.stiffness_scale):
            return f"{self.recording} ({self.knee}): {self.verdict}"
        where = "inside" if self.within_robust_range else "OUTSIDE"
        extra = f"; also found: {', '.join(self.found)}" if self.found else ""
        return (f"{self.recording} ({self.knee}): stiffness scale {self.stiffness_scale:.3g} +- {self.stiffness_scale_u:.2g}, "
                f"{where} the tested range {ROBUST_SCALE[0]:g}-{ROBUST_SCALE[1]:g}{extra}")


def check_simulator(spring: dict[str, Any], paths: list[str | Path]) -> list[SimulatorCheck]:
    """The loop on both knees of every recording (cleaned as `seadesign explain` cleans them, but for the Hall
    offset: see the module docstring)."""
    out = []
    for path in map(Path, paths):
        raw = read_recording(path)
        table = clean(raw, keep_lifted=is_hanging(raw), normalise=False, euler=False, remove_offset=False).table
        for knee in ("l", "r"):
            try:
                ex = explain(robot_loop_data(table, spring, knee), robot_declared(spring))
            except CurveRangeError as exc:  # a recording of another spring, deflected past this curve's end
                out.append(SimulatorCheck(path.stem, knee, math.nan, math.nan, (), f"not checked: {exc}"))
                continue
            scale = ex.final.parameters()[SCALE]["scale"]
            found = tuple(k for k in ex.found if k != SCALE)
            out.append(SimulatorCheck(path.stem, knee, scale["value"], scale["uncertainty"], found, ex.verdict()))
    return out
