"""Ranking on a hand-made table: constraints, Pareto front, weighted score, explanation."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

from seadesign.sweep.rank import pareto_front, rank
from seadesign.design.study import load_study


def test_pareto_front_of_a_known_set():
    # (cost1, cost2): (1,4) (2,2) (4,1) are the front; (3,3) is dominated by (2,2); (2,5) by (1,4)
    obj = np.array([[1, 4], [2, 2], [4, 1], [3, 3], [2, 5]])
    assert pareto_front(obj).tolist() == [True, True, True, False, False]


def _table(study) -> pd.DataFrame:
    """Five solved candidates plus one invalid; displacements set by hand so that B and D are dominated."""
    rows = [  # name, k Nm/rad, stall displacement mm, peak von Mises MPa (stall, impact)
        ("A", 20.0, 5.0, 1.0, 2.0),
        ("B", 30.0, 6.0, 1.0, 2.0),  # stiffer (worse protection) and less accurate than A
        ("C", 40.0, 3.0, 1.0, 2.0),
        ("D", 50.0, 3.5, 1.0, 2.0),  # dominated by C
        ("E", 60.0, 2.0, 1.0, 9.0),  # over-stressed at impact
        ("F", 5.0, 20.0, 1.0, 2.0),  # too soft: sags standing
    ]
    t = pd.DataFrame([{"candidate": n, "beam_count": i + 3, "beam_thickness_mm": 6.0, "status": "ok", "reason": "",
                       "row_key": f"{i:032x}", "k_Nm_per_rad": k, "stall_bearing_displacement_mm": d,
                       "stall_rotation_rad": study.load_cases.stall_torque_Nm / k,
                       "impact_rotation_rad": study.load_cases.impact_torque_Nm / k,
                       "stall_von_mises_max_MPa": s1, "impact_von_mises_max_MPa": s2}
                      for i, (n, k, d, s1, s2) in enumerate(rows)])
    invalid = {"candidate": "G", "beam_count": 10, "beam_thickness_mm": 8.0, "status": "invalid",
               "reason": "beams touch", "row_key": "f" * 32}
    return pd.concat([t, pd.DataFrame([invalid])], ignore_index=True)


@pytest.fixture(scope="module")
def study():
    return load_study()  # yield 4 MPa / safety factor 1.5 -> 2.67 MPa allowed; standing limit 10 deg


def test_constraints_front_and_score(study):
    t, choice = rank(_table(study), study)
    by = t.set_index("candidate")
    assert not by.loc["E", "feasible"] and "impact stress" in by.loc["E", "failed_constraints"]
    assert not by.loc["F", "feasible"] and "standing deflection" in by.loc["F", "failed_constraints"]
    assert not by.loc["G", "feasible"] and by.loc["G", "failed_constraints"] == "valid geometry"
    assert by.loc[["A", "B", "C", "D"], "feasible"].all()
    assert by.loc[["A", "B", "C", "D"], "pareto"].tolist() == [True, False, True, False]
    # equal weights; accuracy from displacements 5, 6, 3, 3.5; protection ~ sqrt(k)
    s = np.sqrt([20.0, 30.0, 40.0, 50.0])
    prot = (s.max() - s) / (s.max() - s.min())
    acc = (6.0 - np.array([5.0, 6.0, 3.0, 3.5])) / 3.0
    expected = 0.5 * acc + 0.5 * prot
    assert by.loc[["A", "B", "C", "D"], "score"].to_numpy() == pytest.approx(expected)
    best = ["A", "B", "C", "D"][int(np.argmax(expected))]
    assert t.loc[choice.index, "candidate"] == best and choice.feasible
    assert best in choice.explanation and "runner-up" in choice.explanation


def test_weights_move_the_choice(study):
    accurate = dataclasses.replace(study, ranking=dataclasses.replace(study.ranking, weight_accuracy=1.0,
                                                                      weight_protection=0.0))
    protective = dataclasses.replace(study, ranking=dataclasses.replace(study.ranking, weight_accuracy=0.0,
                                                                        weight_protection=1.0))
    t, c = rank(_table(study), accurate)
    assert t.loc[c.index, "candidate"] == "C"  # smallest displacement among feasible
    t, c = rank(_table(study), protective)
    assert t.loc[c.index, "candidate"] == "A"  # softest feasible spring


def test_k_range_and_no_feasible_candidate(study):
    narrow = dataclasses.replace(study, ranking=dataclasses.replace(study.ranking, k_min_Nm_per_rad=100.0))
    t, c = rank(_table(study), narrow)
    assert not t["feasible"].any() and not c.feasible
    assert "No candidate meets every hard constraint" in c.explanation
    assert t.loc[c.index, "n_failed_constraints"] == t.loc[t["status"] == "ok", "n_failed_constraints"].min()


def test_physical_protection_columns(study):
    t, _ = rank(_table(study), study)
    k = t["k_Nm_per_rad"]
    omega = study.ranking.impact_speed_m_per_s / study.robot.lower_leg_m
    # energy balance: J w^2 / 2 = tau^2 / (2 k)
    tau = t["impact_gearbox_torque_Nm"]
    assert (tau ** 2 / (2 * k)).dropna().to_numpy() == pytest.approx(
        [0.5 * study.ranking.knee_inertia_kg_m2 * omega ** 2] * 6)
    assert t["impact_energy_J"].iloc[0] == pytest.approx(study.load_cases.impact_torque_Nm ** 2 / 40.0)
    assert bool(t["extrapolation"].iloc[0]) == (study.load_cases.impact_torque_Nm / 20.0 > 0.1)
    assert math.isnan(t["thesis_reaction_N"].iloc[0])
