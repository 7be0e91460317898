"""Reports people read: the decision first, then a compact table, the plots, the renders, and the full
table and settings collapsed. One `Page` is written as report.md and as a self-contained report.html
(images inlined as base64, laid out for a laptop screen); the sweep and the explorer each build theirs.
"""

from __future__ import annotations

import base64
import html
import importlib.util
import math
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

SUMMARY_COLUMNS = [
    "candidate", "status", "mass_g", "k_Nm_per_rad", "k_rel_error", "large_stop_reason", "large_stop_rotation_rad",
    "large_stop_torque_Nm", "large_cyclic_limit_torque_Nm", "large_single_limit_torque_Nm", "usable_torque_Nm", "large_stall_rotation_rad", "large_stall_secant_k_Nm_per_rad",
    "large_stall_tangent_k_Nm_per_rad", "large_stall_bearing_displacement_mm", "large_stall_tensile_strain",
    "large_stall_compressive_strain", "large_impact_tensile_strain",
    "large_stall_strain_margin", "large_stall_survives", "large_impact_survives", "standing_deflection_deg",
    "working_min_tangent_k_Nm_per_rad", "working_max_tangent_k_Nm_per_rad", "natural_frequency_Hz", "torque_per_count_Nm",
    "impact_gearbox_torque_Nm", "stall_rotation_rad", "stall_von_mises_max_MPa", "thesis_reaction_N",
    "thesis_displacement_mm", "feasible", "conditional", "pareto", "rank", "failed_constraints", "not_judged", "reason",
]
# the compact table's columns: (results column, heading with its unit)
COMPACT_COLUMNS = [
    ("mass_g", "mass (g)"), ("k_Nm_per_rad", "k at rest (Nm/rad)"), ("large_stop_torque_Nm", "path ends at (Nm)"),
    ("large_stop_reason", "why it ends"), ("usable_torque_Nm", "usable torque (Nm)"),
    ("standing_deflection_deg", "standing sag (deg)"), ("large_stall_bearing_displacement_mm", "stall bearing arc (mm)"),
    ("impact_gearbox_torque_Nm", "strike torque (Nm)"), ("total_violation", "total miss (-)"),
    ("failed_constraints", "requirements missed"),
]
STYLE = """
body{font-family:system-ui,sans-serif;font-size:15px;line-height:1.4;max-width:1180px;margin:0 auto;padding:8px 16px;color:#222}
h1{font-size:20px;margin:6px 0}h2{font-size:17px;margin:18px 0 6px}
#decision{border-left:6px solid #2a7;background:#f3faf6;padding:8px 14px;margin:8px 0}
#decision.infeasible{border-color:#c63;background:#fdf5f0}
#decision .headline{font-size:18px;font-weight:600;margin:0 0 6px}
#decision ul{margin:4px 0 0 18px;padding:0}
table{border-collapse:collapse;font-size:12px;margin:4px 0}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}
td:first-child,th:first-child,td.text{text-align:left}
.figures{display:grid;grid-template-columns:repeat(auto-fill,minmax(520px,1fr));gap:12px}
figure{margin:0}figure img{width:100%;height:auto;border:1px solid #eee}figcaption{font-size:13px;color:#555}
details{margin:8px 0}summary{cursor:pointer;font-weight:600}.scroll{overflow-x:auto}
"""


@dataclass
class Page:
    """A report: the decision and why, then the compact table, plots, renders and collapsed details."""

    title: str
    headline: str  # the decision in one sentence
    feasible: bool  # whether the decision meets every requirement (colours the box)
    why: list[str]  # the reasons, one point each
    table: pd.DataFrame  # compact, already formatted (text cells)
    table_caption: str
    figures: dict[str, Path] = field(default_factory=dict)  # plots by caption
    renders: dict[str, Path] = field(default_factory=dict)
    sections: list[tuple[str, str]] = field(default_factory=list)  # (heading, text) after the figures
    details: list[tuple[str, pd.DataFrame | str]] = field(default_factory=list)  # collapsed: tables or text


def fmt(value, digits: int = 3) -> str:
    """A number with `digits` significant digits (no exponent for everyday magnitudes); text as it is."""
    if isinstance(value, (bool, str)) or value is None or value is pd.NA:
        return "" if value is None or value is pd.NA else str(value)
    v = float(value)
    if math.isnan(v):
        return ""
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return f"{v:.{digits}g}" if v == 0 or 1e-3 <= abs(v) < 1e6 else f"{v:.{digits - 1}e}"


def compact_table(t: pd.DataFrame, extra: list[tuple[str, str]] = ()) -> pd.DataFrame:
    """The rows of `t` with the compact columns present (and `extra` (column, heading) pairs first after the
    name), numbers formatted, headings with units."""
    cols = [("candidate", "design"), *extra, *COMPACT_COLUMNS]
    out = pd.DataFrame({head: [fmt(v) for v in t[c]] for c, head in cols if c in t})
    return out


def summary_table(t: pd.DataFrame) -> pd.DataFrame:
    cols = [c for c in SUMMARY_COLUMNS if c in t.columns]
    return t[cols].round(4)


def _table_html(df: pd.DataFrame) -> str:
    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in df.columns)
    body = []
    for _, r in df.iterrows():
        cells = []
        for v in r:
            text = fmt(v) if not isinstance(v, str) else v
            cls = " class='text'" if isinstance(v, str) and not _numeric(v) else ""
            cells.append(f"<td{cls}>{html.escape(text)}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    return f"<div class='scroll'><table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table></div>"


def _numeric(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def _img(title: str, path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode()
    return (f"<figure><img alt='{html.escape(title)}' src='data:image/png;base64,{data}'>"
            f"<figcaption>{html.escape(title)}</figcaption></figure>")


def write_html(path: Path, page: Page) -> Path:
    """The page as one self-contained HTML file."""
    box = "" if page.feasible else " class='infeasible'"
    parts = [f"<!doctype html><html lang='en'><head><meta charset='utf-8'>"
             f"<meta name='viewport' content='width=device-width, initial-scale=1'>"
             f"<title>{html.escape(page.title)}</title><style>{STYLE}</style></head><body>",
             f"<h1>{html.escape(page.title)}</h1>",
             f"<section id='decision'{box}><p class='headline'>{html.escape(page.headline)}</p><ul>"
             + "".join(f"<li>{html.escape(w)}</li>" for w in page.why) + "</ul></section>",
             f"<h2>{html.escape(page.table_caption)}</h2>" + _table_html(page.table)]
    if page.figures:
        parts.append("<h2>Plots</h2><div class='figures'>" + "".join(_img(t, p) for t, p in page.figures.items())
                     + "</div>")
    if page.renders:
        parts.append("<h2>Renders</h2><div class='figures'>" + "".join(_img(t, p) for t, p in page.renders.items())
                     + "</div>")
    for head, text in page.sections:
        parts.append(f"<h2>{html.escape(head)}</h2><p>{html.escape(text)}</p>")
    for head, content in page.details:
        inner = _table_html(content) if isinstance(content, pd.DataFrame) else f"<p>{html.escape(content)}</p>"
        parts.append(f"<details><summary>{html.escape(head)}</summary>{inner}</details>")
    parts.append("</body></html>")
    path.write_text("\n".join(parts))
    return path


def _markdown_table(df: pd.DataFrame) -> str:
    if importlib.util.find_spec("tabulate") is not None:  # pandas' to_markdown needs the optional tabulate
        return df.to_markdown(index=False)
    return "```\n" + df.to_string(index=False) + "\n```"


def write_markdown(path: Path, page: Page) -> Path:
    """The page as Markdown (images linked beside it)."""
    lines = [f"# {page.title}", "", f"**{page.headline}**", ""] + [f"- {w}" for w in page.why] + [""]
    lines += [f"## {page.table_caption}", "", _markdown_table(page.table), ""]
    images = {**page.figures, **page.renders}
    if images:
        lines += ["## Plots and renders", ""] + [f"![{t}]({p.name})" for t, p in images.items()] + [""]
    for head, text in page.sections:
        lines += [f"## {head}", "", text, ""]
    for head, content in page.details:
        lines += [f"## {head}", "", _markdown_table(content) if isinstance(content, pd.DataFrame) else content, ""]
    path.write_text("\n".join(lines))
    return path
