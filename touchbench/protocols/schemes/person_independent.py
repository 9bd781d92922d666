"""The ``person-independent`` scheme: subjects dealt into k disjoint parties, each party tested
once (Zhou et al. 2017, Sec. 5.4, Fig. 9c).
"""

from __future__ import annotations


import numpy as np
import pandas as pd
from pydantic import Field

from .base import (SPLITTERS, Fold, SchemeParams, SplitError, Splitter, natural_key, require_columns,
                   sorted_values, str_col)


class _PartyParams(SchemeParams):
    k: int = Field(default=4, ge=2)
    column: str = "subject"


@SPLITTERS.register(
    "person-independent",
    description="subjects dealt into k disjoint parties, each party tested once (Zhou 2017: 4 of 6)",
    paper="Zhou et al. 2017, Sec. 5.4, Fig. 9c",
)
class PersonIndependent(Splitter):
    """Subjects shuffled (seeded) and dealt into ``k`` disjoint parties.

    Fold ``i`` tests party ``i`` and trains on the other parties, so each
    subject is tested exactly once and never trained on in its own fold. Zhou
    et al. deal 24 people into 4 parties of 6; parties differ in size by at
    most one subject when ``k`` does not divide the number of subjects.
    """

    name = "person-independent"
    Params = _PartyParams

    def keeps_subjects_apart(self) -> bool:
        return self.params.column == "subject"

    def apart_column(self) -> str | None:
        return self.params.column

    def tests_each_capture_once(self) -> bool:
        return True

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        require_columns(meta, self.name, p.column)
        subj = str_col(meta, p.column)
        values = sorted_values(subj)
        if len(values) < p.k:
            raise SplitError(
                f"scheme 'person-independent': k={p.k} parties but only {len(values)} values of {p.column!r}; lower k"
            )
        rng = self._rng()
        order = [values[i] for i in rng.permutation(len(values))]
        parties = [sorted(order[i::p.k], key=natural_key) for i in range(p.k)]
        if len(values) % p.k:
            self.notes_.append(f"{len(values)} subjects do not divide into {p.k} equal parties: sizes differ by one")
        folds = []
        for i, party in enumerate(parties):
            test = np.isin(subj, party)
            folds.append(
                Fold(f"party{i + 1}", np.flatnonzero(~test), np.flatnonzero(test), group=f"party{i + 1}",
                     notes=(f"party{i + 1} = {party}",))
            )
        return folds
