"""``confusion``: the confusion matrix of a method pooled over its folds, as counts and
row-normalised (each row is a true class, summing to 1), with the class names on both axes; one
figure per method asked for (by default the table's best)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from ...results.store import PREDICTED, TRUE
from ..labels import method_label, method_labels
from ..leaderboard import Leaderboard
from ..results import ResultSet
from .base import (
    FIGURES,
    FORMATS,
    MIN_FONT_PT,
    FigureOptions,
    clean,
    figure_width,
    has_predictions,
    pyplot,
    save,
    unique_stem,
    wrap,
)

__all__ = ["confusion_matrix", "draw", "plot_confusion"]


def confusion_matrix(rs: ResultSet, lb: Leaderboard, method: str) -> pd.DataFrame:
    """Counts (rows: true class, columns: predicted) of ``method`` pooled over its folds (on a data
    curve, those of the table's reference point)."""
    p = rs.predictions
    if p is None:
        raise ValueError("no predictions: confusion matrices need predictions.parquet")
    p = p[(p["table_key"] == lb.key) & (p["method_id"] == method)]
    p = p[p["fold_key"].isin(set(lb.folds.loc[lb.folds["method_id"] == method, "fold_key"]))]
    p = p.sort_values("finished_at", kind="stable").drop_duplicates(["fold_key", "seed", "capture_id"], keep="last")
    classes = sorted(set(p[TRUE].astype(str)) | set(p[PREDICTED].astype(str)))
    m = pd.crosstab(p[TRUE].astype(str), p[PREDICTED].astype(str)).reindex(index=classes, columns=classes, fill_value=0)
    m.index.name, m.columns.name = "true", "predicted"
    return m


def plot_confusion(rs: ResultSet, lb: Leaderboard, method: str, base: Path, size: str = "text",
                   formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Counts and row-normalised confusion matrix of ``method`` (the row-normalised one alone when the
    classes are too many for two panels at the figure's width)."""
    plt = pyplot()
    m = confusion_matrix(rs, lb, method)
    counts = m.to_numpy(dtype=float)
    if counts.size == 0:
        raise ValueError(f"{lb.title}: method {method} has no predictions")
    with np.errstate(invalid="ignore", divide="ignore"):
        norm = counts / counts.sum(axis=1, keepdims=True)
    norm = np.nan_to_num(norm)
    k = len(m)
    w = figure_width(size)
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
    fig.suptitle(wrap(f"{lb.title}\n{method_label(r)}: pooled accuracy {100 * acc:.1f} % over "
                      f"{int(counts.sum())} test captures", w))
    return save(fig, base, formats)


@FIGURES.register("confusion", description="confusion matrices of methods pooled over their folds (counts, recall)",
                  order=3)
def draw(rs: ResultSet, lb: Leaderboard, base: Path, options: FigureOptions) -> list[Path]:
    """One confusion matrix per method of ``options.methods`` (default: the table's best), as
    ``base-<features>-<classifier>``; none without predictions or for a method without any."""
    if not has_predictions(rs, lb):
        return []
    labels = method_labels(lb.rows)
    names: set[str] = set()
    out: list[Path] = []
    for mid in options.methods or [str(lb.rows["method_id"].iloc[0])]:
        stem = unique_stem(clean(labels[mid].replace(" / ", "-")), names)
        try:
            out += plot_confusion(rs, lb, mid, base.parent / f"{base.name}-{stem}", options.size, options.formats)
        except ValueError:
            pass
    return out
