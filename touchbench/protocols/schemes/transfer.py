"""The ``transfer`` scheme: train on one group, test on another, both directions (Zhou et al.
2017, Sec. 5.4, Fig. 11).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from pydantic import Field

from .base import (SPLITTERS, Fold, SchemeParams, SplitError, Splitter, StrList, natural_key, require_columns,
                   sorted_values, str_col)


class _TransferParams(SchemeParams):
    column: str = "group"
    groups: StrList | None = Field(default=None, min_length=2)
    both_directions: bool = True


@SPLITTERS.register(
    "transfer",
    description="train on one group, test on another, both directions (Zhou 2017: A->B, B->A)",
    paper="Zhou et al. 2017, Sec. 5.4, Fig. 11",
)
class Transfer(Splitter):
    """Train on all captures of one group, test on all captures of another.

    ``groups`` (default: every value of ``column``, sorted) lists the groups;
    every ordered pair is a fold named ``A->B`` (train A, test B), or only the
    pairs in list order with ``both_directions: false``. Captures of other
    groups are not used. A subject found in two groups is noted (the groups
    are then not independent).
    """

    name = "transfer"
    single_test_set = True
    Params = _TransferParams

    def keeps_subjects_apart(self) -> bool:
        return True

    def apart_column(self) -> str | None:
        return self.params.column

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        require_columns(meta, self.name, p.column)
        g = str_col(meta, p.column)
        present = sorted_values(v for v in g if v is not None)
        groups = p.groups if p.groups is not None else present
        unknown = [x for x in groups if x not in present]
        if unknown:
            raise SplitError(f"scheme 'transfer': unknown {p.column} value(s) {unknown}; the dataset has {present}")
        if len(groups) < 2:
            raise SplitError(f"scheme 'transfer' needs at least 2 values of {p.column!r}; the dataset has {present}")
        subj = str_col(meta, "subject")
        for i, a in enumerate(groups):
            for b in groups[i + 1:]:
                shared = sorted(set(subj[g == a]) & set(subj[g == b]), key=natural_key)
                if shared:
                    self.notes_.append(f"subject(s) {shared} are in both groups {a!r} and {b!r}")
        folds = []
        for i, a in enumerate(groups):
            for j, b in enumerate(groups):
                if a == b or (not p.both_directions and j < i):
                    continue
                name = f"{a}->{b}"
                folds.append(Fold(name, np.flatnonzero(g == a), np.flatnonzero(g == b), group=name))
        return folds
