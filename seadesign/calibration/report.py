"""The loop's report: JSON (a `steps` list), Markdown, self-contained HTML, plots, calibration JSON."""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seadesign.calibration.engine import Explanation, TraceEntry  # noqa: E402


def _trace_row(t: TraceEntry) -> dict:
    return {"effect": t.effect, "held_out_rmse": t.held_out_rmse, "bic": t.bic, "aic": t.aic,
            "accepted": t.accepted, "at_bound": t.at_bound}


def _errors(e: dict) -> dict:
    return {part: {k: float(v) for k, v in m.items()} for part, m in e.items()}


def to_json(ex: Explanation, title: str) -> dict[str, Any]:
    """JSON-ready report: settings, plain errors, one entry per added effect, final residual tests."""
    unit = ex.data.measured_unit
    return {
        "title": title,
        "measured": ex.data.columns.get("measured", ex.data.measured_name),
        "error_unit": unit,
        "samples": ex.data.n,
        "signals": {r: {"column": ex.data.columns.get(r, r), "unit": ex.data.unit(r)} for r in ex.data.signals},
        "settings": ex.settings,
        "plain": {"errors": _errors(ex.plain.errors), "bic": ex.plain.bic, "aic": ex.plain.aic},
        "declared_refit": {"errors": _errors(ex.base.errors), "bic": ex.base.bic, "parameters": ex.base.parameters()},
        "declared": [{"name": c.name, "effect": c.key, "declared": c.declared, "fitted": c.fitted,
                      "supported": c.supported, "held_out_rmse_with": c.held_out_rmse_with,
                      "held_out_rmse_without": c.held_out_rmse_without, "text": c.text()} for c in ex.declared],
        "steps": [
            {"effect": s.effect, "parameters": s.after.parameters(),
             "errors_before": _errors(s.before.errors), "errors_after": _errors(s.after.errors),
             "bic_before": s.before.bic, "bic_after": s.after.bic,
             "ambiguous_with": None if s.alternative is None else
             {"effect": s.alternative.effect, "held_out_rmse": s.alternative.held_out_rmse,
              "parameters": s.alternative.fit.parameters()[s.alternative.effect]},
             "trace": [_trace_row(t) for t in s.trace]}
            for s in ex.steps
        ],
        "last_trace": [_trace_row(t) for t in ex.last_trace],
        "final": {"effects": ex.found, "unsupported": ex.unsupported, "ambiguities": [list(a) for a in ex.ambiguities],
                  "converged": ex.final.converged, "parameters": ex.final.parameters(),
                  "errors": _errors(ex.final.errors)},
        "residual_tests_before": ex.tests_before,
        "residual_tests": ex.tests_after,
        "verdict": ex.verdict(),
    }


def plots(ex: Explanation, out_dir: Path, stem: str, loop_plot: bool) -> list[Path]:
    """PNG plots: residual vs each signal before/after, time series, and (bench) the torque-deflection loop."""
    out_dir.mkdir(parents=True, exist_ok=True)
    d, files = ex.data, []
    before, after = d.measured - ex.plain.prediction, d.measured - ex.final.prediction
    roles = list(d.signals)
    fig, axes = plt.subplots(len(roles), 1, figsize=(7, 2.4 * len(roles)), squeeze=False)
    step = max(1, d.n // 5000)
    for ax, role in zip(axes[:, 0], roles):
        x = d.signals[role][::step]
        ax.plot(x, before[::step], ".", ms=1.5, alpha=0.5, label="before (declared model)")
        ax.plot(x, after[::step], ".", ms=1.5, alpha=0.5, label="after")
        ax.set_xlabel(f"{role}: {d.columns.get(role, role)} ({d.unit(role)})")
        ax.set_ylabel(f"residual ({d.measured_unit})")
    axes[0, 0].legend(loc="best", markerscale=6)
    fig.tight_layout()
    files.append(out_dir / f"{stem}_residual_vs_signals.png")
    fig.savefig(files[-1], dpi=90)
    plt.close(fig)

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    t = d.time
    a1.plot(t, d.measured, lw=0.8, label="measured")
    a1.plot(t, ex.plain.prediction, lw=0.8, label="declared model")
    a1.plot(t, ex.final.prediction, lw=0.8, label="model + " + (", ".join(ex.found) or "nothing"))
    a1.set_ylabel(f"{d.measured_name} ({d.measured_unit})")
    a1.legend(loc="best", fontsize=7)
    a2.plot(t, before, lw=0.6, label="residual before")
    a2.plot(t, after, lw=0.6, label="residual after")
    a2.fill_between(t, *a2.get_ylim(), where=ex.held, color="0.85", label="held out", zorder=0)
    a2.set_xlabel(f"time ({d.unit('time')})")
    a2.set_ylabel(f"residual ({d.measured_unit})")
    a2.legend(loc="best", fontsize=7)
    fig.tight_layout()
    files.append(out_dir / f"{stem}_time_series.png")
    fig.savefig(files[-1], dpi=90)
    plt.close(fig)

    if loop_plot and "deflection" in d.signals:
        fig, ax = plt.subplots(figsize=(5, 4))
        x = d.signals["deflection"]
        ax.plot(x[::step], d.measured[::step], ".", ms=1.5, label="measured")
        ax.plot(x, ex.plain.prediction, lw=1, label="declared model")
        ax.plot(x, ex.final.prediction, lw=0.8, label="fitted model")
        ax.set_xlabel(f"{d.columns.get('deflection', 'deflection')} ({d.unit('deflection')})")
        ax.set_ylabel(f"{d.measured_name} ({d.measured_unit})")
        ax.legend(loc="best", fontsize=7, markerscale=6)
        fig.tight_layout()
        files.append(out_dir / f"{stem}_loop.png")
        fig.savefig(files[-1], dpi=90)
        plt.close(fig)
    return files


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def markdown(report: dict[str, Any], images: list[Path]) -> str:
    """The report as Markdown (images referenced by file name)."""
    u = report["error_unit"]
    lines = [f"# {report['title']}", "", report["verdict"], "",
             f"Measured: `{report['measured']}` ({u}), {report['samples']} samples; held-out: time blocks "
             f"{report['settings']['held_out_blocks']} of {report['settings']['n_blocks']}. A candidate is added only "
             f"when it cuts the held-out RMSE by >= {100 * report['settings']['min_gain']:.0f} % and lowers the "
             f"training BIC by >= {report['settings']['min_bic_drop']:g}.", "",
             "## Error before and after", "", f"| model | train RMSE ({u}) | held-out RMSE ({u}) | held-out peak ({u}) | held-out fit % |",
             "|---|---|---|---|---|"]
    rows = [("declared model as given", report["plain"]["errors"]),
            ("declared model refitted", report["declared_refit"]["errors"])] + \
        [(f"+ {s['effect']}", s["errors_after"]) for s in report["steps"]] + [("final", report["final"]["errors"])]
    for name, e in rows:
        lines.append(f"| {name} | {_fmt(e['train']['rmse'])} | {_fmt(e['held_out']['rmse'])} | "
                     f"{_fmt(e['held_out']['peak'])} | {e['held_out']['fit_percent']:.2f} |")
    if report["declared"]:
        lines += ["", "## Declared model: declared values against what the data says", ""]
        lines += [f"- {c['text']}" for c in report["declared"]]
    if not report["final"]["converged"]:
        lines += ["", "**The final fit did not converge (least_squares stopped at its evaluation limit); its "
                      "numbers are not a result.**"]
    for i, s in enumerate(report["steps"], 1):
        lines += ["", f"## Step {i}: {s['effect']}", ""]
        if s["ambiguous_with"]:
            a = s["ambiguous_with"]
            lines += [f"Ambiguous: {a['effect']} fits as well (held-out RMSE {_fmt(a['held_out_rmse'])} {u}) and adds "
                      f"nothing beside {s['effect']}; the data cannot tell them apart. Its fit: "
                      + ", ".join(f"{n} = {_fmt(p['value'])} {p['unit']}" for n, p in a["parameters"].items()), ""]
        lines += ["| effect | parameter | value | uncertainty (1 sigma) | unit |", "|---|---|---|---|---|"]
        for eff, ps in s["parameters"].items():
            for name, p in ps.items():
                bound = " (at search bound)" if p["at_bound"] else " (held)" if p["held"] else ""
                lines.append(f"| {eff} | {name} | {_fmt(p['value'])}{bound} | {_fmt(p['uncertainty'])} | {p['unit']} |")
        lines += ["", f"Candidates tried (held-out RMSE {u}, BIC):", "",
                  "| candidate | held-out RMSE | BIC | accepted | parameter at search bound |", "|---|---|---|---|---|"]
        lines += [f"| {t['effect']} | {_fmt(t['held_out_rmse'])} | {t['bic']:.1f} | {'yes' if t['accepted'] else 'no'} "
                  f"| {'yes' if t['at_bound'] else 'no'} |" for t in s["trace"]]
    if report["last_trace"]:
        lines += ["", "## Last trace (nothing accepted)", "", "| candidate | held-out RMSE | BIC |", "|---|---|---|"]
        lines += [f"| {t['effect']} | {_fmt(t['held_out_rmse'])} | {t['bic']:.1f} |" for t in report["last_trace"]]
    lines += ["", "## Residual tests (final model)", ""]
    for label, key in (("before", "residual_tests_before"), ("after", "residual_tests")):
        a = report[key]["autocorrelation"]
        lines.append(f"- {label}: Ljung-Box Q = {a['Q']:.1f} over {a['lags']} lags, p = {a['p_value']:.3g} "
                     f"({'structured' if a['structured'] else 'white'}); strongest autocorrelation "
                     f"{a['strongest_autocorrelation']:.3f} at {a['strongest_lag_s']:.3g} s")
        for role, c in report[key]["cross"].items():
            lines.append(f"  - vs {role}: max |corr| {c['max_abs_correlation']:.3f} at lag {c['lag_s']:.3g} s "
                         f"(threshold {c['threshold']:.3f}), binned share {c['explained_share_binned']:.3f}"
                         f"{' - structured' if c['structured'] else ''}")
    lines += ["", "## Plots", ""] + [f"![{p.stem}]({p.name})" for p in images]
    return "\n".join(lines) + "\n"


def html_page(md_text: str, report: dict[str, Any], images: list[Path]) -> str:
    """Self-contained HTML: the Markdown's text in <pre> blocks per section and the plots inlined."""
    body = [f"<h1>{html.escape(report['title'])}</h1>"]
    for block in md_text.split("\n## ")[0:]:
        head, _, rest = block.partition("\n")
        if head.startswith("# "):
            body.append(f"<pre>{html.escape(rest)}</pre>")
        elif head != "Plots":
            body.append(f"<h2>{html.escape(head)}</h2><pre>{html.escape(rest)}</pre>")
    for p in images:
        data = base64.b64encode(p.read_bytes()).decode()
        body.append(f'<h3>{html.escape(p.stem)}</h3><img alt="{html.escape(p.stem)}" src="data:image/png;base64,{data}">')
    return ("<!doctype html><html><head><meta charset='utf-8'><title>" + html.escape(report["title"]) +
            "</title><style>body{font-family:sans-serif;max-width:60em;margin:auto}pre{white-space:pre-wrap}"
            "img{max-width:100%}</style></head><body>" + "\n".join(body) + "</body></html>")


def write_report(ex: Explanation, out_dir: Path, stem: str, title: str, loop_plot: bool = False,
                 calibration: dict[str, Any] | None = None) -> dict[str, Path]:
    """Write `<stem>.md`, `<stem>.html`, `<stem>.json`, the plots and (given) `<stem>_calibration.json`."""
    out_dir = Path(out_dir)
    report = to_json(ex, title)
    images = plots(ex, out_dir, stem, loop_plot)
    md = markdown(report, images)
    paths = {"markdown": out_dir / f"{stem}.md", "html": out_dir / f"{stem}.html", "json": out_dir / f"{stem}.json"}
    paths["markdown"].write_text(md)
    paths["html"].write_text(html_page(md, report, images))
    paths["json"].write_text(json.dumps(report, indent=2, default=_default))
    if calibration is not None:
        paths["calibration"] = out_dir / f"{stem}_calibration.json"
        paths["calibration"].write_text(json.dumps(calibration, indent=2, default=_default))
    return paths


def _default(o: Any) -> Any:
    if isinstance(o, (np.floating, np.integer, np.bool_)):
        return o.item()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")
