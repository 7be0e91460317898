"""Before any training: does the spring's torque curve cover what training will ask of it?

The knee simulator reads the spring from spring.json's large-deflection curve, which is never extrapolated
(`design.spring.TorqueCurve`): a rotation past its end raises part-way through training. So `seadesign train`
checks first, and refuses with the load the spring cannot carry, where its curve ends and why, and the remedy (for a
curve that stopped at contact, also the path through self-contact):
the simulator's protocols (hanging and on the ground, every training speed) load the spring by gravity and the
leg's motion; one uncorrected rollout per setting with a linear spring of the same k gives the peak spring
torque, and the softest training scale s (the spring's torque x s) must carry it on the curve: peak / s <= the
curve's end torque. (Recordings given with --data only feed the simulator check, which reports a recording
the curve cannot follow instead of failing: `simcheck`.) A curve whose end is a hard stop carries anything past
it; a spring without a curve is linear and carries all.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from seadesign.corrector.closedloop_training import FINE_TUNING
from seadesign.corrector.imitation import ImitationSettings
from seadesign.design.spring import TorqueCurve, torque_curve
from seadesign.errors import SeadesignError
from seadesign.twin.knee import KneeSession


class SpringRangeError(SeadesignError):
    """The spring's torque curve ends before a load training needs it to carry."""


@dataclass(frozen=True)
class Load:
    """A load training puts on the spring: what it is, and the torque the curve must carry for it (Nm)."""

    what: str
    torque_Nm: float


def protocol_loads(spring: dict[str, Any], settings: ImitationSettings = ImitationSettings()) -> list[Load]:
    """The peak spring torque of each simulator setting's protocol (a linear spring of the same k, no
    correction), divided by the softest training scale: the torque the curve must carry (Nm)."""
    linear = {key: value for key, value in spring.items() if key != "torque_curve"}
    softest = min(min(settings.k_scales), min(FINE_TUNING.k_scales))
    out = []
    for setting in sorted(set(settings.conditions) | set(FINE_TUNING.conditions)):
        session = KneeSession(linear, settings.trials(), ground=setting == "ground", rate_hz=settings.rate_hz,
                              gait=settings.gait)
        peak = float(np.abs(session.spring_torque).max())
        while not session.done:
            session.step()
            peak = max(peak, float(np.abs(session.spring_torque).max()))
        out.append(Load(f"the simulator's {setting} protocol loads the spring to {peak:.3g} Nm, which needs "
                        f"{peak / softest:.3g} Nm on the curve at k x {softest:g} (the softest training scale)",
                        torque_Nm=peak / softest))
    return out


def check_spring_range(spring: dict[str, Any], settings: ImitationSettings = ImitationSettings()) -> None:
    """Raise SpringRangeError, before any training, when a load of `protocol_loads` lies past the end of the
    spring's torque curve."""
    curve = torque_curve(spring)
    if curve is None or curve.hard_stop:
        return
    beyond = [load for load in protocol_loads(spring, settings) if load.torque_Nm > curve.end_torque_Nm]
    if beyond:
        raise SpringRangeError(_refusal(spring, curve, beyond))


def _refusal(spring: dict[str, Any], curve: TorqueCurve, beyond: list[Load]) -> str:
    selection = spring.get("selection", {})
    verdict = ("" if selection.get("meets_requirements", True) else
               f" This spring does not meet its study's requirements ({selection.get('failed_constraints', '')}).")
    through = (" Its path stopped where a gap between facing surfaces closed, without contact forces (a schema-2 "
               "file): `seadesign sweep` now hands on the path through frictionless self-contact, which goes on past "
               "it." if curve.stop_reason == "contact" else "")
    return ("the spring cannot carry what training needs: " + "; ".join(load.what for load in beyond)
            + f". Its torque curve ends at {curve.end_rotation_rad:.4g} rad, {curve.end_torque_Nm:.4g} Nm (stop reason "
            f"{curve.stop_reason}: the large-deflection path ends there, and the curve is not extrapolated)."
            + verdict + " Remedy: hand on a spring whose curve reaches these loads (a stiffer design, or one that "
            "meets the requirements: see the sweep's report)." + through + " Nothing was trained.")
