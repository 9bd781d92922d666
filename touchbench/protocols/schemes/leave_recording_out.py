"""The ``leave-recording-out`` scheme: train on one recording of every person, test on the other,
then swap (Zhou et al. 2017, Sec. 5.4, Fig. 9b).
"""

from __future__ import annotations


import numpy as np
import pandas as pd

from .base import (SPLITTERS, Fold, SchemeParams, SplitError, Splitter, natural_key, require_columns,
                   sorted_values, str_col)


class _RecordingParams(SchemeParams):
    column: str = "session"
    subject_column: str = "subject"


@SPLITTERS.register(
    "leave-recording-out",
    description="train on one recording of every person, test on the other, then swap (Zhou 2017)",
    paper="Zhou et al. 2017, Sec. 5.4, Fig. 9b",
)
class LeaveRecordingOut(Splitter):
    """Train on one recording session of every person, test on another.

    Within each subject the recordings (values of ``column``) are ordered
    (natural sort: ``r2`` before ``r10``); fold ``i`` tests every subject's
    ``i``-th recording and trains on their other recordings. With two
    recordings per person this is Zhou's scheme: train on one session, test
    on the other, then swap. A subject with fewer recordings than the others
    is left out (it could not be on both sides of every fold), with a note.
    """

    name = "leave-recording-out"
    Params = _RecordingParams

    def tests_each_capture_once(self) -> bool:
        return True

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        require_columns(meta, self.name, p.column, p.subject_column)
        subj = str_col(meta, p.subject_column)
        rec = str_col(meta, p.column)
        rank = np.full(len(meta), -1, dtype=np.int64)
        n_rec: dict[str, int] = {}
        for s in sorted_values(subj):
            idx = np.flatnonzero(subj == s)
            recs = sorted_values(rec[idx])
            n_rec[s] = len(recs)
            pos = {r: i for i, r in enumerate(recs)}
            rank[idx] = [pos[str(v)] for v in rec[idx]]
        most = max(n_rec.values())
        if most < 2:
            raise SplitError(f"scheme 'leave-recording-out': every subject has a single {p.column!r}; nothing to leave out")
        short = sorted((s for s, c in n_rec.items() if c < most), key=natural_key)
        keep = ~np.isin(subj, short)
        if short:
            self.notes_.append(
                f"subject(s) {short} have fewer than {most} recordings ({p.column!r}) and are left out"
            )
        folds = []
        for i in range(most):
            test = keep & (rank == i)
            train = keep & (rank != i)
            name = f"test=recording{i + 1}"
            folds.append(Fold(name, np.flatnonzero(train), np.flatnonzero(test), group=name))
        return folds
