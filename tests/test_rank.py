"""Ranking on a hand-made table of large-deflection curves (`helpers_curves`): requirements judged and met,
conditional designs, the deciding objective, the Pareto front, the explanation. Linear curves T = k theta
give closed-form requirements (sag T / k, natural frequency sqrt(k / J) / 2 pi, one sensor count k q, strike
torque w sqrt(k J)); a tanh curve checks the stored-energy reading in closed form."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

from helpers_curves import table, with_limits
from seadesign.design.spring import TorqueCurve
from seadesign.design.study import load_study
from seadesign.sweep.handoff import curve_to_stop
from seadesign.sweep.rank import pareto_front, rank
from seadesign.sweep.requirements import STRAIN_TORQUE_KNOCKDOWN


def test_pareto_front_of_a_known_set():
    # (cost1, cost2): (1,4) (2,2) (4,1) are the front; (3,3) is dominated by (2,2); (2,5) by (1,4)
    obj = np.array([[1, 4], [2, 2], [4, 1], [3, 3], [2, 5]])
    assert pareto_front(obj).tolist() == [True, True, True, False, False]


def test_pareto_front_is_the_definition_of_domination_with_ties():
    """Against the definition written out (a row is dominated by one no worse in every objective and better in
    one), on random sets with many equal values: equal rows do not dominate each other."""
    rng = np.random.default_rng(0)
    for _ in range(300):
        obj = rng.integers(0, 4, (int(rng.integers(1, 25)), int(rng.integers(1, 4)))).astype(float)
        dominated = [(np.all(obj <= f, axis=1) & np.any(obj < f, axis=1)).any() for f in obj]
        assert pareto_front(obj).tolist() == [not d for d in dominated]
    assert pareto_front(np.empty((0, 2))).tolist() == []


ROWS = [  # name, k (Nm/rad), tensile strain per rad, stop torque (Nm; None: the impact torque), mass (g)
    ("A", 20.0, 0.2, None, 30.0),  # stall strain 0.117 of 0.2 cyclic; impact 0.277 of 0.433: feasible, softest
    ("B", 30.0, 0.2, None, 25.0),
    ("C", 40.0, 0.2, None, 22.0),  # the lightest feasible
    ("E", 60.0, 0.5, None, 40.0),  # one count 60 x 2 pi / 4096 = 0.092 Nm of 0.1: feasible, stiffest
    ("T", 70.0, 0.2, None, 20.0),  # one count 0.107 Nm: too stiff for the sensor
    ("H", 50.0, 1.0, None, 20.0),  # stall strain 0.234 > 0.2 cyclic, impact 0.554 > 0.433
    ("F", 5.0, 0.01, None, 10.0),  # too soft: sags 23.7 deg standing, 3.56 Hz
    ("K", 25.0, 0.2, 6.0, 20.0),  # ends at 6 Nm: carries neither stall nor impact
]


@pytest.fixture(scope="module")
def study():
    """The default study (sag 10 deg, one count 0.1 Nm, 5 Hz, strike 11.7 Nm; softest_k decides) with a cyclic
    strain limit of 0.2 and NinjaFlex's elongation at yield 0.65 (single-event limit 0.65 / 1.5)."""
    return with_limits(load_study(), 0.2)


def test_requirements_front_and_the_softest_feasible_choice(study):
    t, choice = rank(table(study, ROWS), study)
    by = t.set_index("candidate")
    assert by.loc["H", "failed_constraints"] == ("stall tensile strain within the cyclic limit; impact tensile strain "
                                                 "within the single-event limit")
    assert by.loc["T", "failed_constraints"] == "one sensor count <= 0.1 Nm"
    assert by.loc["F", "failed_constraints"] == "standing deflection <= 10 deg; natural frequency >= 5 Hz"
    assert by.loc["K", "failed_constraints"] == "carries the stall torque (11.7 Nm); carries the impact torque (27.7 Nm)"
    assert by.loc["G", "failed_constraints"] == "valid geometry"
    feasible = ["A", "B", "C", "E"]
    assert by.loc[feasible, "feasible"].all() and not by.loc[["T", "H", "F", "K", "G"], "feasible"].any()
    assert not by["conditional"].any()
    assert t.loc[choice.index, "candidate"] == "A" and choice.feasible and not choice.conditional
    assert t.loc[choice.runner_up, "candidate"] == "B"
    assert by.loc[feasible, "rank"].tolist() == [1, 2, 3, 4]
    assert "A meets every requirement" in choice.explanation and "Runner-up: B" in choice.explanation
    # k and mass: C (40, 22 g) is dominated by nobody; A, B, C, E all trade k against mass except E (heavier, stiffer)
    assert by.loc[["A", "B", "C"], "pareto"].all() and not by.loc["E", "pareto"]
    # closed forms of a linear spring
    J, w = study.ranking.knee_inertia_kg_m2, study.strike_speed_rad_per_s
    assert by.loc["A", "impact_gearbox_torque_Nm"] == pytest.approx(w * math.sqrt(20.0 * J), rel=1e-12)
    assert by.loc["F", "natural_frequency_Hz"] == pytest.approx(math.sqrt(5.0 / J) / (2 * math.pi), rel=1e-12)
    assert by.loc["E", "torque_per_count_Nm"] == pytest.approx(60.0 * 2 * math.pi / 4096, rel=1e-12)
    assert by.loc["A", "standing_deflection_deg"] == pytest.approx(np.degrees(study.robot.standing_knee_torque_Nm / 20))
    # the strain against each load's class: the cyclic limit crossed at 0.2 / 0.2 rad = 20 Nm for A; the impact's
    # single-event limit (0.433 at 2.17 rad, 43 Nm) lies past the path: limit / strain at the load - 1
    # (the path mesh's knock-down applies: torques at a limit x KD, strains at a load / KD)
    kd = STRAIN_TORQUE_KNOCKDOWN
    assert by.loc["A", "stall_strain_margin"] == pytest.approx(kd * 20.0 / 11.7 - 1, rel=1e-9)
    assert by.loc["A", "impact_strain_margin"] == pytest.approx(kd * 0.65 / 1.5 / (0.2 * 27.7 / 20.0) - 1, rel=1e-3)


def test_the_deciding_objective_moves_the_choice(study):
    def choose(*objectives):
        s = dataclasses.replace(study, requirements=dataclasses.replace(study.requirements, objectives=objectives))
        t, c = rank(table(study, ROWS), s)
        return t.loc[c.index, "candidate"]

    assert choose("mass") == "C"  # the lightest feasible
    assert choose("accuracy") == "E"  # the stiffest feasible: the smallest arc at stall
    assert choose("protection") == "A"  # the softest: strike torque w sqrt(k J)
    assert choose("strain_margin") == "C"  # the smallest share of a limit used (0.2 x 27.7 / 40 of 0.433)


def test_a_requirement_that_cannot_be_judged_is_not_met(study):
    """Without a cyclic strain limit nothing is feasible: the designs that meet every judged requirement are
    conditional, the choice among them says so, and names the value the missing datum must reach."""
    unsourced = with_limits(study, None)
    t, c = rank(table(unsourced, ROWS), unsourced)
    by = t.set_index("candidate")
    assert not t["feasible"].any()
    assert by.loc[["A", "B", "C", "E"], "conditional"].all() and not by.loc[["T", "H", "F", "K"], "conditional"].any()
    assert not c.feasible and c.conditional and t.loc[c.index, "candidate"] == "A"
    # A's tensile strain at stall: 0.2 / rad x 11.7 / 20 rad = 11.7 % (over the knock-down)
    needed = 100 * 0.2 * 11.7 / 20 / STRAIN_TORQUE_KNOCKDOWN
    assert f"passes if NinjaFlex TPU 85A's cyclic strain limit is at least {needed:.3g} %" in c.explanation
    assert np.isnan(by.loc["A", "stall_strain_margin"])
    no_yield = with_limits(study, 0.2, elongation=None)
    t, c = rank(table(no_yield, ROWS), no_yield)
    # A's impact strain 0.2 x 27.7 / 20 = 0.277, needing 0.277 x 1.5 = 41.5 % elongation at yield (over the knock-down)
    needed = 100 * 0.2 * unsourced.load_cases.impact_torque_Nm / 20 * 1.5 / STRAIN_TORQUE_KNOCKDOWN
    assert c.conditional and f"elongation at yield is at least {needed:.3g} %" in t.loc[c.index, "not_judged"]


def test_when_nothing_is_feasible_the_report_names_the_block(study):
    rows = [("P", 20.0, 0.2, 5.0), ("Q", 30.0, 0.2, 8.0), ("R", 70.0, 0.2, 9.0)]
    t, c = rank(table(study, rows), study)
    by = t.set_index("candidate")
    assert not c.feasible and not c.conditional
    # P and Q miss the two loads; R misses the loads and the sensor: the fewest failures are P and Q, and Q
    # misses by less in total (travel 8 / 11.7 - 1 and 8 / 27.7 - 1 against 5 / 11.7 - 1 and 5 / 27.7 - 1)
    assert t.loc[c.index, "candidate"] == "Q" and t.loc[c.runner_up, "candidate"] == "P"
    assert pd.isna(by.loc["R", "rank"])
    assert by.loc["Q", "total_violation"] == pytest.approx(2 - 8 / 11.7 - 8 / study.load_cases.impact_torque_Nm)
    assert "NOT a recommendation" in c.explanation
    assert "misses carries the impact torque (27.7 Nm) (by 71.1 %); carries the stall torque" in c.explanation
    assert "its path ends unconverged before a load: a stiffer material or a larger envelope" in c.explanation


def test_a_strike_the_curve_cannot_store_misses_protection(study):
    """A stiff spring that stops at 0.1 Nm stores 0.1^2 / (2 k) J, far less than the strike's J w^2 / 2: the
    strike margin is the stored energy's shortfall."""
    t, _ = rank(table(study, [("S", 1000.0, 0.01, 0.1)], invalid=False), study)
    energy = 0.5 * study.ranking.knee_inertia_kg_m2 * study.strike_speed_rad_per_s ** 2
    assert np.isnan(t.loc[0, "impact_gearbox_torque_Nm"])
    assert t.loc[0, "strike_margin"] == pytest.approx(0.1 ** 2 / 2000.0 / energy - 1, rel=1e-9)


def strike_torque(row: pd.Series, energy_J: float) -> float:
    torque = TorqueCurve(*map(tuple, curve_to_stop(row))).torque_at_energy(energy_J)
    return math.nan if torque is None else torque


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


def test_the_standing_verdict_says_where_a_path_ends_below_the_standing_torque():
    """A curve that ends below the standing torque has no standing deflection: the verdict says where and why the
    path ended instead of printing nan."""
    import pandas as pd

    from seadesign.design.study import load_study
    from seadesign.report.verdicts import standing_verdict

    study = load_study()
    ranked = pd.DataFrame({"candidate": ["short", "long"], "k_Nm_per_rad": [8.02, 30.0],
                           "standing_deflection_deg": [float("nan"), 4.0], "standing_knee_torque_Nm": [2.07, 2.07],
                           "large_stop_torque_Nm": [1.71, 7.1], "large_stop_reason": ["contact", "contact"]})
    assert standing_verdict(ranked, "short", study) == (
        "short: k 8.02 Nm/rad, its path ends at 1.71 Nm (contact), below the standing torque 2.07 Nm: does NOT carry "
        "the standing load")
    assert standing_verdict(ranked, "long", study).endswith("standing deflection 4 deg under 2.07 Nm (limit 10 deg): "
                                                            "carries the standing load")


def test_what_would_unblock_a_design_says_where_contact_ended_its_path():
    import pandas as pd

    from seadesign.design.study import load_study
    from seadesign.sweep.rank import unblock

    study = load_study()
    row = pd.Series({"stall_travel_margin": -0.5, "impact_travel_margin": -0.7, "large_stop_reason": "unconverged",
                     "large_unconverged_cause": "contact_unconverged", "large_unconverged_rotation_rad": 0.4235,
                     "large_unconverged_at_x_mm": 1.86, "large_unconverged_at_y_mm": 14.04})
    assert unblock(row, study) == ("What would unblock it: its path ends unconverged in contact before a load "
                                   "(contact unconverged at 0.4235 rad, at x 1.9, y 14.0 mm): a stiffer material or "
                                   "a larger envelope.")
    plain = row.drop(["large_unconverged_cause"]).copy()
    assert unblock(plain, study) == ("What would unblock it: its path ends unconverged before a load: a stiffer "
                                     "material or a larger envelope.")
    buckled = plain.copy()
    buckled["large_stop_reason"] = "bifurcation"
    assert unblock(buckled, study).startswith("What would unblock it: its path ends in a bifurcation before a load")
