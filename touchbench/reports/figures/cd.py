"""``cd``: the critical difference diagram across evaluations (Demsar 2006, Sec. 3.2.2): the methods'
mean ranks over the tables (datasets and schemes; a table is one data set, never its folds, which
share their data) and the cliques of methods Nemenyi's critical difference cannot tell apart, at the
tables' alpha (aeon's ``plot_critical_difference`` with ``test="nemenyi"``; one clique when the
Friedman test does not reject). :func:`plot_cd_across` draws it; it draws nothing, and says why
(:class:`NoDiagram`), where the tables are too few for the critical difference to separate any two
methods (:func:`touchbench.reports.stats.datasets_needed`) or aeon is not installed. The ``cd``
figure kind draws nothing for one table: ``touchbench plot`` and ``touchbench report`` draw the
diagram across their tables."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from ...core.versions import missing_extra
from ..across import across_friedman, across_note, across_tables
from ..leaderboard import Leaderboard
from ..results import ResultSet
from .base import FIGURES, FORMATS, MIN_FONT_PT, FigureOptions, figure_width, pyplot, save, wrap

__all__ = ["NoDiagram", "draw", "plot_cd_across"]

#: The alphas aeon's Nemenyi cliques know (its table of q_alpha).
AEON_ALPHAS = (0.01, 0.05, 0.1)


class NoDiagram(ValueError):
    """No critical difference diagram can be drawn; the message says why."""


def _fit_label(label: str, width: int) -> str:
    """``label`` in at most ``width`` characters, shortening the part before `` / `` (the features)."""
    if len(label) <= width:
        return label
    head, sep, tail = label.partition(" / ")
    if not sep:
        return label[: width - 1] + "…"
    keep = max(3, width - len(sep) - len(tail) - 1)
    return head[:keep] + "…" + sep + tail


def _aeon_plot():
    """aeon's diagram function; :class:`NoDiagram` naming the extra when aeon is not installed."""
    try:
        from aeon.visualisation import plot_critical_difference
    except ImportError:
        missing = ", ".join(missing_extra("peers")) or "aeon"
        raise NoDiagram(f"critical difference diagrams are drawn by aeon ({missing} not installed): "
                        "pip install 'touchbench[peers]'") from None
    return plot_critical_difference


def _critical_difference(scores: pd.DataFrame, title: str, alpha: float, base: Path, size: str,
                         formats: tuple[str, ...]) -> list[Path]:
    """aeon's Nemenyi critical difference diagram of ``scores`` (rows: tables, columns: methods)."""
    if alpha not in AEON_ALPHAS:
        raise NoDiagram(f"aeon's critical difference diagram knows alpha {', '.join(map(str, AEON_ALPHAS))} only "
                        f"(the tables use {alpha:g})")
    plot_critical_difference = _aeon_plot()
    pyplot()  # our rcParams for aeon's figure
    w = figure_width(size)
    # long labels would leave no room for the scale: their features are shortened, never the classifier
    labels = [_fit_label(str(c), 22 if size == "column" else 30) for c in scores.columns]
    # room for the labels at 8 pt (about 0.6 em per character), at most a third of the width on each side
    textspace = min(w / 3, max(len(lab) for lab in labels) * 8 * 0.6 / 72 + 0.3)
    fig, ax = plot_critical_difference(scores.to_numpy(dtype=float), labels, test="nemenyi", alpha=alpha,
                                       width=w, textspace=textspace)
    for t in fig.findobj(match=lambda a: hasattr(a, "set_fontsize") and hasattr(a, "get_text")):
        t.set_fontsize(8 if t.get_fontsize() > 8 else max(MIN_FONT_PT, t.get_fontsize()))
    fig.suptitle(wrap(title, w))
    return save(fig, base, formats, tight=True)


def plot_cd_across(lbs: list[Leaderboard], base: Path, size: str = "text",
                   formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Critical difference diagram across tables (datasets and schemes): each table is one data set,
    a method's value its mean accuracy there; methods (by label) present in every table.
    :class:`NoDiagram` (its message the reason) where none can be drawn."""
    f = across_friedman(lbs)
    if f is None:
        raise NoDiagram("a critical difference diagram needs two methods present in two tables or more")
    if not f.can_separate:
        raise NoDiagram(across_note(f))
    acc = across_tables(lbs)
    return _critical_difference(acc, f"mean rank over {f.n_datasets} tables (Nemenyi, α={f.alpha:g})", f.alpha,
                                base, size, formats)


@FIGURES.register("cd", description="critical difference diagram across the tables (aeon); none for one table",
                  order=5)
def draw(rs: ResultSet, lb: Leaderboard, base: Path, options: FigureOptions) -> list[Path]:
    """Nothing: a table's folds are not data sets (Demsar 2006); the diagram is drawn across tables
    (:func:`plot_cd_across`)."""
    return []
