"""The sweep's verdicts in words, as the command line prints them: the spring handed on, a design's standing
load, the choice before and after a calibration."""

from __future__ import annotations

import numpy as np
import pandas as pd

from seadesign.design.study import Study
from seadesign.sweep.rank import Choice


def handoff_verdict(t: pd.DataFrame, choice: Choice) -> str:
    """Whether the spring handed on meets the requirements, in one line."""
    row = t.loc[choice.index]
    if choice.feasible:
        return f"{row['candidate']} meets every requirement, each judged"
    if choice.conditional:
        return f"{row['candidate']} meets every judged requirement; not judged: {row['not_judged']}"
    return f"{row['candidate']} does NOT meet the requirements (misses: {row['failed_constraints']})"


def standing_verdict(ranked: pd.DataFrame, candidate: str, study: Study) -> str:
    """Whether `candidate` carries the robot's standing load in `ranked` (deflection vs the limit, deg)."""
    row = ranked.loc[ranked["candidate"] == candidate].iloc[0]
    limit = study.requirements.max_standing_deflection_deg
    deg = float(row["standing_deflection_deg"])
    if limit is None:
        verdict, limit_words = ("carries" if np.isfinite(deg) else "does NOT carry"), "no sag limit"
    else:
        verdict, limit_words = ("carries" if deg < limit else "does NOT carry"), f"limit {limit:g} deg"
    if not np.isfinite(deg):  # the path ends below the standing torque: no deflection to judge
        return (f"{candidate}: k {row['k_Nm_per_rad']:.4g} Nm/rad, its path ends at {row['large_stop_torque_Nm']:.3g} "
                f"Nm ({row['large_stop_reason']}), below the standing torque {row['standing_knee_torque_Nm']:.3g} Nm: "
                "does NOT carry the standing load")
    return (f"{candidate}: k {row['k_Nm_per_rad']:.4g} Nm/rad, standing deflection {deg:.3g} deg under "
            f"{row['standing_knee_torque_Nm']:.3g} Nm ({limit_words}): {verdict} the standing load")


def calibration_summary(base: pd.DataFrame, base_choice: Choice, calibrated: pd.DataFrame, choice: Choice,
                        study: Study) -> str:
    """Lines comparing the choice before and after calibration, each judged with the calibrated material."""
    if base_choice.index is None or choice.index is None:
        return "calibration: no candidate was solved, nothing to compare"
    before, after = base.loc[base_choice.index, "candidate"], calibrated.loc[choice.index, "candidate"]
    lines = [f"calibration: choice {'unchanged' if before == after else 'changes'}: {before} -> {after}",
             "  uncalibrated choice, calibrated material: " + standing_verdict(calibrated, before, study)]
    if after != before:
        lines.append("  calibrated choice: " + standing_verdict(calibrated, after, study))
    if not choice.feasible:
        lines.append("  no candidate meets every constraint with the calibrated material; see the report")
    return "\n".join(lines)
