"""Leaderboards as text: the cells of a table (terminal, Markdown, HTML), Markdown, JSON and CSV
documents, the terminal tables (columns fitted to its width), and the files written."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any, Iterable

import numpy as np
import pandas as pd
from rich.cells import cell_len
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from ..core.atomic import atomic_write_bytes
from .across import across_friedman, across_note, ranks_across
from .breakdown import breakdown_cells, breakdown_headers, breakdown_legend
from .curve_table import curve_cells, curve_essential, curve_json, curve_legend, curve_markdown, curve_titles, gain_cells, reach_lines
from .labels import _label_parts, _name_cell, _num, _p, _pct, method_names
from .leaderboard import Leaderboard
from .short_labels import FittedLabels, fit_labels
from .seeds import CI_NOTES, legend_note, seeds_note
from .stats import TEST_SHORT
from .stream_table import LIVE_ESSENTIAL, LIVE_LEGEND, LIVE_PRIORITY, live_cells, live_markdown

__all__ = ["to_csv", "to_json", "to_markdown"]


def display_rows(lb: Leaderboard, sep: str = " ") -> tuple[list[str], list[list[str]]]:
    """Header and formatted cells of a leaderboard (terminal, Markdown, HTML); ``sep`` joins a
    number and the note after it (the seeds, the interval's kind, the test: a terminal may break
    the line there)."""
    show_cpu = _has_cpu_times(lb.rows)
    header = ["#", "method", "features", "estimator", "folds", "accuracy % (±sd)", "95 % interval",
              "macro F1 %", "latency ms"] + (["CPU ms"] if show_cpu else []) + [
              "fit s", "features ms", "vs best: Δ pp, p (Holm)", "Pareto"]
    header += breakdown_headers(lb.breakdown)
    machine_at = header.index("vs best: Δ pp, p (Holm)")
    show_machine = len(set(lb.rows["timing_machine"])) > 1
    if show_machine:
        header.insert(machine_at, "timing machine")
    show_leak = bool((lb.rows["leakage"] != "").any())
    if lb.has_design:
        header.insert(7, "held out %")
    if show_leak:
        header.insert(2, "evaluation")
    cells = []
    parts = _label_parts(lb.rows)
    for _, r in lb.rows.iterrows():
        feats = _features_cell(r, parts[r["method_id"]][0], lb.frame_rate)
        acc, ci = _accuracy_cells(r, sep)
        failed_all = r["n_folds"] == 0 and r["n_failed"] > 0
        if failed_all:
            acc, ci = "failed", "—"
        vs = _versus_best_cell(r, failed_all, sep)
        row = [str(r["rank"]), _name_cell(r, parts[r["method_id"]]), feats, str(r["classifier_name"]),
               f"{r['n_folds']}" + (f" (+{r['n_failed']} failed)" if r["n_failed"] else ""), acc, ci,
               _pct(r["macro_f1"]), _num(r["latency_ms"])] + ([_num(r["latency_cpu_ms"])] if show_cpu else []) + [
               _num(r["fit_seconds"]), _num(r["feature_ms"]), vs, "★" if r["pareto"] else ""] + breakdown_cells(r, lb.breakdown)
        if show_machine:
            row.insert(machine_at, str(r["timing_machine"]))
        if lb.has_design:
            if r.get("designed"):
                row[5] += " †"
            row.insert(7, _pct(r["held_out_accuracy"]) + (f" (n={int(r['n_held_out'])})" if r.get("n_held_out") else ""))
        if show_leak:
            row.insert(2, f"LEAKY: {r['leakage']}" if r["leakage"] else "honest")
        cells.append(row)
    return header, cells


def _has_cpu_times(rows: pd.DataFrame) -> bool:
    """Whether a row has a CPU time per capture (results written before touchbench measured it have none)."""
    return "latency_cpu_ms" in rows and bool(rows["latency_cpu_ms"].notna().any())


def _features_cell(r: pd.Series, extra: str, frame_rate: float) -> str:
    """A row's feature sets, with the parameters ``extra`` that tell colliding rows apart and its early
    cut (frames, and seconds where the frame rate is known)."""
    feats = str(r["features"]) + extra  # parameters shown where rows would collide
    if np.isfinite(r["early_frames"]):
        secs = f", {r['early_frames'] / frame_rate:.2g} s" if np.isfinite(frame_rate) and frame_rate > 0 else ""
        feats += f" @ {int(r['early_frames'])} frames{secs}"
    return feats


def _accuracy_cells(r: pd.Series, sep: str = " ") -> tuple[str, str]:
    """A row's accuracy (± sd, and the seeds behind a single fold's spread) and its 95 % interval
    (``sep`` before a note)."""
    acc = _pct(r["accuracy"]) + (f" ± {_pct(r['accuracy_sd'])}" if np.isfinite(r["accuracy_sd"]) else "")
    acc += seeds_note(r, sep)
    ci = f"{_pct(r['ci_low'])}–{_pct(r['ci_high'])}" if np.isfinite(r["ci_low"]) else "—"
    if r["ci_method"] in CI_NOTES and np.isfinite(r["ci_low"]):
        ci += f"{sep}({CI_NOTES[r['ci_method']]})"
    return acc, ci


def _versus_best_cell(r: pd.Series, failed_all: bool, sep: str = " ") -> str:
    """A row's comparison with the best method: the difference, its Holm-adjusted p and test (``sep``
    before the test)."""
    if failed_all:
        return f"failed: {r.get('error') or 'see the scores'}"
    if r["test"] == "best":
        return "best"
    if r["test"] == "none":
        return f"{100 * r['diff_vs_best']:+.1f},{sep}not tested (n={r['n_pairs']})" if np.isfinite(r["diff_vs_best"]) else "not tested"
    star = " *" if r["differs"] else ""
    return (f"{100 * r['diff_vs_best']:+.1f}, p={_p(r['p_holm'])}{star}{sep}"
            f"({TEST_SHORT.get(r['test'], r['test'])}, n={r['n_pairs']} {r['paired_by']}s)")


#: what the timing columns hold, each said in the legend where its column is shown
_TIMINGS = {"latency ms": "latency: median over folds of the wall-clock time to compute the features of one "
                          "capture and predict it",
            "CPU ms": "CPU: median over folds of the CPU time of labelling one capture (which the machine's load "
                      "changes far less than wall-clock time)",
            "fit s": "fit: median seconds per fold", "features ms": "features: median ms per capture"}
#: the column of each time a Pareto front is computed on (:func:`touchbench.reports.pareto.pareto_cost`)
PARETO_COLUMNS = {"latency_cpu_ms": "CPU ms", "latency_ms": "latency ms"}
_PARETO_COSTS = {"latency_cpu_ms": "the CPU time of labelling one capture",
                 "latency_ms": "the wall-clock time of labelling one capture"}


def pareto_sentence(lb: Leaderboard, shown: set[str] | None = None) -> str:
    """What the ★ mark is on: accuracy against the cost column(s) of the table's fronts, each
    named; one the terminal does not show (``shown``: its headers) is said to be hidden."""
    costs = lb.pareto_costs or ["latency_cpu_ms"]
    if shown is not None and any(PARETO_COLUMNS[c] not in shown for c in costs):
        return (" ★ = Pareto: accuracy vs " + " or ".join(PARETO_COLUMNS[c] for c in costs)
                + " per capture (column hidden at this width).")
    return (" ★ = on the Pareto front of accuracy against "
            + " or ".join(f"{_PARETO_COSTS[c]} (the {PARETO_COLUMNS[c]} column)" for c in costs) + ".")


def legend(lb: Leaderboard, shown: Iterable[str] | None = None) -> str:
    """The sentences that explain the table's columns and marks; ``shown``: the headers a terminal
    shows (None: every column), so that a narrow terminal's legend explains only what it prints."""
    shown = None if shown is None else set(shown)
    timings = "; ".join(t for h, t in _TIMINGS.items()
                        if (h in shown if shown is not None else h != "CPU ms" or _has_cpu_times(lb.rows)))
    timings = f"{timings[:1].upper()}{timings[1:]}. " if timings else ""
    pareto = shown is None or "Pareto" in shown
    return (f"Accuracy: mean over folds (± sample sd; for a single fold evaluated with several seeds, the sd over "
            f"the seeds); interval: Student t over folds (Wilson over captures for a single fold). "
            + timings + "Δ: mean paired difference "
            f"to the best method in percentage points; p: McNemar's exact test on the test captures (one test set) "
            f"or the corrected resampled t-test over folds, Holm-adjusted over the table; * = differs at α={lb.alpha:g}."
            + (pareto_sentence(lb, shown) if pareto else "")
            + (" † = the method was designed on part of this data (see the note); held out: accuracy on the "
               "test captures outside the design data (mean over folds)." if lb.has_design else "")
            + legend_note(lb.rows)
            + breakdown_legend(lb.breakdown)
            + (" LEAKY rows: the evaluation let test data inform training (see the notes)."
               if bool((lb.rows["leakage"] != "").any()) else "")
            + (f" ADAPTED: every method of this table adapted to each test session using that session's "
               f"unlabelled captures ({lb.adaptation}; never their labels): a figure of another kind, ranked "
               f"and tested only against each other, never against the plain methods." if lb.adaptation else ""))


def _md_escape(s: str) -> str:
    return s.replace("|", "\\|")


def to_markdown(lbs: list[Leaderboard], title: str | None = "Leaderboard") -> str:
    out = [f"# {title}", ""] if title else []
    for lb in lbs:
        out.append(f"## {lb.title}")
        out.append("")
        if lb.live is not None:
            out += live_markdown(lb.live) + [""] + [f"Note: {n}\n" for n in lb.notes]
            continue
        header, cells = display_rows(lb)
        out.append("| " + " | ".join(header) + " |")
        out.append("|" + "|".join("---" for _ in header) + "|")
        for c in cells:
            out.append("| " + " | ".join(_md_escape(x) for x in c) + " |")
        out.append("")
        out.append(legend(lb))
        for n in lb.notes:
            out.append("")
            out.append(f"Note: {n}")
        out.append("")
        out += curve_markdown(lb.title, lb.curve, method_names(lb.rows)) if lb.curve is not None else []
    ranks = ranks_across(lbs)
    if ranks is not None and len(ranks):
        out += [f"## Mean rank across {int(ranks['tables'].iloc[0])} tables", "",
                "| method | mean rank | mean accuracy % |", "|---|---|---|"]
        out += [f"| {_md_escape(r.method)} | {r.mean_rank:.2f} | {_pct(r.mean_accuracy)} |" for r in ranks.itertuples()]
        out += ["", RANK_LEGEND, ""]
        f = across_friedman(lbs)
        out += [across_note(f), ""] if f is not None else []
    return "\n".join(out)


RANK_LEGEND = ("Rank: within each table by mean accuracy (1 = best; ties share the average of their ranks), "
               "averaged over the tables; only methods present in every table.")


def _records(lb: Leaderboard) -> list[dict[str, Any]]:
    return _clean_records(lb.rows)


def _clean_records(rows: pd.DataFrame) -> list[dict[str, Any]]:
    recs = []
    for r in rows.to_dict(orient="records"):
        clean = {}
        for k, v in r.items():
            if isinstance(v, (np.floating, float)):
                v = None if not np.isfinite(v) else float(v)
            elif isinstance(v, np.integer):
                v = int(v)
            elif isinstance(v, np.bool_):
                v = bool(v)
            clean[k] = v
        recs.append(clean)
    return recs


def to_json(lbs: list[Leaderboard]) -> str:
    tables = []
    for lb in lbs:
        tables.append({
            "dataset": lb.dataset, "dataset_hash": lb.dataset_hash, "target": lb.target, "scheme": lb.scheme,
            "alpha": lb.alpha, "machines": lb.machines, "reference_machine": lb.reference_machine,
            "pooled_machines": lb.pooled_machines, "notes": lb.notes, "rows": _records(lb),
            "leaky": lb.is_leaky, "looks": None if lb.looks is None else vars(lb.looks),
            "adaptation": lb.adaptation, "curve": curve_json(lb.curve, method_names(lb.rows)),
            "live": None if lb.live is None else _clean_records(lb.live),
        })
    return json.dumps({"tables": tables}, indent=2) + "\n"


def to_csv(lbs: list[Leaderboard]) -> str:
    """Every table's rows, a method named by its readable name (its id, and the data's hash, only in
    the JSON document); a stream evaluation's table: its stream table's rows (one per method and rule,
    ``default`` marking the default rule)."""
    frames = []
    for lb in lbs:
        if lb.live is not None:  # a stream evaluation: its stream table's rows, as the other formats show
            d = lb.live.drop(columns="method_id")
            for col in ("same_as", "sources"):
                d[col] = d[col].map("; ".join)
        else:
            d = lb.rows.copy()
            d.insert(1, "method", d["method_id"].map(method_names(lb.rows)))
            d = d.drop(columns="method_id")
        d.insert(0, "scheme", lb.scheme)
        d.insert(0, "target", lb.target)
        d.insert(0, "variant", lb.variant)
        d.insert(0, "dataset", lb.dataset)
        d["adaptation"] = lb.adaptation
        frames.append(d)
    return pd.concat(frames, ignore_index=True).to_csv(index=False)


#: the columns a terminal always shows (the name, the accuracy and its interval, the test's verdict;
#: which rows are leaky), then the others in the order a wider terminal adds them
TERMINAL_ESSENTIAL = ("#", "method", "evaluation", "accuracy % (±sd)", "95 % interval", "vs best: Δ pp, p (Holm)")
#: (the Pareto mark right after the time its front is on: :func:`terminal_priority`)
TERMINAL_PRIORITY = ("held out %", "features", "estimator", "macro F1 %", "CPU ms", "Pareto", "latency ms", "folds",
                     "timing machine", "fit s", "features ms")
#: headers broken over two lines in a terminal, so that a header is no wider than its numbers
_TERMINAL_HEADERS = {"accuracy % (±sd)": "accuracy %\n(±sd)", "95 % interval": "95 %\ninterval",
                     "vs best: Δ pp, p (Holm)": "vs best: Δ pp,\np (Holm)", "macro F1 %": "macro\nF1 %",
                     "latency ms": "latency\nms", "CPU ms": "CPU\nms", "features ms": "features\nms", "held out %": "held out\n%",
                     "timing machine": "timing\nmachine"}
#: the columns of words, not numbers: a narrow terminal shortens them (:func:`~.short_labels.fit_labels`) down to
#: :data:`TEXT_MIN_WIDTH` characters (or their header's width); a number is never cut nor wrapped
TERMINAL_TEXT = ("method", "features", "estimator", "evaluation", "timing machine")
TEXT_MIN_WIDTH = 12
#: the width a text column counts for when a terminal chooses which other columns fit
TEXT_FIT_WIDTH = 40


def fitting_columns(widths: dict[str, int], available: int, essential: Iterable[str]) -> list[str]:
    """The columns a terminal table of ``available`` characters shows, in ``widths``' order (its
    priority): every essential one, then the others while the table still fits with every column at
    its own width (``widths``: the widest cell or header line). A rich table takes 3 characters per
    column (padding and a border) and 1 for its left edge."""
    essential = set(essential)
    shown = [h for h in widths if h in essential]
    used = 1 + sum(widths[h] + 3 for h in shown)
    for h in (h for h in widths if h not in essential):
        if used + widths[h] + 3 > available:
            break
        shown.append(h)
        used += widths[h] + 3
    return shown


def _table_width(widths: dict[str, int], shown: Iterable[str]) -> int:
    """The characters a rich table takes with columns ``shown`` at ``widths`` (:func:`fitting_columns`)."""
    return 1 + sum(widths[h] + 3 for h in shown)


def _narrowed(widths: dict[str, int], least: dict[str, int], shown: list[str], available: int) -> dict[str, int]:
    """``widths`` with the text columns among ``shown`` narrowed, the widest first, until the table
    fits in ``available`` characters or each is at its ``least``."""
    out = dict(widths)
    while _table_width(out, shown) > available:
        text = [h for h in shown if out[h] > least[h]]
        if not text:
            break
        widest = max(text, key=lambda h: out[h])
        out[widest] -= 1
    return out


def terminal_layout(header: list[str], cells: list[list[str]], text_cells: list[set[int]], available: int,
                    essential: Iterable[str], priority: Iterable[str] = (),
                    text: Iterable[str] = TERMINAL_TEXT) -> tuple[list[int], dict[str, int]]:
    """The columns (indices into ``header``) a terminal of ``available`` characters shows and their
    widths. Every essential column is shown, then those of ``priority`` while they fit whole
    (:func:`fitting_columns`; a text column counted as at most :data:`TEXT_FIT_WIDTH`); while the table is too wide, its text shrinks (the text columns,
    :data:`TERMINAL_TEXT`, and each row's cells ``text_cells`` names, down to :data:`TEXT_MIN_WIDTH`).
    A number never shrinks: where even the numbers do not fit, the table is wider than ``available``
    (the terminal wraps its lines). A cell's lines are ``\n``-separated; ``header`` holds the
    header lines as shown; ``text``: the text columns (a column of labels already fitted is not)."""
    names = [h.replace("\n", " ") for h in header]
    text = set(text)
    widths, least = {}, {}
    for i, (h, head) in enumerate(zip(names, header)):
        head_w = max(cell_len(x) for x in head.split("\n"))
        lines = [(cell_len(x), i in row_text or h in text) for c, row_text in zip(cells, text_cells)
                 for x in c[i].split("\n")]
        widths[h] = max([head_w] + [w for w, _ in lines])
        numbers = max([head_w] + [w for w, is_text in lines if not is_text])
        least[h] = max(numbers, min(widths[h], max(TEXT_MIN_WIDTH, head_w)))
    order = [h for h in (*essential, *priority) if h in widths] + [h for h in names if h not in (*essential, *priority)]
    # a long label does not keep the other columns off: it counts as TEXT_FIT_WIDTH when they are chosen
    shown = fitting_columns({h: min(widths[h], max(least[h], TEXT_FIT_WIDTH)) for h in order}, available, essential)
    widths = _narrowed(widths, least, shown, available)
    return [i for i, h in enumerate(names) if h in shown], widths


def _fitted_table(title: str, header: list[str], cells: list[list[str]], text_cells: list[set[int]],
                  available: int, essential: Iterable[str], priority: Iterable[str] = (),
                  text: Iterable[str] = TERMINAL_TEXT) -> tuple[Table, list[int], list[tuple[str, FittedLabels]]]:
    """A rich table of ``cells`` laid out by :func:`terminal_layout`, no cell wrapped, each text
    column's lines fitted to its width as a whole (:func:`~.short_labels.fit_labels`: each still told
    apart); the indices of the columns shown, and each text column's name with its fitted lines."""
    keep, widths = terminal_layout(header, cells, text_cells, available, essential, priority, text)
    text = set(text)
    names = [h.replace("\n", " ") for h in header]
    t = Table(title=escape(title), show_lines=False)  # a name like "[b5830b]" is text, not markup
    for i in keep:
        t.add_column(escape(header[i]), no_wrap=True, overflow="ignore", width=widths[names[i]])
    short: dict[tuple[int, str], str] = {}
    fitted = []
    for i in keep:
        lines = [x for c, row_text in zip(cells, text_cells) if i in row_text or names[i] in text
                 for x in c[i].split("\n")]
        if lines:
            fitted.append((names[i], fit_labels(lines, widths[names[i]])))
            short.update(((i, x), y) for x, y in zip(lines, fitted[-1][1].shown))
    for c in cells:
        t.add_row(*(escape("\n".join(short.get((i, x), x) for x in c[i].split("\n"))) for i in keep))
    return t, keep, fitted


def terminal_priority(lb: Leaderboard) -> tuple[str, ...]:
    """:data:`TERMINAL_PRIORITY` with the column of each time the table's Pareto fronts are on just
    before the Pareto column, so that a terminal never shows the mark without the time it is on."""
    costs = [PARETO_COLUMNS[c] for c in lb.pareto_costs]
    rest = [h for h in TERMINAL_PRIORITY if h not in costs]
    at = rest.index("Pareto")
    return (*rest[:at], *costs, *rest[at:])


def _terminal_table(lb: Leaderboard, width: int) -> tuple[Table, list[str], list[tuple[str, FittedLabels]]]:
    """The table of ``lb`` as a terminal of ``width`` characters shows it (:func:`terminal_layout`):
    a number and its note on one line where the whole table fits so, else on two; the method names
    fitted to their column (:func:`touchbench.reports.short_labels.fit_labels`: each still told
    apart), then the columns laid out again with those names (:func:`_fitted_table`); the headers
    of the columns shown, and each text column fitted (the method names first)."""
    failed = [r["n_folds"] == 0 and r["n_failed"] > 0 for _, r in lb.rows.iterrows()]
    priority = terminal_priority(lb)
    for sep in (" ", "\n"):
        header, cells = display_rows(lb, sep)
        heads = [_TERMINAL_HEADERS.get(h, h) for h in header]
        vs = header.index("vs best: Δ pp, p (Holm)")
        text_cells = [{vs} if f else set() for f in failed]  # a failed method's error is words
        keep, widths = terminal_layout(heads, cells, text_cells, width, TERMINAL_ESSENTIAL, priority)
        whole = all(widths[header[i]] >= cell_len(c[i]) for c in cells for i in keep)
        if whole and _table_width(widths, [header[i] for i in keep]) <= width:
            break  # fits with nothing shortened
    m = header.index("method")
    names = fit_labels([c[m] for c in cells], widths["method"])
    cells = [[*c[:m], name, *c[m + 1:]] for c, name in zip(cells, names.shown)]
    text = [h for h in TERMINAL_TEXT if h != "method"]  # fitted: never cut again
    table, keep, fitted = _fitted_table(lb.title, heads, cells, text_cells, width, TERMINAL_ESSENTIAL, priority, text)
    return table, [header[i] for i in keep], [("method names", names), *fitted]


def _print_fitted(console: Console, table: Table, fitted: list[tuple[str, FittedLabels]] = ()) -> None:
    """Print ``table`` whole: wider than the console when its numbers need it (the terminal wraps
    the lines; no number is cut); above it what the ``fitted`` columns' lines leave out, under it
    their numbered lines in full (:class:`~.short_labels.FittedLabels`)."""
    for what, f in fitted:
        if f.heading(what) is not None:
            console.print(escape(f.heading(what)), style="dim")
    need = console.measure(table, options=console.options.update_width(10 ** 4)).maximum
    width = console.width
    console.width = max(need, width)
    try:
        console.print(table)
    finally:
        console.width = width
    for _, f in fitted:
        if f.legend() is not None:
            console.print(escape(f.legend()))


def _terminal_live(lb: Leaderboard, width: int) -> tuple[Table, list[int], list[tuple[str, FittedLabels]]]:
    """A stream evaluation's table (:mod:`.stream_table`) laid out as any table (:func:`terminal_layout`):
    the method and rule shortened first, no number cut."""
    header, cells = live_cells(lb.live)
    return _fitted_table(lb.title, header, cells, [{0, 1}] * len(cells), width, LIVE_ESSENTIAL, LIVE_PRIORITY)


def _print_curve(console: Console, lb: Leaderboard) -> None:
    """A data curve's tables (:mod:`.curve_table`) laid out as any table, each cell's interval on the
    number's line where every column fits so, else below it; then its sentences and legend."""
    names = method_names(lb.rows)
    for title, make in zip(curve_titles(lb.title, lb.curve), (curve_cells, gain_cells)):
        for sep in (" ", "\n"):
            header, cells = make(lb.curve, names, sep)
            if not header:
                break
            essential = [h for h in curve_essential(lb.curve) if h in header] or header[:1]
            keep, widths = terminal_layout(header, cells, [{0}] * len(cells), console.width, essential)
            if len(keep) == len(header) and _table_width(widths, header) <= console.width:
                break
        if header:
            table, _, fitted = _fitted_table(title, header, cells, [{0}] * len(cells), console.width, essential)
            _print_fitted(console, table, fitted)
            console.print()
    for line in reach_lines(lb.curve, names):
        console.print(escape(line))
    console.print(escape(curve_legend(lb.curve)), style="dim")
    console.print()


def _terminal_width() -> int | None:
    """The console width: ``COLUMNS`` or the terminal's own (None lets rich read them), 250 for a
    pipe or a file (the whole table)."""
    return None if sys.stdout.isatty() or os.environ.get("COLUMNS", "").isdigit() else 250


def print_terminal(lbs: list[Leaderboard], console=None) -> None:
    """The leaderboards in a terminal: on a narrow one the rank, name, accuracy, interval and test
    verdict of every method; a wider one adds columns (``TERMINAL_PRIORITY``)."""
    console = console or Console(width=_terminal_width())
    for lb in lbs:
        if lb.live is None:
            table, shown, fitted = _terminal_table(lb, console.width)
            _print_fitted(console, table, fitted)
            console.print(escape(legend(lb, shown)), style="dim")  # the columns shown, no other
        else:
            table, _, fitted = _terminal_live(lb, console.width)
            _print_fitted(console, table, fitted)
            console.print(escape(LIVE_LEGEND), style="dim")
        for n in lb.notes:
            console.print(escape(f"Note: {n}"), style="yellow")
        console.print()
        if lb.curve is not None:
            _print_curve(console, lb)
    ranks = ranks_across(lbs)
    if ranks is not None and len(ranks):
        header = ["method", "mean rank", "mean accuracy %"]
        cells = [[r.method, f"{r.mean_rank:.2f}", _pct(r.mean_accuracy)] for r in ranks.itertuples()]
        table, _, fitted = _fitted_table(f"Mean rank across {int(ranks['tables'].iloc[0])} tables", header, cells,
                                         [set() for _ in cells], console.width, header)
        _print_fitted(console, table, fitted)
        console.print(RANK_LEGEND, style="dim")
        f = across_friedman(lbs)
        if f is not None:
            console.print(escape(across_note(f)), style="dim")


def write_text(path: Path, text: str) -> Path:
    """Write ``text`` atomically (temporary file + rename), with the mode the umask gives."""

    atomic_write_bytes(Path(path), text.encode())
    return Path(path)


def write_outputs(lbs: list[Leaderboard], out: Path, formats: Iterable[str]) -> list[Path]:
    """Write ``leaderboard.{md,csv,json}`` into ``out`` for the chosen formats."""
    written = []
    for fmt in formats:
        text = {"md": to_markdown, "csv": to_csv, "json": to_json}[fmt](lbs)
        written.append(write_text(Path(out) / f"leaderboard.{fmt}", text))
    return written
