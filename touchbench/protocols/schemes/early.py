"""The ``early`` scheme: any scheme, with test captures (optionally training captures too) cut
to their first N frames or S seconds, N swept over a list (Al-mashhadani et al. 2021, Sec. 2.3).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

import pandas as pd
from pydantic import Field, model_validator

from .base import SPLITTERS, Crop, DataContext, Fold, SchemeParams, Splitter, make_splitter, named

if TYPE_CHECKING:
    from ...datasets.model import TouchDataset


class _EarlyParams(SchemeParams):
    base: dict[str, Any]
    frames: list[int] | None = Field(default=None, min_length=1)
    seconds: list[float] | None = Field(default=None, min_length=1)
    crop_train: bool = False

    @model_validator(mode="before")
    @classmethod
    def _base(cls, d: Any) -> Any:
        return named(d, "base")

    @model_validator(mode="after")
    def _check(self) -> "_EarlyParams":
        if (self.frames is None) == (self.seconds is None):
            raise ValueError("give exactly one of 'frames' (a list of frame counts) or 'seconds' (a list of durations)")
        if self.frames is not None and min(self.frames) < 1:
            raise ValueError("frames must be at least 1")
        if self.seconds is not None and min(self.seconds) <= 0:
            raise ValueError("seconds must be positive")
        name = self.base.get("name")
        if not isinstance(name, str):
            raise ValueError("base must name a scheme: base: {name: loso}")
        if name == "early":
            raise ValueError("the base of 'early' cannot be 'early'")
        return self


@SPLITTERS.register(
    "early",
    description="any scheme, test captures cut to their first N frames / S seconds, N swept (CNN real-time claim)",
    paper="Al-mashhadani et al. 2021, Sec. 2.3 and 4",
)
class Early(Splitter):
    """Recognition from the beginning of a gesture.

    ``base`` is another scheme (``{name: loso}`` or ``{name: kfold, k: 5}``);
    its folds are repeated once per value of ``frames`` (or ``seconds``,
    converted with the sensor's frame rate), with ``Fold.crop`` telling the
    engine to cut the test captures (and, with ``crop_train: true``, the
    training captures) to their first N frames. A capture shorter than N is
    used whole. Accuracy as a function of N measures how recognition grows
    with what has been seen.
    """

    name = "early"
    Params = _EarlyParams
    base_param = "base"
    swept_params = ("frames", "seconds")

    def __init__(self, target: str = "gesture", random_state: int | None = None, **params: Any):
        super().__init__(target=target, random_state=random_state, **params)
        base = dict(self.params.base)
        self.base = make_splitter(base.pop("name"), target=target, random_state=random_state, **base)

    def keeps_subjects_apart(self) -> bool:
        return self.base.keeps_subjects_apart()

    def tests_each_capture_once(self) -> bool:
        return False  # once per crop length

    def check_target(self) -> None:
        self.base.check_target()

    def leakage(self) -> str:
        return self.base.leakage()

    def sample_windows(self):
        return self.base.sample_windows()

    def prepare(self, ds: "TouchDataset", context: DataContext) -> "TouchDataset":
        return self.base.prepare(ds, context)

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        base_folds = self.base.folds(meta)
        self.notes_.extend(self.base.notes_)
        p = self.params
        crops = (
            [Crop(frames=int(n), train=p.crop_train) for n in p.frames]
            if p.frames is not None
            else [Crop(seconds=float(s), train=p.crop_train) for s in p.seconds]
        )
        return [replace(f, name=f"first{c.label}/{f.name}", crop=c) for c in crops for f in base_folds]
