"""The ``calibration`` scheme: any scheme, with k labelled captures per class of each test subject
(or other ``unit``) joining its folds' training data, k swept.

For a fold and a draw, a calibration pool is drawn once for the largest k: for each value of
``unit`` among the fold's test captures and each class, up to that many of its captures in a
random order (seeded by the scheme's ``random_state``, the fold, the draw, the unit and the
class). The point ``k`` trains on the base fold's training captures plus the first k of each pool;
the pool is never scored: every point of a fold and draw (k = 0 included) tests the base fold's
test captures minus the whole pool, so the points are paired. A class with no more captures in a
unit than the largest k gives all but one of them (one is always scored), said in the fold's notes.

Training then holds labelled captures of the test subject (unless ``unit`` is a column above the
subject): the scheme does not keep subjects apart, and every fold with k > 0 says so in its notes.
The scored captures never train, so the scheme adds no leak of its own; a point with k > 0
measures a model calibrated to its user, not accuracy on new people.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from pydantic import Field, field_validator, model_validator

from .base import (CURVE_SCHEMES, SPLITTERS, CurveParams, CurvePoint, Fold, SplitError, WrappingSplitter, check_base,
                   require_columns, sorted_values, str_col)


#: the most labelled captures per class a point may ask of a test unit (a protocol asking more is a typo)
MAX_PER_CLASS = 10_000


class _CalibrationParams(CurveParams):
    per_class: list[int] = Field(min_length=1)
    unit: str = Field(default="subject", min_length=1)

    @field_validator("per_class", mode="before")
    @classmethod
    def _whole(cls, v: Any) -> Any:
        for x in v if isinstance(v, list) else ():
            if isinstance(x, bool) or not isinstance(x, int):
                raise ValueError(f"every number of captures per class must be a whole number such as 2 (got {x!r})")
            if x > MAX_PER_CLASS:
                raise ValueError(f"every number of captures per class must be at most {MAX_PER_CLASS} (got {x})")
        return v

    @field_validator("per_class")
    @classmethod
    def _per_class(cls, v: list[int]) -> list[int]:
        if min(v) < 0:
            raise ValueError(f"every number of captures per class must be at least 0 (got {min(v)})")
        if max(v) < 1:
            raise ValueError("give at least one number of captures per class above 0 (0 is always evaluated)")
        return sorted({0, *v})

    @model_validator(mode="after")
    def _check(self) -> "_CalibrationParams":
        check_base(self.base, "calibration", (*CURVE_SCHEMES, "stream"))
        return self


@SPLITTERS.register(
    "calibration",
    description="any scheme, k labelled captures per class of each test subject joining training, k swept",
    paper="",
)
class Calibration(WrappingSplitter):
    """Accuracy as a function of the labelled captures a test user gives (module docstring).

    ``per_class: [1, 2, 5]`` lists the points (0, the base scheme's model on the same scored
    captures, is always added); ``draws`` independent draws of the pools; ``unit`` is the metadata
    column the pools are drawn per (``subject``; ``session`` or any other column).
    """

    name = "calibration"
    Params = _CalibrationParams
    swept_params = ("draws",)

    def keeps_subjects_apart(self) -> bool:
        return False  # the test subject's calibration captures are in training

    def apart_column(self) -> str | None:
        return None

    def tests_each_capture_once(self) -> bool:
        return False

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        base_folds = self.base.folds(meta)
        self.notes_.extend(self.base.notes_)
        p = self.params
        require_columns(meta, self.name, p.unit)
        y, units = self._y(meta), str_col(meta, p.unit)
        out, takes = [], []
        for f in base_folds:
            missing = int(sum(u is None for u in units[f.test].tolist()))
            if missing:
                raise SplitError(f"scheme 'calibration': unit: {missing} test capture(s) of fold {f.name!r} have no "
                                 f"{p.unit!r} value to draw calibration captures per")
            for d in range(p.draws):
                pools, short = self._pools(f, y, units, d)
                takes += [len(pool) for pool in pools] if d == 0 else []
                test = np.setdiff1d(f.test, np.concatenate([f.test[:0], *pools]))
                for k in p.per_class:
                    calib = np.concatenate([f.train[:0], *(pool[:k] for pool in pools)])
                    added = np.minimum(k, [len(pool) for pool in pools], dtype=np.float64)
                    note = (f"calibration: {k} labelled capture(s) per class of each test {p.unit} in training",) if k else ()
                    point = CurvePoint("calibration", float(k), d, float(added.mean()) if len(added) else np.nan,
                                       float(added.min()) if len(added) else np.nan)
                    out.append(f.with_extra(point, name=f"k{k}#{d}/{f.name}", train=np.union1d(f.train, calib), test=test,
                                         notes=f.notes + note + short))
        self.notes_ += self._capped(np.asarray(takes, dtype=np.int64))
        self.notes_.append(f"calibration: k = {', '.join(map(str, p.per_class))} labelled captures per class of each "
                           f"test {p.unit} join the training data ({p.draws} random draws); every k of a fold and draw "
                           f"scores the same captures (the test captures less the k = {p.per_class[-1]} pool); with "
                           "k > 0 training holds captures of the test subject: a calibrated model, not a new user")
        return out

    def _capped(self, takes: np.ndarray) -> list[str]:
        """Refuse a point no (unit, class) pool of any fold can give (``takes``: each pool's size), and
        a note per point some pools give fewer captures than asked (its mean and least)."""
        p, most = self.params, int(takes.max()) if takes.size else 0
        over = [k for k in p.per_class if k > most]
        if over:
            raise SplitError(
                f"scheme 'calibration': per_class: k = {', '.join(map(str, over))} cannot be given by any test "
                f"{p.unit}: no {p.unit}/class pair of the test captures holds more than {most + 1 if takes.size else 0} "
                f"capture(s), and one of each is always scored, so at most {most} per class can join training "
                f"(unit: {p.unit}); lower per_class or choose a unit with more captures per class")
        notes = []
        for k in p.per_class[1:]:
            added = np.minimum(k, takes)
            if (added < k).any():
                notes.append(f"calibration: k = {k} is capped: {int((added < k).sum())} of {takes.size} test "
                             f"{p.unit}/class pair(s) hold no more than {k} captures, so {added.mean():.3g} labelled "
                             f"captures per class join training on average (at least {int(added.min())}); the tables "
                             "label the point by the captures it added")
        return notes

    def _pools(self, fold: Fold, y: np.ndarray, units: np.ndarray, draw: int) -> tuple[list[np.ndarray], tuple[str, ...]]:
        """The calibration pool of each (unit, class) of ``fold``'s test captures in ``draw``, each in
        its drawn order (the point k takes the first k), and the note on the short ones."""
        k_max = self.params.per_class[-1]
        tu, ty = units[fold.test], y[fold.test]
        pools, short = [], []
        for u in sorted_values(tu):
            for c in sorted_values(ty[tu == u]):
                idx = fold.test[(tu == u) & (ty == c)]
                take = min(k_max, len(idx) - 1)
                if take < k_max:
                    short.append(f"{u}/{c} ({len(idx)})")
                pools.append(self._rng(fold.name, draw, u, c).permutation(idx)[:take])
        note = () if not short else (
            f"calibration: {len(short)} {self.params.unit}/class pair(s) with at most k = {k_max} captures "
            f"({', '.join(short[:5])}{'...' if len(short) > 5 else ''}) give all but one (one is always scored)",)
        return pools, note
