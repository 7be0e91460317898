"""Requirements in a study: parsed strictly, and judged as margins that change sign at each limit."""

from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest

from seadesign.design.study import DEFAULT_STUDY, load_study
from seadesign.errors import ConfigError
from seadesign.sweep.rank import constraint_columns, physical_columns


def _study(tmp_path, requirements: str, ranking_extra: str = ""):
    text = DEFAULT_STUDY.read_text() + "\n[requirements]\n" + requirements + "\n"
    if ranking_extra:
        text = re.sub(r"(?m)^\[ranking\]\n", "[ranking]\n" + ranking_extra + "\n", text)
    path = tmp_path / "req.toml"
    path.write_text(text)
    return load_study(path)


def test_parsing_and_clear_errors(tmp_path):
    s = _study(tmp_path, 'k_Nm_per_rad = {target = 40.0, tolerance_percent = 10.0}\nloads = ["stall"]\n'
                         'max_outer_diameter_mm = 80.0\nmax_thickness_mm = 20.0\nobjectives = ["mass", "protection"]')
    r = s.requirements
    assert (r.k_min_Nm_per_rad, r.k_max_Nm_per_rad) == pytest.approx((36.0, 44.0))
    assert r.loads == ("stall",) and r.objectives == ("mass", "protection") and r.max_outer_diameter_mm == 80.0
    assert load_study().requirements.loads == ("stall", "impact")  # a study without [requirements]: the sweep's
    cases = [
        ('k_Nm_per_rad = {min = 50.0, max = 40.0}', "requirements.k_Nm_per_rad.max must be larger than min"),
        ('k_Nm_per_rad = {target = 40.0}', "requirements.k_Nm_per_rad.tolerance_percent is missing"),
        ('loads = ["walk"]', "requirements.loads has 'walk'; choose from stall, impact"),
        ('objectives = ["cost"]', "requirements.objectives has 'cost'; choose from mass, accuracy, protection"),
        ('max_thickness_mm = -1.0', r"requirements.max_thickness_mm must be > 0 \(got -1\)"),
        ('max_height_mm = 3.0', "requirements.max_height_mm is not a known key"),
    ]
    for text, message in cases:
        with pytest.raises(ConfigError, match=message):
            _study(tmp_path, text)
    with pytest.raises(ConfigError, match="give the k range once"):
        _study(tmp_path, 'k_Nm_per_rad = {min = 10.0}', ranking_extra="k_min_Nm_per_rad = 5.0")


def _path_row(study, k: float, stop_Nm: float, strain_per_rad: float) -> dict:
    """A solved design with curve T = k theta to contact at `stop_Nm` (or the impact torque), peak strain
    strain_per_rad * theta; the crossing of the allowable where it lies on the path."""
    lc = study.load_cases
    allowable = study.material.allowable_strain(study.ranking.safety_factor)
    cross = allowable / strain_per_rad
    row = {"candidate": "x", "beam_count": 6, "beam_thickness_mm": 6.0, "status": "ok", "k_Nm_per_rad": k,
           "mass_g": 20.0, "large_curve_rotation_rad": [0.0, stop_Nm / k], "large_curve_torque_Nm": [0.0, stop_Nm],
           "large_stop_torque_Nm": stop_Nm, "large_stop_rotation_rad": stop_Nm / k, "large_allowable_strain": allowable,
           "large_strain_limit_torque_Nm": k * cross if k * cross <= stop_Nm else math.nan}
    for case, torque in (("standing", study.robot.standing_knee_torque_Nm), ("stall", lc.stall_torque_Nm),
                         ("impact", lc.impact_torque_Nm)):
        theta = torque / k if torque <= stop_Nm else math.nan
        row[f"large_{case}_rotation_rad"], row[f"large_{case}_peak_strain"] = theta, strain_per_rad * theta
    return row


def test_margins_change_sign_at_each_limit(tmp_path):
    s = _study(tmp_path, "max_outer_diameter_mm = 70.0\nmax_thickness_mm = 9.5", ranking_extra="k_max_Nm_per_rad = 50.0")
    lc = s.load_cases
    allowable = s.material.allowable_strain(s.ranking.safety_factor)
    rows = [
        _path_row(s, 40.0, 0.9 * lc.stall_torque_Nm, 0.1),  # contact 10 % below stall
        _path_row(s, 40.0, lc.impact_torque_Nm, 40.0 * allowable / (1.25 * lc.stall_torque_Nm)),  # strain at 1.25 stall
        _path_row(s, 60.0, lc.impact_torque_Nm, 0.01),  # too stiff by 20 %, strain never reached
    ]
    t = constraint_columns(physical_columns(pd.DataFrame(rows), s), s)
    assert t.loc[0, "stall_travel_margin"] == pytest.approx(-0.1)
    assert np.isnan(t.loc[0, "stall_strain_margin"])  # no strain to read where the path does not go
    assert t.loc[1, "stall_travel_margin"] == pytest.approx(lc.impact_torque_Nm / lc.stall_torque_Nm - 1)
    assert t.loc[1, "stall_strain_margin"] == pytest.approx(0.25)
    assert t.loc[1, "impact_strain_margin"] == pytest.approx(1.25 * lc.stall_torque_Nm / lc.impact_torque_Nm - 1)
    assert t.loc[2, "k_max_margin"] == pytest.approx(-0.2)
    # never reached on the path: allowable / strain at the load - 1
    assert t.loc[2, "impact_strain_margin"] == pytest.approx(allowable / (0.01 * lc.impact_torque_Nm / 60.0) - 1)
    # the envelope from the geometry: ring outer radius 14 + 2 x 5 + 8 = 32 mm, thickness 9 mm
    assert t.loc[0, "outer_diameter_margin"] == pytest.approx(1 - 64 / 70) and \
        t.loc[0, "thickness_margin"] == pytest.approx(1 - 9 / 9.5)
    assert t.loc[2, "failed_constraints"] == "k <= 50 Nm/rad"
    assert t.loc[2, "total_violation"] == pytest.approx(0.2)
    assert t.loc[1, "failed_constraints"] == "impact strain < 0.433" and not t.loc[1, "feasible"]
