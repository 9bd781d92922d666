"""Plots of a leaderboard (matplotlib, Agg backend; each written as PNG and SVG).

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
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..protocols.splits import _natural_key
from .leaderboard import Leaderboard, subject_values
from .results import ResultSet

__all__ = ["KINDS", "plot_confusion", "plot_frames", "plot_pareto", "plot_subjects", "plot_table", "slug",
           "confusion_matrix"]

KINDS = ("pareto", "frames", "confusion", "subjects")


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    # text stays text in SVG (searchable, smaller); fixed hash salt: the same plot gives the same file
    plt.rcParams.update({"svg.hashsalt": "touchbench", "svg.fonttype": "none", "font.size": 9, "axes.titlesize": 10})
    return plt


def slug(lb: Leaderboard) -> str:
    s = f"{lb.dataset}-{lb.scheme}"
    s = re.sub(r"[^A-Za-z0-9._-]+", "-", s).strip("-").lower()
    return f"{s[:60]}-{lb.key[:6]}"


def _save(fig, base: Path) -> list[Path]:
    plt = _plt()
    base.parent.mkdir(parents=True, exist_ok=True)
    out = []
    for ext in ("png", "svg"):
        p = base.with_suffix(f".{ext}")
        kw = {"metadata": {"Date": None}} if ext == "svg" else {"metadata": {"Software": None}}
        fig.savefig(p, dpi=100, **kw)  # constrained layout: no bbox_inches="tight" (a second draw)
        out.append(p)
    plt.close(fig)
    return out


def _plain_log_ticks(ax) -> None:
    """Tick labels as plain numbers (no mathtext: much faster to draw)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator

    ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0), numticks=8))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_locator(NullLocator())


def _short(r: Any, width: int = 28, with_features: bool = True) -> str:
    lab = f"{r['features']}/{r['classifier']}" if with_features else str(r["classifier"])
    return lab if len(lab) <= width else lab[: width - 1] + "…"


#: a label's height and its width per character at fontsize 7, in points (a generous estimate)
_LABEL_H, _LABEL_CHAR_W = 8.5, 4.3
#: offsets (points) tried in turn for a label, right of its point
_LABEL_OFFSETS = ((4, 3), (4, -9), (4, 11), (4, -17), (4, 19), (4, -25), (4, 27))


def label_offsets(points_pt: np.ndarray, widths_pt: np.ndarray) -> list[tuple[int, int]]:
    """Offsets (points) for labels at ``points_pt`` (N, 2 display points) so that their boxes do not overlap.

    Greedy, in the given order: each label takes the first offset of
    ``_LABEL_OFFSETS`` whose box (``widths_pt`` wide, ``_LABEL_H`` high,
    lower-left corner at point + offset) overlaps no box placed before it;
    when every offset collides, the least overlapping one.
    """
    placed: list[tuple[float, float, float, float]] = []
    out = []
    for (x, y), w in zip(np.asarray(points_pt, dtype=float), np.asarray(widths_pt, dtype=float)):
        best, best_overlap = _LABEL_OFFSETS[0], np.inf
        for dx, dy in _LABEL_OFFSETS:
            box = (x + dx, y + dy, x + dx + w, y + dy + _LABEL_H)
            overlap = sum(max(0.0, min(box[2], b[2]) - max(box[0], b[0])) * max(0.0, min(box[3], b[3]) - max(box[1], b[1]))
                          for b in placed)
            if overlap < best_overlap:
                best, best_overlap = (dx, dy), overlap
            if overlap == 0:
                break
        dx, dy = best
        placed.append((x + dx, y + dy, x + dx + w, y + dy + _LABEL_H))
        out.append(best)
    return out


def plot_pareto(lb: Leaderboard, base: Path, references: list[tuple[str, float]] | None = None) -> list[Path]:
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
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), sharey=True, layout="constrained")
    machines = sorted(set(rows["timing_machine"]))
    markers = ["o", "s", "^", "D", "v"]
    label_all = len(rows) <= 12
    with_features = rows["features"].nunique() > 1
    if references:
        lows = [100 * rows["ci_low"].min(), min(v for _, v in references) - 2]
        highs = [100 * rows["ci_high"].max(), max(v for _, v in references) + 3]
        axes[0].set_ylim(np.nanmin(lows), np.nanmax(highs))
    for ax, (col, title) in zip(axes, costs):
        labelled = []
        for mi, m in enumerate(machines):
            g = rows[(rows["timing_machine"] == m) & np.isfinite(rows[col]) & np.isfinite(rows["accuracy"])]
            if g.empty:
                continue
            x = np.maximum(g[col].to_numpy(dtype=float), 1e-6)
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
                    ax.step(np.maximum(front["latency_ms"].to_numpy(float), 1e-6), 100 * front["accuracy"].to_numpy(float),
                            where="post", color="tab:red", lw=1, alpha=0.6)
            labelled.append((g, x, y))
        ax.set_xscale("log")
        for label, value in references or []:
            ax.axhline(value, color="0.45", lw=0.8, ls="--", zorder=0)
            if ax is axes[0]:
                ax.annotate(f"{label} {value:g} %", (0.01, value), xycoords=("axes fraction", "data"),
                            textcoords="offset points", xytext=(0, 2), fontsize=6.5, color="0.35")
        ax.autoscale_view()
        texts, pts = [], []
        for g, x, y in labelled:
            for (_, r), xi, yi in zip(g.iterrows(), x, y):
                if label_all or r["pareto"]:
                    texts.append((_short(r, with_features=with_features), xi, yi))
                    pts.append(ax.transData.transform((xi, yi)) * 72.0 / fig.dpi)
        if texts:
            order = np.argsort([-p[1] for p in pts], kind="stable")  # top to bottom
            offs = label_offsets(np.array(pts)[order], np.array([len(texts[i][0]) * _LABEL_CHAR_W for i in order]))
            for i, off in zip(order, offs):
                lab, xi, yi = texts[i]
                ax.annotate(lab, (xi, yi), textcoords="offset points", xytext=off, fontsize=7)
        _plain_log_ticks(ax)
        ax.set_xlabel(title)
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_ylabel("accuracy (%)")
    if len(machines) > 1:
        axes[0].legend(title="machine", fontsize=7)
    fig.suptitle(f"{lb.title}: accuracy vs cost (red: Pareto front on accuracy / latency)")
    return _save(fig, base)


def _base_method(r: Any) -> str:
    return f"{r['feature_params']}|{r['classifier_name']}|{r['classifier_params']}"


def plot_frames(lb: Leaderboard, base: Path) -> list[Path]:
    """Accuracy against frames (and seconds) seen, from an ``early`` scheme."""
    plt = _plt()
    rows = lb.rows[np.isfinite(lb.rows["early_frames"])].copy()
    if rows.empty:
        raise ValueError(f"{lb.title}: not an early scheme (no frames-seen values)")
    rows["base"] = [_base_method(r) for _, r in rows.iterrows()]
    fig, ax = plt.subplots(figsize=(7, 4.2), layout="constrained")
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
    ax.legend(fontsize=7)
    ax.set_title(f"{lb.title}: accuracy vs frames seen", pad=28 if np.isfinite(fr) else 6)
    return _save(fig, base)


def confusion_matrix(rs: ResultSet, lb: Leaderboard, method: str) -> pd.DataFrame:
    """Counts (rows: true class, columns: predicted) of ``method`` pooled over its folds."""
    p = rs.predictions
    if p is None:
        raise ValueError("no predictions: confusion matrices need predictions.parquet")
    p = p[(p["table_key"] == lb.key) & (p["method_id"] == method)]
    p = p.sort_values("finished_at", kind="stable").drop_duplicates(["fold_key", "seed", "capture_id"], keep="last")
    classes = sorted(set(p["true"].astype(str)) | set(p["predicted"].astype(str)))
    m = pd.crosstab(p["true"].astype(str), p["predicted"].astype(str)).reindex(index=classes, columns=classes, fill_value=0)
    m.index.name, m.columns.name = "true", "predicted"
    return m


def plot_confusion(rs: ResultSet, lb: Leaderboard, method: str, base: Path) -> list[Path]:
    """Counts and row-normalised confusion matrix of ``method``."""
    plt = _plt()
    m = confusion_matrix(rs, lb, method)
    counts = m.to_numpy(dtype=float)
    if counts.size == 0:
        raise ValueError(f"{lb.title}: method {method} has no predictions")
    with np.errstate(invalid="ignore", divide="ignore"):
        norm = counts / counts.sum(axis=1, keepdims=True)
    norm = np.nan_to_num(norm)
    k = len(m)
    size = max(3.2, 0.45 * k + 1.5)
    fig, axes = plt.subplots(1, 2, figsize=(2 * size + 1.6, size + 0.8), layout="constrained")
    for ax, data, title, fmt in ((axes[0], counts, "counts", "{:.0f}"), (axes[1], norm, "row-normalised (recall)", "{:.2f}")):
        im = ax.imshow(data, cmap="Blues", vmin=0, vmax=max(1.0, counts.max()) if title == "counts" else 1.0)
        ax.set_xticks(range(k), labels=list(m.columns), rotation=45, ha="right")
        ax.set_yticks(range(k), labels=list(m.index))
        ax.set_xlabel("predicted")
        ax.set_ylabel("true")
        ax.set_title(title)
        thresh = (data.max() if data.size else 0) / 2
        if k <= 16:
            for i in range(k):
                for j in range(k):
                    v = data[i, j]
                    ax.text(j, i, fmt.format(v), ha="center", va="center", fontsize=7,
                            color="white" if v > thresh else "black")
        fig.colorbar(im, ax=ax, shrink=0.8)
    r = lb.rows[lb.rows["method_id"] == method].iloc[0]
    acc = np.trace(counts) / counts.sum() if counts.sum() else math.nan
    fig.suptitle(f"{lb.title}\n{_short(r, 60)} [{method}]: pooled accuracy {100 * acc:.1f} % "
                 f"over {int(counts.sum())} test captures")
    return _save(fig, base)


def plot_subjects(rs: ResultSet, lb: Leaderboard, base: Path, top: int = 5) -> list[Path]:
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

    subjects = sorted(set().union(*[set(s.index) for _, s in series.values()]), key=_natural_key)
    fig, ax = plt.subplots(figsize=(max(6, 0.45 * len(subjects) + 3), 4), layout="constrained")
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
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)
    ax.set_title(f"{lb.title}: per-subject accuracy")
    return _save(fig, base)


def plot_table(rs: ResultSet, lb: Leaderboard, out_dir: Path, kinds: tuple[str, ...] = KINDS,
               methods: list[str] | None = None, references: list[tuple[str, float]] | None = None,
               name: str | None = None) -> dict[str, list[Path]]:
    """Every applicable plot of one table into ``out_dir``; ``{name: [png, svg]}``.

    ``references`` go to :func:`plot_pareto` (reference accuracies in %).
    Files are named ``<name>-<kind>`` (``name`` defaults to :func:`slug`, the
    table's dataset and scheme with a short key); a stable ``name`` gives
    stable file names, e.g. for figures a document links to.

    Confusion matrices are drawn for ``methods`` (ids), by default the best
    method of the table. A plot that does not apply (``frames`` outside an
    ``early`` scheme, ``confusion`` without predictions) is skipped.
    """
    out_dir = Path(out_dir)
    s = name or slug(lb)
    made: dict[str, list[Path]] = {}
    if "pareto" in kinds and lb.rows["accuracy"].notna().any():
        made["pareto"] = plot_pareto(lb, out_dir / f"{s}-pareto", references)
    if "frames" in kinds and lb.is_early:
        made["frames"] = plot_frames(lb, out_dir / f"{s}-frames")
    has_preds = rs.predictions is not None and (rs.predictions["table_key"] == lb.key).any()
    if "confusion" in kinds and has_preds:
        for mid in methods or [str(lb.rows["method_id"].iloc[0])]:
            try:
                made[f"confusion-{mid}"] = plot_confusion(rs, lb, mid, out_dir / f"{s}-confusion-{mid}")
            except ValueError:
                pass
    if "subjects" in kinds and has_preds:
        try:
            made["subjects"] = plot_subjects(rs, lb, out_dir / f"{s}-subjects")
        except ValueError:
            pass
    return made
