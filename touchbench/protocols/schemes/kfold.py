"""The ``kfold`` scheme: (stratified) k-fold cross-validation with repeats, optionally grouped so
no subject is on both sides of a fold (Gaus 2015 Sec. 4; Flagg 2012 Sec. 4.4; Zhou 2017 Sec. 5).
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
from pydantic import Field, model_validator
from sklearn.model_selection import GroupKFold, StratifiedGroupKFold

from ..seeding import derive_seed
from .base import (SPLITTERS, Fold, SchemeParams, SplitError, Splitter, deal, folds_from_assignment, require_columns,
                   small_class_notes, str_col)


class _KFoldParams(SchemeParams):
    k: int = Field(default=10, ge=2, description="the number of folds.")
    repeats: int = Field(default=1, ge=1, description="how many times the k folds are drawn (more than one "
                         "needs ``shuffle``).")
    stratified: bool = Field(default=True, description="each fold holds each class in proportion.")
    grouped: bool = Field(default=False, description="every value of ``group_column`` on one side of each fold.")
    group_column: str = Field(default="subject", description="the metadata column ``grouped`` keeps together.")
    shuffle: bool = Field(default=True, description="captures dealt at random (from the protocol's seed).")

    @model_validator(mode="after")
    def _check(self) -> "_KFoldParams":
        if self.repeats > 1 and not self.shuffle:
            raise ValueError("repeats > 1 needs shuffle: true (unshuffled repeats are identical)")
        return self


#: the leak of every scheme that lets one subject's captures be on both sides of a fold
SUBJECTS_SHARED = "captures of one subject on both sides of a fold (k-fold ignoring subjects)"


@SPLITTERS.register(
    "kfold",
    description="stratified k-fold cross-validation with repeats, optionally grouped by subject",
    paper="Gaus 2015 Sec. 4 (10-fold); Flagg 2012 Sec. 4.4 (100-fold); Zhou 2017 Sec. 5 (5-fold)",
)
class KFold(Splitter):
    """k folds (stratified on the target by default), ``repeats`` times.

    Not grouped, folds are dealt at random per class (see ``deal``): each
    capture is tested exactly once per repeat. ``grouped: true`` keeps every
    value of ``group_column`` (the subject) on one side of each fold, using
    scikit-learn's ``StratifiedGroupKFold`` (``GroupKFold`` if not stratified).
    ``k`` larger than the number of captures (or groups) is refused; a class
    with fewer than ``k`` captures is handled (it is absent from some test
    folds) and noted in the report.
    """

    name = "kfold"
    Params = _KFoldParams

    def keeps_subjects_apart(self) -> bool:
        return self.params.grouped and self.params.group_column == "subject"

    def apart_column(self) -> str | None:
        return self.params.group_column if self.params.grouped else None

    def tests_each_capture_once(self) -> bool:
        return True

    def leakage(self) -> str:
        if self.target == "subject" or self.keeps_subjects_apart():
            return ""
        return SUBJECTS_SHARED

    def _n_splits(self) -> int | None:
        return self.params.k * self.params.repeats

    def _grouping(self) -> str | None:
        """The column no value of which is on both sides of a fold (None: not grouped)."""
        return self.params.group_column if self.params.grouped else None

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        n = len(meta)
        y = self._y(meta)
        group_column = self._grouping()
        if n < p.k:
            raise SplitError(f"scheme {self.name!r}: k={p.k} folds but only {n} "
                             f"{'windows' if self.sample_windows() else 'captures'}; lower k")
        folds: list[Fold] = []
        if group_column is not None:
            require_columns(meta, self.name, group_column)
            groups = str_col(meta, group_column)
            n_groups = len(set(groups))
            if n_groups < p.k:
                raise SplitError(
                    f"scheme {self.name!r} (grouped by {group_column!r}): k={p.k} folds but only {n_groups} groups; lower k"
                )
        elif p.stratified:
            self.notes_.extend(small_class_notes(y, p.k))
        for r in range(p.repeats):
            seed = derive_seed(self.random_state, "kfold", r)
            if group_column is not None:

                if p.stratified:
                    cv = StratifiedGroupKFold(n_splits=p.k, shuffle=p.shuffle, random_state=seed if p.shuffle else None)
                else:
                    cv = GroupKFold(n_splits=p.k, shuffle=p.shuffle, random_state=seed if p.shuffle else None)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    pairs = [(np.sort(a), np.sort(b)) for a, b in cv.split(np.zeros(n), y, groups)]
            else:
                if p.shuffle:
                    assign = deal(y if p.stratified else None, n, p.k, np.random.default_rng(seed))
                else:
                    assign = np.arange(n) * p.k // n  # contiguous blocks, in table order
                pairs = folds_from_assignment(assign, p.k)
            for i, (tr, te) in enumerate(pairs):
                name = f"r{r}/f{i}" if p.repeats > 1 else f"f{i}"
                folds.append(Fold(name, tr, te, group=f"r{r}"))
        return folds
