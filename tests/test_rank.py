"""Ranking on a hand-made table of large-deflection curves: constraints, Pareto front, weighted score,
the unscorable pool, explanation. Linear curves T = k theta give closed-form objectives (bearing arc
r T / k, strike torque w sqrt(k J)); a tanh curve checks the stored-energy reading in closed form."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

from seadesign.design.study import load_study
from seadesign.sweep.rank import pareto_front, rank, strike_torque

ALLOWABLE = 0.433


def test_pareto_front_of_a_known_set():
    # (cost1, cost2): (1,4) (2,2) (4,1) are the front; (3,3) is dominated by (2,2); (2,5) by (1,4)
    obj = np.array([[1, 4], [2, 2], [4, 1], [3, 3], [2, 5]])
    assert pareto_front(obj).tolist() == [True, True, True, False, False]


def _row(study, i: int, name: str, k: float, strain_per_rad: float, stop_Nm: float | None = None) -> dict:
    """A solved candidate whose curve is T = k theta up to the impact torque, or to contact at `stop_Nm`; the
    peak strain grows as strain_per_rad * theta."""
    lc, r = study.load_cases, study.bearing_radius_mm
    reason = "target_reached" if stop_Nm is None else "contact"
    stop = lc.impact_torque_Nm if stop_Nm is None else stop_Nm
    row = {"candidate": name, "beam_count": i + 3, "beam_thickness_mm": 6.0, "status": "ok", "reason": "",
           "row_key": f"{i:032x}", "k_Nm_per_rad": k, "large_curve_rotation_rad": list(np.linspace(0, stop / k, 9)),
           "large_curve_torque_Nm": list(np.linspace(0, stop, 9)), "large_stop_reason": reason,
           "large_stop_rotation_rad": stop / k, "large_stop_torque_Nm": stop, "large_allowable_strain": ALLOWABLE,
           "large_strain_limit_rotation_rad": ALLOWABLE / strain_per_rad,
           "large_strain_limit_torque_Nm": k * ALLOWABLE / strain_per_rad}
    for case, torque in (("standing", study.robot.standing_knee_torque_Nm), ("stall", lc.stall_torque_Nm),
                         ("impact", lc.impact_torque_Nm)):
        theta = torque / k if torque <= stop else math.nan
        row.update({f"large_{case}_rotation_rad": theta, f"large_{case}_peak_strain": strain_per_rad * theta})
    row["large_stall_secant_k_Nm_per_rad"] = k
    row["large_stall_bearing_displacement_mm"] = row["large_stall_rotation_rad"] * r
    return row


def _table(study, rows) -> pd.DataFrame:
    t = pd.DataFrame([_row(study, i, *r) for i, r in enumerate(rows)])
    invalid = {"candidate": "G", "beam_count": 10, "beam_thickness_mm": 8.0, "status": "invalid",
               "reason": "beams touch", "row_key": "f" * 32}
    return pd.concat([t, pd.DataFrame([invalid])], ignore_index=True)


ROWS = [  # name, k (Nm/rad), strain per rad, contact torque (Nm)
    ("A", 20.0, 0.2),
    ("B", 30.0, 0.2),
    ("C", 40.0, 0.2),
    ("E", 60.0, 0.5),  # impact: 27.7 / 60 rad x 0.5 = 0.23 < 0.433; stall fine too -> feasible, stiffest
    ("H", 50.0, 1.0),  # impact strain 0.55 > 0.433
    ("F", 5.0, 0.01),  # too soft: sags standing
    ("K", 25.0, 0.2, 6.0),  # contact at 6 Nm: carries neither stall nor impact
]


@pytest.fixture(scope="module")
def study():
    return load_study()  # allowable strain 0.65 / 1.5; standing limit 10 deg


def test_constraints_front_and_score(study):
    t, choice = rank(_table(study, ROWS), study)
    by = t.set_index("candidate")
    assert by.loc["H", "failed_constraints"] == "impact strain < 0.433"
    assert "standing deflection" in by.loc["F", "failed_constraints"]
    assert by.loc["K", "failed_constraints"] == "carries the stall torque (11.7 Nm); carries the impact torque (27.7 Nm)"
    assert by.loc["G", "failed_constraints"] == "valid geometry"
    feasible = ["A", "B", "C", "E"]
    assert by.loc[feasible, "feasible"].all() and not by.loc[["H", "F", "K", "G"], "feasible"].any()
    k = np.array([20.0, 30.0, 40.0, 60.0])
    # linear curves: every feasible k is on the front (arc ~ 1 / k, strike torque ~ sqrt(k))
    assert by.loc[feasible, "pareto"].all()
    omega = study.ranking.impact_speed_m_per_s / study.robot.lower_leg_m
    strike = omega * np.sqrt(k * study.ranking.knee_inertia_kg_m2)
    # PCHIP of a straight line is the line: stored energy exact, bisected to 1e-18 rad
    assert by.loc[feasible, "impact_gearbox_torque_Nm"].to_numpy() == pytest.approx(strike, rel=1e-12)
    arc = study.load_cases.stall_torque_Nm / k * study.bearing_radius_mm
    acc, prot = (arc.max() - arc) / (arc.max() - arc.min()), (strike.max() - strike) / (strike.max() - strike.min())
    expected = 0.5 * acc + 0.5 * prot
    assert by.loc[feasible, "score"].to_numpy() == pytest.approx(expected, rel=1e-12)
    best = feasible[int(np.argmax(expected))]
    assert t.loc[choice.index, "candidate"] == best and choice.feasible
    assert best in choice.explanation and "runner-up" in choice.explanation
    assert by.loc["A", "standing_deflection_deg"] == pytest.approx(np.degrees(study.robot.standing_knee_torque_Nm / 20))


def test_weights_move_the_choice(study):
    accurate = dataclasses.replace(study, ranking=dataclasses.replace(study.ranking, weight_accuracy=1.0,
                                                                      weight_protection=0.0))
    protective = dataclasses.replace(study, ranking=dataclasses.replace(study.ranking, weight_accuracy=0.0,
                                                                        weight_protection=1.0))
    t, c = rank(_table(study, ROWS), accurate)
    assert t.loc[c.index, "candidate"] == "E"  # stiffest feasible: smallest arc
    t, c = rank(_table(study, ROWS), protective)
    assert t.loc[c.index, "candidate"] == "A"  # softest feasible spring


def test_a_pool_that_stops_before_stall_is_ordered_by_the_usable_torque(study):
    """Usable: the smaller of the stop torque and where the strain passes the allowable. S stops at 9 Nm but
    passes the allowable at 0.433 / 3 rad x 30 Nm/rad = 4.33 Nm, below both loads: it misses the strain at
    stall and impact too, so it fails four requirements and the others two."""
    rows = [("P", 20.0, 0.2, 5.0), ("Q", 30.0, 0.2, 8.0), ("R", 25.0, 0.2, 7.0), ("S", 30.0, 3.0, 9.0)]
    t, c = rank(_table(study, rows), study)
    by = t.set_index("candidate")
    assert by.loc["S", "usable_torque_Nm"] == pytest.approx(4.33) and by.loc["Q", "usable_torque_Nm"] == 8.0
    assert by.loc["S", "failed_constraints"] == ("carries the stall torque (11.7 Nm); carries the impact torque "
                                                 "(27.7 Nm); stall strain < 0.433; impact strain < 0.433")
    # the margins: travel 9 / 11.7 - 1, strain 4.33 / 11.7 - 1 at stall (and / 27.7 at impact)
    assert by.loc["S", "stall_travel_margin"] == pytest.approx(9 / 11.7 - 1)
    assert by.loc["S", "stall_strain_margin"] == pytest.approx(4.33 / 11.7 - 1, rel=1e-3)
    assert not c.feasible and t.loc[c.index, "candidate"] == "Q"
    assert by.loc[["Q", "R", "P"], "rank"].tolist() == [1, 2, 3] and pd.isna(by.loc["S", "rank"])
    assert t["score"].isna().all() and "most usable torque" in c.explanation and "8 Nm usable" in c.explanation


def test_k_range_and_no_feasible_candidate(study):
    narrow = dataclasses.replace(study, requirements=dataclasses.replace(study.requirements, k_min_Nm_per_rad=100.0))
    t, c = rank(_table(study, ROWS), narrow)
    assert not t["feasible"].any() and not c.feasible
    assert "No candidate meets every hard constraint" in c.explanation
    assert t.loc[c.index, "n_failed_constraints"] == t.loc[t["status"] == "ok", "n_failed_constraints"].min()


def _path_row(theta: np.ndarray, torque: np.ndarray, stop_rad: float, stop_Nm: float) -> pd.Series:
    return pd.Series({"large_curve_rotation_rad": list(theta), "large_curve_torque_Nm": list(torque),
                      "large_stop_rotation_rad": stop_rad, "large_stop_torque_Nm": stop_Nm})


def test_strike_torque_of_a_softening_curve():
    """T = A tanh(theta / B) stores E(theta) = A B ln cosh(theta / B): the torque at energy E is
    A tanh(acosh(exp(E / (A B))))."""
    a, b = 15.0, 0.8
    theta = np.linspace(0.0, 1.2, 25)
    row = _path_row(theta, a * np.tanh(theta / b), theta[-1], a * math.tanh(theta[-1] / b))
    for energy in (0.01, 0.5, 3.0):
        exact = a * math.tanh(math.acosh(math.exp(energy / (a * b))))
        # PCHIP through 25 points: measured 1.9e-5 relative at most
        assert strike_torque(row, energy) == pytest.approx(exact, rel=6e-5)
    assert math.isnan(strike_torque(row, 20.0))  # stores at most 6.1 J


def test_strike_torque_of_a_path_that_ends_at_a_limit_point():
    """T = A sin(theta / B) up to its maximum at pi B / 2, where the path stops; its last point lies past the
    maximum (the path found it there), and the curve is read up to the stop. E(theta) = A B (1 - cos(theta / B)):
    the torque at energy E is A sin(acos(1 - E / (A B)))."""
    a, b = 6.0, 0.2
    top = math.pi * b / 2
    theta = np.append(np.linspace(0.0, 0.95 * top, 20), 1.1 * top)
    row = _path_row(theta, a * np.sin(theta / b), top, a)
    for energy in (0.05, 0.3):  # of at most A B = 1.2 J
        exact = a * math.sin(math.acos(1 - energy / (a * b)))
        # PCHIP through 21 points: measured 8.7e-6 and 2.1e-5 relative
        assert strike_torque(row, energy) == pytest.approx(exact, rel=6e-5)
