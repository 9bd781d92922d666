"""``subjects``: per-subject accuracy (from the predictions) of the best methods of a table, one
bar per method and subject."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...protocols.schemes.base import natural_key
from ..leaderboard import Leaderboard
from ..paired import subject_values
from ..results import ResultSet
from .base import FIGURES, FORMATS, FigureOptions, figure_width, has_predictions, pyplot, save, short_label, wrap

__all__ = ["draw", "plot_subjects"]


def plot_subjects(rs: ResultSet, lb: Leaderboard, base: Path, top: int = 5, size: str = "text",
                  formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Per-subject accuracy of the ``top`` methods of the table."""

    plt = pyplot()
    preds = rs.predictions[rs.predictions["table_key"] == lb.key] if rs.predictions is not None else None
    rows = lb.rows.head(top)
    series = {}
    for _, r in rows.iterrows():
        s = subject_values(preds, r["method_id"], lb.folds.loc[lb.folds["method_id"] == r["method_id"], "fold_key"])
        if len(s):
            series[r["method_id"]] = (r, s)
    if not series:
        raise ValueError(f"{lb.title}: no predictions to compute per-subject accuracy")

    subjects = sorted(set().union(*[set(s.index) for _, s in series.values()]), key=natural_key)
    w = figure_width(size)
    fig, ax = plt.subplots(figsize=(w, 3.4 if size == "text" else 3.0), layout="constrained")
    n = len(series)
    width = 0.8 / n
    for i, (mid, (r, s)) in enumerate(series.items()):
        x = np.arange(len(subjects)) + (i - (n - 1) / 2) * width
        y = [100 * s.get(subj, np.nan) for subj in subjects]
        ax.bar(x, y, width=width, label=f"{short_label(r, 36)} ({100 * r['accuracy']:.1f} %)")
    ax.set_xticks(range(len(subjects)), labels=subjects, rotation=45 if len(subjects) > 12 else 0)
    ax.set_xlabel("subject")
    ax.set_ylabel("accuracy (%)")
    ax.set_ylim(0, 105)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2 if size == "text" else 1, frameon=False)
    ax.set_title(wrap(f"{lb.title}: per-subject accuracy", w))
    return save(fig, base, formats)


@FIGURES.register("subjects", description="per-subject accuracy of a table's five best methods", order=4)
def draw(rs: ResultSet, lb: Leaderboard, base: Path, options: FigureOptions) -> list[Path]:
    """The per-subject plot of a table with predictions (none without)."""
    if not has_predictions(rs, lb):
        return []
    try:
        return plot_subjects(rs, lb, base, size=options.size, formats=options.formats)
    except ValueError:
        return []
