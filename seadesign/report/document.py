"""report.md and a self-contained report.html (images inlined as base64) of a ranked sweep."""

from __future__ import annotations

import base64
import html
import importlib.util
from pathlib import Path

import pandas as pd

SUMMARY_COLUMNS = [
    "candidate", "status", "mass_g", "k_Nm_per_rad", "k_rel_error", "large_stop_reason", "large_stop_rotation_rad",
    "large_stop_torque_Nm", "large_strain_limit_torque_Nm", "usable_torque_Nm", "large_stall_rotation_rad", "large_stall_secant_k_Nm_per_rad",
    "large_stall_tangent_k_Nm_per_rad", "large_stall_bearing_displacement_mm", "large_stall_peak_strain",
    "large_stall_strain_margin", "large_stall_survives", "large_impact_survives", "standing_deflection_deg",
    "impact_gearbox_torque_Nm", "stall_rotation_rad", "stall_von_mises_max_MPa", "thesis_reaction_N",
    "thesis_displacement_mm", "feasible", "pareto", "score", "rank", "failed_constraints", "reason",
]


def summary_table(t: pd.DataFrame) -> pd.DataFrame:
    cols = [c for c in SUMMARY_COLUMNS if c in t.columns]
    return t[cols].round(4)


def sections(study, t: pd.DataFrame, explanation: str, settings: dict) -> list[tuple[str, str]]:
    """(heading, markdown-free text) pairs shared by both documents."""
    removed = t[t["n_failed_constraints"] > 0]
    counts = {}
    for text in removed["failed_constraints"]:
        for c in filter(None, text.split("; ")):
            counts[c] = counts.get(c, 0) + 1
    lc, rk = study.load_cases, study.ranking
    return [
        ("Study", f"{study.name}: {study.description}. Material "
                  + ", ".join(f"{m.name} (E = {m.youngs_modulus_Pa / 1e6:.4g} MPa, yield {m.yield_strength_Pa / 1e6:.3g} MPa)"
                              for m in study.materials.values()) + ". "
                  f"Stall torque {lc.stall_torque_Nm:g} Nm on the hub; impact torque {lc.impact_torque_Nm:.2f} Nm on the "
                  f"backplate side; standing knee torque {study.robot.standing_knee_torque_Nm:.2f} Nm. "
                  f"Mesh: {study.mesh.elements_across_beam:g} elements across a beam ({study.mesh.backend})."),
        ("Choice", explanation),
        ("Constraints that removed candidates",
         "; ".join(f"{c}: {n} candidates" for c, n in counts.items()) or "none"),
        ("Objectives", "accuracy = the arc the bearing circle turns through at the stall torque, read from the "
                       "large-deflection curve (mm); protection = peak torque a foot strike drives into the gearbox: "
                       "the torque where the curve has stored the leg's kinetic energy J w^2 / 2, with "
                       f"w = {rk.impact_speed_m_per_s:g} m/s / lower leg and J = {rk.knee_inertia_kg_m2:g} kg m^2; "
                       f"weights {rk.weight_accuracy:g} / {rk.weight_protection:g}."),
        ("Large deflection", large_deflection_summary(t)),
        ("Linear model", "The linear results (k at small load, stall rotation torque / k, von Mises stresses) stay in "
                         "the table for comparison with the thesis; at these loads they are outside their range, so "
                         "nothing is ranked on them and yield stress against a linear stress is not a criterion."),
        ("Settings and versions", ", ".join(f"{k}: {v}" for k, v in settings.items())),
    ]


def large_deflection_summary(t: pd.DataFrame) -> str:
    """How the solved candidates' torque paths went, in words: where they stop and why, and the strain limit."""
    solved = t[t["status"] == "ok"]
    if solved.empty or "large_stop_reason" not in solved:
        return "No candidate was solved."
    stops = solved["large_stop_reason"].value_counts()
    allowable = solved["large_allowable_strain"].dropna()
    text = ("Each solved candidate's hub is rotated (hyperelastic finite-strain FEA, hub held as the servo holds it) "
            "until the impact torque or a stop. Stops: " + ", ".join(f"{r}: {n}" for r, n in stops.items()) + ". "
            f"{int(solved['large_stall_survives'].astype(bool).sum())} of {len(solved)} carry the stall torque within "
            f"the allowable strain; {int(solved['large_impact_survives'].astype(bool).sum())} the impact torque. Torque "
            f"carried before the path stops: {solved['large_stop_torque_Nm'].min():.3g}-"
            f"{solved['large_stop_torque_Nm'].max():.3g} Nm.")
    if not allowable.empty:
        passed = solved["large_strain_limit_torque_Nm"].dropna()
        text += (f" Allowable strain {allowable.iloc[0]:.3g} (elongation at yield / safety factor): passed by "
                 f"{len(passed)} candidates" + (f", at {passed.min():.3g}-{passed.max():.3g} Nm." if len(passed) else "."))
    return text


def write_markdown(path: Path, study, t: pd.DataFrame, explanation: str, settings: dict, images: dict[str, Path]) -> Path:
    lines = [f"# Design sweep: {study.name}", ""]
    for head, text in sections(study, t, explanation, settings):
        lines += [f"## {head}", "", text, ""]
    lines += ["## Results", "", summary_table(t).to_markdown(index=False) if _has_tabulate() else
              "```\n" + summary_table(t).to_string(index=False) + "\n```", ""]
    lines += ["## Figures", ""] + [f"![{title}]({p.name})" for title, p in images.items()] + [""]
    path.write_text("\n".join(lines))
    return path


def write_html(path: Path, study, t: pd.DataFrame, explanation: str, settings: dict, images: dict[str, Path]) -> Path:
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>Design sweep: {html.escape(study.name)}</title>",
             "<style>body{font-family:sans-serif;max-width:1200px;margin:auto}table{border-collapse:collapse;"
             "font-size:11px}td,th{border:1px solid #ccc;padding:2px 4px}img{max-width:100%}</style></head><body>",
             f"<h1>Design sweep: {html.escape(study.name)}</h1>"]
    for head, text in sections(study, t, explanation, settings):
        parts.append(f"<h2>{html.escape(head)}</h2><p>{html.escape(text)}</p>")
    parts.append("<h2>Results</h2>" + summary_table(t).to_html(index=False, na_rep=""))
    parts.append("<h2>Figures</h2>")
    for title, p in images.items():
        data = base64.b64encode(p.read_bytes()).decode()
        parts.append(f"<h3>{html.escape(title)}</h3><img alt='{html.escape(title)}' src='data:image/png;base64,{data}'>")
    parts.append("</body></html>")
    path.write_text("\n".join(parts))
    return path


def _has_tabulate() -> bool:
    """pandas' to_markdown needs the optional tabulate package."""
    return importlib.util.find_spec("tabulate") is not None
