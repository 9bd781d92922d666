"""An evaluation's extra leaderboard columns (its ``report:`` block): the recall of named classes and
the accuracy per value of metadata columns.

A protocol's evaluation says ``report: {recall: [notouch], by: [cover, motion]}``; the run writes it
into the manifest with, for each ``by`` column, the ids of the test data's captures of each value
(:func:`touchbench.engine.runner` ``_report_block``). A table then gets, per method:

- ``recall[C]``: of the test predictions whose true class is C, the fraction predicted C;
- ``accuracy[COL=V]``: of the test predictions of captures whose COL is V, the fraction correct;

each pooled over every fold and seed of the method (one prediction per fold, seed and capture: the
latest), NaN where the method predicted no such capture. Values a column takes only in the
training data get no column.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import pandas as pd

from ..results.store import PREDICTED, TRUE
from .labels import _pct
from .paired import _latest

__all__ = ["Breakdown", "breakdown_cells", "breakdown_headers", "breakdown_legend"]


@dataclass(frozen=True)
class Breakdown:
    """What a table's evaluation asked for: classes to recall and, per column and value, its captures."""

    recall: tuple[str, ...]
    rows: tuple[tuple[str, str, frozenset[str]], ...]  # (column, value, capture ids)

    @classmethod
    def of(cls, sources: list[dict]) -> "Breakdown | None":
        """The report the sources of a table recorded (the first that has one; None when none has)."""
        report = next((s["report"] for s in sources if s.get("report")), None)
        if not report:
            return None
        rows = tuple((str(col), str(v), frozenset(map(str, ids)))
                     for col in report.get("by") or [] for v, ids in sorted(((report.get("rows") or {}).get(col) or {}).items()))
        return cls(tuple(map(str, report.get("recall") or [])), rows)

    def tested(self, preds: pd.DataFrame | None) -> "Breakdown":
        """Only the (column, value) pairs some test prediction of the table has."""
        if preds is None or preds.empty:
            return Breakdown(self.recall, ())
        tested = set(preds["capture_id"].astype(str))
        return Breakdown(self.recall, tuple(r for r in self.rows if r[2] & tested))

    @property
    def columns(self) -> list[str]:
        """The row columns, in order: each recall, then each column's values."""
        return [f"recall[{c}]" for c in self.recall] + [f"accuracy[{col}={v}]" for col, v, _ in self.rows]

    def fields(self, preds: pd.DataFrame | None, mid: str) -> dict[str, float]:
        """Method ``mid``'s value of each column (module docstring)."""
        mine = _latest(preds[preds["method_id"] == mid]) if preds is not None and len(preds) else None
        if mine is None or mine.empty:
            return {c: math.nan for c in self.columns}
        truth, predicted = mine[TRUE].astype(str), mine[PREDICTED].astype(str)
        out = {f"recall[{c}]": _fraction(predicted[truth == c] == c) for c in self.recall}
        ids = mine["capture_id"].astype(str)
        for col, v, captures in self.rows:
            out[f"accuracy[{col}={v}]"] = _fraction(mine["correct"][ids.isin(captures)].astype(bool))
        return out


def _fraction(hits: pd.Series) -> float:
    """The mean of ``hits`` (booleans) in float64; NaN for none."""
    return float(hits.astype("float64").mean()) if len(hits) else math.nan


def breakdown_headers(columns: list[str]) -> list[str]:
    """The headers of a table's breakdown columns: ``notouch recall %``, ``cover=none %``."""
    return [f"{c[len('recall['):-1]} recall %" if c.startswith("recall[") else f"{c[len('accuracy['):-1]} %"
            for c in columns]


def breakdown_cells(row: Any, columns: list[str]) -> list[str]:
    """A leaderboard row's breakdown cells, as percentages."""
    return [_pct(row.get(c, math.nan)) for c in columns]


def breakdown_legend(columns: list[str]) -> str:
    """The legend's sentence on the breakdown columns ("" without any)."""
    if not columns:
        return ""
    return (" C recall: of the test captures of class C, the % predicted C; COL=V: accuracy on the test captures "
            "whose COL is V; both pooled over every fold and seed.")
