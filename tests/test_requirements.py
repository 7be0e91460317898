"""Requirements in a study: parsed strictly, the k window they imply, and judged as margins that change sign
at each limit (rows from `helpers_curves`, closed-form curves)."""

from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest

from helpers_curves import linear_row, with_limits
from seadesign.design.study import DEFAULT_STUDY, load_study
from seadesign.errors import ConfigError
from seadesign.sweep.physical import physical_columns
from seadesign.sweep.rank import constraint_columns
from seadesign.sweep.requirements import STRAIN_TORQUE_KNOCKDOWN, working_tangents

KNEE_REQUIREMENTS = re.compile(r"(?ms)^\[requirements\].*\Z")  # the default study's table, its last


def _study(tmp_path, requirements: str, ranking_extra: str = ""):
    text = KNEE_REQUIREMENTS.sub("", DEFAULT_STUDY.read_text()) + "\n[requirements]\n" + requirements + "\n"
    if ranking_extra:
        text = re.sub(r"(?m)^\[ranking\]\n", "[ranking]\n" + ranking_extra + "\n", text)
    path = tmp_path / "req.toml"
    path.write_text(text)
    return load_study(path)


def test_parsing_and_clear_errors(tmp_path):
    s = _study(tmp_path, 'k_Nm_per_rad = {target = 40.0, tolerance_percent = 10.0}\nloads = ["stall"]\n'
                         'max_outer_diameter_mm = 80.0\nmax_thickness_mm = 20.0\nobjectives = ["mass", "protection"]\n'
                         'max_stall_foot_error_mm = 200.0\nmax_strike_torque_Nm = 11.7')
    r = s.requirements
    assert (r.k_min_Nm_per_rad, r.k_max_Nm_per_rad) == pytest.approx((36.0, 44.0))
    assert r.loads == ("stall",) and r.objectives == ("mass", "protection") and r.max_outer_diameter_mm == 80.0
    assert r.max_stall_foot_error_mm == 200.0 and r.max_standing_deflection_deg is None
    cases = [
        ('k_Nm_per_rad = {min = 50.0, max = 40.0}', "requirements.k_Nm_per_rad.max must be larger than min"),
        ('k_Nm_per_rad = {target = 40.0}', "requirements.k_Nm_per_rad.tolerance_percent is missing"),
        ('loads = ["walk"]', "requirements.loads has 'walk'; choose from stall, impact"),
        ('objectives = ["cost"]', "requirements.objectives has 'cost'; choose from mass, accuracy, protection, "
                                  "strain_margin, softest_k"),
        ('max_thickness_mm = -1.0', r"requirements.max_thickness_mm must be > 0 \(got -1\)"),
        ('max_height_mm = 3.0', "requirements.max_height_mm is not a known key"),
        ('max_standing_deflection = 10.0', "requirements.max_standing_deflection has no unit in its name; write "
                                           "requirements.max_standing_deflection_deg"),
        ('min_natural_frequency = 5.0', "write requirements.min_natural_frequency_Hz"),
    ]
    for text, message in cases:
        with pytest.raises(ConfigError, match=message):
            _study(tmp_path, text)


@pytest.mark.parametrize("key, new", [("max_standing_deflection_deg = 10.0", "requirements.max_standing_deflection_deg"),
                                      ("k_min_Nm_per_rad = 5.0", r"requirements.k_Nm_per_rad = \{ min"),
                                      ("weight_accuracy = 0.5", "requirements.objectives")])
def test_moved_ranking_keys_name_their_replacement(tmp_path, key, new):
    with pytest.raises(ConfigError, match=rf"ranking.{key.split()[0]} has moved: write {new}"):
        _study(tmp_path, "max_thickness_mm = 20.0", ranking_extra=key)


def test_the_k_window_from_the_study_numbers_and_crossing_bounds(tmp_path):
    """Linear-spring bounds by hand: sag k >= T_standing / theta_max; bandwidth k >= J (2 pi f)^2; one sensor count
    k <= tau_q / (2 pi / 4096); foot error k >= T_stall l / e; strike k <= (tau / w)^2 / J."""
    knee = load_study()
    window = knee.k_window
    standing = knee.robot.standing_knee_torque_Nm
    assert window.lower.key == "max_standing_deflection_deg"
    assert window.lower.stiffness_Nm_per_rad == pytest.approx(standing / math.radians(10.0), rel=1e-12)
    assert window.upper.key == "max_torque_per_count_Nm"
    assert window.upper.stiffness_Nm_per_rad == pytest.approx(0.1 / (2 * math.pi / 4096), rel=1e-12)
    assert window.describe().startswith("k between 11.9 and 65.2 Nm/rad: 11.9 Nm/rad from the standing sag")
    s = _study(tmp_path, "min_natural_frequency_Hz = 20.0\nmax_strike_torque_Nm = 2.0\nmax_stall_foot_error_mm = 50.0")
    bounds = {b.key: b.stiffness_Nm_per_rad for b in s.k_window.bounds}
    J, w = s.ranking.knee_inertia_kg_m2, s.ranking.impact_speed_m_per_s / s.robot.lower_leg_m
    assert bounds["min_natural_frequency_Hz"] == pytest.approx(J * (2 * math.pi * 20.0) ** 2, rel=1e-12)
    assert bounds["max_strike_torque_Nm"] == pytest.approx((2.0 / w) ** 2 / J, rel=1e-12)
    assert bounds["max_stall_foot_error_mm"] == pytest.approx(11.7 * 0.2038 / 0.05, rel=1e-12)
    # 20 Hz needs k >= 158 Nm/rad, one count of 0.1 Nm allows k <= 65.2: refused before any solve
    with pytest.raises(ConfigError, match=r"requirements.min_natural_frequency_Hz needs k >= 157.9 Nm/rad .* but "
                                          r"requirements.max_torque_per_count_Nm allows k <= 65.19 Nm/rad .* cross by 142 %"):
        _study(tmp_path, "min_natural_frequency_Hz = 20.0\nmax_torque_per_count_Nm = 0.1")


def test_margins_change_sign_at_each_limit(tmp_path):
    s = with_limits(_study(tmp_path, "max_outer_diameter_mm = 70.0\nmax_thickness_mm = 9.5\nk_Nm_per_rad = {max = 50.0}\n"
                                     "max_standing_deflection_deg = 10.0\nmax_torque_per_count_Nm = 0.1\n"
                                     "min_natural_frequency_Hz = 8.0\nmax_stall_foot_error_mm = 100.0\n"
                                     "max_strike_torque_Nm = 0.8"), 0.2)
    lc = s.load_cases
    rows = [
        linear_row(s, 0, "a", 40.0, 0.1, 0.9 * lc.stall_torque_Nm),  # contact 10 % below stall
        linear_row(s, 1, "b", 40.0, 0.2 * 40.0 / (1.25 * lc.stall_torque_Nm)),  # cyclic limit at 1.25 x stall
        linear_row(s, 2, "c", 60.0, 0.01),  # too stiff by 20 %, strain never at a limit
    ]
    t = constraint_columns(physical_columns(pd.DataFrame(rows), s), s)
    assert t.loc[0, "stall_travel_margin"] == pytest.approx(-0.1)
    assert np.isnan(t.loc[0, "stall_strain_margin"])  # no strain to read where the path does not go
    assert t.loc[0, "foot_error_margin"] == pytest.approx(-0.1)  # the travel stands in for the stall's rotation
    assert t.loc[1, "stall_travel_margin"] == pytest.approx(lc.impact_torque_Nm / lc.stall_torque_Nm - 1)
    kd = STRAIN_TORQUE_KNOCKDOWN  # the path mesh's knock-down: torques at a limit x kd, strains at a load / kd
    assert t.loc[1, "stall_strain_margin"] == pytest.approx(1.25 * kd - 1)
    assert t.loc[2, "k_max_margin"] == pytest.approx(-0.2)
    # never at the limit on the path: limit / strain at the load - 1
    assert t.loc[2, "impact_strain_margin"] == pytest.approx(kd * 0.65 / 1.5 / (0.01 * lc.impact_torque_Nm / 60.0) - 1)
    # closed forms of the linear spring k = 40: sag, foot error, one count, natural frequency, strike torque
    J, w = s.ranking.knee_inertia_kg_m2, s.strike_speed_rad_per_s
    assert t.loc[1, "standing_margin"] == pytest.approx(1 - math.degrees(s.robot.standing_knee_torque_Nm / 40) / 10)
    assert t.loc[1, "foot_error_margin"] == pytest.approx(1 - 11.7 / 40 * 203.8 / 100.0)
    assert t.loc[1, "torque_resolution_margin"] == pytest.approx(1 - 40 * 2 * math.pi / 4096 / 0.1)
    assert t.loc[1, "natural_frequency_margin"] == pytest.approx(math.sqrt(40 / J) / (2 * math.pi) / 8.0 - 1)
    assert t.loc[1, "strike_margin"] == pytest.approx(1 - w * math.sqrt(40 * J) / 0.8)
    # the envelope from the geometry: ring outer radius 14 + 2 x 5 + 8 = 32 mm, thickness 9 mm
    assert t.loc[0, "outer_diameter_margin"] == pytest.approx(1 - 64 / 70) and \
        t.loc[0, "thickness_margin"] == pytest.approx(1 - 9 / 9.5)
    assert t.loc[2, "failed_constraints"] == "strike torque into the gearbox <= 0.8 Nm; k <= 50 Nm/rad"
    assert t.loc[2, "total_violation"] == pytest.approx(0.2 + w * math.sqrt(60 * J) / 0.8 - 1)
    assert t.loc[1, "failed_constraints"] == "strike torque into the gearbox <= 0.8 Nm" and not t.loc[1, "feasible"]


def test_the_working_range_reads_tangents_to_the_stall_torque():
    """A stiffening curve T = a theta + b theta^3 (tangent a + 3 b theta^2): the working range's tangents run
    from a at rest to the tangent at the stall torque, interpolated linearly between the bracketing points."""
    a, b = 10.0, 40.0
    theta = np.linspace(0.0, 0.8, 9)
    row = pd.Series({"large_curve_torque_Nm": list(a * theta + b * theta ** 3),
                     "large_curve_tangent_Nm_per_rad": list(a + 3 * b * theta ** 2)})
    tangents = working_tangents(row, 11.7)
    stall = 11.7
    i = int(np.argmax(a * theta + b * theta ** 3 > stall))
    t0, t1 = a * theta[i - 1] + b * theta[i - 1] ** 3, a * theta[i] + b * theta[i] ** 3
    expected = (a + 3 * b * theta[i - 1] ** 2) + (stall - t0) / (t1 - t0) * 3 * b * (theta[i] ** 2 - theta[i - 1] ** 2)
    assert tangents.min() == a and tangents.max() == pytest.approx(expected, rel=1e-12)
    assert len(tangents) == i + 1


def test_the_binding_window_requirement_and_a_conflict_found_on_the_curves(tmp_path):
    """A linear spring k = 40: one sensor count 40 x 2 pi / 4096 = 0.0614 Nm of 0.1 (38.6 % to spare) binds before
    the sag (2.96 of 10 deg). When each window requirement is met by some design but none meets both, the
    window's requirements conflict on the computed curves: a finding."""
    from seadesign.sweep.requirements import window_verdict

    s = with_limits(_study(tmp_path, "max_standing_deflection_deg = 10.0\nmax_torque_per_count_Nm = 0.1"), 0.2)
    t = constraint_columns(physical_columns(pd.DataFrame([linear_row(s, 0, "a", 40.0, 0.1)]), s), s)
    assert window_verdict(t, 0, s) == ("At a the window's binding requirement is one sensor count <= 0.1 Nm: met "
                                       f"with {100 * (1 - 40 * 2 * math.pi / 4096 / 0.1):.3g} % to spare.")
    # the sag needs k >= 11.9, the count k <= 65.2: a stiff design (70) meets the sag only, a soft one (10) the count only
    t = constraint_columns(physical_columns(pd.DataFrame([linear_row(s, 0, "stiff", 70.0, 0.1),
                                                          linear_row(s, 1, "soft", 10.0, 0.1)]), s), s)
    assert "Finding: the window's requirements conflict on the computed curves" in window_verdict(t, 0, s)
    t = constraint_columns(physical_columns(pd.DataFrame([linear_row(s, 0, "a", 40.0, 0.1),
                                                          linear_row(s, 1, "soft", 10.0, 0.1)]), s), s)
    assert "Finding" not in window_verdict(t, 0, s)  # a meets both
