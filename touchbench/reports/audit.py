"""The leakage audit as a table (terminal, Markdown, JSON), a figure and an HTML page.

One row per method: the honest accuracy, then each leaky variant's accuracy
and its inflation over the honest one (percentage points); with a published
number, which variants come within its tolerance. The figure draws each
method's accuracies, honest first, the published number as a dashed line.
"""

from __future__ import annotations

import html
import json
import math
from pathlib import Path
from typing import Any

import pandas as pd

from ..core.atomic import atomic_write_bytes
from .labels import _pct

__all__ = ["audit_markdown", "audit_rows", "plot_audit", "write_audit"]

LEGEND = ("Accuracy: mean over folds. Inflation: a leaky variant's accuracy minus the honest one, in percentage "
          "points. honest: subjects kept apart, nothing chosen on test data. capture-kfold: k-fold over captures "
          "ignoring subjects. window-kfold: k-fold over windows cut from the captures (windows of one capture on "
          "both sides). subject-id: capture-kfold with the subject's id as a feature. tuned-on-test: a parameter "
          "chosen by its mean test accuracy. stopped-on-test: training stopped at the epoch of the best test "
          "accuracy (early stopping on the held-out subject).")


def audit_rows(table: pd.DataFrame, published: dict[str, dict[str, Any]] | None = None) -> tuple[list[str], list[list[str]]]:
    """Header and cells: a row per method, a column per variant (accuracy, and inflation for the leaky ones)."""
    variants = list(dict.fromkeys(table["variant"]))
    header = ["method"] + [("honest %" if v == "honest" else f"{v} % (Δ pp)") for v in variants]
    if published:
        header += ["published %", "within tolerance"]
    cells = []
    for method, g in table.groupby("method", sort=False):
        by = g.set_index("variant")
        row = [method]
        for v in variants:
            acc = by["accuracy"].get(v, math.nan)
            row.append(_pct(acc) if v == "honest" else f"{_pct(acc)} ({by['inflation_pp'].get(v, math.nan):+.1f})")
        if published:
            pub = published.get(method)
            if pub:
                hits = [v for v in variants if abs(100 * by["accuracy"].get(v, math.nan) - pub["value"]) <= pub["tolerance"]]
                row += [f"{pub['value']:g} ± {pub['tolerance']:g}", ", ".join(hits) or "none"]
            else:
                row += ["—", "—"]
        cells.append(row)
    return header, cells


def audit_markdown(table: pd.DataFrame, published: dict[str, dict[str, Any]] | None = None, title: str = "Leakage audit",
                   notes: list[str] | None = None) -> str:
    header, cells = audit_rows(table, published)
    out = [f"## {title}", "", "| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(c.replace("|", "\\|") for c in row) + " |" for row in cells]
    out += ["", LEGEND, *[f"\nNote: {n}" for n in notes or []], ""]
    return "\n".join(out)


def plot_audit(table: pd.DataFrame, path_stem: Path, published: dict[str, dict[str, Any]] | None = None,
               title: str = "Leakage audit") -> list[Path]:
    """Grouped bars: each method's accuracy per variant (honest first); the published number dashed
    where there is one (the axis says so only then); the legend right of the panel.
    Drawn at text width with the figures' fonts (:mod:`touchbench.reports.figures.base`)."""
    from .figures.base import figure_width, pyplot, save

    plt = pyplot()
    variants = list(dict.fromkeys(table["variant"]))
    methods = list(dict.fromkeys(table["method"]))
    h = 0.8 / len(variants)
    fig, ax = plt.subplots(figsize=(figure_width("text"), 1.0 + 0.25 * len(methods) * len(variants)), layout="constrained")
    for j, v in enumerate(variants):
        accs = [100 * float(table[(table["method"] == m) & (table["variant"] == v)]["accuracy"].mean()) for m in methods]
        ax.barh([i + j * h for i in range(len(methods))], accs, height=h, label=v,
                hatch=None if v == "honest" else "//", alpha=1.0 if v == "honest" else 0.7)
    drawn = 0
    for i, m in enumerate(methods):
        pub = (published or {}).get(m)
        if pub:
            ax.plot([pub["value"]] * 2, [i - h / 2, i + 0.8 - h / 2], "k--", lw=1, label=None if drawn else "published")
            drawn += 1
    ax.set_yticks([i + 0.4 - h / 2 for i in range(len(methods))], methods)
    ax.set_xlabel("accuracy %" + (" (dashed: published)" if drawn else ""))
    ax.set_xlim(0, 100)
    ax.set_title(title)
    # beside the panel, never over a bar (the constrained layout narrows the panel to make room)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    return save(fig, path_stem, formats=("png", "svg"))


def write_audit(table: pd.DataFrame, out: Path, published: dict[str, dict[str, Any]] | None = None,
                notes: list[str] | None = None, title: str = "Leakage audit") -> list[Path]:
    """``audit.md``, ``audit.json``, ``audit.png`` / ``.svg`` and a self-contained ``audit.html`` in ``out``."""
    out = Path(out)
    md = audit_markdown(table, published, title, notes)
    atomic_write_bytes(out / "audit.md", md.encode())
    atomic_write_bytes(out / "audit.json", (json.dumps({"rows": json.loads(table.to_json(orient="records")),
                                                         "published": published or {}, "notes": notes or []},
                                                        indent=2) + "\n").encode())
    figs = plot_audit(table, out / "audit", published, title)
    header, cells = audit_rows(table, published)
    svg = (out / "audit.svg").read_text()
    page = ("<!doctype html><html><head><meta charset='utf-8'><title>" + html.escape(title) + "</title></head><body>"
            f"<h1>{html.escape(title)}</h1><table border=1 cellpadding=4><tr>"
            + "".join(f"<th>{html.escape(x)}</th>" for x in header) + "</tr>"
            + "".join("<tr>" + "".join(f"<td>{html.escape(x)}</td>" for x in row) + "</tr>" for row in cells)
            + f"</table><p>{html.escape(LEGEND)}</p>" + "".join(f"<p>Note: {html.escape(n)}</p>" for n in notes or [])
            + svg[svg.find("<svg"):] + "</body></html>\n")
    atomic_write_bytes(out / "audit.html", page.encode())
    return [out / "audit.md", out / "audit.json", *figs, out / "audit.html"]
