"""Comparisons across tables (several datasets or schemes): the methods present in every plain
table, their mean ranks, and the Friedman test with the Nemenyi critical difference (each table one
data set, never its folds; :mod:`touchbench.reports.stats`)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.stats import rankdata

from .labels import _p, method_labels
from .leaderboard import Leaderboard
from .stats import Friedman, friedman, rank_values

__all__ = ["across_friedman", "across_note", "across_tables", "mean_ranks", "plain_tables", "ranks_across"]



def plain_tables(lbs: list[Leaderboard]) -> list[Leaderboard]:
    """The tables of methods that did not adapt to the test data: the only ones compared across tables."""
    return [lb for lb in lbs if not lb.adaptation]


def across_tables(lbs: list[Leaderboard]) -> pd.DataFrame:
    """Mean accuracy of each method (by label) in each table (rows: table titles); only methods
    present, with an accuracy, in every table; only the plain tables (:func:`plain_tables`). The
    accuracies are rounded to :data:`touchbench.reports.stats.RANK_DIGITS` significant digits
    (:func:`touchbench.reports.stats.rank_values`), so that equal ones tie in every ranking of them
    (mean ranks, Friedman, the critical difference diagram)."""
    cols = {}
    for lb in plain_tables(lbs):
        labels = method_labels(lb.rows)
        r = lb.rows[lb.rows["accuracy"].notna()]
        cols[lb.title] = pd.Series(rank_values(r["accuracy"]), index=[labels[m] for m in r["method_id"]])
    acc = pd.DataFrame(cols).T
    return acc.dropna(axis=1)


def across_friedman(lbs: list[Leaderboard]) -> Friedman | None:
    """The Friedman test and Nemenyi critical difference over the tables (each table one data set, at
    the tables' alpha) of the methods present in every table; None with fewer than two of either."""
    acc = across_tables(lbs)
    if acc.shape[0] < 2 or acc.shape[1] < 2:
        return None
    return friedman(acc.to_numpy(np.float64), lbs[0].alpha)


def across_note(f: Friedman) -> str:
    """What the Friedman test and the critical difference say across the tables, in one paragraph."""
    test = (f"Friedman test over N = {f.n_datasets} tables of {f.k} methods: chi2 = {f.statistic:.2f}, "
            f"p = {_p(f.pvalue)}" if np.isfinite(f.pvalue) else
            f"no Friedman test: it needs three methods (here {f.k}) and two tables (here {f.n_datasets})")
    cd = f"Nemenyi critical difference at α={f.alpha:g}: {f.cd:.2f} mean ranks"
    if f.can_separate:
        return f"{test}. {cd}."
    return (f"{test}. {cd}: with {f.n_datasets} tables even the largest possible difference ({f.k - 1}) is below it, "
            f"so no two methods can be told apart and no diagram is drawn; {f.k} methods need at least "
            f"{f.datasets_needed} tables (datasets or evaluations).")


def ranks_across(lbs: list[Leaderboard]) -> pd.DataFrame | None:
    """:func:`mean_ranks` of ``lbs`` when they hold at least two plain tables (:func:`plain_tables`:
    the only ones compared across tables), else None: the section across tables of every report."""
    return mean_ranks(lbs) if len(plain_tables(lbs)) > 1 else None


def mean_ranks(lbs: list[Leaderboard]) -> pd.DataFrame:
    """Methods present in every table, ranked within each table (1 = best accuracy; ties get the
    average of their ranks) and the ranks averaged over the tables: columns ``method``,
    ``mean_rank``, ``tables``, ``mean_accuracy``; best first."""
    acc = across_tables(lbs)
    if acc.empty:
        return pd.DataFrame(columns=["method", "mean_rank", "tables", "mean_accuracy"])
    ranks = np.vstack([rankdata(-row.to_numpy(float), method="average") for _, row in acc.iterrows()])
    out = pd.DataFrame({"method": list(acc.columns), "mean_rank": ranks.mean(axis=0), "tables": len(acc),
                        "mean_accuracy": acc.mean(axis=0).to_numpy(float)})
    return out.sort_values(["mean_rank", "method"], kind="stable").reset_index(drop=True)
