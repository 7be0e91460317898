"""The sweep's report page: the choice and why first, then the ranked candidates, plots, the render, and
the full table and settings collapsed."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from seadesign.report.document import Page, compact_table, summary_table
from seadesign.sweep.rank import Choice
from seadesign.sweep.requirements import OBJECTIVE_WORDS, STRAIN_TORQUE_KNOCKDOWN, limit_torque, window_verdict

RANKED_SHOWN = 10  # candidates in the compact table


def large_deflection_summary(t: pd.DataFrame) -> str:
    """How the solved candidates' torque paths went, in words: where they stop and why, and the strain limits."""
    solved = t[t["status"] == "ok"]
    if solved.empty or "large_stop_reason" not in solved:
        return "No candidate was solved."
    stops = solved["large_stop_reason"].value_counts()
    text = ("Each solved candidate's hub is rotated (hyperelastic finite-strain FEA, hub held as the servo holds it) "
            "until the impact torque or a stop. Stops: " + ", ".join(f"{r}: {n}" for r, n in stops.items()) + ". "
            f"{int(solved['large_stall_survives'].astype(bool).sum())} of {len(solved)} carry the stall torque within "
            f"the cyclic strain limit; {int(solved['large_impact_survives'].astype(bool).sum())} the impact torque "
            f"within the single-event limit. Torque carried before the path stops: "
            f"{solved['large_stop_torque_Nm'].min():.3g}-{solved['large_stop_torque_Nm'].max():.3g} Nm. Strains are "
            "tensile principal strains (along directions of tensile principal stress); a squeezed region's bulge "
            "is reported as compression beside them. The path mesh reaches a strain at a higher torque than the "
            f"default mesh, so its strain-limit torques are knocked down by x {STRAIN_TORQUE_KNOCKDOWN:.3g} (and its "
            "strains at a load raised by its inverse).")
    for kind, words in (("cyclic", "cyclic strain limit (repeating loads)"),
                        ("single", "single-event strain limit (elongation at yield / safety factor)")):
        limit = solved[f"large_{kind}_strain_limit"].dropna()
        if limit.empty:
            text += f" No sourced {words}: not judged, so not met."
            continue
        passed = limit_torque(solved, kind).dropna()
        text += (f" {words[0].upper() + words[1:]} {limit.iloc[0]:.3g}: passed by {len(passed)} candidates"
                 + (f", at {passed.min():.3g}-{passed.max():.3g} Nm." if len(passed) else "."))
    return text


def constraint_counts(t: pd.DataFrame) -> str:
    """How many candidates each requirement removed, in words."""
    counts: dict[str, int] = {}
    for text in t.loc[t["n_failed_constraints"] > 0, "failed_constraints"]:
        for c in filter(None, text.split("; ")):
            counts[c] = counts.get(c, 0) + 1
    return "; ".join(f"{c}: {n} candidates" for c, n in counts.items()) or "none"


def study_text(study) -> str:
    lc = study.load_cases
    return (f"{study.name}: {study.description}. Material "
            + ", ".join(f"{m.name} (E = {m.youngs_modulus_Pa / 1e6:.4g} MPa, yield {m.yield_strength_Pa / 1e6:.3g} MPa)"
                        for m in study.materials.values()) + ". "
            f"Stall torque {lc.stall_torque_Nm:g} Nm on the hub; impact torque {lc.impact_torque_Nm:.2f} Nm on the "
            f"backplate side; standing knee torque {study.robot.standing_knee_torque_Nm:.2f} Nm. "
            f"Mesh: {study.mesh.elements_across_beam:g} elements across a beam ({study.mesh.backend}).")


def objectives_text(study) -> str:
    """The objectives, the deciding one first, and the k window the requirements imply, in words."""
    rk, objectives = study.ranking, study.requirements.objectives
    return (f"Deciding objective: {OBJECTIVE_WORDS[objectives[0]]}, minimised among the designs that meet every "
            "requirement, each judged; mass breaks ties" + (f"; the front also shows {', '.join(OBJECTIVE_WORDS[o] for o in objectives[1:])}"
                                                          if len(objectives) > 1 else "") + ". "
            f"{study.k_window.describe()}. Every requirement is judged at the material's room-temperature modulus: "
            "heat softening (the thesis's spring softened with use, sec. 7) is not modelled. "
            "Accuracy = the arc the bearing circle turns through at the stall torque, read from the large-deflection "
            "curve (mm); protection = peak torque a foot strike drives into the gearbox: the torque where the curve has "
            "stored the leg's kinetic energy J w^2 / 2, with "
            f"w = {rk.impact_speed_m_per_s:g} m/s / lower leg and J = {rk.knee_inertia_kg_m2:g} kg m^2.")


LINEAR_NOTE = ("The linear results (k at small load, stall rotation torque / k, von Mises stresses) stay in the table for "
               "comparison with the thesis; at these loads they are outside their range, so nothing is ranked on them "
               "and yield stress against a linear stress is not a criterion.")


@dataclass(frozen=True)
class Baseline:
    """The uncalibrated sweep a calibrated one is compared with: what was calibrated (`note`), its ranked table
    and its choice."""

    note: str
    ranked: pd.DataFrame
    choice: Choice


def _verdict(t: pd.DataFrame, candidate: str) -> tuple[str, str]:
    row = t.loc[t["candidate"] == candidate].iloc[0]
    meets = "yes" if bool(row["feasible"]) else "no"
    return meets, str(row["failed_constraints"]) or "-"


def calibration_text(baseline: Baseline, t: pd.DataFrame, choice: Choice) -> str:
    """The calibrated materials and the choice without and with the calibration, side by side, each judged with
    the calibrated material."""
    if baseline.choice.index is None or choice.index is None:
        return f"{baseline.note}. No candidate was solved, so there is no choice to compare."
    before = baseline.ranked.loc[baseline.choice.index, "candidate"]
    after = t.loc[choice.index, "candidate"]
    rows = [("uncalibrated choice", before), ("calibrated choice", after)]
    lines = ["| | candidate | meets every requirement (calibrated material) | misses |", "|---|---|---|---|"]
    lines += [f"| {label} | {name} | {' | '.join(_verdict(t, name))} |" for label, name in rows]
    return (f"Calibrated: {baseline.note}. The choice {'is unchanged' if before == after else 'changes'}: "
            f"{before} -> {after}.\n\n" + "\n".join(lines))


def sweep_page(study, t: pd.DataFrame, choice: Choice, settings: dict, figures: dict[str, Path],
               renders: dict[str, Path], baseline: Baseline | None = None) -> Page:
    """The sweep's report."""
    if choice.index is None:
        headline, feasible = "No candidate was solved, so none can be chosen.", False
    else:
        name = t.loc[choice.index, "candidate"]
        row = t.loc[choice.index]
        headline = (f"Print {name}: it meets every requirement, each judged, and ranks first." if choice.feasible else
                    f"No candidate meets every requirement with each judged; {name} meets every judged one, "
                    f"conditionally: {row['not_judged']}." if choice.conditional else
                    f"No candidate meets every requirement: NOT a recommendation. The nearest is {name} "
                    f"(misses: {row['failed_constraints']}).")
        feasible = choice.feasible
    ranked = t[t["rank"].notna()].sort_values("rank").head(RANKED_SHOWN)
    return Page(
        title=f"Design sweep: {study.name}",
        headline=headline, feasible=feasible,
        why=[choice.explanation, study.k_window.describe() + ". " + ("" if choice.index is None else
                                                                    window_verdict(t, choice.index, study)),
             f"Requirements that removed candidates: {constraint_counts(t)}.", large_deflection_summary(t)],
        table=compact_table(ranked, [("rank", "rank")]),
        table_caption=f"Ranked candidates (the first {len(ranked)})",
        figures=figures, renders=renders,
        sections=([("Calibration", calibration_text(baseline, t, choice))] if baseline is not None else [])
                 + [
                  ("Study", study_text(study)), ("Objectives", objectives_text(study)), ("Linear model", LINEAR_NOTE),
                  ("Input files", study.files.describe())],
        details=[("All candidates (full table)", summary_table(t)),
                 ("Settings and versions", ", ".join(f"{k}: {v}" for k, v in settings.items()))],
    )
