"""Plots of a leaderboard (matplotlib, Agg backend), paper-ready: each written as PDF, SVG and
300-dpi PNG (``FORMATS``), at a column or a text width (``SIZES``: 3.5 and 7 inches) with every
font at least ``MIN_FONT_PT`` (7 pt) at that size. Titles and file names come from the dataset,
scheme and method names (never a hash); names that would collide get ``-2``, ``-3``...

- ``pareto``: accuracy (mean over folds, 95 % interval as error bar) against
  the three measured costs -- latency per capture, fit time per fold and
  feature extraction time per capture -- with the accuracy / latency Pareto
  front drawn as a step line (per machine when several machines measured).
- ``frames``: from an ``early`` scheme, accuracy against the number of
  frames seen (bottom axis) and seconds seen (top axis, from the dataset's
  frame rate), one curve per method.
- ``confusion``: the confusion matrix of a method pooled over its folds, as
  counts and row-normalised (each row is a true class, summing to 1), with
  the class names on both axes.
- ``subjects``: per-subject accuracy (from the predictions) of the best
  methods of a table.
- ``cd``: a critical difference diagram (aeon's ``plot_critical_difference``:
  mean ranks over the folds, cliques of methods not told apart by pairwise
  Wilcoxon tests with Holm's correction) of the methods of a table;
  :func:`plot_cd_across` draws one across tables (datasets and schemes), a
  table being one problem.
"""

from __future__ import annotations

import math
import re
import textwrap
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd

from ..core.errors import TouchbenchError
from ..protocols.schemes.base import natural_key
from ..results.store import PREDICTED, TRUE
from .leaderboard import Leaderboard, method_label, method_labels, subject_values
from .results import ResultSet

__all__ = ["FORMATS", "KINDS", "MIN_FONT_PT", "SIZES", "confusion_matrix", "plot_cd", "plot_cd_across",
           "plot_confusion", "plot_frames", "plot_pareto", "plot_subjects", "plot_table", "slug", "unique_stem"]

KINDS = ("pareto", "frames", "confusion", "subjects", "cd")
#: figure widths in inches: one column of a two-column paper, the text width
SIZES = {"column": 3.5, "text": 7.0}
FORMATS = ("pdf", "svg", "png")
MIN_FONT_PT = 7.0
PNG_DPI = 300


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    # text stays text in SVG (searchable, smaller); fixed hash salt: the same plot gives the same file;
    # every font at least MIN_FONT_PT at print size (figures are drawn at their print width)
    plt.rcParams.update({
        "svg.hashsalt": "touchbench", "svg.fonttype": "none", "pdf.fonttype": 42,
        "font.size": 8, "axes.titlesize": 8, "axes.labelsize": 8, "figure.titlesize": 8,
        "xtick.labelsize": MIN_FONT_PT, "ytick.labelsize": MIN_FONT_PT, "legend.fontsize": MIN_FONT_PT,
        "legend.title_fontsize": MIN_FONT_PT,
    })
    return plt


def _width(size: str) -> float:
    if size not in SIZES:
        raise ValueError(f"unknown figure size {size!r} (known: {', '.join(SIZES)})")
    return SIZES[size]


def _wrap(text: str, width_in: float) -> str:
    """``text`` wrapped to the figure's width (about 15 characters per inch at 8 pt)."""
    return "\n".join(textwrap.fill(line, max(20, int(width_in * 15))) for line in text.split("\n"))


def _clean(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._+-]+", "-", text).strip("-.").lower()


def slug(lb: Leaderboard) -> str:
    """A file stem from the table's dataset (a file's name without its suffix), scheme and target."""
    dataset = Path(lb.dataset).stem if lb.dataset.endswith((".parquet", ".csv", ".gz")) else lb.dataset
    parts = [dataset, lb.scheme] + ([f"target-{lb.target}"] if lb.target != "gesture" else [])
    parts += [lb.variant] if getattr(lb, "variant", "") else []
    return _clean("-".join(parts))[:80] or "table"


def unique_stem(stem: str, taken: set[str]) -> str:
    """``stem``, or ``stem-2``, ``stem-3``... the first not in ``taken`` (which it joins)."""
    out, k = stem, 1
    while out in taken:
        k += 1
        out = f"{stem}-{k}"
    taken.add(out)
    return out


def _save(fig, base: Path, formats: tuple[str, ...] = FORMATS, tight: bool = False) -> list[Path]:
    """``base``.pdf/.svg/.png (``base`` may hold dots: the extension is appended, never substituted);
    ``tight``: trimmed to what is drawn (a figure drawn by another library, not laid out by us)."""
    plt = _plt()
    base.parent.mkdir(parents=True, exist_ok=True)
    out = []
    meta = {"svg": {"Date": None}, "pdf": {"CreationDate": None, "ModDate": None}, "png": {"Software": None}}
    for ext in formats:
        if ext not in meta:
            raise ValueError(f"unknown figure format {ext!r} (known: {', '.join(FORMATS)})")
        p = base.parent / f"{base.name}.{ext}"
        # constrained layout: no bbox_inches="tight" (a second draw) unless asked
        fig.savefig(p, dpi=PNG_DPI, metadata=meta[ext], **({"bbox_inches": "tight", "pad_inches": 0.05} if tight else {}))
        out.append(p)
    plt.close(fig)
    return out


def _plain_log_ticks(ax) -> None:
    """Tick labels as plain numbers (no mathtext: much faster to draw); 1-2-5 ticks over at most two
    decades, powers of ten beyond (so that labels never run into each other on a narrow panel)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator

    lo, hi = ax.get_xlim()
    decades = math.log10(max(hi, 1e-12) / max(lo, 1e-12))
    subs = (1.0, 2.0, 5.0) if decades <= 2 else (1.0,)
    ax.xaxis.set_major_locator(LogLocator(base=10, subs=subs, numticks=8))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_locator(NullLocator())


def _short(r: Any, width: int = 28, with_features: bool = True) -> str:
    lab = f"{r['features']}/{r['classifier']}" if with_features else str(r["classifier"])
    return lab if len(lab) <= width else lab[: width - 1] + "…"


#: a label's height and its width per character at fontsize 7, in points (a generous estimate)
_LABEL_H, _LABEL_CHAR_W = 8.5, 4.3
#: offsets (points) tried in turn for a label, right of its point
_LABEL_OFFSETS = ((4, 3), (4, -9), (4, 11), (4, -17), (4, 19), (4, -25), (4, 27), (4, -33), (4, 35), (4, -41), (4, 43))


def label_offsets(points_pt: np.ndarray, widths_pt: np.ndarray, taken: Sequence[tuple[float, float, float, float]] = (),
                  bounds: tuple[float, float, float, float] | None = None) -> list[tuple[int, int]]:
    """Offsets (points) for labels at ``points_pt`` (N, 2 display points) so that their boxes do not overlap.

    Greedy, in the given order: each label takes the first offset of
    ``_LABEL_OFFSETS`` (right of its point), then of the same heights to
    the left of its point, whose box (``widths_pt`` wide, ``_LABEL_H``
    high) overlaps no box placed before it nor a box of ``taken`` (other
    text already drawn, in the same points) and stays inside ``bounds``
    (x0, y0, x1, y1: the panel, when given); when every offset collides,
    the one with the least overlap and area outside the panel.
    """
    placed: list[tuple[float, float, float, float]] = [tuple(map(float, b)) for b in taken]
    out = []
    for (x, y), w in zip(np.asarray(points_pt, dtype=float), np.asarray(widths_pt, dtype=float)):
        candidates = list(_LABEL_OFFSETS) + [(-int(math.ceil(w)) - dx, dy) for dx, dy in _LABEL_OFFSETS]
        best, best_cost = candidates[0], np.inf
        for dx, dy in candidates:
            box = (x + dx, y + dy, x + dx + w, y + dy + _LABEL_H)
            cost = sum(_overlap(box, b) for b in placed)
            if bounds is not None:
                cost += w * _LABEL_H - _overlap(box, bounds)
            if cost < best_cost:
                best, best_cost = (dx, dy), cost
            if cost == 0:
                break
        dx, dy = best
        placed.append((x + dx, y + dy, x + dx + w, y + dy + _LABEL_H))
        out.append(best)
    return out


def _overlap(a: Sequence[float], b: Sequence[float]) -> float:
    """Area shared by two boxes (x0, y0, x1, y1)."""
    return max(0.0, min(a[2], b[2]) - max(a[0], b[0])) * max(0.0, min(a[3], b[3]) - max(a[1], b[1]))


def _reference_labels(ax, fig, references: list[tuple[str, float]]) -> list[tuple[float, float, float, float]]:
    """Write each reference's label at the left of the panel, below its line, or above it when that
    would run into the label of a reference close by; their boxes (points), for the point labels to avoid."""
    x0 = ax.transAxes.transform((0.01, 0.0))[0] * 72.0 / fig.dpi
    boxes: list[tuple[float, float, float, float]] = []
    for label, value in sorted(references, key=lambda r: -r[1]):
        text = f"{label} {value:g} %"
        w = len(text) * _LABEL_CHAR_W
        y = ax.transData.transform((1.0, value))[1] * 72.0 / fig.dpi
        for dy in (-9, 2, -18, 11):
            box = (x0, y + dy, x0 + w, y + dy + _LABEL_H)
            if not any(_overlap(box, b) for b in boxes):
                break
        boxes.append(box)
        ax.annotate(text, (0.01, value), xycoords=("axes fraction", "data"), textcoords="offset points",
                    xytext=(0, dy), fontsize=MIN_FONT_PT, color="0.35").set_in_layout(False)
    return boxes


def plot_pareto(lb: Leaderboard, base: Path, references: list[tuple[str, float]] | None = None,
                size: str = "text", formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Accuracy against latency, fit time and feature time (see the module docstring).

    ``references``: (label, accuracy in %) pairs drawn as dashed horizontal
    lines on every panel (published results, targets). Points are labelled
    by classifier alone when every method of the table has the same
    features; labels are moved apart so that they do not overlap.
    """
    plt = _plt()
    rows = lb.rows
    costs = [("latency_ms", "latency per capture (ms)"), ("fit_seconds", "fit time per fold (s)"),
             ("feature_ms", "feature extraction per capture (ms)")]
    w = _width(size)
    if size == "column":  # three panels stacked
        fig, axes = plt.subplots(3, 1, figsize=(w, 7.0), sharey=True, layout="constrained")
    else:
        fig, axes = plt.subplots(1, 3, figsize=(w, 3.2), sharey=True, layout="constrained")
    machines = sorted(set(rows["timing_machine"]))
    markers = ["o", "s", "^", "D", "v"]
    label_all = len(rows) <= (6 if size == "column" else 10)
    with_features = rows["features"].nunique() > 1
    if references:
        lows = [100 * rows["ci_low"].min(), min(v for _, v in references) - 2]
        highs = [100 * rows["ci_high"].max(), max(v for _, v in references) + 3]
        axes[0].set_ylim(np.nanmin(lows), np.nanmax(highs))
    panels = []
    for ax, (col, title) in zip(axes, costs):
        labelled, n_zero = [], 0
        for mi, m in enumerate(machines):
            g = rows[(rows["timing_machine"] == m) & np.isfinite(rows[col]) & np.isfinite(rows["accuracy"])]
            n_zero += int((g[col] <= 0).sum())
            g = g[g[col] > 0]  # a log axis has no 0: a method whose features are computed by its estimator
            if g.empty:
                continue
            x = g[col].to_numpy(dtype=float)
            y = 100 * g["accuracy"].to_numpy(dtype=float)
            lo = 100 * g["ci_low"].to_numpy(dtype=float)
            hi = 100 * g["ci_high"].to_numpy(dtype=float)
            err = np.vstack([np.where(np.isfinite(lo), y - lo, 0), np.where(np.isfinite(hi), hi - y, 0)])
            colors = np.where(g["pareto"].to_numpy(dtype=bool), "tab:red", "tab:blue")
            ax.errorbar(x, y, yerr=err, fmt="none", ecolor="0.7", elinewidth=0.8, zorder=1)
            ax.scatter(x, y, c=list(colors), marker=markers[mi % len(markers)], s=28, zorder=2,
                       label=m if len(machines) > 1 else None)
            if col == "latency_ms":
                front = g[g["pareto"].to_numpy(dtype=bool)].sort_values("latency_ms")
                if len(front) > 1:
                    ax.step(front["latency_ms"].to_numpy(float), 100 * front["accuracy"].to_numpy(float),
                            where="post", color="tab:red", lw=1, alpha=0.6)
            labelled.append((g, x, y))
        ax.set_xscale("log")
        for _, value in references or []:
            ax.axhline(value, color="0.45", lw=0.8, ls="--", zorder=0)
        if n_zero:
            ax.annotate(f"not shown: {n_zero} without this cost", (0.99, 0.02), xycoords="axes fraction",
                        ha="right", fontsize=MIN_FONT_PT, color="0.35")
        ax.autoscale_view()
        if labelled:
            lo, hi = ax.get_xlim()  # room on the log axis for the labels beside the extreme points
            ax.set_xlim(lo / 1.3, hi * 1.3)
        _plain_log_ticks(ax)
        ax.set_xlabel(title)
        ax.grid(True, which="major", alpha=0.3)
        panels.append((ax, labelled))
    axes[0].set_ylabel("accuracy (%)")
    if len(machines) > 1:
        axes[0].legend(title="machine")
    fig.suptitle(_wrap(f"{lb.title}: accuracy vs cost (red: Pareto front on accuracy / latency)", w))
    fig.draw_without_rendering()  # the constrained layout places the panels: label boxes in final points
    for ax, labelled in panels:
        taken = _reference_labels(ax, fig, references) if references and ax is axes[0] else []
        _label_points(ax, fig, labelled, label_all, with_features, taken)
    return _save(fig, base, formats)


def _label_points(ax, fig, labelled: list, label_all: bool, with_features: bool,
                  taken: list[tuple[float, float, float, float]]) -> None:
    """Label the points of ``labelled`` ((rows, x, y) per machine; all, or the Pareto front's) apart from
    each other, from ``taken`` and from the panel's edge, with a line to a label moved away."""
    texts, pts = [], []
    for g, x, y in labelled:
        for (_, r), xi, yi in zip(g.iterrows(), x, y):
            if label_all or r["pareto"]:
                texts.append((_short(r, with_features=with_features), xi, yi))
                pts.append(ax.transData.transform((xi, yi)) * 72.0 / fig.dpi)
    if not texts:
        return
    order = np.argsort([-p[1] for p in pts], kind="stable")  # top to bottom
    bbox = ax.get_window_extent()
    bounds = tuple(v * 72.0 / fig.dpi for v in (bbox.x0, bbox.y0, bbox.x1, bbox.y1))
    offs = label_offsets(np.array(pts)[order], np.array([len(texts[i][0]) * _LABEL_CHAR_W for i in order]),
                         taken=taken, bounds=bounds)
    for i, off in zip(order, offs):
        lab, xi, yi = texts[i]
        leader = None if off == _LABEL_OFFSETS[0] else {"arrowstyle": "-", "color": "0.6", "lw": 0.5,
                                                        "shrinkA": 0, "shrinkB": 0}
        ax.annotate(lab, (xi, yi), textcoords="offset points", xytext=off, fontsize=MIN_FONT_PT,
                    va="bottom", arrowprops=leader).set_in_layout(False)  # labels may run over: panels keep their width


def _base_method(r: Any) -> str:
    return f"{r['feature_params']}|{r['classifier_name']}|{r['classifier_params']}"


def plot_frames(lb: Leaderboard, base: Path, size: str = "text", formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Accuracy against frames (and seconds) seen, from an ``early`` scheme."""
    plt = _plt()
    rows = lb.rows[np.isfinite(lb.rows["early_frames"])].copy()
    if rows.empty:
        raise ValueError(f"{lb.title}: not an early scheme (no frames-seen values)")
    rows["base"] = [_base_method(r) for _, r in rows.iterrows()]
    w = _width(size)
    fig, ax = plt.subplots(figsize=(w, 0.62 * w if size == "text" else 3.4), layout="constrained")
    for _, g in rows.groupby("base", sort=False):
        g = g.sort_values("early_frames")
        x = g["early_frames"].to_numpy(float)
        y = 100 * g["accuracy"].to_numpy(float)
        line = ax.plot(x, y, marker="o", ms=4, label=_short(g.iloc[0], 40))[0]
        lo, hi = 100 * g["ci_low"].to_numpy(float), 100 * g["ci_high"].to_numpy(float)
        if np.isfinite(lo).all():
            ax.fill_between(x, lo, hi, color=line.get_color(), alpha=0.15)
    ax.set_xlabel("frames seen")
    ax.set_ylabel("accuracy (%)")
    ax.grid(True, alpha=0.3)
    fr = lb.frame_rate
    if np.isfinite(fr) and fr > 0:
        sec = ax.secondary_xaxis("top", functions=(lambda f: f / fr, lambda s: s * fr))
        sec.set_xlabel(f"seconds seen (at {fr:g} frames/s)")
    ax.legend()
    ax.set_title(_wrap(f"{lb.title}: accuracy vs frames seen", w), pad=20 if np.isfinite(fr) else 6)
    return _save(fig, base, formats)


def confusion_matrix(rs: ResultSet, lb: Leaderboard, method: str) -> pd.DataFrame:
    """Counts (rows: true class, columns: predicted) of ``method`` pooled over its folds."""
    p = rs.predictions
    if p is None:
        raise ValueError("no predictions: confusion matrices need predictions.parquet")
    p = p[(p["table_key"] == lb.key) & (p["method_id"] == method)]
    p = p.sort_values("finished_at", kind="stable").drop_duplicates(["fold_key", "seed", "capture_id"], keep="last")
    classes = sorted(set(p[TRUE].astype(str)) | set(p[PREDICTED].astype(str)))
    m = pd.crosstab(p[TRUE].astype(str), p[PREDICTED].astype(str)).reindex(index=classes, columns=classes, fill_value=0)
    m.index.name, m.columns.name = "true", "predicted"
    return m


def plot_confusion(rs: ResultSet, lb: Leaderboard, method: str, base: Path, size: str = "text",
                   formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Counts and row-normalised confusion matrix of ``method`` (the row-normalised one alone when the
    classes are too many for two panels at the figure's width)."""
    plt = _plt()
    m = confusion_matrix(rs, lb, method)
    counts = m.to_numpy(dtype=float)
    if counts.size == 0:
        raise ValueError(f"{lb.title}: method {method} has no predictions")
    with np.errstate(invalid="ignore", divide="ignore"):
        norm = counts / counts.sum(axis=1, keepdims=True)
    norm = np.nan_to_num(norm)
    k = len(m)
    w = _width(size)
    panels = [(counts, "counts", "{:.0f}"), (norm, "row-normalised (recall)", "{:.2f}")]
    if k * MIN_FONT_PT * 1.6 > (w - 1.2) / 2 * 72:  # tick labels no longer fit two panels
        panels = panels[1:]
    panel_w = (w - 0.4) / len(panels)
    fig, axes = plt.subplots(1, len(panels), figsize=(w, min(9.0, panel_w + 1.4)), layout="constrained",
                             squeeze=False)
    cell_pt = (panel_w - 1.0) * 72 / max(k, 1)
    for ax, (data, title, fmt) in zip(axes[0], panels):
        im = ax.imshow(data, cmap="Blues", vmin=0, vmax=max(1.0, counts.max()) if title == "counts" else 1.0)
        ax.set_xticks(range(k), labels=list(m.columns), rotation=90 if k > 8 else 45, ha="right" if k <= 8 else "center")
        ax.set_yticks(range(k), labels=list(m.index))
        ax.set_xlabel("predicted")
        ax.set_ylabel("true")
        ax.set_title(title)
        thresh = (data.max() if data.size else 0) / 2
        if cell_pt >= len(fmt.format(data.max() if data.size else 0)) * MIN_FONT_PT * 0.62:  # numbers fit
            for i in range(k):
                for j in range(k):
                    v = data[i, j]
                    ax.text(j, i, fmt.format(v), ha="center", va="center", fontsize=MIN_FONT_PT,
                            color="white" if v > thresh else "black")
        fig.colorbar(im, ax=ax, shrink=0.8)
    r = lb.rows[lb.rows["method_id"] == method].iloc[0]
    acc = np.trace(counts) / counts.sum() if counts.sum() else math.nan
    fig.suptitle(_wrap(f"{lb.title}\n{method_label(r)}: pooled accuracy {100 * acc:.1f} % over "
                       f"{int(counts.sum())} test captures", w))
    return _save(fig, base, formats)


def plot_subjects(rs: ResultSet, lb: Leaderboard, base: Path, top: int = 5, size: str = "text",
                  formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Per-subject accuracy of the ``top`` methods of the table."""

    plt = _plt()
    preds = rs.predictions[rs.predictions["table_key"] == lb.key] if rs.predictions is not None else None
    rows = lb.rows.head(top)
    series = {}
    for _, r in rows.iterrows():
        s = subject_values(preds, r["method_id"])
        if len(s):
            series[r["method_id"]] = (r, s)
    if not series:
        raise ValueError(f"{lb.title}: no predictions to compute per-subject accuracy")

    subjects = sorted(set().union(*[set(s.index) for _, s in series.values()]), key=natural_key)
    w = _width(size)
    fig, ax = plt.subplots(figsize=(w, 3.4 if size == "text" else 3.0), layout="constrained")
    n = len(series)
    width = 0.8 / n
    for i, (mid, (r, s)) in enumerate(series.items()):
        x = np.arange(len(subjects)) + (i - (n - 1) / 2) * width
        y = [100 * s.get(subj, np.nan) for subj in subjects]
        ax.bar(x, y, width=width, label=f"{_short(r, 36)} ({100 * r['accuracy']:.1f} %)")
    ax.set_xticks(range(len(subjects)), labels=subjects, rotation=45 if len(subjects) > 12 else 0)
    ax.set_xlabel("subject")
    ax.set_ylabel("accuracy (%)")
    ax.set_ylim(0, 105)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2 if size == "text" else 1, frameon=False)
    ax.set_title(_wrap(f"{lb.title}: per-subject accuracy", w))
    return _save(fig, base, formats)


def _fit_label(label: str, width: int) -> str:
    """``label`` in at most ``width`` characters, shortening the part before `` / `` (the features)."""
    if len(label) <= width:
        return label
    head, sep, tail = label.partition(" / ")
    if not sep:
        return label[: width - 1] + "…"
    keep = max(3, width - len(sep) - len(tail) - 1)
    return head[:keep] + "…" + sep + tail


def _critical_difference(scores: pd.DataFrame, title: str, base: Path, size: str,
                         formats: tuple[str, ...]) -> list[Path]:
    """aeon's critical difference diagram of ``scores`` (rows: problems, columns: methods)."""
    try:
        from aeon.visualisation import plot_critical_difference
    except ImportError:
        raise TouchbenchError("critical difference diagrams are drawn by aeon: pip install 'touchbench[peers]'") from None
    _plt()  # our rcParams for aeon's figure
    scores = scores.dropna()
    if scores.shape[1] < 2 or scores.shape[0] < 2:
        raise ValueError(f"{title}: a critical difference diagram needs two methods and two problems "
                         f"(got {scores.shape[1]} and {scores.shape[0]})")
    w = _width(size)
    # long labels would leave no room for the scale: their features are shortened, never the classifier
    labels = [_fit_label(str(c), 22 if size == "column" else 30) for c in scores.columns]
    # room for the labels at 8 pt (about 0.6 em per character), at most a third of the width on each side
    textspace = min(w / 3, max(len(lab) for lab in labels) * 8 * 0.6 / 72 + 0.3)
    fig, ax = plot_critical_difference(scores.to_numpy(dtype=float), labels, width=w, textspace=textspace)
    for t in fig.findobj(match=lambda a: hasattr(a, "set_fontsize") and hasattr(a, "get_text")):
        t.set_fontsize(8 if t.get_fontsize() > 8 else max(MIN_FONT_PT, t.get_fontsize()))
    fig.suptitle(_wrap(title, w))
    return _save(fig, base, formats, tight=True)


def plot_cd(lb: Leaderboard, base: Path, size: str = "text", formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Critical difference diagram of a table's methods over its folds (a fold is one problem;
    folds some method lacks are left out)."""
    labels = method_labels(lb.rows)
    f = lb.folds.pivot_table(index="fold_key", columns="method_id", values="accuracy", aggfunc="mean")
    f = f[[m for m in lb.rows["method_id"] if m in f.columns]].rename(columns=labels)
    return _critical_difference(f, f"{lb.title}: mean rank over {len(f.dropna())} folds", base, size, formats)


def plot_cd_across(lbs: list[Leaderboard], base: Path, size: str = "text",
                   formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Critical difference diagram across tables (datasets and schemes): each table is one problem,
    a method's value its mean accuracy there; methods (by label) present in every table."""
    from .leaderboard import across_tables

    acc = across_tables(lbs)
    return _critical_difference(acc, f"mean rank over {len(acc.dropna())} tables", base, size, formats)


def plot_table(rs: ResultSet, lb: Leaderboard, out_dir: Path, kinds: tuple[str, ...] = KINDS,
               methods: list[str] | None = None, references: list[tuple[str, float]] | None = None,
               name: str | None = None, *, size: str = "text", formats: tuple[str, ...] = FORMATS,
               taken: set[str] | None = None) -> dict[str, list[Path]]:
    """Every applicable plot of one table into ``out_dir``; ``{name: [pdf, svg, png]}``.

    ``references`` go to :func:`plot_pareto` (reference accuracies in %).
    Files are named ``<name>-<kind>`` (``name`` defaults to :func:`slug`: the
    table's dataset, scheme and target); confusion matrices
    ``<name>-confusion-<features>-<classifier>``. ``taken`` (shared over the
    tables of one call) makes names unique with ``-2``, ``-3``... A stable
    ``name`` gives stable file names, e.g. for figures a document links to.

    Confusion matrices are drawn for ``methods`` (ids), by default the best
    method of the table. A plot that does not apply (``frames`` outside an
    ``early`` scheme, ``confusion`` without predictions, ``cd`` with fewer
    than two methods or folds) is skipped.
    """
    out_dir = Path(out_dir)
    taken = set() if taken is None else taken
    s = unique_stem(_clean(name) if name else slug(lb), taken)
    made: dict[str, list[Path]] = {}
    if "pareto" in kinds and lb.rows["accuracy"].notna().any():
        made["pareto"] = plot_pareto(lb, out_dir / f"{s}-pareto", references, size, formats)
    if "frames" in kinds and lb.is_early:
        made["frames"] = plot_frames(lb, out_dir / f"{s}-frames", size, formats)
    has_preds = rs.predictions is not None and (rs.predictions["table_key"] == lb.key).any()
    if "confusion" in kinds and has_preds:
        labels = method_labels(lb.rows)
        names: set[str] = set()
        for mid in methods or [str(lb.rows["method_id"].iloc[0])]:
            stem = unique_stem(f"confusion-{_clean(labels[mid].replace(' / ', '-'))}", names)
            try:
                made[stem] = plot_confusion(rs, lb, mid, out_dir / f"{s}-{stem}", size, formats)
            except ValueError:
                pass
    if "subjects" in kinds and has_preds:
        try:
            made["subjects"] = plot_subjects(rs, lb, out_dir / f"{s}-subjects", size=size, formats=formats)
        except ValueError:
            pass
    if "cd" in kinds:
        try:
            made["cd"] = plot_cd(lb, out_dir / f"{s}-cd", size, formats)
        except ValueError:
            pass
    return made
