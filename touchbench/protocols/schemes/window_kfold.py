"""The ``window-kfold`` scheme: k-fold over windows cut from the captures, the windows the
samples (leaky unless grouped by subject).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

import numpy as np
import pandas as pd
from pydantic import Field, model_validator

from ...datasets.windows import seconds_to_frames, window_dataset
from .base import SPLITTERS, DataContext, Fold, require_columns
from .kfold import SUBJECTS_SHARED, KFold, _KFoldParams

if TYPE_CHECKING:
    from ...datasets.model import TouchDataset

#: the leak of k-fold over windows dealt at random
WINDOWS_SHARED = "windows of one capture on both sides of a fold"


class _WindowKFoldParams(_KFoldParams):
    frames: int | None = Field(default=None, ge=1)
    seconds: float | None = Field(default=None, gt=0)
    hop: int | None = Field(default=None, ge=1)
    group_by: Literal["none", "capture", "subject"] = "none"
    #: keep only the first ``per_capture`` windows of each capture (None: every window)
    per_capture: int | None = Field(default=None, ge=1)
    #: run only the first ``folds`` of the ``k`` folds (None: all): a cheaper estimate of the same split
    folds: int | None = Field(default=None, ge=1)

    @model_validator(mode="after")
    def _one_length(self) -> "_WindowKFoldParams":
        if (self.frames is None) == (self.seconds is None):
            raise ValueError("give exactly one of 'frames' or 'seconds' (the window length)")
        if self.grouped:
            raise ValueError("window-kfold groups with group_by: none, capture or subject (not grouped)")
        if self.folds is not None and (self.folds > self.k or self.repeats > 1):
            raise ValueError(f"folds: {self.folds} runs the first of k={self.k} folds of one repeat: at most k, "
                             "and repeats 1")
        return self


@SPLITTERS.register(
    "window-kfold",
    description="k-fold over windows cut from the captures (leaky unless group_by: subject)",
    paper="Al-mashhadani et al. 2021, Sec. 2.3 and Table 3 (252 windows); Cang et al. 2015 (2-s windows)",
)
class WindowKFold(KFold):
    """Captures cut into windows of ``frames`` (or ``seconds``) every ``hop``
    frames (default: the window length, no overlap), each window a sample
    with its capture's labels; then k-fold over the windows.

    ``group_by: none`` (the default, as published evaluations did it) deals
    windows to folds at random, so windows of one capture, a few frames
    apart, are trained on and tested: **leaky**. ``capture`` keeps a
    capture's windows on one side but still shares subjects (leaky when the
    target is not the subject); ``subject`` keeps subjects apart (honest).
    :meth:`prepare` cuts the windows
    (:func:`touchbench.datasets.windows.window_dataset`); the metadata then
    has ``source_capture`` and ``window`` columns. Accuracy is per window.
    ``per_capture: N`` keeps the first N windows of each capture (a method
    that cuts a capture into L windows: ``per_capture: L``). ``folds: n``
    runs only the first n of the k folds (every window dealt as for k folds,
    so each fold trains on (k - 1) / k of the windows): fewer tasks, the
    same kind of estimate, not every window tested.
    """

    name = "window-kfold"
    Params = _WindowKFoldParams

    def _grouping(self) -> str | None:
        return {"none": None, "capture": "source_capture", "subject": "subject"}[self.params.group_by]

    def keeps_subjects_apart(self) -> bool:
        return self.params.group_by == "subject"

    def apart_column(self) -> str | None:
        return "subject" if self.params.group_by == "subject" else None

    def leakage(self) -> str:
        if self.params.group_by == "none":
            return WINDOWS_SHARED + ("" if self.target == "subject" else ", and captures of one subject")
        return "" if self.target == "subject" or self.params.group_by == "subject" else SUBJECTS_SHARED

    def tests_each_capture_once(self) -> bool:
        return self.params.folds is None or self.params.folds == self.params.k

    def sample_windows(self):
        p = self.params
        return (p.frames, p.seconds, p.hop)

    def prepare(self, ds: "TouchDataset", context: DataContext) -> "TouchDataset":
        """Every capture cut into its windows, with a note."""
        frames, seconds, hop = self.sample_windows()
        if frames is None:
            frames = seconds_to_frames(seconds, ds.sensor.frame_rate, "the window length")
        n = len(ds)
        ds = window_dataset(ds, frames, hop)
        first = self.params.per_capture
        if first is not None:
            ds = ds.subset(np.flatnonzero(ds.meta["window"].to_numpy() < first))
        context.notes.append(f"the samples are windows of {frames} frames every {hop or frames}"
                             + (f", the first {first} of each capture" if first is not None else "")
                             + f" (from {n} captures: {len(ds)} windows)")
        return ds

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        require_columns(meta, self.name, "source_capture")
        folds = super()._split(meta)
        if self.params.folds is not None and self.params.folds < len(folds):
            self.notes_.append(f"only the first {self.params.folds} of the {len(folds)} folds run")
            folds = folds[:self.params.folds]
        return folds

