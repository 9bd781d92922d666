"""The ``early`` scheme: any scheme, with test captures (optionally training captures too) cut
to their first N frames or S seconds, N swept over a list (Al-mashhadani et al. 2021, Sec. 2.3).
"""

from __future__ import annotations


import pandas as pd
from pydantic import Field, model_validator

from .base import SPLITTERS, Crop, Fold, WrappingParams, WrappingSplitter, check_base


class _EarlyParams(WrappingParams):
    frames: list[int] | None = Field(default=None, min_length=1)
    seconds: list[float] | None = Field(default=None, min_length=1)
    crop_train: bool = False

    @model_validator(mode="after")
    def _check(self) -> "_EarlyParams":
        if (self.frames is None) == (self.seconds is None):
            raise ValueError("give exactly one of 'frames' (a list of frame counts) or 'seconds' (a list of durations)")
        if self.frames is not None and min(self.frames) < 1:
            raise ValueError("frames must be at least 1")
        if self.seconds is not None and min(self.seconds) <= 0:
            raise ValueError("seconds must be positive")
        check_base(self.base, "early")
        return self


@SPLITTERS.register(
    "early",
    description="any scheme, test captures cut to their first N frames / S seconds, N swept (CNN real-time claim)",
    paper="Al-mashhadani et al. 2021, Sec. 2.3 and 4",
)
class Early(WrappingSplitter):
    """Recognition from the beginning of a gesture.

    ``base`` is another scheme (``{name: loso}`` or ``{name: kfold, k: 5}``);
    its folds are repeated once per value of ``frames`` (or ``seconds``,
    converted with the sensor's frame rate), with a :class:`Crop` on each fold telling the
    engine to cut the test captures (and, with ``crop_train: true``, the
    training captures) to their first N frames. A capture shorter than N is
    used whole. Accuracy as a function of N measures how recognition grows
    with what has been seen.
    """

    name = "early"
    Params = _EarlyParams
    swept_params = ("frames", "seconds")

    def tests_each_capture_once(self) -> bool:
        return False  # once per crop length

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        base_folds = self.base.folds(meta)
        self.notes_.extend(self.base.notes_)
        p = self.params
        crops = (
            [Crop(frames=int(n), train=p.crop_train) for n in p.frames]
            if p.frames is not None
            else [Crop(seconds=float(s), train=p.crop_train) for s in p.seconds]
        )
        return [f.with_extra(c, name=f"first{c.label}/{f.name}") for c in crops for f in base_folds]
