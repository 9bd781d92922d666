"""A data curve (:mod:`touchbench.reports.curves`) as text: its table (rows the methods, columns the
sizes, each cell the accuracy and its 95 % interval), the calibration gains' table, the plain
sentences (the smallest size reaching the asked share of the full accuracy; the gains at
:data:`GAIN_SIZES`), its legend, and the same in Markdown, HTML and JSON. The terminal lays the
tables out as every table (:func:`touchbench.reports.rendering.terminal_layout`): the method, the
smallest and largest sizes and the reach always, the other sizes while they fit."""

from __future__ import annotations

import html
import math
from typing import Any

import numpy as np
import pandas as pd

from .curves import Curve
from .labels import _pct

__all__ = ["GAIN_SIZES", "curve_cells", "curve_essential", "curve_html", "curve_json", "curve_legend",
           "curve_markdown", "capped_notes", "curve_titles", "gain_cells", "reach_lines", "reference_note", "size_label", "size_words"]

#: the calibration sizes (labelled captures per class) whose gains over none the sentences name
GAIN_SIZES = (1.0, 3.0)


def _shares(curve: Curve) -> bool:
    """Whether a subjects curve's sizes are shares of the training subjects (all at most 1, some below)."""
    return curve.axis == "subjects" and max(curve.sizes) <= 1 and min(curve.sizes) < 1


def _added(curve: Curve, size: float) -> tuple[float, float] | None:
    """The captures per class a capped calibration point really added (mean, least), else None."""
    return curve.capped().get(size)


def size_label(curve: Curve, size: float) -> str:
    """A size as a column header: ``n=4`` (subjects), ``50 %`` (a share of them), ``k=2`` (calibration;
    a capped point by the captures it added: ``k=1 (5 asked)``, ``k≈3.5 (5 asked)``)."""
    if curve.axis == "calibration":
        added = _added(curve, size)
        if added is None:
            return f"k={size:g}"
        mean = added[0]
        return f"k={mean:g} ({size:g} asked)" if mean == round(mean) else f"k≈{mean:.3g} ({size:g} asked)"
    if curve.full_varies and size == curve.sizes[-1]:
        return "all"
    return f"{100 * size:g} %" if size < 1 or _shares(curve) else f"n={size:g}"


def size_words(curve: Curve, size: float) -> str:
    """A size in words: ``4 subjects``, ``50 % of the training subjects``, ``2 labelled captures per class``."""
    if curve.axis == "calibration":
        if size == 0:
            return "no labelled capture from the test data"
        added = _added(curve, size)
        if added is not None:
            mean, least = added
            return (f"{mean:.3g} labelled capture{'' if mean == 1 else 's'} per class "
                    f"{'' if mean == least else f'on average (at least {least:g}) '}where {size:g} were asked "
                    "(the test data held no more)")
        return f"{size:g} labelled capture{'' if size == 1 else 's'} per class"
    if curve.full_varies and size == curve.sizes[-1]:
        return "every training subject"
    if size < 1 or _shares(curve):
        return f"{100 * size:g} % of the training subjects"
    return f"{size:g} subject{'' if size == 1 else 's'}"


def _share(fraction: float) -> str:
    return f"{100 * fraction:g} %"


def _interval(lo: float, hi: float, sign: bool = False) -> str:
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return "[—]"
    return f"[{100 * lo:+.1f}, {100 * hi:+.1f}]" if sign else f"[{_pct(lo)}, {_pct(hi)}]"


def _reach_header(curve: Curve) -> str:
    return f"{_share(curve.fraction)} of full at"


def curve_essential(curve: Curve) -> tuple[str, ...]:
    """The columns a narrow terminal keeps: the method, the smallest and largest sizes, the reach."""
    ends = [size_label(curve, s) for s in (curve.sizes[0], curve.sizes[-1])]
    return ("method", *ends, _reach_header(curve))


def _ordered(curve: Curve, names: dict[str, str]) -> list[str]:
    """The methods in the curve's order (full accuracy, best first), those the table names."""
    return [m for m in curve.reach["method_id"] if m in names]


def curve_cells(curve: Curve, names: dict[str, str], sep: str = " ") -> tuple[list[str], list[list[str]]]:
    """Header and cells of the curve's table: per method, each size's accuracy % and ``[low, high]``
    (``sep`` between them), then the smallest size reaching the asked share of the full accuracy."""
    header = ["method", *(size_label(curve, s) for s in curve.sizes), _reach_header(curve)]
    cells = []
    for mid in _ordered(curve, names):
        pts = curve.points[curve.points["method_id"] == mid].set_index("size")
        row = [names[mid]]
        for s in curve.sizes:
            if s not in pts.index or not np.isfinite(pts.loc[s, "accuracy"]):
                row.append("—")
                continue
            p = pts.loc[s]
            row.append(f"{_pct(p['accuracy'])}{sep}{_interval(p['ci_low'], p['ci_high'])}")
        r = curve.reach[curve.reach["method_id"] == mid].iloc[0]
        row.append(size_label(curve, r["size"]) if np.isfinite(r["size"]) else "—")
        cells.append(row)
    return header, cells


def gain_cells(curve: Curve, names: dict[str, str], sep: str = " ") -> tuple[list[str], list[list[str]]]:
    """Header and cells of the calibration gains: per method and ``k > 0``, the gain over ``k = 0`` in
    percentage points and its paired ``[low, high]`` (empty header: no gain)."""
    if curve.gains.empty:
        return [], []
    sizes = sorted(set(curve.gains["size"]))
    header = ["method", *(size_label(curve, s) for s in sizes)]
    cells = []
    for mid in _ordered(curve, names):
        g = curve.gains[curve.gains["method_id"] == mid].set_index("size")
        row = [names[mid]]
        for s in sizes:
            ok = s in g.index and np.isfinite(g.loc[s, "gain"])
            row.append(f"{100 * g.loc[s, 'gain']:+.1f}{sep}{_interval(g.loc[s, 'ci_low'], g.loc[s, 'ci_high'], True)}"
                       if ok else "—")
        cells.append(row)
    return header, cells


def _axis_words(curve: Curve) -> str:
    if curve.axis == "calibration":
        return "against k labelled captures per class from the test data added to training"
    return "against the number of training subjects n"


def curve_titles(title: str, curve: Curve) -> tuple[str, str]:
    """The titles of the curve's table and of its gains' table, after the leaderboard's ``title``."""
    what = "calibration curve" if curve.axis == "calibration" else "learning curve"
    return (f"{title} — {what}: accuracy % on the held-out captures {_axis_words(curve)}",
            "gain over k=0 (no labelled capture from the test data), percentage points")


def curve_legend(curve: Curve) -> str:
    """What the curve's cells are: the points, the unit of the interval, what full means."""
    kinds = set(curve.points["ci_method"])
    parts = ["Each point is scored on the same held-out test captures as the other points of its test fold and "
             "random draw; its accuracy is the mean over the test folds of each fold's mean over its draws."]
    if "t" in kinds:
        parts.append(f"Interval: 95 % Student t over the test folds (up to {curve.units}; the unit is the test "
                     "fold, its draws averaged first).")
    if "bootstrap" in kinds:
        parts.append("One test set: 95 % percentile bootstrap over the draws and the test captures crossed "
                     "(the pigeonhole bootstrap, Owen 2007).")
    full = ("the largest k swept; k=0 is the baseline the gains are measured from" if curve.axis == "calibration"
            else "the largest n (every training subject)")
    parts.append(f"{_reach_header(curve)}: the smallest size whose mean accuracy is at least {_share(curve.fraction)} "
                 f"of the full accuracy, full being {full}.")
    if not curve.gains.empty:
        parts.append("Gain: per test fold the accuracy at k minus that at k=0 (paired), the mean over the folds and "
                     "its 95 % Student t interval (one test set: the bootstrap over draws and captures).")
    return " ".join(parts)


def _gain_phrase(curve: Curve, mid: str) -> str:
    g = curve.gains[(curve.gains["method_id"] == mid) & curve.gains["size"].isin(GAIN_SIZES)]
    return ", ".join(f"{100 * r.gain:+.1f} points {_interval(r.ci_low, r.ci_high, True)} with "
                     f"{size_words(curve, r.size)}" for r in g.sort_values("size").itertuples()
                     if np.isfinite(r.gain))


def reach_lines(curve: Curve, names: dict[str, str]) -> list[str]:
    """One plain sentence per method: where it reaches the asked share of its full accuracy (and, on a
    calibration curve, its accuracy with no labelled capture and its gains at :data:`GAIN_SIZES`)."""
    out = []
    for mid in _ordered(curve, names):
        r = curve.reach[curve.reach["method_id"] == mid].iloc[0]
        if not np.isfinite(r["size"]):
            continue
        full = f"{_pct(r['full_accuracy'])} % with {size_words(curve, r['full_size'])}"
        if curve.axis == "calibration":
            gains = _gain_phrase(curve, mid)
            base = (f"{_pct(r['baseline'])} % with {size_words(curve, 0.0)}" if np.isfinite(r["baseline"])
                    else "")
            lead = "; ".join(x for x in (base, gains) if x)
            out.append(f"{names[mid]}: {lead + '; ' if lead else ''}reaches {_share(curve.fraction)} of its accuracy "
                       f"at the largest k with {size_words(curve, r['size'])} ({_pct(r['accuracy'])} %; at the "
                       f"largest k: {full}).")
        else:
            out.append(f"{names[mid]} reaches {_share(curve.fraction)} of its full accuracy with "
                       f"{size_words(curve, r['size'])} ({_pct(r['accuracy'])} %; full: {full}).")
    return out


def capped_notes(curve: Curve) -> list[str]:
    """One note per capped calibration point: the captures asked and those really added."""
    return [f"calibration: k={k:g} asked, but some test pools held no more than {k:g} captures of a class (one is "
            f"always scored): {mean:.3g} labelled captures per class were added on average, at least {least:g}; "
            "the point is labelled by what it added" for k, (mean, least) in sorted(curve.capped().items())]


def reference_note(curve: Curve) -> str:
    """The note of a curve's leaderboard: which point its table ranks."""
    if curve.axis == "calibration":
        at = "k=0 (no labelled capture from the test data)" if 0.0 in curve.sizes else size_label(curve, curve.sizes[-1])
        return f"a calibration curve: this table ranks the methods at {at}; the curve and the gains of each k follow"
    full = "" if curve.full_varies else f"{size_label(curve, curve.sizes[-1])}, "
    return f"a learning curve: this table ranks the methods at its full point ({full}every training subject); the curve follows"


def _md_table(header: list[str], cells: list[list[str]]) -> list[str]:
    esc = lambda s: s.replace("|", "\\|")  # noqa: E731
    return (["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
            + ["| " + " | ".join(esc(c) for c in row) + " |" for row in cells])


def curve_markdown(title: str, curve: Curve, names: dict[str, str]) -> list[str]:
    """The curve's tables, sentences and legend as Markdown lines (``title``: the leaderboard's)."""
    head, gain_head = curve_titles(title, curve)
    out = [f"### {head}", "", *_md_table(*curve_cells(curve, names)), ""]
    header, cells = gain_cells(curve, names)
    if header:
        out += [f"### {gain_head}", "", *_md_table(header, cells), ""]
    out += [f"- {line}" for line in reach_lines(curve, names)]
    return out + ["", curve_legend(curve), ""]


def _html_table(header: list[str], cells: list[list[str]]) -> str:
    out = ["<table class='curve'><thead><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in header)
           + "</tr></thead><tbody>"]
    for row in cells:
        out.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" if i == 0 else f"<td class='num'>{html.escape(c)}</td>"
                                    for i, c in enumerate(row)) + "</tr>")
    return "\n".join(out + ["</tbody></table>"])


def curve_html(title: str, curve: Curve, names: dict[str, str]) -> str:
    """The curve's tables, sentences and legend as an HTML fragment."""
    head, gain_head = curve_titles(title, curve)
    out = [f"<h3>{html.escape(head)}</h3>", _html_table(*curve_cells(curve, names))]
    header, cells = gain_cells(curve, names)
    if header:
        out += [f"<h3>{html.escape(gain_head)}</h3>", _html_table(header, cells)]
    out += [f"<p>{html.escape(line)}</p>" for line in reach_lines(curve, names)]
    return "\n".join(out + [f"<p class='legend'>{html.escape(curve_legend(curve))}</p>"])


def _records(df: pd.DataFrame, names: dict[str, str]) -> list[dict[str, Any]]:
    """Rows as JSON records, a method named, NaN as null."""
    out = []
    for r in df.to_dict(orient="records"):
        r = {k: v.item() if hasattr(v, "item") else v for k, v in r.items()}
        r = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in r.items()}
        out.append({"method": names.get(r["method_id"], r["method_id"]), **r})
    return out


def curve_json(curve: Curve | None, names: dict[str, str]) -> dict[str, Any] | None:
    """The curve as a JSON-ready document (None off a curve)."""
    if curve is None:
        return None
    return {"axis": curve.axis, "sizes": [float(s) for s in curve.sizes], "fraction": curve.fraction,
            "points": _records(curve.points, names), "gains": _records(curve.gains, names),
            "reach": _records(curve.reach, names),
            "added": [{"size": float(k), "mean": a[0], "least": a[1]} for k, a in sorted(curve.added.items())]}
