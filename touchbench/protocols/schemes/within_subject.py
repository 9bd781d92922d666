"""The ``within-subject`` scheme: k-fold inside each subject, one model per subject, scores per
subject (Flagg 2012, Sec. 4.4, Fig. 4.5).
"""

from __future__ import annotations


import numpy as np
import pandas as pd
from pydantic import Field

from ..seeding import derive_seed
from .base import (SPLITTERS, Fold, SchemeParams, SplitError, Splitter, deal, folds_from_assignment,
                   require_columns, small_class_notes, sorted_values, str_col)


class _WithinParams(SchemeParams):
    k: int = Field(default=10, ge=2)
    repeats: int = Field(default=1, ge=1)
    stratified: bool = True
    column: str = "subject"


@SPLITTERS.register(
    "within-subject",
    description="k-fold inside each subject, one model per subject, scores per subject (Flagg 2012)",
    paper="Flagg 2012, Sec. 4.4, Fig. 4.5",
)
class WithinSubject(Splitter):
    """k-fold cross-validation inside each subject separately.

    Every fold trains and tests on one subject's captures only (Flagg's
    per-person models); ``Fold.group`` is the subject, so scores are reported
    per subject. A subject with fewer captures than ``k`` gets one fold per
    capture (leave-one-out for that subject); a subject with a single capture
    cannot be cross-validated and is left out. Both are noted in the report.
    The target ``subject`` is refused (one class per model).
    """

    name = "within-subject"
    Params = _WithinParams

    def tests_each_capture_once(self) -> bool:
        return True

    def check_target(self) -> None:
        if self.target == self.params.column or self.target == "subject":
            raise SplitError(
                "scheme 'within-subject' trains one model per subject: the target cannot be the subject "
                "(every model would see one class)"
            )

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        require_columns(meta, self.name, p.column)
        subj = str_col(meta, p.column)
        y = self._y(meta)
        folds: list[Fold] = []
        skipped = []
        for s in sorted_values(subj):
            idx = np.flatnonzero(subj == s)
            n = len(idx)
            if n < 2:
                skipped.append(s)
                continue
            k = min(p.k, n)
            notes: list[str] = []
            if k < p.k:
                notes.append(f"subject {s!r} has {n} captures < k={p.k}: {k} folds (leave-one-out)")
            if p.stratified:
                notes.extend(small_class_notes(y[idx], k, where=f"subject {s!r}: "))
            self.notes_.extend(notes)
            for r in range(p.repeats):
                rng = np.random.default_rng(derive_seed(self.random_state, self.name, s, r))
                assign = deal(y[idx] if p.stratified else None, n, k, rng)
                for i, (tr, te) in enumerate(folds_from_assignment(assign, k, base=idx)):
                    name = f"{s}/r{r}/f{i}" if p.repeats > 1 else f"{s}/f{i}"
                    folds.append(Fold(name, tr, te, group=s, notes=tuple(notes)))
        if skipped:
            self.notes_.append(f"subject(s) {skipped} have a single capture and are left out (cannot cross-validate)")
        if not folds:
            raise SplitError("scheme 'within-subject': no subject has 2 or more captures")
        return folds
