"""``cd``: a critical difference diagram (aeon's ``plot_critical_difference``: mean ranks over the
folds, cliques of methods not told apart by pairwise Wilcoxon tests with Holm's correction) of the
methods of a table; :func:`plot_cd_across` draws one across tables (datasets and schemes), a table
being one problem."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from ...core.errors import TouchbenchError
from ..leaderboard import Leaderboard, across_tables, method_labels
from ..results import ResultSet
from .base import FIGURES, FORMATS, MIN_FONT_PT, FigureOptions, figure_width, pyplot, save, wrap

__all__ = ["draw", "plot_cd", "plot_cd_across"]


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
    pyplot()  # our rcParams for aeon's figure
    scores = scores.dropna()
    if scores.shape[1] < 2 or scores.shape[0] < 2:
        raise ValueError(f"{title}: a critical difference diagram needs two methods and two problems "
                         f"(got {scores.shape[1]} and {scores.shape[0]})")
    w = figure_width(size)
    # long labels would leave no room for the scale: their features are shortened, never the classifier
    labels = [_fit_label(str(c), 22 if size == "column" else 30) for c in scores.columns]
    # room for the labels at 8 pt (about 0.6 em per character), at most a third of the width on each side
    textspace = min(w / 3, max(len(lab) for lab in labels) * 8 * 0.6 / 72 + 0.3)
    fig, ax = plot_critical_difference(scores.to_numpy(dtype=float), labels, width=w, textspace=textspace)
    for t in fig.findobj(match=lambda a: hasattr(a, "set_fontsize") and hasattr(a, "get_text")):
        t.set_fontsize(8 if t.get_fontsize() > 8 else max(MIN_FONT_PT, t.get_fontsize()))
    fig.suptitle(wrap(title, w))
    return save(fig, base, formats, tight=True)


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
    acc = across_tables(lbs)
    return _critical_difference(acc, f"mean rank over {len(acc.dropna())} tables", base, size, formats)


@FIGURES.register("cd", description="critical difference diagram of a table's methods over its folds (aeon)", order=5)
def draw(rs: ResultSet, lb: Leaderboard, base: Path, options: FigureOptions) -> list[Path]:
    """The critical difference diagram of a table (none with fewer than two methods or folds)."""
    try:
        return plot_cd(lb, base, options.size, options.formats)
    except ValueError:
        return []
