"""One self-contained HTML page: the leaderboards and every plot.

Images are embedded as base64 ``data:`` URIs (PNG), so the page can be
mailed or checked in alone; the PNG and SVG files, and the leaderboard as
Markdown, CSV and JSON, are written beside it.
"""

from __future__ import annotations

import base64
import html
from datetime import datetime, timezone
from pathlib import Path

from .across import across_friedman, across_note, ranks_across
from .curve_table import curve_html
from .labels import method_names
from .leaderboard import Leaderboard
from .rendering import RANK_LEGEND, display_rows, legend, write_outputs, write_text
from .figures import plot_table
from .figures.cd import NoDiagram, plot_cd_across
from .results import ResultSet

__all__ = ["render_html", "write_report"]

_CSS = """
tr.leaky td{background:#fde2e2;color:#7a0000}h2.leaky{color:#a00000}
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:2em auto;max-width:1400px;
color:#222;padding:0 1em}
h1{font-size:1.6em}h2{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ccc;padding-bottom:.2em}
table{border-collapse:collapse;font-size:.85em;margin:.6em 0}
th,td{border:1px solid #ddd;padding:.25em .5em;text-align:left;vertical-align:top}
th{background:#f3f3f3}tr.best td{background:#eef7ee}td.num{text-align:right;font-variant-numeric:tabular-nums}
.note{color:#8a5a00}.legend{color:#555;font-size:.85em;max-width:1100px}
img{max-width:100%;height:auto;border:1px solid #eee;margin:.4em 0}
code{font-size:.9em}
"""


def _img(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode()
    return f'<img alt="{html.escape(path.stem)}" src="data:image/png;base64,{data}">'


def _table_html(lb: Leaderboard) -> str:
    header, cells = display_rows(lb)
    out = ["<table><thead><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in header) + "</tr></thead><tbody>"]
    numeric = {0, 4, 5, 6, 7, 8, 9, 10}
    for c in cells:
        leaky = any(x.startswith("LEAKY:") for x in c)
        cls = ' class="leaky"' if leaky else (' class="best"' if c[0] == "1" else "")
        tds = "".join(f'<td class="num">{html.escape(x)}</td>' if i in numeric else f"<td>{html.escape(x)}</td>"
                      for i, x in enumerate(c))
        out.append(f"<tr{cls}>{tds}</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def _across_html(lbs: list[Leaderboard], cd: list[Path], cd_note: str) -> str:
    """The section across the tables: mean ranks, the Friedman test and critical difference, and the
    diagram or the note saying why there is none ("" for one table)."""
    ranks = ranks_across(lbs)
    if ranks is None or ranks.empty:
        return ""
    out = [f"<h2>Across {int(ranks['tables'].iloc[0])} tables</h2><table><thead><tr><th>method</th>"
           "<th>mean rank</th><th>mean accuracy %</th></tr></thead><tbody>"]
    out += [f"<tr><td>{html.escape(r.method)}</td><td class='num'>{r.mean_rank:.2f}</td>"
            f"<td class='num'>{100 * r.mean_accuracy:.1f}</td></tr>" for r in ranks.itertuples()]
    out.append(f"</tbody></table><p class='legend'>{html.escape(RANK_LEGEND)}</p>")
    f = across_friedman(lbs)
    if f is not None:
        out.append(f"<p class='legend'>{html.escape(across_note(f))}</p>")
    png = [p for p in cd if p.suffix == ".png"]
    if png:
        out.append(f"<h3>critical difference</h3>{_img(png[0])}")
    elif cd_note and (f is None or f.can_separate):  # a diagram the tables allow, not drawn: why
        out.append(f"<p class='note'>Note: no critical difference diagram: {html.escape(cd_note)}</p>")
    return "\n".join(out)


def render_html(rs: ResultSet, lbs: list[Leaderboard], plots: dict[str, dict[str, list[Path]]],
                title: str = "touchbench report", across: str = "") -> str:
    now = datetime.now(timezone.utc).isoformat(timespec="seconds")
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>",
             f"<style>{_CSS}</style></head><body>", f"<h1>{html.escape(title)}</h1>",
             f"<p>Generated {now} from {len(rs.sources)} results director{'y' if len(rs.sources) == 1 else 'ies'}.</p>"]
    parts.append("<h2>Runs</h2><table><thead><tr><th>protocol</th><th>run</th><th>dataset</th><th>machine</th>"
                 "<th>tasks (failed)</th><th>run time s</th><th>finished</th></tr></thead><tbody>")
    for s in rs.sources:
        parts.append(
            f"<tr><td>{html.escape(str(s['protocol']))}</td><td><code>{html.escape(str(s['run_id']))}</code></td>"
            f"<td>{html.escape(str(s['dataset']))}</td><td>{html.escape(s['machine'])}: {html.escape(s['machine_desc'])}</td>"
            f"<td class='num'>{s['n_tasks']} ({s['n_failed']})</td><td class='num'>{s['seconds']:.1f}</td>"
            f"<td>{html.escape(str(s.get('finished_at') or ''))}</td></tr>")
    parts.append("</tbody></table>")
    for lb in lbs:
        parts.append(f"<h2{' class=leaky' if lb.is_leaky else ''}>{html.escape(lb.title)}</h2>")
        parts.append(_table_html(lb))
        parts.append(f"<p class='legend'>{html.escape(legend(lb))}</p>")
        for n in lb.notes:
            parts.append(f"<p class='note'>Note: {html.escape(n)}</p>")
        if lb.curve is not None:
            parts.append(curve_html(lb.title, lb.curve, method_names(lb.rows)))
        for name, paths in plots.get(lb.key, {}).items():
            png = [p for p in paths if p.suffix == ".png"]
            if png:
                parts.append(f"<h3>{html.escape(name.split('-')[0])}</h3>{_img(png[0])}")
    parts.append(across)
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def write_report(rs: ResultSet, lbs: list[Leaderboard], out: str | Path, title: str = "touchbench report",
                 kinds: tuple[str, ...] | None = None) -> Path:
    """``out/report.html`` (self-contained), ``out/plots/*.{png,svg}`` (text width, 300 dpi; ``kinds``:
    the figure kinds, by default every one), ``out/leaderboard.{md,csv,json}``. Several tables add a
    section across them (mean ranks, Friedman test, the critical difference diagram where the tables
    can separate methods); a figure an optional extra draws is left out with a note naming it."""
    out = Path(out)
    taken: set[str] = set()  # file names unique over the tables
    plots = {lb.key: plot_table(rs, lb, out / "plots", kinds, taken=taken, formats=("svg", "png")) for lb in lbs}
    cd, cd_note = _cd_across(lbs, out / "plots", kinds)
    write_outputs(lbs, out, ("md", "csv", "json"))
    page = out / "report.html"
    return write_text(page, render_html(rs, lbs, plots, title, _across_html(lbs, cd, cd_note)))


def _cd_across(lbs: list[Leaderboard], folder: Path, kinds: tuple[str, ...] | None) -> tuple[list[Path], str]:
    """The critical difference diagram across the tables, or why there is none (a missing extra
    included: the report is written without it)."""
    if len(lbs) < 2 or (kinds is not None and "cd" not in kinds):
        return [], ""
    try:
        return plot_cd_across(lbs, folder / "across-tables-cd", formats=("svg", "png")), ""
    except NoDiagram as e:
        return [], str(e)
