"""The ``multi-source`` scheme: the datasets of ``cross-dataset``, the other dataset's subjects left
out one at a time with its other subjects in training.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from .base import SPLITTERS, Fold, SplitError, natural_key, str_col
from .cross_dataset import CrossDataset


@SPLITTERS.register(
    "multi-source",
    description="train on the protocol's dataset and the other subjects of another, test each of its subjects",
    paper="",
)
class MultiSource(CrossDataset):
    """Multi-source training: one fold per subject of ``test`` (a dataset reference, as for
    ``cross-dataset``, with its ``adapters``), training on every capture of the protocol's dataset and
    on the test dataset's other subjects, testing on that subject. What a second study's own people
    add to a model trained on the first: beside ``cross-dataset`` (the first study alone) and
    ``loso`` inside the second study (the second alone). Every test capture is tested once.
    """

    name = "multi-source"
    single_test_set = False

    @classmethod
    def heading(cls, params: dict[str, Any], dataset: str) -> str | None:
        """``multi-source: trained on DATASET and TEST's other subjects, tested on each subject of TEST``."""
        test = cls._test_name(params)
        if test is None:
            return None
        return f"multi-source: trained on {dataset} and the other subjects of {test}, tested on each subject of {test}"

    def apart_column(self) -> str | None:
        return "subject"

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        train, test = self._sides(meta)
        subj = str_col(meta, "subject")
        held = sorted(set(subj[test].tolist()), key=natural_key)
        if len(held) < 2:
            raise SplitError(f"scheme 'multi-source' needs at least 2 subjects in the test dataset; it has {held}")
        folds = []
        for v in held:
            out = test[subj[test] == v]
            folds.append(Fold(f"subject={v}", np.concatenate([train, test[subj[test] != v]]), out, group=v))
        return folds
