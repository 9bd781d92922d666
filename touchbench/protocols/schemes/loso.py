"""The ``loso`` scheme: leave one subject out (Al-mashhadani et al. 2021, Sec. 3, Table 2), or
leave one value of another column out.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from pydantic import Field

from .base import SPLITTERS, Fold, SchemeParams, SplitError, Splitter, StrList, require_columns, sorted_values, str_col


class _LosoParams(SchemeParams):
    column: str = Field(default="subject", description="the metadata column whose values are held out in turn.")
    subjects: StrList | None = Field(default=None, min_length=1, description="the values held out (None: every "
                                     "one); each fold still trains on all the others.")


@SPLITTERS.register(
    "loso",
    description="leave one subject out (Al-mashhadani 2021, Table 2)",
    paper="Al-mashhadani et al. 2021, Sec. 3",
)
class LeaveOneSubjectOut(Splitter):
    """One fold per subject: test on that subject, train on all the others.

    ``subjects`` restricts which subjects are held out (each fold still
    trains on every other subject): Al-mashhadani et al. select the frame
    length on subjects 1, 3, 5, 7 only (Fig. 5). ``column`` may name another
    grouping column (a leave-one-group-out).
    """

    name = "loso"
    Params = _LosoParams

    def keeps_subjects_apart(self) -> bool:
        return self.params.column == "subject"

    def apart_column(self) -> str | None:
        return self.params.column

    def tests_each_capture_once(self) -> bool:
        return self.params.subjects is None

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        col = self.params.column
        require_columns(meta, self.name, col)
        g = str_col(meta, col)
        values = sorted_values(g)
        if len(values) < 2:
            raise SplitError(f"scheme 'loso' needs at least 2 values of {col!r}; the dataset has {values}")
        held = values
        if self.params.subjects is not None:
            unknown = [s for s in self.params.subjects if s not in values]
            if unknown:
                raise SplitError(f"scheme 'loso': unknown {col} {unknown}; the dataset has {values}")
            held = [v for v in values if v in set(self.params.subjects)]
        folds = []
        for v in held:
            test = g == v
            folds.append(Fold(f"{col}={v}", np.flatnonzero(~test), np.flatnonzero(test), group=v))
        small = [v for v in held if (g == v).sum() == 1]
        if small:
            self.notes_.append(f"{col} {small} have a single capture: their fold tests one capture")
        return folds
