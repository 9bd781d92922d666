"""The ``challenge`` scheme: the fixed train/test split of the Social Touch Gesture Challenge 2015
(Gaus et al. 2015, Sec. 4), from a split column or subject lists.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from pydantic import Field, model_validator

from .base import SPLITTERS, Fold, SchemeParams, SplitError, Splitter, require_columns, sorted_values, str_col


class _ChallengeParams(SchemeParams):
    column: str = "split"
    train: list[str] = Field(default_factory=lambda: ["train"])
    test: list[str] = Field(default_factory=lambda: ["test"])
    train_subjects: list[str] | None = None
    test_subjects: list[str] | None = None

    @model_validator(mode="before")
    @classmethod
    def _listify(cls, d: Any) -> Any:
        if isinstance(d, dict):
            d = dict(d)
            for k in ("train", "test", "train_subjects", "test_subjects"):
                v = d.get(k)
                if isinstance(v, (str, int)):
                    d[k] = [str(v)]
                elif isinstance(v, list):
                    d[k] = [str(x) for x in v]
        return d

    @model_validator(mode="after")
    def _check(self) -> "_ChallengeParams":
        if self.train_subjects is not None and self.test_subjects is None:
            raise ValueError("train_subjects needs test_subjects (or give test_subjects alone)")
        if self.train_subjects and self.test_subjects:
            both = sorted(set(self.train_subjects) & set(self.test_subjects))
            if both:
                raise ValueError(f"subjects on both sides: {both}")
        return self


@SPLITTERS.register(
    "challenge",
    description="fixed train/test split from a split column or subject lists (Gaus 2015, Sec. 4)",
    paper="Gaus et al. 2015, Sec. 4",
)
class ChallengeSplit(Splitter):
    """One fold: the Social Touch Gesture Challenge 2015 train/test split.

    With ``test_subjects`` the split is by subject (``train_subjects``
    defaults to every other subject); otherwise the ``column`` (``split``)
    decides: values in ``train`` are trained on, values in ``test`` tested.
    Captures in neither are left out, and the report says how many.
    """

    name = "challenge"
    single_test_set = True
    Params = _ChallengeParams

    def keeps_subjects_apart(self) -> bool:
        return self.params.test_subjects is not None

    def apart_column(self) -> str | None:
        return "subject" if self.params.test_subjects is not None else self.params.column

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        if p.test_subjects is not None:
            subj = str_col(meta, "subject")
            known = set(subj)
            unknown = [s for s in (p.test_subjects + (p.train_subjects or [])) if s not in known]
            if unknown:
                raise SplitError(f"scheme 'challenge': unknown subject(s) {unknown}; the dataset has {sorted_values(known)}")
            is_test = np.isin(subj, p.test_subjects)
            is_train = np.isin(subj, p.train_subjects) if p.train_subjects is not None else ~is_test
        else:
            require_columns(meta, self.name, p.column)
            col = str_col(meta, p.column)
            is_train = np.isin(col, p.train)
            is_test = np.isin(col, p.test)
            both = sorted(set(p.train) & set(p.test))
            if both:
                raise SplitError(f"scheme 'challenge': value(s) {both} of column {p.column!r} are both train and test")
            subj = str_col(meta, "subject")
            shared = sorted(set(subj[is_train]) & set(subj[is_test]))
            if shared:
                self.notes_.append(f"subjects on both sides of the {p.column!r} split: {shared}")
        unused = int((~is_train & ~is_test).sum())
        if unused:
            self.notes_.append(f"{unused} captures are in neither train nor test and are not used")
        return [Fold("challenge", np.flatnonzero(is_train), np.flatnonzero(is_test), group="challenge")]
